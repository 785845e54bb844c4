// The population balance (src/grind/pbm.h): the batch solver against
// Reid's closed form, mass balances, the continuous mill's limits, the
// appearance function, the breakage probability and the size read-outs.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "grind/pbm.h"

using namespace mc::grind;

namespace {

struct Mill {
  SizeSeries s = geometric_series(3.35e-3, std::sqrt(2.0), 20);
  std::vector<std::vector<double>> b = breakage_matrix(s, AustinBreakage{0.55, 1.2, 4.0});
  // Austin's rates with a maximum near 2 mm, per minute.
  std::vector<double> S = austin_rates(s, AustinRates{0.9, 1.1, 2.5e-3, 2.5});
  std::vector<double> feed = [] {
    std::vector<double> m(20, 0.0);
    m[0] = 0.6, m[1] = 0.3, m[2] = 0.1;
    return m;
  }();
};

double sum(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

}  // namespace

TEST_CASE("the appearance function's columns sum to one and Austin's B is met at the class tops", "[grind]") {
  Mill m;
  for (int j = 0; j + 1 < m.s.size(); ++j) {
    double c = 0;
    for (int i = j + 1; i < m.s.size(); ++i) c += m.b[i][j];
    CHECK(c == Approx(1.0).margin(1e-12));
    CHECK(m.b[j][j] == 0.0);
  }
  // Cumulative from the sink up to class 3's top, for breakage of class 0:
  // B(x_3 / x_1) = 0.55 (2^-1)^1.2 + 0.45 (2^-1)^4.
  double below = 0;
  for (int i = 3; i < m.s.size(); ++i) below += m.b[i][0];
  const double u = m.s.top_m[3] / m.s.top_m[1];
  CHECK(below == Approx(0.55 * std::pow(u, 1.2) + 0.45 * std::pow(u, 4.0)).epsilon(1e-12));
}

TEST_CASE("batch grinding: the solver against Reid's closed form, and mass kept", "[grind]") {
  Mill m;
  double worst = 0, worst_mass = 0;
  for (double t : {0.5, 2.0, 8.0, 30.0}) {  // minutes
    const std::vector<double> rk = batch_grind(m.feed, m.S, m.b, t);
    const std::vector<double> reid = reid_batch(m.feed, m.S, m.b, t);
    for (std::size_t i = 0; i < rk.size(); ++i) {
      INFO("t " << t << " class " << i << " solver " << rk[i] << " Reid " << reid[i]);
      const double err = std::fabs(rk[i] - reid[i]) / std::max(reid[i], 1e-6);
      CHECK(err <= 1e-8);
      worst = std::max(worst, err);
    }
    worst_mass = std::max({worst_mass, std::fabs(sum(rk) - 1), std::fabs(sum(reid) - 1)});
    CHECK(sum(rk) == Approx(1.0).margin(1e-12));
    CHECK(sum(reid) == Approx(1.0).margin(1e-12));
  }
  // The top class decays at its own rate alone.
  CHECK(batch_grind(m.feed, m.S, m.b, 2.0)[0] == Approx(0.6 * std::exp(-2.0 * m.S[0])).epsilon(1e-9));
  std::printf("batch grind vs Reid: worst relative error %.2e, worst mass error %.2e\n", worst, worst_mass);
}

TEST_CASE("a continuous mill: one tank's closed form, plug flow in the limit of many tanks", "[grind]") {
  Mill m;
  const double tau = 3.0;
  const std::vector<double> one = continuous_grind(m.feed, m.S, m.b, tau, 1);
  CHECK(one[0] == Approx(0.6 / (1 + tau * m.S[0])).epsilon(1e-12));
  CHECK(sum(one) == Approx(1.0).margin(1e-12));
  const std::vector<double> many = continuous_grind(m.feed, m.S, m.b, tau, 4000);
  const std::vector<double> plug = reid_batch(m.feed, m.S, m.b, tau);
  for (std::size_t i = 0; i < plug.size(); ++i) CHECK(many[i] == Approx(plug[i]).margin(2e-4));
  // Mixing grinds less of the top class than plug flow at the same tau.
  CHECK(one[0] > plug[0]);
}

TEST_CASE("Whiten's classification curve: C at the fines, C/2 at d50c, none of the coarse", "[grind]") {
  for (double beta : {0.0, 0.5}) {
    INFO("beta " << beta);
    WhitenClassifier c{150e-6, 3.0, 0.2, beta};
    CHECK(c.to_overflow(150e-6) == Approx(0.8 / 2).epsilon(1e-9));
    CHECK(c.to_overflow(1e-3) < 1e-3);
    CHECK(c.to_overflow(5e-3) < 1e-30);
    if (beta == 0) {
      CHECK(c.beta_star() == 1.0);
      CHECK(c.to_overflow(1e-9) == Approx(0.8).epsilon(1e-5));
      // The curve's form at one point: E = C (e^a - 1) / (e^(a y) + e^a - 2).
      const double ea = std::exp(3.0);
      CHECK(c.to_overflow(300e-6) == Approx(0.8 * (ea - 1) / (std::exp(6.0) + ea - 2)).epsilon(1e-12));
    } else {
      // The fish hook: fines below a size report less to the overflow than
      // somewhat larger ones.
      CHECK(c.to_overflow(1e-6) < c.to_overflow(60e-6));
    }
  }
  // Sharper: closer to a step at d50c.
  const WhitenClassifier blunt{150e-6, 1.0}, sharp{150e-6, 8.0};
  CHECK(sharp.to_overflow(100e-6) > blunt.to_overflow(100e-6));
  CHECK(sharp.to_overflow(220e-6) < blunt.to_overflow(220e-6));
}

TEST_CASE("a closed circuit: the two-class closed form, the mass kept, the open mill in the limit", "[grind]") {
  // One class and the sink, a perfect-mixing mill, the fresh feed F all in
  // the class. With Q the mill's whole feed, tau = H/Q, e_c and e_s the
  // shares of the class and the sink to the overflow, the class leaves the
  // mill at C = F / (S tau + e_c), and the overflow carries F out:
  // Q = C + (F - e_c C) / e_s. Solved here by bisection on Q.
  SizeSeries two;
  two.top_m = {1e-3, 0.5e-3};
  const std::vector<std::vector<double>> b = {{0.0, 0.0}, {1.0, 0.0}};
  const double S = 0.5, H = 0.02, F = 0.3;  // per min, t, t/h
  const WhitenClassifier c{two.mid_m(0) / 1.1, 4.0};
  const double ec = c.to_overflow(two.mid_m(0)), es = c.to_overflow(two.mid_m(1));
  REQUIRE(ec < 0.5);
  REQUIRE(es > 0.5);
  auto class_out = [&](double Q) { return F / (S * H * 60 / Q + ec); };
  auto g = [&](double Q) { return Q - (class_out(Q) + (F - ec * class_out(Q)) / es); };
  double lo = F, hi = 1e3 * F;
  REQUIRE(g(lo) < 0);
  REQUIRE(g(hi) > 0);
  for (int k = 0; k < 300; ++k) (g(0.5 * (lo + hi)) < 0 ? lo : hi) = 0.5 * (lo + hi);
  const double Q = 0.5 * (lo + hi), C = class_out(Q);
  const ClosedCircuit cc = closed_circuit(two, {F, 0.0}, {S, 0.0}, b, H, 1, c);
  REQUIRE(cc.converged);
  CHECK(cc.underflow[0] == Approx((1 - ec) * C).epsilon(1e-9));
  CHECK(cc.underflow[1] == Approx((1 - es) * (Q - C)).epsilon(1e-9));
  CHECK(cc.circulating_load == Approx((Q - F) / F).epsilon(1e-9));
  CHECK(cc.residence_min == Approx(H / Q * 60).epsilon(1e-9));
  CHECK(sum(cc.product) == Approx(F).epsilon(1e-10));  // the overflow carries the fresh feed out

  // A real series: mass kept, finer than the open mill at the same feed, and
  // the open mill when the cut lies far above the feed.
  Mill m;
  const double H2 = 0.05, F2 = 0.4;
  std::vector<double> fresh(m.feed);
  for (double& f : fresh) f *= F2;
  const ClosedCircuit closed = closed_circuit(m.s, fresh, m.S, m.b, H2, 1, WhitenClassifier{300e-6, 3.0});
  REQUIRE(closed.converged);
  CHECK(sum(closed.product) == Approx(F2).epsilon(1e-10));
  CHECK(closed.circulating_load > 0.5);
  std::vector<double> open = continuous_grind(fresh, m.S, m.b, H2 / F2 * 60, 1);
  CHECK(passing_size(m.s, closed.product, 0.8) < passing_size(m.s, open, 0.8));
  const ClosedCircuit wide = closed_circuit(m.s, fresh, m.S, m.b, H2, 1, WhitenClassifier{1.0, 50.0});
  CHECK(wide.circulating_load < 1e-12);
  for (std::size_t i = 0; i < open.size(); ++i) CHECK(wide.product[i] == Approx(open[i]).margin(1e-12));
}

TEST_CASE("sizes passing: P80 of a known distribution, feed interpolated at the class tops", "[grind]") {
  const SizeSeries s = geometric_series(4e-3, 2.0, 6);  // 4, 2, 1, 0.5, 0.25, 0.125 mm
  // Rosin-free check: passing 1, 0.8, 0.5, 0.3, 0.2, 0.1 at the tops.
  const std::vector<double> m{0.2, 0.3, 0.2, 0.1, 0.1, 0.1};
  CHECK(passing_size(s, m, 0.8) == Approx(2e-3).epsilon(1e-12));
  CHECK(passing_size(s, m, 0.65) == Approx(std::sqrt(2e-3 * 1e-3)).epsilon(1e-12));
  CHECK(std::isnan(passing_size(s, m, 0.05)));
  const std::vector<double> f = feed_masses(s, {4e-3, 1e-3, 0.25e-3}, {1.0, 0.5, 0.2});
  CHECK(f[0] == Approx(0.25).epsilon(1e-12));  // passing 0.75 at 2 mm: log-linear
  CHECK(sum(f) == Approx(1.0).margin(1e-12));
}

TEST_CASE("the breakage probability: half at E50, Tavares' size effect, certain at Emax", "[grind]") {
  const Fracture f{120.0, 5e-3, 1.2, 0.8, 8.0};  // J/kg, m
  for (double d : {0.5e-3, 2e-3, 8e-3}) {
    CHECK(f.broken(f.e50(d), d) == Approx(0.5).margin(1e-12));
    CHECK(f.broken(0.5 * f.e50(d), d) < 0.5);
    CHECK(f.broken(8.0 * f.e50(d), d) == 1.0);
  }
  CHECK(f.e50(5e-3) == Approx(240.0));
  CHECK(f.e50(0.5e-3) > f.e50(8e-3));  // fine particles are stronger
  // The mechanistic rate grows with the energy of the collisions.
  const SizeSeries s = geometric_series(3.35e-3, std::sqrt(2.0), 12);
  const std::vector<SpectrumBin> weak{{1e4, 1e-3, 0.01}}, strong{{1e4, 1e-2, 0.01}};
  const auto Sw = spectrum_rates(s, weak, f, 2700, 0.6, 1.0, 1.0);
  const auto Ss = spectrum_rates(s, strong, f, 2700, 0.6, 1.0, 1.0);
  for (int i = 0; i + 1 < s.size(); ++i) CHECK(Ss[i] >= Sw[i]);
  CHECK(Ss[0] > 0);
  CHECK(Ss.back() == 0.0);
  // Captured mass: the monolayer's closed form.
  CHECK(captured_mass(1e-3, 0.01, 2700, 0.6) == Approx(0.6 * 9.8696044 / 3 * 2700 * 1e-6 * 0.01).epsilon(1e-6));
}

TEST_CASE("the incomplete beta function: closed forms, its symmetry and a tabulated value", "[grind][t10]") {
  for (double x : {1e-6, 0.01, 0.1, 0.37, 0.5, 0.9, 0.999}) {
    INFO("x " << x);
    CHECK(incomplete_beta(x, 1, 1) == Approx(x).epsilon(1e-12));
    CHECK(incomplete_beta(x, 2.7, 1) == Approx(std::pow(x, 2.7)).epsilon(1e-12));
    CHECK(incomplete_beta(x, 1, 3.5) == Approx(-std::expm1(3.5 * std::log1p(-x))).epsilon(1e-12));
    CHECK(incomplete_beta(x, 2, 2) == Approx(3 * x * x - 2 * x * x * x).epsilon(1e-12));
    CHECK(incomplete_beta(x, 0.4, 7.0) + incomplete_beta(1 - x, 7.0, 0.4) == Approx(1.0).epsilon(1e-12));
  }
  CHECK(incomplete_beta(0, 2, 3) == 0.0);
  CHECK(incomplete_beta(1, 2, 3) == 1.0);
  // Cephes' incbet(0.3, 0.6, 0.5), as its documentation tabulates it.
  CHECK(incomplete_beta(0.5, 0.3, 0.6) == Approx(0.68786273145845922).epsilon(1e-13));
}

namespace {
// Tavares' t10 with the Schuhmann family: t_n = t10^log10(n).
T10Breakage schuhmann_t10(double a, double b_prime) {
  T10Breakage t;
  t.a = a;
  t.b_prime = b_prime;
  t.n = {2, 4, 25, 50, 75};
  for (double n : t.n) t.alpha.push_back(std::log10(n)), t.beta.push_back(1.0);
  return t;
}
}  // namespace

TEST_CASE("Tavares' t10: its closed form, the Schuhmann family as Austin's B, the median of the broken",
          "[grind][t10]") {
  const T10Breakage t = schuhmann_t10(0.45, 0.8);
  CHECK(t.t10(0) == 0.0);
  CHECK(t.t10(2.0) == Approx(0.45 * (1 - std::exp(-1.6))).epsilon(1e-14));
  CHECK(t.t10(1e3) == Approx(0.45).epsilon(1e-14));  // A at high energy
  // With tn_alpha = log10(n), tn_beta = 1, B(u) = u^gamma, gamma = -log10(t10),
  // at the nodes, between them and below the last.
  for (double t10 : {0.02, 0.1, 0.3}) {
    const double gamma = -std::log10(t10);
    for (double u : {1.0, 0.7, 0.5, 0.3, 0.1, 0.06, 0.04, 0.02, 1.0 / 75, 0.005, 1e-4}) {
      INFO("t10 " << t10 << " u " << u);
      CHECK(t.cumulative(u, t10) == Approx(std::pow(u, gamma)).epsilon(1e-12));
    }
  }
  // E50b: P(E50b) = P(e) / 2; above Emax every particle breaks and E50b is E50.
  const Fracture f{60.0, 2e-3, 1.2, 0.8, 10.0};
  for (double d : {0.1e-3, 1e-3, 3e-3})
    for (double r : {0.3, 1.0, 3.0}) {
      const double e = r * f.e50(d), e50b = median_broken_energy(f, e, d);
      INFO("d " << d << " e/E50 " << r);
      CHECK(e50b < e);
      CHECK(f.broken(e50b, d) == Approx(0.5 * f.broken(e, d)).epsilon(1e-10));
    }
  CHECK(median_broken_energy(f, 20 * f.e50(1e-3), 1e-3) == Approx(f.e50(1e-3)).epsilon(1e-10));
  CHECK(median_broken_energy(f, 0.0, 1e-3) == 0.0);
}

TEST_CASE("Tavares' t10 in a mill: each class's events as Austin's B, mass kept, finer progeny from harder hits",
          "[grind][t10]") {
  const SizeSeries s = geometric_series(3.35e-3, std::sqrt(2.0), 20);
  const Fracture f{60.0, 2e-3, 1.2, 0.8, 10.0};
  const T10Breakage t = schuhmann_t10(0.5, 0.1);
  // One bin: every class meets one event, whose t10 sets Austin's B with
  // phi = 1 and gamma = -log10(t10).
  const std::vector<SpectrumBin> one{{1e4, 2e-3, 0.01}};
  std::vector<double> t10;
  const auto b = t10_breakage_matrix(s, one, f, t, 2700, 0.6, &t10);
  for (int j = 0; j + 1 < s.size(); ++j) {
    const double d = s.mid_m(j), e = 2e-3 / captured_mass(d, 0.01, 2700, 0.6);
    INFO("class " << j);
    if (f.broken(e, d) > 0) CHECK(t10[j] == Approx(t.t10(e / median_broken_energy(f, e, d))).epsilon(1e-12));
    const auto austin = breakage_matrix(s, AustinBreakage{1.0, -std::log10(t10[j]), 4.0});
    double sum = 0;
    for (int i = j + 1; i < s.size(); ++i) {
      CHECK(b[i][j] == Approx(austin[i][j]).margin(1e-12));
      CHECK(b[i][j] >= 0);
      sum += b[i][j];
    }
    CHECK(sum == Approx(1.0).margin(1e-12));
  }
  // Harder collisions break with more energy to spare: each class's mean
  // t10 rises, and the progeny are finer (more of the mass two classes down).
  const std::vector<SpectrumBin> weak{{1e4, 1e-3, 0.01}, {1e3, 3e-3, 0.01}},
      strong{{1e4, 1e-2, 0.01}, {1e3, 3e-2, 0.01}};
  std::vector<double> tw, ts;
  const auto bw = t10_breakage_matrix(s, weak, f, t, 2700, 0.6, &tw);
  const auto bs = t10_breakage_matrix(s, strong, f, t, 2700, 0.6, &ts);
  for (int j = 0; j + 3 < s.size(); ++j) {
    INFO("class " << j << " t10 weak " << tw[j] << " strong " << ts[j]);
    CHECK(ts[j] > tw[j]);
    double below_w = 0, below_s = 0;
    for (int i = j + 3; i < s.size(); ++i) below_w += bw[i][j], below_s += bs[i][j];
    CHECK(below_s > below_w);
  }
}

// ------------------------------------------------------------ the command

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/commands.h"
#include "app/grind.h"
#include "core/version.h"
#include "io/case_file.h"
#include "io/ore_file.h"

namespace {

namespace fs = std::filesystem;

std::string text_of(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A short run of a slice of the lab mill, made once.
const fs::path& short_run() {
  static const fs::path out = [] {
    const fs::path dir = fs::temp_directory_path() / ("millcharge_test_grind_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    mc::app::RunOptions o;
    o.c.overrides = {"mill.length=0.06", "run.settle=0.05", "run.warmup=0.1", "run.output_interval=0.01",
                     "run.snapshot_interval=0.2"};
    o.c.duration = 0.3;
    o.out = dir.string();
    o.quiet = true;
    REQUIRE(mc::app::cmd_run(o) == 0);
    return dir;
  }();
  return out;
}

fs::path ore_file(const std::string& name) { return fs::path(MC_ASSET_DIR) / "ores" / name; }

// The example ore with one line replaced (or a line added).
fs::path edited_ore(const std::string& from, const std::string& to, const std::string& base = "example_energy.toml") {
  std::string t = text_of(ore_file(base));
  const std::size_t at = t.find(from);
  REQUIRE(at != std::string::npos);
  t.replace(at, from.size(), to);
  const fs::path p = fs::temp_directory_path() / ("millcharge_test_ore_" + std::to_string(::getpid()) + ".toml");
  std::ofstream(p) << t;
  return p;
}

// grind of this ore on this run folder throws a message holding `says`
// and writes nothing in `out`.
void refuses_grind(const fs::path& ore, const fs::path& run_dir, const fs::path& out, const std::string& says) {
  mc::app::GrindOptions o;
  o.run_dir = run_dir.string();
  o.ore = ore.string();
  o.out = out.string();
  o.quiet = true;
  INFO("expected: " << says);
  CHECK_THROWS_WITH(mc::app::cmd_grind(o), Catch::Contains(says));
  CHECK(!fs::exists(out));
}

}  // namespace

TEST_CASE("grind: a run's product size in batch and continuous, both rate models", "[grind][outputs]") {
  const fs::path run = short_run();
  const nlohmann::json summary = nlohmann::json::parse(text_of(run / "summary.json"));
  const double power_W = summary["power_W"]["torque"].get<double>();
  for (const char* ore : {"example_energy.toml", "example_spectrum.toml"}) {
    INFO(ore);
    mc::app::GrindOptions o;
    o.run_dir = run.string();
    o.ore = ore_file(ore).string();
    o.times_min = {1, 4, 16};
    o.feed_rate_t_h = 0.02;
    o.target_p80_um = 200;
    o.out = (run / (std::string("grind-") + ore)).string();
    o.quiet = true;
    REQUIRE(mc::app::cmd_grind(o) == 0);
    const nlohmann::json j = nlohmann::json::parse(text_of(fs::path(o.out) / "grind.json"));
    const double H = j["holdup_kg"].get<double>();
    CHECK(H > 0);
    const auto& p = j["products"];
    REQUIRE(p.size() == 5);
    // Specific energy: the power over the hold-up, times the time.
    CHECK(p[1]["specific_energy_kWh_t"].get<double>() == Approx(power_W / 1000 * 4 / 60 / (H / 1000)).epsilon(1e-9));
    // Finer with time, all below the feed's F80.
    const double f80 = j["F80_um"].get<double>();
    CHECK(p[0]["P80_um"].get<double>() < f80);
    CHECK(p[1]["P80_um"].get<double>() < p[0]["P80_um"].get<double>());
    CHECK(p[2]["P80_um"].get<double>() < p[1]["P80_um"].get<double>());
    // The throughput that gives the target P80.
    CHECK(p[4]["P80_um"].get<double>() == Approx(200).epsilon(1e-6));
    CHECK(j["throughput_at_target_t_h"].get<double>() == Approx(p[4]["feed_rate_t_h"].get<double>()));
    CHECK(j["build"]["commit"] == mc::build_commit());
    for (const char* f : {"grind.csv", "rates.csv", "grind.png"}) CHECK(fs::file_size(fs::path(o.out) / f) > 100);
  }
}

TEST_CASE("grind --classifier: the continuous mill closed, its throughput at a target P80", "[grind][outputs]") {
  const fs::path run = short_run();
  auto grind = [&](double d50c_um, const std::string& name) {
    mc::app::GrindOptions o;
    o.run_dir = run.string();
    o.ore = ore_file("example_energy.toml").string();
    o.feed_rate_t_h = 0.02;
    o.target_p80_um = 200;
    o.classifier_d50c_um = d50c_um;
    o.out = (run / name).string();
    o.quiet = true;
    REQUIRE(mc::app::cmd_grind(o) == 0);
    return nlohmann::json::parse(text_of(fs::path(o.out) / "grind.json"));
  };
  const nlohmann::json open = grind(0, "grind-open"), closed = grind(250, "grind-closed");
  CHECK(!open.contains("classifier"));
  CHECK(closed["classifier"]["d50c_um"].get<double>() == 250);
  const auto& po = open["products"];
  const auto& pc = closed["products"];
  REQUIRE(po.size() == 2);
  REQUIRE(pc.size() == 2);
  // At the same feed rate the closed circuit's product is finer, with a
  // circulating load and a shorter residence in the mill.
  CHECK(pc[0]["circulating_load"].get<double>() > 0.1);
  CHECK(pc[0]["steady"].get<bool>());
  CHECK(pc[0]["P80_um"].get<double>() < po[0]["P80_um"].get<double>());
  CHECK(pc[0]["time_min"].get<double>() < po[0]["time_min"].get<double>());
  CHECK(pc[0]["specific_energy_kWh_t"].get<double>() == Approx(po[0]["specific_energy_kWh_t"].get<double>()));
  // And it makes the target P80 at a higher throughput.
  CHECK(pc[1]["P80_um"].get<double>() == Approx(200).epsilon(1e-6));
  CHECK(closed["throughput_at_target_t_h"].get<double>() > open["throughput_at_target_t_h"].get<double>());

  // Bad input, by option, nothing written.
  const fs::path out = run / "grind-bad";
  auto refuses = [&](mc::app::GrindOptions o, const std::string& says) {
    o.run_dir = run.string();
    o.ore = ore_file("example_energy.toml").string();
    o.out = out.string();
    o.quiet = true;
    INFO("expected: " << says);
    CHECK_THROWS_WITH(mc::app::cmd_grind(o), Catch::Contains(says));
    CHECK(!fs::exists(out));
  };
  mc::app::GrindOptions o;
  o.classifier_d50c_um = 250;
  refuses(o, "give --feed-rate or --target-p80");
  o.feed_rate_t_h = 0.02;
  o.classifier_d50c_um = 9000;
  refuses(o, "--classifier 9000: the cut size must lie inside the size classes");
  o.classifier_d50c_um = 0;
  o.classifier_bypass = 0.1;
  refuses(o, "give --classifier D50C_UM with them");
}

TEST_CASE("grind refuses bad ore files and run folders by name, writing nothing", "[grind][failures]") {
  const fs::path run = short_run();
  const fs::path out = fs::temp_directory_path() / ("millcharge_test_grind_bad_" + std::to_string(::getpid()));
  fs::remove_all(out);
  auto refuses = [&](const fs::path& ore, const fs::path& dir, const std::string& says) {
    refuses_grind(ore, dir, out, says);
  };
  refuses(edited_ore("passing  = [1.00,", "passing  = [0.90,"), run, "feed.passing");
  refuses(edited_ore("passing  = [1.00,", "passing  = [0.90,"), run, "must sum to 1");
  refuses(edited_ore("top_mm = 3.35", "top_mm = 2.0"), run, "sizes.top_mm");
  refuses(edited_ore("top_mm = 3.35", "top_mm = 2.0"), run, "does not cover the feed");
  refuses(edited_ore("model = \"energy\"", "model = \"kick\""), run, "rates.model");
  refuses(edited_ore("zeta1 = 0.6", "zeta1 = 60"), run, "rates.zeta1");
  refuses(edited_ore("density = 2700", "density = -1"), run, "density");
  refuses(edited_ore("phi = 0.55", "phi = 0.55\nchi = 1"), run, "breakage.chi: unknown key");
  refuses(ore_file("example_energy.toml"), run / "snapshots", "summary.json: missing");
  // A run from before the severity spectra (eight columns fewer).
  const fs::path old = out.string() + "-old-run";
  fs::remove_all(old);
  fs::create_directories(old);
  for (const char* f : {"summary.json", "case.toml"}) fs::copy_file(run / f, old / f);
  {
    std::ifstream in(run / "spectra.csv");
    std::ofstream o(old / "spectra.csv");
    for (std::string l; std::getline(in, l);) {
      for (int k = 0; k < 8; ++k) l = l.substr(0, l.rfind(','));
      o << l << '\n';
    }
  }
  refuses(ore_file("example_spectrum.toml"), old, "has no impact severity spectrum");
  // A run resumed from an older checkpoint: its normal spectrum holds part
  // of the collisions only.
  {
    std::ifstream in(run / "spectra.csv");
    std::ofstream o(old / "spectra.csv");
    std::string l;
    std::getline(in, l);
    o << l << '\n';
    while (std::getline(in, l)) {
      std::vector<std::string> f;
      std::stringstream ss(l);
      for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
      f[f.size() - 6] = std::to_string(0.5 * std::stod(f[f.size() - 6]));  // impact_collisions_per_s
      for (std::size_t k = 0; k < f.size(); ++k) o << (k ? "," : "") << f[k];
      o << '\n';
    }
  }
  refuses(ore_file("example_spectrum.toml"), old, "holds 50.0 % of the collisions");
  // The binary: exit status 2 and the message.
  const std::string cmd = std::string(MC_BINARY) + " grind " + run.string() + " --ore " +
                          edited_ore("model = \"energy\"", "model = \"kick\"").string() + " --out " + out.string() +
                          " > " + out.string() + ".log 2>&1";
  const int status = std::system(cmd.c_str());
  CHECK(WEXITSTATUS(status) == 2);
  CHECK(text_of(out.string() + ".log").find("rates.model") != std::string::npos);
  CHECK(!fs::exists(out));
  fs::remove_all(old);
}

TEST_CASE("grind with Tavares' t10: each class's mean t10 written, the ore file read back, bad t10 keys refused",
          "[grind][t10][failures]") {
  const fs::path run = short_run();
  mc::app::GrindOptions o;
  o.run_dir = run.string();
  o.ore = ore_file("example_t10.toml").string();
  o.out = (run / "grind-t10").string();
  o.quiet = true;
  REQUIRE(mc::app::cmd_grind(o) == 0);
  const nlohmann::json j = nlohmann::json::parse(text_of(fs::path(o.out) / "grind.json"));
  CHECK(j["appearance"] == "t10");
  const auto t10 = j["t10_mean_by_class"].get<std::vector<double>>();
  REQUIRE(t10.size() == 20);
  // Under A = 50 %; finer classes take more specific energy from the same
  // collisions, so their mean t10 rises down the classes.
  for (std::size_t i = 0; i + 1 < t10.size(); ++i) {
    INFO("class " << i);
    CHECK(t10[i] > 0.01);
    CHECK(t10[i] < 0.5);
    if (i > 0 && i + 1 < t10.size()) CHECK(t10[i] > t10[i - 1]);
  }
  CHECK(text_of(fs::path(o.out) / "rates.csv").rfind("class,top_um,mid_um,S_per_min,SE_t_per_kWh,t10\n", 0) == 0);
  // The ore file written (as a fit writes it) reads back to the same ore.
  const Ore ore = mc::io::read_ore(o.ore);
  const fs::path back = fs::temp_directory_path() / ("millcharge_test_t10_back_" + std::to_string(::getpid()) + ".toml");
  std::ofstream(back) << mc::io::ore_toml(ore, "");
  const Ore again = mc::io::read_ore(back);
  fs::remove(back);
  CHECK(again.appearance == Appearance::t10);
  CHECK(again.t10.a == Approx(ore.t10.a).epsilon(1e-9));
  CHECK(again.t10.b_prime == Approx(ore.t10.b_prime).epsilon(1e-9));
  CHECK(again.t10.n == ore.t10.n);
  for (std::size_t k = 0; k < ore.t10.n.size(); ++k) {
    CHECK(again.t10.alpha[k] == Approx(ore.t10.alpha[k]).epsilon(1e-9));
    CHECK(again.t10.beta[k] == Approx(ore.t10.beta[k]).epsilon(1e-9));
  }

  const fs::path out = fs::temp_directory_path() / ("millcharge_test_grind_t10_bad_" + std::to_string(::getpid()));
  fs::remove_all(out);
  auto refuses = [&](const fs::path& ore_path, const std::string& says) { refuses_grind(ore_path, run, out, says); };
  const std::string base = "example_t10.toml";
  refuses(edited_ore("tn_n = [2, 4, 25, 50, 75]", "tn_n = [2, 4, 10, 50, 75]", base), "breakage.tn_n: holds 10");
  refuses(edited_ore("tn_n = [2, 4, 25, 50, 75]", "tn_n = [2, 4, 50, 25, 75]", base), "must ascend");
  refuses(edited_ore("tn_beta = [1, 1, 1, 1, 1]", "tn_beta = [1, 1, 1, 1]", base),
          "breakage.tn_beta: holds 4 values for the 5 sizes");
  refuses(edited_ore("tn_alpha = [0.30103,", "tn_alpha = [3.0,", base), "must fall as n rises");
  refuses(edited_ore("tn_beta = [1, 1, 1, 1, 1]", "tn_beta = [1, 1, 1, 0, 1]", base), "breakage.tn_beta");
  refuses(edited_ore("model = \"t10\"", "model = \"t10\"\nphi = 0.5", base), "breakage.phi: unknown key");
  refuses(edited_ore("model = \"t10\"", "model = \"kick\"", base), "breakage.model");
  refuses(edited_ore("t10_max_percent = 50", "t10_max_percent = 0.5", base), "breakage.t10_max_percent");
  refuses(edited_ore("b_prime = 0.1", "b_prime = \"0.1\"", base), "breakage.b_prime");
  // t10 needs the collisions: with the energy-specific rates it is refused.
  {
    const std::string t = text_of(ore_file(base)), e = text_of(ore_file("example_energy.toml"));
    const fs::path p = fs::temp_directory_path() / ("millcharge_test_t10_energy_" + std::to_string(::getpid()) + ".toml");
    std::ofstream(p) << t.substr(0, t.find("[rates]")) + e.substr(e.find("[rates]"));
    refuses(p, "needs rates.model = \"spectrum\"");
    fs::remove(p);
  }
}

TEST_CASE("grind --bond: a locked-cycle test that settles at 250 % and Bond's formula", "[grind]") {
  const fs::path run = short_run();
  mc::app::GrindOptions o;
  o.run_dir = run.string();
  o.ore = ore_file("example_energy.toml").string();
  o.bond_p1_um = 150;
  o.out = (run / "grind-bond").string();
  o.quiet = true;
  REQUIRE(mc::app::cmd_grind(o) == 0);
  const nlohmann::json j = nlohmann::json::parse(text_of(fs::path(o.out) / "grind.json"));
  const auto& b = j["bond"];
  CHECK(b["steady"] == true);
  CHECK(b["cycles"].get<int>() >= 6);
  CHECK(b["circulating_load"].get<double>() == Approx(2.5).margin(0.075));
  CHECK(b["charge_g"].get<double>() == Approx(700 * 2.7 * 0.6));  // 700 cm³ at the bed's bulk density
  const double gbp = b["Gbp_g_per_rev"].get<double>(), p80 = b["P80_um"].get<double>(), f80 = b["F80_um"].get<double>();
  CHECK(gbp > 0);
  CHECK(p80 < 150);
  // Bond's formula per short ton, per tonne: 1000 / 907.18474.
  CHECK(b["work_index_kWh_t"].get<double>() ==
        Approx(1000 / 907.18474 * 44.5 / (std::pow(150.0, 0.23) * std::pow(gbp, 0.82) * (10 / std::sqrt(p80) - 10 / std::sqrt(f80))))
            .epsilon(1e-9));
  // The last three cycles' Gbp agree within 3 %.
  const auto& g = b["Gbp_by_cycle"];
  const std::size_t n = g.size();
  const double hi = std::max({g[n - 1].get<double>(), g[n - 2].get<double>(), g[n - 3].get<double>()});
  const double lo = std::min({g[n - 1].get<double>(), g[n - 2].get<double>(), g[n - 3].get<double>()});
  CHECK((hi - lo) / hi < 0.03);
  // A closing sieve above the feed's F80 is refused.
  o.bond_p1_um = 3000;
  o.out = (run / "grind-bond-bad").string();
  CHECK_THROWS_WITH(mc::app::cmd_grind(o), Catch::Contains("--bond 3000"));
  CHECK(!fs::exists(o.out));
  // P1 on the finest class top (3350 um / sqrt(2)^19) leaves the product no
  // class below it: refused by name, not a NaN work index.
  o.bond_p1_um = 3350 / std::pow(std::sqrt(2.0), 19);
  CHECK_THROWS_WITH(mc::app::cmd_grind(o), Catch::Contains("--bond 4.6") && Catch::Contains("finest class top"));
  CHECK(!fs::exists(o.out));
}

TEST_CASE("grind --bond leaves the call's other products as they are without it", "[grind]") {
  // Bond's test holds 700 cm³ of feed; the other products of the call are
  // the run's, at the run's hold-up: the same numbers as a call without --bond.
  const fs::path run = short_run();
  auto grind = [&](double p1_um, const std::string& name) {
    mc::app::GrindOptions o;
    o.run_dir = run.string();
    o.ore = ore_file("example_energy.toml").string();
    o.times_min = {4};
    o.bond_p1_um = p1_um;
    o.out = (run / name).string();
    o.quiet = true;
    REQUIRE(mc::app::cmd_grind(o) == 0);
    return nlohmann::json::parse(text_of(fs::path(o.out) / "grind.json"));
  };
  const nlohmann::json alone = grind(0, "grind-alone"), with = grind(150, "grind-with-bond");
  const double power_W = nlohmann::json::parse(text_of(run / "summary.json"))["power_W"]["torque"].get<double>();
  const double H = alone["holdup_kg"].get<double>();
  CHECK(with["holdup_kg"].get<double>() == Approx(H).epsilon(1e-12));
  const auto& a = alone["products"][0];
  const auto& w = with["products"][0];
  CHECK(w["specific_energy_kWh_t"].get<double>() == Approx(power_W / 1000 * 4 / 60 / (H / 1000)).epsilon(1e-9));
  CHECK(w["P80_um"].get<double>() == Approx(a["P80_um"].get<double>()).epsilon(1e-12));
  CHECK(with["bond"]["work_index_kWh_t"].get<double>() > 0);
}

TEST_CASE("grind reads a run's spectra.csv strictly: a cut or damaged or foreign file is refused by its line",
          "[grind][failures]") {
  const fs::path run = short_run();
  const fs::path bad = fs::temp_directory_path() / ("millcharge_test_grind_cut_" + std::to_string(::getpid()));
  const fs::path out = bad / "grind";
  const std::string text = text_of(run / "spectra.csv");
  std::vector<std::string> lines;
  for (std::size_t from = 0; from < text.size();) {
    const std::size_t nl = text.find('\n', from);
    lines.push_back(text.substr(from, nl - from));
    from = nl + 1;
  }
  REQUIRE(lines.size() > 200);
  auto refuses = [&](const std::string& spectra, const std::string& says) {
    fs::remove_all(bad);
    fs::create_directories(bad);
    for (const char* f : {"summary.json", "case.toml"}) fs::copy_file(run / f, bad / f);
    std::ofstream(bad / "spectra.csv", std::ios::binary) << spectra;
    mc::app::GrindOptions o;
    o.run_dir = bad.string();
    o.ore = ore_file("example_spectrum.toml").string();
    o.out = out.string();
    o.quiet = true;
    INFO("expected: " << says);
    CHECK_THROWS_WITH(mc::app::cmd_grind(o), Catch::Contains(says));
    CHECK(!fs::exists(out));
  };
  auto first = [&](std::size_t n) {
    std::string s;
    for (std::size_t k = 0; k < n; ++k) s += lines[k] + "\n";
    return s;
  };
  const std::size_t third = lines.size() / 3;
  const std::string path = (bad / "spectra.csv").string();
  // The file: a third of the rows, then "0.1,abc".
  refuses(first(third) + "0.1,abc", path + ":" + std::to_string(third + 1) + ": the last line ends without a newline");
  refuses(first(third) + "0.1,abc\n", path + ":" + std::to_string(third + 1) + ": 2 fields, the header has 21");
  // Cut inside a line.
  refuses(text.substr(0, text.size() / 3), "the file was cut short");
  // A number that is not one, by its line and column.
  {
    std::string t = first(lines.size());
    const std::size_t row = t.find("\nsteel-steel,5,");
    REQUIRE(row != std::string::npos);
    const std::size_t field = t.find(',', t.find(',', t.find(',', t.find(',', row + 1) + 1) + 1) + 1);
    t.replace(field + 1, t.find(',', field + 1) - field - 1, "abc");
    refuses(t, path + ":7: collisions_per_s: \"abc\" is not a number");
  }
  // Cut at a line's end: inside a pair, and between two pairs.
  refuses(first(1 + 122 + 50), "has 50 bins, the first pair 122: the file was cut short");
  refuses(first(1 + 2 * 122), "holds the pairs steel-steel, steel-shell, summary.json steel-steel, steel-shell, "
                              "steel-lifter, steel-end plate");
  // Another run's spectra (the rates scaled): not summary.json's.
  {
    std::string t = lines[0] + "\n";
    for (std::size_t k = 1; k < lines.size(); ++k) {
      std::vector<std::string> f;
      std::stringstream ss(lines[k]);
      for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
      f[4] = std::to_string(1.1 * std::stod(f[4]));
      for (std::size_t c = 0; c < f.size(); ++c) t += (c ? "," : "") + f[c];
      t += "\n";
    }
    refuses(t, "collisions/s, summary.json gives");
  }
  // The whole file, unchanged, is read.
  fs::remove_all(bad);
  fs::create_directories(bad);
  for (const char* f : {"summary.json", "case.toml", "spectra.csv"}) fs::copy_file(run / f, bad / f);
  mc::app::GrindOptions o;
  o.run_dir = bad.string();
  o.ore = ore_file("example_spectrum.toml").string();
  o.out = out.string();
  o.quiet = true;
  CHECK(mc::app::cmd_grind(o) == 0);
  fs::remove_all(bad);
}

TEST_CASE("grind --target-p80 a mill cannot reach is refused by name and range messages say what is wanted",
          "[grind][failures][cli]") {
  const fs::path run = short_run();
  const fs::path out = fs::temp_directory_path() / ("millcharge_test_grind_opts_" + std::to_string(::getpid()));
  fs::remove_all(out);
  auto binary = [&](const std::string& args) {
    const fs::path log = out.string() + ".log";
    const std::string cmd = std::string(MC_BINARY) + " grind " + run.string() + " --ore " +
                            ore_file("example_spectrum.toml").string() + " --out " + out.string() + " " + args +
                            " > " + log.string() + " 2>&1";
    const int status = std::system(cmd.c_str());
    const std::string said = text_of(log);
    fs::remove(log);
    return std::make_pair(WEXITSTATUS(status), said);
  };
  // Finer than the finest class: refused, nothing written (it was answered
  // with the finest product, under the target's heading).
  {
    const auto [status, said] = binary("--target-p80 0.0001");
    INFO(said);
    CHECK(status == 2);
    CHECK_THAT(said, Catch::Contains("--target-p80 0.0001: finer than the ore's finest size class"));
    CHECK(!fs::exists(out));
  }
  // Every numeric option's range: one short line that says what is wanted.
  const std::vector<std::pair<std::string, std::string>> wrong = {
      {"--feed-rate 0", "--feed-rate: must be > 0 t/h, got 0"},
      {"--feed-rate -5", "--feed-rate: must be > 0 t/h, got -5"},
      {"--feed-rate abc", "--feed-rate: must be a number > 0 t/h, got \"abc\""},
      {"--target-p80 0", "--target-p80: must be > 0 um, got 0"},
      {"--classifier 0", "--classifier: must be > 0 um, got 0"},
      {"--sharpness -1", "--sharpness: must be > 0, got -1"},
      {"--bond -106", "--bond: must be > 0 um, got -106"},
      {"--tanks 0", "--tanks: must be a whole number from 1 to 1000, got 0"},
      {"--tanks 2.5", "--tanks: must be a whole number from 1 to 1000, got \"2.5\""},
      {"--bypass 1", "--bypass: must be from 0 to 0.95, got 1"},
  };
  for (const auto& [args, says] : wrong) {
    const auto [status, said] = binary(args);
    INFO(args << ": " << said);
    CHECK(status == 2);
    CHECK_THAT(said, Catch::StartsWith(says));
    CHECK(said.find('\n') < 80);  // no numeric limit printed in full
    CHECK(!fs::exists(out));
  }
  // The other commands' numeric options, the same way.
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {"bench --steps 0", "--steps: must be a whole number >= 1, got 0"},
           {"bench --warmup -1", "--warmup: must be >= 0 s, got -1"},
           {"bench --tile 0", "--tile: must be a whole number from 1 to 10000, got 0"},
           {"view --frames 0", "--frames: must be a whole number from 1 to 100000000, got 0"},
           {"sweep check x.toml --throughput 0", "--throughput: must be > 0 particle-updates/s, got 0"},
           {"sweep run x.toml --print --cpus-per-task 99999", "--cpus-per-task: must be a whole number from 0 to 4096, got 99999"},
       }) {
    const fs::path log = out.string() + ".log";
    const int status = std::system((std::string(MC_BINARY) + " " + args + " > " + log.string() + " 2>&1").c_str());
    const std::string said = text_of(log);
    fs::remove(log);
    INFO(args << ": " << said);
    CHECK(WEXITSTATUS(status) == 2);
    CHECK_THAT(said, Catch::StartsWith(says));
    CHECK(said.find('\n') < 80);
  }
}
