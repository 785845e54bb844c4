// millcharge life-compare (life_compare.h): life studies side by side.
#include "app/life_compare.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <set>
#include <stdexcept>

#include "app/commands.h"
#include "app/life_picture.h"
#include "io/atomic_file.h"
#include "io/csv_read.h"
#include "io/png_plot.h"

namespace mc::app {

namespace fs = std::filesystem;

namespace life {

namespace {

int figure_of(const std::string& name) {
  for (int f = 0; f < kComparedCount; ++f)
    if (name == kCompared[f]) return f;
  return -1;
}

std::string drawn_names() {
  std::string t;
  for (int f = 0; f < kDrawnCount; ++f) t += (f ? ", " : "") + std::string(kCompared[f]);
  return t;
}

// A field that may be empty (a figure the study has no value for): NaN.
double optional_number(const io::CsvTable& t, std::size_t r, int c) {
  if (c < 0 || t.rows[r][c].empty()) return NAN;
  return t.number(r, c);
}

// A stage's hours (after the last's) and the study's wear basis from
// life.csv's row r.
void add_stage_hours(const io::CsvTable& t, std::size_t r, int c_hours, StudyPath& s) {
  const double h = t.number(r, c_hours);
  if (!s.hours.empty() && h < s.hours.back())
    throw std::invalid_argument(fmt::format("{}: hours: {:g} after {:g}: a study's hours do not go back", t.where(r), h,
                                            s.hours.back()));
  s.hours.push_back(h);
  if (s.basis.empty() && t.has("wear_basis")) s.basis = t.rows[r][t.column("wear_basis")];
}

// A mesh study's path: the stage figures of life.csv, the bars' from
// life_meshes.csv (the K-th worn mesh's rows).
StudyPath read_mesh_study_path(const fs::path& folder, const io::CsvTable& t, StudyPath s, int mesh) {
  const fs::path file = folder / "life_meshes.csv";
  const io::CsvTable m = io::read_csv_strict(file, " (a life study of a mesh liner holds life_meshes.csv)");
  const char* bars[] = {"mid_leading_angle_deg", "mid_height_mm", "mid_trailing_angle_deg"};  // figures 0 to 2
  const int c_stage = m.column("stage"), c_mesh = m.column("mesh"), c_hours = t.column("hours");
  std::vector<int> meshes;  // the worn meshes' [[walls.mesh]] indices, in order
  for (std::size_t r = 0; r < m.rows.size(); ++r) {
    const int k = static_cast<int>(m.number(r, c_mesh));
    if (std::find(meshes.begin(), meshes.end(), k) == meshes.end()) meshes.push_back(k);
  }
  if (mesh < 0 || mesh >= static_cast<int>(meshes.size()))
    throw std::invalid_argument(fmt::format("{}: --profile {}: the study wears {} mesh{} (0 to {})", file.string(), mesh,
                                            meshes.size(), meshes.size() == 1 ? "" : "es",
                                            static_cast<int>(meshes.size()) - 1));
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    add_stage_hours(t, r, c_hours, s);
    // The stage's row of the mesh in life_meshes.csv.
    long row = -1;
    for (std::size_t q = 0; q < m.rows.size() && row < 0; ++q)
      if (m.number(q, c_stage) == t.number(r, t.column("stage")) && m.number(q, c_mesh) == meshes[mesh])
        row = static_cast<long>(q);
    if (row < 0)
      throw std::invalid_argument(fmt::format("{}: no row of stage {} and mesh {}", file.string(),
                                              t.rows[r][t.column("stage")], meshes[mesh]));
    for (int f = 0; f < kComparedCount; ++f) {
      if (f < 3) {
        s.value[f].push_back(optional_number(m, row, m.column(bars[f])));
        s.se[f].push_back(optional_number(m, row, m.column(std::string(bars[f]) + "_se")));
      } else {
        s.value[f].push_back(optional_number(t, r, t.has(kCompared[f]) ? t.column(kCompared[f]) : -1));
        s.se[f].push_back(NAN);
      }
    }
  }
  return s;
}

}  // namespace

double StudyPath::at(int figure, double h, bool want_se) const {
  const std::vector<double>& y = want_se ? se[figure] : value[figure];
  const std::size_t n = hours.size();
  if (n == 0 || !(h >= hours.front() - 1e-9) || !(h <= hours.back() + 1e-9)) return NAN;
  for (std::size_t i = 0; i < n; ++i)
    if (std::abs(hours[i] - h) <= 1e-9 * std::max(1.0, std::abs(h))) return y[i];
  for (std::size_t i = 1; i < n; ++i)
    if (h < hours[i]) {
      const double t = (h - hours[i - 1]) / (hours[i] - hours[i - 1]);
      // Within a stage one window's error in the wear rate acts over the
      // hours so far: the stage's own error grows in proportion to them,
      // added in quadrature to the error the stage began with.
      if (want_se) return std::sqrt(y[i - 1] * y[i - 1] + t * t * (y[i] * y[i] - y[i - 1] * y[i - 1]));
      return y[i - 1] + t * (y[i] - y[i - 1]);
    }
  return y.back();
}

StudyPath read_study_path(const fs::path& folder, const std::string& label, int profile) {
  const fs::path file = folder / "life.csv";
  if (!fs::is_directory(folder)) throw std::invalid_argument(folder.string() + ": not a folder (a life study's --out)");
  const io::CsvTable t = io::read_csv_strict(file, " (a life study's folder holds life.csv)");
  StudyPath s;
  s.label = label, s.folder = folder.string();
  s.value.assign(kComparedCount, {}), s.se.assign(kComparedCount, {});
  const int c_hours = t.column("hours", "a life study's life.csv"), c_profile = t.column("profile", "a life study's life.csv");
  std::vector<int> c_value(kComparedCount), c_se(kComparedCount);
  for (int f = 0; f < kComparedCount; ++f) {
    // impact_wear_share came with impact wear: an older study has none.
    c_value[f] = f == 6 && !t.has(kCompared[f]) ? -1 : t.column(kCompared[f], "a life study's life.csv");
    const std::string se = std::string(kCompared[f]) + "_se";
    c_se[f] = t.has(se) ? t.column(se) : -1;
  }
  // A study whose bars are a mesh: its stage rows have no profile, and
  // life_meshes.csv measures the bars (the mean of their sections at
  // mid-length, its standard error from their spread); --profile K picks
  // its K-th worn mesh.
  if (!t.rows.empty() && t.rows[0][c_profile].empty()) return read_mesh_study_path(folder, t, std::move(s), profile);
  int profiles = 0;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const double p = t.number(r, c_profile);
    profiles = std::max(profiles, static_cast<int>(p) + 1);
    if (static_cast<int>(p) != profile) continue;
    add_stage_hours(t, r, c_hours, s);
    for (int f = 0; f < kComparedCount; ++f) {
      s.value[f].push_back(optional_number(t, r, c_value[f]));
      s.se[f].push_back(optional_number(t, r, c_se[f]));
    }
  }
  if (s.hours.empty())
    throw std::invalid_argument(fmt::format("{}: --profile {}: the study has lifter profiles 0 to {}", file.string(),
                                            profile, profiles - 1));
  return s;
}

Measured parse_measured(const std::string& text) {
  const std::size_t at = text.find('@'), eq = text.find('=');
  const auto bad = [&](const std::string& why) {
    return std::invalid_argument("--measured " + text + ": " + why +
                                 " (expected COLUMN@HOURS=VALUE, e.g. leading_angle_deg@4000=47.1)");
  };
  if (at == std::string::npos || eq == std::string::npos || eq < at) throw bad("not COLUMN@HOURS=VALUE");
  Measured m;
  m.text = text;
  m.figure = figure_of(text.substr(0, at));
  if (m.figure < 0 || m.figure >= kDrawnCount) throw bad("the column is one of " + drawn_names());
  const auto number = [&](const std::string& s, double& x) {
    char* end = nullptr;
    x = std::strtod(s.c_str(), &end);
    return !s.empty() && *end == '\0' && std::isfinite(x);
  };
  if (!number(text.substr(at + 1, eq - at - 1), m.hours) || m.hours < 0) throw bad("the hours are not a number >= 0");
  if (!number(text.substr(eq + 1), m.value)) throw bad("the value is not a number");
  return m;
}

Against against(const StudyPath& s, const Measured& m) {
  Against a;
  a.value = s.at(m.figure, m.hours);
  a.se = s.at(m.figure, m.hours, true);
  a.difference = a.value - m.value;
  if (a.se > 0) a.in_se = a.difference / a.se;
  return a;
}

}  // namespace life

namespace {

std::string num(double v, int digits) { return std::isfinite(v) ? fmt::format("{:.{}f}", v, digits) : ""; }

std::string with_se(double v, double se, int digits) {
  if (!std::isfinite(v)) return "-";
  return std::isfinite(se) ? fmt::format("{:.{}f} ± {:.{}f}", v, digits, se, digits) : fmt::format("{:.{}f}", v, digits);
}

const std::uint32_t kColours[] = {0x1f77b4, 0xd62728, 0x2ca02c, 0x9467bd, 0xff7f0e, 0x8c564b, 0xe377c2, 0x17becf};

}  // namespace

int cmd_life_compare(const LifeCompareOptions& o) {
  using namespace life;
  if (!o.labels.empty() && o.labels.size() != o.studies.size())
    throw std::invalid_argument(fmt::format("--label: given {} times for {} studies (one per study, in their order)",
                                            o.labels.size(), o.studies.size()));
  std::vector<StudyPath> paths;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < o.studies.size(); ++i) {
    const std::string label = o.labels.empty() ? fs::path(o.studies[i]).lexically_normal().filename().string() : o.labels[i];
    if (!seen.insert(label).second)
      throw std::invalid_argument("--label " + label + ": two studies have this label; give each its own (--label)");
    paths.push_back(read_study_path(o.studies[i], label, o.profile));
  }
  for (const StudyPath& s : paths)
    if (s.basis != paths.front().basis)
      std::cerr << fmt::format("millcharge: note: the studies' hours stand on different grounds ({} {}, {} {}): "
                               "compare them by shape, not by hours\n",
                               paths.front().label, paths.front().basis, s.label, s.basis);
  std::vector<Measured> measured;
  for (const std::string& m : o.measured) measured.push_back(parse_measured(m));
  double end = INFINITY;
  for (const StudyPath& s : paths) end = std::min(end, s.hours.back());
  std::vector<double> at = o.at;
  if (at.empty())
    for (int q = 1; q <= 4; ++q) at.push_back(end * q / 4);
  for (double h : at)
    for (const StudyPath& s : paths)
      if (h > s.hours.back() * (1 + 1e-9))
        throw std::invalid_argument(fmt::format("--at {:g}: study {} ({}) ends at {:g} h", h, s.label, s.folder,
                                                s.hours.back()));
  const fs::path out = o.out.empty() ? fs::path("runs/life-compare") : fs::path(o.out);
  fs::create_directories(out);

  // compare.csv: each study at each hour asked, every figure with its ±.
  std::string csv = "label,study,hours";
  for (int f = 0; f < kComparedCount; ++f) csv += fmt::format(",{0},{0}_se", kCompared[f]);
  csv += "\n";
  for (const StudyPath& s : paths)
    for (double h : at) {
      csv += fmt::format("{},{},{:.6g}", s.label, s.folder, h);
      for (int f = 0; f < kComparedCount; ++f) csv += "," + num(s.at(f, h), 4) + "," + num(s.at(f, h, true), 4);
      csv += "\n";
    }
  io::write_file_atomic(out / "compare.csv", csv);

  // compare.png: the drawn figures over the hours, bands of ± 2 standard
  // errors, the measured points.
  static const char* titles[] = {"leading face angle", "height above the shell", "trailing face angle",
                                 "shell worn since new"};
  static const char* units[] = {"face angle from the radial line (deg)", "height above the shell (mm)",
                                "face angle from the radial line (deg)", "shell worn (mm)"};
  std::vector<io::LinePlot> plots;
  for (int f = 0; f < kDrawnCount; ++f) {
    io::LinePlot p;
    p.title = std::string(titles[f]) + " (bands: \u00b1 2 standard errors where the study has them)";
    // Relative hours (the default wear coefficient, not calibrated) said so
    // where every study stands on them.
    const bool relative =
        std::all_of(paths.begin(), paths.end(), [](const StudyPath& s) { return s.basis == "relative"; });
    p.x_label = hours_label(relative);
    p.y_label = units[f];
    for (std::size_t i = 0; i < paths.size(); ++i) {
      const StudyPath& s = paths[i];
      io::PlotSeries line;
      line.label = s.label;
      line.rgb = kColours[i % 8];
      line.markers = true;
      line.x = s.hours, line.y = s.value[f];
      bool any = false;
      for (std::size_t k = 0; k < s.hours.size(); ++k) {
        const double e = 2 * s.se[f][k];
        any = any || std::isfinite(e);
        line.band_lo.push_back(std::isfinite(e) ? s.value[f][k] - e : NAN);
        line.band_hi.push_back(std::isfinite(e) ? s.value[f][k] + e : NAN);
      }
      if (!any) line.band_lo.clear(), line.band_hi.clear();
      p.series.push_back(line);
    }
    for (const Measured& m : measured)
      if (m.figure == f) {
        io::PlotSeries pt;
        pt.label = fmt::format("measured: {:g} at {:g} h", m.value, m.hours);
        pt.rgb = 0x000000;
        pt.markers = true;
        pt.x = {m.hours}, pt.y = {m.value};
        p.series.push_back(pt);
      }
    if (f == 1 || f == 3) p.y_cover_lo = 0;
    p.pad_x = true;
    plots.push_back(p);
  }
  io::draw_or_warn(out / "compare.png", [&] { io::write_line_plots_png(out / "compare.png", plots, 960, 380); });

  if (!o.quiet) {
    for (const StudyPath& s : paths) {
      std::cout << fmt::format("{:<15} {} ({} stages to {:g} h)\n", "study", s.label, s.hours.size() - 1, s.hours.back());
      for (double h : at)
        std::cout << fmt::format("{:<15}   {:>7g} h: leading face {} deg, height {} mm, trailing face {} deg, shell worn {} mm\n",
                                 "", h, with_se(s.at(0, h), s.at(0, h, true), 1), with_se(s.at(1, h), s.at(1, h, true), 1),
                                 with_se(s.at(2, h), s.at(2, h, true), 1), num(s.at(3, h), 1));
    }
    for (const Measured& m : measured)
      for (const StudyPath& s : paths) {
        const Against a = against(s, m);
        if (m.hours > s.hours.back() * (1 + 1e-9)) {  // beyond the study: drawn, not compared
          std::cout << fmt::format("{:<15} {} at {:g} h, {}: the study ends at {:g} h\n", "measured",
                                   kCompared[m.figure], m.hours, s.label, s.hours.back());
          continue;
        }
        std::cout << fmt::format("{:<15} {} at {:g} h, {}: {} against {:g} measured ({:+.1f}{})\n", "measured",
                                 kCompared[m.figure], m.hours, s.label, with_se(a.value, a.se, 1), m.value, a.difference,
                                 std::isfinite(a.in_se) ? fmt::format(", {:.1f} standard errors", a.in_se) : "");
      }
    std::cout << fmt::format("{:<15} {}/{{compare.csv, compare.png}}\n", "wrote", out.string());
  }
  return 0;
}

}  // namespace mc::app
