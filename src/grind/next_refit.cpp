// Which batch test to run next, by refits (next_refit.h).
#include "grind/next_refit.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

namespace mc::grind {

namespace {

using Matrix = std::vector<std::vector<double>>;

double to_var(const OreParameter& p, double v) { return p.log ? std::log(std::max(v, 1e-300)) : v; }
double from_var(const OreParameter& p, double x) { return p.log ? std::exp(x) : x; }
double clamp_var(const OreParameter& p, double x) {
  return std::min(std::max(x, to_var(p, p.log ? std::max(p.lo, 1e-300) : p.lo)), to_var(p, p.hi));
}

// The lower Cholesky factor of a covariance; a direction it cannot factor
// (not positive) gets no scatter.
Matrix cholesky(const Matrix& A) {
  const std::size_t n = A.size();
  Matrix L(n, std::vector<double>(n, 0.0));
  for (std::size_t j = 0; j < n; ++j) {
    double d = A[j][j];
    for (std::size_t k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
    if (!(d > 1e-300)) continue;
    L[j][j] = std::sqrt(d);
    for (std::size_t i = j + 1; i < n; ++i) {
      double s = A[i][j];
      for (std::size_t k = 0; k < j; ++k) s -= L[i][k] * L[j][k];
      L[i][j] = s / L[j][j];
    }
  }
  return L;
}

// A seed of its own for draw k of a run seeded `seed` (splitmix64).
std::uint64_t mix(std::uint64_t seed, std::uint64_t k) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (k + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// The free variables of an ore.
std::vector<double> free_variables(const Ore& o, const std::vector<std::string>& names) {
  std::vector<double> x;
  for (const std::string& n : names) {
    const OreParameter& p = *find_ore_parameter(n);
    x.push_back(to_var(p, p.get(o)));
  }
  return x;
}

}  // namespace

SeededNormal::SeededNormal(std::uint64_t seed) : state_(mix(seed, 0) | 1) {}

double SeededNormal::uniform() {
  state_ ^= state_ >> 12;
  state_ ^= state_ << 25;
  state_ ^= state_ >> 27;
  const std::uint64_t r = state_ * 0x2545F4914F6CDD1DULL;
  return (static_cast<double>(r >> 11) + 0.5) / 9007199254740992.0;
}

double SeededNormal::next() {
  if (has_spare_) return has_spare_ = false, spare_;
  const double u = uniform(), v = uniform();
  const double r = std::sqrt(-2 * std::log(u)), a = 2 * M_PI * v;
  spare_ = r * std::sin(a);
  has_spare_ = true;
  return r * std::cos(a);
}

std::vector<PlausibleTruth> plausible_truths(const Ore& ore, const RealTests& real, int n, std::uint64_t seed) {
  const FitCovariance& u = ore.fitted_under.covariance;
  const std::size_t np = u.names.size(), nh = u.held.size();
  SeededNormal g(mix(seed, 0x7275746873ULL));  // the truths' own stream: the candidates' scatter has others
  const Matrix L = cholesky(interval_covariance(u));
  const bool rays = nh > 0 && !u.edges.empty() && u.best.held.size() == nh && u.best.free.size() == np;
  const double t = t_quantile(0.975, interval_dof(u));
  std::vector<PlausibleTruth> out;
  for (int k = 0; k < n; ++k) {
    PlausibleTruth p;
    p.ore = rays ? best_point(ore, u) : ore;
    std::vector<double> centre = free_variables(p.ore, u.names);
    if (rays) {
      p.edge = std::min<int>(static_cast<int>(g.uniform() * u.edges.size()), static_cast<int>(u.edges.size()) - 1);
      const HeldEdge& e = u.edges[p.edge];
      // |z| chi-distributed with nh degrees of freedom, the edge at t: the
      // normal posterior along the ray, not cut at the edge (past it, r > 1,
      // clamped to the ore file's ranges below).
      double z2 = 0;
      for (std::size_t j = 0; j < nh; ++j) z2 += std::pow(g.next(), 2);
      p.fraction = std::sqrt(z2) / t;
      for (std::size_t j = 0; j < nh && j < e.held.size(); ++j) {
        const OreParameter& q = *find_ore_parameter(u.held[j].name);
        const double a = to_var(q, u.best.held[j]), b = to_var(q, e.held[j]);
        q.set(p.ore, from_var(q, clamp_var(q, a + p.fraction * (b - a))));
      }
      if (e.free.size() == np)
        for (std::size_t j = 0; j < np; ++j)
          centre[j] = clamp_var(*find_ore_parameter(u.names[j]), centre[j] + p.fraction * (e.free[j] - centre[j]));
      p.ore = with_variables(p.ore, u, centre);
      // The free ones refitted there, the held ones where the ray puts them:
      // a truth in the valley the real tests allow, not on a chord across it.
      if (np > 0) try {
          const BatchFit f = fit_batch_tests(p.ore, real.tests, u.names, 300, false);
          p.ore = f.ore;
          p.refitted = true;
          centre = free_variables(p.ore, u.names);
        } catch (const std::exception&) {
        }
    }
    // The free ones' own scatter, given the held ones.
    std::vector<double> z(np);
    for (double& v : z) v = g.next();
    std::vector<double> x = centre;
    for (std::size_t i = 0; i < np; ++i) {
      for (std::size_t j = 0; j <= i && i < L.size(); ++j) x[i] += L[i][j] * z[j];
      x[i] = clamp_var(*find_ore_parameter(u.names[i]), x[i]);
    }
    p.ore = with_variables(p.ore, u, x);
    out.push_back(p);
  }
  return out;
}

std::vector<std::string> held_without_edges(const Ore& ore) {
  const FitCovariance& u = ore.fitted_under.covariance;
  const std::size_t nh = u.held.size();
  const bool rays = nh > 0 && !u.edges.empty() && u.best.held.size() == nh && u.best.free.size() == u.names.size();
  std::vector<std::string> out;
  for (std::size_t j = 0; j < nh; ++j) {
    bool moved = false;
    for (const HeldEdge& e : u.edges) moved = moved || (rays && j < e.held.size() && e.held[j] != u.best.held[j]);
    if (!moved) out.push_back(u.held[j].name);
  }
  return out;
}

BatchTest simulated_test(const Ore& truth, const TestInMill& candidate, double scatter_pp, SeededNormal& noise) {
  BatchTest t = candidate.test;
  t.passing = batch_test_products(truth, candidate.spectrum, candidate.power_W, candidate.holdup_kg, t);
  const std::vector<std::size_t> sieves = informative_sieves(t);
  // Correlated along the sieves as the candidate's sieve_rho says (AR(1),
  // each reading's scatter scatter_pp; sieve_errors.h); independent at 0.
  const double rho = candidate.sieve_rho, keep = std::sqrt(1 - rho * rho);
  for (auto& row : t.passing) {
    double e = 0;
    for (std::size_t j = 0; j < sieves.size(); ++j) {
      const double xi = noise.next();
      e = j == 0 ? xi : rho * e + keep * xi;
      row[sieves[j]] += scatter_pp / 100 * e;
    }
  }
  return t;
}

std::vector<RefitWidth> refitted_widths(const Ore& ore, const RealTests& real,
                                        const std::vector<PlausibleTruth>& truths,
                                        const std::vector<TestInMill>& candidates,
                                        const std::function<double(const Ore&)>& number, double scatter_pp,
                                        std::uint64_t seed, unsigned threads) {
  // Each draw on its own seed (the draw's, not the candidate's: every
  // candidate sees the same scatter), its result in its own place: the same
  // widths whatever the threads. A draw that keeps held parameters costs a
  // profile search, so the draws of every candidate are shared out one at a
  // time from one list.
  const std::size_t nd = truths.size(), nc = candidates.size();
  std::vector<double> width(nc * nd, std::numeric_limits<double>::quiet_NaN());
  std::vector<std::string> why(nc * nd);
  auto draw = [&](std::size_t at) {
    const std::size_t m = at / nd, k = at % nd;
    SeededNormal noise(mix(seed, k));
    try {  // the copies and the simulated test too: a truth where the candidate cannot be made is a failed draw
      std::vector<TestInMill> tests = real.tests;
      TestInMill c = candidates[m];
      c.test.noise_pp = real.tests.empty() ? 1.0 : real.tests.front().test.noise_pp;
      if (!real.tests.empty()) c.sieve_rho = real.tests.front().sieve_rho;  // sieved as the fit took the tests
      c.test = simulated_test(truths[k].ore, c, scatter_pp, noise);
      tests.push_back(c);
      BatchFit f = fit_batch_tests(ore, tests, real.names);
      const FitCovariance u = fit_covariance(f, tests);
      f.ore.fitted_under.covariance = u;
      const Interval i = propagate(f.ore, u, [&](const Ore& o) { return std::vector<double>{number(o)}; })[0];
      if (!i.valid() || !std::isfinite(i.lo) || !std::isfinite(i.hi))
        why[at] = "the fit has no closed interval of the product";
      else
        width[at] = i.hi - i.lo;
    } catch (const std::exception& e) {
      why[at] = e.what();
    } catch (...) {  // nothing may leave a thread
      why[at] = "the fit failed";
    }
  };
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t at; (at = next++) < nc * nd;) draw(at);
  };
  const std::size_t n_threads =
      std::min<std::size_t>(threads > 0 ? threads : std::max(1u, std::thread::hardware_concurrency()),
                            std::max<std::size_t>(nc * nd, 1));
  std::vector<std::thread> pool;
  try {
    for (std::size_t t = 1; t < n_threads; ++t) pool.emplace_back(worker);
  } catch (const std::system_error&) {
    // No more threads to be had: those made, and this one, share the draws
    // (a throw past the joinable ones would end the program).
  }
  worker();
  for (std::thread& t : pool) t.join();
  std::vector<RefitWidth> out(nc);
  for (std::size_t m = 0; m < nc; ++m) {
    std::vector<double> per_draw(width.begin() + m * nd, width.begin() + (m + 1) * nd);
    std::vector<std::string> whys;
    for (std::size_t k = 0; k < nd; ++k)
      if (!std::isfinite(per_draw[k])) whys.push_back("draw " + std::to_string(k + 1) + ": " + why[m * nd + k]);
    out[m] = summarise_draws(per_draw, whys);
  }
  return out;
}

RefitWidth summarise_draws(const std::vector<double>& per_draw, const std::vector<std::string>& why,
                           double width_now) {
  const double inf = std::numeric_limits<double>::infinity();
  RefitWidth r;
  r.draws = static_cast<int>(per_draw.size());
  r.failures = why;
  int wide = 0;
  for (double w : per_draw) {
    const bool ok = std::isfinite(w);
    r.per_draw.push_back(ok ? w : inf);
    if (ok) r.widths.push_back(w);
    wide += !ok || w > width_now;
  }
  r.converged = static_cast<int>(r.widths.size());
  if (r.draws == 0) return r;
  r.median = quantile(r.per_draw, 0.5);
  r.p10 = quantile(r.per_draw, 0.1);
  r.p90 = quantile(r.per_draw, 0.9);
  r.wide = static_cast<double>(wide) / r.draws;
  if (r.converged > 0) {
    double sum = 0;
    for (double w : r.widths) sum += w;
    r.mean = sum / r.converged;
  }
  return r;
}

bool ranks_before(const RefitWidth& a, const RefitWidth& b) {
  // NaN (no draws) after everything; inf equal to inf, then the next figure.
  auto key = [](double v) { return std::isnan(v) ? std::numeric_limits<double>::infinity() : v; };
  const double ka[] = {key(a.median), key(a.wide), key(a.p90), key(a.mean)};
  const double kb[] = {key(b.median), key(b.wide), key(b.p90), key(b.mean)};
  for (int k = 0; k < 4; ++k)
    if (ka[k] != kb[k]) return ka[k] < kb[k];
  return false;
}

RefitWidth refitted_width(const Ore& ore, const RealTests& real, const std::vector<PlausibleTruth>& truths,
                          const TestInMill& candidate, const std::function<double(const Ore&)>& number,
                          double scatter_pp, std::uint64_t seed) {
  return refitted_widths(ore, real, truths, {candidate}, number, scatter_pp, seed).front();
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const double at = q * (v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(at)), hi = std::min(lo + 1, v.size() - 1);
  if (at == lo || v[hi] == v[lo]) return v[lo];
  if (std::isinf(v[hi])) return v[hi];  // a step toward an infinite one
  return v[lo] + (at - lo) * (v[hi] - v[lo]);
}

}  // namespace mc::grind
