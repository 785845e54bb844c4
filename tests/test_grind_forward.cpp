// The forward model of `grind` against computations that share none of its
// code: the batch products `--fit` inverts (batch_test_products), made from
// a hand-made spectrum of one energy bin, against the rates worked out from
// docs/grinding.md's formulas and the two-class closed form of a batch grind;
// Tavares' t_n with tn_beta other than 1 against a numerical integration of
// the beta density.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "grind/circuit.h"
#include "grind/fit.h"
#include "io/ore_file.h"

using namespace mc::grind;

namespace {

// Tavares' upper-truncated lognormal as docs/grinding.md and Tavares'
// review state it: P(e) = Φ(ln(e*/E50*) / σ), e* = Emax e / (Emax − e),
// E50(d) = E∞ (1 + (d0/d)^φ), Emax = ratio · E50; Φ from erfc.
double broken_share(double e, double d, double e_inf, double d0, double phi, double sigma, double ratio) {
  const double e50 = e_inf * (1 + std::pow(d0 / d, phi)), emax = ratio * e50;
  if (e >= emax) return 1;
  const double z = std::log((emax * e / (emax - e)) / (emax * e50 / (emax - e50))) / sigma;
  return 0.5 * std::erfc(-z / std::sqrt(2.0));
}

// I_x(a, b) by integrating the beta density, independent of the code's
// continued fraction: with x = X v^m, m = 4/a, the integral of
// x^(a-1) (1-x)^(b-1) from 0 to X is X^a m times that of
// v^3 (1 - X v^m)^(b-1) over 0..1, smooth for X < 1 (composite Simpson,
// 4000 intervals); B(a, b) from lgamma.
double beta_by_quadrature(double X, double a, double b) {
  const double m = 4 / a;
  const int n = 4000;
  auto f = [&](double v) { return v * v * v * std::pow(1 - X * std::pow(v, m), b - 1); };
  double sum = f(0) + f(1);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4 : 2) * f(static_cast<double>(i) / n);
  const double integral = std::pow(X, a) * m * sum / (3.0 * n);
  return integral / std::exp(std::lgamma(a) + std::lgamma(b) - std::lgamma(a + b));
}

}  // namespace

TEST_CASE("the batch products --fit inverts: one class breaking into the next, against rates and a closed form "
          "by hand",
          "[grind][fit][numbers]") {
  // Three classes on the √2 series from 2 mm (the last the sink), every
  // particle of the feed in the top one, one bin of collisions.
  const double r2 = std::sqrt(2.0);
  Ore ore;
  ore.model = RateModel::spectrum;
  ore.appearance = Appearance::austin;
  ore.sizes = geometric_series(2e-3, r2, 3);
  ore.density = 2700;
  ore.packing = 0.6;
  ore.efficiency = 0.5;
  ore.breakage = AustinBreakage{0.4, 0.9, 3.5};
  ore.fracture = Fracture{50, 2e-3, 1.2, 0.7, 10};
  const double N = 200, E = 0.015, R = 0.01, H = 1.0;  // collisions/s, J, m, kg
  const std::vector<SpectrumBin> spectrum = {SpectrumBin{N, E, R}};
  BatchTest test;
  test.sieve_m = {2e-3, 2e-3 / r2, 1e-3};  // the class tops
  test.feed_passing = {1, 0, 0};
  test.times_min = {1, 2.5, 4};
  test.holdup_kg = H;
  const auto rows = batch_test_products(ore, spectrum, 100, H, test);

  // The rates by hand: S_i = η/H · N · m_cap · P(E/m_cap), per minute, with
  // m_cap = p (π²/3) ρ d² R at the class's geometric mean d.
  const double pi = std::acos(-1.0);
  double S[2], P[2];
  for (int i = 0; i < 2; ++i) {
    const double d = 2e-3 * std::pow(r2, -i - 0.5);
    const double m_cap = 0.6 * pi * pi / 3 * 2700 * d * d * R;
    P[i] = broken_share(E / m_cap, d, 50, 2e-3, 1.2, 0.7, 10);
    S[i] = 60 * 0.5 / H * N * m_cap * P[i];
  }
  // Both well inside (0, 1) of P, so the check sees the lognormal, and the
  // rates apart, as the closed form needs.
  INFO("P " << P[0] << ", " << P[1] << "; S " << S[0] << ", " << S[1] << " per min");
  CHECK(P[0] > 0.1);
  CHECK(P[1] < 0.9);
  CHECK(std::fabs(S[1] / S[0] - 1) > 0.1);
  // Austin's B of the top class at the next class's lower size, u = 1/√2
  // (B(1) = 1: all that breaks leaves): the share landing in class 1.
  const double u = 1 / r2, b10 = 1 - (0.4 * std::pow(u, 0.9) + 0.6 * std::pow(u, 3.5));
  // dm0/dt = −S0 m0, dm1/dt = b10 S0 m0 − S1 m1, m0(0) = 1, m1(0) = 0.
  REQUIRE(rows.size() == 3);
  double worst = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    const double t = test.times_min[k];
    const double m0 = std::exp(-S[0] * t);
    const double m1 = b10 * S[0] / (S[1] - S[0]) * (std::exp(-S[0] * t) - std::exp(-S[1] * t));
    INFO("t " << t << " min: m0 " << m0 << " m1 " << m1);
    CHECK(rows[k][0] == Approx(1).margin(1e-14));
    CHECK(rows[k][1] == Approx(1 - m0).epsilon(1e-13));  // measured 4e-16
    CHECK(rows[k][2] == Approx(1 - m0 - m1).epsilon(1e-13));  // measured 4e-16
    worst = std::max({worst, std::fabs(rows[k][1] / (1 - m0) - 1), std::fabs(rows[k][2] / (1 - m0 - m1) - 1)});
  }
  std::printf("batch products against the closed form: worst relative difference %.1e\n", worst);
}

TEST_CASE("Tavares' t_n with tn_beta other than 1: the incomplete beta against the beta density integrated",
          "[grind][t10][numbers]") {
  // tests/data/ore_t10_beta.toml: made-up alpha and beta, t_n falling with
  // n as the ore file asks.
  const Ore ore = mc::io::read_ore(std::string(MC_TEST_DATA) + "/ore_t10_beta.toml");
  const T10Breakage& t = ore.t10;
  REQUIRE(t.n.size() == 5);
  CHECK(t.beta[2] == 0.8);
  double worst = 0, worst_b = 0;
  for (double x : {0.003, 0.02, 0.1, 0.3, 0.5}) {
    std::vector<double> tn;
    for (std::size_t k = 0; k < t.n.size(); ++k) {
      const double ref = beta_by_quadrature(x, t.alpha[k], t.beta[k]);
      INFO("t10 " << x << " n " << t.n[k] << " alpha " << t.alpha[k] << " beta " << t.beta[k]);
      CHECK(t.tn(k, x) == Approx(ref).epsilon(2e-12));  // measured 2e-13
      worst = std::max(worst, std::fabs(t.tn(k, x) / ref - 1));
      tn.push_back(ref);
    }
    // The event's B(u) through those nodes: t_n at u = 1/n, log-log linear
    // between 1/2 and 1/4, the last segment's power law below 1/75.
    const double between = std::exp(std::log(tn[0]) + std::log(2.0 / 3) / std::log(0.5) * std::log(tn[1] / tn[0]));
    const double below = tn[4] * std::pow((1.0 / 150) / (1.0 / 75), std::log(tn[4] / tn[3]) / std::log(50.0 / 75));
    const double u[] = {0.25, 0.1, 1.0 / 3, 1.0 / 150}, want[] = {tn[1], x, between, below};
    for (int k = 0; k < 4; ++k) {
      INFO("t10 " << x << " u " << u[k]);
      CHECK(t.cumulative(u[k], x) == Approx(want[k]).epsilon(2e-12));
      worst_b = std::max(worst_b, std::fabs(t.cumulative(u[k], x) / want[k] - 1));
    }
  }
  std::printf("t_n with tn_beta != 1 against the quadrature: worst relative difference %.1e, B(u) %.1e\n", worst,
              worst_b);
}
