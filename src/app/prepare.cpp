#include "app/prepare.h"

#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace mc::app {

namespace fs = std::filesystem;

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

Prepared prepare(const CaseOptions& o, const fs::path& default_path) {
  Prepared p;
  p.path = o.case_path.empty() ? default_path : fs::path(o.case_path);
  // A --duration not longer than the case's own warm-up: the warm-up (unless
  // given with --set) becomes half the run, said once, rather than a refusal
  // that blames a line of the case the user never touched.
  std::vector<std::string> overrides = case_overrides(o);
  bool warmup_set = false;
  for (const std::string& s : o.overrides) warmup_set = warmup_set || s.rfind("run.warmup=", 0) == 0;
  if (!o.duration_auto && o.duration > 0 && !warmup_set) {
    CaseOptions plain = o;
    plain.duration = 0;
    const double warmup = io::read_case(p.path, case_overrides(plain)).warmup;
    if (!(warmup < o.duration)) {
      std::fprintf(stderr,
                   "millcharge: note: --duration %.4g s is not longer than the case's warm-up (run.warmup = %.4g s): "
                   "the warm-up is cut to %.4g s, half the run (--set run.warmup=S to choose another)\n",
                   o.duration, warmup, 0.5 * o.duration);
      std::ostringstream w;
      w.precision(17);
      w << "run.warmup=" << 0.5 * o.duration;
      overrides.push_back(w.str());
    }
  }
  p.c = io::read_case(p.path, overrides);
  p.d = derive(p.c);
  try {
    p.scene = build_scene(p.c, p.d);
  } catch (const std::invalid_argument& e) {
    throw io::CaseError(p.path.string() + ": " + e.what());
  }
  return p;
}

Prepared prepare_from_checkpoint(const fs::path& dir, io::Checkpoint& cp, const std::string& consequence) {
  try {
    cp = io::read_complete_checkpoint(dir / io::kCheckpointFile);
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

std::string watts(double w) {
  char b[48];
  const double a = std::fabs(w);
  if (a >= 1e6) std::snprintf(b, sizeof b, "%.4g MW", w / 1e6);
  else if (a >= 1e3) std::snprintf(b, sizeof b, "%.4g kW", w / 1e3);
  else std::snprintf(b, sizeof b, "%.4g W", w);
  return b;
}

std::string kilograms(double kg) {
  char b[48];
  if (std::fabs(kg) >= 1e3) std::snprintf(b, sizeof b, "%.4g t", kg / 1e3);
  else std::snprintf(b, sizeof b, "%.4g kg", kg);
  return b;
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

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

}  // namespace mc::app
