// The fit's uncertainty carried to a fitted ore's products (interval.h).
#include "grind/interval.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <string>
#include <vector>

namespace mc::grind {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

double to_var(const OreParameter& p, double v) { return p.log ? std::log(v) : v; }
double from_var(const OreParameter& p, double x) { return p.log ? std::exp(x) : x; }
// The ore file's range in the fitted variable.
double var_lo(const OreParameter& p) { return to_var(p, p.log ? std::max(p.lo, 1e-300) : p.lo); }
double var_hi(const OreParameter& p) { return to_var(p, p.hi); }

std::vector<double> variables_of(const Ore& ore, const std::vector<std::string>& names) {
  std::vector<double> x;
  for (const std::string& n : names) {
    const OreParameter* p = find_ore_parameter(n);
    x.push_back(to_var(*p, p->get(ore)));
  }
  return x;
}

// ------------------------------------------------------------ profiles

// The free parameters refitted with some held ones moved (none of them
// held in turn: they are free at the fit), and `also` (held ones refitted
// with them, for a profile): the weighted sum of squares there and the
// free variables; ok false where no fit is found.
struct Refit {
  bool ok = false;
  double ssr = kInf;
  std::vector<double> free;
  Ore ore;
};

Refit refit(const Ore& from, const FitCovariance& u, const std::vector<TestInMill>& tests,
            const std::vector<std::string>& also = {}) {
  Refit r;
  r.ore = from;
  std::vector<std::string> names = u.names;
  names.insert(names.end(), also.begin(), also.end());
  try {
    if (!names.empty()) {
      const BatchFit f = fit_batch_tests(from, tests, names, 300, false);
      r.ore = f.ore;
      r.ssr = f.ssr;
    } else {
      r.ssr = weighted_ssr(from, tests);
    }
  } catch (const std::exception&) {
    return r;
  }
  r.ok = std::isfinite(r.ssr);
  r.free = variables_of(r.ore, u.names);
  return r;
}

// A point of the held parameters: their values (file units) and the free
// ones refitted there.
struct HeldPoint {
  std::vector<double> held;
  Refit at;
};

HeldPoint held_point(const FitCovariance& u, const std::vector<double>& held, const Ore& warm,
                     const std::vector<TestInMill>& tests) {
  Ore o = warm;
  for (std::size_t k = 0; k < held.size(); ++k) find_ore_parameter(u.held[k].name)->set(o, held[k]);
  return {held, refit(o, u, tests)};
}

// A point of held parameter j's profile: j at `value`, the free ones and
// the other held ones refitted from `warm` (where they start). A refit
// along a flat direction can end in a worse valley than where it started:
// the free ones are also refitted alone, the other held ones as in `warm`,
// and the lower S of the two kept (the profile is the least S over the
// others; each refit is a point above it), where the first is past
// `limit` or found no fit (within it, the point is inside the profile's
// stretch either way).
HeldPoint profile_point(const FitCovariance& u, std::size_t j, double value, const Ore& warm,
                        const std::vector<TestInMill>& tests, double limit = 0) {
  Ore o = warm;
  find_ore_parameter(u.held[j].name)->set(o, value);
  std::vector<std::string> others;
  for (std::size_t k = 0; k < u.held.size(); ++k)
    if (k != j) others.push_back(u.held[k].name);
  Refit r = refit(o, u, tests, others);
  if (!others.empty() && !(r.ok && r.ssr <= limit)) {
    Refit alone = refit(o, u, tests);
    if (alone.ok && (!r.ok || alone.ssr < r.ssr)) r = alone;
  }
  std::vector<double> held;
  for (const HeldParameter& h : u.held) held.push_back(find_ore_parameter(h.name)->get(r.ok ? r.ore : o));
  held[j] = value;
  return {held, r};
}

struct LinePoint {
  double x = 0;  // the moving held parameter's variable
  HeldPoint p;
};

// Held parameter j moved through the point `from` (its profile: the others
// refitted at each point, from the point before): each
// side stepped out (a factor of e for a scale, a quarter of its file
// range for a value) to the file's range, or to the first point past the
// limit of the least S met so far (which only falls: a point past it stays
// past it), or where no fit is found. Sorted by x, `from` among them.
std::vector<LinePoint> line(const FitCovariance& u, std::size_t j, const HeldPoint& from,
                            const std::vector<TestInMill>& tests, double& ssr_min) {
  const OreParameter& p = *find_ore_parameter(u.held[j].name);
  const double x0 = to_var(p, from.held[j]), step = p.log ? 1.0 : (p.hi - p.lo) / 4;
  std::vector<LinePoint> pts = {{x0, from}};
  for (int dir : {-1, +1}) {
    const double end = dir < 0 ? var_lo(p) : var_hi(p);
    double x = x0;
    Ore warm = from.at.ore;
    while (dir < 0 ? x > end : x < end) {
      x = dir < 0 ? std::max(x - step, end) : std::min(x + step, end);
      pts.push_back({x, profile_point(u, j, from_var(p, x), warm, tests, profile_limit(ssr_min, interval_dof(u)))});
      const Refit& r = pts.back().p.at;
      if (!r.ok) break;
      ssr_min = std::min(ssr_min, r.ssr);
      if (r.ssr > profile_limit(ssr_min, interval_dof(u))) break;
      warm = r.ore;
    }
  }
  std::sort(pts.begin(), pts.end(), [](const LinePoint& a, const LinePoint& b) { return a.x < b.x; });
  return pts;
}

std::size_t lowest_of(const std::vector<LinePoint>& pts) {
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (pts[i].p.at.ok && pts[i].p.at.ssr < pts[k].p.at.ssr) k = i;
  return k;
}

// The least S on a line between the neighbours of its least point, by
// golden sections: until the bracket is a thousandth of a step or the two
// inner points' S differ by less than 10⁻⁴ of `margin` (a flat profile);
// at most 16 refits. Inserted into the line; its index returned.
std::size_t refine(std::vector<LinePoint>& pts, const FitCovariance& u, std::size_t j,
                   const std::vector<TestInMill>& tests, double margin) {
  const OreParameter& p = *find_ore_parameter(u.held[j].name);
  const double step = p.log ? 1.0 : (p.hi - p.lo) / 4;
  const std::size_t k = lowest_of(pts);
  LinePoint lowest = pts[k];
  double a = k > 0 ? pts[k - 1].x : pts[k].x, b = k + 1 < pts.size() ? pts[k + 1].x : pts[k].x;
  if (!(b > a)) return k;
  const double limit = profile_limit(lowest.p.at.ssr, interval_dof(u));
  auto at = [&](double x) {
    return LinePoint{x, profile_point(u, j, from_var(p, x), lowest.p.at.ore, tests, limit)};
  };
  auto keep = [&](const LinePoint& q) {
    if (q.p.at.ok && q.p.at.ssr < lowest.p.at.ssr) lowest = q;
  };
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  LinePoint c = at(b - g * (b - a)), d = at(a + g * (b - a));
  for (int i = 0; i < 14 && b - a > 1e-3 * step; ++i) {
    keep(c), keep(d);
    if (i >= 2 && c.p.at.ok && d.p.at.ok && std::fabs(c.p.at.ssr - d.p.at.ssr) < 1e-4 * margin) break;
    if (!(d.p.at.ok && (!c.p.at.ok || c.p.at.ssr > d.p.at.ssr))) {
      b = d.x, d = c, c = at(b - g * (b - a));
    } else {
      a = c.x, c = d, d = at(a + g * (b - a));
    }
  }
  keep(c), keep(d);
  if (lowest.x == pts[k].x) return k;
  const auto it = std::upper_bound(pts.begin(), pts.end(), lowest,
                                   [](const LinePoint& l, const LinePoint& r) { return l.x < r.x; });
  const auto at_lowest = pts.insert(it, lowest);
  return static_cast<std::size_t>(at_lowest - pts.begin());
}

// The stretch of a line within `limit` around its point `k`: each end
// between the last point within and the first past, by halvings to 2 %
// of its distance from point k (at most twenty), as the rays' ends. The
// two ends.
std::pair<LinePoint, LinePoint> stretch(const std::vector<LinePoint>& pts, std::size_t k, const FitCovariance& u,
                                        std::size_t j, const std::vector<TestInMill>& tests, double limit) {
  const OreParameter& p = *find_ore_parameter(u.held[j].name);
  auto within = [&](const LinePoint& q) { return q.p.at.ok && q.p.at.ssr <= limit; };
  LinePoint ends[2];
  for (int side = 0; side < 2; ++side) {
    const int dir = side ? +1 : -1;
    std::size_t i = k;
    while ((dir < 0 ? i > 0 : i + 1 < pts.size()) && within(pts[dir < 0 ? i - 1 : i + 1])) i = dir < 0 ? i - 1 : i + 1;
    LinePoint in = pts[i];
    if (dir < 0 ? i > 0 : i + 1 < pts.size()) {
      double x_out = pts[dir < 0 ? i - 1 : i + 1].x;
      for (int b = 0; b < 20 && std::fabs(x_out - in.x) > 0.02 * std::fabs(in.x - pts[k].x); ++b) {
        const double x = 0.5 * (in.x + x_out);
        LinePoint q{x, profile_point(u, j, from_var(p, x), in.p.at.ore, tests, limit)};
        if (within(q)) in = q;
        else x_out = x;
      }
    }
    ends[side] = in;
  }
  return {ends[0], ends[1]};
}

// An edge point, unless it is the best point or one kept already.
void add_edge(FitCovariance& u, const std::vector<double>& best, const std::vector<double>& held,
              const std::vector<double>& free, int of = -1) {
  if (held == best) return;
  for (const HeldEdge& e : u.edges)
    if (e.held == held) return;
  u.edges.push_back({held, free, of});
}

// What the data leave open to the held parameters (fit_covariance):
// 1. where they fit best: each moved in turn through the best point met
//    (its least S refined by golden sections);
// 2. through that point, each one's stretch within S_min (1 + t²/ν): its
//    range (widened to hold where it is held) and two edge points;
// 3. two to four together, from the best point toward each corner of their
//    ranges, as far as the limit allows (the corner itself, or found by
//    six halvings): more edge points.
void held_ranges(FitCovariance& u, const BatchFit& fit, const std::vector<TestInMill>& tests) {
  const std::size_t nh = u.held.size();
  Refit at_fit;
  at_fit.ok = true;
  at_fit.ssr = fit.ssr;
  at_fit.free = u.values;
  at_fit.ore = fit.ore;
  std::vector<double> held;
  for (const HeldParameter& h : u.held) held.push_back(h.value);
  HeldPoint best{held, at_fit};
  // With two or more, the first profile starts where the others are
  // refitted at the first one's held value.
  if (nh >= 2) {
    const HeldPoint start = profile_point(u, 0, held[0], fit.ore, tests);
    if (start.at.ok && start.at.ssr < best.at.ssr) best = start;
  }
  double ssr_min = best.at.ssr;
  const int nu = interval_dof(u);
  const double margin = profile_limit(fit.ssr, nu) - fit.ssr;
  std::vector<std::vector<LinePoint>> lines(nh);
  for (std::size_t j = 0; j < nh; ++j) {
    lines[j] = line(u, j, best, tests, ssr_min);
    const std::size_t k = refine(lines[j], u, j, tests, margin);
    if (lines[j][k].p.at.ssr < best.at.ssr) best = lines[j][k].p;
  }
  const double limit = profile_limit(best.at.ssr, nu);
  u.best = {best.held, best.at.free};
  u.ssr_fit = fit.ssr;
  u.ssr_best = best.at.ssr;
  u.ssr_limit = limit;
  std::vector<std::pair<std::vector<double>, std::vector<double>>> profile_ends;  // each one's low and high end
  for (std::size_t j = 0; j < nh; ++j) {
    // The last line runs through the best point already; the others again.
    std::vector<LinePoint> pts = lines[j];
    std::size_t k = lowest_of(pts);
    if (pts[k].p.held != best.held) {
      double ignored = best.at.ssr;
      pts = line(u, j, best, tests, ignored);
      k = 0;
      while (pts[k].p.held != best.held) ++k;
    }
    const auto [lo, hi] = stretch(pts, k, u, j, tests, limit);
    HeldParameter& h = u.held[j];
    const OreParameter& p = *find_ore_parameter(h.name);
    const double x_held = to_var(p, h.value);
    // The range, widened to hold where the parameter is held (its products are made there).
    h.lo = lo.x < x_held ? from_var(p, lo.x) : h.value;
    h.hi = hi.x > x_held ? from_var(p, hi.x) : h.value;
    h.free_at_lo = lo.x < x_held ? lo.p.at.free : u.values;
    h.free_at_hi = hi.x > x_held ? hi.p.at.free : u.values;
    for (const LinePoint* e : {&lo, &hi}) add_edge(u, best.held, e->p.held, e->p.at.free, static_cast<int>(j));
    // Its ends in the variables, every held parameter, for the region's shape.
    if (lo.x < hi.x) {
      std::pair<std::vector<double>, std::vector<double>> e;
      for (std::size_t k = 0; k < nh; ++k) {
        const OreParameter& q = *find_ore_parameter(u.held[k].name);
        e.first.push_back(to_var(q, lo.p.held[k]));
        e.second.push_back(to_var(q, hi.p.held[k]));
      }
      profile_ends.push_back(e);
    }
  }
  if (nh < 2 || nh > 4) return;
  std::vector<const OreParameter*> ps;
  for (const HeldParameter& h : u.held) ps.push_back(find_ore_parameter(h.name));
  std::vector<double> x0(nh);
  for (std::size_t j = 0; j < nh; ++j) x0[j] = to_var(*ps[j], best.held[j]);
  // From the best point along d, as far as the limit allows. S along a
  // ray rises about as the square of the distance (exactly so for a model
  // linear in its parameters), so each refit predicts where S meets the
  // limit, s √((limit − S_b) / (S − S_b)), and the next is taken there
  // (2 % short of it where the last was past), kept inside the bracket of
  // the last point within and the first past (halved instead where the
  // last prediction did not halve it: S flat, then a wall): from x0 + d
  // (or where the ray leaves the file's range, or s_cap), until a point
  // within lies within 2 % of the prediction, at most eight refits; then, where none is
  // within, four halvings toward the best point. The last point within is
  // an edge point.
  auto ray = [&](const std::vector<double>& d, double s_cap) {
    double s_max = s_cap;
    bool moves = false;
    for (std::size_t j = 0; j < nh; ++j) {
      if (d[j] > 0) s_max = std::min(s_max, (var_hi(*ps[j]) - x0[j]) / d[j]);
      if (d[j] < 0) s_max = std::min(s_max, (var_lo(*ps[j]) - x0[j]) / d[j]);
      moves = moves || d[j] != 0;
    }
    if (!moves || !(s_max > 0)) return;
    if (s_max == kInf) s_max = 1;
    auto at = [&](double s, const Ore& warm) {
      std::vector<double> v(nh);
      for (std::size_t j = 0; j < nh; ++j) v[j] = from_var(*ps[j], x0[j] + s * d[j]);
      return held_point(u, v, warm, tests);
    };
    const double s_b = best.at.ssr;
    double s_in = 0, s_out = kInf, s = std::min(1.0, s_max);
    HeldPoint in = best;
    double bracket = kInf;  // s_out − s_in before the last refit
    for (int k = 0; k < 8; ++k) {
      const HeldPoint q = at(s, s_in > 0 ? in.at.ore : best.at.ore);
      const bool within = q.at.ok && q.at.ssr <= limit;
      if (within) s_in = s, in = q;
      else s_out = std::min(s_out, s);
      if (within && s_in >= s_max) break;  // on the file's range
      double next = q.at.ok && q.at.ssr > s_b ? s * std::sqrt((limit - s_b) / (q.at.ssr - s_b)) : 2 * s;
      if (!within) next *= 0.98;
      if (within && std::fabs(next - s) <= 0.02 * s) break;
      next = std::min(next, s_max);
      // A prediction outside the bracket, or one that did not halve it
      // last time (S far from quadratic along the ray: flat, then a wall):
      // halve it instead.
      const bool slow = s_out < kInf && s_out - s_in > 0.5 * bracket;
      if (s_out < kInf) bracket = s_out - s_in;
      if (!(next > s_in && next < s_out) || slow)
        next = s_out < kInf ? 0.5 * (s_in + s_out) : std::min(2 * s_in, s_max);
      s = next;
    }
    for (int b = 0; b < 4 && s_in == 0 && s_out < kInf; ++b) {
      s = 0.5 * s_out;
      const HeldPoint q = at(s, best.at.ore);
      if (q.at.ok && q.at.ssr <= limit) s_in = s, in = q;
      else s_out = s;
    }
    if (s_in > 0) add_edge(u, best.held, in.held, in.at.free);
  };
  // The region's shape from the profiles' ends: for a model linear in its
  // parameters the region is an ellipsoid Δ Σ, and the end of k's profile
  // lies at √Δ Σ e_k / √Σ_kk from its centre, so Δ Σ_lk = P_k[l] P_k[k],
  // P_k half the vector from k's low end to its high one. Rays along the
  // ± axes and the diagonals of the space that makes the ellipsoid a ball
  // (L w, L Lᵀ = Δ Σ, L lower triangular; ±e₀ left out, L e₀ being held
  // 0's profile end): in two dimensions, with the profiles' ends, no two
  // directions more than 45° apart, so a linear number's extreme is within
  // cos 22.5° of the point nearest it whatever the correlation. Where that shape cannot be had (a profile
  // without two ends, Σ not positive definite): toward each corner of the
  // ranges, as before.
  std::vector<std::vector<double>> A(nh, std::vector<double>(nh, 0.0)), L(nh, std::vector<double>(nh, 0.0));
  bool shaped = profile_ends.size() == nh;
  for (std::size_t k = 0; k < nh && shaped; ++k)
    for (std::size_t l = 0; l < nh; ++l) {
      const double pk = 0.5 * (profile_ends[k].second[k] - profile_ends[k].first[k]);
      A[l][k] += 0.5 * 0.5 * (profile_ends[k].second[l] - profile_ends[k].first[l]) * pk;
      A[k][l] += 0.5 * 0.5 * (profile_ends[k].second[l] - profile_ends[k].first[l]) * pk;
    }
  for (std::size_t j = 0; j < nh && shaped; ++j) {  // Cholesky
    double dd = A[j][j];
    for (std::size_t k = 0; k < j; ++k) dd -= L[j][k] * L[j][k];
    if (!(dd > 1e-12 * std::max(A[j][j], 1e-300)) || !std::isfinite(dd)) shaped = false;
    else L[j][j] = std::sqrt(dd);
    for (std::size_t i = j + 1; i < nh && shaped; ++i) {
      double v = A[i][j];
      for (std::size_t k = 0; k < j; ++k) v -= L[i][k] * L[j][k];
      L[i][j] = v / L[j][j];
    }
  }
  if (shaped) {
    std::vector<std::vector<double>> ws;
    for (std::size_t i = 1; i < nh; ++i)  // L e₀ is held 0's own profile end: no ray
      for (double sign : {-1.0, 1.0}) {
        std::vector<double> w(nh, 0.0);
        w[i] = sign;
        ws.push_back(w);
      }
    for (unsigned c = 0; c < (1u << nh); ++c) {
      std::vector<double> w(nh);
      for (std::size_t j = 0; j < nh; ++j) w[j] = ((c >> j) & 1u ? 1.0 : -1.0) / std::sqrt(static_cast<double>(nh));
      ws.push_back(w);
    }
    for (const std::vector<double>& w : ws) {
      std::vector<double> d(nh, 0.0);
      for (std::size_t i = 0; i < nh; ++i)
        for (std::size_t k = 0; k <= i; ++k) d[i] += L[i][k] * w[k];
      ray(d, kInf);
    }
    return;
  }
  for (unsigned c = 0; c < (1u << nh); ++c) {
    std::vector<double> d(nh);
    std::size_t moving = 0;
    for (std::size_t j = 0; j < nh; ++j) {
      d[j] = to_var(*ps[j], (c >> j) & 1u ? u.held[j].hi : u.held[j].lo) - x0[j];
      moving += d[j] != 0;
    }
    ray(d, moving >= 2 ? kInf : 1);  // one moving alone: its own range's end, no further
  }
}

// The Jacobian of the weighted residuals at `ore` in the free variables and
// then the held ones (one row a variable): by differences inside the ore
// file's ranges (central, or one-sided of second order at a bound), steps
// of 10⁻⁴ of the variable (at least 10⁻⁴).
std::vector<std::vector<double>> jacobian(const FitCovariance& u, const Ore& ore, const std::vector<TestInMill>& tests) {
  std::vector<const OreParameter*> ps;
  for (const std::string& n : u.names) ps.push_back(find_ore_parameter(n));
  for (const HeldParameter& h : u.held) ps.push_back(find_ore_parameter(h.name));
  const std::vector<double> r0 = weighted_residuals(ore, tests);
  std::vector<std::vector<double>> J(ps.size());
  for (std::size_t v = 0; v < ps.size(); ++v) {
    const OreParameter& p = *ps[v];
    const double x = to_var(p, p.get(ore)), lo = var_lo(p), hi = var_hi(p);
    double h = 1e-4 * std::max(1.0, std::fabs(x));
    if (x - h < lo && x + h > hi) h = std::max(hi - x, x - lo) / 2;
    const int sign = x + h <= hi && x - h >= lo ? 0 : x + 2 * h <= hi ? +1 : -1;
    auto at = [&](double xv) {
      Ore o = ore;
      p.set(o, from_var(p, xv));
      return weighted_residuals(o, tests);
    };
    const std::vector<double> a = at(sign == 0 ? x + h : x + sign * h), b = at(sign == 0 ? x - h : x + 2 * sign * h);
    for (std::size_t i = 0; i < r0.size(); ++i)
      J[v].push_back(sign == 0 ? (a[i] - b[i]) / (2 * h) : sign * (-3 * r0[i] + 4 * a[i] - b[i]) / (2 * h));
  }
  return J;
}

// The tests' information on every variable, JᵀJ / s² (s² the fit's).
std::vector<std::vector<double>> information(const FitCovariance& u, const std::vector<std::vector<double>>& J) {
  if (!(u.residual_variance_pp2 > 0)) return {};
  std::vector<std::vector<double>> L(J.size(), std::vector<double>(J.size(), 0.0));
  for (std::size_t a = 0; a < J.size(); ++a)
    for (std::size_t b = 0; b < J.size(); ++b) {
      for (std::size_t i = 0; i < J[a].size(); ++i) L[a][b] += J[a][i] * J[b][i];
      L[a][b] /= u.residual_variance_pp2;
    }
  return L;
}

// ------------------------------------------------------------ Student's t

// P(T <= t) for Student's t with nu degrees of freedom, by the
// regularised incomplete beta function (pbm.h): 1 - I_x(nu/2, 1/2) / 2,
// x = nu / (nu + t²), for t >= 0.
double t_cdf(double t, double nu) {
  const double tail = 0.5 * incomplete_beta(nu / (nu + t * t), 0.5 * nu, 0.5);
  return t >= 0 ? 1 - tail : tail;
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

// An evaluation of f that gives NaNs instead of throwing.
std::vector<double> evaluate(const std::function<std::vector<double>(const Ore&)>& f, const Ore& o, std::size_t n) {
  try {
    std::vector<double> v = f(o);
    if (v.size() == n) return v;
  } catch (const std::exception&) {
  }
  return std::vector<double>(n, kNaN);
}

}  // namespace

double profile_limit(double ssr_min, int dof) {
  return dof > 0 ? ssr_min * (1 + std::pow(t_quantile(0.975, dof), 2) / dof) : kNaN;
}

int interval_dof(const FitCovariance& u) { return u.dof - static_cast<int>(u.held.size()); }

double interval_variance(const FitCovariance& u) {
  if (u.held.empty()) return u.residual_variance_pp2;
  const int nu = interval_dof(u);
  if (nu <= 0) return kNaN;
  const double s_min = u.ssr_best > 0 ? u.ssr_best : u.residual_variance_pp2 * u.dof;
  return s_min / nu;
}

std::vector<std::vector<double>> interval_covariance(const FitCovariance& u) {
  std::vector<std::vector<double>> C = u.matrix;
  if (u.held.empty() || !(u.residual_variance_pp2 > 0)) return C;
  const double scale = interval_variance(u) / u.residual_variance_pp2;
  for (auto& row : C)
    for (double& c : row) c *= scale;
  return C;
}

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

std::string ore_file_key(const std::string& parameter) {
  return parameter.rfind("breakage.", 0) == 0 || parameter.rfind("rates.", 0) == 0 ? parameter : "rates." + parameter;
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
    u.held.push_back(h);
  }
  if (!u.held.empty() && interval_dof(u) > 0) held_ranges(u, fit, tests);
  // The free parameters' covariance and the information where the
  // interval is centred: where the held ones fit best, the free ones
  // refitted there (the fit's own point without held ones). Taken where
  // they are held, a curvature far from the data's best can make the free
  // part many times too wide (or too narrow).
  const Ore at = best_point(fit.ore, u);
  const std::vector<std::vector<double>> J = jacobian(u, at, tests);
  u.information = information(u, J);
  if (!u.held.empty() && u.best.held.size() == u.held.size() && !u.names.empty() && !J.empty()) {
    std::vector<std::vector<double>> Jf(J[0].size(), std::vector<double>(u.names.size()));
    for (std::size_t a = 0; a < u.names.size(); ++a)
      for (std::size_t i = 0; i < J[a].size(); ++i) Jf[i][a] = J[a][i];
    // s² the fit's (S at the held point over its dof), as the fit's own
    // covariance: interval_covariance rescales it to S_min / ν.
    u.matrix = covariance_matrix(Jf, fit.ssr);
  }
  return u;
}

double t_quantile(double p, int dof) {
  if (dof <= 0) return normal_quantile(p);
  if (dof == 1) return std::tan(kPi * (p - 0.5));
  if (dof == 2) return (2 * p - 1) / std::sqrt(2 * p * (1 - p));
  if (p == 0.5) return 0;
  if (p < 0.5) return -t_quantile(1 - p, dof);
  double lo = 0, hi = 1;
  while (t_cdf(hi, dof) < p && hi < 1e300) lo = hi, hi *= 2;
  for (int k = 0; k < 200 && hi - lo > 1e-15 * hi; ++k) {
    const double mid = 0.5 * (lo + hi);
    (t_cdf(mid, dof) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

Ore with_variables(const Ore& ore, const FitCovariance& u, const std::vector<double>& x) {
  Ore o = ore;
  for (std::size_t j = 0; j < u.names.size() && j < x.size(); ++j) {
    const OreParameter* p = find_ore_parameter(u.names[j]);
    p->set(o, from_var(*p, x[j]));
  }
  return o;
}

Ore best_point(const Ore& ore, const FitCovariance& u) {
  if (u.held.empty() || u.best.held.size() != u.held.size() || u.best.free.size() != u.names.size()) return ore;
  Ore o = with_variables(ore, u, u.best.free);
  for (std::size_t k = 0; k < u.held.size(); ++k) find_ore_parameter(u.held[k].name)->set(o, u.best.held[k]);
  return o;
}

std::vector<Sensitivity> sensitivities(const Ore& ore, const FitCovariance& u,
                                       const std::function<std::vector<double>(const Ore&)>& f, bool held_gradient) {
  const std::vector<double> v0 = f(ore);
  const std::size_t n = v0.size(), np = u.names.size(), nh = u.held.size();
  // The gradients are taken where the interval is centred: the best point
  // of the held parameters, the free ones refitted there.
  const Ore at = best_point(ore, u);
  const std::vector<double> x0 = variables_of(at, u.names);
  // Two points a free variable: x ± h, or x + h and x + 2h (x − h and
  // x − 2h) where a step would leave the ore file's range.
  struct Diff {
    double h = 0;
    int sign = 0;  // 0: central; +1 forward, -1 backward
    std::vector<double> a, b;  // f at x + h and x − h (central) or x ± h and x ± 2h
  };
  auto differences = [&](const OreParameter& p, double x, double h, const std::function<Ore(double)>& moved) {
    Diff d;
    const double lo = var_lo(p), hi = var_hi(p);
    if (x - h < lo && x + h > hi) h = std::max(hi - x, x - lo) / 2;
    d.h = h;
    d.sign = x + h <= hi && x - h >= lo ? 0 : x + 2 * h <= hi ? +1 : -1;
    d.a = evaluate(f, moved(d.sign == 0 ? x + h : x + d.sign * h), n);
    d.b = evaluate(f, moved(d.sign == 0 ? x - h : x + 2 * d.sign * h), n);
    return d;
  };
  std::vector<Diff> diffs, held_diffs;
  for (std::size_t j = 0; j < np; ++j) {
    const OreParameter& p = *find_ore_parameter(u.names[j]);
    const double h = u.matrix[j][j] > 0 ? 0.1 * std::sqrt(u.matrix[j][j]) : 1e-6;
    diffs.push_back(differences(p, x0[j], h, [&](double x) {
      std::vector<double> xs = x0;
      xs[j] = x;
      return with_variables(at, u, xs);
    }));
  }
  if (held_gradient)
    for (const HeldParameter& hp : u.held) {
      const OreParameter& p = *find_ore_parameter(hp.name);
      held_diffs.push_back(differences(p, to_var(p, p.get(at)), 1e-3, [&](double x) {
        Ore o = at;
        p.set(o, from_var(p, x));
        return o;
      }));
    }
  // The held parameters' points: each alone at its range's ends, then
  // together toward the corners; the free ones as refitted there.
  auto at_point = [&](const HeldEdge& c) {
    Ore o = c.free.size() == np ? with_variables(ore, u, c.free) : ore;
    for (std::size_t k = 0; k < nh; ++k) find_ore_parameter(u.held[k].name)->set(o, c.held[k]);
    return evaluate(f, o, n);
  };
  // The centre the held parameters' reach is measured from: where they fit
  // the data best (else, an ore written without it, where they are held).
  const bool centred = nh > 0 && u.best.held.size() == nh;
  const std::vector<double> at_best = centred ? at_point(u.best) : v0;
  std::vector<std::vector<double>> ends;
  std::vector<int> end_of;  // the held parameter a point moves alone from the centre; -1: several
  if (!u.edges.empty()) {
    // An ore that marks its profiles' ends names each one's; one written
    // before: a point that moves one parameter alone is that one's.
    bool marked = false;
    for (const HeldEdge& e : u.edges) marked = marked || e.of >= 0;
    for (const HeldEdge& e : u.edges) {
      if (e.held.size() != nh) continue;
      ends.push_back(at_point(e));
      int alone = -1, moved = 0;
      for (std::size_t k = 0; k < nh; ++k)
        if (!centred || e.held[k] != u.best.held[k]) alone = static_cast<int>(k), ++moved;
      // A profile's end (the others refitted there), else one moved alone.
      end_of.push_back(marked ? (static_cast<std::size_t>(e.of) < nh ? e.of : -1) : moved == 1 ? alone : -1);
    }
  } else {  // an ore written before the edge points were kept: each at its range's ends
    for (std::size_t k = 0; k < nh; ++k) {
      const HeldParameter& h = u.held[k];
      const OreParameter* p = find_ore_parameter(h.name);
      for (int side = 0; side < 2; ++side) {
        const double at = side ? h.hi : h.lo;
        const std::vector<double>& free_at = side ? h.free_at_hi : h.free_at_lo;
        if (at == h.value) continue;
        Ore o = free_at.size() == np ? with_variables(ore, u, free_at) : ore;
        p->set(o, at);
        ends.push_back(evaluate(f, o, n));
        end_of.push_back(static_cast<int>(k));
      }
    }
  }

  std::vector<Sensitivity> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    Sensitivity& s = out[i];
    s.value = v0[i];
    if (!std::isfinite(v0[i])) continue;
    // A number positive wherever it is evaluated is propagated as its
    // logarithm: its interval is then never below 0 (a feed rate, a P80),
    // and wider above than below where it grows faster than linearly.
    bool positive = v0[i] > 0, finite = true;
    for (const auto* set : {&diffs, &held_diffs})
      for (const Diff& d : *set) {
        positive = positive && d.a[i] > 0 && d.b[i] > 0;
        finite = finite && std::isfinite(d.a[i]) && std::isfinite(d.b[i]);
      }
    for (const auto& v : ends) positive = positive && (v[i] > 0 || v[i] == -kInf);
    positive = positive && at_best[i] > 0;
    if (!finite || !std::isfinite(at_best[i])) continue;
    s.log = positive;
    auto g_of = [&](double v) { return positive && std::isfinite(v) ? std::log(v) : v; };
    const double y0 = g_of(v0[i]);
    s.center = g_of(at_best[i]);
    auto slope = [&](const Diff& d) {
      if (d.sign == 0) return (g_of(d.a[i]) - g_of(d.b[i])) / (2 * d.h);
      return d.sign * (-3 * s.center + 4 * g_of(d.a[i]) - g_of(d.b[i])) / (2 * d.h);
    };
    for (const Diff& d : diffs) s.g.push_back(slope(d));
    for (const Diff& d : held_diffs) s.g_held.push_back(slope(d));
    bool ok = true;
    // The reach below and above the centre, over the held parameters'
    // points and where they are held.
    s.down = std::min(0.0, y0 - s.center);
    s.up = std::max(0.0, y0 - s.center);
    s.down_by_held.assign(nh, s.down);
    s.up_by_held.assign(nh, s.up);
    for (std::size_t e = 0; e < ends.size(); ++e) {
      const double v = ends[e][i];
      if (std::isnan(v)) ok = false;
      const double dy = g_of(v) - s.center;
      s.down = std::min(s.down, dy);
      s.up = std::max(s.up, dy);
      if (end_of[e] >= 0) {
        s.down_by_held[end_of[e]] = std::min(s.down_by_held[end_of[e]], dy);
        s.up_by_held[end_of[e]] = std::max(s.up_by_held[end_of[e]], dy);
      }
    }
    s.ok = ok;
  }
  return out;
}

Interval interval_of(const Sensitivity& s, const std::vector<std::vector<double>>& C, double q, double width_scale) {
  Interval out;
  if (!s.ok) return out;
  double var = 0;
  for (std::size_t a = 0; a < s.g.size(); ++a)
    for (std::size_t b = 0; b < s.g.size(); ++b) var += s.g[a] * C[a][b] * s.g[b];
  if (!std::isfinite(var)) return out;
  // The free parameters' half-width and the held ones' reach, in
  // quadrature: for a model linear in its parameters this is the profile
  // interval over all of them at the same limit (docs/grinding-intervals.md).
  const double half = q * std::sqrt(std::max(var, 0.0));
  const double below = std::hypot(half, width_scale * s.down), above = std::hypot(half, width_scale * s.up);
  out.lo = s.log ? std::exp(s.center - below) : s.center - below;
  out.hi = s.log ? std::exp(s.center + above) : s.center + above;
  if (s.down == -kInf) out.lo = -kInf;
  if (s.up == kInf) out.hi = kInf;
  return out;
}

std::vector<Interval> propagate(const Ore& ore, const FitCovariance& u,
                                const std::function<std::vector<double>(const Ore&)>& f, double width_scale) {
  const std::vector<Sensitivity> ss = sensitivities(ore, u, f);
  const double q = t_quantile(0.975, interval_dof(u)) * width_scale;
  const std::vector<std::vector<double>> C = interval_covariance(u);
  std::vector<Interval> out;
  for (const Sensitivity& s : ss) out.push_back(interval_of(s, C, q, width_scale));
  return out;
}

std::string stale_covariance(const Ore& ore, const FitCovariance& u) {
  auto differs = [](const OreParameter& p, double a, double b) {
    const double scale = p.log ? std::max(std::fabs(a), std::fabs(b)) : std::max(p.hi - p.lo, 1e-300);
    return std::fabs(a - b) > 1e-7 * scale;
  };
  for (std::size_t j = 0; j < u.names.size() && j < u.values.size(); ++j) {
    const OreParameter* p = find_ore_parameter(u.names[j]);
    const double now = p->get(ore), then = from_var(*p, u.values[j]);
    if (differs(*p, now, then))
      return fmt::format("{} = {:.6g}, the covariance is at {:.6g}", ore_file_key(u.names[j]), now, then);
  }
  for (const HeldParameter& h : u.held) {
    const OreParameter* p = find_ore_parameter(h.name);
    const double now = p->get(ore);
    if (differs(*p, now, h.value))
      return fmt::format("{} = {:.6g}, held at {:.6g} in the covariance", ore_file_key(h.name), now, h.value);
  }
  return "";
}

std::string outside_region(const FitCovariance& u) {
  if (u.held.empty() || !(u.ssr_limit > 0) || !(u.ssr_fit > u.ssr_limit)) return "";
  std::string held, best;
  for (std::size_t k = 0; k < u.held.size(); ++k) {
    held += fmt::format("{}{} {:.6g}", k ? ", " : "", u.held[k].name, u.held[k].value);
    if (k < u.best.held.size())
      best += fmt::format("{}{} {:.6g}", k ? ", " : "", u.held[k].name, u.best.held[k]);
  }
  return fmt::format("the ore's held values ({}) lie outside the data's 95 % region: S {:.4g} there against the "
                     "limit {:.4g} from where they fit best ({}, S {:.4g}); its numbers are not the data's best, and "
                     "the intervals are built around that best point",
                     held, u.ssr_fit, u.ssr_limit, best.empty() ? "not kept" : best, u.ssr_best);
}

std::vector<std::string> open_held(const FitCovariance& u) {
  std::vector<std::string> out;
  for (const HeldParameter& h : u.held) {
    const OreParameter* p = find_ore_parameter(h.name);
    const double span = p->hi - p->lo, tol = 1e-9 * span;
    if (h.value <= p->lo + tol || h.value >= p->hi - tol) continue;  // on its bound: said as such
    if (h.lo <= p->lo + tol || h.hi >= p->hi - tol)
      out.push_back(fmt::format("{} ({:.6g} to {:.6g})", h.name, h.lo, h.hi));
  }
  return out;
}

std::vector<Correlated> correlated_pairs(const FitCovariance& u, double limit) {
  std::vector<Correlated> out;
  for (std::size_t a = 0; a < u.names.size(); ++a)
    for (std::size_t b = a + 1; b < u.names.size(); ++b) {
      const double r = u.matrix[a][b] / std::sqrt(u.matrix[a][a] * u.matrix[b][b]);
      if (std::fabs(r) > limit) out.push_back({variable_name(u.names[a]), variable_name(u.names[b]), r});
    }
  return out;
}

}  // namespace mc::grind
