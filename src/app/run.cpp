// millcharge run: a case run headless, or a run resumed or extended from
// its checkpoint. cmd_run reads as its steps: prepare (the case or the
// checkpoint, the device, the run folder), announce, open the files the
// run writes as it goes, settle and turn (sim/mill_run.h), then the report
// (run_report.h).
#include "app/commands.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "app/prepare.h"
#include "app/run_report.h"
#include "compute/context.h"
#include "core/mill_case.h"
#include "io/atomic_file.h"
#include "io/case_file.h"
#include "io/checkpoint.h"
#include "io/csv_read.h"
#include "io/vtk.h"
#include "sim/mill_run.h"
#include "sim/solver.h"

namespace mc::app {

namespace fs = std::filesystem;

namespace {

// Progress on stderr: one line rewritten in place on a terminal; plain lines
// at every tenth of the run (or every 30 s) otherwise.
class ProgressPrinter {
 public:
  explicit ProgressPrinter(bool quiet) : quiet_(quiet), tty_(::isatty(2) == 1) {}
  void operator()(const RunProgress& p) {
    if (quiet_) return;
    char line[256], speed[96];
    // The speed over the last report's interval: none yet at the first.
    if (p.steps_per_s > 0)
      std::snprintf(speed, sizeof speed, "%.3g steps/s  %.3g updates/s", p.steps_per_s, p.updates_per_s);
    else
      std::snprintf(speed, sizeof speed, "speed from the next line");
    const std::string left = p.steps_per_s > 0 ? duration_text(p.eta_s) : std::string("?");
    if (p.phase == "settle")
      std::snprintf(line, sizeof line, "settling  t %.3f s  %s steps  %s", p.simulated_s, thousands(p.steps).c_str(),
                    speed);
    else if (p.relative_error >= 0)  // an auto run: its power's error so far, and the time left to its cap
      std::snprintf(line, sizeof line, "turning   t %.3f s  rev %.2f  power \u00b1%.2f %%  %s  %s left at most",
                    p.simulated_s, p.revolutions, 100 * p.relative_error, speed, left.c_str());
    else
      std::snprintf(line, sizeof line, "turning   t %.3f s  rev %.2f  %3.0f %%  %s  %s left", p.simulated_s,
                    p.revolutions, 100 * p.done, speed, left.c_str());
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (tty_) {
      std::fprintf(stderr, "\r\033[K%s", line);
      if (p.done >= 1) std::fprintf(stderr, "\n");
    } else {
      const int tenth = static_cast<int>(p.done * 10);
      if (p.phase != phase_ || tenth > tenth_ || wall - last_ > 30 || p.done >= 1) {
        std::fprintf(stderr, "%s\n", line);
        tenth_ = tenth;
        last_ = wall;
      }
    }
    phase_ = p.phase;
    std::fflush(stderr);
  }
  void finish_line() {
    if (tty_ && !quiet_) std::fprintf(stderr, "\n");
  }

 private:
  bool quiet_, tty_;
  std::string phase_;
  int tenth_ = -1;
  double last_ = 0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

fs::path default_out(const MillCase& c) {
  const std::time_t t = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", std::localtime(&t));
  return fs::path("runs") / (c.name + "-" + stamp);
}

// The run folder: refuses one that holds an earlier run unless --force.
void make_run_dir(const fs::path& out, bool force) {
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw std::invalid_argument("--out " + out.string() + ": exists and is not a folder");
  for (const char* f : {"summary.json", "timeseries.csv", "charge.pvd", "case.toml"})
    if (fs::exists(out / f, ec) && !force)
      throw std::invalid_argument("--out " + out.string() + ": already holds a run (" + f +
                                  "); choose another folder or add --force to replace it");
  if (force) {
    for (const char* f : {"summary.json", "timeseries.csv", "charge.pvd", "power.png", "charge.png", "spectra.csv",
                          "spectra.png", "wear.csv", "lifter_wear.csv", "liner.vtp", "liner.png"})
      fs::remove(out / f, ec);
    fs::remove_all(out / "snapshots", ec);
  }
  fs::create_directories(out / "snapshots", ec);
  if (ec) throw std::runtime_error("cannot create " + (out / "snapshots").string() + ": " + ec.message());
}

io::Snapshot snapshot_of(const std::vector<BallState>& balls, double t) {
  io::Snapshot s;
  s.time_s = t;
  const std::size_t n = balls.size();
  s.position.resize(n);
  s.velocity.resize(n);
  s.radius.resize(n);
  s.material.resize(n);
  s.id.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const BallState& b = balls[i];
    s.position[i] = {float(b.position.x), float(b.position.y), float(b.position.z)};
    s.velocity[i] = {float(b.velocity.x), float(b.velocity.y), float(b.velocity.z)};
    s.radius[i] = float(b.radius);
    s.material[i] = b.material;
    s.id[i] = b.id;
  }
  return s;
}

volatile std::sig_atomic_t g_signal = 0;
extern "C" void on_stop_signal(int sig) { g_signal = sig; }

// SIGINT and SIGTERM ask the run to stop at the next chunk with a checkpoint;
// the previous handlers come back when the run ends.
class StopSignals {
 public:
  StopSignals() {
    g_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~StopSignals() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  int signal() const { return g_signal; }

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

// The first `rows` data rows of an earlier timeseries.csv, and the file cut
// back to them (atomically), for a resumed run.
std::vector<std::string> keep_rows(const fs::path& csv, long rows, bool clear_averaged = false) {
  std::ifstream in(csv);
  if (!in) throw std::invalid_argument(csv.string() + ": missing; the run folder is incomplete");
  std::vector<std::string> lines;
  std::string line;
  while (static_cast<long>(lines.size()) < rows + 1 && std::getline(in, line)) {
    if (in.eof()) break;  // a last line without its newline was cut short
    lines.push_back(line);
  }
  if (static_cast<long>(lines.size()) < rows + 1)
    throw std::invalid_argument(csv.string() + ": holds " + std::to_string(lines.size() ? lines.size() - 1 : 0) +
                                " whole rows, the checkpoint " + std::to_string(rows));
  // The rows the checkpoint counts are read back strictly: the header's
  // width, numbers throughout (rows past them, written after the
  // checkpoint, are dropped whatever they hold).
  const std::size_t width = io::split_csv_line(lines[0]).size();
  for (std::size_t k = 1; k < lines.size(); ++k) {
    const std::string where = csv.string() + ":" + std::to_string(k + 1) + ": ";
    const std::vector<std::string> fields = io::split_csv_line(lines[k]);
    for (const std::string& f : fields)
      if (double x = 0; !io::csv_number(f, x))
        throw std::invalid_argument(where + "\"" + f + "\" is not a number; the run's time series is damaged, so "
                                    "it cannot be resumed (run it again)");
    if (fields.size() != width)
      throw std::invalid_argument(where + std::to_string(fields.size()) + " fields, the header has " +
                                  std::to_string(width) +
                                  "; the run's time series is damaged, so it cannot be resumed (run it again)");
  }
  if (clear_averaged)  // the last column, `averaged`
    for (std::size_t k = 1; k < lines.size(); ++k)
      if (lines[k].size() >= 2 && lines[k].compare(lines[k].size() - 2, 2, ",1") == 0) lines[k].back() = '0';
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  io::write_file_atomic(csv, text);
  lines.erase(lines.begin());
  return lines;
}

// The keys a resumed run may change: how long it turns (to extend it).
constexpr const char* kExtendKeys[] = {"run.duration", "run.max_duration", "run.tolerance"};

// A resumed run given a new duration (or an auto run's cap or tolerance):
// the case with those keys changed, and the state it goes on from. Other
// keys are refused by name: the charge, the mill and the contacts are the
// checkpoint's.
void extend_from_checkpoint(const RunOptions& o, Prepared& p, io::Checkpoint& cp) {
  const std::string where = "--resume " + o.resume + ": ";
  for (const std::string& ov : o.c.overrides) {
    const std::string key = ov.substr(0, ov.find('='));
    if (std::find(std::begin(kExtendKeys), std::end(kExtendKeys), key) == std::end(kExtendKeys))
      throw std::invalid_argument(where + "--set " + key +
                                  ": a resumed run keeps its case; only run.duration, run.max_duration and "
                                  "run.tolerance may change (to turn it longer)");
  }
  // A duration no longer than what has turned, by its own name (before the
  // case's checks, which would name the warm-up it no longer exceeds).
  double asked = o.c.duration;
  for (const std::string& ov : o.c.overrides)
    if (ov.rfind("run.duration=", 0) == 0) {
      char* end = nullptr;
      const double v = std::strtod(ov.c_str() + 13, &end);
      if (end && *end == '\0' && end != ov.c_str() + 13) asked = v;
    }
  const double turned = cp.run.phase >= 2 ? cp.run.turn_step * p.d.dt : 0;
  if (asked > 0 && !o.c.duration_auto && asked <= turned + 0.5 * p.d.dt) {
    char m[200];
    std::snprintf(m, sizeof m, "run.duration: %.4g s ends where the run already is: it has turned %.4g s; give a "
                  "longer duration to extend it", asked, turned);
    throw std::invalid_argument(where + m);
  }
  const fs::path dir(o.resume);
  MillCase nc = io::parse_case(cp.case_toml, (dir / "case.toml").string(), case_overrides(o.c));
  nc.name = cp.case_name;
  const MillDerived nd = derive(nc);
  try {
    cp.run = extend_run(cp.run, p.c, p.d, nc, nd, p.d.dt);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(where + e.what());
  }
  p.c = nc;
  p.d = nd;
  cp.case_toml = io::case_to_toml(nc);
}

// A run as it starts: its case (from CASE or from the checkpoint it
// resumes), the device and the solver with its state, and its folder.
struct RunStart {
  bool resume = false, extend = false;
  // An extension that could not keep the window already begun starts a new
  // one: the rows before it are no longer averaged.
  bool window_restarted = false;
  Prepared p;
  io::Checkpoint cp;
  std::unique_ptr<compute::Context> ctx;
  std::unique_ptr<Solver> solver;
  fs::path out;
  std::string case_text;
  std::vector<std::string> kept_rows;  // timeseries.csv's rows before the checkpoint
  // A checkpoint that counts no rows, in a folder without a time series (a
  // state saved by the viewer): the series begins here.
  bool new_series = false;
};

// What the run writes as it goes: the time series, the snapshots' index,
// the power plot's points, and the time of the last checkpoint.
struct RunFiles {
  std::ofstream csv;
  std::vector<double> t_series, p_torque, p_diss;
  std::unique_ptr<io::PvdIndex> pvd;
  int n_snap = 0;
  double checkpoint_t = -1;
};

// The case (or the checkpoint), the device and the kernels, then the run
// folder: nothing is written before the device and the kernels are known
// good. The pictures need nothing from the machine (their font is built
// in), and one that cannot be drawn is a warning at the end, never a lost
// run.
RunStart prepare_run(const RunOptions& o) {
  RunStart r;
  r.resume = !o.resume.empty();
  r.extend = r.resume && (o.c.duration > 0 || o.c.duration_auto || !o.c.overrides.empty());
  if (r.resume) {
    if (!o.c.case_path.empty() || !o.c.precision.empty())
      throw std::invalid_argument("--resume " + o.resume +
                                  ": continues the run with its own case; a CASE or --precision cannot be given "
                                  "with it (--duration may, to turn it longer)");
    const fs::path dir(o.resume);
    r.p = prepare_from_checkpoint(dir, r.cp, "; the run cannot be resumed from it");
    std::error_code ec;
    if (!r.extend && r.cp.run.phase == 3 && fs::exists(dir / "summary.json", ec))
      throw std::invalid_argument("--resume " + o.resume +
                                  ": the run there is complete (summary.json); nothing to do. To turn it longer, "
                                  "give --duration S (longer than it has turned) or --duration auto");
    const int window_begun_before = r.cp.run.window_begun;
    if (r.extend) extend_from_checkpoint(o, r.p, r.cp);
    r.window_restarted = r.extend && r.cp.run.window_begun == 0 && window_begun_before != 0;
  } else {
    r.p = prepare(o.c);
  }
  r.ctx = std::make_unique<compute::Context>(o.c.device);
  r.solver = make_solver(*r.ctx, r.p.scene);
  if (r.resume) {
    try {
      r.solver->restore_state(r.cp.solver);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(o.resume + "/" + io::kCheckpointFile + ": " + e.what());
    }
  }
  r.out = r.resume ? fs::path(o.resume) : o.out.empty() ? default_out(r.p.c) : fs::path(o.out);
  r.case_text = r.resume ? r.cp.case_toml : io::case_to_toml(r.p.c);
  if (r.resume) {
    std::error_code ec;
    r.new_series = r.cp.run.rows == 0 && !fs::exists(r.out / "timeseries.csv", ec);
    if (!r.new_series) r.kept_rows = keep_rows(r.out / "timeseries.csv", r.cp.run.rows, r.window_restarted);
    fs::create_directories(r.out / "snapshots", ec);
    if (ec) throw std::runtime_error("cannot create " + (r.out / "snapshots").string() + ": " + ec.message());
    if (r.extend) io::write_file_atomic(r.out / "case.toml", r.case_text);
  } else {
    make_run_dir(r.out, o.force);
    io::write_file_atomic(r.out / "case.toml", r.case_text);
  }
  return r;
}

// The run's first lines: the mill, the device, where it resumes.
void announce(const RunStart& r) {
  const MillCase& c = r.p.c;
  const MillDerived& d = r.p.d;
  std::printf("millcharge: %s: D %.3g m x L %.3g m, %s balls, %.1f %% of critical (%.2f rpm), J %.3f, dt %.3g s, %s\n",
              c.name.c_str(), c.diameter, c.length, thousands(d.n_balls).c_str(), 100 * d.speed_fraction, d.speed_rpm,
              d.filling_from_counts, d.dt, c.precision == Precision::double_ ? "double" : "float");
  std::printf("millcharge: device %s; output in %s\n", r.ctx->info().label().c_str(), r.out.string().c_str());
  if (r.resume)
    std::printf("millcharge: resuming at t = %.4f s (step %s, %ld rows written)\n", r.solver->time_s(),
                thousands(r.solver->steps()).c_str(), r.cp.run.rows);
  if (r.extend) {
    const TurnPlan plan = plan_turning(c, d, d.dt, r.cp.run.window_floor_step, r.cp.run.stop_step);
    std::printf("millcharge: extended: the mill turns to %.4g s; the window %s at %.4g s%s\n",
                plan.turn_steps * d.dt, r.cp.run.window_begun == 0 ? "begins" : "goes on from its start",
                plan.window_start * d.dt,
                r.window_restarted
                    ? ". The averages start again there: the longer run averages over its own last whole "
                      "revolutions, which begin where the first run's window had not, so the first run's books "
                      "cannot be carried on. Nothing is lost and nothing needs doing: the figures at the end are "
                      "the longer run's (its summary.json replaces the first's; copy that first to keep it)"
                    : "");
  }
  std::fflush(stdout);
}

// timeseries.csv (new, or appended to after the rows kept), the plot's
// points from the rows kept, and charge.pvd.
RunFiles open_run_files(const RunStart& r) {
  RunFiles f;
  const fs::path& out = r.out;
  if (r.resume && !r.new_series) {
    f.csv.open(out / "timeseries.csv", std::ios::app);
  } else {
    f.csv.open(out / "timeseries.csv");
    f.csv << "time_s,revolutions,torque_Nm,torque_power_W,dissipation_power_W,torque_arm_power_W,kinetic_J,"
             "rotational_J,potential_J,elastic_J,toe_deg,shoulder_deg,com_angle_deg,neighbours_per_ball,averaged\n";
  }
  if (!f.csv) throw std::runtime_error("cannot write " + (out / "timeseries.csv").string());
  f.csv.flush();
  for (const std::string& row : r.kept_rows) {  // the plot's points from the rows kept
    double v[5];
    if (std::sscanf(row.c_str(), "%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4]) == 5 &&
        v[0] >= 0.05 * r.p.d.revolution_s) {
      f.t_series.push_back(v[0]);
      f.p_torque.push_back(v[3]);
      f.p_diss.push_back(v[4]);
    }
  }
  f.pvd = std::make_unique<io::PvdIndex>(out / "charge.pvd");
  if (r.resume) f.pvd->keep_existing(static_cast<std::size_t>(r.cp.run.snapshots));
  f.n_snap = r.resume ? static_cast<int>(r.cp.run.snapshots) : 0;
  f.checkpoint_t = r.resume ? r.solver->time_s() : -1;
  return f;
}

// Settles and turns the mill (run_mill), writing rows, snapshots and
// checkpoints as it goes; stops at SIGINT or SIGTERM with a checkpoint.
RunSummary settle_and_turn(RunStart& r, RunFiles& f, const RunOptions& o, ProgressPrinter& progress,
                           StopSignals& signals) {
  const MillCase& c = r.p.c;
  const MillDerived& d = r.p.d;
  const fs::path& out = r.out;
  Solver& solver = *r.solver;
  RunHooks hooks;
  hooks.on_row = [&](const TimeRow& row) {
    char line[512];
    std::snprintf(line, sizeof line, "%.6f,%.6f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%s,%s,%.3f,%.4g,%d\n",
                  row.time_s, row.revolutions, row.torque_Nm, row.torque_power_W, row.dissipation_power_W,
                  row.torque_arm_power_W, row.kinetic_J, row.rotational_J, row.potential_J, row.elastic_J,
                  row.angles.found ? std::to_string(row.angles.toe_deg).c_str() : "",
                  row.angles.found ? std::to_string(row.angles.shoulder_deg).c_str() : "", row.com_angle_deg,
                  row.neighbours_per_ball, row.averaged ? 1 : 0);
    f.csv << line;
    f.csv.flush();
    if (row.time_s >= 0.05 * d.revolution_s) {  // the start-up jolt would flatten the plot
      f.t_series.push_back(row.time_s);
      f.p_torque.push_back(row.torque_power_W);
      f.p_diss.push_back(row.dissipation_power_W);
    }
  };
  hooks.on_snapshot = [&](double t) {
    char name[64];
    std::snprintf(name, sizeof name, "snapshots/charge_%06d.vtp", f.n_snap++);
    io::Snapshot snap = snapshot_of(solver.balls(), t);
    if (!r.p.scene.bodies.empty()) {  // each component's body and its orientation
      const std::vector<BodyState> bodies = solver.bodies();
      std::vector<int> body_of(r.p.scene.balls.size(), -1);
      for (const Ball& b : r.p.scene.balls) body_of[b.id] = b.body;
      snap.body.resize(snap.size());
      snap.orientation.resize(snap.size());
      for (std::size_t i = 0; i < snap.size(); ++i) {
        const int b = body_of[snap.id[i]];
        snap.body[i] = b;
        const auto& q = b >= 0 ? bodies[b].orientation : std::array<double, 4>{0, 0, 0, 1};
        snap.orientation[i] = {float(q[0]), float(q[1]), float(q[2]), float(q[3])};
      }
    }
    io::write_vtp(out / name, snap);
    f.pvd->add(t, name);
  };
  hooks.on_progress = [&](const RunProgress& pr) { progress(pr); };
  // Checkpoints: the rows and snapshots are on disk before the checkpoint
  // that counts them, so a resumed run cuts the files back to it.
  hooks.checkpoint_interval_s = c.checkpoint_interval;
  hooks.on_checkpoint = [&](const RunState& rs) {
    f.csv.flush();
    io::write_checkpoint(out / io::kCheckpointFile, io::Checkpoint{c.name, r.case_text, rs, solver.save_state()});
    f.checkpoint_t = solver.time_s();
  };
  hooks.stop_requested = [&] { return signals.signal() != 0; };
  hooks.poison_at_s = o.poison_at_s;

  RunSummary s;
  try {
    s = run_mill(solver, r.p.scene, c, d, hooks, r.resume ? r.cp.run : RunState{});
  } catch (const compute::Error&) {
    throw;
  } catch (const std::runtime_error& e) {
    std::string m = e.what();
    if (f.checkpoint_t >= 0)
      m += ". The last good checkpoint (t = " + std::to_string(f.checkpoint_t) + " s) is " +
           (out / io::kCheckpointFile).string() + "; after a fix that keeps the case, resume with: millcharge run --resume " +
           out.string();
    else
      m += ". No checkpoint was written before it";
    throw std::runtime_error(m);
  }
  f.csv.close();
  return s;
}

// A run stopped by a signal: how to go on. The exit status is 128 + the signal.
int stopped(const RunStart& r, ProgressPrinter& progress, const StopSignals& signals) {
  progress.finish_line();
  const int sig = signals.signal();
  std::fprintf(stderr,
               "millcharge: stopped by %s at t = %.4f s; checkpoint %s written; continue with: millcharge run "
               "--resume %s\n",
               sig == SIGTERM ? "SIGTERM" : "SIGINT", r.solver->time_s(), (r.out / io::kCheckpointFile).string().c_str(),
               r.out.string().c_str());
  return 128 + sig;
}

}  // namespace

int cmd_run(const RunOptions& o) {
  RunStart r = prepare_run(o);
  announce(r);
  RunFiles files = open_run_files(r);
  ProgressPrinter progress(o.quiet);
  StopSignals signals;
  const RunSummary s = settle_and_turn(r, files, o, progress, signals);
  if (s.interrupted) return stopped(r, progress, signals);
  const FinishedRun done{r.p.c,        r.p.d,        r.p.scene,     s,         *r.solver, r.ctx->info().label(),
                         r.out,        *files.pvd,   files.t_series, files.p_torque, files.p_diss};
  const RunReport report = report_of(done);
  const std::vector<std::string> not_written = write_run_results(done, report);
  print_run_results(done, report, not_written);
  return 0;
}

}  // namespace mc::app
