// `millcharge grind`: reads the ore file and the run folder (src/io), runs
// the population balance on them (src/grind) and writes what the mill
// makes: grind.csv, rates.csv, grind.json and grind.png.
#include "app/grind.h"
#include "app/grind_interval.h"
#include "app/grind_next.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "grind/bond.h"
#include "grind/circuit.h"
#include "grind/fit.h"
#include "grind/sieve_errors.h"
#include "grind/ore.h"
#include "grind/pbm.h"
#include "core/version.h"
#include "io/atomic_file.h"
#include "io/ore_file.h"
#include "io/png_plot.h"
#include "io/run_folder.h"

namespace mc::app {

namespace fs = std::filesystem;
using namespace mc::grind;

namespace {

// Torque and dissipation further apart than this share of the torque: the
// run is not in steady motion (grind warns).
constexpr double kImbalanceWarn = 0.10;

std::string fmt_um(double m) { return std::isfinite(m) ? fmt::format("{:.1f}", m * 1e6) : "below the finest class"; }

const char* model_name(RateModel m) {
  return m == RateModel::austin ? "austin" : m == RateModel::energy ? "energy" : "spectrum";
}

void check_classifier(const GrindOptions& o, const Ore& ore) {
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
}

// `bond_ore`: the ore with its series moved onto P1.
void check_bond(const GrindOptions& o, const Ore& bond_ore, const io::Run& run) {
  if (!(o.bond_p1_um * 1e-6 < bond_ore.f80_m))
    throw std::invalid_argument(fmt::format("--bond {:g}: the closing sieve must lie below the feed's F80 ({} um)",
                                            o.bond_p1_um, fmt_um(bond_ore.f80_m)));
  check_bond_sieve(bond_ore.sizes, o.bond_p1_um * 1e-6);
  if (!(run.speed_rpm > 0)) throw std::invalid_argument(o.run_dir + "/summary.json: speed_rpm missing");
}

// Bond's test of the ore in its own mill: 700 cm³ of feed as the hold-up,
// on the series moved onto P1; the run's other products keep the run's
// hold-up and the ore's own series.
BondResult run_bond(const GrindOptions& o, const Ore& bond_ore, const io::Run& run) {
  const double charge = bond_charge_kg(bond_ore);
  const MillRates r = mill_rates(bond_ore, run.spectrum, run.power_W, charge);
  const auto b = appearance_matrix(bond_ore, run.spectrum);
  const BondResult bond =
      bond_test(bond_ore.sizes, bond_ore.feed, r.S_per_min, b, run.speed_rpm, charge, o.bond_p1_um * 1e-6);
  if (!bond.steady)
    throw std::invalid_argument(fmt::format(
        "--bond {:g}: no work index: Bond's test did not reach its equilibrium in {} cycles (circulating load {:.0f} "
        "%, not 250 %: the revolutions a cycle needs lie outside the test's 10 to 5000); the ore grinds too slowly "
        "or too fast in this mill for the test",
        o.bond_p1_um, bond.cycles, 100 * bond.circulating_load));
  if (!std::isfinite(bond.wi_kWh_t) || !(bond.wi_kWh_t > 0))
    throw std::invalid_argument(fmt::format(
        "--bond {:g}: no work index: the test's product has P80 {} um and Gbp {:.4g} g/rev (more sizes.classes "
        "below P1, or a faster ore)",
        o.bond_p1_um, std::isfinite(bond.p80_um) ? fmt::format("{:.1f}", bond.p80_um) : "below the finest class",
        bond.gbp_g_rev));
  return bond;
}

Product continuous(const Circuit& c, double feed_t_h) {
  Product p = continuous_product(c, feed_t_h);
  p.label = c.closed ? fmt::format("closed circuit {:.4g} t/h", feed_t_h)
                     : fmt::format("continuous {:.4g} t/h", feed_t_h);
  return p;
}

// The product at --target-p80, and the feed rate that makes it.
// `lenient` (an ore moved for the intervals): a target that no feed rate
// reaches gives the throughput past any bound, -inf (the ore too hard:
// coarser even fed slowest) or +inf (too soft: finer even fed fastest),
// which opens that end of its interval.
Product at_target(const GrindOptions& o, const Ore& ore, const Circuit& c, double& rate_t_h, bool lenient = false) {
  const double target = o.target_p80_um * 1e-6;
  if (!(target < ore.f80_m))
    throw std::invalid_argument(fmt::format("--target-p80 {:g}: not below the feed's F80 of {} um", o.target_p80_um,
                                            fmt_um(ore.f80_m)));
  // The finest class's top is the finest P80 the series resolves.
  const double finest = c.sizes.top_m.back();
  if (!(target > finest))
    throw std::invalid_argument(fmt::format(
        "--target-p80 {:g}: finer than the ore's finest size class (top {} um), so no product can be shown to "
        "meet it; give a target above {} um, or an ore file whose size series reaches finer",
        o.target_p80_um, fmt_um(finest), fmt_um(finest)));
  const TargetFeed f = feed_rate_for_p80(c, target);
  if (lenient && (f.outcome == TargetFeed::Outcome::coarse_when_slowest ||
                  f.outcome == TargetFeed::Outcome::fine_when_fastest)) {
    const double inf = std::numeric_limits<double>::infinity();
    const bool hard = f.outcome == TargetFeed::Outcome::coarse_when_slowest;
    Product p;
    p.feed_t_h = rate_t_h = hard ? -inf : inf;
    p.kWh_t = hard ? inf : -inf;
    p.p80_m = target;
    p.m.assign(c.feed.size(), std::numeric_limits<double>::quiet_NaN());
    return p;
  }
  if (f.outcome == TargetFeed::Outcome::coarse_when_slowest)
    throw std::invalid_argument(fmt::format(
        "--target-p80 {:g}: not reached: even fed at {:g} t/h the mill's product has P80 {} um", o.target_p80_um,
        kSlowestFeed_t_h, fmt_um(f.p80_slowest_m)));
  if (f.outcome == TargetFeed::Outcome::fine_when_fastest)
    throw std::invalid_argument(fmt::format(
        "--target-p80 {:g}: not reached: even fed at {:g} t/h the mill's product has P80 {} um, finer than the "
        "target",
        o.target_p80_um, kFastestFeed_t_h, fmt_um(f.p80_fastest_m)));
  if (f.outcome == TargetFeed::Outcome::missed)
    throw std::invalid_argument(fmt::format(
        "--target-p80 {:g}: not reached: the closest product found, fed at {:.4g} t/h, has P80 {} um (P80 does "
        "not rise smoothly with the feed rate here)",
        o.target_p80_um, f.rate_t_h, fmt_um(f.product.p80_m)));
  rate_t_h = f.rate_t_h;
  Product p = f.product;
  p.label = fmt::format("{} at P80 {:g} um", c.closed ? "closed circuit" : "continuous", o.target_p80_um);
  return p;
}

// grind.csv (each product's cumulative passing at the class tops) and
// rates.csv.
// With intervals, each product's column is followed by its 95 % interval's
// lower and upper ends.
void write_tables(const fs::path& out, const Circuit& c, const std::vector<Product>& products,
                  const std::vector<double>& SE, const GrindIntervals& ci) {
  const SizeSeries& s = c.sizes;
  const int n = s.size();
  std::string csv = "size_um,feed_passing";
  for (const Product& p : products) {
    csv += "," + fmt::format("\"{}\"", p.label);
    if (ci.given) csv += fmt::format(",\"{} lower 95\",\"{} upper 95\"", p.label, p.label);
  }
  csv += "\n";
  const std::vector<double> fp = passing(c.feed);
  std::vector<std::vector<double>> pp;
  for (const Product& p : products) pp.push_back(passing(p.m));
  for (int i = 0; i < n; ++i) {
    csv += fmt::format("{:.6g},{:.8g}", s.top_m[i] * 1e6, fp[i]);
    for (std::size_t k = 0; k < pp.size(); ++k) {
      csv += fmt::format(",{:.8g}", pp[k][i]);
      if (ci.given) {
        const Interval& iv = ci.products[k].passing[i];
        csv += iv.valid() ? fmt::format(",{:.8g},{:.8g}", std::max(iv.lo, 0.0), std::min(iv.hi, 1.0)) : ",,";
      }
    }
    csv += "\n";
  }
  io::write_file_atomic(out / "grind.csv", csv);
  const bool t10 = !c.t10_mean.empty();
  std::string rates = std::string("class,top_um,mid_um,S_per_min,SE_t_per_kWh") + (t10 ? ",t10\n" : "\n");
  for (int i = 0; i < n; ++i)
    rates += fmt::format("{},{:.6g},{:.6g},{:.8g},{:.8g}", i, s.top_m[i] * 1e6, s.mid_m(i) * 1e6, c.S_per_min[i],
                         SE[i]) +
             (t10 ? fmt::format(",{:.8g}\n", c.t10_mean[i]) : std::string("\n"));
  io::write_file_atomic(out / "rates.csv", rates);
}

nlohmann::ordered_json summary(const GrindOptions& o, const Ore& ore, const io::Run& run, const Circuit& c,
                               double holdup_kg, const std::vector<Product>& products, double target_rate,
                               const BondResult& bond) {
  nlohmann::ordered_json j;
  j["ore"] = ore.name;
  j["run"] = run.title;
  j["model"] = model_name(ore.model);
  j["appearance"] = ore.appearance == Appearance::t10 ? "t10" : "austin";
  if (!c.t10_mean.empty()) j["t10_mean_by_class"] = c.t10_mean;
  j["power_W"] = run.power_W;
  j["holdup_kg"] = holdup_kg;
  j["mean_ball_diameter_mm"] = 2e3 * run.ball_radius_m;
  j["tanks"] = c.tanks;
  if (c.closed)
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
  j["build"] = {{"version", version()}, {"commit", build_commit()}};  // the code that made it
  return j;
}

// grind.png: the products' sizes beside the feed's, and the rates.
void draw(const fs::path& out, const Ore& ore, const io::Run& run, const Circuit& c,
          const std::vector<Product>& products, const GrindIntervals& ci) {
  const SizeSeries& s = c.sizes;
  const int n = s.size();
  const std::vector<double> fp = passing(c.feed);
  static const std::uint32_t colours[] = {0x1f77b4, 0xd62728, 0x2ca02c, 0xff7f0e, 0x9467bd, 0x8c564b, 0xe377c2, 0x17becf};
  io::LinePlot psd, rp;
  psd.title = (ore.name.empty() ? std::string("ore") : ore.name) + ": product size, " + model_name(ore.model) +
              " rates, " + fmt::format("{:.0f} W", run.power_W);
  psd.x_label = "size (um)";
  psd.y_label = "cumulative passing";
  psd.log_x = rp.log_x = true;
  io::PlotSeries fs_{"feed", {}, {}, 0x222222};
  for (int i = 0; i < n; ++i) fs_.x.push_back(s.top_m[i] * 1e6), fs_.y.push_back(fp[i]);
  fs_.dashed = true;
  psd.series.push_back(fs_);
  for (std::size_t k = 0; k < products.size(); ++k) {
    const std::vector<double> pp = passing(products[k].m);
    io::PlotSeries q{products[k].label, {}, {}, colours[k % 8]};
    for (int i = 0; i < n; ++i) q.x.push_back(s.top_m[i] * 1e6), q.y.push_back(pp[i]);
    psd.series.push_back(q);
    if (!ci.given) continue;
    // The 95 % band: its two ends, dashed, in the product's colour.
    io::PlotSeries lo{"", {}, {}, colours[k % 8]}, hi = lo;
    lo.dashed = hi.dashed = true;
    for (int i = 0; i < n; ++i) {
      const Interval& iv = ci.products[k].passing[i];
      if (!iv.valid()) continue;
      lo.x.push_back(s.top_m[i] * 1e6), lo.y.push_back(std::max(iv.lo, 0.0));
      hi.x.push_back(s.top_m[i] * 1e6), hi.y.push_back(std::min(iv.hi, 1.0));
    }
    psd.series.push_back(lo);
    psd.series.push_back(hi);
  }
  if (ci.given) {
    io::PlotSeries key{"dashed: 95 % interval", {}, {}, 0x888888};
    key.dashed = true;
    psd.series.push_back(key);
  }
  rp.title = "specific breakage rate of each class";
  rp.x_label = "size (um, class's geometric mean)";
  rp.y_label = "S (1/min)";
  io::PlotSeries rs{"S_i", {}, {}, 0x1f77b4};
  rs.markers = true;
  for (int i = 0; i + 1 < n; ++i) rs.x.push_back(s.mid_m(i) * 1e6), rs.y.push_back(c.S_per_min[i]);
  rp.series.push_back(rs);
  std::vector<io::LinePlot> plots = {psd, rp};
  if (!c.t10_mean.empty()) {  // Tavares' appearance: what the mill's collisions leave of each class
    io::LinePlot tp;
    tp.title = "Tavares' t10: mean over this mill's collisions";
    tp.x_label = "size (um, class's geometric mean)";
    tp.y_label = "t10 (%)";
    tp.log_x = true;
    io::PlotSeries ts{"t10", {}, {}, 0xd62728};
    ts.markers = true;
    for (int i = 0; i + 1 < n; ++i) ts.x.push_back(s.mid_m(i) * 1e6), ts.y.push_back(100 * c.t10_mean[i]);
    tp.series.push_back(ts);
    plots.push_back(tp);
  }
  io::draw_or_warn(out / "grind.png", [&] { io::write_line_plots_png(out / "grind.png", plots); });
}

// The products asked for, in a mill.
// `lenient` (an ore moved for the intervals): a target not reached gives a
// product of NaN rather than a refusal, so that the other products keep
// their intervals.
std::vector<Product> make_products(const GrindOptions& o, const Ore& ore, const Circuit& c,
                                   const std::vector<double>& times, double& target_rate, bool lenient = false) {
  std::vector<Product> products;
  for (double t : times) {
    Product p = batch_product(c, t);
    p.label = fmt::format("batch {:g} min", t);
    products.push_back(p);
  }
  if (o.feed_rate_t_h > 0) products.push_back(continuous(c, o.feed_rate_t_h));
  if (o.target_p80_um > 0) {
    try {
      products.push_back(at_target(o, ore, c, target_rate, lenient));
    } catch (const std::invalid_argument&) {
      if (!lenient) throw;
      const double nan = std::numeric_limits<double>::quiet_NaN();
      Product p;
      p.feed_t_h = p.kWh_t = p.p80_m = target_rate = nan;
      p.m.assign(c.feed.size(), nan);
      products.push_back(p);
    }
  }
  return products;
}

// Herbst & Fuerstenau's scale-up beside the spectrum model's: S_i^E =
// S_i H / P of the ore in the laboratory run (from its spectrum there),
// held in this mill, S_i = S_i^E P / H with this run's power and hold-up.
// Where the two disagree, the DEM's spectrum says that this mill spends
// its energy differently from the laboratory's.
struct ScaleUp {
  io::Run lab;
  std::vector<double> SE_t_per_kWh;
  std::vector<Product> products;  // labelled " [H&F from lab]"
  double target_rate = std::numeric_limits<double>::quiet_NaN();
  std::string contact_changed;  // lab -> this run; empty: the same
};
constexpr const char* kScaleTag = " [H&F from lab]";

// An ore that says it reads one energy but records a fit on another: its
// fitted parameters (η above all) hold on the energy it was fitted on.
// Refused where products are made; a new fit replaces the record.
void check_energy_basis(const std::string& path, const Ore& ore) {
  const std::string& fitted = ore.fitted_under.energy_basis;
  if (ore.model != RateModel::spectrum || !ore.energy_basis_given || fitted.empty() ||
      fitted == basis_name(ore.energy_basis))
    return;
  throw std::invalid_argument(path + ": rates.energy_basis is \"" + basis_name(ore.energy_basis) +
                              "\" but the ore was fitted on \"" + fitted +
                              "\" ([fitted] energy_basis; a fit from before the severity spectra names none and "
                              "read the loss with one radius): set rates.energy_basis = \"" + fitted +
                              "\", or fit the ore again on the new basis (grind --fit or --fit-wi replaces the "
                              "[fitted] table)");
}

// The laboratory run of --scale-from, read once.
io::Run scale_from_run(const GrindOptions& o, const Ore& ore, const io::Run& plant) {
  if (ore.model != RateModel::spectrum)
    throw std::invalid_argument("--scale-from: sets the spectrum model's prediction beside the energy-specific "
                                "scale-up; the ore's rates.model must be \"spectrum\"");
  if (o.bond_p1_um > 0) throw std::invalid_argument("--scale-from with --bond: give one");
  io::Run lab = io::read_run(o.scale_from, true, ore.energy_basis);
  // The two runs' spectra are comparable under one contact only.
  const std::string changed = contact_mismatch(lab.contact, plant.contact);
  if (!changed.empty())
    std::fprintf(stderr,
                 "millcharge: warning: --scale-from %s: the laboratory run's contact differs from this run's (%s); "
                 "the two models then differ by the contact too\n",
                 o.scale_from.c_str(), changed.c_str());
  return lab;
}

ScaleUp scale_up(const GrindOptions& o, const Ore& ore, const io::Run& plant, const io::Run& lab, const Circuit& c,
                 const std::vector<double>& times, bool lenient) {
  ScaleUp up;
  up.lab = lab;
  up.contact_changed = contact_mismatch(up.lab.contact, plant.contact);
  const double lab_holdup = mill_holdup_kg(ore, up.lab.porosity, up.lab.filling, up.lab.mill_volume);
  up.SE_t_per_kWh = mill_rates(ore, up.lab.spectrum, up.lab.power_W, lab_holdup).SE_t_per_kWh;
  Circuit he = c;
  // The energy-specific scale-up holds the laboratory's appearance too: with
  // Tavares' t10, that of the laboratory mill's collisions.
  if (ore.appearance == Appearance::t10) he.b = appearance_matrix(ore, up.lab.spectrum);
  for (std::size_t i = 0; i < he.S_per_min.size(); ++i)
    he.S_per_min[i] = up.SE_t_per_kWh[i] * c.power_kW / c.holdup_t / 60;
  try {
    up.products = make_products(o, ore, he, times, up.target_rate, lenient);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(e.what()) + " (by the energy-specific rates of --scale-from " +
                                o.scale_from + ")");
  }
  for (Product& p : up.products) p.label += kScaleTag;
  return up;
}

nlohmann::ordered_json scale_up_json(const GrindOptions& o, const ScaleUp& up, const std::vector<Product>& all) {
  nlohmann::ordered_json j;
  j["model"] = "Herbst & Fuerstenau: the energy-specific rates of the ore in the laboratory run";
  j["lab_run"] = o.scale_from;
  j["lab_title"] = up.lab.title;
  j["lab_power_W"] = up.lab.power_W;
  if (!up.contact_changed.empty()) j["contact_differs_from_lab"] = up.contact_changed;
  j["SE_t_per_kWh"] = up.SE_t_per_kWh;
  if (o.target_p80_um > 0)
    j["throughput_at_target_t_h"] = std::isfinite(up.target_rate) ? nlohmann::json(up.target_rate) : nlohmann::json();
  nlohmann::json pairs = nlohmann::json::array();
  const std::size_t n = all.size() - up.products.size();
  for (std::size_t k = 0; k < n; ++k) {
    const double a = all[k].p80_m, b = up.products[k].p80_m;
    pairs.push_back({{"label", all[k].label},
                     {"P80_um_spectrum", std::isfinite(a) ? nlohmann::json(a * 1e6) : nlohmann::json()},
                     {"P80_um_energy_specific", std::isfinite(b) ? nlohmann::json(b * 1e6) : nlohmann::json()},
                     {"ratio", std::isfinite(a) && std::isfinite(b) ? nlohmann::json(a / b) : nlohmann::json()}});
  }
  j["P80_side_by_side"] = pairs;
  return j;
}

void print_scale_up(const GrindOptions& o, const ScaleUp& up, const std::vector<Product>& all) {
  std::printf("scale-up from %s (%.1f W): P80 by the spectrum here / by the lab's energy-specific rates\n",
              o.scale_from.c_str(), up.lab.power_W);
  const std::size_t n = all.size() - up.products.size();
  for (std::size_t k = 0; k < n; ++k)
    std::printf("  %-28s %s / %s um  ratio %.3f\n", all[k].label.c_str(), fmt_um(all[k].p80_m).c_str(),
                fmt_um(up.products[k].p80_m).c_str(), all[k].p80_m / up.products[k].p80_m);
  if (o.target_p80_um > 0)
    std::printf("  throughput at P80 %g um: %.4g t/h by the spectrum, %.4g t/h by the energy-specific rates\n",
                o.target_p80_um, all[n - 1].feed_t_h, up.target_rate);
}

void print(const GrindOptions& o, const Ore& ore, const io::Run& run, const Circuit& c, double holdup_kg,
           const std::vector<Product>& products, const BondResult& bond, const GrindIntervals& ci) {
  std::printf("ore %s, %s rates; mill power %.1f W, hold-up %.3g kg, F80 %s um\n", ore.name.c_str(),
              model_name(ore.model), run.power_W, holdup_kg, fmt_um(ore.f80_m).c_str());
  if (!c.t10_mean.empty()) {
    // Tavares' appearance: the mean t10 of the coarsest class, the class
    // at the feed's F80 and the finest that breaks.
    std::string t10s;
    const int n = c.sizes.size();
    for (int i : {0, n / 2, n - 2})
      t10s += fmt::format("{}{:.1f} % at {:.0f} um", t10s.empty() ? "" : ", ", 100 * c.t10_mean[i],
                          c.sizes.mid_m(i) * 1e6);
    std::printf("  appearance: Tavares' t10 from this mill's collisions, mean t10 %s\n", t10s.c_str());
  }
  if (ci.given) {
    std::printf("  with the 95 %% intervals the fit leaves open: value [lo, hi]\n");
    // A fit that ended on a bound may sit in another valley than the ore's:
    // the intervals are local (docs/grinding-intervals.md).
    for (const HeldParameter& h : ore.fitted_under.covariance.held)
      if (h.why == "on its bound")
        std::printf("  note: the fit left %s on its bound (%g), held there: its range is one-sided, and the "
                    "intervals describe this fit's neighbourhood only; another test or fewer parameters "
                    "(docs/grinding-intervals.md)\n",
                    h.name.c_str(), h.value);
    for (const std::string& h : ci.open_held)
      std::printf("  note: the data do not bound %s within the ore file's range: its reach there is the file's "
                  "range, not the data's, and the intervals are no 95 %% statement (docs/grinding-intervals.md)\n",
                  h.c_str());
    if (!ci.outside.empty()) std::printf("  note: %s (docs/grinding-intervals.md)\n", ci.outside.c_str());
    for (const Correlated& c : ci.correlated)
      std::printf("  note: %s and %s are correlated at r = %+.4f: the tests fix only their combination, not "
                  "each\n",
                  c.a.c_str(), c.b.c_str(), c.r);
  }
  for (std::size_t k = 0; k < products.size(); ++k) {
    const Product& p = products[k];
    // An interval where the number depends on the ore (a batch's kWh/t does
    // not; a P80 held at the target moves by the solver's tolerance only,
    // about 1e-7 of it: below 1e-6, none).
    auto iv = [&](Interval ProductInterval::*m, double scale, const char* f) {
      if (!ci.given) return std::string();
      const Interval& i = ci.products[k].*m;
      return i.valid() && i.hi - i.lo > 1e-6 * std::fabs(i.hi) ? bracket(i, scale, f) : std::string();
    };
    std::printf("  %-28s %s %8.3g kWh/t%s  P80 %s um%s%s\n", p.label.c_str(),
                p.feed_t_h > 0 ? fmt::format("{:9.4g} t/h{}", p.feed_t_h, iv(&ProductInterval::feed_t_h, 1, "{:.4g}"))
                                     .c_str()
                               : "             ",
                p.kWh_t, iv(&ProductInterval::kWh_t, 1, "{:.3g}").c_str(), fmt_um(p.p80_m).c_str(),
                ci.given && !ci.products[k].p80_um.valid() && std::isfinite(p.p80_m)
                    ? " [no interval: a product the ore's range cannot make]"
                    : iv(&ProductInterval::p80_um, 1, "{:.1f}").c_str(),
                p.circulating_load >= 0
                    ? fmt::format("  circulating load {:.0f} %{}", 100 * p.circulating_load,
                                  p.converged ? "" : " (not steady)")
                          .c_str()
                    : "");
  }
  if (o.bond_p1_um > 0)
    std::printf("  Bond test at P1 %g um, %.0f g charge: %d cycles%s, Gbp %.3f g/rev%s, CL %.0f %%, F80 %.0f um, P80 %.0f "
                "um%s, Wi %.2f kWh/t%s\n",
                bond.p1_um, bond.charge_g, bond.cycles, bond.steady ? "" : " (not steady)", bond.gbp_g_rev,
                bracket(ci.gbp_g_rev, 1, "{:.3f}").c_str(), 100 * bond.circulating_load, bond.f80_um, bond.p80_um,
                bracket(ci.bond_p80_um, 1, "{:.0f}").c_str(), bond.wi_kWh_t,
                bracket(ci.work_index_kWh_t, 1, "{:.2f}").c_str());
}

// Everything grind makes of one ore in the run: the circuit, the products
// (with --scale-from's beside them) and Bond's test.
struct Made {
  double holdup_kg = 0;
  MillRates rates;
  Circuit c;
  std::vector<Product> products;
  ScaleUp up;
  BondResult bond;
  double target_rate = std::numeric_limits<double>::quiet_NaN();
};

// `lenient`: an ore moved for the intervals; a product or Bond's test it
// cannot make is NaN, not a refusal.
Made make(const GrindOptions& o, const Ore& ore, const io::Run& run, const io::Run& lab,
          const std::vector<double>& times, bool lenient = false) {
  Made m;
  // The mill: the ore in it, the rates, the circuit.
  m.holdup_kg = mill_holdup_kg(ore, run.porosity, run.filling, run.mill_volume);
  m.rates = mill_rates(ore, run.spectrum, run.power_W, m.holdup_kg);
  Circuit& c = m.c;
  c.sizes = ore.sizes;
  c.feed = ore.feed;
  c.S_per_min = m.rates.S_per_min;
  c.b = appearance_matrix(ore, run.spectrum, &c.t10_mean);
  c.power_kW = run.power_W / 1000;
  c.holdup_t = m.holdup_kg / 1000;
  c.tanks = o.tanks > 0 ? o.tanks : ore.tanks;
  c.closed = o.classifier_d50c_um > 0;
  c.classifier.d50c_m = o.classifier_d50c_um * 1e-6;
  c.classifier.alpha = o.classifier_alpha;
  c.classifier.bypass = o.classifier_bypass;
  // The products: batch times, a feed rate, the feed rate for a target P80.
  m.products = make_products(o, ore, c, times, m.target_rate, lenient);
  // --scale-from: the same products by Herbst & Fuerstenau's scale-up, the
  // energy-specific rates the ore has in the laboratory run held in this mill.
  if (!o.scale_from.empty()) {
    m.up = scale_up(o, ore, run, lab, c, times, lenient);
    m.products.insert(m.products.end(), m.up.products.begin(), m.up.products.end());
  }
  if (o.bond_p1_um > 0) {
    Ore bond_ore = ore;
    put_sieve_on_class_top(bond_ore, o.bond_p1_um * 1e-6);
    try {
      m.bond = run_bond(o, bond_ore, run);
    } catch (const std::invalid_argument&) {
      if (!lenient) throw;
      m.bond.wi_kWh_t = m.bond.p80_um = m.bond.gbp_g_rev = std::numeric_limits<double>::quiet_NaN();
    }
  }
  return m;
}

GrindNumbers numbers(const GrindOptions& o, const Made& m) {
  GrindNumbers g;
  g.products = m.products;
  g.bond = o.bond_p1_um > 0;
  g.bond_result = m.bond;
  g.target = o.target_p80_um > 0;
  g.target_rate_t_h = m.target_rate;
  return g;
}

// grind.json: each number's interval beside it ("P80_um_95": [lo, hi]).
void add_intervals(nlohmann::ordered_json& j, const GrindOptions& o, const GrindIntervals& ci) {
  // An open end (past any bound: a target the moved ore cannot reach) is
  // null, and "KEY_open" says which.
  auto end = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  auto pair = [&](const Interval& i) { return i.valid() ? nlohmann::json({end(i.lo), end(i.hi)}) : nlohmann::json(); };
  auto put = [&](nlohmann::ordered_json& at, const std::string& key, const Interval& i) {
    at[key] = pair(i);
    if (i.valid() && (i.open_below() || i.open_above()))
      at[key + "_open"] = i.open_below() && i.open_above() ? "both" : i.open_below() ? "below" : "above";
  };
  j["intervals"] = {{"level", 0.95},
                    {"method", "linearised propagation of the fit's covariance (Student's t), combined in quadrature "
                               "with how far the held parameters move each number (docs/grinding-intervals.md)"}};
  if (!ci.outside.empty()) j["intervals"]["outside_data_region"] = ci.outside;
  if (!ci.open_held.empty())
    j["intervals"]["open_held"] = {{"parameters", ci.open_held},
                                   {"note", "the data do not bound these within the ore file's range: the intervals "
                                            "reach as far as the file's range, and are no 95 % statement"}};
  if (!ci.correlated.empty()) {
    nlohmann::json pairs = nlohmann::json::array();
    for (const Correlated& c : ci.correlated)
      pairs.push_back({{"variables", {c.a, c.b}},
                       {"r", c.r},
                       {"note", "the tests fix only this pair's combination, not each"}});
    j["intervals"]["correlated"] = pairs;
  }
  for (std::size_t k = 0; k < ci.products.size(); ++k) {
    auto& q = j["products"][k];
    const ProductInterval& p = ci.products[k];
    put(q, "P80_um_95", p.p80_um);
    put(q, "specific_energy_kWh_t_95", p.kWh_t);
    if (q.contains("feed_rate_t_h")) put(q, "feed_rate_t_h_95", p.feed_t_h);
    if (q.contains("circulating_load")) put(q, "circulating_load_95", p.circulating_load);
  }
  if (o.target_p80_um > 0) put(j, "throughput_at_target_t_h_95", ci.throughput_t_h);
  if (o.bond_p1_um > 0) {
    j["bond"]["work_index_kWh_t_95"] = pair(ci.work_index_kWh_t);
    j["bond"]["P80_um_95"] = pair(ci.bond_p80_um);
    j["bond"]["Gbp_g_per_rev_95"] = pair(ci.gbp_g_rev);
  }
}

}  // namespace

int cmd_grind(const GrindOptions& o) {
  if (!o.fit_tests.empty() || o.fit_wi_kWh_t > 0) return cmd_grind_fit(o);
  if (!o.fit_params.empty()) throw std::invalid_argument("--fit-params: names what --fit or --fit-wi fits; give one");
  if (!o.sieve_errors.empty())
    throw std::invalid_argument("--sieve-errors: says how --fit takes a batch test's sieve errors; give --fit");
  // The inputs, checked before anything is computed.
  const Ore ore = io::read_ore(o.ore);
  Ore bond_ore = ore;
  if (o.bond_p1_um > 0) put_sieve_on_class_top(bond_ore, o.bond_p1_um * 1e-6);
  check_classifier(o, ore);
  check_energy_basis(o.ore, ore);
  const io::Run run = io::read_run(o.run_dir, ore.model == RateModel::spectrum, ore.energy_basis);
  if (ore.model == RateModel::spectrum && ore.energy_basis == EnergyBasis::impact && run.clumps)
    throw std::invalid_argument(
        o.ore + ": rates.energy_basis \"impact\" with a charge of clumps (" + o.run_dir +
        "): two bodies touching at several spheres book the whole encounter's impact energy at each, with the "
        "bodies' masses, so the impact spectrum overstates it; set rates.energy_basis = \"loss\" (the loss is "
        "split between the contacts: docs/energy.md)");
  if (ore.model == RateModel::spectrum && ore.energy_basis == EnergyBasis::loss_one_radius && !o.quiet)
    std::fprintf(stderr,
                 "millcharge: note: %s: read on the normal loss with one radius for every collision, as it was "
                 "fitted (its [fitted] table names no energy_basis); fit it again to read each collision's own "
                 "radius and the impact energy (docs/grinding.md)\n",
                 o.ore.c_str());
  if (o.bond_p1_um > 0) check_bond(o, bond_ore, run);
  // A run still settling into its motion: its torque also lifts the charge
  // (the energy-specific and Austin rates take the torque's power, the
  // spectrum only the collisions).
  const bool unbalanced = std::fabs(run.imbalance) > kImbalanceWarn;
  if (unbalanced)
    std::fprintf(stderr,
                 "millcharge: warning: %s: not in steady motion: torque %.4g W, dissipation %.4g W (%+.0f %%), the "
                 "charge's energy changed by %.4g W over the window; its products are those of the run's start: "
                 "run it longer\n",
                 o.run_dir.c_str(), run.power_W, run.dissipation_W, 100 * run.imbalance, run.energy_change_W);
  // An ore fitted through a run holds under that run's contact law and
  // parameters only: a run with others gives another spectrum.
  const std::string contact_changed = contact_mismatch(ore.fitted_under, run.contact);
  if (!contact_changed.empty())
    std::fprintf(stderr,
                 "millcharge: warning: %s: the ore was fitted under other contact parameters than this run's (%s); "
                 "its breakage parameters hold under the contact they were fitted under (docs/grinding-fit.md)\n",
                 o.ore.c_str(), contact_changed.c_str());

  const io::Run lab = o.scale_from.empty() ? io::Run{} : scale_from_run(o, ore, run);
  const NextPlan next = plan_next(o, ore);  // the candidates of --next-test, checked
  const std::vector<double> times = o.times_min.empty() && !(o.feed_rate_t_h > 0) && !(o.target_p80_um > 0) &&
                                            !(o.bond_p1_um > 0)
                                        ? std::vector<double>{1, 2, 4, 8, 16}
                                        : o.times_min;
  const Made made = make(o, ore, run, lab, times);
  const Circuit& c = made.c;
  const std::vector<Product>& products = made.products;
  const BondResult& bond = made.bond;
  // The intervals the fit leaves open: every product again with the ore moved.
  if (!ore.fitted_under.law.empty() && !ore.fitted_under.covariance.given && !o.quiet)
    std::fprintf(stderr,
                 "millcharge: note: %s: its [fitted] table keeps no covariance (fitted before intervals were kept, "
                 "or to a work index): products without intervals; fit it again with --fit for them\n",
                 o.ore.c_str());
  const GrindIntervals ci = grind_intervals(ore, numbers(o, made),
                                            [&](const Ore& moved) { return numbers(o, make(o, moved, run, lab, times, true)); });
  // The fit's residuals correlated along the sieves and taken as
  // independent: the intervals shown are likely too narrow; said once.
  const std::string sieve_note =
      sieve_errors_note(ore.fitted_under.residual_lag1, ore.fitted_under.sieve_error_rho, SieveErrors::independent);
  if (ci.given && !o.quiet && !(ore.fitted_under.sieve_error_rho > 0) && !sieve_note.empty())
    std::fprintf(stderr, "millcharge: %s: %s\n", o.ore.c_str(), sieve_note.c_str());
  if (!ci.stale.empty() && !o.quiet)
    std::fprintf(stderr,
                 "millcharge: note: %s: %s ([fitted] %s): the ore was changed after its fit, and "
                 "the covariance describes the fitted ore only: products without intervals; fit it again with "
                 "--fit for them\n",
                 o.ore.c_str(), ci.stale.c_str(), ci.stale_key.c_str());
  // Which test next: every candidate's expected interval of the product.
  NextRanking ranking;
  if (next.asked) {
    const GrindNumbers g = numbers(o, made);
    const NextTarget target = next_target(o, g);
    ranking = rank_next(next, ore, target, ci, g, [&](const Ore& moved) {
      return flatten(numbers(o, make(o, moved, run, lab, times, true)))[target.index];
    });
  }

  // Everything computed; now the files.
  const fs::path out = o.out.empty() ? fs::path(o.run_dir) / "grind" : fs::path(o.out);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw std::runtime_error(out.string() + ": cannot create: " + ec.message());
  write_tables(out, c, products, made.rates.SE_t_per_kWh, ci);
  nlohmann::ordered_json j = summary(o, ore, run, c, made.holdup_kg, products, made.target_rate, bond);
  if (ci.given) add_intervals(j, o, ci);
  if (!ci.stale.empty()) j["intervals"] = {{"none", "the ore differs from the fit its covariance describes"}, {"changed", ci.stale}};
  if (!contact_changed.empty()) j["contact_differs_from_fit"] = contact_changed;
  if (unbalanced)
    j["not_in_steady_motion"] = {{"torque_W", run.power_W},
                                 {"dissipation_W", run.dissipation_W},
                                 {"imbalance", run.imbalance},
                                 {"energy_change_W", run.energy_change_W}};
  if (!o.scale_from.empty()) j["scale_up"] = scale_up_json(o, made.up, products);
  if (next.asked) {
    j["next_test"] = next_json(ranking);
    write_next_csv(out, ranking);
  }
  io::write_file_atomic(out / "grind.json", j.dump(2) + "\n");
  draw(out, ore, run, c, products, ci);
  if (!o.quiet) {
    print(o, ore, run, c, made.holdup_kg, products, bond, ci);
    if (!o.scale_from.empty()) print_scale_up(o, made.up, products);
    if (next.asked) print_next(ranking);
    std::printf("wrote %s/{grind.csv, rates.csv, grind.json, grind.png%s}\n", out.string().c_str(),
                next.asked ? ", next_test.csv" : "");
  }
  return 0;
}

}  // namespace mc::app
