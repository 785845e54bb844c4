// The grind's numbers against independent computations: the batch solver's
// exact exponential against Reid's closed form, the Runge-Kutta reference
// and equal rates; a feed whose passing rises within its noise; Whiten's
// curve at any sharpness against the sharp cut; Bond's locked cycles
// against their equilibrium found directly.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "grind/bond.h"
#include "grind/circuit.h"
#include "grind/ore.h"
#include "grind/pbm.h"

using namespace mc::grind;

namespace {

using Matrix = std::vector<std::vector<double>>;

double sum(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

// Solves A x = y by Gaussian elimination with partial pivoting.
std::vector<double> solve(Matrix A, std::vector<double> y) {
  const std::size_t n = y.size();
  for (std::size_t c = 0; c < n; ++c) {
    std::size_t p = c;
    for (std::size_t r = c + 1; r < n; ++r)
      if (std::fabs(A[r][c]) > std::fabs(A[p][c])) p = r;
    std::swap(A[c], A[p]);
    std::swap(y[c], y[p]);
    for (std::size_t r = c + 1; r < n; ++r) {
      const double f = A[r][c] / A[c][c];
      for (std::size_t k = c; k < n; ++k) A[r][k] -= f * A[c][k];
      y[r] -= f * y[c];
    }
  }
  std::vector<double> x(n);
  for (std::size_t r = n; r-- > 0;) {
    double s = y[r];
    for (std::size_t k = r + 1; k < n; ++k) s -= A[r][k] * x[k];
    x[r] = s / A[r][r];
  }
  return x;
}

}  // namespace

TEST_CASE("batch grinding exactly: Reid's closed form, the Runge-Kutta reference, equal rates, any time",
          "[grind][numbers]") {
  const SizeSeries s = geometric_series(45e-3, std::sqrt(2.0), 30);
  const Matrix b = breakage_matrix(s, AustinBreakage{0.55, 1.2, 4.0});
  const std::vector<double> S = austin_rates(s, AustinRates{0.9, 1.1, 20e-3, 2.5});
  std::vector<double> feed(30, 0.0);
  feed[0] = 0.5, feed[1] = 0.3, feed[2] = 0.2;
  double worst_reid = 0, worst_rk = 0;
  for (double t : {0.05, 0.5, 2.0, 8.0}) {
    const std::vector<double> m = batch_grind(feed, S, b, t);
    const std::vector<double> reid = reid_batch(feed, S, b, t);
    const std::vector<double> rk = batch_grind_rk4(feed, S, b, t);
    for (std::size_t i = 0; i < m.size(); ++i) {
      INFO("t " << t << " class " << i << ": " << m[i] << " Reid " << reid[i] << " RK4 " << rk[i]);
      CHECK(std::fabs(m[i] - reid[i]) <= 1e-12);
      CHECK(std::fabs(m[i] - rk[i]) <= 1e-9);
      worst_reid = std::max(worst_reid, std::fabs(m[i] - reid[i]));
      worst_rk = std::max(worst_rk, std::fabs(m[i] - rk[i]));
    }
    CHECK(sum(m) == Approx(1.0).margin(1e-13));
  }
  std::printf("batch grind (exact) vs Reid: worst %.1e, vs RK4: worst %.1e\n", worst_reid, worst_rk);
  // Equal rates, where Reid's form divides by zero: two classes and the
  // sink, S on both, all of class 0 to class 1. m1 = b S t e^(-S t) by hand.
  SizeSeries three;
  three.top_m = {4e-3, 2e-3, 1e-3};
  const Matrix b3 = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<double> m3 = batch_grind({1, 0, 0}, {0.7, 0.7, 0}, b3, 3.0);
  CHECK(m3[0] == Approx(std::exp(-2.1)).epsilon(1e-13));
  CHECK(m3[1] == Approx(2.1 * std::exp(-2.1)).epsilon(1e-13));
  CHECK(m3[2] == Approx(1 - std::exp(-2.1) - 2.1 * std::exp(-2.1)).epsilon(1e-13));
  // Any time costs about the same: S_max t of 1e6 leaves everything in the
  // sink, mass kept, in about the time of a short grind.
  double smax = 0;
  for (std::size_t i = 0; i + 1 < S.size(); ++i) smax = std::max(smax, S[i]);
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<double> long_grind = batch_grind(feed, S, b, 1e6 / smax);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  CHECK(long_grind.back() == Approx(1.0).margin(1e-9));
  CHECK(sum(long_grind) == Approx(1.0).margin(1e-12));
  for (double x : long_grind) CHECK(x >= -1e-12);
  std::printf("batch grind to S_max t = 1e6: %.4f s\n", seconds);
}

TEST_CASE("a feed whose passing rises within its noise: made monotone, masses summing to 1", "[grind][numbers]") {
  // Sieves 4, 2, 1, 0.5 mm passing 1, 0.5, 0.515 (1.5 pp up), 0.2. The
  // least-squares non-increasing curve pools the rising pair at their mean:
  // 1, 0.5075, 0.5075, 0.2; differenced on classes of tops 4, 2, 1 and
  // 0.5 mm (the last the sink): 0.4925, 0, 0.3075, 0.2.
  const SizeSeries s = geometric_series(4e-3, 2.0, 4);
  const std::vector<double> m = feed_masses(s, {4e-3, 2e-3, 1e-3, 0.5e-3}, {1.0, 0.5, 0.515, 0.2});
  CHECK(m[0] == Approx(0.4925).margin(1e-12));
  CHECK(m[1] == Approx(0.0).margin(1e-12));
  CHECK(m[2] == Approx(0.3075).margin(1e-12));
  CHECK(m[3] == Approx(0.2).margin(1e-12));
  CHECK(sum(m) == Approx(1.0).margin(1e-12));
  // Two rises in a row pool as one run: 1, 0.4, 0.45, 0.5, 0.1 -> 0.45 x 3.
  const std::vector<double> m2 =
      feed_masses(geometric_series(8e-3, 2.0, 5), {8e-3, 4e-3, 2e-3, 1e-3, 0.5e-3}, {1.0, 0.4, 0.45, 0.5, 0.1});
  CHECK(m2[0] == Approx(0.55).margin(1e-12));
  CHECK(m2[1] == Approx(0.0).margin(1e-12));
  CHECK(m2[2] == Approx(0.0).margin(1e-12));
  CHECK(m2[3] == Approx(0.35).margin(1e-12));
}

TEST_CASE("Whiten's curve at any sharpness: finite, and the sharp cut in the limit", "[grind][numbers]") {
  // As alpha grows, E -> C below d50c, C/2 at it, 0 above. At y = 0.95 and
  // 1.05 the curve differs from that by about C e^(-0.05 alpha).
  for (double alpha : {800.0, 5000.0, 1e6}) {
    INFO("alpha " << alpha);
    const WhitenClassifier c{106e-6, alpha, 0.3, 0};
    CHECK(c.to_overflow(0.95 * 106e-6) == Approx(0.7).margin(1e-15 + 0.7 * std::exp(-0.05 * alpha)));
    CHECK(c.to_overflow(106e-6) == Approx(0.35).epsilon(1e-12));
    CHECK(c.to_overflow(1.05 * 106e-6) <= 0.7 * std::exp(-0.05 * alpha) * 1.01);
    CHECK(c.to_overflow(1e-3) == 0.0);
    CHECK(c.to_overflow(1e-7) == Approx(0.7).epsilon(1e-12));
    // With a fish hook too: finite, C/2 at d50c.
    const WhitenClassifier h{106e-6, alpha, 0.3, 0.5};
    CHECK(std::isfinite(h.to_overflow(50e-6)));
    CHECK(h.to_overflow(106e-6) == Approx(0.35).epsilon(1e-6));
  }
  // A closed circuit at sharpness 800 is the sharp cut's: classes whose
  // mean lies below d50c all to the overflow, the rest back (a class's
  // mean is never within 1 % of d50c here, where e^-8 < 4e-4).
  const SizeSeries s = geometric_series(3.35e-3, std::sqrt(2.0), 20);
  const Matrix b = breakage_matrix(s, AustinBreakage{0.55, 1.2, 4.0});
  const std::vector<double> S = austin_rates(s, AustinRates{0.9, 1.1, 2.5e-3, 2.5});
  std::vector<double> fresh(20, 0.0);
  fresh[0] = 0.006, fresh[1] = 0.003, fresh[2] = 0.001;  // t/h
  const ClosedCircuit sharp = closed_circuit(s, fresh, S, b, 0.02, 1, WhitenClassifier{106e-6, 800, 0, 0});
  REQUIRE(sharp.converged);
  CHECK(sum(sharp.product) == Approx(0.01).epsilon(1e-9));
  INFO("circulating load " << sharp.circulating_load);
  for (int i = 0; i < s.size(); ++i) {
    INFO("class " << i << " mean " << s.mid_m(i) * 1e6 << " um");
    if (s.mid_m(i) > 106e-6) CHECK(sharp.product[i] <= 1e-12);
    else CHECK(sharp.product[i] == Approx(sharp.mill_product[i]).epsilon(1e-3));
  }
  CHECK(std::isfinite(passing_size(s, sharp.product, 0.8)));
}

TEST_CASE("Bond's locked cycles reach the equilibrium found directly", "[grind][numbers]") {
  // A toy ore on a sqrt(2) series, P1 on a class top. At the equilibrium
  // every cycle starts from the same charge m, turns N revolutions, and the
  // undersize u is a third of the oversize (250 %). For a given N the cycle
  // is linear in m: m' = (I - P) E m + f 1'(P E m), E = exp(A N / rpm) (by
  // Reid's closed form here), P the classes below P1, f the fresh feed; its
  // fixed point of mass `charge` is solved as a linear system, and N
  // bisected until u = charge / 3.5. Then Gbp = (u - u_fresh) / N.
  const int n = 24;
  const SizeSeries s = geometric_series(3.35e-3, std::sqrt(2.0), n);
  const Matrix b = breakage_matrix(s, AustinBreakage{0.55, 1.2, 4.0});
  const std::vector<double> S = austin_rates(s, AustinRates{0.4, 1.1, 2.5e-3, 2.5});
  std::vector<double> feed(n, 0.0);
  const double f_w[] = {0.2, 0.2, 0.15, 0.12, 0.1, 0.08, 0.06, 0.04, 0.03, 0.02};
  for (int i = 0; i < 10; ++i) feed[i] = f_w[i];
  feed[n - 1] = 1 - sum(feed);
  const int k1 = 10;  // P1 = top of class 10
  const double p1 = s.top_m[k1], rpm = 70, charge_g = 1260;
  double fresh_fines = 0;
  for (int i = k1; i < n; ++i) fresh_fines += feed[i];

  auto equilibrium = [&](double N, std::vector<double>& m) {
    Matrix E(n, std::vector<double>(n));
    for (int j = 0; j < n; ++j) {
      std::vector<double> e(n, 0.0);
      e[j] = 1;
      const std::vector<double> col = reid_batch(e, S, b, N / rpm);
      for (int i = 0; i < n; ++i) E[i][j] = col[i];
    }
    Matrix A(n, std::vector<double>(n, 0.0));  // M - I
    for (int j = 0; j < n; ++j) {
      double pe = 0;
      for (int i = k1; i < n; ++i) pe += E[i][j];
      for (int i = 0; i < n; ++i) A[i][j] = (i < k1 ? E[i][j] : 0.0) + feed[i] * pe - (i == j ? 1 : 0);
    }
    std::vector<double> y(n, 0.0);
    A[0].assign(n, 1.0);  // one equation traded for the mass
    y[0] = charge_g;
    m = solve(A, y);
    double u = 0;
    for (int i = k1; i < n; ++i)
      for (int j = 0; j < n; ++j) u += E[i][j] * m[j];
    return u;
  };
  double lo = 10, hi = 5000;
  std::vector<double> m;
  for (int k = 0; k < 200; ++k) {
    const double mid = std::sqrt(lo * hi);
    (equilibrium(mid, m) < charge_g / 3.5 ? lo : hi) = mid;
  }
  const double N = std::sqrt(lo * hi), u = equilibrium(N, m);
  const double gbp = (u - fresh_fines * u) / N;

  const BondResult r = bond_test(s, feed, S, b, rpm, charge_g / 1000, p1);
  INFO("cycles " << r.cycles << " Gbp " << r.gbp_g_rev << " direct " << gbp << " revs " << N);
  REQUIRE(r.steady);
  CHECK(r.gbp_g_rev == Approx(gbp).epsilon(1e-5));
  CHECK(r.revs_by_cycle.back() == Approx(N).epsilon(1e-5));
  CHECK(r.circulating_load == Approx(2.5).epsilon(1e-5));
  // Bond's formula at the equilibrium, per tonne (1 short ton = 907.18474 kg).
  const double wi = 1000 / 907.18474 * 44.5 /
                    (std::pow(p1 * 1e6, 0.23) * std::pow(gbp, 0.82) *
                     (10 / std::sqrt(r.p80_um) - 10 / std::sqrt(r.f80_um)));
  CHECK(r.wi_kWh_t == Approx(wi).epsilon(1e-5));
  std::printf("Bond's cycles: %d to the equilibrium, Gbp %.6f g/rev (direct %.6f), %.2f rev\n", r.cycles,
              r.gbp_g_rev, gbp, N);
}

TEST_CASE("Bond's test needs classes below its closing sieve", "[grind][numbers]") {
  const SizeSeries s = geometric_series(3.35e-3, std::sqrt(2.0), 20);
  CHECK_THROWS_WITH(check_bond_sieve(s, s.top_m.back()), Catch::Contains("--bond") && Catch::Contains("finest class"));
  CHECK_THROWS_AS(check_bond_sieve(s, s.top_m.back() / 2), std::invalid_argument);
  CHECK_NOTHROW(check_bond_sieve(s, s.top_m[s.size() - 2]));
}

TEST_CASE("the captured mass against a direct integration over the gap narrower than d", "[grind][numbers]") {
  // A sphere of radius R over a plane leaves the gap h(r) = R - sqrt(R² - r²)
  // at a distance r from the contact; particles of size d sit where h < d,
  // one per d² lattice site of a square lattice of spacing d, a share p of
  // the sites filled, each of mass rho pi d³ / 6. Integrated over r here by
  // the midpoint rule; as d / R -> 0 it tends to p (pi²/3) rho d² R, and
  // with the area fraction of circles phi = p pi / 4 that is
  // phi (4 pi / 3) rho d² R.
  const double R = 0.02, d = 2e-6, rho = 2700, p = 0.6;
  const int steps = 2000000;
  const double dr = R / steps;
  double mass = 0;
  for (int k = 0; k < steps; ++k) {
    const double r = (k + 0.5) * dr;
    if (R - std::sqrt(R * R - r * r) < d) mass += 2 * M_PI * r * dr * p / (d * d) * rho * M_PI * d * d * d / 6;
  }
  CHECK(captured_mass(d, R, rho, p) == Approx(mass).epsilon(2e-3));
  const double phi = p * M_PI / 4;
  CHECK(captured_mass(d, R, rho, p) == Approx(phi * 4 * M_PI / 3 * rho * d * d * R).epsilon(1e-12));
}

TEST_CASE("Tavares' t10 against the parent's size, the class's geometric mean", "[grind][numbers][t10]") {
  // A series of ratio r = 10^(1/3.5): the top of class j + 4 is a tenth of
  // class j's geometric mean, so the broken mass of class 0 finer than it is
  // t10 of what breaks. One collision bin hard enough to break every
  // particle (e above E_max), so E50b = E50 and t10 = A (1 - exp(-b' e / E50)).
  // The Schuhmann family (alpha_n = log10 n, beta_n = 1): B(u) = u^(-log10 t10).
  // What leaves class 0 is its progeny finer than its lower size,
  // L = B(r^(-1/2)); the column is per unit of that, and the rate S L.
  const double r = std::pow(10.0, 1 / 3.5);
  Ore ore;
  ore.sizes = geometric_series(3.35e-3, r, 8);
  ore.density = 2700;
  ore.packing = 0.6;
  ore.efficiency = 0.5;
  ore.model = RateModel::spectrum;
  ore.appearance = Appearance::t10;
  ore.fracture = Fracture{100, 1e-3, 1.0, 0.8, 10};
  ore.t10.a = 0.5;
  ore.t10.b_prime = 0.1;
  for (double n : {2.0, 4.0, 25.0, 50.0, 75.0}) {
    ore.t10.n.push_back(n);
    ore.t10.alpha.push_back(std::log10(n));
    ore.t10.beta.push_back(1.0);
  }
  const std::vector<SpectrumBin> spectrum = {{30.0, 1.0, 0.01}};  // 30 /s of 1 J, R_eff 10 mm
  const double d = 3.35e-3 / std::sqrt(r);
  const double m_cap = 0.6 * M_PI * M_PI / 3 * 2700 * d * d * 0.01;
  const double e50 = 100 * (1 + 1e-3 / d), e = 1.0 / m_cap;
  REQUIRE(e > 10 * e50);
  const double t10 = 0.5 * (1 - std::exp(-0.1 * e / e50));
  const double L = std::pow(std::pow(r, -0.5), -std::log10(t10));
  std::vector<double> t10_mean, leaving;
  const Matrix b = t10_breakage_matrix(ore.sizes, spectrum, ore.fracture, ore.t10, 2700, 0.6, &t10_mean, &leaving);
  double finer = 0, column = 0;
  for (int i = 1; i < ore.sizes.size(); ++i) column += b[i][0];
  for (int i = 4; i < ore.sizes.size(); ++i) finer += b[i][0];
  CHECK(t10_mean[0] == Approx(t10).epsilon(1e-12));
  CHECK(leaving[0] == Approx(L).epsilon(1e-9));
  CHECK(column == Approx(1.0).epsilon(1e-12));
  CHECK(finer * L == Approx(t10).epsilon(1e-9));
  // The rate: efficiency / H · N · m_cap · P (= 1) · L, per minute.
  const double H = 2.0;
  const MillRates rates = mill_rates(ore, spectrum, 100.0, H);
  CHECK(rates.S_per_min[0] == Approx(0.5 / H * 30 * m_cap * L * 60).epsilon(1e-9));
}
