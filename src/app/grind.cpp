#include "app/grind.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>
#include <toml++/toml.h>

#include "core/mill_case.h"
#include "grind/pbm.h"
#include "io/atomic_file.h"
#include "io/case_file.h"
#include "io/csv_read.h"
#include "io/png_plot.h"
#include "io/toml_names.h"

namespace mc::app {

namespace fs = std::filesystem;
using namespace mc::grind;

namespace {

enum class RateModel { austin, energy, spectrum };

struct Ore {
  std::string name;
  double density = 0;        // kg/m³
  double holdup_kg = 0;      // ore in the mill; or from powder_filling
  double powder_filling = 0; // U: the ball bed's voids the ore fills
  double bed_porosity = 0.4; // of the ore's own bed
  double bulk_density = 0;   // kg/m³ of the packed feed (Bond's 700 cm³), 0: density (1 - bed_porosity)
  SizeSeries sizes;
  std::vector<double> feed;  // class masses
  std::vector<double> sieve_m, sieve_passing;  // the feed as given
  double ratio = 0;
  double f80_m = 0;
  AustinBreakage breakage;
  RateModel model = RateModel::energy;
  AustinRates austin;
  EnergyRates energy;
  Fracture fracture;
  double packing = 0.6, efficiency = 1.0;
  int tanks = 1;
};

// The ore file's tables and keys, with file:line in every message.
class OreReader {
 public:
  OreReader(const toml::table& t, std::string file) : top_(t), file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& key, const toml::node* n, const std::string& what) const {
    std::string where = file_;
    if (n && n->source().begin.line > 0) where += ":" + std::to_string(n->source().begin.line);
    throw std::invalid_argument(where + ": " + key + ": " + what);
  }
  const toml::table* table(const std::string& name, bool required) const {
    const toml::node* n = top_.get(name);
    if (!n) {
      if (required) fail(name, nullptr, "missing table [" + name + "]");
      return nullptr;
    }
    if (!n->is_table()) fail(name, n, "must be a table, not " + io::type_name(*n));
    return n->as_table();
  }
  void knows(const toml::table& t, const std::string& prefix, const std::set<std::string>& keys) const {
    for (const auto& [k, v] : t)
      if (!keys.count(std::string(k.str()))) {
        std::string list;
        for (const auto& x : keys) list += (list.empty() ? "" : ", ") + x;
        fail(prefix + std::string(k.str()), &v, "unknown key (known here: " + list + ")");
      }
  }
  // A number in [lo, hi] (open ends where `open`), or the default when the
  // key is absent and a default is given.
  double number(const toml::table& t, const std::string& prefix, const std::string& key, double lo, double hi,
                const std::string& range, std::optional<double> dflt = std::nullopt) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (dflt) return *dflt;
      fail(prefix + key, nullptr, "missing (" + range + ")");
    }
    if (!n->is_number()) fail(prefix + key, n, "must be a number, not " + io::type_name(*n));
    const double v = n->value<double>().value();
    if (!std::isfinite(v) || v < lo || v > hi) fail(prefix + key, n, fmt::format("{:g} is out of range: {}", v, range));
    return v;
  }
  std::vector<double> numbers(const toml::table& t, const std::string& prefix, const std::string& key) const {
    const toml::node* n = t.get(key);
    if (!n) fail(prefix + key, nullptr, "missing (an array of numbers)");
    if (!n->is_array()) fail(prefix + key, n, "must be an array of numbers, not " + io::type_name(*n));
    std::vector<double> v;
    for (const toml::node& e : *n->as_array()) {
      if (!e.is_number()) fail(prefix + key, &e, "must hold numbers only, not " + io::type_name(e));
      v.push_back(e.value<double>().value());
    }
    if (v.size() < 2) fail(prefix + key, n, "needs at least two values");
    return v;
  }
  const toml::node* node(const toml::table& t, const std::string& key) const { return t.get(key); }

 private:
  const toml::table& top_;
  std::string file_;
};

constexpr double kInf = std::numeric_limits<double>::infinity();

Ore read_ore(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw std::invalid_argument("--ore " + path.string() + ": is a directory, not a file");
  if (!fs::exists(path, ec)) throw std::invalid_argument("--ore " + path.string() + ": no such file");
  toml::table top;
  try {
    top = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}:{}:{}: not valid TOML: {}", path.string(), e.source().begin.line,
                                            e.source().begin.column, e.description()));
  }
  const std::string file = path.string();
  OreReader r(top, file);
  Ore o;
  r.knows(top, "", {"name", "density", "holdup_kg", "powder_filling", "bed_porosity", "bulk_density", "tanks",
                    "sizes", "feed", "breakage", "rates"});
  if (const toml::node* n = top.get("name")) o.name = n->value<std::string>().value_or("");
  o.density = r.number(top, "", "density", 500, 25000, "kg/m^3 of the ore's solid, 500 to 25000");
  const bool has_holdup = top.get("holdup_kg"), has_u = top.get("powder_filling");
  if (has_holdup == has_u)
    r.fail(has_holdup ? "powder_filling" : "holdup_kg", has_u ? top.get("powder_filling") : nullptr,
           "give exactly one of holdup_kg (kg of ore in the mill) and powder_filling (U, the share of the ball "
           "bed's voids the ore fills)");
  if (has_holdup) o.holdup_kg = r.number(top, "", "holdup_kg", 0, kInf, "kg > 0");
  if (o.holdup_kg == 0 && has_holdup) r.fail("holdup_kg", top.get("holdup_kg"), "must be > 0 kg");
  if (has_u) o.powder_filling = r.number(top, "", "powder_filling", 0.01, 3, "0.01 to 3 (1: the voids just full)");
  o.bed_porosity = r.number(top, "", "bed_porosity", 0.2, 0.7, "0.2 to 0.7", 0.4);
  o.bulk_density = r.number(top, "", "bulk_density", 300, 15000, "kg/m^3 of the packed feed, 300 to 15000",
                            o.density * (1 - o.bed_porosity));
  if (o.bulk_density >= o.density)
    r.fail("bulk_density", top.get("bulk_density"), "must be below the solid's density");
  o.tanks = static_cast<int>(r.number(top, "", "tanks", 1, 1000, "1 to 1000 tanks in series", 1));

  const toml::table& sz = *r.table("sizes", true);
  r.knows(sz, "sizes.", {"top_mm", "ratio", "classes"});
  const double top_mm = r.number(sz, "sizes.", "top_mm", 1e-3, 1e3, "mm, 0.001 to 1000");
  const double ratio = r.number(sz, "sizes.", "ratio", 1.05, 4, "1.05 to 4 (sqrt 2 or 2^0.25 are the usual series)",
                                std::sqrt(2.0));
  const double classes = r.number(sz, "sizes.", "classes", 4, 200, "4 to 200");
  if (classes != std::floor(classes)) r.fail("sizes.classes", sz.get("classes"), "must be a whole number");
  o.sizes = geometric_series(top_mm * 1e-3, ratio, static_cast<int>(classes));

  const toml::table& fd = *r.table("feed", true);
  r.knows(fd, "feed.", {"sieve_mm", "passing"});
  const std::vector<double> sieve = r.numbers(fd, "feed.", "sieve_mm");
  const std::vector<double> pass = r.numbers(fd, "feed.", "passing");
  if (sieve.size() != pass.size())
    r.fail("feed.passing", fd.get("passing"),
           fmt::format("holds {} values for {} sieves in feed.sieve_mm", pass.size(), sieve.size()));
  for (std::size_t k = 0; k < sieve.size(); ++k) {
    if (!(sieve[k] > 0)) r.fail("feed.sieve_mm", fd.get("sieve_mm"), "sizes must be > 0 mm");
    if (k > 0 && !(sieve[k] < sieve[k - 1]))
      r.fail("feed.sieve_mm", fd.get("sieve_mm"), "sizes must descend, coarsest first");
    if (!(pass[k] >= 0 && pass[k] <= 1)) r.fail("feed.passing", fd.get("passing"), "each passing must be in 0..1");
    if (k > 0 && pass[k] > pass[k - 1])
      r.fail("feed.passing", fd.get("passing"), "passing must not rise as the sieves get finer");
  }
  if (std::fabs(pass.front() - 1) > 1e-9)
    r.fail("feed.passing", fd.get("passing"),
           fmt::format("the coarsest sieve ({:g} mm) must pass all the feed (1), not {:g}: the feed must sum to 1",
                       sieve.front(), pass.front()));
  if (sieve.front() > top_mm * (1 + 1e-9))
    r.fail("sizes.top_mm", sz.get("top_mm"),
           fmt::format("{:g} mm is below the feed's top size {:g} mm: the size series does not cover the feed", top_mm,
                       sieve.front()));
  std::vector<double> sieve_m;
  for (double s : sieve) sieve_m.push_back(s * 1e-3);
  o.feed = feed_masses(o.sizes, sieve_m, pass);
  o.sieve_m = sieve_m;
  o.sieve_passing = pass;
  o.ratio = ratio;
  o.f80_m = passing_size(o.sizes, o.feed, 0.8);

  const toml::table& bk = *r.table("breakage", true);
  r.knows(bk, "breakage.", {"phi", "gamma", "beta"});
  o.breakage.phi = r.number(bk, "breakage.", "phi", 0, 1, "0 to 1");
  o.breakage.gamma = r.number(bk, "breakage.", "gamma", 0.2, 3, "0.2 to 3");
  o.breakage.beta = r.number(bk, "breakage.", "beta", 1, 10, "1 to 10");

  const toml::table& rt = *r.table("rates", true);
  const toml::node* mn = rt.get("model");
  const std::string model = mn ? mn->value<std::string>().value_or("?") : "";
  if (model == "austin") {
    o.model = RateModel::austin;
    r.knows(rt, "rates.", {"model", "a_per_min", "alpha", "mu_mm", "lambda"});
    o.austin.a_per_min = r.number(rt, "rates.", "a_per_min", 1e-6, 100, "per minute at 1 mm, 1e-6 to 100");
    o.austin.alpha = r.number(rt, "rates.", "alpha", 0.1, 3, "0.1 to 3");
    o.austin.mu_m = r.number(rt, "rates.", "mu_mm", 1e-3, 1e3, "mm, 0.001 to 1000") * 1e-3;
    o.austin.lambda = r.number(rt, "rates.", "lambda", 0.5, 10, "0.5 to 10");
  } else if (model == "energy") {
    o.model = RateModel::energy;
    r.knows(rt, "rates.", {"model", "s1e_t_per_kWh", "x1_mm", "zeta1", "zeta2"});
    o.energy.s1e_t_per_kWh = r.number(rt, "rates.", "s1e_t_per_kWh", 1e-6, 100, "t/kWh, 1e-6 to 100");
    o.energy.x1_m = r.number(rt, "rates.", "x1_mm", 1e-3, 1e3, "mm, 0.001 to 1000") * 1e-3;
    o.energy.zeta1 = r.number(rt, "rates.", "zeta1", -5, 5, "-5 to 5");
    o.energy.zeta2 = r.number(rt, "rates.", "zeta2", -5, 5, "-5 to 5", 0.0);
  } else if (model == "spectrum") {
    o.model = RateModel::spectrum;
    r.knows(rt, "rates.", {"model", "e_inf_J_kg", "d0_mm", "phi", "sigma", "emax_ratio", "packing", "efficiency"});
    o.fracture.e_inf_J_kg = r.number(rt, "rates.", "e_inf_J_kg", 1e-3, 1e5, "J/kg, 0.001 to 1e5");
    o.fracture.d0_m = r.number(rt, "rates.", "d0_mm", 1e-4, 1e3, "mm, 1e-4 to 1000") * 1e-3;
    o.fracture.phi = r.number(rt, "rates.", "phi", 0, 5, "0 to 5");
    o.fracture.sigma = r.number(rt, "rates.", "sigma", 0.05, 3, "0.05 to 3");
    o.fracture.emax_ratio = r.number(rt, "rates.", "emax_ratio", 1.01, 1e3, "1.01 to 1000", 10.0);
    o.packing = r.number(rt, "rates.", "packing", 0.05, 0.91, "0.05 to 0.91 (areal packing of the monolayer)", 0.6);
    o.efficiency = r.number(rt, "rates.", "efficiency", 1e-4, 1, "1e-4 to 1", 1.0);
  } else {
    r.fail("rates.model", mn, "must be \"austin\", \"energy\" or \"spectrum\"" +
                                  (mn ? std::string(", not \"") + model + "\"" : std::string(" (missing)")));
  }
  return o;
}

struct Run {
  double speed_rpm = 0;
  double power_W = 0, filling = 0, mill_volume = 0, porosity = 0.4, ball_radius_m = 0;
  std::vector<SpectrumBin> normal;  // the normal energy spectrum
  std::string title;
};

Run read_run(const fs::path& dir, bool need_spectrum) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw std::invalid_argument(dir.string() + ": not a run folder");
  const fs::path sj = dir / "summary.json";
  if (!fs::exists(sj, ec))
    throw std::invalid_argument(sj.string() + ": missing; grind needs a finished run (millcharge run)");
  nlohmann::json j;
  try {
    std::ifstream in(sj);
    j = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw std::invalid_argument(sj.string() + ": not valid JSON: " + e.what());
  }
  Run r;
  try {
    r.power_W = j.at("power_W").at("torque").get<double>();
    r.filling = j.at("filling").get<double>();
    r.title = j.value("title", std::string());
    r.speed_rpm = j.value("speed_rpm", 0.0);
  } catch (const std::exception&) {
    throw std::invalid_argument(sj.string() + ": power_W.torque or filling missing; not a millcharge run's summary");
  }
  if (!(r.power_W > 0)) throw std::invalid_argument(sj.string() + ": power_W.torque is not > 0: the mill drew no power");
  const MillCase c = io::read_case(dir / "case.toml");
  const MillDerived d = derive(c);
  r.mill_volume = d.mill_volume;
  r.porosity = c.porosity;
  double n = 0, sum_r = 0;
  for (std::size_t k = 0; k < c.sizes.size(); ++k) {
    n += d.class_counts[k];
    sum_r += d.class_counts[k] * 0.25 * (c.sizes[k].diameter_min + c.sizes[k].diameter_max);
  }
  r.ball_radius_m = n > 0 ? sum_r / n : 0;
  if (!need_spectrum) return r;
  const fs::path sc = dir / "spectra.csv";
  const io::CsvTable t = io::read_csv_strict(sc, "the spectrum model needs the run's collision spectra");
  const std::string older = "the run is from an older millcharge; run it again";
  if (!t.has("normal_spectrum_collisions_per_s") || !t.has("normal_spectrum_W") || !t.has("pair"))
    throw std::invalid_argument(sc.string() +
                                ": has no normal energy spectrum (columns normal_spectrum_collisions_per_s, "
                                "normal_spectrum_W): " + older);
  const int c_pair = t.column("pair"), c_bin = t.column("bin"), c_n = t.column("normal_spectrum_collisions_per_s"),
            c_w = t.column("normal_spectrum_W");
  const int c_all = t.has("collisions_per_s") ? t.column("collisions_per_s") : -1;
  // Each pair's bins 0, 1, ... in order, every pair with as many: a file
  // cut at a line's end, or with rows lost, is refused by its line.
  std::vector<std::string> pairs;
  std::vector<double> pair_collisions;
  long bins = -1, bin = 0;
  for (std::size_t k = 0; k < t.rows.size(); ++k) {
    const std::string& pair = t.rows[k][c_pair];
    if (pairs.empty() || pair != pairs.back()) {
      if (!pairs.empty() && bins < 0) bins = bin;
      if (!pairs.empty() && bin != bins)
        throw std::invalid_argument(fmt::format("{}: pair {} has {} bins, the first pair {}; the file is damaged",
                                                t.where(k - 1), pairs.back(), bin, bins));
      if (std::find(pairs.begin(), pairs.end(), pair) != pairs.end())
        throw std::invalid_argument(t.where(k) + ": pair " + pair + " again after other pairs; the file is damaged");
      pairs.push_back(pair);
      pair_collisions.push_back(0);
      bin = 0;
    }
    if (t.number(k, c_bin) != bin)
      throw std::invalid_argument(fmt::format("{}: bin {} of pair {} where bin {} was due; the file is damaged",
                                              t.where(k), t.rows[k][c_bin], pair, bin));
    ++bin;
    if (c_all >= 0) pair_collisions.back() += t.number(k, c_all);
  }
  if (pairs.empty()) throw std::invalid_argument(sc.string() + ": no rows; the file is damaged");
  if (bins >= 0 && bin != bins)
    throw std::invalid_argument(fmt::format("{}: pair {} has {} bins, the first pair {}: the file was cut short",
                                            t.where(t.rows.size() - 1), pairs.back(), bin, bins));
  // The pairs and their collision rates are those summary.json gives.
  if (j.contains("spectra") && j["spectra"].is_object() && j["spectra"].contains("by_pair") && c_all >= 0) {
    const auto& by_pair = j["spectra"]["by_pair"];
    std::vector<std::string> want;
    for (const auto& q : by_pair)
      if (q.is_object() && q.contains("pair") && q["pair"].is_string()) want.push_back(q["pair"].get<std::string>());
    if (want != pairs) {
      std::string a, b;
      for (const std::string& x : want) a += (a.empty() ? "" : ", ") + x;
      for (const std::string& x : pairs) b += (b.empty() ? "" : ", ") + x;
      throw std::invalid_argument(sc.string() + ": holds the pairs " + b + ", summary.json " + a +
                                  "; the file is damaged or from another run");
    }
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const double rate = by_pair[k].value("collisions_per_s", std::nan(""));
      if (std::isfinite(rate) && std::fabs(pair_collisions[k] - rate) > 1e-5 * std::max(rate, 1.0))
        throw std::invalid_argument(fmt::format(
            "{}: pair {} sums to {:.6g} collisions/s, summary.json gives {:.6g}; the file is damaged or from "
            "another run",
            sc.string(), pairs[k], pair_collisions[k], rate));
    }
  }
  double all_collisions = 0, normal_collisions = 0;
  for (std::size_t k = 0; k < t.rows.size(); ++k) {
    if (c_all >= 0) all_collisions += t.number(k, c_all);
    SpectrumBin b;
    b.collisions_per_s = t.number(k, c_n);
    normal_collisions += b.collisions_per_s;
    const double w = t.number(k, c_w);
    if (b.collisions_per_s <= 0 || w <= 0) continue;
    b.energy_J = w / b.collisions_per_s;
    const std::string& pair = t.rows[k][c_pair];
    auto ends = [&](const std::string& tail) {
      return pair.size() > tail.size() && pair.compare(pair.size() - tail.size(), tail.size(), tail) == 0;
    };
    const bool wall = ends("-shell") || ends("-lifter") || ends("-end plate") || ends("-ends");
    // Equal balls meet with half a radius; a ball meets a wall with its own.
    b.r_eff_m = wall ? r.ball_radius_m : 0.5 * r.ball_radius_m;
    r.normal.push_back(b);
  }
  if (c_all >= 0 && all_collisions > 0 && std::fabs(normal_collisions - all_collisions) > 0.01 * all_collisions)
    throw std::invalid_argument(fmt::format(
        "{}: the normal energy spectrum holds {:.1f} % of the collisions (a run resumed from an older millcharge's "
        "checkpoint); run it again",
        sc.string(), 100 * normal_collisions / all_collisions));
  if (r.normal.empty()) throw std::invalid_argument(sc.string() + ": no collisions in the normal energy spectrum");
  return r;
}

// The part of m finer than x (the class that x cuts, in log proportion).
std::vector<double> part_below(const SizeSeries& s, const std::vector<double>& m, double x) {
  std::vector<double> u(m.size(), 0.0);
  const int n = s.size();
  for (int i = 0; i < n; ++i) {
    const double hi = s.top_m[i], lo = i + 1 < n ? s.top_m[i + 1] : 0.0;
    if (hi <= x) u[i] = m[i];
    else if (lo < x) u[i] = m[i] * (lo > 0 ? std::log(x / lo) / std::log(hi / lo) : 1.0);
  }
  return u;
}

double mass_below(const SizeSeries& s, const std::vector<double>& m, double x) {
  double below = 0;
  for (double v : part_below(s, m, x)) below += v;
  return below;
}

// Bond's locked-cycle test (F. C. Bond 1961, the standard procedure): 700
// cm³ of feed, ground, screened at P1; the undersize replaced by fresh
// feed; the revolutions of each cycle set so that the undersize is 1/3.5
// of the charge (a circulating load of 250 %); Gbp the net grams of
// undersize made per revolution, over the last three cycles once they
// agree within 3 % with the load within 3 % of 250 %.
struct BondResult {
  double p1_um = 0, gbp_g_rev = 0, p80_um = 0, f80_um = 0, wi_kWh_t = 0, charge_g = 0, circulating_load = 0;
  int cycles = 0;
  bool steady = false;
  std::vector<double> gbp_by_cycle, revs_by_cycle;
};

BondResult bond_test(const SizeSeries& s, const std::vector<double>& feed, const std::vector<double>& S_per_min,
                     const std::vector<std::vector<double>>& b, double rpm, double charge_kg, double p1_m) {
  BondResult r;
  r.p1_um = p1_m * 1e6;
  r.charge_g = charge_kg * 1000;
  const double fresh_fines = mass_below(s, feed, p1_m);  // fraction of fresh feed already below P1
  std::vector<double> m(feed.size());
  for (std::size_t i = 0; i < m.size(); ++i) m[i] = feed[i] * r.charge_g;  // grams
  double revs = 100;
  std::vector<double> product;
  for (int c = 1; c <= 30; ++c) {
    const double fines_in = mass_below(s, m, p1_m);
    m = batch_grind(m, S_per_min, b, revs / rpm);
    const std::vector<double> under = part_below(s, m, p1_m);
    double u = 0;
    for (double x : under) u += x;
    const double gbp = (u - fines_in) / revs;
    r.gbp_by_cycle.push_back(gbp);
    r.revs_by_cycle.push_back(revs);
    product = under;
    // Replace the undersize by fresh feed of the same mass.
    for (std::size_t i = 0; i < m.size(); ++i) m[i] += -under[i] + feed[i] * u;
    r.cycles = c;
    const std::size_t k = r.gbp_by_cycle.size();
    if (c >= 6) {
      const double g0 = r.gbp_by_cycle[k - 3], g1 = r.gbp_by_cycle[k - 2], g2 = r.gbp_by_cycle[k - 1];
      const double hi = std::max({g0, g1, g2}), lo = std::min({g0, g1, g2});
      const double cl = (r.charge_g - u) / u;
      if (lo > 0 && (hi - lo) / hi < 0.03 && std::fabs(cl - 2.5) < 0.075) {
        r.steady = true;
        r.gbp_g_rev = (g0 + g1 + g2) / 3;
        r.circulating_load = cl;
        break;
      }
    }
    // Next cycle: undersize made to 1/3.5 of the charge.
    const double target = r.charge_g / 3.5 - fresh_fines * u;
    revs = gbp > 0 ? std::clamp(target / gbp, 10.0, 5000.0) : 5000.0;
  }
  if (!r.steady) {
    r.gbp_g_rev = r.gbp_by_cycle.back();
    double u = 0;
    for (double x : product) u += x;
    r.circulating_load = (r.charge_g - u) / u;
  }
  r.p80_um = passing_size(s, product, 0.8) * 1e6;
  r.f80_um = passing_size(s, feed, 0.8) * 1e6;
  // Bond's formula, in kWh per metric tonne (1.1 x the short-ton form).
  r.wi_kWh_t = 1.1 * 44.5 /
               (std::pow(r.p1_um, 0.23) * std::pow(r.gbp_g_rev, 0.82) *
                (10 / std::sqrt(r.p80_um) - 10 / std::sqrt(r.f80_um)));
  return r;
}

std::string fmt_um(double m) { return std::isfinite(m) ? fmt::format("{:.1f}", m * 1e6) : "below the finest class"; }

}  // namespace

int cmd_grind(const GrindOptions& o) {
  Ore ore = read_ore(o.ore);
  if (o.bond_p1_um > 0) {
    // Bond's test screens at P1: the series is moved up to put P1 on a
    // class top (it still covers the feed; the classes keep their count).
    const double p1 = o.bond_p1_um * 1e-6, top = ore.sizes.top_m.front();
    const double k = std::ceil(std::log(top / p1) / std::log(ore.ratio) - 1e-9);
    ore.sizes = geometric_series(p1 * std::pow(ore.ratio, k), ore.ratio, ore.sizes.size());
    ore.feed = feed_masses(ore.sizes, ore.sieve_m, ore.sieve_passing);
  }
  if (o.classifier_d50c_um > 0) {
    if (!(o.feed_rate_t_h > 0) && !(o.target_p80_um > 0))
      throw std::invalid_argument(fmt::format(
          "--classifier {:g}: closes a continuous mill; give --feed-rate or --target-p80 with it", o.classifier_d50c_um));
    const double d = o.classifier_d50c_um * 1e-6;
    if (!(d > ore.sizes.top_m.back() && d < ore.sizes.top_m.front()))
      throw std::invalid_argument(fmt::format("--classifier {:g}: the cut size must lie inside the size classes ({:.1f} "
                                              "to {:.0f} um)",
                                              o.classifier_d50c_um, ore.sizes.top_m.back() * 1e6,
                                              ore.sizes.top_m.front() * 1e6));
  } else if (o.classifier_alpha != 3 || o.classifier_bypass != 0) {
    throw std::invalid_argument("--sharpness and --bypass describe the classifier: give --classifier D50C_UM with them");
  }
  const Run run = read_run(o.run_dir, ore.model == RateModel::spectrum);
  const int tanks = o.tanks > 0 ? o.tanks : ore.tanks;
  // The ore in the mill.
  // In Bond's test the mill holds 700 cm³ of packed feed.
  const double bond_charge_kg = 700e-6 * ore.bulk_density;
  if (o.bond_p1_um > 0) {
    if (!(o.bond_p1_um * 1e-6 < ore.f80_m))
      throw std::invalid_argument(fmt::format("--bond {:g}: the closing sieve must lie below the feed's F80 ({} um)",
                                              o.bond_p1_um, fmt_um(ore.f80_m)));
    if (o.bond_p1_um * 1e-6 < ore.sizes.top_m.back())
      throw std::invalid_argument(fmt::format("--bond {:g}: below the finest class top ({:.1f} um): more sizes.classes",
                                              o.bond_p1_um, ore.sizes.top_m.back() * 1e6));
    if (!(run.speed_rpm > 0)) throw std::invalid_argument(o.run_dir + "/summary.json: speed_rpm missing");
  }
  const double holdup_kg = o.bond_p1_um > 0  ? bond_charge_kg
                           : ore.holdup_kg > 0 ? ore.holdup_kg
                                             : ore.powder_filling * run.porosity * run.filling * run.mill_volume *
                                                   ore.density * (1 - ore.bed_porosity);
  const SizeSeries& s = ore.sizes;
  const int n = s.size();
  // Rates per minute.
  std::vector<double> S(n, 0.0), SE(n, 0.0);
  const double power_kW = run.power_W / 1000, holdup_t = holdup_kg / 1000;
  if (ore.model == RateModel::austin) S = austin_rates(s, ore.austin);
  if (ore.model == RateModel::energy) {
    SE = energy_specific_rates(s, ore.energy);
    for (int i = 0; i < n; ++i) S[i] = SE[i] * power_kW / holdup_t / 60;
  }
  if (ore.model == RateModel::spectrum) {
    S = spectrum_rates(s, run.normal, ore.fracture, ore.density, ore.packing, ore.efficiency, holdup_kg);
    for (double& x : S) x *= 60;
  }
  if (ore.model != RateModel::energy)
    for (int i = 0; i < n; ++i) SE[i] = S[i] * 60 * holdup_t / power_kW;
  S[n - 1] = SE[n - 1] = 0;
  const auto b = breakage_matrix(s, ore.breakage);

  const std::vector<double> times = o.times_min.empty() && !(o.feed_rate_t_h > 0) && !(o.target_p80_um > 0) &&
                                            !(o.bond_p1_um > 0)
                                        ? std::vector<double>{1, 2, 4, 8, 16}
                                        : o.times_min;
  struct Product {
    std::string label;
    double t_min = 0, feed_t_h = 0, kWh_t = 0, p80_m = 0;
    double circulating_load = -1;  // a closed circuit's; < 0: open
    bool converged = true;
    std::vector<double> m;
  };
  std::vector<Product> products;
  for (double t : times) {
    Product p;
    p.label = fmt::format("batch {:g} min", t);
    p.t_min = t;
    p.m = batch_grind(ore.feed, S, b, t);
    p.kWh_t = power_kW * t / 60 / holdup_t;
    p.p80_m = passing_size(s, p.m, 0.8);
    products.push_back(p);
  }
  const bool closed = o.classifier_d50c_um > 0;
  WhitenClassifier classifier;
  classifier.d50c_m = o.classifier_d50c_um * 1e-6;
  classifier.alpha = o.classifier_alpha;
  classifier.bypass = o.classifier_bypass;
  auto continuous = [&](double feed_t_h) {
    Product p;
    p.feed_t_h = feed_t_h;
    if (closed) {
      std::vector<double> fresh(ore.feed);
      for (double& f : fresh) f *= feed_t_h;
      const ClosedCircuit cc = closed_circuit(s, fresh, S, b, holdup_t, tanks, classifier);
      p.m = cc.product;
      for (double& m : p.m) m /= feed_t_h;
      p.t_min = cc.residence_min;
      p.circulating_load = cc.circulating_load;
      p.converged = cc.converged;
      p.label = fmt::format("closed circuit {:.4g} t/h", feed_t_h);
    } else {
      p.t_min = holdup_t / feed_t_h * 60;  // mean residence time
      p.m = continuous_grind(ore.feed, S, b, p.t_min, tanks);
      p.label = fmt::format("continuous {:.4g} t/h", feed_t_h);
    }
    p.kWh_t = power_kW / feed_t_h;
    p.p80_m = passing_size(s, p.m, 0.8);
    return p;
  };
  if (o.feed_rate_t_h > 0) products.push_back(continuous(o.feed_rate_t_h));
  double target_rate = std::numeric_limits<double>::quiet_NaN();
  if (o.target_p80_um > 0) {
    const double target = o.target_p80_um * 1e-6;
    if (!(target < ore.f80_m))
      throw std::invalid_argument(fmt::format("--target-p80 {:g}: not below the feed's F80 of {} um", o.target_p80_um,
                                              fmt_um(ore.f80_m)));
    // The finest class's top is the finest P80 the series resolves.
    const double finest = s.top_m.back();
    if (!(target > finest))
      throw std::invalid_argument(fmt::format(
          "--target-p80 {:g}: finer than the ore's finest size class (top {} um), so no product can be shown to "
          "meet it; give a target above {} um, or an ore file whose size series reaches finer",
          o.target_p80_um, fmt_um(finest), fmt_um(finest)));
    // P80 rises with the feed rate: bisect its logarithm between the rates
    // the solver brackets.
    constexpr double kSlowest = 1e-9, kFastest = 1e6;  // t/h
    double lo = kSlowest, hi = kFastest;
    auto p80 = [&](double f) {
      const double x = continuous(f).p80_m;
      return std::isfinite(x) ? x : 0.0;
    };
    const double p80_slowest = p80(lo), p80_fastest = p80(hi);
    if (!(p80_slowest < target))
      throw std::invalid_argument(fmt::format(
          "--target-p80 {:g}: not reached: even fed at {:g} t/h the mill's product has P80 {} um", o.target_p80_um,
          kSlowest, fmt_um(p80_slowest)));
    if (!(p80_fastest > target))
      throw std::invalid_argument(fmt::format(
          "--target-p80 {:g}: not reached: even fed at {:g} t/h the mill's product has P80 {} um, finer than the "
          "target",
          o.target_p80_um, kFastest, fmt_um(p80_fastest)));
    for (int k = 0; k < 200 && hi / lo > 1 + 1e-10; ++k) {
      const double mid = std::sqrt(lo * hi);
      (p80(mid) < target ? lo : hi) = mid;
    }
    target_rate = std::sqrt(lo * hi);
    Product p = continuous(target_rate);
    // The bisection assumes P80 rises with the rate; a circuit where it
    // does not (or a step in P80) leaves a product off the target: said,
    // never shown as the answer.
    if (!(std::fabs(p.p80_m - target) <= 0.01 * target))
      throw std::invalid_argument(fmt::format(
          "--target-p80 {:g}: not reached: the closest product found, fed at {:.4g} t/h, has P80 {} um (P80 does "
          "not rise smoothly with the feed rate here)",
          o.target_p80_um, target_rate, fmt_um(p.p80_m)));
    p.label = fmt::format("{} at P80 {:g} um", closed ? "closed circuit" : "continuous", o.target_p80_um);
    products.push_back(p);
  }

  BondResult bond;
  if (o.bond_p1_um > 0) bond = bond_test(s, ore.feed, S, b, run.speed_rpm, bond_charge_kg, o.bond_p1_um * 1e-6);

  // Everything computed; now the files.
  const fs::path out = o.out.empty() ? fs::path(o.run_dir) / "grind" : fs::path(o.out);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw std::runtime_error(out.string() + ": cannot create: " + ec.message());

  std::string csv = "size_um,feed_passing";
  for (const Product& p : products) csv += "," + fmt::format("\"{}\"", p.label);
  csv += "\n";
  const std::vector<double> fp = passing(ore.feed);
  std::vector<std::vector<double>> pp;
  for (const Product& p : products) pp.push_back(passing(p.m));
  for (int i = 0; i < n; ++i) {
    csv += fmt::format("{:.6g},{:.8g}", s.top_m[i] * 1e6, fp[i]);
    for (const auto& q : pp) csv += fmt::format(",{:.8g}", q[i]);
    csv += "\n";
  }
  io::write_file_atomic(out / "grind.csv", csv);
  std::string rates = "class,top_um,mid_um,S_per_min,SE_t_per_kWh\n";
  for (int i = 0; i < n; ++i)
    rates += fmt::format("{},{:.6g},{:.6g},{:.8g},{:.8g}\n", i, s.top_m[i] * 1e6, s.mid_m(i) * 1e6, S[i], SE[i]);
  io::write_file_atomic(out / "rates.csv", rates);

  nlohmann::ordered_json j;
  j["ore"] = ore.name;
  j["run"] = run.title;
  j["model"] = ore.model == RateModel::austin ? "austin" : ore.model == RateModel::energy ? "energy" : "spectrum";
  j["power_W"] = run.power_W;
  j["holdup_kg"] = holdup_kg;
  j["mean_ball_diameter_mm"] = 2e3 * run.ball_radius_m;
  j["tanks"] = tanks;
  if (closed)
    j["classifier"] = {{"model", "whiten"},
                       {"d50c_um", o.classifier_d50c_um},
                       {"sharpness", o.classifier_alpha},
                       {"bypass", o.classifier_bypass}};
  j["F80_um"] = std::isfinite(ore.f80_m) ? nlohmann::json(ore.f80_m * 1e6) : nlohmann::json();
  j["products"] = nlohmann::json::array();
  for (const Product& p : products) {
    nlohmann::ordered_json q;
    q["label"] = p.label;
    q["time_min"] = p.t_min;
    if (p.feed_t_h > 0) q["feed_rate_t_h"] = p.feed_t_h;
    q["specific_energy_kWh_t"] = p.kWh_t;
    if (p.circulating_load >= 0) {
      q["circulating_load"] = p.circulating_load;
      q["steady"] = p.converged;
    }
    q["P80_um"] = std::isfinite(p.p80_m) ? nlohmann::json(p.p80_m * 1e6) : nlohmann::json();
    j["products"].push_back(q);
  }
  if (o.target_p80_um > 0)
    j["throughput_at_target_t_h"] = std::isfinite(target_rate) ? nlohmann::json(target_rate) : nlohmann::json();
  if (o.bond_p1_um > 0) {
    nlohmann::ordered_json q;
    q["P1_um"] = bond.p1_um;
    q["charge_g"] = bond.charge_g;
    q["cycles"] = bond.cycles;
    q["steady"] = bond.steady;
    q["Gbp_g_per_rev"] = bond.gbp_g_rev;
    q["circulating_load"] = bond.circulating_load;
    q["F80_um"] = bond.f80_um;
    q["P80_um"] = bond.p80_um;
    q["work_index_kWh_t"] = bond.wi_kWh_t;
    q["revolutions_by_cycle"] = bond.revs_by_cycle;
    q["Gbp_by_cycle"] = bond.gbp_by_cycle;
    j["bond"] = q;
  }
  io::write_file_atomic(out / "grind.json", j.dump(2) + "\n");

  static const std::uint32_t colours[] = {0x1f77b4, 0xd62728, 0x2ca02c, 0xff7f0e, 0x9467bd, 0x8c564b, 0xe377c2, 0x17becf};
  io::LinePlot psd, rp;
  psd.title = (ore.name.empty() ? std::string("ore") : ore.name) + ": product size, " + j["model"].get<std::string>() +
              " rates, " + fmt::format("{:.0f} W", run.power_W);
  psd.x_label = "size (um)";
  psd.y_label = "cumulative passing";
  psd.log_x = rp.log_x = true;
  io::PlotSeries fs_{"feed", {}, {}, 0x222222};
  for (int i = 0; i < n; ++i) fs_.x.push_back(s.top_m[i] * 1e6), fs_.y.push_back(fp[i]);
  fs_.dashed = true;
  psd.series.push_back(fs_);
  for (std::size_t k = 0; k < products.size(); ++k) {
    io::PlotSeries q{products[k].label, {}, {}, colours[k % 8]};
    for (int i = 0; i < n; ++i) q.x.push_back(s.top_m[i] * 1e6), q.y.push_back(pp[k][i]);
    psd.series.push_back(q);
  }
  rp.title = "specific breakage rate of each class";
  rp.x_label = "size (um, class's geometric mean)";
  rp.y_label = "S (1/min)";
  io::PlotSeries rs{"S_i", {}, {}, 0x1f77b4};
  rs.markers = true;
  for (int i = 0; i + 1 < n; ++i) rs.x.push_back(s.mid_m(i) * 1e6), rs.y.push_back(S[i]);
  rp.series.push_back(rs);
  io::draw_or_warn(out / "grind.png", [&] { io::write_line_plots_png(out / "grind.png", {psd, rp}); });

  if (!o.quiet) {
    std::printf("ore %s, %s rates; mill power %.1f W, hold-up %.3g kg, F80 %s um\n", ore.name.c_str(),
                j["model"].get<std::string>().c_str(), run.power_W, holdup_kg, fmt_um(ore.f80_m).c_str());
    for (const Product& p : products)
      std::printf("  %-28s %s %8.3g kWh/t  P80 %s um%s\n", p.label.c_str(),
                  p.feed_t_h > 0 ? fmt::format("{:9.4g} t/h", p.feed_t_h).c_str() : "             ", p.kWh_t,
                  fmt_um(p.p80_m).c_str(),
                  p.circulating_load >= 0
                      ? fmt::format("  circulating load {:.0f} %{}", 100 * p.circulating_load,
                                    p.converged ? "" : " (not steady)")
                            .c_str()
                      : "");
    if (o.bond_p1_um > 0)
      std::printf("  Bond test at P1 %g um: %d cycles%s, Gbp %.3f g/rev, CL %.0f %%, F80 %.0f um, P80 %.0f um, Wi %.2f "
                  "kWh/t\n",
                  bond.p1_um, bond.cycles, bond.steady ? "" : " (not steady)", bond.gbp_g_rev,
                  100 * bond.circulating_load, bond.f80_um, bond.p80_um, bond.wi_kWh_t);
    std::printf("wrote %s/{grind.csv, rates.csv, grind.json, grind.png}\n", out.string().c_str());
  }
  return 0;
}

}  // namespace mc::app
