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
  for (std::size_t m = 0; m < plan.runs.size(); ++m)
    for (const std::vector<double>& times : plan.times) {
      const TestInMill c{candidate_test(ore, times), plan.read[m].spectrum, plan.read[m].power_W, plan.holdup_kg[m]};
      const NextTestWidth w = expected_after(ore, u, s, c);
      r.rows.push_back({plan.runs[m], times, w.expected, w.width, w.fixes});
    }
  std::stable_sort(r.rows.begin(), r.rows.end(), [](const NextRow& a, const NextRow& b) {
    return std::isnan(b.width) ? !std::isnan(a.width) : a.width < b.width;
  });
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

void print_next(const NextRanking& r) {
  std::printf("which test next, for the %s (%s): now %.4g%s, width %.3g; expected after one more test (the usual "
              "13 sieves, scatter as the fit's):\n",
              r.target.name.c_str(), r.target.unit.c_str(), r.value, bracket(r.now, 1, "{:.4g}").c_str(), r.width_now);
  std::printf("  %4s  %-28s %-18s %14s  %-24s %s\n", "rank", "mill (run)", "times (min)", "expected width",
              "expected interval", "fixes held");
  for (std::size_t k = 0; k < r.rows.size(); ++k) {
    const NextRow& w = r.rows[k];
    std::printf("  %4zu  %-28s %-18s %14.3g  %-24s %s\n", k + 1, w.run.c_str(), times_text(w.times).c_str(), w.width,
                bracket(w.expected, 1, "{:.4g}").c_str(), w.fixes.empty() ? "-" : fixes_text(w.fixes).c_str());
  }
  std::printf("  (linear, at the fitted ore: docs/grinding-intervals.md; %.2f s)\n", r.seconds);
}

void write_next_csv(const fs::path& out, const NextRanking& r) {
  std::string csv = "rank,run,times_min,expected_lo,expected_hi,expected_width,width_now,fixes_held\n";
  for (std::size_t k = 0; k < r.rows.size(); ++k) {
    const NextRow& w = r.rows[k];
    csv += fmt::format("{},\"{}\",\"{}\",{},{},{},{:.6g},\"{}\"\n", k + 1, w.run, times_text(w.times),
                       end_text(w.expected.lo), end_text(w.expected.hi), end_text(w.width), r.width_now,
                       fixes_text(w.fixes));
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
  j["method"] = "linear: the fit's information plus the candidate's J^T J / s^2 at the fitted ore "
                "(docs/grinding-intervals.md)";
  j["candidates"] = nlohmann::json::array();
  for (const NextRow& w : r.rows)
    j["candidates"].push_back({{"run", w.run},
                               {"times_min", w.times},
                               {"expected_interval", {end(w.expected.lo), end(w.expected.hi)}},
                               {"expected_width", end(w.width)},
                               {"fixes_held", w.fixes}});
  return j;
}

}  // namespace mc::app
