// millcharge life-compare: several life studies side by side
// (docs/liner-life.md, "Studies side by side"). Each study's life.csv is
// read strictly; its figures are interpolated linearly in the calibrated
// hours at the hours asked, with their standard errors where the study has
// them; measured points (a plant's profile at so many hours) are set beside
// them in standard errors. compare.csv and compare.png hold the whole.
#pragma once

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace mc::app::life {

// The figures a comparison follows, as life.csv names them; the first four
// are drawn, and may be measured.
inline constexpr const char* kCompared[] = {"leading_angle_deg", "height_mm", "trailing_angle_deg", "shell_wear_mm",
                                            "impact_point_deg", "power_W", "impact_wear_share"};
inline constexpr int kComparedCount = 7;
inline constexpr int kDrawnCount = 4;

// One study's path: per compared figure, its values (and standard errors,
// NaN where the study has none) at each stage's hours.
struct StudyPath {
  std::string label, folder;
  std::string basis;  // life.csv's wear_basis: what its hours stand on
  std::vector<double> hours;
  std::vector<std::vector<double>> value, se;  // [figure][stage]
  // Interpolated linearly between the stages around `h`; the standard
  // error as the stage's own error grows, in proportion to its hours, in
  // quadrature with the error it began with. NaN outside the study's hours.
  double at(int figure, double h, bool want_se = false) const;
};

// A study's life.csv for lifter profile `profile`; std::invalid_argument
// naming the file (and line, column) where it is not a life study's, the
// profile is not in it or its hours go back.
StudyPath read_study_path(const std::filesystem::path& folder, const std::string& label, int profile);

// A measured point: COLUMN@HOURS=VALUE, e.g. leading_angle_deg@4000=47.1.
struct Measured {
  int figure = 0;
  double hours = 0, value = 0;
  std::string text;  // as given
};
// std::invalid_argument naming --measured and what is wrong.
Measured parse_measured(const std::string& text);

// How far a study is from a measured point: its value there, the standard
// error, and the difference in standard errors (NaN without an error).
struct Against {
  double value = NAN, se = NAN, difference = NAN, in_se = NAN;
};
Against against(const StudyPath& s, const Measured& m);

}  // namespace mc::app::life
