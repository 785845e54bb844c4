// millcharge view: the window on a case (viewer/viewer.h), from a fresh
// packing or, with --from RUN, from the state in a run's checkpoint.
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "app/commands.h"
#include "app/prepare.h"
#include "viewer/viewer.h"

namespace mc::app {

namespace fs = std::filesystem;

namespace {

// A case as case_to_toml writes it, flattened to the dotted keys --set takes
// (arrays of tables numbered: lifters.profile.0.height), in file order.
std::vector<std::pair<std::string, std::string>> flat_keys(const std::string& toml) {
  std::vector<std::pair<std::string, std::string>> out;
  std::map<std::string, int> tables;  // arrays of tables: entries so far
  std::string prefix;
  std::istringstream in(toml);
  std::string line;
  auto trim = [](std::string s) {
    const auto a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t\r");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
  };
  while (std::getline(in, line)) {
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    if (line.rfind("[[", 0) == 0) {
      const std::string name = line.substr(2, line.find("]]") - 2);
      prefix = name + "." + std::to_string(tables[name]++) + ".";
    } else if (line[0] == '[') {
      prefix = line.substr(1, line.find(']') - 1) + ".";
    } else if (const auto eq = line.find(" = "); eq != std::string::npos) {
      out.emplace_back(prefix + line.substr(0, eq), line.substr(eq + 3));
    } else if (!out.empty()) {  // a value that goes on over lines
      out.back().second += " " + line;
    }
  }
  return out;
}

// A value as a person reads it: numbers to 6 digits (the file keeps 17).
std::string readable(const std::string& v) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (end == v.c_str() || *end) return v;
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

// CASE and --set given with --from must describe the run's case: the
// window opens on the run's charge in the run's mill. Keys that only say how
// long a headless run lasts and what it records do not count.
void require_same_case(const ViewOptions& o, const io::Checkpoint& cp, const Prepared& run) {
  if (o.c.case_path.empty() && o.c.overrides.empty()) return;
  CaseOptions co = o.c;
  co.precision.clear();  // compared on its own below
  const std::string given_name = o.c.case_path.empty() ? "--set" : o.c.case_path;
  MillCase given = o.c.case_path.empty()
                       ? io::parse_case(cp.case_toml, o.from + "/" + io::kCheckpointFile + " (case)", case_overrides(co))
                       : io::read_case(o.c.case_path, case_overrides(co));
  const MillCase& r = run.c;
  given.name = r.name;
  given.title = r.title;
  given.duration = r.duration;
  given.duration_auto = r.duration_auto;
  given.tolerance = r.tolerance;
  given.max_duration = r.max_duration;
  given.warmup = r.warmup;
  given.output_interval = r.output_interval;
  given.snapshot_interval = r.snapshot_interval;
  given.checkpoint_interval = r.checkpoint_interval;
  const auto a = flat_keys(io::case_to_toml(r)), b = flat_keys(io::case_to_toml(given));
  const std::map<std::string, std::string> run_keys(a.begin(), a.end()), given_keys(b.begin(), b.end());
  std::vector<std::string> diffs;
  std::set<std::string> seen;
  auto note = [&](const std::string& key) {
    const auto ra = run_keys.find(key), gb = given_keys.find(key);
    if (ra != run_keys.end() && gb != given_keys.end() && ra->second == gb->second) return;
    if (!seen.insert(key).second) return;
    diffs.push_back(key + " " + (gb == given_keys.end() ? std::string("not given") : readable(gb->second) + " given") +
                    ", " + (ra == run_keys.end() ? std::string("none") : readable(ra->second)) + " in the run");
  };
  for (const auto& [key, value] : b) note(key);
  for (const auto& [key, value] : a) note(key);
  if (diffs.empty()) return;
  std::string list = diffs[0];
  for (std::size_t k = 1; k < diffs.size() && k < 3; ++k) list += "; " + diffs[k];
  if (diffs.size() > 3) list += "; and " + std::to_string(diffs.size() - 3) + " more";
  throw std::invalid_argument("--from " + o.from + ": " + given_name + " disagrees with the run's case (" + list +
                              "). The window opens on the run's own case: leave " +
                              (o.c.case_path.empty() ? "--set" : "CASE") +
                              " out, and change the mill in the window or with --edit 0:KEY=VALUE");
}

// The run of --from: its case and its checkpoint, checked before any window
// opens.
Prepared prepare_from_run(const ViewOptions& o, io::Checkpoint& cp) {
  fs::path dir(o.from);
  std::error_code ec;
  if (fs::is_regular_file(dir, ec)) dir = dir.parent_path();  // the checkpoint itself
  Prepared p = prepare_from_checkpoint(dir, cp, "; the window cannot open on it");
  require_same_case(o, cp, p);
  if (!o.c.precision.empty() && (o.c.precision == "double") != (p.c.precision == Precision::double_))
    throw std::invalid_argument("--from " + o.from + ": the checkpoint holds " +
                                (p.c.precision == Precision::double_ ? "double" : "float") +
                                " state; leave --precision out");
  return p;
}

}  // namespace

int cmd_view(const ViewOptions& o) {
  const auto started = std::chrono::steady_clock::now();
  io::Checkpoint cp;
  Prepared p = o.from.empty() ? prepare(o.c) : prepare_from_run(o, cp);
  viewer::ViewOptions v;
  v.started = started;
  v.device = o.c.device;
  v.frames = o.frames;
  v.screenshot = o.screenshot;
  v.steps_per_frame = o.steps_per_frame;
  v.camera = o.camera;
  v.colour = o.colour;
  v.liner = o.liner;
  v.width = o.width;
  v.height = o.height;
  v.panel = !o.no_panel;
  if (!o.from.empty()) {
    v.from = &cp;
    v.from_dir = o.from;
  }
  for (const std::string& e : o.edits) {
    const auto colon = e.find(':');
    char* end = nullptr;
    const long frame = colon == std::string::npos ? -1 : std::strtol(e.c_str(), &end, 10);
    if (colon == std::string::npos || end != e.c_str() + colon || frame < 0 || e.find('=', colon) == std::string::npos)
      throw std::invalid_argument("--edit " + e + ": expected FRAME:KEY=VALUE, e.g. --edit 100:charge.filling=0.35");
    if (o.frames > 0 && frame >= o.frames)
      throw std::invalid_argument("--edit " + e + ": frame " + std::to_string(frame) + " is past the last of --frames " +
                                  std::to_string(o.frames) + " (frames 0 to " + std::to_string(o.frames - 1) +
                                  "), so it would never apply");
    v.edits.emplace_back(frame, e.substr(colon + 1));
  }
  if (!o.screenshot.empty() && o.frames <= 0)
    throw std::invalid_argument("--screenshot needs --frames N (the picture is taken after the last frame)");
  if (!o.save_state.empty()) {
    if (o.frames <= 0) throw std::invalid_argument("--save-state needs --frames N (the state is saved after the last frame)");
    std::error_code ec;
    for (const char* f : {io::kCheckpointFile, "timeseries.csv", "summary.json"})
      if (fs::exists(fs::path(o.save_state) / f, ec))
        throw std::invalid_argument("--save-state " + o.save_state + ": already holds a run (" + f +
                                    "); choose another folder");
    v.save_state_dir = o.save_state;
  }
  return viewer::run(p.c, p.d, std::move(p.scene), v);
}

}  // namespace mc::app
