// Which batch test to run next (next_test.h).
#include "grind/next_test.h"
#include "grind/sieve_errors.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace mc::grind {

namespace {

using Matrix = std::vector<std::vector<double>>;

double to_var(const OreParameter& p, double v) { return p.log ? std::log(v) : v; }
double from_var(const OreParameter& p, double x) { return p.log ? std::exp(x) : x; }
double var_lo(const OreParameter& p) { return to_var(p, p.log ? std::max(p.lo, 1e-300) : p.lo); }
double var_hi(const OreParameter& p) { return to_var(p, p.hi); }

// The inverse of a small symmetric positive definite matrix (Cholesky);
// false where it is not positive definite.
bool invert_spd(const Matrix& A, Matrix& inv) {
  const std::size_t n = A.size();
  Matrix L(n, std::vector<double>(n, 0.0));
  for (std::size_t j = 0; j < n; ++j) {
    double d = A[j][j];
    for (std::size_t k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
    if (!(d > 1e-300)) return false;
    L[j][j] = std::sqrt(d);
    for (std::size_t i = j + 1; i < n; ++i) {
      double s = A[i][j];
      for (std::size_t k = 0; k < j; ++k) s -= L[i][k] * L[j][k];
      L[i][j] = s / L[j][j];
    }
  }
  inv.assign(n, std::vector<double>(n, 0.0));
  for (std::size_t c = 0; c < n; ++c) {  // solve A x = e_c
    std::vector<double> y(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      double s = i == c ? 1.0 : 0.0;
      for (std::size_t k = 0; k < i; ++k) s -= L[i][k] * y[k];
      y[i] = s / L[i][i];
    }
    for (std::size_t i = n; i-- > 0;) {
      double s = y[i];
      for (std::size_t k = i + 1; k < n; ++k) s -= L[k][i] * inv[k][c];
      inv[i][c] = s / L[i][i];
    }
  }
  return true;
}

// The candidate's readings (pp) at its informative sieves, for an ore.
std::vector<double> readings(const Ore& o, const TestInMill& c, const std::vector<std::size_t>& sieves) {
  const auto pred = batch_test_products(o, c.spectrum, c.power_W, c.holdup_kg, c.test);
  std::vector<double> r;
  for (std::size_t t = 0; t < c.test.times_min.size(); ++t)
    for (std::size_t k : sieves) r.push_back(100 * pred[t][k]);
  return r;
}

// The column of J_c for one variable: central differences, one-sided of
// second order where a step would leave the ore file's range.
std::vector<double> column(const OreParameter& p, const Ore& ore, const TestInMill& c,
                           const std::vector<std::size_t>& sieves, const std::vector<double>& r0) {
  const double x = to_var(p, p.get(ore)), lo = var_lo(p), hi = var_hi(p);
  double h = 1e-4 * std::max(1.0, std::fabs(x));
  if (x - h < lo && x + h > hi) h = std::max(hi - x, x - lo) / 2;
  const int sign = x + h <= hi && x - h >= lo ? 0 : x + 2 * h <= hi ? +1 : -1;
  auto at = [&](double xv) {
    Ore o = ore;
    p.set(o, from_var(p, xv));
    return readings(o, c, sieves);
  };
  const std::vector<double> a = at(sign == 0 ? x + h : x + sign * h), b = at(sign == 0 ? x - h : x + 2 * sign * h);
  std::vector<double> col(r0.size());
  for (std::size_t i = 0; i < r0.size(); ++i)
    col[i] = sign == 0 ? (a[i] - b[i]) / (2 * h) : sign * (-3 * r0[i] + 4 * a[i] - b[i]) / (2 * h);
  return col;
}

}  // namespace

BatchTest candidate_test(const Ore& ore, const std::vector<double>& times_min) {
  BatchTest t;
  std::vector<double> sieves = {3.35e-3};
  for (int k = 0; k < 12; ++k) sieves.push_back(2.36e-3 / std::pow(std::sqrt(2.0), k));
  for (double x : sieves)
    if (x <= ore.sizes.top_m.front() * (1 + 1e-9) && x >= ore.sizes.top_m.back() * (1 - 1e-9)) t.sieve_m.push_back(x);
  for (double x : t.sieve_m) t.feed_passing.push_back(passing_at(ore.sizes, ore.feed, x));
  t.times_min = times_min;
  return t;
}

NextTestWidth expected_after(const Ore& ore, const FitCovariance& u, const Sensitivity& s,
                             const TestInMill& candidate) {
  NextTestWidth out;
  const std::size_t np = u.names.size(), nh = u.held.size(), nv = np + nh;
  if (!s.ok || s.g.size() != np || s.g_held.size() != nh) return out;
  // The candidate's readings as the fitted ore makes them, at the sieves
  // that carry information: at the best point (where the information kept
  // and the product's gradients are taken; the ore itself without held ones).
  const Ore at = best_point(ore, u);
  TestInMill c = candidate;
  c.test.passing = batch_test_products(at, c.spectrum, c.power_W, c.holdup_kg, c.test);
  const std::vector<std::size_t> sieves = informative_sieves(c.test);
  const std::vector<double> r0 = readings(at, c, sieves);
  out.data = static_cast<int>(r0.size());
  std::vector<const OreParameter*> ps;
  for (const std::string& n : u.names) ps.push_back(find_ore_parameter(n));
  for (const HeldParameter& h : u.held) ps.push_back(find_ore_parameter(h.name));
  Matrix Jc(r0.size(), std::vector<double>(nv));
  for (std::size_t v = 0; v < nv; ++v) {
    std::vector<double> col = column(*ps[v], at, c, sieves, r0);
    // Its readings' errors correlated along the sieves as the fit took them.
    whiten_rows(col.data(), c.test.times_min.size(), sieves.size(), c.sieve_rho);
    for (std::size_t i = 0; i < r0.size(); ++i) Jc[i][v] = col[i];
  }
  // The current information: the tests' JᵀJ / s² on every variable, kept
  // with the covariance (s² the fit's), taken at the intervals' s²
  // (interval_variance: S_min over the data less every parameter).
  if (u.information.size() != nv) return out;
  const double s2 = interval_variance(u);
  if (!(s2 > 0) || !(u.residual_variance_pp2 > 0)) return out;
  Matrix L = u.information;
  for (auto& row : L)
    for (double& v : row) v *= u.residual_variance_pp2 / s2;
  const Matrix Lnow = L;
  // The candidate's information: its readings scatter as the first test's (s²).
  out.added.assign(nv, std::vector<double>(nv));
  for (std::size_t a = 0; a < nv; ++a)
    for (std::size_t b = 0; b < nv; ++b) {
      double v = 0;
      for (std::size_t i = 0; i < r0.size(); ++i) v += Jc[i][a] * Jc[i][b];
      out.added[a][b] = v / s2;
      L[a][b] += v / s2;
    }
  // The variables estimated from an information matrix: the free ones and
  // every held one it reaches (positive definite); a held one without
  // information is dropped, one at a time, the least informed for its
  // limit first. The product's variance over all of them (cᵀ Σ c) and over
  // the free ones given the held (gᵀ L_ff⁻¹ g): for a model linear in its
  // parameters the first is the second plus the held parameters' part,
  // wᵀ S⁻¹ w (w the product's slope in them with the free ones refitted,
  // S their information with the free ones refitted: a Schur complement).
  // ok false where the free ones alone cannot be inverted.
  struct Solved {
    bool ok = false;
    std::vector<bool> in;
    std::vector<std::size_t> idx;
    Matrix Sigma;
    double var_all = 0, var_free = 0;
  };
  auto solve = [&](const Matrix& L) {
    Solved r;
    r.in.assign(nv, true);
    for (;;) {
      r.idx.clear();
      for (std::size_t v = 0; v < nv; ++v)
        if (r.in[v]) r.idx.push_back(v);
      Matrix sub(r.idx.size(), std::vector<double>(r.idx.size()));
      for (std::size_t a = 0; a < r.idx.size(); ++a)
        for (std::size_t b = 0; b < r.idx.size(); ++b) sub[a][b] = L[r.idx[a]][r.idx[b]];
      if (r.idx.empty() || invert_spd(sub, r.Sigma)) break;
      std::size_t drop = nv;
      double least = HUGE_VAL;
      for (std::size_t v : r.idx) {
        if (v < np) continue;
        const OreParameter& p = *ps[v];
        const double limit = p.log ? 1.0 : (p.hi - p.lo) / 4;
        const double info = std::max(L[v][v], 0.0) * limit * limit;
        if (info <= least) least = info, drop = v;
      }
      if (drop == nv) return r;
      r.in[drop] = false;
    }
    std::vector<double> grad(r.idx.size());
    for (std::size_t a = 0; a < r.idx.size(); ++a)
      grad[a] = r.idx[a] < np ? s.g[r.idx[a]] : s.g_held[r.idx[a] - np];
    for (std::size_t a = 0; a < r.idx.size(); ++a)
      for (std::size_t b = 0; b < r.idx.size(); ++b) r.var_all += grad[a] * r.Sigma[a][b] * grad[b];
    r.var_free = r.var_all;
    if (r.idx.size() > np) {
      Matrix Lff(np, std::vector<double>(np)), Cff;
      for (std::size_t a = 0; a < np; ++a)
        for (std::size_t b = 0; b < np; ++b) Lff[a][b] = L[a][b];
      if (!invert_spd(Lff, Cff)) return r;
      r.var_free = 0;
      for (std::size_t a = 0; a < np; ++a)
        for (std::size_t b = 0; b < np; ++b) r.var_free += s.g[a] * Cff[a][b] * s.g[b];
    }
    r.ok = true;
    return r;
  };
  const Solved after = solve(L);
  if (!after.ok) return out;
  const std::vector<bool>& in = after.in;
  const std::vector<std::size_t>& idx = after.idx;
  const Matrix& Sigma = after.Sigma;
  const double var_all = after.var_all, var_free = after.var_free;
  // Which held ones the sum fixes, by the fit's own rule (an expected
  // standard error within a factor of e for a scale, a quarter of its
  // range for a value): said, not used.
  for (std::size_t a = 0; a < idx.size(); ++a) {
    if (idx[a] < np) continue;
    const OreParameter& p = *ps[idx[a]];
    const double limit = p.log ? 1.0 : (p.hi - p.lo) / 4;
    if (std::sqrt(std::max(Sigma[a][a], 0.0)) <= limit) out.fixes.push_back(u.held[idx[a] - np].name);
  }
  out.sd = std::sqrt(std::max(var_free, 0.0));
  out.sd_all = std::sqrt(std::max(var_all, 0.0));
  // Student's t with the intervals' degrees of freedom (every parameter,
  // free and held, counted already) and the candidate's readings.
  const double t = t_quantile(0.975, interval_dof(u) + out.data);
  const double half = t * out.sd;
  // The held parameters' expected reach: their reach now (the profiles'
  // and the rays', from the centre) scaled by how much the linear reach
  // falls, t √(wᵀ S⁻¹ w) after the test against the same now (from the
  // tests' information alone, t at their ν), never above 1: a candidate
  // that adds no information leaves it as it is (but for t). The reach now
  // of each held one left without information even after the test stays
  // (in quadrature where several): the result is at least that.
  const double linear = t * std::sqrt(std::max(var_all - var_free, 0.0));
  const Solved now = solve(Lnow);
  const double linear_now =
      now.ok ? t_quantile(0.975, interval_dof(u)) * std::sqrt(std::max(now.var_all - now.var_free, 0.0)) : 0.0;
  double rest_down = 0, rest_up = 0;
  const bool by_held = s.down_by_held.size() == nh && s.up_by_held.size() == nh;
  for (std::size_t j = 0; j < nh; ++j)
    if (!in[np + j]) {
      if (!by_held) rest_down = s.down, rest_up = s.up;
      else rest_down = -std::hypot(rest_down, s.down_by_held[j]), rest_up = std::hypot(rest_up, s.up_by_held[j]);
    }
  if (linear_now > 0 && std::isfinite(linear_now)) {
    const double ratio = std::min(1.0, linear / linear_now);
    out.reach_down = std::max(-s.down * ratio, -rest_down);
    out.reach_up = std::max(s.up * ratio, rest_up);
  } else {  // no held one informed now: the linear reach after, if less
    out.reach_down = std::min(-s.down, std::hypot(linear, rest_down));
    out.reach_up = std::min(s.up, std::hypot(linear, rest_up));
  }
  // Centred where the interval now is: the linear expectation does not
  // move the estimate.
  const double y0 = s.center;
  const double below = std::hypot(half, out.reach_down), above = std::hypot(half, out.reach_up);
  out.expected.lo = s.log ? std::exp(y0 - below) : y0 - below;
  out.expected.hi = s.log ? std::exp(y0 + above) : y0 + above;
  if (!std::isfinite(below)) out.expected.lo = -HUGE_VAL;
  if (!std::isfinite(above)) out.expected.hi = HUGE_VAL;
  out.width = out.expected.hi - out.expected.lo;
  return out;
}

}  // namespace mc::grind
