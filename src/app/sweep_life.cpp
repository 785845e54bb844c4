#include "app/sweep_life.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "app/life_compare.h"
#include "app/life_state.h"
#include "app/sweep_runs.h"
#include "io/atomic_file.h"
#include "io/csv_read.h"
#include "io/json_read.h"
#include "io/png_plot.h"

namespace mc::app {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

std::string life_study_difference(const fs::path& case_dir, const nlohmann::json& request) {
  const fs::path file = case_dir / "life.json";
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    // No study yet: an empty folder, or one a sweep began (its log), and
    // nothing else.
    const std::string other = file_not_of_a_sweep(case_dir);
    return other.empty() ? "" : "it holds " + other + " and no life study (life.json): a run's folder, or another sweep's";
  }
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const std::string fault = io::json_text_fault(text);
  if (!fault.empty()) return "its life.json does not read: " + fault;
  const nlohmann::json j = nlohmann::json::parse(text);
  if (!j.is_object() || !j.contains("request") || !j["request"].is_object())
    return "its life.json has no request (not a life study's)";
  nlohmann::json asked = request;
  life::begun_before_plates(j["request"], asked);  // it resumes with its plates held
  return life::request_difference(j["request"], asked);
}

Crossing hours_to_height(const std::vector<double>& hours, const std::vector<double>& height,
                         const std::vector<double>& se, double relining_mm, double tolerance_mm) {
  Crossing c;
  const std::size_t n = std::min(hours.size(), height.size());
  if (n == 0 || !(relining_mm > 0)) return c;
  auto se_at = [&](std::size_t i) { return i < se.size() ? se[i] : NAN; };
  const double at = relining_mm + tolerance_mm;
  if (height[0] <= at) {
    c.hours = hours[0];
    return c;
  }
  for (std::size_t i = 1; i < n; ++i) {
    if (!(height[i] <= at)) continue;
    const double t = std::min(1.0, (height[i - 1] - relining_mm) / (height[i - 1] - height[i]));
    c.hours = hours[i - 1] + t * (hours[i] - hours[i - 1]);
    // The height's standard error there, as life-compare interpolates it
    // (a stage's error grows over its hours), over the path's fall per hour.
    const double a = se_at(i - 1), b = se_at(i);
    const double var = std::max(0.0, (std::isfinite(a) ? a * a : 0.0) +
                                         t * t * ((std::isfinite(b) ? b * b : 0.0) - (std::isfinite(a) ? a * a : 0.0)));
    const double slope = (height[i - 1] - height[i]) / (hours[i] - hours[i - 1]);
    if (std::isfinite(b) && slope > 0) c.se = std::sqrt(var) / slope;
    return c;
  }
  return c;
}

namespace {

// The figures tabled, as life.csv (and life-compare) names them.
struct Figure {
  int index;          // into life::kCompared
  const char* column; // the table's stem
};
const Figure kFigures[] = {{1, "height_mm"},       {0, "leading_angle_deg"}, {2, "trailing_angle_deg"},
                           {3, "shell_wear_mm"},   {5, "power_W"},           {4, "impact_point_deg"},
                           {6, "impact_wear_share"}};

json number(double v) { return std::isfinite(v) ? json(v) : json(); }

// power_sem_W of each stage (life.csv's stage rows of profile 0, or of a
// mesh study's rows without a profile), in the stages' order.
std::vector<double> power_sem(const fs::path& folder) {
  std::vector<double> out;
  const io::CsvTable t = io::read_csv_strict(folder / "life.csv");
  if (!t.has("power_sem_W")) return out;
  const int c_sem = t.column("power_sem_W"), c_profile = t.column("profile");
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const std::string& p = t.rows[r][c_profile];
    if (!p.empty() && t.number(r, c_profile) != 0) continue;
    // A window too short for batch means writes "nan": no error known.
    const std::string& cell = t.rows[r][c_sem];
    out.push_back(cell.empty() || cell == "nan" ? NAN : t.number(r, c_sem));
  }
  return out;
}

// The lifter profile the study follows, as `millcharge life` does: the
// tallest of the new liner's (life.csv's stage 0); 0 for a mesh liner's.
int tallest_profile(const fs::path& folder) {
  const io::CsvTable t = io::read_csv_strict(folder / "life.csv");
  const int c_stage = t.column("stage"), c_profile = t.column("profile"), c_height = t.column("height_mm");
  int best = 0;
  double top = -1;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    if (t.rows[r][c_profile].empty() || t.number(r, c_stage) != 0) continue;
    const double h = t.number(r, c_height);
    if (h > top) top = h, best = static_cast<int>(t.number(r, c_profile));
  }
  return best;
}

std::string value_text(const json& v, const char* fmt = "%g") {
  if (v.is_number()) {
    char buf[64];
    std::snprintf(buf, sizeof buf, fmt, v.get<double>());
    return buf;
  }
  return v.is_string() ? v.get<std::string>() : "";
}

std::string with_se(const json& v, const json& se, int digits) {
  if (!v.is_number()) return "-";
  if (!se.is_number()) return fmt::format("{:.{}f}", v.get<double>(), digits);
  return fmt::format("{:.{}f} ± {:.{}f}", v.get<double>(), digits, se.get<double>(), digits);
}

// The deepest end-plate ring at the study's last stage (life_plates.csv),
// mm; NaN where the study holds its plates.
double deepest_plate_mm(const fs::path& folder) {
  std::error_code ec;
  if (!fs::exists(folder / "life_plates.csv", ec)) return NAN;
  const io::CsvTable t = io::read_csv_strict(folder / "life_plates.csv");
  const int c_stage = t.column("stage"), c_depth = t.column("depth_mm");
  double last = -1, deepest = NAN;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const double stage = t.number(r, c_stage), d = t.number(r, c_depth);
    if (stage > last) last = stage, deepest = d;
    else if (stage == last) deepest = std::max(deepest, d);
  }
  return deepest;
}

const std::uint32_t kColours[] = {0x1f77b4, 0xd62728, 0x2ca02c, 0x9467bd, 0xff7f0e,
                                  0x8c564b, 0xe377c2, 0x17becf, 0xbcbd22, 0x7f7f7f};

}  // namespace

LifeSweep collect_life_table(const fs::path& sweep_dir, const nlohmann::json& cases, double relining_mm) {
  LifeSweep out;
  out.relining_mm = relining_mm;
  if (relining_mm > 0) out.relining_source = "--relining-height";
  else if (cases.contains("life") && cases["life"].is_object() && cases["life"].contains("until-height") &&
           cases["life"]["until-height"].is_number()) {
    out.relining_mm = cases["life"]["until-height"].get<double>();
    out.relining_source = "[life] until-height";
  }
  SweepTable& t = out.table;
  t.name = cases.value("sweep", sweep_dir.filename().string());
  for (const auto& a : cases["axes"]) t.axes.push_back(a.at("key").get<std::string>());
  t.columns = t.axes;
  for (const char* c : {"status", "stages", "hours.end", "wear_basis", "stopped"}) t.columns.push_back(c);
  for (const Figure& f : kFigures) {
    t.columns.push_back(std::string(f.column) + ".new");
    if (f.index == 5) t.columns.push_back("power_W.new_se");
    t.columns.push_back(std::string(f.column) + ".end");
    t.columns.push_back(std::string(f.column) + ".end_se");
  }
  for (const char* c : {"plate_depth_mm.end", "relining_height_mm", "hours_to_relining", "hours_to_relining_se", "error"})
    t.columns.push_back(c);

  for (const auto& c : cases["cases"]) {
    json row;
    for (const std::string& key : t.axes) row[key] = c.at("values").contains(key) ? json(c["values"][key]) : json();
    const fs::path folder = case_path(sweep_dir, c.at("dir").get<std::string>());
    const CaseState st = case_state(folder, true);
    row["status"] = status_name(st.status);
    if (st.status == CaseStatus::failed) row["error"] = st.last_line;
    LifeSweep::Path path;
    for (const std::string& key : t.axes) {
      const json& v = row[key];
      path.label += (path.label.empty() ? "" : ", ") + key.substr(key.find_last_of(".]") + 1) + " " + value_text(v);
    }
    std::error_code ec;
    if (fs::exists(folder / "life.csv", ec)) {
      try {
        const life::StudyPath p = life::read_study_path(folder, path.label, tallest_profile(folder));
        const nlohmann::json state = life_study_state(folder);
        const std::vector<double> sem = power_sem(folder);
        const std::size_t last = p.hours.size() - 1;
        row["stages"] = static_cast<double>(last);
        row["hours.end"] = p.hours[last];
        row["wear_basis"] = p.basis;
        row["stopped"] = life_study_stopped(state);
        for (const Figure& f : kFigures) {
          row[std::string(f.column) + ".new"] = number(p.value[f.index][0]);
          row[std::string(f.column) + ".end"] = number(p.value[f.index][last]);
          row[std::string(f.column) + ".end_se"] = number(f.index == 5 ? (last < sem.size() ? sem[last] : NAN)
                                                                       : p.se[f.index][last]);
          if (f.index == 5) row["power_W.new_se"] = number(sem.empty() ? NAN : sem[0]);
        }
        if (out.relining_mm > 0) {
          // A study stopped by its own --until-height at this height ends
          // within 0.05 mm above it (app/life.cpp).
          double until = 0;
          if (state.contains("request") && state["request"].is_object() && state["request"].contains("until_height_mm") &&
              state["request"]["until_height_mm"].is_number())
            until = state["request"]["until_height_mm"].get<double>();
          const Crossing x = hours_to_height(p.hours, p.value[1], p.se[1], out.relining_mm,
                                             until > 0 && std::abs(until - out.relining_mm) < 1e-9 ? 0.05 : 0.0);
          row["hours_to_relining"] = number(x.hours);
          row["hours_to_relining_se"] = number(x.se);
        }
        row["plate_depth_mm.end"] = number(deepest_plate_mm(folder));
        path.hours = p.hours, path.height = p.value[1], path.leading = p.value[0];
        path.power = p.value[5], path.impact = p.value[4];
      } catch (const std::invalid_argument& e) {
        row["error"] = e.what();
      }
    }
    row["relining_height_mm"] = out.relining_mm > 0 ? json(out.relining_mm) : json();
    for (const std::string& col : t.columns)
      if (!row.contains(col)) row[col] = nullptr;
    if (st.status == CaseStatus::done) ++t.finished;
    t.rows.push_back(row);
    out.paths.push_back(path);
  }
  return out;
}

bool write_life_sweep_plot(const LifeSweep& s, const fs::path& file) {
  struct Panel {
    const char* title;
    const char* y;
    std::vector<double> LifeSweep::Path::*values;
  };
  const Panel panels[] = {{"lifter height", "height (mm)", &LifeSweep::Path::height},
                          {"leading face", "leading face angle (deg)", &LifeSweep::Path::leading},
                          {"power", "torque power (W)", &LifeSweep::Path::power},
                          {"impact point", "impact point (deg)", &LifeSweep::Path::impact}};
  std::string basis;
  for (const json& r : s.table.rows)
    if (r["wear_basis"].is_string()) basis = r["wear_basis"].get<std::string>();
  const std::string hours = basis == "relative" ? "hours (relative: wear coefficient not calibrated)" : "operating hours";
  std::vector<io::LinePlot> plots;
  for (const Panel& p : panels) {
    io::LinePlot lp;
    lp.title = s.table.name + ": " + p.title;
    lp.x_label = hours;
    lp.y_label = p.y;
    for (std::size_t i = 0; i < s.paths.size(); ++i) {
      const LifeSweep::Path& path = s.paths[i];
      if (path.hours.empty()) continue;
      io::PlotSeries ps{path.label, path.hours, path.*(p.values), kColours[i % std::size(kColours)], true};
      lp.series.push_back(ps);
    }
    if (&p == &panels[0] && s.relining_mm > 0)
      lp.ref_lines.push_back({s.relining_mm, 0, 0, 0x222222, true, fmt::format("relining height {:g} mm", s.relining_mm)});
    if (&p == &panels[0]) lp.y_cover_lo = 0;
    plots.push_back(lp);
  }
  if (plots.front().series.empty()) return false;
  return io::draw_or_warn(file, [&] { io::write_line_plots_png(file, plots, 960, 380); });
}

int collect_life_sweep(const fs::path& dir, const nlohmann::json& cases, double relining_mm) {
  const LifeSweep s = collect_life_table(dir, cases, relining_mm);
  const SweepTable& t = s.table;
  io::write_file_atomic(dir / "sweep.csv", table_csv(t));
  json j = table_json(t);
  j["command"] = "life";
  j["relining_height_mm"] = s.relining_mm > 0 ? json(s.relining_mm) : json();
  io::write_file_atomic(dir / "sweep.json", j.dump(2) + "\n");
  std::error_code ec;
  fs::remove(dir / "sweep.png", ec);  // a picture of other studies would mislead
  const bool drawn = write_life_sweep_plot(s, dir / "sweep.png");

  // The console: each study's end beside its new liner's.
  std::vector<std::vector<std::string>> rows(1);
  for (const std::string& a : t.axes) rows[0].push_back(a.substr(a.find_last_of(".]") + 1));
  for (const char* h : {"status", "stages", "hours", "height_mm", "leading_deg", "power_W new", "end",
                        "impact_deg new", "end"})
    rows[0].push_back(h);
  bool relative = false;
  for (const json& r : t.rows) relative = relative || (r["wear_basis"].is_string() && r["wear_basis"] == "relative");
  bool plates = false;  // a study that wears its end plates: their deepest ring at its end
  for (const json& r : t.rows) plates = plates || r["plate_depth_mm.end"].is_number();
  if (plates) rows[0].push_back("plate_mm end");
  if (s.relining_mm > 0)
    rows[0].push_back(fmt::format("{}hours to {:g} mm", relative ? "relative " : "", s.relining_mm));
  rows[0].push_back("error");
  for (const json& r : t.rows) {
    std::vector<std::string> line;
    for (const std::string& a : t.axes) line.push_back(value_text(r[a]));
    line.push_back(r["status"].get<std::string>());
    line.push_back(r["stages"].is_number() ? value_text(r["stages"], "%.0f") : "-");
    line.push_back(r["hours.end"].is_number() ? value_text(r["hours.end"], "%.0f") : "-");
    line.push_back(with_se(r["height_mm.end"], r["height_mm.end_se"], 1));
    line.push_back(with_se(r["leading_angle_deg.end"], r["leading_angle_deg.end_se"], 1));
    line.push_back(with_se(r["power_W.new"], r["power_W.new_se"], 0));
    line.push_back(with_se(r["power_W.end"], r["power_W.end_se"], 0));
    line.push_back(with_se(r["impact_point_deg.new"], json(), 1));
    line.push_back(with_se(r["impact_point_deg.end"], json(), 1));
    if (plates) line.push_back(r["plate_depth_mm.end"].is_number() ? value_text(r["plate_depth_mm.end"], "%.1f") : "-");
    if (s.relining_mm > 0)
      line.push_back(r["hours_to_relining"].is_number()
                         ? with_se(r["hours_to_relining"], r["hours_to_relining_se"], 0)
                         : r["hours.end"].is_number() ? "not by " + value_text(r["hours.end"], "%.0f") : "-");
    line.push_back(r["error"].is_string() ? r["error"].get<std::string>() : "");
    rows.push_back(line);
  }
  std::vector<std::size_t> width;
  for (const auto& r : rows)
    for (std::size_t i = 0; i + 1 < r.size(); ++i) {
      if (width.size() <= i) width.resize(i + 1, 0);
      // "±" is two bytes and one column.
      const std::size_t shown = r[i].size() - std::count(r[i].begin(), r[i].end(), '\xC2');
      width[i] = std::max(width[i], shown);
    }
  for (const auto& r : rows) {
    std::string line;
    for (std::size_t i = 0; i < r.size(); ++i) {
      line += r[i];
      const std::size_t shown = r[i].size() - std::count(r[i].begin(), r[i].end(), '\xC2');
      if (i + 1 < r.size()) line += std::string(width[i] - shown + 2, ' ');
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    std::printf("%s\n", line.c_str());
  }
  std::printf("%d of %zu studies ended; the end is each study's last stage, ± its standard error (the stage "
              "windows' noise carried along the study)%s; wrote %s/{sweep.csv, sweep.json%s}\n",
              t.finished, t.rows.size(),
              s.relining_mm > 0 ? fmt::format("; relining height {:g} mm ({})", s.relining_mm, s.relining_source).c_str()
                                : "; give --relining-height MM for the hours to it",
              dir.string().c_str(), drawn ? ", sweep.png" : "");
  return 0;
}

}  // namespace mc::app
