// An ore fitted to a batch test, least squares, identification (fit.h).
#include "grind/fit.h"
#include "grind/sieve_errors.h"

#include <fmt/format.h>
#include "core/edit_distance.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "grind/circuit.h"

namespace mc::grind {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using Matrix = std::vector<std::vector<double>>;

// Solves A x = b for a small symmetric positive definite A (Cholesky);
// false if A is not positive definite.
bool solve_spd(Matrix A, std::vector<double> b, std::vector<double>& x) {
  const std::size_t n = b.size();
  for (std::size_t j = 0; j < n; ++j) {
    double d = A[j][j];
    for (std::size_t k = 0; k < j; ++k) d -= A[j][k] * A[j][k];
    if (!(d > 0)) return false;
    A[j][j] = std::sqrt(d);
    for (std::size_t i = j + 1; i < n; ++i) {
      double s = A[i][j];
      for (std::size_t k = 0; k < j; ++k) s -= A[i][k] * A[j][k];
      A[i][j] = s / A[j][j];
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < i; ++k) b[i] -= A[i][k] * b[k];
    b[i] /= A[i][i];
  }
  for (std::size_t i = n; i-- > 0;) {
    for (std::size_t k = i + 1; k < n; ++k) b[i] -= A[k][i] * b[k];
    b[i] /= A[i][i];
  }
  x = b;
  return true;
}

// Eigenvalues and vectors (columns of V) of a small symmetric matrix:
// cyclic Jacobi rotations.
void jacobi_eigen(Matrix A, std::vector<double>& lambda, Matrix& V) {
  const std::size_t n = A.size();
  V.assign(n, std::vector<double>(n, 0.0));
  for (std::size_t i = 0; i < n; ++i) V[i][i] = 1;
  for (int sweep = 0; sweep < 100; ++sweep) {
    double off = 0;
    for (std::size_t p = 0; p < n; ++p)
      for (std::size_t q = p + 1; q < n; ++q) off += A[p][q] * A[p][q];
    if (off < 1e-30) break;
    for (std::size_t p = 0; p < n; ++p)
      for (std::size_t q = p + 1; q < n; ++q) {
        if (A[p][q] == 0) continue;
        const double theta = (A[q][q] - A[p][p]) / (2 * A[p][q]);
        const double t = (theta >= 0 ? 1 : -1) / (std::fabs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (std::size_t k = 0; k < n; ++k) {
          const double akp = A[k][p], akq = A[k][q];
          A[k][p] = c * akp - s * akq;
          A[k][q] = s * akp + c * akq;
        }
        for (std::size_t k = 0; k < n; ++k) {
          const double apk = A[p][k], aqk = A[q][k];
          A[p][k] = c * apk - s * aqk;
          A[q][k] = s * apk + c * aqk;
        }
        for (std::size_t k = 0; k < n; ++k) {
          const double vkp = V[k][p], vkq = V[k][q];
          V[k][p] = c * vkp - s * vkq;
          V[k][q] = s * vkp + c * vkq;
        }
      }
  }
  lambda.resize(n);
  for (std::size_t i = 0; i < n; ++i) lambda[i] = A[i][i];
}

double sum_sq(const std::vector<double>& r) {
  double s = 0;
  for (double x : r) s += x * x;
  return s;
}

// The fitted variable of a parameter value, and back.
double to_var(const OreParameter& p, double v) { return p.log ? std::log(v) : v; }
double from_var(const OreParameter& p, double x) { return p.log ? std::exp(x) : x; }

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}


}  // namespace

double passing_at(const SizeSeries& s, const std::vector<double>& m, double x) {
  const std::vector<double> P = passing(m);
  const int n = s.size();
  if (x >= s.top_m[0]) return P[0];
  for (int i = 0; i + 1 < n; ++i)
    if (x <= s.top_m[i] && x >= s.top_m[i + 1]) {
      const double f = std::log(x / s.top_m[i + 1]) / std::log(s.top_m[i] / s.top_m[i + 1]);
      return P[i + 1] + f * (P[i] - P[i + 1]);
    }
  return kNaN;
}

std::vector<std::vector<double>> batch_test_products(const Ore& ore, const std::vector<SpectrumBin>& spectrum,
                                                     double power_W, double holdup_kg, const BatchTest& test) {
  const std::vector<double> feed = feed_masses(ore.sizes, test.sieve_m, test.feed_passing);
  const MillRates rates = mill_rates(ore, spectrum, power_W, holdup_kg);
  const auto b = appearance_matrix(ore, spectrum);
  std::vector<std::vector<double>> out;
  std::vector<double> m = feed;
  double t = 0;
  for (double ti : test.times_min) {  // ascending: each grinds on from the last
    m = batch_grind(m, rates.S_per_min, b, ti - t);
    t = ti;
    std::vector<double> row;
    for (double x : test.sieve_m) row.push_back(passing_at(ore.sizes, m, x));
    out.push_back(row);
  }
  return out;
}

// ------------------------------------------------------------ parameters

const std::vector<OreParameter>& ore_parameters() {
  using R = RateModel;
  static const std::vector<OreParameter> all = {
      {"efficiency", true, 1e-4, 1, false, R::spectrum, [](const Ore& o) { return o.efficiency; },
       [](Ore& o, double v) { o.efficiency = v; }, {}},
      {"e_inf_J_kg", true, 1e-3, 1e5, false, R::spectrum, [](const Ore& o) { return o.fracture.e_inf_J_kg; },
       [](Ore& o, double v) { o.fracture.e_inf_J_kg = v; }, {}},
      {"d0_mm", true, 1e-4, 1e3, false, R::spectrum, [](const Ore& o) { return o.fracture.d0_m * 1e3; },
       [](Ore& o, double v) { o.fracture.d0_m = v * 1e-3; }, {}},
      {"rates.phi", true, 1e-3, 5, false, R::spectrum, [](const Ore& o) { return o.fracture.phi; },
       [](Ore& o, double v) { o.fracture.phi = v; }, {}},
      {"sigma", true, 0.05, 3, false, R::spectrum, [](const Ore& o) { return o.fracture.sigma; },
       [](Ore& o, double v) { o.fracture.sigma = v; }, {}},
      {"s1e_t_per_kWh", true, 1e-6, 100, false, R::energy, [](const Ore& o) { return o.energy.s1e_t_per_kWh; },
       [](Ore& o, double v) { o.energy.s1e_t_per_kWh = v; }, {}},
      {"x1_mm", true, 1e-3, 1e3, false, R::energy, [](const Ore& o) { return o.energy.x1_m * 1e3; },
       [](Ore& o, double v) { o.energy.x1_m = v * 1e-3; }, {}},
      {"zeta1", false, -5, 5, false, R::energy, [](const Ore& o) { return o.energy.zeta1; },
       [](Ore& o, double v) { o.energy.zeta1 = v; }, {}},
      {"zeta2", false, -5, 5, false, R::energy, [](const Ore& o) { return o.energy.zeta2; },
       [](Ore& o, double v) { o.energy.zeta2 = v; }, {}},
      {"a_per_min", true, 1e-6, 100, false, R::austin, [](const Ore& o) { return o.austin.a_per_min; },
       [](Ore& o, double v) { o.austin.a_per_min = v; }, {}},
      {"alpha", true, 0.1, 3, false, R::austin, [](const Ore& o) { return o.austin.alpha; },
       [](Ore& o, double v) { o.austin.alpha = v; }, {}},
      {"mu_mm", true, 1e-3, 1e3, false, R::austin, [](const Ore& o) { return o.austin.mu_m * 1e3; },
       [](Ore& o, double v) { o.austin.mu_m = v * 1e-3; }, {}},
      {"lambda", true, 0.5, 10, false, R::austin, [](const Ore& o) { return o.austin.lambda; },
       [](Ore& o, double v) { o.austin.lambda = v; }, {}},
      {"breakage.phi", false, 0, 1, true, R::spectrum, [](const Ore& o) { return o.breakage.phi; },
       [](Ore& o, double v) { o.breakage.phi = v; }, Appearance::austin},
      {"breakage.gamma", true, 0.2, 3, true, R::spectrum, [](const Ore& o) { return o.breakage.gamma; },
       [](Ore& o, double v) { o.breakage.gamma = v; }, Appearance::austin},
      {"breakage.beta", true, 1, 10, true, R::spectrum, [](const Ore& o) { return o.breakage.beta; },
       [](Ore& o, double v) { o.breakage.beta = v; }, Appearance::austin},
      {"breakage.t10_max_percent", true, 1, 100, false, R::spectrum, [](const Ore& o) { return 100 * o.t10.a; },
       [](Ore& o, double v) { o.t10.a = v / 100; }, Appearance::t10},
      {"breakage.b_prime", true, 1e-3, 100, false, R::spectrum, [](const Ore& o) { return o.t10.b_prime; },
       [](Ore& o, double v) { o.t10.b_prime = v; }, Appearance::t10},
  };
  return all;
}

const OreParameter* find_ore_parameter(const std::string& name) {
  const std::string key = name.rfind("rates.", 0) == 0 && name != "rates.phi" ? name.substr(6) : name;
  for (const OreParameter& p : ore_parameters())
    if (p.name == key) return &p;
  return nullptr;
}

std::string closest_ore_parameter(const std::string& name) {
  const std::string key = lower(name);
  std::string best;
  std::size_t best_d = std::string::npos;
  for (const OreParameter& p : ore_parameters())
    if (lower(p.name) == key) return p.name;  // the case alone differs
  for (const OreParameter& p : ore_parameters())  // the start of a name ("e_inf")
    if (!key.empty() && lower(p.name).rfind(key, 0) == 0) return p.name;
  for (const OreParameter& p : ore_parameters()) {
    // Also against the name without its table ("phi" in "rates.phi").
    const std::size_t dot = p.name.find('.');
    std::size_t d = edit_distance(key, lower(p.name));
    if (dot != std::string::npos) d = std::min(d, edit_distance(key, lower(p.name.substr(dot + 1))));
    if (d < best_d) best_d = d, best = p.name;
  }
  return best;
}

// ------------------------------------------------------------ least squares

LmResult levenberg_marquardt(const LmProblem& prob) {
  const std::size_t np = prob.x0.size(), n = static_cast<std::size_t>(prob.n_data);
  LmResult res;
  auto clamp = [&](std::vector<double>& x) {
    for (std::size_t k = 0; k < np; ++k) x[k] = std::clamp(x[k], prob.lo[k], prob.hi[k]);
  };
  auto eval = [&](const std::vector<double>& x, std::vector<double>& r) {
    r.assign(n, 0.0);
    prob.residuals(x, r);
    ++res.evaluations;
  };
  // Central differences, one-sided at a bound.
  auto jacobian = [&](const std::vector<double>& x, Matrix& J) {
    J.assign(n, std::vector<double>(np, 0.0));
    std::vector<double> rp, rm;
    for (std::size_t k = 0; k < np; ++k) {
      const double h = 1e-5 * std::max(1.0, std::fabs(x[k]));
      std::vector<double> xp = x, xm = x;
      xp[k] = std::min(x[k] + h, prob.hi[k]);
      xm[k] = std::max(x[k] - h, prob.lo[k]);
      eval(xp, rp);
      eval(xm, rm);
      const double d = xp[k] - xm[k];
      for (std::size_t i = 0; i < n; ++i) J[i][k] = d > 0 ? (rp[i] - rm[i]) / d : 0.0;
    }
  };
  res.x = prob.x0;
  clamp(res.x);
  eval(res.x, res.r);
  res.ssr = sum_sq(res.r);
  double lambda = 1e-3;
  for (res.iterations = 1; res.iterations <= prob.max_iterations; ++res.iterations) {
    jacobian(res.x, res.J);
    Matrix A(np, std::vector<double>(np, 0.0));
    std::vector<double> g(np, 0.0);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t a = 0; a < np; ++a) {
        g[a] -= res.J[i][a] * res.r[i];
        for (std::size_t b = 0; b < np; ++b) A[a][b] += res.J[i][a] * res.J[i][b];
      }
    double dmax = 0;
    for (std::size_t a = 0; a < np; ++a) dmax = std::max(dmax, A[a][a]);
    if (!(dmax > 0)) {  // the data depend on none of the parameters
      res.converged = true;
      return res;
    }
    // A parameter on a bound that the descent would push past it is held
    // there this iteration (an active bound): the step and the test of
    // convergence are taken over the others.
    std::vector<bool> active(np, false);
    for (std::size_t a = 0; a < np; ++a)
      active[a] = (res.x[a] >= prob.hi[a] && g[a] > 0) || (res.x[a] <= prob.lo[a] && g[a] < 0);
    // At a minimum the residuals are orthogonal to every column of J: the
    // largest cosine between r and a column, below 1e-8 (the numerical
    // Jacobian's own error is about 1e-10).
    double cos_max = 0;
    for (std::size_t a = 0; a < np; ++a)
      if (A[a][a] > 0 && !active[a]) cos_max = std::max(cos_max, std::fabs(g[a]) / std::sqrt(A[a][a] * res.ssr));
    if (res.ssr < 1e-28 || cos_max < 1e-8) {
      res.converged = true;
      return res;
    }
    bool stepped = false, done = false;
    for (int tries = 0; tries < 40 && !stepped; ++tries) {
      Matrix M = A;
      std::vector<double> rhs = g;
      for (std::size_t a = 0; a < np; ++a) M[a][a] += lambda * std::max(A[a][a], 1e-12 * dmax);
      for (std::size_t a = 0; a < np; ++a)
        if (active[a]) {
          for (std::size_t b = 0; b < np; ++b) M[a][b] = M[b][a] = 0;
          M[a][a] = 1;
          rhs[a] = 0;
        }
      std::vector<double> dx;
      if (!solve_spd(M, rhs, dx)) {
        lambda *= 10;
        continue;
      }
      std::vector<double> xt = res.x;
      for (std::size_t a = 0; a < np; ++a) xt[a] += dx[a];
      clamp(xt);
      std::vector<double> rt;
      eval(xt, rt);
      const double st = sum_sq(rt);
      double moved = 0;
      for (std::size_t a = 0; a < np; ++a)
        moved = std::max(moved, std::fabs(xt[a] - res.x[a]) / (1 + std::fabs(res.x[a])));
      if (st <= res.ssr) {
        const double gain = res.ssr - st;
        res.x = xt;
        res.r = rt;
        res.ssr = st;
        lambda = std::max(lambda / 3, 1e-12);
        stepped = true;
        if (st < 1e-28 || (moved < 1e-10 && gain <= 1e-12 * std::max(st, 1e-300))) done = true;
      } else {
        // A step that cannot lower the sum while it hardly moves: at the minimum.
        if (moved < 1e-12) {
          done = true;
          break;
        }
        lambda *= 4;
      }
    }
    if (done) {
      jacobian(res.x, res.J);
      res.converged = true;
      return res;
    }
    if (!stepped) break;
  }
  res.iterations = std::min(res.iterations, prob.max_iterations);
  jacobian(res.x, res.J);
  return res;
}

Identification identify(const Matrix& J, double ssr, const std::vector<double>& se_limit) {
  const std::size_t n = J.size(), np = n ? J[0].size() : 0;
  Identification id;
  id.se.assign(np, kNaN);
  id.identified.assign(np, true);
  id.why.assign(np, "");
  Matrix A(np, std::vector<double>(np, 0.0));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t a = 0; a < np; ++a)
      for (std::size_t b = 0; b < np; ++b) A[a][b] += J[i][a] * J[i][b];
  // Parameters the data do not depend on at all.
  double dmax = 0;
  for (std::size_t a = 0; a < np; ++a) dmax = std::max(dmax, A[a][a]);
  std::vector<std::size_t> live;
  for (std::size_t a = 0; a < np; ++a) {
    if (!(A[a][a] > 1e-20 * dmax) || !(A[a][a] > 0)) {
      id.identified[a] = false;
      id.why[a] = "the data do not depend on it";
    } else {
      live.push_back(a);
    }
  }
  const std::size_t m = live.size();
  if (m == 0) return id;
  Matrix C(m, std::vector<double>(m, 0.0));
  std::vector<double> d(m);
  for (std::size_t a = 0; a < m; ++a) d[a] = 1 / std::sqrt(A[live[a]][live[a]]);
  for (std::size_t a = 0; a < m; ++a)
    for (std::size_t b = 0; b < m; ++b) C[a][b] = A[live[a]][live[b]] * d[a] * d[b];
  std::vector<double> lambda;
  Matrix V;
  jacobi_eigen(C, lambda, V);
  const double lmax = *std::max_element(lambda.begin(), lambda.end());
  const double lmin = *std::min_element(lambda.begin(), lambda.end());
  id.condition = lmin > 0 ? lmax / lmin : std::numeric_limits<double>::infinity();
  const double s2 = n > np ? ssr / static_cast<double>(n - np) : kNaN;
  // Each singular direction: the parameter with its largest component is
  // the one the others can stand in for.
  std::vector<bool> singular(m, false);
  for (std::size_t k = 0; k < m; ++k)
    if (lambda[k] < 1e-10 * lmax) {
      std::size_t worst = 0;
      for (std::size_t a = 0; a < m; ++a)
        if (!singular[a] && (singular[worst] || std::fabs(V[a][k]) > std::fabs(V[worst][k]))) worst = a;
      singular[worst] = true;
    }
  for (std::size_t a = 0; a < m; ++a) {
    const std::size_t p = live[a];
    if (singular[a]) {
      id.identified[p] = false;
      id.why[p] = "JᵀJ is singular in its direction: other parameters can take its part";
      continue;
    }
    double var = 0;  // (C⁻¹)_aa over the regular directions
    for (std::size_t k = 0; k < m; ++k)
      if (lambda[k] >= 1e-10 * lmax) var += V[a][k] * V[a][k] / lambda[k];
    id.se[p] = std::sqrt(var * s2) * d[a];
    const double limit = se_limit.empty() ? 1.0 : se_limit[p];
    if (id.se[p] > limit) {
      id.identified[p] = false;
      id.why[p] = limit == 1.0 ? "its standard error is more than a factor of e"
                               : "its standard error is more than a quarter of its range";
    }
  }
  return id;
}

Matrix covariance_matrix(const Matrix& J, double ssr) {
  const std::size_t n = J.size(), np = n ? J[0].size() : 0;
  Matrix cov(np, std::vector<double>(np, 0.0));
  if (np == 0 || n <= np) return cov;
  Matrix A(np, std::vector<double>(np, 0.0));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t a = 0; a < np; ++a)
      for (std::size_t b = 0; b < np; ++b) A[a][b] += J[i][a] * J[i][b];
  std::vector<double> d(np);
  for (std::size_t a = 0; a < np; ++a) d[a] = A[a][a] > 0 ? 1 / std::sqrt(A[a][a]) : 0;
  Matrix C(np, std::vector<double>(np, 0.0));
  for (std::size_t a = 0; a < np; ++a)
    for (std::size_t b = 0; b < np; ++b) C[a][b] = A[a][b] * d[a] * d[b];
  std::vector<double> lambda;
  Matrix V;
  jacobi_eigen(C, lambda, V);
  const double lmax = *std::max_element(lambda.begin(), lambda.end());
  const double s2 = ssr / static_cast<double>(n - np);
  for (std::size_t a = 0; a < np; ++a)
    for (std::size_t b = 0; b < np; ++b) {
      double v = 0;
      for (std::size_t k = 0; k < np; ++k)
        if (lambda[k] >= 1e-10 * lmax) v += V[a][k] * V[b][k] / lambda[k];
      cov[a][b] = v * s2 * d[a] * d[b];
    }
  return cov;
}

// ------------------------------------------------------------ the fit

namespace {

void check_names(const Ore& start, const std::vector<std::string>& names, std::vector<const OreParameter*>& params) {
  if (names.empty()) throw std::invalid_argument("--fit-params: no parameter named");
  for (const std::string& nm : names) {
    if (nm == "phi")
      throw std::invalid_argument(
          "--fit-params phi: ambiguous: rates.phi (the size effect of E50) or breakage.phi (Austin's B)");
    const OreParameter* p = find_ore_parameter(nm);
    if (!p)
      throw std::invalid_argument("--fit-params " + nm + ": not a parameter a fit can move; did you mean " +
                                  closest_ore_parameter(nm) + "? (docs/grinding-fit.md lists them)");
    if (!p->any_model && p->model != start.model)
      throw std::invalid_argument("--fit-params " + nm + ": not a parameter of the ore's rate model (rates.model)");
    if (p->appearance && *p->appearance != start.appearance)
      throw std::invalid_argument("--fit-params " + nm +
                                  ": not a parameter of the ore's appearance function (breakage.model)");
    if (std::find(params.begin(), params.end(), p) != params.end())
      throw std::invalid_argument("--fit-params " + nm + ": named twice");
    params.push_back(p);
  }
}

}  // namespace

BatchFit fit_batch_test(const Ore& start, const std::vector<SpectrumBin>& spectrum, double power_W,
                        double holdup_kg, const BatchTest& test, const std::vector<std::string>& names,
                        int max_iterations) {
  return fit_batch_tests(start, {TestInMill{test, spectrum, power_W, holdup_kg}}, names, max_iterations);
}

std::vector<double> test_weights(const std::vector<TestInMill>& tests) {
  std::vector<double> w(tests.size(), 1.0);
  bool alike = true;
  for (const TestInMill& tm : tests) alike = alike && tm.test.noise_pp == tests.front().test.noise_pp;
  if (alike) return w;
  for (std::size_t m = 0; m < tests.size(); ++m) {
    if (!(tests[m].test.noise_pp > 0))
      throw std::invalid_argument("--fit: test " + std::to_string(m + 1) +
                                  " has noise_pp 0 beside tests with scatter: its weight 1/noise_pp^2 is infinite; "
                                  "give each test the scatter of its sieving");
    w[m] = tests.front().test.noise_pp / tests[m].test.noise_pp;
  }
  return w;
}

double residual_lag1(const std::vector<double>& r, const std::vector<std::size_t>& row_lengths) {
  std::size_t total = 0;
  for (std::size_t len : row_lengths) total += len;
  if (total == 0 || total > r.size()) return kNaN;
  double mean = 0;
  for (std::size_t i = 0; i < total; ++i) mean += r[i] / static_cast<double>(total);
  double num = 0, den = 0;
  std::size_t i = 0, pairs = 0;
  for (std::size_t len : row_lengths) {
    for (std::size_t k = 0; k < len; ++k) {
      const double d = r[i + k] - mean;
      den += d * d;
      if (k + 1 < len) num += d * (r[i + k + 1] - mean), ++pairs;
    }
    i += len;
  }
  return pairs > 0 && den > 0 ? num / den : kNaN;
}

std::vector<double> weighted_residuals(const Ore& ore, const std::vector<TestInMill>& tests) {
  const std::vector<double> w = test_weights(tests);
  std::vector<double> r;
  for (std::size_t m = 0; m < tests.size(); ++m) {
    const TestInMill& tm = tests[m];
    const auto pred = batch_test_products(ore, tm.spectrum, tm.power_W, tm.holdup_kg, tm.test);
    const std::vector<std::size_t> used = informative_sieves(tm.test);
    const std::size_t at = r.size();
    for (std::size_t t = 0; t < tm.test.times_min.size(); ++t)
      for (std::size_t k : used) r.push_back(w[m] * 100 * (pred[t][k] - tm.test.passing[t][k]));
    whiten_rows(r.data() + at, tm.test.times_min.size(), used.size(), tm.sieve_rho);
  }
  return r;
}

double weighted_ssr(const Ore& ore, const std::vector<TestInMill>& tests) {
  double ssr = 0;
  for (double x : weighted_residuals(ore, tests)) ssr += x * x;
  return ssr;
}

std::vector<std::size_t> informative_sieves(const BatchTest& test) {
  std::vector<std::size_t> used;
  for (std::size_t k = 0; k < test.sieve_m.size(); ++k) {
    bool all_one = test.feed_passing[k] >= 1 - 1e-12;
    for (std::size_t t = 0; t < test.times_min.size(); ++t) all_one = all_one && test.passing[t][k] >= 1 - 1e-12;
    if (!all_one) used.push_back(k);
  }
  return used;
}

BatchFit fit_batch_tests(const Ore& start, const std::vector<TestInMill>& tests, const std::vector<std::string>& names,
                         int max_iterations, bool hold_unidentified) {
  std::vector<const OreParameter*> params;
  check_names(start, names, params);
  if (tests.empty()) throw std::invalid_argument("--fit: no batch test");
  // Sieves where every product and the feed pass 1 hold no information;
  // the rest are the data, test after test.
  std::vector<std::vector<std::size_t>> used;
  std::size_t n = 0;
  for (const TestInMill& tm : tests) {
    used.push_back(informative_sieves(tm.test));
    n += tm.test.times_min.size() * used.back().size();
    if (tm.test.sieve_m.back() < start.sizes.top_m.back() * (1 - 1e-9))
      throw std::invalid_argument("sieve_mm: the finest sieve lies below the ore's finest class top (" +
                                  std::to_string(start.sizes.top_m.back() * 1e6) + " um): more sizes.classes");
    if (tm.test.sieve_m.front() > start.sizes.top_m.front() * (1 + 1e-9))
      throw std::invalid_argument("sieve_mm: the coarsest sieve lies above the ore's top class (sizes.top_mm)");
  }
  if (params.size() >= n)
    throw std::invalid_argument("--fit-params: " + std::to_string(params.size()) + " parameters for " +
                                std::to_string(n) +
                                " data (times x sieves below the top): a fit needs more data than parameters");
  const std::vector<double> weight = test_weights(tests);
  // The residuals of an ore against every test, in percentage points of
  // the first test's noise (each test's weighted by its noise); the
  // products by test.
  // Whitened by each test's sieve_rho unless `raw`.
  auto residuals_of = [&](const Ore& o, std::vector<double>& r, std::vector<Matrix>* products, bool raw = false) {
    std::size_t i = 0;
    for (std::size_t m = 0; m < tests.size(); ++m) {
      const TestInMill& tm = tests[m];
      const auto pred = batch_test_products(o, tm.spectrum, tm.power_W, tm.holdup_kg, tm.test);
      const std::size_t at = i;
      for (std::size_t t = 0; t < tm.test.times_min.size(); ++t)
        for (std::size_t k : used[m]) r[i++] = weight[m] * 100 * (pred[t][k] - tm.test.passing[t][k]);
      if (!raw) whiten_rows(r.data() + at, tm.test.times_min.size(), used[m].size(), tm.sieve_rho);
      if (products) products->push_back(pred);
    }
  };

  BatchFit fit;
  fit.data = static_cast<int>(n);
  std::vector<bool> held(params.size(), false);
  std::vector<std::string> held_why(params.size());
  for (;;) {
    std::vector<std::size_t> free;
    for (std::size_t k = 0; k < params.size(); ++k)
      if (!held[k]) free.push_back(k);
    Ore ore = start;
    LmProblem prob;
    prob.n_data = static_cast<int>(n);
    prob.max_iterations = max_iterations;
    for (std::size_t k : free) {
      prob.x0.push_back(to_var(*params[k], params[k]->get(start)));
      prob.lo.push_back(to_var(*params[k], params[k]->log ? std::max(params[k]->lo, 1e-300) : params[k]->lo));
      prob.hi.push_back(to_var(*params[k], params[k]->hi));
    }
    prob.residuals = [&](const std::vector<double>& x, std::vector<double>& r) {
      Ore o = start;
      for (std::size_t a = 0; a < free.size(); ++a) params[free[a]]->set(o, from_var(*params[free[a]], x[a]));
      residuals_of(o, r, nullptr);
    };
    LmResult lm;
    if (!free.empty()) lm = levenberg_marquardt(prob);
    fit.iterations += lm.iterations;
    fit.evaluations += lm.evaluations;
    if (!free.empty() && !lm.converged) {
      char buf[240];
      std::snprintf(buf, sizeof buf,
                    "--fit: the fit did not converge in %d iterations (rms residual %.3g pp); nothing written: "
                    "start nearer, or fit fewer parameters",
                    lm.iterations, std::sqrt(lm.ssr / static_cast<double>(n)));
      throw std::invalid_argument(buf);
    }
    // A parameter the fit left on its bound is not free there: it has no
    // standard error, and the others' are those with it fixed.
    std::vector<bool> on_bound(free.size(), false);
    std::vector<std::size_t> inner;  // indices into free, off their bounds
    // Within a whisker of it (a millionth of its range in the fitted
    // variable) counts as on it, and is put there: a parameter that close
    // has no room for a standard error on that side.
    for (std::size_t a = 0; a < free.size(); ++a) {
      const double whisker = kBoundWhisker * (prob.hi[a] - prob.lo[a]);
      if (lm.x[a] - prob.lo[a] < whisker) lm.x[a] = prob.lo[a], on_bound[a] = true;
      if (prob.hi[a] - lm.x[a] < whisker) lm.x[a] = prob.hi[a], on_bound[a] = true;
      if (!on_bound[a]) inner.push_back(a);
    }
    // Which the data cannot fix, judged with every free parameter; the
    // standard errors of those off their bounds, with the bound ones fixed.
    std::vector<double> limits;  // unidentified past a factor of e (a logarithm), a quarter of the range (a value)
    for (std::size_t k : free) limits.push_back(params[k]->log ? 1.0 : (params[k]->hi - params[k]->lo) / 4);
    Identification id = free.empty() ? Identification{} : identify(lm.J, lm.ssr, limits);
    if (!inner.empty() && inner.size() < free.size()) {
      Matrix Jin(lm.J.size(), std::vector<double>(inner.size()));
      std::vector<double> lim_in;
      for (std::size_t a = 0; a < inner.size(); ++a) {
        lim_in.push_back(limits[inner[a]]);
        for (std::size_t i = 0; i < lm.J.size(); ++i) Jin[i][a] = lm.J[i][inner[a]];
      }
      const Identification in = identify(Jin, lm.ssr, lim_in);
      for (std::size_t a = 0; a < inner.size(); ++a) {
        id.se[inner[a]] = in.se[a];
        id.identified[inner[a]] = in.identified[a];
        id.why[inner[a]] = in.why[a];
      }
      id.condition = in.condition;
    }
    // Hold one parameter at a time, and fit the rest again: first one the
    // others can stand in for, else the one with the largest error.
    std::size_t hold = free.size();
    for (std::size_t a = 0; a < free.size(); ++a)
      if (!id.identified[a] && (hold == free.size() || (std::isnan(id.se[a]) && !std::isnan(id.se[hold])) ||
                                (!std::isnan(id.se[hold]) && id.se[a] > id.se[hold])))
        hold = a;
    if (hold < free.size() && hold_unidentified) {
      held[free[hold]] = true;
      held_why[free[hold]] = id.why[hold];
      ++fit.refits;
      continue;
    }
    for (std::size_t a = 0; a < free.size(); ++a) params[free[a]]->set(ore, from_var(*params[free[a]], lm.x[a]));
    fit.ore = ore;
    fit.free = static_cast<int>(free.size());
    fit.condition = id.condition;
    // The residuals of the products as written, whatever is free (with
    // nothing free, those of the starting ore); by test too.
    std::vector<double> r(n), w(n);
    residuals_of(ore, r, &fit.predicted_by_test, true);
    residuals_of(ore, w, nullptr);
    fit.predicted = fit.predicted_by_test.front();
    // The sum of squares as weighted and whitened (what the fit minimised);
    // the rms residuals in percentage points as measured.
    fit.ssr = sum_sq(w);
    double ssr_pp = 0;
    std::size_t i = 0;
    for (std::size_t m = 0; m < tests.size(); ++m) {
      double ssr_m = 0;
      const std::size_t nm = tests[m].test.times_min.size() * used[m].size();
      for (std::size_t j = 0; j < nm; ++j, ++i) ssr_m += r[i] * r[i];
      ssr_m /= weight[m] * weight[m];
      ssr_pp += ssr_m;
      fit.rms_by_test.push_back(nm ? std::sqrt(ssr_m / static_cast<double>(nm)) : 0.0);
    }
    fit.rms_pp = std::sqrt(ssr_pp / static_cast<double>(n));
    std::vector<std::size_t> rows;
    for (std::size_t m = 0; m < tests.size(); ++m)
      rows.insert(rows.end(), tests[m].test.times_min.size(), used[m].size());
    fit.residual_r1 = residual_lag1(r, rows);
    fit.raw_residuals = r;
    fit.residual_rows = rows;
    // The covariance of those off their bounds, with the bound ones fixed.
    if (!inner.empty()) {
      Matrix Jin(lm.J.size(), std::vector<double>(inner.size()));
      for (std::size_t a = 0; a < inner.size(); ++a) {
        fit.covariance_of.push_back(free[inner[a]]);
        for (std::size_t i = 0; i < lm.J.size(); ++i) Jin[i][a] = lm.J[i][inner[a]];
      }
      fit.covariance = covariance_matrix(Jin, lm.ssr);
      // Unwhitened, test by test, time by time.
      fit.raw_jacobian = Jin;
      std::size_t at = 0;
      for (std::size_t m = 0; m < tests.size(); ++m)
        for (std::size_t t = 0; t < tests[m].test.times_min.size(); ++t, at += used[m].size())
          for (std::size_t a = 0; a < inner.size(); ++a) {
            std::vector<double> col(used[m].size());
            for (std::size_t k = 0; k < col.size(); ++k) col[k] = Jin[at + k][a];
            unwhiten_row(col.data(), col.size(), tests[m].sieve_rho);
            for (std::size_t k = 0; k < col.size(); ++k) fit.raw_jacobian[at + k][a] = col[k];
          }
    }
    fit.dof = static_cast<int>(n - inner.size());
    fit.s2 = fit.dof > 0 ? fit.ssr / fit.dof : kNaN;
    for (std::size_t k = 0; k < params.size(); ++k) {
      FittedParameter f;
      f.name = params[k]->name;
      f.start = params[k]->get(start);
      f.value = params[k]->get(ore);
      const auto it = std::find(free.begin(), free.end(), k);
      if (it == free.end()) {
        f.identified = false;
        f.se = kNaN;
        f.why = held_why[k] + "; held at its start";
      } else {
        const std::size_t a = static_cast<std::size_t>(it - free.begin());
        f.at_bound = on_bound[a];
        f.se = f.at_bound ? kNaN : params[k]->log ? f.value * id.se[a] : id.se[a];
      }
      fit.parameters.push_back(f);
    }
    return fit;
  }
}

WiFit fit_work_index(const Ore& ore_on_p1, const std::vector<SpectrumBin>& spectrum, double power_W, double rpm,
                     double p1_m, double wi_kWh_t, const std::string& name) {
  const OreParameter* p = find_ore_parameter(name);
  if (!p || (!p->any_model && p->model != ore_on_p1.model) || !p->log || p->appearance)
    throw std::invalid_argument("--fit-params " + name +
                                ": a work index fits one scale of the ore's rates (efficiency or e_inf_J_kg for the "
                                "spectrum model, s1e_t_per_kWh for the energy model, a_per_min for Austin's)");
  WiFit w;
  w.start = p->get(ore_on_p1);
  const double charge = bond_charge_kg(ore_on_p1);
  auto bond_at = [&](double v) {
    Ore o = ore_on_p1;
    p->set(o, v);
    const MillRates r = mill_rates(o, spectrum, power_W, charge);
    const auto b = appearance_matrix(o, spectrum);  // t10's moves with the fracture energies
    ++w.evaluations;
    return bond_test(o.sizes, o.feed, r.S_per_min, b, rpm, charge, p1_m);
  };
  double lo = std::log(p->lo), hi = std::log(p->hi);
  const BondResult at_lo = bond_at(p->lo), at_hi = bond_at(p->hi);
  const double wlo = at_lo.wi_kWh_t, whi = at_hi.wi_kWh_t;
  char buf[400];
  if (!((wlo - wi_kWh_t) * (whi - wi_kWh_t) < 0)) {
    std::snprintf(buf, sizeof buf,
                  "--fit-wi %g: not reachable with %s in its range: %s %g gives Wi %.4g kWh/t, %g gives %.4g; fit "
                  "another parameter (--fit-params)",
                  wi_kWh_t, p->name.c_str(), p->name.c_str(), p->lo, wlo, p->hi, whi);
    throw std::invalid_argument(buf);
  }
  const bool rising = whi > wlo;
  BondResult mid;
  for (int k = 0; k < 100 && hi - lo > 1e-12; ++k) {
    const double x = 0.5 * (lo + hi);
    mid = bond_at(std::exp(x));
    ((mid.wi_kWh_t < wi_kWh_t) == rising ? lo : hi) = x;
  }
  w.value = std::exp(0.5 * (lo + hi));
  w.bond = bond_at(w.value);
  if (!(std::fabs(w.bond.wi_kWh_t - wi_kWh_t) <= 1e-4 * wi_kWh_t) || !w.bond.steady) {
    std::snprintf(buf, sizeof buf, "--fit-wi %g: not met: the closest %s, %.6g, gives Wi %.6g kWh/t%s; nothing written",
                  wi_kWh_t, p->name.c_str(), w.value, w.bond.wi_kWh_t,
                  w.bond.steady ? "" : " (Bond's cycles not steady there)");
    throw std::invalid_argument(buf);
  }
  // The slope, from 1 % either side.
  const double up = bond_at(w.value * 1.01).wi_kWh_t, dn = bond_at(w.value / 1.01).wi_kWh_t;
  w.dvalue_dwi = (w.value * 1.01 - w.value / 1.01) / (up - dn);
  return w;
}

std::string contact_mismatch(const ContactRecord& f, const ContactRecord& r) {
  if (f.law.empty()) return "";
  if (f.law != r.law) return "contact law " + f.law + " -> " + r.law;
  std::string out;
  auto cmp = [&](const char* name, double a, double b) {
    if (std::fabs(a - b) > 1e-6 * std::max(std::fabs(a), std::fabs(b))) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s%s %g -> %g", out.empty() ? "" : ", ", name, a, b);
      out += buf;
    }
  };
  cmp("restitution", f.restitution, r.restitution);
  cmp("friction", f.friction, r.friction);
  cmp("rolling_friction", f.rolling_friction, r.rolling_friction);
  if (f.law == "linear") cmp("stiffness_N_m", f.stiffness_N_m, r.stiffness_N_m);
  if (f.law == "hertz") cmp("youngs_modulus_Pa", f.youngs_modulus_Pa, r.youngs_modulus_Pa);
  if (f.pairs != r.pairs)
    out += (out.empty() ? "" : ", ") + std::string("pair overrides \"") + f.pairs + "\" -> \"" + r.pairs + "\"";
  return out;
}

}  // namespace mc::grind
