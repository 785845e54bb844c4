#include "app/sweep.h"

#include <sys/file.h>
#include <fcntl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "app/cli_checks.h"
#include "app/life_options.h"
#include "app/life_state.h"
#include "app/prepare.h"
#include "app/sweep_life.h"
#include "app/slurm.h"
#include "app/sweep_runs.h"
#include "app/sweep_table.h"
#include "core/mill_case.h"
#include "core/scene.h"
#include "io/atomic_file.h"
#include "io/case_file.h"
#include "io/json_read.h"
#include "io/png_plot.h"
#include "io/sweep_file.h"

namespace mc::app {

namespace fs = std::filesystem;

namespace {

// Particle-updates per second assumed for the wall-time estimate when neither
// --throughput nor the file gives one: a stated round figure, not a
// measurement (`millcharge bench` measures a device).
constexpr double kDefaultThroughput = 1e7;

std::string estimate_text(double s) {
  char buf[32];
  if (!(s >= 0) || s > 1e9) return "?";
  if (s < 60) std::snprintf(buf, sizeof buf, "%.0fs", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  else std::snprintf(buf, sizeof buf, "%dh%02dm", static_cast<int>(s) / 3600, static_cast<int>(s) / 60 % 60);
  return buf;
}

// Columns padded to their widest cell, two spaces apart; the last column
// (a message) is not padded.
void print_table(const std::vector<std::vector<std::string>>& rows, const std::string& indent = "  ") {
  std::vector<std::size_t> width;
  for (const auto& r : rows)
    for (std::size_t i = 0; i + 1 < r.size(); ++i) {
      if (width.size() <= i) width.resize(i + 1, 0);
      width[i] = std::max(width[i], r[i].size());
    }
  for (const auto& r : rows) {
    std::string line = indent;
    for (std::size_t i = 0; i < r.size(); ++i) {
      line += r[i];
      if (i + 1 < r.size()) line += std::string(width[i] - r[i].size() + 2, ' ');
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    std::printf("%s\n", line.c_str());
  }
}

std::string number_text(double v, const char* fmt = "%.4g") {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// One case checked as `millcharge check` would: the case read with its
// overrides, derived and packed.
struct CaseCheck {
  std::string error;         // empty: valid
  long balls = 0;            // particles: balls and clumps
  long spheres = 0;          // what the kernels step: balls and the clumps' spheres
  double steps = 0;          // settling (at its limit when "auto") and turning
  bool settle_auto = false;
  std::string resolved;      // case_to_toml, to compare with a run folder's
  int runs = 1;              // a life study: its new liner and each worn stage asked (stages + 1)
  nlohmann::json request;    // a life study's, to compare with a case folder's life.json
};

CaseCheck check_case(const io::Sweep& s, const io::SweepCase& sc) {
  CaseCheck r;
  try {
    const MillCase c = io::read_case(s.base_case, sc.overrides);
    const MillDerived d = derive(c);
    try {
      r.spheres = static_cast<long>(build_scene(c, d).balls.size());
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(s.base_case.filename().string() + ": " + e.what());
    }
    r.balls = d.n_balls;
    // As run_mill bounds an automatic settle: 2 s + 4 sqrt(D/g).
    const double settle = c.settle < 0 ? 2.0 + 4.0 * std::sqrt(c.diameter / 9.81) : c.settle;
    r.steps = std::round((settle + d.turn_limit_s) / d.dt);  // an auto run at its cap
    r.settle_auto = c.settle < 0;
    r.resolved = io::case_to_toml(c);
    if (s.is_life()) {
      // The study's options read and checked as `millcharge life` does.
      LifeOptions lo = life_options_from(sc.life_args);
      lo.c.case_path = s.base_case.string();
      lo.c.overrides = sc.overrides;
      const Prepared given{s.base_case, c, d, build_scene(c, d)};
      double twin_edge_m = 0;  // the twin's file is the study's; only its triangles count here
      const Prepared p = life_base(lo, given, fs::path("cases") / sc.dir, &twin_edge_m);
      check_life(lo, p);
      r.runs = lo.stages + 1;
      r.request = life_request(lo, p, twin_edge_m);
    }
  } catch (const std::invalid_argument& e) {
    r.error = e.what();
  }
  return r;
}

struct Checked {
  io::Sweep sweep;
  std::vector<io::SweepCase> cases;
  std::vector<CaseCheck> checks;
  int bad = 0;
};

Checked check_all(io::Sweep s) {
  // A [life] key or life.* axis that is no life option is one mistake of
  // the file, said once with its line, not once per case.
  if (s.is_life()) {
    const std::vector<std::string> names = sweep_life_option_names();
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    auto known = [&](const std::string& key, const std::string& where) {
      if (std::find(names.begin(), names.end(), key) == names.end())
        throw io::SweepError(where + ": not an option of millcharge life that a sweep can give (those: " + list +
                             "; --out is the sweep's, each study's folder its case's; --force and --quiet are not for a sweep's studies)");
    };
    for (const io::SweepLifeOption& o : s.life)
      known(o.key, s.file.string() + ":" + std::to_string(o.line) + ": life." + o.key);
    for (const io::SweepAxis& a : s.axes)
      if (a.key.rfind(io::kLifeAxisPrefix, 0) == 0)
        known(a.key.substr(std::string(io::kLifeAxisPrefix).size()), s.file.string() + ": axes." + a.key);
  }
  Checked k;
  k.cases = io::expand(s);
  for (const io::SweepCase& c : k.cases) {
    k.checks.push_back(check_case(s, c));
    if (!k.checks.back().error.empty()) ++k.bad;
  }
  k.sweep = std::move(s);
  return k;
}

// Each bad case on stderr: the sweep file, the case by its values, the
// case reader's message (which names the key and the --set).
void report_bad(const Checked& k, const char* consequence) {
  for (std::size_t i = 0; i < k.cases.size(); ++i)
    if (!k.checks[i].error.empty())
      std::cerr << "millcharge: " << k.sweep.file.string() << ": case " << i << " ("
                << io::case_label(k.sweep, k.cases[i]) << "): " << k.checks[i].error << '\n';
  std::cerr << "millcharge: " << k.sweep.file.string() << ": " << k.bad << " of " << k.cases.size()
            << " cases are not valid" << consequence << '\n';
}

void print_sweep_head(const io::Sweep& s, std::size_t n_cases) {
  std::printf("sweep %s: %zu cases of %s, %s\n", s.name.c_str(), n_cases, s.base_case.string().c_str(),
              s.axes.size() == 1 ? "one axis" : s.zipped ? "zipped" : "crossed");
  for (const io::SweepAxis& a : s.axes) {
    std::string values;
    for (const io::SweepValue& v : a.values) values += " " + v.text;
    std::printf("  %-32s %zu values:%s\n", a.key.c_str(), a.values.size(), values.c_str());
  }
  if (!s.set.empty()) {
    std::string set;
    for (const std::string& k : s.set) set += " --set " + k;
    std::printf("  every case:%s\n", set.c_str());
  }
}

// The run folder's case against the sweep's: the keys that differ (empty:
// the same case).
void flatten(const toml::node& n, const std::string& key, std::map<std::string, std::string>& out) {
  if (const toml::table* t = n.as_table()) {
    for (auto&& [k, v] : *t) flatten(v, key.empty() ? std::string(k.str()) : key + "." + std::string(k.str()), out);
  } else if (const toml::array* a = n.as_array(); a && a->is_array_of_tables()) {
    for (std::size_t i = 0; i < a->size(); ++i) flatten(*a->get(i), key + "." + std::to_string(i), out);
  } else {
    std::ostringstream v;
    if (const toml::array* arr = n.as_array()) v << *arr;
    else n.visit([&](auto&& x) { v << x; });
    out[key] = v.str();
  }
}

std::vector<std::string> differing_keys(const std::string& a, const std::string& b) {
  std::map<std::string, std::string> fa, fb;
  flatten(toml::parse(a), "", fa);
  flatten(toml::parse(b), "", fb);
  std::vector<std::string> out;
  std::set<std::string> keys;
  for (auto& [k, v] : fa) keys.insert(k);
  for (auto& [k, v] : fb) keys.insert(k);
  for (const std::string& k : keys) {
    const auto ia = fa.find(k), ib = fb.find(k);
    const std::string va = ia == fa.end() ? "(none)" : ia->second, vb = ib == fb.end() ? "(none)" : ib->second;
    if (va != vb) out.push_back(k + " " + va + " there, " + vb + " in the sweep");
  }
  return out;
}

std::string now_utc() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

// The sweep's record of submitted jobs; an empty list when there is none.
// A damaged one is refused, not read as empty: the cases Slurm still holds
// would be submitted again, and the record overwritten.
nlohmann::json read_jobs(const fs::path& p) {
  std::error_code ec;
  if (!fs::exists(p, ec)) return nlohmann::json::array();
  std::ifstream in(p, std::ios::binary);
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const std::string fault = io::json_text_fault(text);
  if (!fault.empty())
    throw std::invalid_argument(p.string() + ": " + fault +
                                ": the sweep's record of submitted jobs is damaged; if none of its jobs is queued "
                                "(squeue), move it aside and run again");
  const nlohmann::json j = nlohmann::json::parse(text);
  if (!j.is_array())
    throw std::invalid_argument(p.string() + ": not a list of jobs: the sweep's record of submitted jobs is damaged; "
                                "if none of its jobs is queued (squeue), move it aside and run again");
  // Each entry as `sweep run --slurm` writes it: the job's id and its tasks' folders.
  for (std::size_t k = 0; k < j.size(); ++k) {
    const nlohmann::json& e = j[k];
    bool ok = e.is_object() && e.contains("job") && e["job"].is_string() &&
              (!e.contains("tasks") || e["tasks"].is_object());
    if (ok && e.contains("tasks"))
      for (const auto& task : e["tasks"].items()) ok = ok && task.value().is_string();
    if (!ok)
      throw std::invalid_argument(p.string() + ": entry " + std::to_string(k) +
                                  " is not a job (its id as \"job\", its tasks' folders as \"tasks\"): the sweep's "
                                  "record of submitted jobs is damaged; if none of its jobs is queued (squeue), move "
                                  "it aside and run again");
  }
  return j;
}

// The folders of cases that Slurm still holds for this sweep (pending or
// running), from the jobs `sweep run --slurm` recorded in jobs.json.
std::set<std::string> queued_dirs(const fs::path& sweep_dir) {
  std::set<std::string> out;
  const nlohmann::json jobs = read_jobs(sweep_dir / "jobs.json");
  if (jobs.empty() || !on_path("squeue")) return out;
  std::set<std::string> ids;
  for (const auto& j : jobs) ids.insert(j.value("job", ""));
  for (const auto& [job, tasks] : queued_tasks(ids))
    for (const auto& j : jobs)
      if (j.value("job", "") == job)
        for (int t : tasks)
          if (j.contains("tasks") && j["tasks"].contains(std::to_string(t)))
            out.insert(j["tasks"][std::to_string(t)].get<std::string>());
  return out;
}

// Holds SWEEP/.lock while this process runs cases here.
class SweepLock {
 public:
  explicit SweepLock(const fs::path& dir) {
    fd_ = ::open((dir / ".lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0 || ::flock(fd_, LOCK_EX | LOCK_NB) != 0)
      throw std::runtime_error(dir.string() + ": another `millcharge sweep run --local` is running this sweep");
  }
  ~SweepLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  SweepLock(const SweepLock&) = delete;
  SweepLock& operator=(const SweepLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace

int cmd_sweep_check(const SweepCheckOptions& o) {
  const Checked k = check_all(io::read_sweep(o.file));
  const io::Sweep& s = k.sweep;
  const double throughput = o.throughput > 0 ? o.throughput : s.throughput > 0 ? s.throughput : kDefaultThroughput;
  print_sweep_head(s, k.cases.size());
  const std::vector<std::string> names = io::short_axis_names(s);
  std::vector<std::vector<std::string>> table;
  table.push_back({"case"});
  table[0].insert(table[0].end(), names.begin(), names.end());
  // A charge of clumps costs per sphere: the spheres are what the kernels
  // step, so the work and the estimate count them (bench's sphere-updates).
  bool clumps = false;
  for (const CaseCheck& c : k.checks) clumps = clumps || (c.error.empty() && c.spheres != c.balls);
  const char* work_name = clumps ? "sphere-steps" : "ball-steps";
  table[0].push_back(clumps ? "particles" : "balls");
  if (clumps) table[0].push_back("spheres");
  // A life study runs its new liner and each worn stage: its steps are
  // the runs' steps together.
  if (s.is_life()) table[0].push_back("runs");
  for (const char* h : {"steps", work_name, "wall"}) table[0].push_back(h);
  double total_balls = 0, total_spheres = 0, total_steps = 0, total_work = 0;
  for (std::size_t i = 0; i < k.cases.size(); ++i) {
    const CaseCheck& c = k.checks[i];
    std::vector<std::string> row = {std::to_string(i)};
    for (std::size_t a = 0; a < s.axes.size(); ++a) row.push_back(s.axes[a].values[k.cases[i].value_index[a]].text);
    if (!c.error.empty()) {
      row.push_back("NOT VALID (below)");
    } else {
      const double steps = c.steps * c.runs;
      const double work = static_cast<double>(c.spheres) * steps;
      total_balls += c.balls, total_spheres += c.spheres, total_steps += steps, total_work += work;
      row.push_back(thousands(c.balls));
      if (clumps) row.push_back(thousands(c.spheres));
      if (s.is_life()) row.push_back(std::to_string(c.runs));
      row.insert(row.end(), {thousands(static_cast<long>(steps)), number_text(work, "%.3g"),
                             estimate_text(work / throughput)});
    }
    table.push_back(row);
  }
  print_table(table);
  std::fflush(stdout);
  if (k.bad > 0) {
    report_bad(k, "");
    return 2;
  }
  const std::string spheres_text = clumps ? " (" + thousands(static_cast<long>(total_spheres)) + " spheres)" : "";
  std::printf("%zu cases, all valid: %s %s%s, %.3g steps, %.3g %s in all;\n", k.cases.size(),
              thousands(static_cast<long>(total_balls)).c_str(), clumps ? "particles" : "balls", spheres_text.c_str(),
              total_steps, total_work, work_name);
  bool any_auto = false;
  for (const CaseCheck& c : k.checks) any_auto = any_auto || c.settle_auto;
  std::printf("estimated %s of device time at %.3g %s/s (%s; `millcharge bench` measures a device%s)%s\n",
              estimate_text(total_work / throughput).c_str(), throughput,
              clumps ? "sphere-updates" : "particle-updates",
              o.throughput > 0   ? "--throughput"
              : s.throughput > 0 ? "the file's throughput"
                                 : "a stated round figure, not a measurement",
              clumps ? "; for clumps, bench a case of the same shapes" : "",
              any_auto ? ";\nsettling counted at its limit, 2 s + 4 sqrt(D/g), where run.settle is \"auto\"" : "");
  if (s.is_life())
    std::printf("each life study counted as its new liner's run and one run per stage asked (stages + 1); a study "
                "that goes on until it covers its hours or height may run up to 3 x stages + 1\n");
  return 0;
}

int cmd_sweep_run(const SweepRunOptions& o) {
  const int modes = (o.local > 0) + o.slurm + o.print;
  if (modes != 1)
    throw std::invalid_argument("sweep run: give exactly one of --local [N] (here, N at a time), --slurm (submit a "
                                "job array) and --print (write the job script only)");
  if (o.slurm && !on_path("sbatch"))
    throw std::runtime_error("sbatch is not on PATH: run `millcharge sweep run --slurm` on the cluster's login node, "
                             "or use --print (the script only) or --local N");
  io::Sweep sweep = io::read_sweep(o.file);
  if (!o.device.empty()) sweep.device = o.device;
  io::SlurmSettings& sl = sweep.slurm;
  if (!o.partition.empty()) sl.partition = o.partition;
  if (!o.time.empty()) sl.time = o.time;
  if (o.gpus_per_task >= 0) sl.gpus_per_task = o.gpus_per_task;
  if (o.cpus_per_task >= 0) sl.cpus_per_task = o.cpus_per_task;
  if (o.max_running >= 0) sl.max_running = o.max_running;
  if (o.signal_grace >= 0) sl.signal_grace_s = o.signal_grace;
  sl.sbatch_args.insert(sl.sbatch_args.end(), o.sbatch_args.begin(), o.sbatch_args.end());
  for (const std::string& a : sl.sbatch_args)
    if (a.rfind("--", 0) != 0) throw std::invalid_argument("--sbatch-arg " + a + ": expected an sbatch option, e.g. --qos=long");
  if (!o.time.empty() && !io::slurm_time_valid(o.time))
    throw std::invalid_argument("--time \"" + o.time + "\" is not a Slurm time limit: expected " +
                                std::string(io::kSlurmTimeForms));

  const Checked k = check_all(std::move(sweep));
  const io::Sweep& s = k.sweep;
  if (k.bad > 0) {
    report_bad(k, "; nothing was run or written");
    return 2;
  }
  const fs::path sweep_dir = fs::absolute(o.out.empty() ? fs::path("runs") / s.name : fs::path(o.out)).lexically_normal();
  std::error_code ec;
  if ((o.slurm || o.print) && sweep_dir.string().find_first_of(" \t\n'\"") != std::string::npos)
    throw std::invalid_argument("--out " + sweep_dir.string() +
                                ": the job script's #SBATCH --output line cannot hold spaces or quotes; choose a "
                                "folder without them");
  if (fs::exists(sweep_dir, ec) && !fs::is_directory(sweep_dir, ec))
    throw std::invalid_argument("--out " + sweep_dir.string() + ": exists and is not a folder");

  // A case folder from an earlier run must hold the same case: a resumed run
  // goes on with its checkpoint's case, whatever the sweep file says now.
  std::vector<CaseState> states;
  int mismatched = 0;
  for (std::size_t i = 0; i < k.cases.size(); ++i) {
    const fs::path dir = case_path(sweep_dir, k.cases[i].dir);
    states.push_back(case_state(dir, s.is_life()));
    if (s.is_life()) {
      const std::string differs = life_study_difference(dir, k.checks[i].request);
      if (differs.empty()) continue;
      ++mismatched;
      std::cerr << "millcharge: " << dir.string() << ": not the study of the sweep's case " << i << " ("
                << io::case_label(s, k.cases[i]) << "): " << differs << '\n';
      continue;
    }
    std::ifstream in(dir / "case.toml");
    if (!in) continue;
    std::ostringstream text;
    text << in.rdbuf();
    std::vector<std::string> diff;
    try {
      const MillCase there = io::parse_case(text.str(), (dir / "case.toml").string());
      diff = differing_keys(io::case_to_toml(there), k.checks[i].resolved);
    } catch (const std::exception& e) {
      diff = {std::string("its case.toml does not read: ") + e.what()};
    }
    if (diff.empty()) continue;
    ++mismatched;
    std::string what;
    for (std::size_t d = 0; d < diff.size() && d < 3; ++d) what += (d ? "; " : "") + diff[d];
    if (diff.size() > 3) what += "; and " + std::to_string(diff.size() - 3) + " more";
    std::cerr << "millcharge: " << dir.string() << ": holds a run of another case than the sweep's case " << i << " ("
              << io::case_label(s, k.cases[i]) << "): " << what << '\n';
  }
  if (mismatched > 0) {
    std::cerr << "millcharge: " << s.file.string() << ": " << mismatched << " case folders hold other "
              << (s.is_life() ? "studies" : "cases")
              << " (the sweep file or its base case changed); remove them to run them afresh, or give another "
                 "--out\n";
    return 2;
  }

  // What to run: every case not finished, not failed (unless asked) and not
  // still queued or running on Slurm.
  const std::set<std::string> queued = queued_dirs(sweep_dir);
  std::vector<int> to_run;
  int n_done = 0, n_failed = 0, n_queued = 0, n_resume = 0;
  for (std::size_t i = 0; i < k.cases.size(); ++i) {
    const CaseState& st = states[i];
    if (st.status == CaseStatus::done) ++n_done;
    else if (queued.count(k.cases[i].dir)) ++n_queued;
    else if (st.status == CaseStatus::failed && !o.retry_failed) ++n_failed;
    else {
      to_run.push_back(static_cast<int>(i));
      n_resume += st.checkpoint;
    }
  }
  print_sweep_head(s, k.cases.size());
  std::printf("%d finished, %d queued or running, %d failed%s; %zu to run (%d resume from %s)\n", n_done,
              n_queued, n_failed, n_failed > 0 && !o.retry_failed ? " (not run again: --retry-failed)" : "",
              to_run.size(), n_resume, s.is_life() ? "their life.json" : "a checkpoint");
  for (std::size_t i = 0; i < k.cases.size(); ++i)
    if (states[i].status == CaseStatus::failed && !o.retry_failed && !queued.count(k.cases[i].dir))
      std::printf("  case %zu (%s) failed (exit status %d): %s\n", i, io::case_label(s, k.cases[i]).c_str(),
                  states[i].exit_status, states[i].last_line.c_str());
  std::fflush(stdout);

  // The sweep folder: cases.json, the sweep file as given, the job script.
  fs::create_directories(sweep_dir / "cases", ec);
  if (o.slurm || o.print) fs::create_directories(sweep_dir / "slurm", ec);
  if (ec) throw std::runtime_error("cannot create " + sweep_dir.string() + ": " + ec.message());
  std::unique_ptr<SweepLock> lock;
  if (o.local > 0) lock = std::make_unique<SweepLock>(sweep_dir);
  io::write_file_atomic(sweep_dir / "cases.json", cases_json(s, k.cases).dump(2) + "\n");
  {
    std::ifstream in(s.file, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    io::write_file_atomic(sweep_dir / "sweep.toml", text.str());
  }
  const fs::path millcharge = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot tell where the millcharge program is (/proc/self/exe): " + ec.message());
  JobScript js = job_script_for(s, k.cases, sweep_dir, millcharge);
  js.array = to_run;
  const fs::path script = sweep_dir / "sweep.sh";
  io::write_file_atomic(script, job_script_text(js));
  fs::permissions(script, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                  fs::perm_options::add, ec);

  if (o.print) {
    std::printf("wrote %s (array %s); submit it with: sbatch %s\n", script.string().c_str(),
                to_run.empty() ? "empty: nothing to run" : array_spec(to_run, sl.max_running).c_str(),
                script.string().c_str());
    return 0;
  }
  if (to_run.empty()) {
    std::printf("nothing to run; `millcharge sweep collect %s` makes the table\n", sweep_dir.string().c_str());
    return 0;
  }
  if (o.local > 0) return run_local(script, sweep_dir, k.cases, to_run, o.local, s);

  const std::string job = submit(script);
  nlohmann::json jobs = read_jobs(sweep_dir / "jobs.json");
  nlohmann::json entry = {{"job", job}, {"submitted", now_utc()}, {"tasks", nlohmann::json::object()}};
  for (int i : to_run) entry["tasks"][std::to_string(i)] = k.cases[i].dir;
  jobs.push_back(entry);
  io::write_file_atomic(sweep_dir / "jobs.json", jobs.dump(2) + "\n");
  std::printf("submitted job %s: array %s, %zu of %zu cases; script %s\n", job.c_str(),
              array_spec(to_run, sl.max_running).c_str(), to_run.size(), k.cases.size(), script.string().c_str());
  return 0;
}

int cmd_sweep_collect(const SweepCollectOptions& o) {
  const fs::path dir = fs::absolute(o.dir).lexically_normal();
  // A sweep of life studies tables each study's life (app/sweep_life.h).
  if (fs::exists(dir / "cases.json")) {
    const nlohmann::json cases = io::read_json_file(dir / "cases.json");
    if (cases.is_object() && cases.value("command", "run") == "life") {
      if (!cases.contains("axes") || !cases["axes"].is_array() || !cases.contains("cases") || !cases["cases"].is_array())
        throw std::invalid_argument((dir / "cases.json").string() + ": no axes and cases; not a sweep's cases.json");
      return collect_life_sweep(dir, cases, o.relining_height_mm);
    }
  }
  if (o.relining_height_mm > 0)
    throw std::invalid_argument("--relining-height: " + dir.string() +
                                " is a sweep of runs; the relining height is for a sweep of life studies (command = "
                                "\"life\")");
  const SweepTable t = collect_table(dir);
  io::write_file_atomic(dir / "sweep.csv", table_csv(t));
  io::write_file_atomic(dir / "sweep.json", table_json(t).dump(2) + "\n");
  const std::vector<fs::path> plots = write_sweep_plots(t, dir);

  // The table on stdout: axes, status, power, Morrell, toe, shoulder, and
  // why a case has no figures.
  std::vector<std::vector<std::string>> table(1);
  for (const std::string& a : t.axes) table[0].push_back(a.substr(a.find_last_of(".]") + 1));
  for (const char* h : {"status", "torque_W", "dissipation_W", "morrell_W", "toe_deg", "shoulder_deg", "error"})
    table[0].push_back(h);
  for (const auto& row : t.rows) {
    std::vector<std::string> r;
    for (const std::string& a : t.axes)
      r.push_back(row[a].is_number() ? number_text(row[a].get<double>(), "%g") : row[a].is_string() ? row[a].get<std::string>() : "");
    r.push_back(row["status"].get<std::string>());
    for (const char* c : {"power_W.torque", "power_W.dissipation", "morrell.power_W"})
      r.push_back(row[c].is_number() ? number_text(row[c].get<double>()) : "-");
    for (const char* c : {"toe_deg", "shoulder_deg"})
      r.push_back(row[c].is_number() ? number_text(row[c].get<double>(), "%.1f") : "-");
    r.push_back(row["error"].is_string() ? row["error"].get<std::string>() : "");
    table.push_back(r);
  }
  print_table(table, "");
  std::printf("%d of %zu cases finished; wrote %s/{sweep.csv, sweep.json, sweep.png} and %zu plots in %s/plots\n",
              t.finished, t.rows.size(), dir.string().c_str(), plots.empty() ? 0 : plots.size() - 1,
              dir.string().c_str());
  return 0;
}

}  // namespace mc::app

// ------------------------------------------------------------ the command --

namespace mc::app {

void add_sweep_commands(CLI::App& app, SweepCli& cli) {
  cli.sweep = app.add_subcommand("sweep", "design sweeps: a sweep file's cases run here or as a Slurm job array, "
                                          "then one table (docs/sweeps.md)");
  cli.sweep->require_subcommand(1);

  cli.check = cli.sweep->add_subcommand("check", "validate every case of a sweep file; print the cases and their cost");
  cli.check->add_option("file", cli.check_options.file, "sweep file (TOML)")->required();
  cli.check->add_option("--throughput", cli.check_options.throughput,
                        "particle-updates per second for the wall-time estimate (measure: millcharge bench)")
      ->check(cli::positive("particle-updates/s"));

  SweepRunOptions& r = cli.run_options;
  cli.run = cli.sweep->add_subcommand("run", "run the unfinished cases: here (--local N), on Slurm (--slurm) or "
                                             "write the job script (--print)");
  cli.run->add_option("file", r.file, "sweep file (TOML)");
  cli.run->add_option("--local", cli.local, "run the cases on this machine, N at a time (default 1)")
      ->expected(0, 1)
      ->type_name("[N]");
  cli.run->add_flag("--slurm", r.slurm, "write the job-array script and submit it with sbatch");
  cli.run->add_flag("--print", r.print, "write the job-array script only (SWEEP/sweep.sh)");
  cli.run->add_option("--out", r.out, "the sweep folder (default runs/NAME)")->type_name("DIR");
  cli.run->add_option("--device", r.device, "OpenCL device of every run: auto, gpu, cpu, P:D, pocl, nvidia, amd, intel, rusticl, mesa or part of a name");
  cli.run->add_flag("--retry-failed", r.retry_failed, "run failed cases again too");
  cli.run->add_option("--partition", r.partition, "Slurm partition")->group("Slurm");
  cli.run->add_option("--time", r.time, "time limit per task, e.g. 04:00:00")->group("Slurm");
  cli.run->add_option("--gpus-per-task", r.gpus_per_task, "GPUs per task (one device per run: 1)")
      ->check(cli::count(0, 64))
      ->group("Slurm");
  cli.run->add_option("--cpus-per-task", r.cpus_per_task, "CPU cores per task")->check(cli::count(0, 4096))->group("Slurm");
  cli.run->add_option("--max-running", r.max_running, "at most N tasks at once (the array's %N)")
      ->check(cli::count(0, 100000))
      ->group("Slurm");
  cli.run->add_option("--signal-grace", r.signal_grace,
                      "SIGTERM this many seconds before the time limit, so the run checkpoints (default 120)")
      ->check(cli::count(0, 65535, "s"))
      ->group("Slurm");
  cli.run->add_option("--sbatch-arg", r.sbatch_args, "another sbatch option for the script, e.g. --sbatch-arg=--qos=long")
      ->group("Slurm")
      ->allow_extra_args(false);

  cli.collect = cli.sweep->add_subcommand("collect", "join the sweep's runs into sweep.csv, sweep.json and plots");
  cli.collect->add_option("dir", cli.collect_options.dir, "the sweep folder (runs/NAME)")->required();
  cli.collect->add_option("--relining-height", cli.collect_options.relining_height_mm,
                          "a sweep of life studies: the hours each takes to wear its lifters down to MM (default: "
                          "[life] until-height)")
      ->check(cli::positive("mm"))
      ->type_name("MM");
}

bool run_sweep(SweepCli& cli, int& status) {
  if (!cli.sweep || !*cli.sweep) return false;
  if (*cli.check) {
    status = cmd_sweep_check(cli.check_options);
  } else if (*cli.run) {
    SweepRunOptions& r = cli.run_options;
    const CLI::Option* local = cli.run->get_option("--local");
    if (local->count() > 0) {
      std::string n = cli.local;
      // `sweep run --local FILE`: the file, not a count.
      if (r.file.empty() && !n.empty() && n.find_first_not_of("0123456789") != std::string::npos) r.file = n, n.clear();
      if (n.empty()) n = "1";
      if (n.find_first_not_of("0123456789") != std::string::npos || n.size() > 4 || std::stoi(n) < 1)
        throw std::invalid_argument("--local " + n + ": expected how many cases run at once, a count >= 1");
      r.local = std::stoi(n);
    }
    if (r.file.empty()) throw std::invalid_argument("sweep run: give the sweep file, e.g. millcharge sweep run sweep.toml --local 2");
    status = cmd_sweep_run(r);
  } else {
    status = cmd_sweep_collect(cli.collect_options);
  }
  return true;
}

}  // namespace mc::app
