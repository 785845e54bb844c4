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

// The panels in one picture; throws where it cannot be written.
void write_life_picture(const std::filesystem::path& file, const std::string& name, const std::vector<Stage>& stages,
                        const LifeAxis& axis);

}  // namespace mc::app::life
