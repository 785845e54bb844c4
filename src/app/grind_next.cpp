// Which batch test to run next (grind_next.h).
#include "app/grind_next.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "grind/circuit.h"
#include "grind/fit.h"
#include "grind/next_test.h"
#include "grind/pbm.h"
#include "io/atomic_file.h"
#include "io/batch_test_file.h"

namespace mc::app {

namespace fs = std::filesystem;
using namespace mc::grind;

namespace {

std::string times_text(const std::vector<double>& t) {
  std::string s;
  for (double x : t) s += (s.empty() ? "" : ",") + fmt::format("{:g}", x);
  return s;
}

std::string fixes_text(const std::vector<std::string>& f) {
  std::string s;
  for (const std::string& x : f) s += (s.empty() ? "" : " ") + x;
  return s;
}

// Split "a, b" (the [fitted] table's lists) at `sep`, each piece trimmed.
std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> out;
  for (std::size_t start = 0; start <= text.size();) {
    std::size_t end = text.find(sep, start);
    if (end == std::string::npos) end = text.size();
    std::string item = text.substr(start, end - start);
    item.erase(0, item.find_first_not_of(' '));
    item.erase(item.find_last_not_of(' ') + 1);
    if (!item.empty()) out.push_back(item);
    start = end + 1;
  }
  return out;
}

// The user's tests, as the ore's [fitted] table names them (each test's
// file and its run, relative to where --fit ran), read as --fit read them;
// the parameters it fitted. Empty, with `why`, where they cannot be had.
RealTests real_tests(const Ore& ore, std::string& why) {
  RealTests r;
  const ContactRecord& f = ore.fitted_under;
  const std::vector<std::string> files = split(f.test, ','), runs = split(f.run, ',');
  r.names = split(f.parameters, ',');
  if (files.empty() || files.size() != runs.size() || r.names.empty()) {
    why = "the ore's [fitted] table does not name its tests, their runs and parameters (test, run, parameters)";
    return {};
  }
  try {
    for (std::size_t k = 0; k < files.size(); ++k) {
      const io::BatchTestFile t = io::read_batch_test(files[k]);
      const io::Run run = io::read_run(runs[k], ore.model == RateModel::spectrum, ore.energy_basis);
      const double holdup = t.test.holdup_kg > 0 ? t.test.holdup_kg
                                                  : mill_holdup_kg(ore, run.porosity, run.filling, run.mill_volume);
      r.tests.push_back({t.test, run.spectrum, run.power_W, holdup, f.sieve_error_rho});
    }
    // The same tests as fitted, and in the same runs: the fitted ore's sum
    // of squares on them is the one its fit kept (ssr_held, with held
    // parameters), its rms residual the one kept (rms_residual_pp), each to
    // its 10 digits. A test file edited or a run made again since would
    // give the refits other data than the ore's covariance describes.
    double ss_pp = 0, n = 0;  // each test alone: its residuals in pp as measured
    for (TestInMill t : r.tests) {
      t.sieve_rho = 0;  // as measured
      for (double x : weighted_residuals(ore, {t})) ss_pp += x * x, ++n;
    }
    const double ssr_kept = ore.fitted_under.covariance.ssr_fit, ssr_now = weighted_ssr(ore, r.tests);
    const double rms_kept = f.rms_residual_pp, rms_now = n > 0 ? std::sqrt(ss_pp / n) : 0;
    auto differs = [](double now, double kept) { return kept > 0 && !(std::fabs(now - kept) <= 1e-6 * kept + 1e-9); };
    if (differs(ssr_now, ssr_kept) || differs(rms_now, rms_kept)) {
      why = fmt::format("the tests the ore was fitted to ([fitted] test = \"{}\", run = \"{}\") are not as they "
                        "were: the fitted ore's rms residual on them is {:.6g} pp here, {:.6g} at its fit "
                        "(rms_residual_pp); a test or a run changed since: fit the ore again",
                        f.test, f.run, rms_now, rms_kept);
      return {};
    }
  } catch (const std::exception& e) {
    why = "the tests the ore was fitted to cannot be read here ([fitted] test = \"" + f.test + "\": " + e.what() +
          "; run grind where --fit ran)";
    return {};
  }
  return r;
}

// An interval's end for a table: "" where it is open.
std::string end_text(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : ""; }

}  // namespace

NextPlan plan_next(const GrindOptions& o, const Ore& ore) {
  NextPlan p;
  if (o.next_tests.empty()) {
    if (!o.next_times.empty()) throw std::invalid_argument("--next-times: the times of a next test; give --next-test RUN");
    if (!o.next_for.empty()) throw std::invalid_argument("--next-for: the product a next test narrows; give --next-test RUN");
    return p;
  }
  p.asked = true;
  const FitCovariance& u = ore.fitted_under.covariance;
  if (!u.given)
    throw std::invalid_argument("--next-test: " + o.ore +
                                " keeps no covariance ([fitted] degrees_of_freedom): rank next tests for an ore "
                                "fitted with --fit");
  if (u.information.size() != u.names.size() + u.held.size())
    throw std::invalid_argument("--next-test: " + o.ore +
                                " keeps no information matrix ([fitted] information: fitted by an older millcharge): "
                                "fit it again with --fit");
  // The same check as the intervals': a fitted or held value, or any other key of its tables.
  const Staleness stale = covariance_staleness(ore);
  if (!stale.what.empty())
    throw std::invalid_argument("--next-test: " + o.ore + ": " + stale.what + " ([fitted] " + stale.key +
                                "): the ore was changed after its fit; its covariance describes the fitted ore only");
  for (const std::string& dir : o.next_tests) {
    if (std::find(p.runs.begin(), p.runs.end(), dir) != p.runs.end())
      throw std::invalid_argument("--next-test " + dir + ": given twice");
    if (!fs::is_regular_file(fs::path(dir) / "summary.json"))
      throw std::invalid_argument("--next-test " + dir +
                                  ": not a run folder: it has no summary.json (make it with millcharge run)");
    io::Run r;
    try {
      r = io::read_run(dir, ore.model == RateModel::spectrum, ore.energy_basis);
    } catch (const std::exception& e) {
      throw std::invalid_argument("--next-test " + dir + ": " + e.what());
    }
    const std::string changed = contact_mismatch(ore.fitted_under, r.contact);
    if (!changed.empty())
      throw std::invalid_argument("--next-test " + dir + ": its contact differs from the one the ore was fitted under (" +
                                  changed + "): a test there would fit another ore");
    p.runs.push_back(dir);
    p.holdup_kg.push_back(mill_holdup_kg(ore, r.porosity, r.filling, r.mill_volume));
    p.read.push_back(r);
  }
  p.draws = o.next_draws;
  p.refit = o.next_refit;
  p.seed = o.next_seed;
  p.real = real_tests(ore, p.refit_note);
  p.times = o.next_times.empty() ? std::vector<std::vector<double>>{{0.5, 1, 2, 4, 8}, {1, 2, 4, 8, 16}, {2, 4, 8, 16, 32}}
                                 : o.next_times;
  return p;
}

NextTarget next_target(const GrindOptions& o, const GrindNumbers& made) {
  NextTarget t;
  std::size_t per_products = 0;
  for (const Product& p : made.products) per_products += 4 + p.m.size();
  const std::string what = !o.next_for.empty()       ? o.next_for
                           : made.bond               ? std::string("wi")
                           : made.target             ? std::string("throughput")
                                                     : std::string("p80:1");
  if (what == "wi") {
    if (!made.bond) throw std::invalid_argument("--next-for wi: Bond's work index needs --bond P1_UM");
    t.index = per_products;
    t.name = "Bond Wi";
    t.unit = "kWh/t";
  } else if (what == "throughput") {
    if (!made.target) throw std::invalid_argument("--next-for throughput: the throughput at a target needs --target-p80 UM");
    t.index = per_products + (made.bond ? 3 : 0);
    t.name = "throughput at the target P80";
    t.unit = "t/h";
  } else if (what.rfind("p80:", 0) == 0) {
    char* stop = nullptr;
    const long k = std::strtol(what.c_str() + 4, &stop, 10);
    if (what.size() == 4 || *stop != '\0' || k < 1 || static_cast<std::size_t>(k) > made.products.size())
      throw std::invalid_argument(fmt::format("--next-for {}: p80:K with K from 1 to {} (the products, as listed)",
                                              what, made.products.size()));
    for (long i = 0; i + 1 < k; ++i) t.index += 4 + made.products[i].m.size();
    t.name = "P80 of " + made.products[k - 1].label;
    t.unit = "um";
  } else {
    throw std::invalid_argument("--next-for " + what + ": wi, throughput or p80:K");
  }
  return t;
}

NextRanking rank_next(const NextPlan& plan, const Ore& ore, const NextTarget& target, const GrindIntervals& ci,
                      const GrindNumbers& made, const std::function<double(const Ore&)>& number) {
  const auto t0 = std::chrono::steady_clock::now();
  NextRanking r;
  r.target = target;
  r.value = flatten(made)[target.index];
  // The interval now, as grind reports it.
  if (target.name == "Bond Wi") r.now = ci.work_index_kWh_t;
  else if (target.unit == "t/h") r.now = ci.throughput_t_h;
  else
    for (std::size_t k = 0, at = 0; k < made.products.size(); at += 4 + made.products[k].m.size(), ++k)
      if (at == target.index) r.now = ci.products[k].p80_um;
  r.width_now = r.now.hi - r.now.lo;
  const FitCovariance& u = ore.fitted_under.covariance;
  const Sensitivity s =
      sensitivities(ore, u, [&](const Ore& o) { return std::vector<double>{number(o)}; }, true).front();
  if (!s.ok || !r.now.valid())
    throw std::invalid_argument("--next-test: the " + target.name +
                                " has no interval at this ore (a held parameter's range reaches where the ore cannot "
                                "make it): nothing to rank by");
  std::vector<TestInMill> candidates;
  for (std::size_t m = 0; m < plan.runs.size(); ++m)
    for (const std::vector<double>& times : plan.times) {
      const TestInMill c{candidate_test(ore, times), plan.read[m].spectrum, plan.read[m].power_W, plan.holdup_kg[m],
                         ore.fitted_under.sieve_error_rho};
      const NextTestWidth w = expected_after(ore, u, s, c);
      NextRow row;
      row.run = plan.runs[m];
      row.times = times;
      row.expected = w.expected;
      row.width = w.width;
      row.fixes = w.fixes;
      r.rows.push_back(row);
      candidates.push_back(c);
    }
  // The linear order picks which candidates are refitted.
  std::vector<std::size_t> order(r.rows.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::isnan(r.rows[b].width) ? !std::isnan(r.rows[a].width) : r.rows[a].width < r.rows[b].width;
  });
  r.draws = plan.draws;
  r.seed = plan.seed;
  r.refit_note = plan.refit != 0 ? plan.refit_note : "";  // --next-refit 0: none asked for
  const auto t1 = std::chrono::steady_clock::now();
  if (plan.refit_note.empty() && plan.refit != 0) {
    // The same truths for every candidate, and the same scatter draws: the
    // candidates differ by the test, not by the luck of the draw.
    const std::vector<PlausibleTruth> truths = plausible_truths(ore, plan.real, plan.draws, plan.seed);
    const double scatter_pp = std::sqrt(interval_variance(u));
    std::vector<TestInMill> chosen;
    for (std::size_t k = 0; k < order.size() && (plan.refit < 0 || static_cast<int>(k) < plan.refit); ++k)
      chosen.push_back(candidates[order[k]]);
    const std::vector<RefitWidth> widths =
        refitted_widths(ore, plan.real, truths, chosen, number, scatter_pp, plan.seed);
    r.held_still = held_without_edges(ore);
    for (std::size_t k = 0; k < widths.size(); ++k) {
      NextRow& row = r.rows[order[k]];
      // The same figures, the wide share against the interval now.
      row.refit = summarise_draws(widths[k].per_draw, widths[k].failures, r.width_now);
      row.refitted = true;
      ++r.refitted;
    }
  }
  r.refit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  // The refitted first, by their draws (a candidate whose draws all failed
  // among them, last: it was refitted and gave nothing); then the linear.
  auto group = [](const NextRow& a) { return a.refitted ? 0 : std::isnan(a.width) ? 2 : 1; };
  std::vector<NextRow> ranked;
  for (std::size_t k : order) ranked.push_back(r.rows[k]);
  std::stable_sort(ranked.begin(), ranked.end(), [&](const NextRow& a, const NextRow& b) {
    if (group(a) != group(b)) return group(a) < group(b);
    if (group(a) == 0) return ranks_before(a.refit, b.refit);
    return group(a) == 1 && a.width < b.width;
  });
  r.rows = ranked;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

// A width for a table: "inf" where a draw gave none.
std::string width_text(double v) { return std::isinf(v) ? "inf" : fmt::format("{:.3g}", v); }

// The refitted width's cells: median, "[p10, p90]", wide share, mean of
// the finite, "converged/draws"; "-" where not refitted.
struct RefitCells {
  std::string median, range, wide, mean, fits;
};
RefitCells refit_cells(const NextRow& w) {
  if (!w.refitted) return {"-", "-", "-", "-", "-"};
  const RefitWidth& f = w.refit;
  return {width_text(f.median), fmt::format("[{}, {}]", width_text(f.p10), width_text(f.p90)),
          fmt::format("{:.0f} %", 100 * f.wide), f.converged > 0 ? width_text(f.mean) : "none",
          fmt::format("{}/{}", f.converged, f.draws)};
}

void print_next(const NextRanking& r) {
  std::printf("which test next, for the %s (%s): now %.4g%s, width %.3g; expected width after one more test (the "
              "usual 13 sieves, scatter as the fit's):\n",
              r.target.name.c_str(), r.target.unit.c_str(), r.value, bracket(r.now, 1, "{:.4g}").c_str(), r.width_now);
  std::printf("  %4s  %-28s %-18s %12s  %-20s %5s  %10s %5s  %12s  %s\n", "rank", "mill (run)", "times (min)",
              "median width", "10-90 % of draws", "wide", "mean (fin)", "fits", "linear width", "fixes held");
  for (std::size_t k = 0; k < r.rows.size(); ++k) {
    const NextRow& w = r.rows[k];
    const RefitCells c = refit_cells(w);
    std::printf("  %4zu  %-28s %-18s %12s  %-20s %5s  %10s %5s  %12.3g  %s\n", k + 1, w.run.c_str(),
                times_text(w.times).c_str(), c.median.c_str(), c.range.c_str(), c.wide.c_str(), c.mean.c_str(),
                c.fits.c_str(), w.width, w.fixes.empty() ? "-" : fixes_text(w.fixes).c_str());
  }
  if (r.refitted > 0)
    std::printf("  (median width: over %d simulated tests per candidate, each fitted with yours, a draw with no "
                "width counted as infinitely wide; wide: the share of draws wider than the interval now or with no "
                "width; mean (fin): over the draws with a width; seed %llu; linear width: at the fitted ore's best "
                "point; docs/grinding-next-test.md; %.2f s, %.2f s of it refits)\n",
                r.draws, static_cast<unsigned long long>(r.seed), r.seconds, r.refit_seconds);
  else
    std::printf("  (linear, at the fitted ore's best point: docs/grinding-next-test.md; %.2f s)\n", r.seconds);
  for (const NextRow& w : r.rows)
    if (w.refitted && w.refit.converged < w.refit.draws)
      std::printf("  note: %s %s: %d of %d draws gave no width (%s%s)\n", w.run.c_str(), times_text(w.times).c_str(),
                  w.refit.draws - w.refit.converged, w.refit.draws, w.refit.failures.front().c_str(),
                  w.refit.failures.size() > 1 ? "; the rest in grind.json" : "");
  if (!r.held_still.empty())
    std::printf("  note: the truths keep %s where the fit holds %s: the ore keeps no edge point that moves %s\n",
                fixes_text(r.held_still).c_str(), r.held_still.size() > 1 ? "them" : "it",
                r.held_still.size() > 1 ? "them" : "it");
  if (!r.refit_note.empty())
    std::printf("  note: no refits: %s; the ranking is the linear one\n", r.refit_note.c_str());
}

void write_next_csv(const fs::path& out, const NextRanking& r) {
  // inf: a median or percentile that a draw with no width reaches.
  auto cell = [](double v) { return std::isinf(v) ? std::string("inf") : end_text(v); };
  std::string csv =
      "rank,run,times_min,median_width,width_p10,width_p90,wide_share,mean_width_finite,draws_converged,draws,"
      "linear_lo,linear_hi,linear_width,width_now,fixes_held\n";
  for (std::size_t k = 0; k < r.rows.size(); ++k) {
    const NextRow& w = r.rows[k];
    const bool any = w.refitted && w.refit.draws > 0;
    csv += fmt::format("{},\"{}\",\"{}\",{},{},{},{},{},{},{},{},{},{},{:.6g},\"{}\"\n", k + 1, w.run,
                       times_text(w.times), any ? cell(w.refit.median) : "", any ? cell(w.refit.p10) : "",
                       any ? cell(w.refit.p90) : "", any ? fmt::format("{:.6g}", w.refit.wide) : "",
                       any ? end_text(w.refit.mean) : "", w.refitted ? std::to_string(w.refit.converged) : "",
                       w.refitted ? std::to_string(w.refit.draws) : "", end_text(w.expected.lo),
                       end_text(w.expected.hi), end_text(w.width), r.width_now, fixes_text(w.fixes));
  }
  io::write_file_atomic(out / "next_test.csv", csv);
}

nlohmann::ordered_json next_json(const NextRanking& r) {
  auto end = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  nlohmann::ordered_json j;
  j["product"] = r.target.name;
  j["unit"] = r.target.unit;
  j["value"] = r.value;
  j["interval_now"] = {end(r.now.lo), end(r.now.hi)};
  j["width_now"] = end(r.width_now);
  j["method"] = "median_width: the median width over every draw of a simulated candidate test, a draw whose fit "
                "failed or whose interval is open counted as infinitely wide (plausible truths along the profiles' "
                "and rays' directions, r = |z|/t of the way to the region's edge, z normal, uncut, within the ore "
                "file's ranges; Gaussian scatter as the fit's), each fitted with the real tests and its interval "
                "taken as grind takes it; width_10_90 likewise; wide_share: the draws wider than the interval now "
                "or with no width; mean_width_finite: the mean over the draws with a width; linear_width: the fit's "
                "information plus the candidate's J^T J / s^2 at the fitted ore's best point "
                "(docs/grinding-next-test.md)";
  j["draws"] = r.draws;
  j["seed"] = r.seed;
  j["refitted"] = r.refitted;
  if (!r.refit_note.empty()) j["no_refits"] = r.refit_note;
  if (!r.held_still.empty()) j["held_not_drawn"] = r.held_still;
  j["seconds"] = r.seconds;
  j["refit_seconds"] = r.refit_seconds;
  j["candidates"] = nlohmann::json::array();
  for (const NextRow& w : r.rows) {
    const bool any = w.refitted && w.refit.draws > 0;
    // inf (a draw with no width reached it) as the string "inf": JSON has no infinity.
    auto wide_end = [&](double v) { return std::isinf(v) ? nlohmann::json("inf") : end(v); };
    nlohmann::ordered_json c = {{"run", w.run}, {"times_min", w.times}};
    c["median_width"] = any ? wide_end(w.refit.median) : nlohmann::json();
    c["width_10_90"] = any ? nlohmann::json{wide_end(w.refit.p10), wide_end(w.refit.p90)} : nlohmann::json();
    c["wide_share"] = any ? nlohmann::json(w.refit.wide) : nlohmann::json();
    c["mean_width_finite"] = any ? end(w.refit.mean) : nlohmann::json();
    c["draws_converged"] = w.refitted ? nlohmann::json(w.refit.converged) : nlohmann::json();
    c["draws"] = w.refitted ? nlohmann::json(w.refit.draws) : nlohmann::json();
    c["draw_widths"] = w.refit.widths;
    c["draw_failures"] = w.refit.failures;
    c["linear_width"] = end(w.width);
    c["linear_interval"] = {end(w.expected.lo), end(w.expected.hi)};
    c["fixes_held"] = w.fixes;
    j["candidates"].push_back(c);
  }
  return j;
}

}  // namespace mc::app
