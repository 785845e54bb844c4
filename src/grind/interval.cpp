// The fit's uncertainty carried to a fitted ore's products (interval.h).
#include "grind/interval.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <string>
#include <vector>

namespace mc::grind {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double to_var(const OreParameter& p, double v) { return p.log ? std::log(v) : v; }
double from_var(const OreParameter& p, double x) { return p.log ? std::exp(x) : x; }

// The sum of squared residuals (pp²) of the ore's products against the
// tests, over the sieves the fit reads.
double ssr_of(const Ore& ore, const std::vector<TestInMill>& tests) {
  double ssr = 0;
  for (const TestInMill& tm : tests) {
    const auto pred = batch_test_products(ore, tm.spectrum, tm.power_W, tm.holdup_kg, tm.test);
    for (std::size_t k : informative_sieves(tm.test))
      for (std::size_t t = 0; t < tm.test.times_min.size(); ++t)
        ssr += std::pow(100 * (pred[t][k] - tm.test.passing[t][k]), 2);
  }
  return ssr;
}

std::vector<double> variables_of(const Ore& ore, const std::vector<std::string>& names) {
  std::vector<double> x;
  for (const std::string& n : names) {
    const OreParameter* p = find_ore_parameter(n);
    x.push_back(to_var(*p, p->get(ore)));
  }
  return x;
}

// One side (dir −1 or +1) of a held parameter's profile: the furthest value
// within the data, and the free variables refitted there.
void profile_side(HeldParameter& h, int dir, const BatchFit& fit, const FitCovariance& u,
                  const std::vector<TestInMill>& tests) {
  const OreParameter& p = *find_ore_parameter(h.name);
  const double x_held = to_var(p, h.value);
  const double x_end = dir < 0 ? to_var(p, p.log ? std::max(p.lo, 1e-300) : p.lo) : to_var(p, p.hi);
  const double step = p.log ? 1.0 : (p.hi - p.lo) / 4;
  const double limit = fit.ssr + 3.84 * u.residual_variance_pp2;
  double x_in = x_held, x_out = x_held;  // the last step within the data, the first past it
  std::vector<double> free_there = u.values;
  Ore ore = fit.ore, inside = fit.ore;
  // The free ones refitted with the held one at x (from the last ore within
  // the data); false where no fit is found or the data are left.
  auto within = [&](double x) {
    Ore o = inside;
    p.set(o, from_var(p, x));
    try {
      if (!u.names.empty()) o = fit_batch_tests(o, tests, u.names).ore;
    } catch (const std::exception&) {
      return false;
    }
    if (!(ssr_of(o, tests) <= limit)) return false;
    ore = o;
    return true;
  };
  for (int s = 1; s <= 6 && std::isfinite(limit); ++s) {
    const double x = dir < 0 ? std::max(x_held - s * step, x_end) : std::min(x_held + s * step, x_end);
    if (!within(x)) {
      x_out = x;
      break;
    }
    x_in = x;
    inside = ore;
    free_there = variables_of(ore, u.names);
    if (x == x_end) break;
  }
  // Three halvings between the last step within and the first past: the
  // range's end to an eighth of a step.
  for (int k = 0; k < 3 && x_out != x_in; ++k) {
    const double x = 0.5 * (x_in + x_out);
    if (within(x)) {
      x_in = x;
      inside = ore;
      free_there = variables_of(ore, u.names);
    } else {
      x_out = x;
    }
  }
  (dir < 0 ? h.lo : h.hi) = x_in == x_held ? h.value : from_var(p, x_in);
  (dir < 0 ? h.free_at_lo : h.free_at_hi) = free_there;
}

// The normal distribution's quantile, by bisection on erfc.
double normal_quantile(double p) {
  double lo = -40, hi = 40;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

std::string variable_name(const std::string& parameter) {
  const OreParameter* p = find_ore_parameter(parameter);
  return p && p->log ? "log(" + parameter + ")" : parameter;
}

std::string parameter_of_variable(const std::string& v) {
  const bool log = v.size() > 5 && v.rfind("log(", 0) == 0 && v.back() == ')';
  const std::string name = log ? v.substr(4, v.size() - 5) : v;
  const OreParameter* p = find_ore_parameter(name);
  return p && p->log == log ? name : "";
}

FitCovariance fit_covariance(const BatchFit& fit, const std::vector<SpectrumBin>& spectrum, double power_W,
                             double holdup_kg, const BatchTest& test) {
  return fit_covariance(fit, {TestInMill{test, spectrum, power_W, holdup_kg}});
}

FitCovariance fit_covariance(const BatchFit& fit, const std::vector<TestInMill>& tests) {
  FitCovariance u;
  u.given = true;
  for (std::size_t k : fit.covariance_of) u.names.push_back(fit.parameters[k].name);
  u.values = variables_of(fit.ore, u.names);
  u.matrix = fit.covariance;
  u.residual_variance_pp2 = fit.s2;
  u.dof = fit.dof;
  for (std::size_t k = 0; k < fit.parameters.size(); ++k) {
    if (std::find(fit.covariance_of.begin(), fit.covariance_of.end(), k) != fit.covariance_of.end()) continue;
    const FittedParameter& f = fit.parameters[k];
    HeldParameter h;
    h.name = f.name;
    h.value = h.lo = h.hi = f.value;
    h.why = f.identified ? "on its bound" : f.why;
    profile_side(h, -1, fit, u, tests);
    profile_side(h, +1, fit, u, tests);
    u.held.push_back(h);
  }
  return u;
}

double t_quantile(double p, int dof) {
  const double z = normal_quantile(p);
  if (dof <= 0) return z;
  // Cornish–Fisher expansion of Student's t in 1/ν (Abramowitz & Stegun
  // 26.7.5): within 1e-3 of the exact quantile from ν = 5 at p = 0.975.
  const double v = dof, z2 = z * z;
  return z + z * (z2 + 1) / (4 * v) + z * ((5 * z2 + 16) * z2 + 3) / (96 * v * v) +
         z * (((3 * z2 + 19) * z2 + 17) * z2 - 15) / (384 * v * v * v);
}

Ore with_variables(const Ore& ore, const FitCovariance& u, const std::vector<double>& x) {
  Ore o = ore;
  for (std::size_t j = 0; j < u.names.size() && j < x.size(); ++j) {
    const OreParameter* p = find_ore_parameter(u.names[j]);
    p->set(o, from_var(*p, x[j]));
  }
  return o;
}

std::vector<Interval> propagate(const Ore& ore, const FitCovariance& u,
                                const std::function<std::vector<double>(const Ore&)>& f, double width_scale) {
  auto eval = [&](const Ore& o, std::size_t n) {
    try {
      std::vector<double> v = f(o);
      if (v.size() == n) return v;
    } catch (const std::exception&) {
    }
    return std::vector<double>(n, kNaN);
  };
  const std::vector<double> v0 = f(ore);
  const std::size_t n = v0.size(), np = u.names.size();
  const std::vector<double> x0 = variables_of(ore, u.names);
  // The points the numbers are evaluated at: the fit's ± a step in each
  // fitted variable, then each held parameter at its range's ends.
  std::vector<std::vector<double>> plus, minus, ends;
  std::vector<double> steps;
  for (std::size_t j = 0; j < np; ++j) {
    const double h = u.matrix[j][j] > 0 ? 0.1 * std::sqrt(u.matrix[j][j]) : 1e-6;
    std::vector<double> xp = x0, xm = x0;
    xp[j] += h;
    xm[j] -= h;
    steps.push_back(h);
    plus.push_back(eval(with_variables(ore, u, xp), n));
    minus.push_back(eval(with_variables(ore, u, xm), n));
  }
  for (const HeldParameter& h : u.held) {
    const OreParameter* p = find_ore_parameter(h.name);
    if (!p) continue;
    for (int side = 0; side < 2; ++side) {
      const double at = side ? h.hi : h.lo;
      const std::vector<double>& free_at = side ? h.free_at_hi : h.free_at_lo;
      if (at == h.value) continue;
      Ore o = free_at.size() == np ? with_variables(ore, u, free_at) : ore;
      p->set(o, at);
      ends.push_back(eval(o, n));
    }
  }
  const double q = t_quantile(0.975, u.dof) * width_scale;
  std::vector<Interval> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(v0[i])) continue;
    // A number positive wherever it is evaluated is propagated as its
    // logarithm: its interval is then never below 0 (a feed rate, a P80),
    // and wider above than below where it grows faster than linearly.
    bool positive = v0[i] > 0;
    for (const auto* set : {&plus, &minus, &ends})
      for (const auto& v : *set) positive = positive && v[i] > 0;
    auto g_of = [&](double v) { return positive ? std::log(v) : v; };
    const double y0 = g_of(v0[i]);
    std::vector<double> g(np);
    for (std::size_t j = 0; j < np; ++j) g[j] = (g_of(plus[j][i]) - g_of(minus[j][i])) / (2 * steps[j]);
    double var = 0;
    for (std::size_t a = 0; a < np; ++a)
      for (std::size_t b = 0; b < np; ++b) var += g[a] * u.matrix[a][b] * g[b];
    double down = 0, up = 0;  // the held parameters' reach, below and above
    bool ok = std::isfinite(var);
    for (const auto& v : ends) {
      if (!std::isfinite(v[i])) ok = false;
      down = std::min(down, g_of(v[i]) - y0);
      up = std::max(up, g_of(v[i]) - y0);
    }
    if (!ok) continue;
    const double half = q * std::sqrt(std::max(var, 0.0));
    out[i].lo = positive ? std::exp(y0 - half + down) : y0 - half + down;
    out[i].hi = positive ? std::exp(y0 + half + up) : y0 + half + up;
  }
  return out;
}

}  // namespace mc::grind
