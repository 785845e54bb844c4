#include "app/run_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "app/prepare.h"
#include "core/lifters.h"
#include "core/liner_wear.h"
#include "core/plate_wear.h"
#include "core/version.h"
#include "io/atomic_file.h"
#include "io/energy_out.h"
#include "io/png_plot.h"

namespace mc::app {

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Lifter polygons turned from the mill frame into the lab frame.
std::vector<std::vector<Vec2>> lab_lifters(const Scene& scene, double mill_angle) {
  std::vector<std::vector<Vec2>> out = scene.walls.lifters;
  const double c = std::cos(mill_angle), s = std::sin(mill_angle);
  for (auto& poly : out)
    for (Vec2& v : poly) v = {c * v.x - s * v.y, s * v.x + c * v.y};
  return out;
}

// printf into a string (two numbers).
std::string fmt_g(const char* format, double a, double b) {
  char buf[160];
  std::snprintf(buf, sizeof buf, format, a, b);
  return buf;
}

double finite_or_nan(bool ok, double v) { return ok ? v : std::nan(""); }

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

// What the wear figures are: relative at the default wear coefficient.
std::string wear_rates_words(bool relative) {
  return relative ? std::string(kWearRelative) + " (the default stand-in; docs/liner-life.md#the-time-axis)"
                  : "at the case's wear coefficient";
}

// summary.json's liner.consumption_g_per_kWh: each part's g/kWh and what
// it is taken over.
nlohmann::ordered_json consumption_json(const LinerConsumption& x) {
  nlohmann::ordered_json j;
  j["shell_and_lifters"] = number_or_null(x.shell_lifters_g_kWh);
  if (x.has_end_plates) j["end_plates"] = number_or_null(x.end_plates_g_kWh);
  if (x.has_meshes) j["mesh_walls"] = number_or_null(x.mesh_g_kWh);
  j["all"] = number_or_null(x.all_g_kWh);
  j["power_W"] = x.power_W;
  j["what"] = "grams of liner worn per kWh the mill draws: each part's wear_kg_per_h x 1e6 / power_W (the torque "
              "power at the shell, not the motor's); shell_and_lifters is what plants weigh as shell liners (worn "
              "steel only, not what is scrapped at relining); a mesh wall counts with the part its case names "
              "(shell and lifters, or ends), mesh_walls is the meshes' own sum";
  j["relative"] = x.relative;
  return j;
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

// What a life study reads of a half's wear (app/life_state.h WearParts):
// the shell's sliding depth rate and strike energy per m², the shell and
// lifters' sliding kg/h and strike energy.
static nlohmann::ordered_json wear_parts_json(const LinerReport& h, double window_s, double density) {
  nlohmann::ordered_json j;
  j["window_s"] = window_s;
  double kg_h = 0, strike = 0;
  for (const LinerPartRates& p : h.parts) {
    if (p.name == "shell") {
      j["shell_sliding_wear_mm_per_1000h"] =
          p.area_m2 > 0 ? p.sliding_kg_per_h / density / 3600.0 / p.area_m2 * 3.6e9 : 0.0;
      j["shell_strike_W_per_m2"] = p.area_m2 > 0 ? p.strike_W / p.area_m2 : 0.0;
      j["shell_sliding_wear_kg_per_h"] = p.sliding_kg_per_h;
      j["shell_strike_W"] = p.strike_W;
    }
    if (p.name == "shell" || p.name.rfind("lifter", 0) == 0) kg_h += p.sliding_kg_per_h, strike += p.strike_W;
  }
  j["shell_lifters_sliding_wear_kg_per_h"] = kg_h;
  j["shell_lifters_strike_W"] = strike;
  return j;
}

LinerConsumption liner_consumption(const LinerReport& liner, double power_W, double wear_coefficient) {
  LinerConsumption x;
  x.power_W = power_W;
  for (const LinerPartRates& p : liner.parts) {
    if (p.name == "end plates") x.end_plates_kg_h += p.wear_kg_per_h, x.has_end_plates = p.area_m2 > 0;
    if (p.name == "mesh walls") x.mesh_kg_h += p.wear_kg_per_h, x.has_meshes = true;
    x.all_kg_h += p.wear_kg_per_h;
  }
  // A mesh counts with what its case says it stands for: a mesh liner's
  // shell and lifters with the shell and lifters, cone heads with the ends.
  x.shell_lifters_kg_h = shell_lifters_wear_kg_per_h(liner);
  const double mesh_ends = liner.mesh_wear_kg_per_h_by_part[static_cast<int>(MeshPart::ends)];
  x.end_plates_kg_h += mesh_ends;
  x.has_end_plates = x.has_end_plates || mesh_ends > 0;
  x.shell_lifters_g_kWh = grams_per_kWh(x.shell_lifters_kg_h, power_W);
  x.end_plates_g_kWh = grams_per_kWh(x.end_plates_kg_h, power_W);
  x.mesh_g_kWh = grams_per_kWh(x.mesh_kg_h, power_W);
  x.all_g_kWh = grams_per_kWh(x.all_kg_h, power_W);
  x.relative = wear_coefficient_is_default(wear_coefficient);
  return x;
}

RunReport report_of(const FinishedRun& r) {
  const MillCase& c = r.c;
  const MillDerived& d = r.d;
  const RunSummary& s = r.s;
  RunReport rep;
  rep.mi = morrell_input(c, d);
  rep.m = morrell_c_model(rep.mi);
  rep.toe = finite_or_nan(s.angles.found, s.angles.toe_deg);
  rep.shoulder = finite_or_nan(s.angles.found, s.angles.shoulder_deg);
  rep.m_with_dem = s.angles.found
                       ? kMorrellK * morrell_net_power(rep.mi, rep.toe * kPi / 180, rep.shoulder * kPi / 180)
                       : std::nan("");
  rep.err = errors_of(s.window_batches);
  rep.per_rev = std::max(1, s.batches_per_revolution);
  rep.window_revs = static_cast<int>(s.window_batches.size()) / rep.per_rev;
  // A window of less than a revolution: batches of 1/8 revolution give a
  // rough error from half a revolution on (4 of them); less gives none.
  constexpr int kRoughBatches = 4;
  const double rev_s = d.revolution_s, window_s = s.window_to_s - s.window_from_s;
  char why[400];
  if (rep.window_revs >= 1) {
    rep.sem_kind = "whole revolutions";
  } else if (rep.err.power.batches >= kRoughBatches) {
    rep.sem_kind = "rough";
    std::snprintf(why, sizeof why,
                  "from %d batches of 1/%d revolution in a window of %.3g s, less than one revolution (%.3g s): each "
                  "batch sees part of the charge's cycle; turn at least %.3g s (the warm-up and one revolution) for "
                  "an error from whole revolutions",
                  rep.err.power.batches, rep.per_rev, window_s, rev_s, c.warmup + rev_s);
    rep.sem_why = why;
  } else {
    rep.sem_kind = "none";
    std::snprintf(why, sizeof why,
                  "the averaging window (%.3g s after the warm-up of %.3g s) holds less than half a revolution "
                  "(a revolution is %.3g s); turn at least %.3g s for a rough error, %.3g s (the warm-up and one revolution) for one "
                  "from whole revolutions",
                  window_s, c.warmup, rev_s, c.warmup + 0.5 * rev_s, c.warmup + rev_s);
    rep.sem_why = why;
    for (BatchMeans* b : {&rep.err.power, &rep.err.dissipation, &rep.err.torque, &rep.err.arm, &rep.err.toe,
                          &rep.err.shoulder, &rep.err.com, &rep.err.collisions, &rep.err.collision_power,
                          &rep.err.impacts, &rep.err.impact, &rep.err.shear, &rep.err.wear})
      b->sem = std::numeric_limits<double>::quiet_NaN();
  }
  rep.rel_err = rep.err.power.sem / std::fabs(rep.err.power.mean);
  // Where the energy went over the window: collision spectra and the liner.
  rep.layout = liner_layout(r.scene);
  rep.spectra = spectra_report(r.scene, s.books, s.window_s, s.open_loss_start_J, s.open_loss_end_J, s.dissipated_J);
  rep.liner = liner_report(r.scene, rep.layout, s.books, s.window_s, s.profile, s.angles);
  rep.consumption = liner_consumption(rep.liner, s.torque_power_W, r.scene.wall_material.wear_coefficient);
  return rep;
}

std::vector<std::string> write_run_results(const FinishedRun& r, const RunReport& rep) {
  std::vector<std::string> not_written;
  const MillCase& c = r.c;
  const MillDerived& d = r.d;
  const RunSummary& s = r.s;
  const fs::path& out = r.out;
  const MorrellInput& mi = rep.mi;
  const MorrellResult& m = rep.m;
  const Errors& err = rep.err;
  const LinerLayout& layout = rep.layout;
  const SpectraReport& spectra = rep.spectra;
  const LinerReport& liner = rep.liner;
  const double toe = rep.toe, shoulder = rep.shoulder, m_with_dem = rep.m_with_dem;
  const int per_rev = rep.per_rev, window_revs = rep.window_revs;
  const double rel_err = rep.rel_err;
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
                      {"power_relative_sem", number_or_null(rel_err)},
                      {"standard_errors", rep.sem_kind},
                      {"standard_errors_why", rep.sem_why.empty() ? nlohmann::json() : nlohmann::json(rep.sem_why)}};
  j["neighbours_per_ball"] = s.neighbours_per_ball;
  j["morrell"] = {{"power_W", m.charge_power_W},
                  {"k", kMorrellK},
                  {"net_power_W", m.net_power_W},
                  {"toe_deg", m.toe_deg},
                  {"shoulder_deg", m.shoulder_deg},
                  {"power_with_dem_angles_W", number_or_null(m_with_dem)},
                  {"charge_density_kg_m3", mi.charge_density}};
  j["spectra"] = io::spectra_json(spectra);
  j["spectra"]["total"]["collisions_per_s_sem"] = number_or_null(err.collisions.sem);
  j["spectra"]["total"]["power_W_sem"] = number_or_null(err.collision_power.sem);
  j["liner"] = io::liner_json(layout, liner, r.scene.wall_material);
  j["liner"]["impacts_per_s_sem"] = number_or_null(err.impacts.sem);
  j["liner"]["impact_power_W_sem"] = number_or_null(err.impact.sem);
  j["liner"]["shear_power_W_sem"] = number_or_null(err.shear.sem);
  j["liner"]["wear_kg_per_h_sem"] = number_or_null(err.wear.sem);
  j["liner"]["wear_rates"] = wear_rates_words(rep.consumption.relative);
  j["liner"]["consumption_g_per_kWh"] = consumption_json(rep.consumption);
  j["per_metre"] = io::per_metre_json(c.length, s.torque_power_W, s.dissipation_power_W, s.torque_Nm, spectra, liner);
  j["contact_records_refused"] = r.solver.records_refused();
  j["wall_s"] = s.wall_s;
  j["particle_updates_per_s"] = s.updates_per_s;
  j["device"] = r.device;
  j["device_bytes"] = r.solver.device_bytes();
  j["precision"] = c.precision == Precision::double_ ? "double" : "float";
  j["build"] = {{"version", version()}, {"commit", build_commit()}};  // the code that made it

  // The results first: once the charge has turned, nothing after them (a
  // picture, a mesh) may lose them; what cannot be drawn or written then is
  // a warning that names the file.
  // The liner's wear over each half of the window, where the run has them
  // (how far a life study's stage can be trusted: docs/liner-life.md).
  BookSums halves[2];
  const bool split = liner_books_half(r.s.books, s.half_books, 0, halves[0]) &&
                     liner_books_half(r.s.books, s.half_books, 1, halves[1]) && s.half_window_s > 0 &&
                     s.window_s > s.half_window_s;
  const double half_s[2] = {s.half_window_s, s.window_s - s.half_window_s};
  if (split) {
    j["liner"]["halves"] = nlohmann::json::array();
    for (int h = 0; h < 2; ++h)
      j["liner"]["halves"].push_back(wear_parts_json(
          liner_report(r.scene, layout, halves[h], half_s[h], {}, ChargeAngles{}), half_s[h],
          r.scene.wall_material.density));
  }
  io::write_spectra_csv(out / "spectra.csv", spectra);
  io::write_wear_csv(out / "wear.csv", layout, liner);
  if (c.lifter_rows > 0) {
    std::vector<std::vector<Vec2>> outlines;
    for (const LifterProfile& p : c.lifter_pattern) outlines.push_back(profile_outline(p));
    const double k_impact = r.scene.wall_material.impact_wear_coefficient;
    // The bars reach into worn end plates' dish at the shell (core/liner.cpp).
    const double bars =
        c.length + (r.scene.walls.has_end_plates() ? plate_depth_at_shell(r.scene.walls.plate_depth) : 0.0);
    std::vector<std::vector<LifterStation>> by_half;
    for (int h = 0; h < 2 && split; ++h)
      by_half.push_back(lifter_stations(halves[h], half_s[h], outlines, 0.5 * c.diameter, bars, k_impact));
    io::write_lifter_wear_csv(out / "lifter_wear.csv",
                              lifter_stations(r.s.books, s.window_s, outlines, 0.5 * c.diameter, bars, k_impact),
                              by_half);
  }
  io::write_file_atomic(out / "summary.json", j.dump(2) + "\n");

  // Pictures: power against time, and the end view with toe and shoulder.
  io::LinePlot plot;
  plot.title = fmt::format("{}: power draw, {:.4g} % of critical", c.name, 100 * d.speed_fraction);
  plot.x_label = "time since the mill started (s)";
  plot.y_label = "power (W)";
  io::PlotSeries torque, diss;
  torque.label = "torque power", torque.x = r.t_series, torque.y = r.p_torque, torque.rgb = 0x1f77b4;
  diss.label = "dissipation", diss.x = r.t_series, diss.y = r.p_diss, diss.rgb = 0xd62728;
  plot.series = {torque, diss};
  plot.span_from = s.window_from_s;
  plot.span_to = s.window_to_s;
  plot.span_label = "averaged";
  plot.ref_lines = {{s.torque_power_W, s.window_from_s, s.window_to_s, 0x0d3a5c, false,
                     "mean torque power " + io::value_with_error(s.torque_power_W, err.power.sem, "W")},
                    {s.dissipation_power_W, s.window_from_s, s.window_to_s, 0x7a1014, true,
                     "mean dissipation " + io::value_with_error(s.dissipation_power_W, err.dissipation.sem, "W")}};
  if (!io::draw_or_warn(out / "power.png", [&] { io::write_line_plot_png(out / "power.png", plot); }))
    not_written.push_back("power.png");
  io::EndView view;
  view.title = c.name + " at t = " + std::to_string(s.turning_s).substr(0, 5) + " s";
  view.shell_radius = 0.5 * c.diameter;
  view.lifters = lab_lifters(r.scene, r.solver.mill_angle());
  for (const BallState& b : r.solver.balls())
    view.balls.push_back({b.position.x, b.position.y, b.position.z, b.radius, b.velocity.norm()});
  view.toe_deg = s.angles.found ? s.angles.toe_deg : -1;
  view.shoulder_deg = s.angles.found ? s.angles.shoulder_deg : -1;
  view.impact_deg = std::isfinite(liner.impact_point_deg) ? liner.impact_point_deg : -1;
  view.has_com = true;
  const Observables now = r.solver.observe(false);
  view.com_x = now.com_x_m;
  view.com_y = now.com_y_m;
  if (!io::draw_or_warn(out / "charge.png", [&] { io::write_end_view_png(out / "charge.png", view); }))
    not_written.push_back("charge.png");
  if (!io::draw_or_warn(out / "liner.png", [&] { io::write_liner_png(out / "liner.png", c.name, layout, liner,
                                                                        wear_coefficient_is_default(r.scene.wall_material.wear_coefficient)); }))
    not_written.push_back("liner.png");
  if (!io::draw_or_warn(out / "spectra.png", [&] { io::write_spectra_png(out / "spectra.png", c.name, spectra); }))
    not_written.push_back("spectra.png");
  // The liner in the mill frame, and beside each snapshot turned to the
  // mill's angle then (part 1 of the same times in charge.pvd).
  if (!io::write_or_warn(out / "liner.vtp",
                         [&] { io::write_mesh_vtp(out / "liner.vtp", io::liner_mesh(layout, &liner, 0.0, s.turning_s)); }))
    not_written.push_back("liner.vtp");
  {
    const std::vector<double> times = r.pvd.times();
    for (std::size_t k = 0; k < times.size(); ++k) {
      char name[64];
      std::snprintf(name, sizeof name, "snapshots/liner_%06zu.vtp", k);
      const bool written = io::write_or_warn(out / name, [&] {
        io::write_mesh_vtp(out / name, io::liner_mesh(layout, &liner, r.scene.mill_angle + d.omega * times[k], times[k]));
      });
      if (!written) {  // the rest would fail alike: one warning is enough
        std::fprintf(stderr, "warning: the liner beside the %zu later snapshots not written either\n",
                     times.size() - k - 1);
        not_written.push_back("snapshots/liner_*.vtp from " + std::string(name + 10));
        break;
      }
      r.pvd.add(times[k], name, 1);
    }
  }
  return not_written;
}

void print_run_results(const FinishedRun& r, const RunReport& rep, const std::vector<std::string>& not_written) {
  const MillCase& c = r.c;
  const MillDerived& d = r.d;
  const RunSummary& s = r.s;
  const fs::path& out = r.out;
  const MorrellResult& m = rep.m;
  const Errors& err = rep.err;
  const LinerLayout& layout = rep.layout;
  const SpectraReport& spectra = rep.spectra;
  const LinerReport& liner = rep.liner;
  const int per_rev = rep.per_rev, window_revs = rep.window_revs;
  const double rel_err = rep.rel_err;
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
    std::printf("                the charge's energy %s at %.4g W (its rate of change over the window: not yet in "
                "a steady motion, a longer warm-up helps); torque - dissipation - that rate: %+.2f %% of torque\n",
                s.energy_change_W < 0 ? "fell" : "rose", std::fabs(s.energy_change_W),
                100 * (s.torque_power_W - s.dissipation_power_W - s.energy_change_W) / s.torque_power_W);
  std::printf("per metre       torque %s, dissipation %s, torque %.4g N m/m over %.4g m%s\n",
              plus_minus(s.torque_power_W / c.length, err.power.sem / c.length, " W/m").c_str(),
              plus_minus(s.dissipation_power_W / c.length, err.dissipation.sem / c.length, " W/m").c_str(),
              s.torque_Nm / c.length, c.length, c.periodic ? " of periodic slice" : " between the end plates");
  const std::string batch = batch_words(err.power.batch_length, per_rev);
  if (rep.sem_kind == "none")
    std::printf("                no standard error: %s\n", rep.sem_why.c_str());
  else if (rep.sem_kind == "rough")
    std::printf("                \u00b1 a rough standard error, %s\n", rep.sem_why.c_str());
  else if (err.power.batches >= 2 && std::isfinite(err.power.lag1))
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
  const LinerConsumption& use = rep.consumption;
  std::string parts = c.lifter_rows > 0 ? "shell, lifters" : "shell";
  if (use.has_end_plates) parts += ", end plates";
  if (use.has_meshes) parts += ", mesh walls";
  std::printf("liner           impact %s, shear %s, wear %s (%s), worst %.3g mm per 1000 h (%s)\n",
              plus_minus(liner.impact_W, err.impact.sem, " W").c_str(),
              plus_minus(liner.shear_W, err.shear.sem, " W").c_str(),
              plus_minus(liner.wear_kg_per_h, err.wear.sem, " kg/h").c_str(), parts.c_str(),
              liner.worst_wear_mm_per_1000h,
              liner.worst_element >= 0 ? io::element_name(layout, liner.worst_element).c_str() : "none");
  if (liner.impact_kg_per_h > 0)
    std::printf("                wear by sliding %.4g kg/h, by impact %.4g kg/h (%.0f %%: %.4g W of strike energy at "
                "%g m3/J)\n",
                liner.sliding_kg_per_h, liner.impact_kg_per_h, 100 * liner.impact_kg_per_h / liner.wear_kg_per_h,
                liner.strike_W, r.scene.wall_material.impact_wear_coefficient);
  std::string others;
  if (use.has_end_plates)
    others += fmt_g(", end plates %.3g g/kWh (%.3g kg/h)", use.end_plates_g_kWh, use.end_plates_kg_h);
  if (use.has_meshes)
    others += fmt_g(" (mesh walls, counted in these by the part each stands for: %.3g g/kWh, %.3g kg/h)",
                    use.mesh_g_kWh, use.mesh_kg_h);
  std::printf("consumption     %s %.3g g/kWh (%.3g kg/h)%s, all %.3g g/kWh: liner steel worn per kWh of the %.4g W "
              "drawn\n",
              c.lifter_rows > 0 || liner.mesh_wear_kg_per_h_by_part[static_cast<int>(MeshPart::lifters)] > 0
                  ? "shell and lifters"
                  : "shell",
              use.shell_lifters_g_kWh, use.shell_lifters_kg_h,
              others.c_str(), use.all_g_kWh, use.power_W);
  if (use.relative)
    std::printf("                the wear figures are %s (the default stand-in, %g m3/(N m)); calibrate: life "
                "--calibrate-consumption G_PER_KWH, or materials.%s.wear_coefficient\n",
                kWearRelative, r.scene.wall_material.wear_coefficient, c.liner.c_str());
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
  // What this run wrote; a picture or mesh that could not be written was a
  // warning, and is named again here.
  std::string wrote, missing;
  for (const char* f : {"summary.json", "timeseries.csv", "charge.pvd", "power.png", "charge.png", "spectra.csv",
                        "spectra.png", "wear.csv", "lifter_wear.csv", "liner.vtp", "liner.png"}) {
    if (std::string(f) == "lifter_wear.csv" && c.lifter_rows == 0) continue;
    if (std::string(f) == "charge.pvd" && !(c.snapshot_interval > 0)) continue;  // no snapshots asked for
    if (std::find(not_written.begin(), not_written.end(), f) != not_written.end()) continue;
    wrote += (wrote.empty() ? "" : ", ") + std::string(f);
  }
  for (const std::string& f : not_written) missing += (missing.empty() ? "" : ", ") + f;
  std::printf("wrote           %s/{%s}%s\n", out.string().c_str(), wrote.c_str(),
              missing.empty() ? "" : ("; not written (see the warnings): " + missing).c_str());
}

}  // namespace mc::app
