#include "app/sweep_table.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "app/sweep_runs.h"
#include "core/version.h"
#include "io/json_read.h"
#include "io/png_plot.h"

namespace mc::app {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

namespace {

// summary.json fields taken as they are: (column, path in summary.json).
const std::vector<std::pair<std::string, std::string>> kSummaryFields = {
    {"n_particles", "/n_particles"},
    {"speed_fraction", "/speed_fraction"},
    {"speed_rpm", "/speed_rpm"},
    {"filling", "/filling"},
    {"revolutions_averaged", "/average/revolutions"},
    {"power_W.torque", "/power_W/torque"},
    {"power_W.dissipation", "/power_W/dissipation"},
    {"power_W.imbalance", "/power_W/imbalance"},
    {"torque_Nm", "/torque_Nm"},
    {"toe_deg", "/toe_deg"},
    {"shoulder_deg", "/shoulder_deg"},
    {"com_angle_deg", "/com_angle_deg"},
    {"morrell.power_W", "/morrell/power_W"},
    {"morrell.toe_deg", "/morrell/toe_deg"},
    {"morrell.shoulder_deg", "/morrell/shoulder_deg"},
    // standard errors (batch means over whole revolutions); empty in
    // summaries written before they were
    {"power_W.torque_sem", "/power_W/torque_sem"},
    {"torque_Nm_sem", "/torque_Nm_sem"},
    {"toe_deg_sem", "/toe_deg_sem"},
    {"shoulder_deg_sem", "/shoulder_deg_sem"},
};
// Blocks whose numeric scalars all become columns "BLOCK.FIELD".
const std::vector<std::string> kOpenBlocks = {"spectra.total", "liner"};

json number_at(const nlohmann::json& j, const std::string& pointer) {
  const nlohmann::json::json_pointer p(pointer);
  if (!j.contains(p)) return nullptr;
  const nlohmann::json& v = j.at(p);
  return v.is_number() ? json(v.get<double>()) : json(nullptr);
}

double as_number(const json& v) { return v.is_number() ? v.get<double>() : std::nan(""); }

// mill.length of a run folder's resolved case.toml (m); NaN when unreadable.
double case_length(const fs::path& case_toml) {
  try {
    const toml::table t = toml::parse_file(case_toml.string());
    if (auto v = t.at_path("mill.length").value<double>()) return *v;
  } catch (const std::exception&) {
  }
  return std::nan("");
}

std::string csv_cell(const json& v) {
  if (v.is_null()) return "";
  if (v.is_number()) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.10g", v.get<double>());
    return buf;
  }
  std::string s = v.is_string() ? v.get<std::string>() : v.dump();
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char ch : s) out += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return out + "\"";
}

}  // namespace

SweepTable collect_table(const fs::path& sweep_dir) {
  const fs::path index = sweep_dir / "cases.json";
  std::ifstream in(index);
  if (!in)
    throw std::invalid_argument(sweep_dir.string() +
                                ": not a sweep folder (no cases.json; `millcharge sweep run FILE` writes one)");
  nlohmann::json cases = io::read_json_file(index);
  const io::JsonAt at(cases, index.string());
  try {
    if (at.has("sweep")) (void)at["sweep"].text();
    for (std::size_t a = 0; a < at["axes"].size(); ++a) (void)at["axes"][a]["key"].text();
    for (std::size_t k = 0; k < at["cases"].size(); ++k) {
      (void)at["cases"][k]["dir"].text();
      at["cases"][k]["values"].object();
    }
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(e.what()) + "; not a sweep's cases.json");
  }

  SweepTable t;
  t.name = cases.value("sweep", sweep_dir.filename().string());
  for (const auto& a : cases["axes"]) t.axes.push_back(a.at("key").get<std::string>());
  std::vector<std::string> fixed = t.axes;
  fixed.push_back("status");
  for (const auto& [column, path] : kSummaryFields) fixed.push_back(column);
  std::vector<std::string> open_columns;  // from the open blocks, in order of appearance

  for (const auto& c : cases["cases"]) {
    json row;
    for (const std::string& key : t.axes) row[key] = c.at("values").contains(key) ? json(c["values"][key]) : json();
    const std::string dir = c.at("dir").get<std::string>();
    const fs::path folder = case_path(sweep_dir, dir);
    const CaseState st = case_state(folder);
    row["status"] = status_name(st.status);
    nlohmann::json summary;
    if (st.status == CaseStatus::done) {
      std::ifstream s(folder / "summary.json", std::ios::binary);
      const std::string text{std::istreambuf_iterator<char>(s), std::istreambuf_iterator<char>()};
      const std::string fault = io::json_text_fault(text);
      if (fault.empty()) {
        summary = nlohmann::json::parse(text);
      } else {
        row["status"] = status_name(CaseStatus::failed);
        row["error"] = "summary.json: " + fault;
      }
    }
    const bool have = summary.is_object();
    for (const auto& [column, path] : kSummaryFields) row[column] = have ? number_at(summary, path) : json();
    // A figure the run writes as a number (or null, where it has none) that
    // is anything else: the file was damaged after the run; said in the row.
    if (have)
      for (const auto& [column, path] : kSummaryFields) {
        const nlohmann::json::json_pointer ptr(path);
        if (!summary.contains(ptr)) continue;
        const nlohmann::json& v = summary.at(ptr);
        if (v.is_number() || v.is_null()) continue;
        row["status"] = status_name(CaseStatus::failed);
        row["error"] = "summary.json: " + path.substr(1) + ": expected a number, found " + std::string(v.type_name()) +
                       "; the file is damaged";
        break;
      }

    // Per metre of mill: the run's own figure where it gives one (a periodic
    // slice), else the power over the case's length.
    const double length = have ? case_length(folder / "case.toml") : std::nan("");
    json per_torque, per_diss;
    if (have && summary.contains("power_per_metre_W")) {
      const auto& p = summary["power_per_metre_W"];
      if (p.is_number()) per_torque = p.get<double>();
      else if (p.is_object()) per_torque = number_at(p, "/torque"), per_diss = number_at(p, "/dissipation");
    } else if (length > 0) {
      if (row["power_W.torque"].is_number()) per_torque = row["power_W.torque"].get<double>() / length;
      if (row["power_W.dissipation"].is_number()) per_diss = row["power_W.dissipation"].get<double>() / length;
    }
    row["length_m"] = length > 0 ? json(length) : json();
    row["power_per_metre_W.torque"] = per_torque;
    row["power_per_metre_W.dissipation"] = per_diss;
    row["morrell.power_per_metre_W"] =
        length > 0 && row["morrell.power_W"].is_number() ? json(row["morrell.power_W"].get<double>() / length) : json();

    for (const std::string& block : kOpenBlocks) {
      std::string pointer;
      for (std::size_t from = 0;;) {
        const std::size_t dot = block.find('.', from);
        pointer += "/" + block.substr(from, dot - from);
        if (dot == std::string::npos) break;
        from = dot + 1;
      }
      if (!have || !summary.contains(nlohmann::json::json_pointer(pointer))) continue;
      const auto& b = summary.at(nlohmann::json::json_pointer(pointer));
      if (!b.is_object()) continue;
      for (const auto& [k, v] : b.items()) {
        if (!v.is_number()) continue;
        const std::string column = block + "." + k;
        row[column] = v.get<double>();
        if (std::find(open_columns.begin(), open_columns.end(), column) == open_columns.end())
          open_columns.push_back(column);
      }
    }
    // The grind of the case's run, where `millcharge grind` wrote one in
    // its default folder: P80 and specific energy per product, and the
    // throughput at the target P80.
    if (have) {
      nlohmann::json grind;
      std::ifstream g(folder / "grind" / "grind.json", std::ios::binary);
      if (g) {
        const std::string text{std::istreambuf_iterator<char>(g), std::istreambuf_iterator<char>()};
        const std::string fault = io::json_text_fault(text);
        // Said in the row, not read as no grind at all.
        if (fault.empty()) grind = nlohmann::json::parse(text);
        else row["error"] = "grind/grind.json: " + fault + "; its columns are left empty";
      }
      auto put = [&](const std::string& column, const json& v) {
        row[column] = v;
        if (std::find(open_columns.begin(), open_columns.end(), column) == open_columns.end())
          open_columns.push_back(column);
      };
      if (grind.is_object() && grind.contains("products") && grind["products"].is_array()) {
        for (const auto& p : grind["products"]) {
          if (!p.is_object() || !p.contains("label") || !p["label"].is_string()) continue;
          const std::string label = "grind." + p["label"].get<std::string>();
          put(label + ".P80_um", number_at(p, "/P80_um"));
          put(label + ".specific_energy_kWh_t", number_at(p, "/specific_energy_kWh_t"));
        }
        if (grind.contains("throughput_at_target_t_h"))
          put("grind.throughput_at_target_t_h", number_at(grind, "/throughput_at_target_t_h"));
      }
    }
    row["wall_s"] = have ? number_at(summary, "/wall_s") : json();
    // The code each case's run was made by (summaries before the stamp: empty).
    const bool stamped = have && summary.contains("build") && summary["build"].is_object() &&
                         summary["build"].contains("commit") && summary["build"]["commit"].is_string();
    row["build"] = stamped ? json(summary["build"]["commit"].get<std::string>()) : json();
    row["exit_status"] = st.exit_status >= 0 ? json(st.exit_status) : json();
    if (!row.contains("error")) {
      const bool explain = st.status == CaseStatus::failed || st.status == CaseStatus::stopped ||
                           st.status == CaseStatus::incomplete;
      row["error"] = explain && !st.last_line.empty() ? json(st.last_line) : json();
    }
    row["case"] = dir;
    t.finished += row["status"] == "done";
    t.rows.push_back(std::move(row));
  }

  t.columns = fixed;
  for (const char* c : {"length_m", "power_per_metre_W.torque", "power_per_metre_W.dissipation",
                        "morrell.power_per_metre_W"})
    t.columns.push_back(c);
  t.columns.insert(t.columns.end(), open_columns.begin(), open_columns.end());
  for (const char* c : {"wall_s", "build", "exit_status", "error", "case"}) t.columns.push_back(c);
  for (json& row : t.rows)  // every row has every column, in order
    for (const std::string& c : t.columns)
      if (!row.contains(c)) row[c] = nullptr;
  return t;
}

std::string table_csv(const SweepTable& t) {
  std::ostringstream o;
  for (std::size_t i = 0; i < t.columns.size(); ++i) o << (i ? "," : "") << csv_cell(json(t.columns[i]));
  o << "\n";
  for (const json& row : t.rows) {
    for (std::size_t i = 0; i < t.columns.size(); ++i) o << (i ? "," : "") << csv_cell(row[t.columns[i]]);
    o << "\n";
  }
  return o.str();
}

json table_json(const SweepTable& t) {
  json j;
  j["sweep"] = t.name;
  j["axes"] = t.axes;
  j["columns"] = t.columns;
  j["cases_total"] = t.rows.size();
  j["cases_finished"] = t.finished;
  j["collected_by"] = {{"version", version()}, {"commit", build_commit()}};
  j["cases"] = json::array();
  for (const json& row : t.rows) {
    json r;
    for (const std::string& c : t.columns) r[c] = row[c];
    j["cases"].push_back(r);
  }
  return j;
}

namespace {

const std::uint32_t kPalette[] = {0x1f77b4, 0xd62728, 0x2ca02c, 0x9467bd, 0xff7f0e,
                                  0x8c564b, 0xe377c2, 0x17becf, 0xbcbd22, 0x7f7f7f};

std::string short_key(const std::string& key) {
  const std::size_t cut = key.find_last_of(".]");
  return cut == std::string::npos ? key : key.substr(cut + 1);
}

std::string value_text(const json& v) {
  if (v.is_number()) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", v.get<double>());
    return buf;
  }
  return v.is_string() ? v.get<std::string>() : v.dump();
}

// The rows split into lines: one per combination of the axes that do not
// move with the first (the first axis's own group is the x axis).
struct Lines {
  std::vector<std::string> labels;
  std::vector<std::vector<std::size_t>> rows;  // per line, rows sorted by x
  std::vector<double> x_of_row;
  bool numeric_x = true;
  std::vector<std::string> x_names;            // when the first axis is not numeric
};

Lines split_lines(const SweepTable& t, const std::vector<int>& groups) {
  Lines l;
  const std::string& first = t.axes.front();
  for (const json& row : t.rows) l.numeric_x = l.numeric_x && row[first].is_number();
  for (const json& row : t.rows) {
    if (l.numeric_x) {
      l.x_of_row.push_back(row[first].get<double>());
    } else {
      const std::string s = value_text(row[first]);
      auto it = std::find(l.x_names.begin(), l.x_names.end(), s);
      if (it == l.x_names.end()) it = l.x_names.insert(l.x_names.end(), s);
      l.x_of_row.push_back(static_cast<double>(it - l.x_names.begin()));
    }
  }
  std::map<std::string, std::size_t> line_of;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    std::string label;
    for (std::size_t a = 1; a < t.axes.size(); ++a) {
      if (groups[a] == groups[0]) continue;
      label += (label.empty() ? "" : ", ") + short_key(t.axes[a]) + " " + value_text(t.rows[r][t.axes[a]]);
    }
    auto [it, fresh] = line_of.emplace(label, l.labels.size());
    if (fresh) l.labels.push_back(label), l.rows.emplace_back();
    l.rows[it->second].push_back(r);
  }
  for (auto& rows : l.rows)
    std::stable_sort(rows.begin(), rows.end(), [&](std::size_t a, std::size_t b) { return l.x_of_row[a] < l.x_of_row[b]; });
  return l;
}

bool any_finite(const SweepTable& t, const std::string& column) {
  for (const json& row : t.rows)
    if (row[column].is_number() && std::isfinite(row[column].get<double>())) return true;
  return false;
}

// One plot: `column` per line (solid, with markers), `model` (if any) dashed
// beside it, a model line left out where it repeats another.
io::LinePlot figure_plot(const SweepTable& t, const Lines& l, const std::string& column, const std::string& model,
                         const std::string& what) {
  io::LinePlot p;
  p.title = t.name + ": " + what;
  p.x_label = t.axes.front();
  if (!l.numeric_x) {  // values that are not numbers sit at 0, 1, 2, ...
    p.x_label += " (";
    for (std::size_t i = 0; i < l.x_names.size(); ++i) p.x_label += (i ? ", " : "") + std::to_string(i) + " " + l.x_names[i];
    p.x_label += ")";
  }
  p.y_label = column;
  p.pad_x = true;
  std::vector<std::vector<double>> model_ys;
  std::vector<io::PlotSeries> models;
  for (std::size_t k = 0; k < l.rows.size(); ++k) {
    const std::uint32_t rgb = kPalette[k % (sizeof kPalette / sizeof kPalette[0])];
    io::PlotSeries s;
    s.label = l.labels[k].empty() ? std::string("DEM") : l.labels[k];
    s.rgb = rgb;
    s.markers = true;
    for (std::size_t r : l.rows[k]) s.x.push_back(l.x_of_row[r]), s.y.push_back(as_number(t.rows[r][column]));
    p.series.push_back(s);
    if (model.empty()) continue;
    io::PlotSeries m;
    m.rgb = rgb;
    m.dashed = true;
    m.label = l.labels[k].empty() ? "Morrell C-model" : "Morrell, " + l.labels[k];
    for (std::size_t r : l.rows[k]) m.x.push_back(l.x_of_row[r]), m.y.push_back(as_number(t.rows[r][model]));
    bool repeat = false;
    for (const auto& ys : model_ys)
      repeat = repeat || (ys.size() == m.y.size() && std::equal(ys.begin(), ys.end(), m.y.begin(), [](double a, double b) {
                            // Counts of balls differ a little with the lifters: the same model.
                            return std::abs(a - b) <= 2e-3 * std::max(std::abs(a), std::abs(b));
                          }));
    if (repeat) continue;
    model_ys.push_back(m.y);
    models.push_back(m);
  }
  p.series.insert(p.series.end(), models.begin(), models.end());  // after the data in the legend
  // One model line for all (Morrell's model does not see the lifters): grey.
  if (model_ys.size() == 1 && l.rows.size() > 1)
    for (io::PlotSeries& s : p.series)
      if (s.dashed) s.label = "Morrell C-model", s.rgb = 0x555555;
  return p;
}

}  // namespace

std::vector<fs::path> write_sweep_plots(const SweepTable& t, const fs::path& sweep_dir) {
  std::vector<fs::path> written;
  if (t.rows.empty() || t.axes.empty()) return written;
  // Axis groups from cases.json: zipped axes share the first axis's x.
  std::vector<int> groups(t.axes.size());
  {
    nlohmann::json cases = io::read_json_file(sweep_dir / "cases.json");
    for (std::size_t a = 0; a < t.axes.size(); ++a) {
      nlohmann::json& axis = cases["axes"][a];
      groups[a] = axis.contains("group") && axis["group"].is_number_integer() ? axis["group"].get<int>()
                                                                               : static_cast<int>(a);
    }
  }
  const Lines l = split_lines(t, groups);

  io::LinePlot power = figure_plot(t, l, "power_W.torque", "morrell.power_W", "power draw (DEM torque power; Morrell dashed)");
  power.y_label = "power (W)";
  if (io::draw_or_warn(sweep_dir / "sweep.png", [&] { io::write_line_plot_png(sweep_dir / "sweep.png", power); }))
    written.push_back(sweep_dir / "sweep.png");

  struct Figure {
    std::string column, model, what;
  };
  std::vector<Figure> figures = {
      {"power_W.dissipation", "morrell.power_W", "dissipation power (Morrell dashed)"},
      {"power_per_metre_W.torque", "morrell.power_per_metre_W", "power per metre of mill (Morrell dashed)"},
      {"power_W.imbalance", "", "power imbalance (torque - dissipation) / torque"},
      {"torque_Nm", "", "torque"},
      {"toe_deg", "morrell.toe_deg", "toe angle (Morrell dashed)"},
      {"shoulder_deg", "morrell.shoulder_deg", "shoulder angle (Morrell dashed)"},
      {"com_angle_deg", "", "centre-of-mass angle"},
  };
  for (const std::string& c : t.columns)
    for (const std::string& block : kOpenBlocks)
      if (c.rfind(block + ".", 0) == 0) figures.push_back({c, "", c});
  std::error_code ec;
  fs::create_directories(sweep_dir / "plots", ec);
  for (const Figure& f : figures) {
    if (!any_finite(t, f.column)) continue;
    const fs::path file = sweep_dir / "plots" / (f.column + ".png");
    if (io::draw_or_warn(file, [&] { io::write_line_plot_png(file, figure_plot(t, l, f.column, f.model, f.what)); }))
      written.push_back(file);
  }
  return written;
}

}  // namespace mc::app
