#include "grind/pbm.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace mc::grind {

namespace {
constexpr double kPi = 3.14159265358979323846;

// dm/dt for the batch equations (the sink's rate taken as 0).
void rates_of_change(const std::vector<double>& m, const std::vector<double>& S,
                     const std::vector<std::vector<double>>& b, std::vector<double>& out) {
  const std::size_t n = m.size();
  for (std::size_t i = 0; i < n; ++i) {
    double d = i + 1 < n ? -S[i] * m[i] : 0.0;
    for (std::size_t j = 0; j < i && j + 1 < n; ++j) d += b[i][j] * S[j] * m[j];
    out[i] = d;
  }
}
}  // namespace

double SizeSeries::mid_m(int i) const {
  const int n = size();
  if (i + 1 < n) return std::sqrt(top_m[i] * top_m[i + 1]);
  const double ratio = n > 1 ? top_m[n - 2] / top_m[n - 1] : 2.0;
  return top_m[n - 1] / std::sqrt(ratio);
}

SizeSeries geometric_series(double top_m, double ratio, int n) {
  SizeSeries s;
  for (int i = 0; i < n; ++i) s.top_m.push_back(top_m / std::pow(ratio, i));
  return s;
}

double AustinBreakage::cumulative(double u) const {
  if (u >= 1) return 1.0;
  if (u <= 0) return 0.0;
  return std::min(1.0, phi * std::pow(u, gamma) + (1 - phi) * std::pow(u, beta));
}

double incomplete_beta(double x, double a, double b) {
  if (!(x > 0)) return 0.0;
  if (x >= 1) return 1.0;
  // The continued fraction converges fast below (a + 1) / (a + b + 2);
  // above it, I_x(a, b) = 1 - I_{1-x}(b, a).
  if (x > (a + 1) / (a + b + 2)) return 1.0 - incomplete_beta(1 - x, b, a);
  const double front =
      std::exp(a * std::log(x) + b * std::log1p(-x) - (std::lgamma(a) + std::lgamma(b) - std::lgamma(a + b))) / a;
  // I_x = front / (1 + d1 / (1 + d2 / (1 + ...))), with
  // d_{2m+1} = -(a + m)(a + b + m) x / ((a + 2m)(a + 2m + 1)) and
  // d_{2m} = m (b - m) x / ((a + 2m - 1)(a + 2m)); Lentz's method on
  // 1 + 1 / (1 + d1 / ...), whose value less one is the fraction.
  constexpr double tiny = 1e-300;
  double f = 1, c = 1, d = 0;
  for (int i = 0; i <= 1000; ++i) {
    const double m = i / 2;
    double num = 1;
    if (i > 0 && i % 2 == 0) num = m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m));
    if (i % 2 == 1) num = -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1));
    d = 1 + num * d;
    d = 1 / (std::fabs(d) < tiny ? tiny : d);
    c = 1 + num / c;
    if (std::fabs(c) < tiny) c = tiny;
    f *= c * d;
    if (std::fabs(1 - c * d) < 1e-15) break;
  }
  return std::clamp(front * (f - 1), 0.0, 1.0);
}

double T10Breakage::t10(double r) const { return a * (1 - std::exp(-b_prime * std::max(r, 0.0))); }

double T10Breakage::tn(std::size_t k, double t) const { return incomplete_beta(t, alpha[k], beta[k]); }

namespace {
// One event's cumulative B(u): (ln u, ln B) nodes from u = 1 down to the
// smallest 1/n, log-log linear between them, the last segment's power law
// below. Each node is kept at or under the one above, so B never falls as
// u grows.
class T10Curve {
 public:
  T10Curve(const T10Breakage& t, double t10) {
    lu_.push_back(0.0);
    lb_.push_back(0.0);
    bool ten = false;
    auto node = [&](double n, double tn) {
      const double l = std::log(std::max(tn, 1e-300));
      lu_.push_back(-std::log(n));
      lb_.push_back(std::min(l, lb_.back()));
    };
    for (std::size_t k = 0; k < t.n.size(); ++k) {
      if (!ten && t.n[k] > 10) node(10, t10), ten = true;
      node(t.n[k], t.tn(k, t10));
    }
    if (!ten) node(10, t10);
  }
  double operator()(double u) const {
    if (u >= 1) return 1.0;
    if (!(u > 0)) return 0.0;
    const double l = std::log(u);
    std::size_t k = 1;
    while (k + 1 < lu_.size() && l < lu_[k]) ++k;
    // Segment k-1 .. k (below the last node: its slope carried on).
    const double slope = (lb_[k - 1] - lb_[k]) / (lu_[k - 1] - lu_[k]);
    return std::min(1.0, std::exp(lb_[k] + slope * (l - lu_[k])));
  }

 private:
  std::vector<double> lu_, lb_;
};
}  // namespace

double T10Breakage::cumulative(double u, double t) const { return T10Curve(*this, t)(u); }

std::vector<std::vector<double>> breakage_matrix(const SizeSeries& s, const AustinBreakage& br) {
  const int n = s.size();
  std::vector<std::vector<double>> b(n, std::vector<double>(n, 0.0));
  for (int j = 0; j + 1 < n; ++j) {
    const double lower = s.top_m[j + 1];  // what breaks leaves class j
    for (int i = j + 1; i < n; ++i) {
      const double hi = br.cumulative(s.top_m[i] / lower);
      const double lo = i + 1 < n ? br.cumulative(s.top_m[i + 1] / lower) : 0.0;
      b[i][j] = hi - lo;
    }
  }
  return b;
}

namespace {
using Matrix = std::vector<std::vector<double>>;

// C = A B for lower-triangular A and B (C lower-triangular).
Matrix lower_product(const Matrix& A, const Matrix& B) {
  const std::size_t n = A.size();
  Matrix C(n, std::vector<double>(n, 0.0));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = 0; k <= i; ++k) {
      const double a = A[i][k];
      if (a == 0) continue;
      for (std::size_t j = 0; j <= k; ++j) C[i][j] += a * B[k][j];
    }
  return C;
}
}  // namespace

std::vector<double> batch_grind(const std::vector<double>& m0, const std::vector<double>& S,
                                const std::vector<std::vector<double>>& b, double t) {
  if (!(t > 0)) return m0;
  const std::size_t n = m0.size();
  // The system's matrix times t: -S_j t on the diagonal, b_ij S_j t below
  // (the sink's S taken as 0).
  Matrix A(n, std::vector<double>(n, 0.0));
  double norm = 0;  // its 1-norm (largest column sum of magnitudes)
  for (std::size_t j = 0; j + 1 < n; ++j) {
    A[j][j] = -S[j] * t;
    double col = std::fabs(A[j][j]);
    for (std::size_t i = j + 1; i < n; ++i) col += std::fabs(A[i][j] = b[i][j] * S[j] * t);
    norm = std::max(norm, col);
  }
  if (!(norm > 0)) return m0;
  // exp(A) by scaling and squaring: A / 2^q has a norm of at most 1/4, where
  // Taylor's series to the 14th power is exact to about 1e-20; then squared
  // q times. The cost grows with log2(S_max t), not with S_max t.
  const int q = std::max(0, static_cast<int>(std::ceil(std::log2(norm / 0.25))));
  const double scale = std::ldexp(1.0, -q);
  for (auto& row : A)
    for (double& a : row) a *= scale;
  Matrix E(n, std::vector<double>(n, 0.0));
  for (std::size_t i = 0; i < n; ++i) E[i][i] = 1;
  for (int k = 14; k >= 1; --k) {  // Horner: I + A (I + A/2 (I + A/3 (...)))
    E = lower_product(A, E);
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j <= i; ++j) E[i][j] /= k;
      E[i][i] += 1;
    }
  }
  for (int k = 0; k < q; ++k) E = lower_product(E, E);
  std::vector<double> m(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j <= i; ++j) m[i] += E[i][j] * m0[j];
  return m;
}

std::vector<double> batch_grind_rk4(const std::vector<double>& m0, const std::vector<double>& S,
                                    const std::vector<std::vector<double>>& b, double t) {
  std::vector<double> m = m0;
  if (!(t > 0)) return m;
  double s_max = 0;
  for (std::size_t i = 0; i + 1 < S.size(); ++i) s_max = std::max(s_max, S[i]);
  if (s_max <= 0) return m;
  const long steps = std::max(1L, static_cast<long>(std::ceil(t * s_max / 0.01)));
  const double h = t / steps;
  const std::size_t n = m.size();
  std::vector<double> k1(n), k2(n), k3(n), k4(n), y(n);
  for (long s = 0; s < steps; ++s) {
    rates_of_change(m, S, b, k1);
    for (std::size_t i = 0; i < n; ++i) y[i] = m[i] + 0.5 * h * k1[i];
    rates_of_change(y, S, b, k2);
    for (std::size_t i = 0; i < n; ++i) y[i] = m[i] + 0.5 * h * k2[i];
    rates_of_change(y, S, b, k3);
    for (std::size_t i = 0; i < n; ++i) y[i] = m[i] + h * k3[i];
    rates_of_change(y, S, b, k4);
    for (std::size_t i = 0; i < n; ++i) m[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
  }
  return m;
}

std::vector<double> reid_batch(const std::vector<double>& m0, const std::vector<double>& S_in,
                               const std::vector<std::vector<double>>& b, double t) {
  const std::size_t n = m0.size();
  std::vector<double> S = S_in;
  S[n - 1] = 0;  // the sink
  std::vector<std::vector<double>> a(n, std::vector<double>(n, 0.0));
  for (std::size_t i = 0; i < n; ++i) {
    double sum = 0;
    for (std::size_t j = 0; j < i; ++j) {
      double c = 0;
      for (std::size_t k = j; k < i; ++k) c += S[k] * b[i][k] * a[k][j];
      // Reid's coefficients divide by the rates' differences: rates alike to
      // 1e-6 lose every digit (batch_grind's exact solve has no such limit).
      if (std::fabs(S[i] - S[j]) <= 1e-6 * std::max(std::fabs(S[i]), std::fabs(S[j])) && c != 0)
        throw std::invalid_argument("reid_batch: classes " + std::to_string(j) + " and " + std::to_string(i) +
                                    " break at rates alike to 1e-6: Reid's solution has no digits left there");
      a[i][j] = c / (S[i] - S[j]);
      sum += a[i][j];
    }
    a[i][i] = m0[i] - sum;
  }
  std::vector<double> m(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j <= i; ++j) m[i] += a[i][j] * std::exp(-S[j] * t);
  return m;
}

std::vector<double> continuous_grind(const std::vector<double>& feed, const std::vector<double>& S,
                                     const std::vector<std::vector<double>>& b, double tau, int tanks) {
  const std::size_t n = feed.size();
  const double tk = tau / tanks;
  std::vector<double> in = feed, out(n);
  for (int k = 0; k < tanks; ++k) {
    for (std::size_t i = 0; i < n; ++i) {
      double born = 0;
      for (std::size_t j = 0; j < i && j + 1 < n; ++j) born += b[i][j] * S[j] * out[j];
      const double s = i + 1 < n ? S[i] : 0.0;
      out[i] = (in[i] + tk * born) / (1 + tk * s);
    }
    in = out;
  }
  return out;
}

double WhitenClassifier::beta_star() const {
  if (beta <= 0) return 1.0;
  // E(d50c) = C/2: (1 + beta b*)(e^a - 1) = (e^(a b*) + e^a - 2) / 2, with
  // the left side growing slower than the right for b* past the root.
  // Divided by e^a, so that no sharpness overflows: with q = 1 - e^-a,
  // 2 (1 + beta b*) q - (e^(a (b* - 1)) - 1 + 2 q).
  const double q = -std::expm1(-alpha);
  auto f = [&](double bs) { return 2 * (1 + beta * bs) * q - (std::expm1(alpha * (bs - 1)) + 2 * q); };
  double lo = 1e-6, hi = 1.0;
  while (f(hi) > 0 && hi < 1e3) hi *= 2;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) > 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double WhitenClassifier::to_overflow(double x_m) const {
  const double bs = beta_star(), y = x_m / d50c_m;
  // Numerator and denominator divided by e^alpha: with q = 1 - e^-alpha,
  //   E = C (1 + beta b* y) q / (e^(alpha (b* y - 1)) - 1 + 2 q),
  // which holds for any sharpness (e^alpha itself overflows past about
  // 709); as alpha grows it tends to the sharp cut: C below d50c, C/2 at
  // it, 0 above.
  const double q = -std::expm1(-alpha);
  const double e = (1 - bypass) * (1 + beta * bs * y) * q / (std::expm1(alpha * (bs * y - 1)) + 2 * q);
  return std::isfinite(e) ? std::clamp(e, 0.0, 1.0) : 0.0;
}

ClosedCircuit closed_circuit(const SizeSeries& s, const std::vector<double>& fresh_t_h, const std::vector<double>& S,
                             const std::vector<std::vector<double>>& b, double holdup_t, int tanks,
                             const WhitenClassifier& c) {
  const std::size_t n = fresh_t_h.size();
  std::vector<double> to_over(n);
  for (std::size_t i = 0; i < n; ++i) to_over[i] = c.to_overflow(s.mid_m(static_cast<int>(i)));
  double fresh = 0;
  for (double f : fresh_t_h) fresh += f;
  ClosedCircuit r;
  r.underflow.assign(n, 0.0);
  // Substitution: each pass grinds the fresh feed with the last underflow.
  // The underflow's error shrinks by about CL / (1 + CL) a pass.
  for (r.iterations = 1; r.iterations <= 200000; ++r.iterations) {
    std::vector<double> in(n);
    double q = 0;
    for (std::size_t i = 0; i < n; ++i) q += (in[i] = fresh_t_h[i] + r.underflow[i]);
    r.residence_min = holdup_t / q * 60;
    r.mill_product = continuous_grind(in, S, b, r.residence_min, tanks);
    double change = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double u = (1 - to_over[i]) * r.mill_product[i];
      change = std::max(change, std::fabs(u - r.underflow[i]));
      r.underflow[i] = u;
    }
    if (change <= 1e-13 * q) {
      r.converged = true;
      break;
    }
  }
  r.product.resize(n);
  double under = 0;
  for (std::size_t i = 0; i < n; ++i) {
    r.product[i] = to_over[i] * r.mill_product[i];
    under += r.underflow[i];
  }
  r.circulating_load = fresh > 0 ? under / fresh : 0;
  return r;
}

std::vector<double> passing(const std::vector<double>& m) {
  std::vector<double> p(m.size());
  double below = 0;
  for (std::size_t k = m.size(); k-- > 0;) {
    below += m[k];
    p[k] = below;
  }
  return p;
}

double passing_size(const SizeSeries& s, const std::vector<double>& m, double p) {
  const std::vector<double> P = passing(m);
  const double total = P.empty() ? 0 : P[0];
  const double target = p * total;
  // P descends with the index; find the tops that bracket the target.
  for (int i = 0; i + 1 < s.size(); ++i) {
    if (P[i] >= target && P[i + 1] <= target) {
      if (P[i] == P[i + 1]) return s.top_m[i + 1];
      const double f = (target - P[i + 1]) / (P[i] - P[i + 1]);
      return std::exp(std::log(s.top_m[i + 1]) + f * (std::log(s.top_m[i]) - std::log(s.top_m[i + 1])));
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

std::vector<double> feed_masses(const SizeSeries& s, const std::vector<double>& sieve_m,
                                const std::vector<double>& pass_given) {
  const int n = s.size();
  // A test's passing may rise a little toward the finer sieves (within its
  // noise); differenced as it stands, the class masses would sum past 1.
  // It is made monotone first by pooling adjacent violators (each run of
  // sieves that rises replaced by its mean: the least-squares non-increasing
  // curve), none above the coarsest sieve's passing.
  std::vector<double> pass(pass_given);
  if (!pass.empty()) {
    std::vector<double> value;
    std::vector<int> count;
    for (std::size_t k = 1; k < pass.size(); ++k) {
      value.push_back(std::min(pass[k], pass[0]));
      count.push_back(1);
      while (value.size() >= 2 && value[value.size() - 2] < value.back()) {
        const std::size_t b = value.size() - 1;
        value[b - 1] = (value[b - 1] * count[b - 1] + value[b] * count[b]) / (count[b - 1] + count[b]);
        count[b - 1] += count[b];
        value.pop_back();
        count.pop_back();
      }
    }
    std::size_t k = 1;
    for (std::size_t b = 0; b < value.size(); ++b)
      for (int c = 0; c < count[b]; ++c) pass[k++] = value[b];
  }
  auto at = [&](double x) {
    if (x >= sieve_m.front()) return 1.0;
    for (std::size_t k = 0; k + 1 < sieve_m.size(); ++k)
      if (x <= sieve_m[k] && x >= sieve_m[k + 1]) {
        const double f = (std::log(x) - std::log(sieve_m[k + 1])) / (std::log(sieve_m[k]) - std::log(sieve_m[k + 1]));
        return pass[k + 1] + f * (pass[k] - pass[k + 1]);
      }
    // Below the finest sieve: Gates-Gaudin-Schuhmann through its point, slope
    // from the last two sieves (or proportional to size).
    const std::size_t L = sieve_m.size() - 1;
    double slope = 1.0;
    if (L >= 1 && pass[L] > 0 && pass[L - 1] > pass[L])
      slope = std::log(pass[L - 1] / pass[L]) / std::log(sieve_m[L - 1] / sieve_m[L]);
    return pass[L] * std::pow(x / sieve_m[L], slope);
  };
  std::vector<double> m(n);
  for (int i = 0; i < n; ++i) {
    const double hi = i == 0 ? 1.0 : at(s.top_m[i]);
    const double lo = i + 1 < n ? at(s.top_m[i + 1]) : 0.0;
    m[i] = std::max(0.0, hi - lo);
  }
  return m;
}

std::vector<double> austin_rates(const SizeSeries& s, const AustinRates& r) {
  std::vector<double> S(s.size());
  for (int i = 0; i < s.size(); ++i) {
    const double x = s.top_m[i];
    S[i] = r.a_per_min * std::pow(x / 1e-3, r.alpha) / (1 + std::pow(x / r.mu_m, r.lambda));
  }
  return S;
}

std::vector<double> energy_specific_rates(const SizeSeries& s, const EnergyRates& r) {
  std::vector<double> S(s.size());
  for (int i = 0; i < s.size(); ++i) {
    const double l = std::log(s.mid_m(i) / r.x1_m);
    S[i] = r.s1e_t_per_kWh * std::exp(r.zeta1 * l + r.zeta2 * l * l);
  }
  return S;
}

double Fracture::e50(double d_m) const { return e_inf_J_kg * (1 + std::pow(d0_m / d_m, phi)); }

double Fracture::broken(double e, double d_m) const {
  if (!(e > 0)) return 0.0;
  const double m50 = e50(d_m), emax = emax_ratio * m50;
  if (e >= emax) return 1.0;
  const double star = emax * e / (emax - e), star50 = emax * m50 / (emax - m50);
  return 0.5 * (1 + std::erf((std::log(star) - std::log(star50)) / (std::sqrt(2.0) * sigma)));
}

double captured_mass(double d_m, double r_eff_m, double ore_density, double packing) {
  return packing * kPi * kPi / 3 * ore_density * d_m * d_m * r_eff_m;
}

double median_broken_energy(const Fracture& f, double e, double d_m) {
  const double half = 0.5 * f.broken(e, d_m);
  if (!(half > 0)) return 0.0;
  // P rises with the energy: bisect its logarithm below e.
  double lo = std::log(e) - 80, hi = std::log(e);
  for (int k = 0; k < 100; ++k) {
    const double mid = 0.5 * (lo + hi);
    (f.broken(std::exp(mid), d_m) < half ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

std::vector<std::vector<double>> t10_breakage_matrix(const SizeSeries& s, const std::vector<SpectrumBin>& spectrum,
                                                     const Fracture& f, const T10Breakage& t, double ore_density,
                                                     double packing, std::vector<double>* t10_mean,
                                                     std::vector<double>* leaving) {
  const int n = s.size();
  std::vector<std::vector<double>> b(n, std::vector<double>(n, 0.0));
  if (t10_mean) t10_mean->assign(n, 0.0);
  if (leaving) leaving->assign(n, 1.0);
  for (int j = 0; j + 1 < n; ++j) {
    // The parent's size is the class's geometric mean, for the event's
    // energy (captured mass, E50) and for its progeny B(size / parent).
    const double d = s.mid_m(j), lower = s.top_m[j + 1];
    double weight = 0, t10_sum = 0, left = 0;
    auto add = [&](double t10, double w) {
      const T10Curve B(t, t10);
      for (int i = j + 1; i < n; ++i) {
        const double hi = B(s.top_m[i] / d), lo = i + 1 < n ? B(s.top_m[i + 1] / d) : 0.0;
        b[i][j] += w * (hi - lo);
      }
      weight += w;
      t10_sum += w * t10;
      left += w * B(lower / d);  // the progeny finer than the class: what leaves it
    };
    for (const SpectrumBin& k : spectrum) {
      if (k.collisions_per_s <= 0 || k.energy_J <= 0) continue;
      const double m = captured_mass(d, k.r_eff_m, ore_density, packing), e = k.energy_J / m;
      const double w = k.collisions_per_s * m * f.broken(e, d);
      if (w > 0) add(t.t10(e / median_broken_energy(f, e, d)), w);
    }
    if (!(weight > 0)) {
      const double e = f.e50(d);
      add(t.t10(e / median_broken_energy(f, e, d)), 1.0);
    }
    // The progeny still coarser than the class's lower size stay in it: the
    // column is what leaves, and sums to 1.
    for (int i = j + 1; i < n; ++i) b[i][j] /= left;
    if (t10_mean) (*t10_mean)[j] = t10_sum / weight;
    if (leaving) (*leaving)[j] = left / weight;
  }
  return b;
}

std::vector<double> spectrum_rates(const SizeSeries& s, const std::vector<SpectrumBin>& spectrum,
                                   const Fracture& f, double ore_density, double packing, double efficiency,
                                   double holdup_kg) {
  std::vector<double> S(s.size(), 0.0);
  for (int i = 0; i + 1 < s.size(); ++i) {
    const double d = s.mid_m(i);
    double broken_kg_s = 0;
    for (const SpectrumBin& k : spectrum) {
      if (k.collisions_per_s <= 0 || k.energy_J <= 0) continue;
      const double m = captured_mass(d, k.r_eff_m, ore_density, packing);
      broken_kg_s += k.collisions_per_s * m * f.broken(k.energy_J / m, d);
    }
    S[i] = efficiency * broken_kg_s / holdup_kg;
  }
  return S;
}

}  // namespace mc::grind
