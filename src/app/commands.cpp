#include "app/commands.h"
#include "core/clump.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <numeric>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "compute/context.h"
#include "core/charge_edit.h"
#include "core/lifters.h"
#include "core/liner.h"
#include "core/mill_case.h"
#include "core/wall_mesh.h"
#include "core/morrell.h"
#include "io/atomic_file.h"
#include "io/case_file.h"
#include "io/checkpoint.h"
#include "io/energy_out.h"
#include "io/png_plot.h"
#include "io/stl.h"
#include "io/vtk.h"
#include "sim/batch_means.h"
#include "sim/energy_report.h"
#include "sim/mill_run.h"
#include "sim/solver.h"
#include "viewer/viewer.h"

namespace mc::app {

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Prepared {
  fs::path path;
  MillCase c;
  MillDerived d;
  Scene scene;
};

// --set, --duration and --precision as overrides of the case's keys.
std::vector<std::string> case_overrides(const CaseOptions& o) {
  std::vector<std::string> overrides = o.overrides;
  if (o.duration_auto) {
    overrides.push_back("run.duration=\"auto\"");
  } else if (o.duration > 0) {
    std::ostringstream s;
    s.precision(17);
    s << "run.duration=" << o.duration;
    overrides.push_back(s.str());
  }
  if (!o.precision.empty()) overrides.push_back("run.precision=\"" + o.precision + "\"");
  return overrides;
}

Prepared prepare(const CaseOptions& o, const fs::path& default_path = io::default_case()) {
  Prepared p;
  p.path = o.case_path.empty() ? default_path : fs::path(o.case_path);
  p.c = io::read_case(p.path, case_overrides(o));
  p.d = derive(p.c);
  try {
    p.scene = build_scene(p.c, p.d);
  } catch (const std::invalid_argument& e) {
    throw io::CaseError(p.path.string() + ": " + e.what());
  }
  return p;
}

// The case of the run in `dir`, from its checkpoint (read into `cp`). A bad
// checkpoint is bad input: its message, then `consequence`.
Prepared prepare_from_checkpoint(const fs::path& dir, io::Checkpoint& cp, const std::string& consequence) {
  try {
    cp = io::read_checkpoint(dir / io::kCheckpointFile);
  } catch (const io::CheckpointError& e) {
    throw std::invalid_argument(e.what() + consequence);
  }
  Prepared p;
  p.path = dir / "case.toml";
  p.c = io::parse_case(cp.case_toml, (dir / io::kCheckpointFile).string() + " (case)");
  p.c.name = cp.case_name;
  p.d = derive(p.c);
  p.scene = build_scene(p.c, p.d);
  return p;
}

std::string thousands(long v) {
  std::string s = std::to_string(v);
  for (int i = static_cast<int>(s.size()) - 3; i > (v < 0 ? 1 : 0); i -= 3) s.insert(i, ",");
  return s;
}

std::string duration_text(double s) {
  if (!(s >= 0) || s > 1e7) return "?";
  char buf[32];
  if (s < 60) std::snprintf(buf, sizeof buf, "%.0fs", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  else std::snprintf(buf, sizeof buf, "%dh%02dm", static_cast<int>(s) / 3600, static_cast<int>(s) / 60 % 60);
  return buf;
}

// Progress on stderr: one line rewritten in place on a terminal; plain lines
// at every tenth of the run (or every 30 s) otherwise.
class ProgressPrinter {
 public:
  explicit ProgressPrinter(bool quiet) : quiet_(quiet), tty_(::isatty(2) == 1) {}
  void operator()(const RunProgress& p) {
    if (quiet_) return;
    char line[256];
    if (p.phase == "settle")
      std::snprintf(line, sizeof line, "settling  t %.3f s  %s steps  %.3g steps/s  %.3g updates/s", p.simulated_s,
                    thousands(p.steps).c_str(), p.steps_per_s, p.updates_per_s);
    else if (p.relative_error >= 0)  // an auto run: its power's error so far, and the time left to its cap
      std::snprintf(line, sizeof line,
                    "turning   t %.3f s  rev %.2f  power \u00b1%.2f %%  %.3g steps/s  %.3g updates/s  %s left at most",
                    p.simulated_s, p.revolutions, 100 * p.relative_error, p.steps_per_s, p.updates_per_s,
                    duration_text(p.eta_s).c_str());
    else
      std::snprintf(line, sizeof line, "turning   t %.3f s  rev %.2f  %3.0f %%  %.3g steps/s  %.3g updates/s  %s left",
                    p.simulated_s, p.revolutions, 100 * p.done, p.steps_per_s, p.updates_per_s,
                    duration_text(p.eta_s).c_str());
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
                          "spectra.png", "wear.csv", "liner.vtp", "liner.png"})
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

// Lifter polygons turned from the mill frame into the lab frame.
std::vector<std::vector<Vec2>> lab_lifters(const Scene& scene, double mill_angle) {
  std::vector<std::vector<Vec2>> out = scene.walls.lifters;
  const double c = std::cos(mill_angle), s = std::sin(mill_angle);
  for (auto& poly : out)
    for (Vec2& v : poly) v = {c * v.x - s * v.y, s * v.x + c * v.y};
  return out;
}

double finite_or_nan(bool ok, double v) { return ok ? v : std::nan(""); }

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

// "873.9 ± 4.1 W": the value to the standard error's second digit; the
// value alone (as %.4g) where there is no error.
std::string plus_minus(double v, double sem, const char* unit) {
  char b[128];
  if (!std::isfinite(v)) {
    std::snprintf(b, sizeof b, "?%s", unit);
  } else if (!(std::isfinite(sem) && sem > 0)) {
    std::snprintf(b, sizeof b, "%.4g%s", v, unit);
  } else {
    const int decimals = std::clamp(1 - static_cast<int>(std::floor(std::log10(sem))), 0, 6);
    std::snprintf(b, sizeof b, "%.*f \u00b1 %.*f%s", decimals, v, decimals, sem, unit);
  }
  return b;
}

// The standard errors of a run's means, each from its revolutions' means
// (batch means, sim/batch_means.h).
struct Errors {
  BatchMeans power, dissipation, torque, arm, toe, shoulder, com;
  BatchMeans collisions, collision_power, impacts, impact, shear, wear;
};

// A batch of `length` base batches, per_rev of them to a revolution, in
// words: "1/8 revolution", "1/4 revolution", "1 revolution", "2 revolutions".
std::string batch_words(int length, int per_rev) {
  if (length % per_rev == 0) {
    const int r = length / per_rev;
    return std::to_string(r) + (r == 1 ? " revolution" : " revolutions");
  }
  const int g = std::gcd(length, per_rev);
  return std::to_string(length / g) + "/" + std::to_string(per_rev / g) + " revolution";
}

Errors errors_of(const std::vector<WindowBatch>& revs) {
  auto of = [&](double WindowBatch::*field) {
    std::vector<double> v;
    for (const WindowBatch& m : revs) v.push_back(m.*field);
    return batch_means(v);
  };
  Errors e;
  e.power = of(&WindowBatch::torque_power_W);
  e.dissipation = of(&WindowBatch::dissipation_power_W);
  e.torque = of(&WindowBatch::torque_Nm);
  e.arm = of(&WindowBatch::torque_arm_power_W);
  e.toe = of(&WindowBatch::toe_deg);
  e.shoulder = of(&WindowBatch::shoulder_deg);
  e.com = of(&WindowBatch::com_angle_deg);
  e.collisions = of(&WindowBatch::collisions_per_s);
  e.collision_power = of(&WindowBatch::collision_power_W);
  e.impacts = of(&WindowBatch::liner_impacts_per_s);
  e.impact = of(&WindowBatch::liner_impact_W);
  e.shear = of(&WindowBatch::liner_shear_W);
  e.wear = of(&WindowBatch::wear_kg_per_h);
  return e;
}

}  // namespace

int cmd_devices() {
  const auto devices = compute::list_devices();
  if (devices.empty()) {
    std::cerr << "millcharge: OpenCL: " << compute::no_device_message() << '\n';
    return 1;
  }
  for (const auto& d : devices)
    std::printf("%s\n    %s, %s, %d compute units, %.1f GiB, fp64 %s, gl sharing %s\n", d.label().c_str(),
                d.version.c_str(), d.c_version.c_str(), d.compute_units, d.global_mem_bytes / 1073741824.0,
                d.fp64 ? "yes" : "no", d.gl_sharing ? "yes" : "no");
  for (const auto& [index, name] : compute::platforms_without_devices()) {
    std::printf("platform %d (%s): no devices", index, name.c_str());
    if (name == "rusticl" && !std::getenv("RUSTICL_ENABLE"))
      std::printf(" (Mesa's rusticl offers one when RUSTICL_ENABLE names a driver: RUSTICL_ENABLE=llvmpipe for the CPU)");
    std::printf("\n");
  }
  return 0;
}

int cmd_check(const CaseOptions& o) {
  const Prepared p = prepare(o);
  const MillCase& c = p.c;
  const MillDerived& d = p.d;
  std::printf("case            %s%s%s\n", p.path.string().c_str(), c.title.empty() ? "" : ": ", c.title.c_str());
  std::printf("mill            D %.4g m x L %.4g m%s, %d lifter rows, liner \"%s\"\n", c.diameter, c.length,
              c.periodic ? " (a periodic slice)" : "", c.lifter_rows, c.liner.c_str());
  if (c.periodic)
    std::printf("ends            periodic (mill.ends): no end plates, a ball leaving one end enters at the other; "
                "shortest slice %.4g m (%.0f largest balls); power, torque, spectra and wear also per metre\n",
                d.shortest_slice, kSliceDiameters);
  else if (c.ends.cones())
    std::printf("ends            cone heads (mill.ends = \"cones\") beyond the belly's z = 0 and %.4g m\n", c.length);
  else
    std::printf("ends            end plates at z = 0 and %.4g m (mill.ends = \"periodic\" would make a slice: at "
                "least %.4g m)\n",
                c.length, d.shortest_slice);
  std::printf("critical speed  %.2f rpm  (42.3/sqrt(D - d), d = largest ball %.4g mm)\n", d.critical_rpm,
              1000 * d.largest_ball_diameter);
  std::printf("speed           %.2f rpm = %.1f %% of critical  (%.4g rad/s, %.4g s per revolution, tip %.3g m/s)\n",
              d.speed_rpm, 100 * d.speed_fraction, d.omega, d.revolution_s, d.tip_speed);
  std::printf("volume          %.4g m^3 inside the shell, lifters excluded (lifters %.3g m^3)\n", d.mill_volume,
              d.lifter_volume);
  std::printf("charge          J %.3f requested: %s balls, %.4g kg; J %.4f from the whole ball counts\n", c.filling,
              thousands(d.n_balls).c_str(), d.charge_mass, d.filling_from_counts);
  for (std::size_t k = 0; k < c.sizes.size(); ++k) {
    const SizeClass& s = c.sizes[k];
    char dia[64];
    if (s.diameter_min == s.diameter_max) std::snprintf(dia, sizeof dia, "%.4g mm", 1000 * s.diameter_min);
    else std::snprintf(dia, sizeof dia, "%.4g-%.4g mm", 1000 * s.diameter_min, 1000 * s.diameter_max);
    std::printf("  size %-9zu %s %s: %s %s, %s fraction %.3f\n", k, dia, s.material.c_str(),
                thousands(d.class_counts[k]).c_str(), s.shape.empty() ? "balls" : "clumps", c.number_fractions ? "number" : "mass",
                s.fraction);
    if (!s.shape.empty()) {
      // The clump at a volume-equivalent diameter of 1: its spheres, its
      // extent along its principal axes and its moments over m d².
      const ClumpShape u = normalised_shape(size_class_shape(c, s.shape, "charge.size"), 1.0);
      const ClumpMassProperties mp = clump_mass_properties(u);
      double ext[3] = {0, 0, 0};
      for (const ClumpSphere& q : u.spheres) {
        ext[0] = std::max(ext[0], std::fabs(q.centre.x) + q.radius);
        ext[1] = std::max(ext[1], std::fabs(q.centre.y) + q.radius);
        ext[2] = std::max(ext[2], std::fabs(q.centre.z) + q.radius);
      }
      std::printf("    shape \"%s\": a rigid body of %zu spheres, %.3g x %.3g x %.3g d along its principal axes, "
                  "moments %.4g, %.4g, %.4g m d^2 (a ball: 0.1)\n",
                  s.shape.c_str(), u.spheres.size(), 2 * ext[0], 2 * ext[1], 2 * ext[2], mp.principal.x / mp.volume,
                  mp.principal.y / mp.volume, mp.principal.z / mp.volume);
    }
  }
  if (c.ends.cones())
    std::printf("cones           %.4g deg from the end plane, trunnion %.4g m: each head %.4g m deep (the mill "
                "%.4g m long on the axis)\n",
                c.ends.cone_angle_deg, c.ends.trunnion_diameter, cone_depth(c.ends, 0.5 * c.diameter),
                c.length + 2 * cone_depth(c.ends, 0.5 * c.diameter));
  if (!c.meshes.empty() || c.ends.cones() || c.ends.lifter_rows > 0) {
    const std::vector<WallMesh> meshes = place_meshes(c);
    const MeshTopology topo = mesh_topology(meshes);
    for (std::size_t k = 0; k < meshes.size(); ++k) {
      const WallMesh& m = meshes[k];
      const char* part = m.part == MeshPart::shell ? "shell" : m.part == MeshPart::ends ? "ends" : "lifters";
      char vol[96];
      if (m.volume > 0) std::snprintf(vol, sizeof vol, "closed, %.4g m^3 taken from the mill", m.volume);
      else std::snprintf(vol, sizeof vol, "open (its volume is not taken from the mill)");
      const std::string name = k < c.meshes.size() ? c.meshes[k].path : m.name;
      std::printf("mesh %-10zu %s: %s triangles, %s, %s, part \"%s\", material \"%s\"\n", k, name.c_str(),
                  thousands(static_cast<long>(m.triangles.size())).c_str(), vol,
                  m.turning ? "turning with the mill" : "standing still", part, m.material.name.c_str());
    }
    std::printf("meshes          %s triangles, %d edges, %d vertices in %d smooth surfaces (cl/mesh.h)\n",
                thousands(topo.n_triangles).c_str(), topo.n_edges, topo.n_vertices, topo.n_patches);
  }
  if (!o.write_lifters.empty()) {
    // The parametric bars cut at the shell, as an STL: a start for CAD, or a
    // [[walls.mesh]] that stands for them.
    const Scene w = build_walls(c, d);
    if (w.walls.lifters.empty())
      throw std::invalid_argument("--write-lifters: the case has no lifter bars (lifters.rows = 0)");
    const auto tris = lifter_triangles(bars_on_shell(w.walls.lifters, w.walls.shell_radius), c.length);
    io::write_file_atomic(o.write_lifters, io::stl_binary(tris, c.name + " lifters, m"));
    std::printf("lifters         %d bars as %s triangles (binary STL, metres, mill frame at t = 0): %s\n",
                c.lifter_rows, thousands(static_cast<long>(tris.size())).c_str(), o.write_lifters.c_str());
  }
  std::ostringstream stiffness;
  if (c.law == ContactLaw::linear) stiffness << ", kn " << c.contact.kn << " N/m";
  std::printf("contact         %s, e %.3g, friction %.3g, rolling %.3g%s (defaults; %zu pair overrides)\n",
              c.law == ContactLaw::linear ? "linear spring-dashpot" : "Hertz-Mindlin", c.contact.restitution,
              c.contact.mu_slide, c.contact.mu_roll, stiffness.str().c_str(), c.pairs.size());
  std::printf("contact time    %.4g s, shortest ball-ball contact%s\n", d.contact_time,
              c.law == ContactLaw::hertz ? " (impact at the tip speed)" : "");
  std::printf("dt              %.4g s (%s; %.1f steps per contact)\n", d.dt,
              d.dt_auto ? "auto" : "from the case", d.contact_time / d.dt);
  const long steps = std::lround(d.turn_limit_s / d.dt);
  char turn[256];
  if (c.duration_auto)
    std::snprintf(turn, sizeof turn,
                  "turn auto: until the power's standard error is %.3g %% of its mean, at most %.4g s = %.3g "
                  "revolutions (%s steps)",
                  100 * c.tolerance, d.turn_limit_s, d.turn_limit_s / d.revolution_s, thousands(steps).c_str());
  else
    std::snprintf(turn, sizeof turn, "turn %.4g s = %.3g revolutions (%s steps)", c.duration,
                  c.duration / d.revolution_s, thousands(steps).c_str());
  std::printf("run             settle %s (damping %.3g 1/s), %s, warm-up %.4g s, %s\n",
              c.settle < 0 ? "auto" : (std::to_string(c.settle) + " s").c_str(), d.settle_damping, turn, c.warmup,
              c.precision == Precision::double_ ? "double" : "float");
  const MorrellResult m = morrell_c_model(morrell_input(c, d));
  std::printf("morrell c-model power %.4g W (k %.2f x net %.4g W), toe %.1f deg, shoulder %.1f deg\n",
              m.charge_power_W, kMorrellK, m.net_power_W, m.toe_deg, m.shoulder_deg);
  if (p.scene.bodies.empty())
    std::printf("packing         %s balls placed without overlaps\n", thousands(static_cast<long>(p.scene.balls.size())).c_str());
  else
    std::printf("packing         %s clumps (%s spheres) and %s balls placed without overlaps\n",
                thousands(static_cast<long>(p.scene.bodies.size())).c_str(),
                thousands(static_cast<long>(p.scene.balls.size()) - p.scene.bodies.front().first).c_str(),
                thousands(static_cast<long>(p.scene.bodies.front().first)).c_str());
  return 0;
}

namespace {

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
  const std::size_t width = std::count(lines[0].begin(), lines[0].end(), ',') + 1;
  for (std::size_t k = 1; k < lines.size(); ++k) {
    const std::string where = csv.string() + ":" + std::to_string(k + 1) + ": ";
    std::size_t fields = 0, from = 0;
    for (;;) {
      const std::size_t comma = lines[k].find(',', from);
      const std::string f = lines[k].substr(from, comma == std::string::npos ? std::string::npos : comma - from);
      char* end = nullptr;
      const double x = f.empty() ? 0.0 : std::strtod(f.c_str(), &end);
      if (f.empty() || *end != '\0' || !std::isfinite(x))
        throw std::invalid_argument(where + "\"" + f + "\" is not a number; the run's time series is damaged, so "
                                    "it cannot be resumed (run it again)");
      ++fields;
      if (comma == std::string::npos) break;
      from = comma + 1;
    }
    if (fields != width)
      throw std::invalid_argument(where + std::to_string(fields) + " fields, the header has " + std::to_string(width) +
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

}  // namespace

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

int cmd_run(const RunOptions& o) {
  const bool resume = !o.resume.empty();
  const bool extend = resume && (o.c.duration > 0 || o.c.duration_auto || !o.c.overrides.empty());
  Prepared p;
  io::Checkpoint cp;
  // An extension that could not keep the window already begun starts a new
  // one: the rows before it are no longer averaged.
  bool window_restarted = false;
  if (resume) {
    if (!o.c.case_path.empty() || !o.c.precision.empty())
      throw std::invalid_argument("--resume " + o.resume +
                                  ": continues the run with its own case; a CASE or --precision cannot be given "
                                  "with it (--duration may, to turn it longer)");
    const fs::path dir(o.resume);
    p = prepare_from_checkpoint(dir, cp, "; the run cannot be resumed from it");
    std::error_code ec;
    if (!extend && cp.run.phase == 3 && fs::exists(dir / "summary.json", ec))
      throw std::invalid_argument("--resume " + o.resume +
                                  ": the run there is complete (summary.json); nothing to do. To turn it longer, "
                                  "give --duration S (longer than it has turned) or --duration auto");
    const int window_begun_before = cp.run.window_begun;
    if (extend) extend_from_checkpoint(o, p, cp);
    window_restarted = extend && cp.run.window_begun == 0 && window_begun_before != 0;
  } else {
    p = prepare(o.c);
  }
  const MillCase& c = p.c;
  const MillDerived& d = p.d;
  // The device and the kernels before any file is written. The pictures
  // need nothing from the machine (their font is built in), and one that
  // cannot be drawn is a warning at the end, never a lost run.
  compute::Context ctx(o.c.device);
  auto solver = make_solver(ctx, p.scene);
  if (resume) {
    try {
      solver->restore_state(cp.solver);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(o.resume + "/" + io::kCheckpointFile + ": " + e.what());
    }
  }
  const fs::path out = resume ? fs::path(o.resume) : o.out.empty() ? default_out(c) : fs::path(o.out);
  const std::string case_text = resume ? cp.case_toml : io::case_to_toml(c);
  std::vector<std::string> kept_rows;
  if (resume) {
    kept_rows = keep_rows(out / "timeseries.csv", cp.run.rows, window_restarted);
    if (extend) io::write_file_atomic(out / "case.toml", case_text);
  } else {
    make_run_dir(out, o.force);
    io::write_file_atomic(out / "case.toml", case_text);
  }

  std::printf("millcharge: %s: D %.3g m x L %.3g m, %s balls, %.1f %% of critical (%.2f rpm), J %.3f, dt %.3g s, %s\n",
              c.name.c_str(), c.diameter, c.length, thousands(d.n_balls).c_str(), 100 * d.speed_fraction, d.speed_rpm,
              d.filling_from_counts, d.dt, c.precision == Precision::double_ ? "double" : "float");
  std::printf("millcharge: device %s; output in %s\n", ctx.info().label().c_str(), out.string().c_str());
  if (resume)
    std::printf("millcharge: resuming at t = %.4f s (step %s, %ld rows written)\n", solver->time_s(),
                thousands(solver->steps()).c_str(), cp.run.rows);
  if (extend) {
    const TurnPlan plan = plan_turning(c, d, d.dt, cp.run.window_floor_step, cp.run.stop_step);
    std::printf("millcharge: extended: the mill turns to %.4g s; the window %s at %.4g s%s\n",
                plan.turn_steps * d.dt, cp.run.window_begun == 0 ? "begins" : "goes on from its start",
                plan.window_start * d.dt,
                window_restarted ? " (the window already begun could not be kept: its books started elsewhere)" : "");
  }
  std::fflush(stdout);

  std::ofstream csv;
  if (resume) {
    csv.open(out / "timeseries.csv", std::ios::app);
  } else {
    csv.open(out / "timeseries.csv");
    csv << "time_s,revolutions,torque_Nm,torque_power_W,dissipation_power_W,torque_arm_power_W,kinetic_J,"
           "rotational_J,potential_J,elastic_J,toe_deg,shoulder_deg,com_angle_deg,neighbours_per_ball,averaged\n";
  }
  if (!csv) throw std::runtime_error("cannot write " + (out / "timeseries.csv").string());
  csv.flush();
  std::vector<double> t_series, p_torque, p_diss;
  for (const std::string& row : kept_rows) {  // the plot's points from the rows kept
    double v[5];
    if (std::sscanf(row.c_str(), "%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4]) == 5 &&
        v[0] >= 0.05 * d.revolution_s) {
      t_series.push_back(v[0]);
      p_torque.push_back(v[3]);
      p_diss.push_back(v[4]);
    }
  }
  io::PvdIndex pvd(out / "charge.pvd");
  if (resume) pvd.keep_existing(static_cast<std::size_t>(cp.run.snapshots));
  int n_snap = resume ? static_cast<int>(cp.run.snapshots) : 0;
  RunHooks hooks;
  hooks.on_row = [&](const TimeRow& r) {
    char line[512];
    std::snprintf(line, sizeof line, "%.6f,%.6f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%s,%s,%.3f,%.4g,%d\n",
                  r.time_s, r.revolutions, r.torque_Nm, r.torque_power_W, r.dissipation_power_W,
                  r.torque_arm_power_W, r.kinetic_J, r.rotational_J, r.potential_J, r.elastic_J,
                  r.angles.found ? std::to_string(r.angles.toe_deg).c_str() : "",
                  r.angles.found ? std::to_string(r.angles.shoulder_deg).c_str() : "", r.com_angle_deg,
                  r.neighbours_per_ball, r.averaged ? 1 : 0);
    csv << line;
    csv.flush();
    if (r.time_s >= 0.05 * d.revolution_s) {  // the start-up jolt would flatten the plot
      t_series.push_back(r.time_s);
      p_torque.push_back(r.torque_power_W);
      p_diss.push_back(r.dissipation_power_W);
    }
  };
  hooks.on_snapshot = [&](double t) {
    char name[64];
    std::snprintf(name, sizeof name, "snapshots/charge_%06d.vtp", n_snap++);
    io::Snapshot snap = snapshot_of(solver->balls(), t);
    if (!p.scene.bodies.empty()) {  // each component's body and its orientation
      const std::vector<BodyState> bodies = solver->bodies();
      std::vector<int> body_of(p.scene.balls.size(), -1);
      for (const Ball& b : p.scene.balls) body_of[b.id] = b.body;
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
    pvd.add(t, name);
  };
  ProgressPrinter progress(o.quiet);
  hooks.on_progress = [&](const RunProgress& pr) { progress(pr); };
  // Checkpoints: the rows and snapshots are on disk before the checkpoint
  // that counts them, so a resumed run cuts the files back to it.
  double checkpoint_t = resume ? solver->time_s() : -1;
  hooks.checkpoint_interval_s = c.checkpoint_interval;
  hooks.on_checkpoint = [&](const RunState& rs) {
    csv.flush();
    io::write_checkpoint(out / io::kCheckpointFile, io::Checkpoint{c.name, case_text, rs, solver->save_state()});
    checkpoint_t = solver->time_s();
  };
  StopSignals signals;
  hooks.stop_requested = [&] { return signals.signal() != 0; };
  hooks.poison_at_s = o.poison_at_s;

  RunSummary s;
  try {
    s = run_mill(*solver, p.scene, c, d, hooks, resume ? cp.run : RunState{});
  } catch (const compute::Error&) {
    throw;
  } catch (const std::runtime_error& e) {
    std::string m = e.what();
    if (checkpoint_t >= 0)
      m += ". The last good checkpoint (t = " + std::to_string(checkpoint_t) + " s) is " +
           (out / io::kCheckpointFile).string() + "; after a fix that keeps the case, resume with: millcharge run --resume " +
           out.string();
    else
      m += ". No checkpoint was written before it";
    throw std::runtime_error(m);
  }
  csv.close();
  if (s.interrupted) {
    progress.finish_line();
    const int sig = signals.signal();
    std::fprintf(stderr,
                 "millcharge: stopped by %s at t = %.4f s; checkpoint %s written; continue with: millcharge run "
                 "--resume %s\n",
                 sig == SIGTERM ? "SIGTERM" : "SIGINT", solver->time_s(), (out / io::kCheckpointFile).string().c_str(),
                 out.string().c_str());
    return 128 + sig;
  }

  const MorrellInput mi = morrell_input(c, d);
  const MorrellResult m = morrell_c_model(mi);
  const double toe = finite_or_nan(s.angles.found, s.angles.toe_deg);
  const double shoulder = finite_or_nan(s.angles.found, s.angles.shoulder_deg);
  const double m_with_dem =
      s.angles.found ? kMorrellK * morrell_net_power(mi, toe * kPi / 180, shoulder * kPi / 180) : std::nan("");

  nlohmann::ordered_json j;
  j["case"] = c.name;
  j["title"] = c.title;
  j["n_particles"] = d.n_balls;
  j["speed_rpm"] = d.speed_rpm;
  j["critical_speed_rpm"] = d.critical_rpm;
  j["speed_fraction"] = d.speed_fraction;
  j["filling"] = d.filling_from_counts;
  j["filling_requested"] = c.filling;
  j["filling_settled"] = s.settled_filling;
  j["charge_mass_kg"] = d.charge_mass;
  j["law"] = c.law == ContactLaw::linear ? "linear" : "hertz";
  j["dt_s"] = d.dt;
  j["steps"] = s.steps;
  j["simulated_s"] = s.simulated_s;
  j["settle_s"] = s.settle_s;
  j["settle_wall_s"] = s.settle_wall_s;
  j["settled"] = s.settled;
  j["turning_s"] = s.turning_s;
  j["revolutions"] = s.revolutions;
  j["average"] = {{"from_s", s.window_from_s},
                  {"to_s", s.window_to_s},
                  {"revolutions", s.window_revolutions},
                  {"whole_revolutions", s.whole_revolutions}};
  const Errors err = errors_of(s.window_batches);
  const int per_rev = std::max(1, s.batches_per_revolution);
  const int window_revs = static_cast<int>(s.window_batches.size()) / per_rev;
  const double rel_err = err.power.sem / std::fabs(err.power.mean);
  j["power_W"] = {{"torque", s.torque_power_W},
                  {"dissipation", s.dissipation_power_W},
                  {"imbalance", s.imbalance},
                  {"energy_change", s.energy_change_W},
                  {"torque_arm", s.torque_arm_power_W},
                  {"torque_sem", number_or_null(err.power.sem)},
                  {"dissipation_sem", number_or_null(err.dissipation.sem)},
                  {"torque_arm_sem", number_or_null(err.arm.sem)}};
  j["torque_Nm"] = s.torque_Nm;
  j["torque_Nm_sem"] = number_or_null(err.torque.sem);
  // Per metre of mill, which a slice stands for (sweep collect reads it).
  j["ends"] = c.periodic ? "periodic" : "plates";
  j["length_m"] = c.length;
  j["power_per_metre_W"] = {{"torque", s.torque_power_W / c.length},
                            {"dissipation", s.dissipation_power_W / c.length}};
  j["torque_per_metre_Nm"] = s.torque_Nm / c.length;
  j["power_per_metre_W"]["torque_sem"] = number_or_null(err.power.sem / c.length);
  j["power_per_metre_W"]["dissipation_sem"] = number_or_null(err.dissipation.sem / c.length);
  j["toe_deg"] = number_or_null(toe);
  j["toe_deg_sem"] = number_or_null(err.toe.sem);
  j["shoulder_deg"] = number_or_null(shoulder);
  j["shoulder_deg_sem"] = number_or_null(err.shoulder.sem);
  j["com_angle_deg"] = s.com_angle_deg;
  j["com_angle_deg_sem"] = number_or_null(err.com.sem);
  // How the standard errors were taken, and how the turning ended.
  j["convergence"] = {{"duration", c.duration_auto ? "auto" : "fixed"},
                      {"tolerance", c.tolerance},
                      {"max_duration_s", c.duration_auto ? nlohmann::json(d.turn_limit_s) : nlohmann::json()},
                      {"converged", c.duration_auto ? nlohmann::json(s.converged) : nlohmann::json()},
                      {"stopped_at_cap", s.capped},
                      {"revolutions", window_revs},
                      {"batches", err.power.batches},
                      {"batches_per_revolution", per_rev},
                      {"revolutions_per_batch", static_cast<double>(err.power.batch_length) / per_rev},
                      {"lag1_autocorrelation", number_or_null(err.power.lag1)},
                      {"batches_correlated", err.power.correlated},
                      {"power_relative_sem", number_or_null(rel_err)}};
  j["neighbours_per_ball"] = s.neighbours_per_ball;
  j["morrell"] = {{"power_W", m.charge_power_W},
                  {"k", kMorrellK},
                  {"net_power_W", m.net_power_W},
                  {"toe_deg", m.toe_deg},
                  {"shoulder_deg", m.shoulder_deg},
                  {"power_with_dem_angles_W", number_or_null(m_with_dem)},
                  {"charge_density_kg_m3", mi.charge_density}};
  // Where the energy went over the window: collision spectra and the liner.
  const LinerLayout layout = liner_layout(p.scene);
  const SpectraReport spectra =
      spectra_report(p.scene, s.books, s.window_s, s.open_loss_start_J, s.open_loss_end_J, s.dissipated_J);
  const LinerReport liner =
      liner_report(p.scene, layout, s.books, s.window_s, s.profile, s.angles);
  j["spectra"] = io::spectra_json(spectra);
  j["spectra"]["total"]["collisions_per_s_sem"] = number_or_null(err.collisions.sem);
  j["spectra"]["total"]["power_W_sem"] = number_or_null(err.collision_power.sem);
  j["liner"] = io::liner_json(layout, liner, p.scene.wall_material.wear_coefficient);
  j["liner"]["impacts_per_s_sem"] = number_or_null(err.impacts.sem);
  j["liner"]["impact_power_W_sem"] = number_or_null(err.impact.sem);
  j["liner"]["shear_power_W_sem"] = number_or_null(err.shear.sem);
  j["liner"]["wear_kg_per_h_sem"] = number_or_null(err.wear.sem);
  j["per_metre"] = io::per_metre_json(c.length, s.torque_power_W, s.dissipation_power_W, s.torque_Nm, spectra, liner);
  j["contact_records_refused"] = solver->records_refused();
  j["wall_s"] = s.wall_s;
  j["particle_updates_per_s"] = s.updates_per_s;
  j["device"] = ctx.info().label();
  j["device_bytes"] = solver->device_bytes();
  j["precision"] = c.precision == Precision::double_ ? "double" : "float";

  // Pictures: power against time, and the end view with toe and shoulder.
  io::LinePlot plot;
  plot.title = c.name + ": power draw, " + std::to_string(static_cast<int>(std::lround(100 * d.speed_fraction))) +
               "% of critical";
  plot.x_label = "time since the mill started (s)";
  plot.y_label = "power (W)";
  plot.series = {{"torque power", t_series, p_torque, 0x1f77b4}, {"dissipation", t_series, p_diss, 0xd62728}};
  plot.span_from = s.window_from_s;
  plot.span_to = s.window_to_s;
  plot.span_label = "averaged";
  plot.ref_lines = {{s.torque_power_W, s.window_from_s, s.window_to_s, 0x0d3a5c, false,
                     "mean torque power " + io::value_with_error(s.torque_power_W, err.power.sem, "W")},
                    {s.dissipation_power_W, s.window_from_s, s.window_to_s, 0x7a1014, true,
                     "mean dissipation " + io::value_with_error(s.dissipation_power_W, err.dissipation.sem, "W")}};
  io::draw_or_warn(out / "power.png", [&] { io::write_line_plot_png(out / "power.png", plot); });
  io::EndView view;
  view.title = c.name + " at t = " + std::to_string(s.turning_s).substr(0, 5) + " s";
  view.shell_radius = 0.5 * c.diameter;
  view.lifters = lab_lifters(p.scene, solver->mill_angle());
  for (const BallState& b : solver->balls())
    view.balls.push_back({b.position.x, b.position.y, b.position.z, b.radius, b.velocity.norm()});
  view.toe_deg = s.angles.found ? s.angles.toe_deg : -1;
  view.shoulder_deg = s.angles.found ? s.angles.shoulder_deg : -1;
  view.impact_deg = std::isfinite(liner.impact_point_deg) ? liner.impact_point_deg : -1;
  view.has_com = true;
  const Observables now = solver->observe(false);
  view.com_x = now.com_x_m;
  view.com_y = now.com_y_m;
  io::draw_or_warn(out / "charge.png", [&] { io::write_end_view_png(out / "charge.png", view); });
  io::draw_or_warn(out / "liner.png", [&] { io::write_liner_png(out / "liner.png", c.name, layout, liner); });
  io::draw_or_warn(out / "spectra.png", [&] { io::write_spectra_png(out / "spectra.png", c.name, spectra); });
  io::write_spectra_csv(out / "spectra.csv", spectra);
  io::write_wear_csv(out / "wear.csv", layout, liner);
  // The liner in the mill frame, and beside each snapshot turned to the
  // mill's angle then (part 1 of the same times in charge.pvd).
  io::write_mesh_vtp(out / "liner.vtp", io::liner_mesh(layout, &liner, 0.0, s.turning_s));
  {
    const std::vector<double> times = pvd.times();
    for (std::size_t k = 0; k < times.size(); ++k) {
      char name[64];
      std::snprintf(name, sizeof name, "snapshots/liner_%06zu.vtp", k);
      io::write_mesh_vtp(out / name, io::liner_mesh(layout, &liner, p.scene.mill_angle + d.omega * times[k], times[k]));
      pvd.add(times[k], name, 1);
    }
  }
  io::write_file_atomic(out / "summary.json", j.dump(2) + "\n");

  std::printf("power draw      torque %s, dissipation %s (imbalance %+.2f %%), torque arm %s\n",
              plus_minus(s.torque_power_W, err.power.sem, " W").c_str(),
              plus_minus(s.dissipation_power_W, err.dissipation.sem, " W").c_str(), 100 * s.imbalance,
              plus_minus(s.torque_arm_power_W, err.arm.sem, " W").c_str());
  std::printf("                averaged over %.2f revolutions from t = %.3f s to %.3f s\n", s.window_revolutions,
              s.window_from_s, s.window_to_s);
  // An imbalance from a charge whose energy still changes (a window that
  // starts before the charge has settled into its motion) is not an error
  // of the books: say so, and what the books give with the change counted.
  if (s.torque_power_W != 0 && std::fabs(s.energy_change_W) > 0.01 * std::fabs(s.torque_power_W))
    std::printf("                the charge's energy %s by %.4g W over the window (not yet in a steady motion: "
                "a longer warm-up helps); torque - dissipation - that change: %+.2f %% of torque\n",
                s.energy_change_W < 0 ? "fell" : "rose", std::fabs(s.energy_change_W),
                100 * (s.torque_power_W - s.dissipation_power_W - s.energy_change_W) / s.torque_power_W);
  std::printf("per metre       torque %s, dissipation %s, torque %.4g N m/m over %.4g m%s\n",
              plus_minus(s.torque_power_W / c.length, err.power.sem / c.length, " W/m").c_str(),
              plus_minus(s.dissipation_power_W / c.length, err.dissipation.sem / c.length, " W/m").c_str(),
              s.torque_Nm / c.length, c.length, c.periodic ? " of periodic slice" : " between the end plates");
  const std::string batch = batch_words(err.power.batch_length, per_rev);
  if (err.power.batches >= 2 && std::isfinite(err.power.lag1))
    std::printf("                \u00b1 one standard error, from %d batch means of %s (lag-1 "
                "autocorrelation %.2f%s)\n",
                err.power.batches, batch.c_str(), err.power.lag1,
                err.power.correlated ? ", still correlated: the errors are too small" : "");
  else if (err.power.batches >= 2)
    std::printf("                \u00b1 one standard error, from %d batch means of %s (too few to "
                "test their correlation: a rough error)\n",
                err.power.batches, batch.c_str());
  if (s.duration_auto && s.converged)
    std::printf("convergence     converged after %d revolution%s: the power's standard error is %.2f %% of its mean "
                "(run.tolerance %.3g %%)\n",
                window_revs, window_revs == 1 ? "" : "s", 100 * rel_err, 100 * c.tolerance);
  else if (s.duration_auto)
    std::printf("convergence     NOT converged: stopped at the cap (run.max_duration %.4g s) after %d revolutions; "
                "the power's standard error is %.2f %% of its mean, run.tolerance %.3g %%\n",
                d.turn_limit_s, window_revs, 100 * rel_err, 100 * c.tolerance);
  if (s.angles.found)
    std::printf("charge angles   toe %s, shoulder %s, centre of mass %s\n",
                plus_minus(s.angles.toe_deg, err.toe.sem, " deg").c_str(),
                plus_minus(s.angles.shoulder_deg, err.shoulder.sem, " deg").c_str(),
                plus_minus(s.com_angle_deg, err.com.sem, " deg").c_str());
  std::printf("collisions      %s per s, %s (normal %.4g, tangential %.4g, rolling %.4g W); spectra %.4g W "
              "against dissipation %.4g W\n",
              plus_minus(spectra.all.collisions_per_s, err.collisions.sem, "").c_str(),
              plus_minus(spectra.all.power_W, err.collision_power.sem, " W").c_str(), spectra.all.normal_W,
              spectra.all.tangential_W, spectra.all.rolling_W, spectra.books_W, spectra.dissipation_W);
  std::printf("liner           impact %s, shear %s, wear %s, worst %.3g mm per 1000 h (%s)\n",
              plus_minus(liner.impact_W, err.impact.sem, " W").c_str(),
              plus_minus(liner.shear_W, err.shear.sem, " W").c_str(),
              plus_minus(liner.wear_kg_per_h, err.wear.sem, " kg/h").c_str(), liner.worst_wear_mm_per_1000h,
              liner.worst_element >= 0 ? io::element_name(layout, liner.worst_element).c_str() : "none");
  if (std::isfinite(liner.impact_point_deg))
    std::printf("impact point    %.0f deg, on the %s; %.3g W (%.0f %%) of the liner's impact power on bare liner\n",
                liner.impact_point_deg, liner.impact_point_on_liner ? "bare liner above the toe" : "toe",
                liner.bare_liner_impact_W, 100 * liner.bare_liner_impact_share);
  std::printf("morrell         power %.4g W (k %.2f x net %.4g W), toe %.1f deg, shoulder %.1f deg; DEM/model %.3f\n",
              m.charge_power_W, kMorrellK, m.net_power_W, m.toe_deg, m.shoulder_deg, s.torque_power_W / m.charge_power_W);
  std::printf("speed           %s steps in %.1f s wall (settling %.3g s simulated in %.1f s wall, %.0f %%), %.3g "
              "particle-updates/s\n",
              thousands(s.steps).c_str(), s.wall_s, s.settle_s, s.settle_wall_s,
              s.wall_s > 0 ? 100 * s.settle_wall_s / s.wall_s : 0.0, s.updates_per_s);
  std::printf("wrote           %s/{summary.json, timeseries.csv, charge.pvd, power.png, charge.png, spectra.csv, "
              "spectra.png, wear.csv, liner.vtp, liner.png}\n",
              out.string().c_str());
  return 0;
}

// The charge of checkpoint `cp` (the run of case `p`) laid anew `tile` times
// end to end along the mill axis, in the same mill made `tile` times as
// long: a settled, turning charge of `tile` times the balls with the same
// work per ball, for timing large charges without a warm-up that a small
// machine cannot afford. The balls keep their positions (shifted by a
// length per copy), velocities and spins; contact springs start afresh (so
// `tile` 1 gives the same state as the others, per ball), and the end
// plates between copies are gone.
Prepared tile_charge(compute::Context& ctx, const Prepared& p, const io::Checkpoint& cp, int tile) {
  std::vector<BallState> slice;
  {
    auto solver = make_solver(ctx, p.scene);
    solver->restore_state(cp.solver);
    slice = solver->balls();
  }
  for (const SizeClass& sc : p.c.sizes)
    if (!sc.shape.empty())
      throw std::invalid_argument("--tile: " + p.c.name + "'s charge is of clumps (charge.size.shape = \"" + sc.shape +
                                  "\"), and only a charge of balls is tiled; run the longer mill from its case");
  const long total = static_cast<long>(slice.size()) * tile;
  if (total > 500'000'000L)
    throw std::invalid_argument("--tile " + std::to_string(tile) + ": " + thousands(total) +
                                " balls is more than a run can hold (at most 500,000,000)");
  Prepared t = p;
  t.c.length = p.c.length * tile;
  if (tile > 1) t.c.name = p.c.name + " x" + std::to_string(tile);
  t.d = derive(t.c);
  std::vector<Ball> balls;
  balls.reserve(static_cast<std::size_t>(total));
  for (int k = 0; k < tile; ++k)
    for (const BallState& s : slice) {
      Ball b;
      b.id = static_cast<int>(balls.size());
      b.material = s.material;
      b.radius = s.radius;
      b.position = {s.position.x, s.position.y, s.position.z + k * p.c.length};
      b.velocity = s.velocity;
      b.omega = s.omega;
      balls.push_back(b);
    }
  ChargeEditOptions eo;
  eo.mill_angle = cp.solver.mill_angle;
  eo.mill_omega = t.d.omega;
  ChargeEditResult r = edit_charge(t.c, t.d, std::move(balls), eo);
  if (r.added != 0 || r.removed != 0 || r.moved != 0)
    throw std::invalid_argument("--tile " + std::to_string(tile) + ": " + std::to_string(r.moved + r.removed) +
                                " balls of " + cp.case_name + "'s charge overlap the walls of the longer mill");
  t.scene = std::move(r.scene);
  return t;
}

// The benchmark: the case's charge packed and turning for a warm-up, then
// timed steps with the observers a run has (a row of observables every output
// interval, ten contact-profile samples per row), then a shorter pass with
// stage timing for the shares. One JSON line on stdout.
int cmd_bench(const BenchOptions& o) {
  using clock = std::chrono::steady_clock;
  Prepared p;
  io::Checkpoint cp;
  if (!o.from.empty()) {
    if (!o.c.case_path.empty() || !o.c.overrides.empty())
      throw std::invalid_argument("--from " + o.from + ": the case is the run's own; a CASE or --set cannot be given with it");
    p = prepare_from_checkpoint(o.from, cp, "");
    if (!o.c.precision.empty() && (o.c.precision == "double") != (p.c.precision == Precision::double_))
      throw std::invalid_argument("--from " + o.from + ": the checkpoint holds " +
                                  (p.c.precision == Precision::double_ ? "double" : "float") + " state");
  } else {
    p = prepare(o.c, io::case_dir() / "bench_100k.toml");
  }
  if (o.tile > 0 && o.from.empty())
    throw std::invalid_argument("--tile " + std::to_string(o.tile) + ": needs --from DIR (the charge to repeat)");
  compute::Context ctx(o.c.device);
  auto note = [&](const std::string& s) {
    if (!o.quiet) std::fprintf(stderr, "bench: %s\n", s.c_str());
  };
  if (o.tile > 0) p = tile_charge(ctx, p, cp, o.tile);
  const MillCase& c = p.c;
  const MillDerived& d = p.d;
  const long n = static_cast<long>(p.scene.balls.size());
  note(c.name + ": " + thousands(n) + " balls on " + ctx.info().label());
  const auto t_build = clock::now();
  const bool both = o.books == "both";
  Scene scene = p.scene;
  scene.numerics.energy_books = o.books != "off";
  auto solver = make_solver(ctx, scene);
  if (!o.from.empty() && o.tile == 0) solver->restore_state(cp.solver);
  solver->set_mill_omega(d.omega);
  const double warmup_s = o.warmup >= 0 ? o.warmup : o.from.empty() ? 0.25 : 0.0;
  const long warmup = std::lround(warmup_s / d.dt);
  const long out_steps = std::max(1L, std::lround(c.output_interval / d.dt));
  const long profile_every = std::max(1L, out_steps / 10);
  // Steps in chunks between the observers' calls, as run_mill makes them;
  // `since_row` counts a solver's steps since its last row.
  auto steps = [&](Solver& sv, long& since_row, long count) {
    for (long done = 0; done < count;) {
      const long chunk = std::min(count - done, profile_every - since_row % profile_every);
      sv.advance(chunk);
      done += chunk;
      since_row += chunk;
      if (since_row % profile_every == 0) sv.sample_contact_profile();
      if (since_row >= out_steps) {
        sv.observe(true);
        (void)sv.take_contact_profile();
        since_row = 0;
      }
    }
    ctx.finish();
  };
  long since_row = 0;
  const auto t_warm = clock::now();
  note("kernels built and charge uploaded in " + duration_text(std::chrono::duration<double>(t_warm - t_build).count()) +
       "; warm-up " + thousands(warmup) + " steps");
  steps(*solver, since_row, warmup);
  const double warm_s = std::chrono::duration<double>(clock::now() - t_warm).count();
  // Without the books: a second solver from the same state, timed in turn
  // with the first, part by part, so that the machine's drift falls on both.
  std::unique_ptr<Solver> plain;
  long plain_since_row = since_row;
  if (both) {
    Scene off = p.scene;
    off.numerics.energy_books = false;
    plain = make_solver(ctx, off);
    plain->restore_state(solver->save_state());
    plain->set_mill_omega(d.omega);
  }
  long n_steps = o.steps;
  if (n_steps <= 0) {
    const double rate = warmup > 0 && warm_s > 0 ? warmup / warm_s : 100.0;
    n_steps = std::clamp(std::lround(10.0 * rate), 100L, 100000L);
  }
  note("timing " + thousands(n_steps) + " steps" + (both ? ", with the energy books and without, in turn" : ""));
  const long rebuilds0 = solver->rebuilds();
  // Timed in ten parts, each drained: on a shared machine a neighbour's burst
  // slows some parts, so the parts' spread says how far to trust the total,
  // and the best part is the figure least disturbed.
  const int n_parts = static_cast<int>(std::min(10L, n_steps));
  std::vector<double> part_rates, plain_rates;
  double wall = 0, plain_wall = 0;
  auto timed = [&](Solver& sv, long& since, long part, double& sum) {
    const auto t0 = clock::now();
    steps(sv, since, part);
    const double s = std::chrono::duration<double>(clock::now() - t0).count();
    sum += s;
    return s > 0 ? static_cast<double>(n) * part / s : 0.0;
  };
  for (int k = 0; k < n_parts; ++k) {
    const long part = n_steps * (k + 1) / n_parts - n_steps * k / n_parts;
    part_rates.push_back(timed(*solver, since_row, part, wall));
    if (plain) plain_rates.push_back(timed(*plain, plain_since_row, part, plain_wall));
  }
  std::sort(part_rates.begin(), part_rates.end());
  std::sort(plain_rates.begin(), plain_rates.end());
  const long rebuilds = solver->rebuilds() - rebuilds0;
  const ContactStats cs = solver->contact_stats();
  const std::size_t plain_bytes = plain ? plain->device_bytes() : 0;
  const std::size_t bytes = solver->device_bytes();
  plain.reset();

  // The shares: a shorter pass with the queue drained after every stage.
  const long stage_steps = std::max(20L, n_steps / 4);
  note("stage timing over " + thousands(stage_steps) + " steps");
  solver->set_stage_timing(true);
  steps(*solver, since_row, stage_steps);
  const StageTimes st = solver->stage_times();
  solver->set_stage_timing(false);

  const double total = st.total() > 0 ? st.total() : 1.0;
  nlohmann::ordered_json j;
  j["case"] = c.name;
  j["n_particles"] = n;
  j["steps"] = n_steps;
  j["wall_s"] = wall;
  j["particle_updates_per_s"] = static_cast<double>(n) * n_steps / wall;
  j["steps_per_s"] = n_steps / wall;
  j["parts"] = n_parts;
  j["part_updates_per_s"] = {{"min", part_rates.front()},
                             {"median", part_rates[part_rates.size() / 2]},
                             {"max", part_rates.back()}};
  j["energy_books"] = o.books == "off" ? "off" : "on";
  if (both) {
    // The same steps without the books, timed in turn with the ones above.
    const double plain_rate = static_cast<double>(n) * n_steps / plain_wall;
    j["books_off"] = {{"particle_updates_per_s", plain_rate},
                      {"part_updates_per_s",
                       {{"min", plain_rates.front()},
                        {"median", plain_rates[plain_rates.size() / 2]},
                        {"max", plain_rates.back()}}},
                      {"bytes_per_ball", static_cast<double>(plain_bytes) / n}};
    // How much slower the books make a step: by the totals, and by the
    // parts' medians (less moved by a neighbour's burst).
    j["books_cost"] = {{"total", wall / plain_wall - 1},
                       {"median_parts", plain_rates[plain_rates.size() / 2] / part_rates[part_rates.size() / 2] - 1}};
  } else {
    j["books_off"] = nullptr;
    j["books_cost"] = nullptr;
  }
  j["contacts_per_ball"] = cs.ball_contacts_per_ball;
  j["wall_contacts_per_ball"] = cs.wall_contacts_per_ball;
  j["list_entries_per_ball"] = cs.list_entries_per_ball;
  j["rebuild_every_steps"] = number_or_null(rebuilds > 0 ? static_cast<double>(n_steps) / rebuilds : std::nan(""));
  j["device"] = ctx.info().name;
  j["device_type"] = ctx.info().type;
  j["platform"] = ctx.info().platform_name;
  j["compute_units"] = ctx.info().compute_units;
  j["precision"] = c.precision == Precision::double_ ? "double" : "float";
  j["law"] = c.law == ContactLaw::hertz ? "hertz" : "linear";
  j["forces_kernel"] = solver->forces_kernel();
  j["status_every"] = solver->status_every();
  j["dt_s"] = d.dt;
  j["device_bytes"] = bytes;
  j["bytes_per_ball"] = static_cast<double>(bytes) / n;
  j["warmup_steps"] = warmup;
  j["from"] = o.from.empty() ? nlohmann::json() : nlohmann::json(o.from);
  j["tile"] = o.tile > 0 ? nlohmann::json(o.tile) : nlohmann::json();
  j["stage_steps"] = stage_steps;
  j["stage_timed_updates_per_s"] = static_cast<double>(n) * stage_steps / total;
  j["stages"] = {{"binning", st.binning_s / total},
                 {"contacts", st.contacts_s / total},
                 {"forces", st.forces_s / total},
                 {"motion", st.motion_s / total},
                 {"reductions", st.reductions_s / total}};
  std::printf("%s\n", j.dump().c_str());
  return 0;
}

int cmd_view(const ViewOptions& o) {
  Prepared p = prepare(o.c);
  viewer::ViewOptions v;
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
  for (const std::string& e : o.edits) {
    const auto colon = e.find(':');
    char* end = nullptr;
    const long frame = colon == std::string::npos ? -1 : std::strtol(e.c_str(), &end, 10);
    if (colon == std::string::npos || end != e.c_str() + colon || frame < 0 || e.find('=', colon) == std::string::npos)
      throw std::invalid_argument("--edit " + e + ": expected FRAME:KEY=VALUE, e.g. --edit 100:charge.filling=0.35");
    v.edits.emplace_back(frame, e.substr(colon + 1));
  }
  if (!o.screenshot.empty() && o.frames <= 0)
    throw std::invalid_argument("--screenshot needs --frames N (the picture is taken after the last frame)");
  return viewer::run(p.c, p.d, std::move(p.scene), v);
}

}  // namespace mc::app
