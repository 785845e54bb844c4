// `millcharge grind RUN --ore START --fit TEST` and `--bond P1 --fit-wi WI`:
// the ore calibrated through the laboratory mill's run (src/grind/fit.h).
// Everything is computed before the first file is written: a refused input
// or a fit that does not converge leaves nothing behind.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/grind.h"
#include "core/version.h"
#include "grind/bond.h"
#include "grind/circuit.h"
#include "grind/fit.h"
#include "grind/interval.h"
#include "grind/sieve_errors.h"
#include "grind/ore.h"
#include "io/atomic_file.h"
#include "io/batch_test_file.h"
#include "io/ore_file.h"
#include "io/png_plot.h"
#include "io/run_folder.h"

namespace mc::app {

namespace fs = std::filesystem;
using namespace mc::grind;

namespace {

// The scale of each rate model's rates: what a fit moves unless told.
std::string default_parameter(RateModel m) {
  return m == RateModel::spectrum ? "efficiency" : m == RateModel::energy ? "s1e_t_per_kWh" : "a_per_min";
}

void check_fit_options(const GrindOptions& o) {
  const std::string what = o.fit_tests.empty() ? "--fit-wi" : "--fit";
  if (!o.fit_tests.empty() && o.fit_wi_kWh_t > 0)
    throw std::invalid_argument("--fit and --fit-wi: give one (a batch test, or a Bond work index)");
  if (o.fit_wi_kWh_t > 0 && !(o.bond_p1_um > 0))
    throw std::invalid_argument("--fit-wi: give the test's closing sieve with --bond P1_UM");
  if (!o.fit_tests.empty() && o.bond_p1_um > 0)
    throw std::invalid_argument("--fit with --bond: a batch test is fitted alone; fit a work index with --fit-wi");
  if (!o.times_min.empty() || o.feed_rate_t_h > 0 || o.target_p80_um > 0 || o.classifier_d50c_um > 0 ||
      !o.scale_from.empty() || !o.next_tests.empty() || !o.next_times.empty() || !o.next_for.empty())
    throw std::invalid_argument(what +
                                ": fits the ore and writes it; grind the fitted ore in a second call (--time, "
                                "--feed-rate, --target-p80, --classifier, --scale-from and --next-test belong there)");
  if (o.fit_wi_kWh_t > 0 && !o.sieve_errors.empty())
    throw std::invalid_argument("--sieve-errors: says how --fit takes a batch test's sieve errors; --fit-wi fits a "
                                "work index, with no sieves");
  if (o.fit_wi_kWh_t > 0 && o.fit_params.size() > 1)
    throw std::invalid_argument("--fit-params: a work index is one number and fits one parameter, not " +
                                std::to_string(o.fit_params.size()));
}

ContactRecord record(const io::Run& run, const std::string& test, const std::string& run_dir,
                     const std::vector<std::string>& names, double rms_pp) {
  ContactRecord c = run.contact;
  c.energy_basis = run.spectrum.empty() ? "" : grind::basis_name(run.basis);  // the spectrum model's only
  c.test = test;
  c.run = run_dir;
  for (const std::string& n : names) c.parameters += (c.parameters.empty() ? "" : ",") + n;
  c.rms_residual_pp = rms_pp;
  return c;
}

std::string header(const std::string& what) {
  return std::string("# Fitted by millcharge ") + version() + " (" + build_commit() + "): " + what +
         "\n# The parameters hold under the contact law of [fitted] (docs/grinding-fit.md).\n";
}

// fit.png: measured points and fitted curves of cumulative passing; below,
// the residuals in percentage points.
void draw_fit(const fs::path& out, const std::string& name, const BatchTest& t, const BatchFit& f,
              const std::string& title) {
  static const std::uint32_t colours[] = {0x1f77b4, 0xd62728, 0x2ca02c, 0xff7f0e, 0x9467bd, 0x8c564b, 0xe377c2, 0x17becf};
  io::LinePlot psd, res;
  psd.title = title;
  psd.x_label = "sieve (um)";
  psd.y_label = "cumulative passing";
  psd.log_x = res.log_x = true;
  res.title = "residual: fitted - measured";
  res.x_label = "sieve (um)";
  res.y_label = "percentage points";
  const std::size_t ns = t.sieve_m.size();
  io::PlotSeries feed{"feed", {}, {}, 0x222222};
  feed.dashed = true;
  for (std::size_t k = 0; k < ns; ++k) feed.x.push_back(t.sieve_m[k] * 1e6), feed.y.push_back(t.feed_passing[k]);
  psd.series.push_back(feed);
  for (std::size_t i = 0; i < t.times_min.size(); ++i) {
    const std::uint32_t c = colours[i % 8];
    io::PlotSeries meas{fmt::format("{:g} min measured", t.times_min[i]), {}, {}, c};
    io::PlotSeries fitted{fmt::format("{:g} min fitted", t.times_min[i]), {}, {}, c};
    io::PlotSeries r{fmt::format("{:g} min", t.times_min[i]), {}, {}, c};
    meas.markers = r.markers = true;
    for (std::size_t k = 0; k < ns; ++k) {
      const double x = t.sieve_m[k] * 1e6;
      meas.x.insert(meas.x.end(), {x, std::nan("")});  // points only: NaN breaks the line
      meas.y.insert(meas.y.end(), {t.passing[i][k], std::nan("")});
      fitted.x.push_back(x), fitted.y.push_back(f.predicted[i][k]);
      r.x.push_back(x), r.y.push_back(100 * (f.predicted[i][k] - t.passing[i][k]));
    }
    psd.series.push_back(meas);
    psd.series.push_back(fitted);
    res.series.push_back(r);
  }
  res.ref_lines.push_back({0.0, 0, 0, 0x222222, true, ""});
  io::draw_or_warn(out / name, [&] { io::write_line_plots_png(out / name, {psd, res}); });
}

// The fit's folder (--out, else RUN/fit), made.
fs::path fit_folder(const GrindOptions& o) {
  const fs::path out = o.out.empty() ? fs::path(o.run_dir) / "fit" : fs::path(o.out);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw std::runtime_error(out.string() + ": cannot create: " + ec.message());
  return out;
}

// A held parameter's range in words: "from 0.87 to its bound (one-sided)",
// "open: ..." where the data bound it on neither side within the file's
// range. `kind` gets "one-sided", "open" or "two-sided".
std::string held_range(const HeldParameter& h, std::string* kind = nullptr) {
  const OreParameter* p = find_ore_parameter(h.name);
  const double span = p->hi - p->lo;
  const bool lo_end = h.lo <= p->lo + 1e-9 * span, hi_end = h.hi >= p->hi - 1e-9 * span;
  const bool on_lo = h.value <= p->lo + 1e-9 * span, on_hi = h.value >= p->hi - 1e-9 * span;
  std::string k = "two-sided", text;
  if (on_lo || on_hi) {
    k = (on_lo ? hi_end : lo_end) ? "open" : "one-sided";
    text = k == "open" ? fmt::format("open: the data do not bound it within the ore file's range ({:.6g} to {:.6g})",
                                     p->lo, p->hi)
                       : on_lo ? fmt::format("one-sided: from its bound {:.6g} to {:.6g}", h.value, h.hi)
                               : fmt::format("one-sided: from {:.6g} to its bound {:.6g}", h.lo, h.value);
  } else {
    if (lo_end && hi_end) k = "open";
    text = fmt::format("from {:.6g} to {:.6g}", h.lo, h.hi);
    if (lo_end || hi_end)
      text += lo_end && hi_end ? " (open: the whole of the ore file's range)"
                               : lo_end ? " (open below: the ore file's range ends there)"
                                        : " (open above: the ore file's range ends there)";
  }
  if (kind) *kind = k;
  return text;
}

const HeldParameter* held_entry(const FitCovariance& u, const std::string& name) {
  for (const HeldParameter& h : u.held)
    if (h.name == name) return &h;
  return nullptr;
}

nlohmann::ordered_json parameter_json(const FittedParameter& p, const FitCovariance& u) {
  nlohmann::ordered_json q;
  q["name"] = p.name;
  q["start"] = p.start;
  q["identified"] = p.identified;
  if (p.identified) {
    q["value"] = p.value;
    q["at_bound"] = p.at_bound;
    if (!p.at_bound) {  // on its bound it is not free: no standard error
      q["standard_error"] = p.se;
      q["relative_standard_error"] = p.value != 0 ? nlohmann::json(p.se / std::fabs(p.value)) : nlohmann::json();
    } else if (const HeldParameter* h = held_entry(u, p.name)) {  // held there: its range, one-sided or open
      std::string kind;
      held_range(*h, &kind);
      q["range_95"] = {h->lo, h->hi};
      q["range_95_kind"] = kind;
    }
  } else {
    q["held_at"] = p.value;
    q["why"] = p.why;
  }
  return q;
}

// The covariance of the fitted variables, their correlations, and the
// held parameters' ranges.
nlohmann::ordered_json covariance_json(const FitCovariance& u) {
  nlohmann::ordered_json j;
  std::vector<std::string> vars;
  for (const std::string& n : u.names) vars.push_back(variable_name(n));
  j["variables"] = vars;
  j["values"] = u.values;
  j["matrix"] = u.matrix;
  std::vector<std::vector<double>> r = u.matrix;
  for (std::size_t a = 0; a < r.size(); ++a)
    for (std::size_t b = 0; b < r.size(); ++b) r[a][b] = u.matrix[a][b] / std::sqrt(u.matrix[a][a] * u.matrix[b][b]);
  j["correlation"] = r;
  j["residual_variance_pp2"] = u.residual_variance_pp2;
  j["degrees_of_freedom"] = u.dof;
  // The intervals' ν and s²: every parameter named, held ones too, fitted at S_min.
  j["interval_degrees_of_freedom"] = interval_dof(u);
  const double s2 = interval_variance(u);
  j["interval_variance_pp2"] = std::isfinite(s2) ? nlohmann::json(s2) : nlohmann::json();
  j["held"] = nlohmann::json::array();
  for (const HeldParameter& h : u.held) {
    std::string kind;
    held_range(h, &kind);
    j["held"].push_back({{"name", h.name}, {"value", h.value}, {"lo", h.lo}, {"hi", h.hi}, {"kind", kind}});
  }
  j["edge_points"] = u.edges.size();
  j["correlated"] = nlohmann::json::array();
  for (const Correlated& c : correlated_pairs(u))
    j["correlated"].push_back({{"variables", {c.a, c.b}}, {"r", c.r}});
  return j;
}

void print_covariance(const FitCovariance& u) {
  if (u.names.size() > 1) {
    std::printf("  correlation of the fitted variables:\n");
    for (std::size_t a = 0; a < u.names.size(); ++a) {
      std::string row;
      for (std::size_t b = 0; b < u.names.size(); ++b)
        row += fmt::format(" {:6.3f}", u.matrix[a][b] / std::sqrt(u.matrix[a][a] * u.matrix[b][b]));
      std::printf("    %-22s%s\n", variable_name(u.names[a]).c_str(), row.c_str());
    }
  }
  for (const Correlated& c : correlated_pairs(u))
    std::printf("  note: %s and %s are correlated at r = %+.4f: the tests fix only their combination, not each\n",
                c.a.c_str(), c.b.c_str(), c.r);
  for (const HeldParameter& h : u.held)
    std::printf("  %-16s held at %.6g; 95 %% range %s (the free ones refitted there%s)\n", h.name.c_str(), h.value,
                held_range(h).c_str(),
                u.held.size() > 1 ? " with the other held ones" : "");
  if (!u.held.empty() && u.best.held.size() == u.held.size()) {
    std::string at;
    for (std::size_t k = 0; k < u.held.size(); ++k)
      at += fmt::format("{}{} {:.6g}", k ? ", " : "", u.held[k].name, u.best.held[k]);
    std::printf("  the held parameters fit the data best at %s (the free ones refitted there; S %.4g there, %.4g "
                "where they are held, the limit %.4g): the intervals are built around it\n",
                at.c_str(), u.ssr_best, u.ssr_fit, profile_limit(u.ssr_best, interval_dof(u)));
    if (const std::string out = outside_region(u); !out.empty()) std::printf("  note: %s\n", out.c_str());
  }
}

// One batch test of a fit and the run of the mill it was made in.
struct TestRun {
  std::string path, run_dir;
  io::BatchTestFile file;
  io::Run run;
  double holdup_kg = 0;
};

bool same_data(const BatchTest& a, const BatchTest& b) {
  return a.sieve_m == b.sieve_m && a.feed_passing == b.feed_passing && a.times_min == b.times_min &&
         a.passing == b.passing;
}

// The tests of --fit, each with its run (its `run` key, relative to the
// file; else RUN), checked before anything is fitted: every message names
// the file and the key.
std::vector<TestRun> read_tests(const GrindOptions& o, const Ore& start) {
  std::vector<TestRun> tests;
  for (const std::string& path : o.fit_tests) {
    TestRun t;
    t.path = path;
    t.file = io::read_batch_test(path);
    for (const TestRun& u : tests) {
      std::error_code e1, e2;
      if (fs::weakly_canonical(path, e1) == fs::weakly_canonical(u.path, e2))
        throw std::invalid_argument("--fit " + path + ": the same test twice");
      if (same_data(t.file.test, u.file.test))
        throw std::invalid_argument("--fit " + path + ": the same test as " + u.path +
                                    " (sieve_mm, feed and every product alike): the same test twice");
    }
    t.run_dir = t.file.run.empty() ? o.run_dir : (fs::path(path).parent_path() / t.file.run).lexically_normal().string();
    tests.push_back(t);
  }
  for (TestRun& t : tests) {
    const BatchTest& bt = t.file.test;
    if (bt.sieve_m.front() > start.sizes.top_m.front() * (1 + 1e-9) ||
        bt.sieve_m.back() < start.sizes.top_m.back() * (1 - 1e-9))
      throw std::invalid_argument(fmt::format(
          "{}: sieve_mm: {:g} to {:g} mm lies outside the ore's size classes ({:g} to {:g} mm): the tests fitted "
          "together share the ore's one series (sizes.top_mm, sizes.classes)",
          t.path, bt.sieve_m.front() * 1e3, bt.sieve_m.back() * 1e3, start.sizes.top_m.front() * 1e3,
          start.sizes.top_m.back() * 1e3));
    if (t.file.run.empty()) {
      t.run = io::read_run(o.run_dir, start.model == RateModel::spectrum, start.energy_basis);
    } else {
      if (!fs::is_regular_file(fs::path(t.run_dir) / "summary.json"))
        throw std::invalid_argument(t.path + ": run: \"" + t.file.run + "\" (" + t.run_dir +
                                    ") is not a run folder: it has no summary.json (make it with millcharge run)");
      try {
        t.run = io::read_run(t.run_dir, start.model == RateModel::spectrum, start.energy_basis);
      } catch (const std::exception& e) {
        throw std::invalid_argument(t.path + ": run: \"" + t.file.run + "\": " + e.what());
      }
    }
    if (!(bt.noise_pp > 0) && tests.size() > 1)
      for (const TestRun& u : tests)
        if (u.file.test.noise_pp > 0)
          throw std::invalid_argument(t.path + ": noise_pp: 0 beside " + u.path +
                                      "'s scatter: tests fitted together count by 1/noise_pp^2, infinite at 0; give "
                                      "the test the scatter of its sieving");
    t.holdup_kg = bt.holdup_kg > 0 ? bt.holdup_kg
                                   : mill_holdup_kg(start, t.run.porosity, t.run.filling, t.run.mill_volume);
    // One ore holds under one contact: tests through runs of other contacts cannot share it.
    const std::string changed = contact_mismatch(tests.front().run.contact, t.run.contact);
    if (!changed.empty())
      throw std::invalid_argument(t.path + ": run: \"" + t.run_dir + "\": its contact differs from " +
                                  tests.front().run_dir + "'s (" + changed +
                                  "): tests fitted together must be run under one contact");
  }
  return tests;
}

int fit_batch(const GrindOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const Ore start = io::read_ore(o.ore);
  const std::vector<TestRun> tests = read_tests(o, start);
  const std::vector<std::string> names =
      o.fit_params.empty() ? std::vector<std::string>{default_parameter(start.model)} : o.fit_params;
  std::vector<TestInMill> in_mills;
  for (const TestRun& t : tests) in_mills.push_back({t.file.test, t.run.spectrum, t.run.power_W, t.holdup_kg});
  const SieveErrors mode = parse_sieve_errors(o.sieve_errors.empty() ? "auto" : o.sieve_errors).value();
  SieveErrorFit sf = fit_with_sieve_errors(start, in_mills, names, mode);
  in_mills = sf.tests;  // with the sieve errors' rho: the covariance and every refit read them so
  BatchFit& fit = sf.fit;
  const std::vector<double> weights = test_weights(in_mills);  // on the residuals: the squares count by their square
  std::string test_names, run_names;
  for (const TestRun& t : tests) {
    test_names += (test_names.empty() ? "" : ", ") + t.path;
    run_names += (run_names.empty() ? "" : ", ") + t.run_dir;
  }
  const io::Run& run = tests.front().run;
  fit.ore.fitted_under = record(run, test_names, run_names, names, fit.rms_pp);
  // r1 of the residuals taken as independent (what says whether they correlate), and rho.
  fit.ore.fitted_under.residual_lag1 = sf.r1_independent;
  fit.ore.fitted_under.sieve_error_rho = sf.rho;
  // What the fit leaves open, kept with the ore for the intervals of its products.
  const auto t_cov = std::chrono::steady_clock::now();
  fit.ore.fitted_under.covariance = fit_covariance(fit, in_mills);
  const double cov_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_cov).count();
  // Its tables as fitted: a later hand edit of any key leaves the covariance stale.
  fit.ore.fitted_under.covariance.tables_hash = io::ore_tables_hash(fit.ore);
  const FitCovariance& cov = fit.ore.fitted_under.covariance;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // Everything computed; now the files.
  const fs::path out = fit_folder(o);
  io::write_file_atomic(out / "ore_fitted.toml",
                        io::ore_toml(fit.ore, header((tests.size() > 1 ? "fitted to the batch tests " : "fitted to the "
                                                                                                          "batch test ") +
                                                     test_names + " through the run" + (tests.size() > 1 ? "s " : " ") +
                                                     run_names)));
  // Several tests: a first column names each row's.
  std::string csv = std::string(tests.size() > 1 ? "test," : "") +
                    "time_min,sieve_um,measured_passing,fitted_passing,residual_pp\n";
  for (std::size_t m = 0; m < tests.size(); ++m) {
    const BatchTest& t = tests[m].file.test;
    const auto& pred = fit.predicted_by_test[m];
    for (std::size_t i = 0; i < t.times_min.size(); ++i)
      for (std::size_t k = 0; k < t.sieve_m.size(); ++k)
        csv += (tests.size() > 1 ? "\"" + tests[m].path + "\"," : std::string()) +
               fmt::format("{:g},{:.6g},{:.8f},{:.8f},{:.6f}\n", t.times_min[i], t.sieve_m[k] * 1e6, t.passing[i][k],
                           pred[i][k], 100 * (pred[i][k] - t.passing[i][k]));
  }
  io::write_file_atomic(out / "fit_residuals.csv", csv);
  nlohmann::ordered_json j;
  j["test"] = tests.front().path;
  j["run"] = run.title;
  j["ore"] = start.name;
  j["model"] = start.model == RateModel::spectrum ? "spectrum" : start.model == RateModel::energy ? "energy" : "austin";
  j["power_W"] = run.power_W;
  j["holdup_kg"] = tests.front().holdup_kg;
  j["tests"] = nlohmann::json::array();
  for (std::size_t m = 0; m < tests.size(); ++m)
    j["tests"].push_back({{"file", tests[m].path},
                          {"run", tests[m].run_dir},
                          {"power_W", tests[m].run.power_W},
                          {"holdup_kg", tests[m].holdup_kg},
                          {"noise_pp", tests[m].file.test.noise_pp},
                          {"weight", std::pow(weights[m], 2)},
                          {"rms_residual_pp", fit.rms_by_test[m]}});
  j["data"] = fit.data;
  j["parameters"] = nlohmann::json::array();
  for (const FittedParameter& p : fit.parameters) j["parameters"].push_back(parameter_json(p, cov));
  j["free_parameters"] = fit.free;
  j["rms_residual_pp"] = fit.rms_pp;
  // Sieve errors correlated along the sieves, and how the fit took them
  // (grind/sieve_errors.h; docs/grinding-intervals.md, "Sieve errors
  // correlated between sieves").
  j["residual_lag1"] = std::isfinite(sf.r1_independent) ? nlohmann::json(sf.r1_independent) : nlohmann::json();
  j["residuals_correlated"] = sf.r1_independent > kSwitchToCorrelated;
  j["sieve_errors"] = {{"asked", sieve_errors_name(mode)},
                       {"model", sf.correlated ? "correlated" : "independent"},
                       {"rho", sf.rho},
                       {"rounds", sf.rounds},
                       {"settled", sf.settled},
                       {"at_cap", sf.at_cap},
                       {"failed", sf.why_failed.empty() ? nlohmann::json() : nlohmann::json(sf.why_failed)},
                       {"residual_lag1_whitened", sf.correlated && std::isfinite(fit.residual_r1)
                                                      ? nlohmann::json(whitened_lag1(fit, sf.rho))
                                                      : nlohmann::json()}};
  double noise_pp = 0;
  for (const TestRun& t : tests) noise_pp = std::max(noise_pp, t.file.test.noise_pp);
  // With nothing free the residual says how far the ore as it stands is
  // from the test, not how well a fit did: no verdict then.
  j["within_twice_noise"] = fit.free > 0 ? nlohmann::json(fit.rms_pp <= 2 * noise_pp) : nlohmann::json();
  j["iterations"] = fit.iterations;
  j["evaluations"] = fit.evaluations;
  j["refits"] = fit.refits;
  j["condition"] = std::isfinite(fit.condition) ? nlohmann::json(fit.condition) : nlohmann::json();
  j["covariance"] = covariance_json(cov);
  j["seconds"] = seconds;
  j["covariance_seconds"] = cov_seconds;
  j["contact"] = {{"law", run.contact.law},
                  {"restitution", run.contact.restitution},
                  {"friction", run.contact.friction},
                  {"stiffness_N_m", run.contact.stiffness_N_m},
                  {"youngs_modulus_Pa", run.contact.youngs_modulus_Pa}};
  j["build"] = {{"version", version()}, {"commit", build_commit()}};
  io::write_file_atomic(out / "fit.json", j.dump(2) + "\n");
  std::string pictures;
  for (std::size_t m = 0; m < tests.size(); ++m) {
    BatchFit one = fit;
    one.predicted = fit.predicted_by_test[m];
    const std::string name = m == 0 ? "fit.png" : fmt::format("fit_{}.png", m + 1);
    pictures += ", " + name;
    const std::string& title = tests[m].file.title;
    draw_fit(out, name, tests[m].file.test, one,
             fmt::format("{}: fitted through the run ({:.1f} W), rms {:.3g} pp",
                         title.empty() ? std::string("batch test") : title, tests[m].run.power_W, fit.rms_by_test[m]));
  }
  bool any_at_bound = false;
  for (const FittedParameter& p : fit.parameters) any_at_bound = any_at_bound || p.at_bound;
  if (!o.quiet) {
    for (std::size_t m = 0; m < tests.size(); ++m) {
      const BatchTest& t = tests[m].file.test;
      if (tests.size() == 1)
        std::printf("batch test %s: %zu times x %zu sieves, %d data; run %.1f W, hold-up %.4g kg, %s contact\n",
                    tests[m].path.c_str(), t.times_min.size(), t.sieve_m.size(), fit.data, tests[m].run.power_W,
                    tests[m].holdup_kg, tests[m].run.contact.law.c_str());
      else
        std::printf("batch test %s: %zu times x %zu sieves; run %s, %.1f W, hold-up %.4g kg; rms residual %.4g pp\n",
                    tests[m].path.c_str(), t.times_min.size(), t.sieve_m.size(), tests[m].run_dir.c_str(),
                    tests[m].run.power_W, tests[m].holdup_kg, fit.rms_by_test[m]);
    }
    if (tests.size() > 1)
      std::printf("  %zu tests fitted together, %d data, %s contact\n", tests.size(), fit.data,
                  run.contact.law.c_str());
    for (const FittedParameter& p : fit.parameters) {
      if (p.identified && p.at_bound)
        std::printf("  %-16s %.6g on its bound, held there: the test wants it past the ore file's range (no "
                    "standard error)   start %.6g\n",
                    p.name.c_str(), p.value, p.start);
      else if (p.identified)
        std::printf("  %-16s %.6g +- %.2g (%.2g %%)   start %.6g\n", p.name.c_str(), p.value, p.se,
                    100 * p.se / std::fabs(p.value), p.start);
      else
        std::printf("  %-16s unidentified: %s (%.6g)\n", p.name.c_str(), p.why.c_str(), p.value);
    }
    print_covariance(cov);
    if (fit.free == 0)
      std::printf("  no parameter left free: every one is held, the residuals are the starting ore's\n");
    std::printf("  rms residual %.4g pp; %d iterations, %d evaluations, %.2f s (%.2f s of it what the fit leaves "
                "open: covariance, profiles)\n",
                fit.rms_pp, fit.iterations, fit.evaluations, seconds, cov_seconds);
    if (std::isfinite(sf.r1_independent))
      std::printf("  residuals' lag-1 autocorrelation along the sieves r1 = %.3f%s\n", sf.r1_independent,
                  sf.correlated ? " (fitted as independent)" : "");
    if (fit.free > 0 && !sieve_errors_note(sf.r1_independent, sf.rho, mode).empty())
      std::printf("  %s\n", sieve_errors_note(sf.r1_independent, sf.rho, mode).c_str());
    for (const std::string& w : sieve_errors_warnings(sf)) std::printf("  %s\n", w.c_str());
    if (fit.rms_pp > 2 * noise_pp && fit.free > 0)
      std::printf("  note: the rms residual is above twice the test's noise_pp (%g pp): the model cannot reproduce "
                  "the test with these parameters free%s\n",
                  noise_pp, any_at_bound ? " (one is held on its bound)" : "");
    std::printf("wrote %s/{ore_fitted.toml, fit_residuals.csv, fit.json%s}\n", out.string().c_str(), pictures.c_str());
  }
  return 0;
}

int fit_wi(const GrindOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const Ore start = io::read_ore(o.ore);
  Ore on_p1 = start;
  put_sieve_on_class_top(on_p1, o.bond_p1_um * 1e-6);
  if (!(o.bond_p1_um * 1e-6 < on_p1.f80_m))
    throw std::invalid_argument(fmt::format("--bond {:g}: the closing sieve must lie below the feed's F80 ({:.1f} um)",
                                            o.bond_p1_um, on_p1.f80_m * 1e6));
  check_bond_sieve(on_p1.sizes, o.bond_p1_um * 1e-6);
  const io::Run run = io::read_run(o.run_dir, start.model == RateModel::spectrum, start.energy_basis);
  if (!(run.speed_rpm > 0)) throw std::invalid_argument(o.run_dir + "/summary.json: speed_rpm missing");
  const std::string name = o.fit_params.empty() ? default_parameter(start.model) : o.fit_params.front();
  const WiFit w = fit_work_index(on_p1, run.spectrum, run.power_W, run.speed_rpm, o.bond_p1_um * 1e-6, o.fit_wi_kWh_t,
                                 name);
  Ore fitted = start;
  find_ore_parameter(name)->set(fitted, w.value);
  fitted.fitted_under = record(run, fmt::format("Bond Wi {:g} kWh/t at P1 {:g} um", o.fit_wi_kWh_t, o.bond_p1_um),
                               o.run_dir, {name}, 0);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  const fs::path out = fit_folder(o);
  io::write_file_atomic(out / "ore_fitted.toml",
                        io::ore_toml(fitted, header(fmt::format("{} set so that Bond's test at P1 {:g} um gives Wi {:g} "
                                                                "kWh/t in the run {}",
                                                                name, o.bond_p1_um, o.fit_wi_kWh_t, o.run_dir))));
  nlohmann::ordered_json j;
  j["target_work_index_kWh_t"] = o.fit_wi_kWh_t;
  j["P1_um"] = o.bond_p1_um;
  j["parameter"] = name;
  j["start"] = w.start;
  j["value"] = w.value;
  j["value_per_kWh_t"] = w.dvalue_dwi;
  j["work_index_kWh_t"] = w.bond.wi_kWh_t;
  j["Gbp_g_per_rev"] = w.bond.gbp_g_rev;
  j["P80_um"] = w.bond.p80_um;
  j["F80_um"] = w.bond.f80_um;
  j["cycles"] = w.bond.cycles;
  j["evaluations"] = w.evaluations;
  j["seconds"] = seconds;
  j["build"] = {{"version", version()}, {"commit", build_commit()}};
  io::write_file_atomic(out / "fit.json", j.dump(2) + "\n");
  if (!o.quiet) {
    std::printf("Bond test at P1 %g um in the run (%.1f W, %.0f rpm, %s contact): Wi %g kWh/t wanted\n", o.bond_p1_um,
                run.power_W, run.speed_rpm, run.contact.law.c_str(), o.fit_wi_kWh_t);
    std::printf("  %s %.6g (start %.6g): Wi %.4f kWh/t, Gbp %.3f g/rev, P80 %.0f um, %d cycles\n", name.c_str(),
                w.value, w.start, w.bond.wi_kWh_t, w.bond.gbp_g_rev, w.bond.p80_um, w.bond.cycles);
    std::printf("  a work index 1 kWh/t higher would move %s by %.3g (%.2g %%); %d Bond tests, %.2f s\n", name.c_str(),
                w.dvalue_dwi, 100 * w.dvalue_dwi / w.value, w.evaluations, seconds);
    std::printf("  one number fixes one parameter: the rest (how the rates fall with size, the appearance function) "
                "stay the starting ore's\n");
    std::printf("wrote %s/{ore_fitted.toml, fit.json}\n", out.string().c_str());
  }
  return 0;
}

}  // namespace

int cmd_grind_fit(const GrindOptions& o) {
  check_fit_options(o);
  return o.fit_tests.empty() ? fit_wi(o) : fit_batch(o);
}

}  // namespace mc::app
