// life.png (docs/liner-life.md): a life study's panels, built apart from
// their drawing so that a test can read what each panel holds.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "app/life_state.h"
#include "io/png_plot.h"

namespace mc::app::life {

// What the hours axis of a study is: its stages, the factor between
// calibrated and case hours (calibrated = case / factor), whether they are
// relative (the default wear coefficient, not calibrated), the bars' length
// (the stations' rates are over it: the mill's, and a worn case's held
// dish at the shell; app/life_plates.h bar_length adds a worn stage's).
struct LifeAxis {
  double factor = 1;
  bool relative = false;
  double length = 1;
};

// The hours axis' title: "operating hours", or relative ones said so.
std::string hours_label(bool relative);

// At most this many stages' profiles are drawn (the first, the last and
// evenly between): each with its own legend entry.
inline constexpr int kProfilesDrawn = 9;

// The panels, top to bottom: the profiles, each above its own worn shell;
// the power draw (its axis at least ±5 % of the mean); where the charge
// lands; where it leaves the shell; the lifters' heights; their face angles;
// the impact power on bare liner; the wear rates of the bars' tops and the
// shell. Only the stages that ran are drawn.
std::vector<io::LinePlot> life_plots(const std::string& name, const std::vector<Stage>& stages, const LifeAxis& axis);

// The panels along the mill of a study with --axial-segments, from its
// life_segments.csv and its stages' summary.json in `out`: the bars'
// leading face and height per worn mesh and segment (bands: ± 2 standard
// errors of the segment's mean bar; an empty figure breaks them), and the
// impact point per axial bin of the liner (liner.impact_point_along), with
// in the title the widest spread over the stages where every bin has a
// point. Empty where the study has no segments; throws naming a file that
// cannot be read.
std::vector<io::LinePlot> along_plots(const std::string& name, const std::filesystem::path& out, bool relative);

// The panels in one picture (and `extra` under them); throws where it
// cannot be written.
void write_life_picture(const std::filesystem::path& file, const std::string& name, const std::vector<Stage>& stages,
                        const LifeAxis& axis, const std::vector<io::LinePlot>& extra = {});

}  // namespace mc::app::life
