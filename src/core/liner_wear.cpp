#include "core/liner_wear.h"

#include <algorithm>
#include <cmath>

namespace mc {

namespace {

// A piece of the exposed outline: its middle, outward normal and tangent
// (along the path), its length and where it lies on the path.
struct Sample {
  Vec2 p, n, t;  // mill frame of the bar at angle 0
  double len = 0, s = 0;
};

double cross(Vec2 o, Vec2 a, Vec2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

double polygon_area(const std::vector<Vec2>& p) {
  double a = 0;
  for (std::size_t k = 0; k < p.size(); ++k) {
    const Vec2 u = p[k], v = p[(k + 1) % p.size()];
    a += 0.5 * (u.x * v.y - v.x * u.y);
  }
  return a;
}

// The bar at angle 0 (its frame's x along the mill's y, its height along −x
// from the shell), and the path of its wear stations.
struct Bar {
  std::vector<Vec2> poly;
  WearPath path;
  std::vector<double> edge_from;  // s at the start of each edge of the path
};

Bar bar_of(const std::vector<Vec2>& outline, double R) {
  LifterProfile p;
  p.points = outline;
  Bar b;
  b.poly = lifter_polygon(R, p, 0.0);
  b.path = lifter_wear_path(b.poly, R);
  double s = 0;
  const std::size_t n = b.poly.size();
  for (std::size_t j = 0; j < n; ++j) {
    b.edge_from.push_back(s);
    const Vec2 a = b.poly[(b.path.start + j) % n], c = b.poly[(b.path.start + j + 1) % n];
    s += std::hypot(c.x - a.x, c.y - a.y);
  }
  b.edge_from.push_back(s);
  return b;
}

// The point of the path at length s (its middle for a piece there).
Vec2 at_length(const Bar& b, double s) {
  const std::size_t n = b.poly.size();
  std::size_t j = 0;
  while (j + 1 < n && b.edge_from[j + 1] <= s) ++j;
  const Vec2 a = b.poly[(b.path.start + j) % n], c = b.poly[(b.path.start + j + 1) % n];
  const double len = b.edge_from[j + 1] - b.edge_from[j];
  const double t = len > 0 ? std::clamp((s - b.edge_from[j]) / len, 0.0, 1.0) : 0.0;
  return {a.x + t * (c.x - a.x), a.y + t * (c.y - a.y)};
}

// The exposed outline cut into pieces of about `piece` (m), edge by edge.
std::vector<Sample> samples_of(const Bar& b, double piece) {
  std::vector<Sample> out;
  const std::size_t n = b.poly.size();
  for (std::size_t j = 0; j < n; ++j) {
    const double e0 = std::max(b.edge_from[j], b.path.from), e1 = std::min(b.edge_from[j + 1], b.path.to);
    if (!(e1 > e0)) continue;
    const Vec2 a = b.poly[(b.path.start + j) % n], c = b.poly[(b.path.start + j + 1) % n];
    const double l = std::hypot(c.x - a.x, c.y - a.y);
    const Vec2 t{(c.x - a.x) / l, (c.y - a.y) / l};
    const int k_max = std::max(1, static_cast<int>(std::ceil((e1 - e0) / piece)));
    for (int k = 0; k < k_max; ++k) {
      const double s = e0 + (e1 - e0) * (k + 0.5) / k_max;
      const double f = (s - b.edge_from[j]) / l;
      out.push_back({{a.x + f * (c.x - a.x), a.y + f * (c.y - a.y)}, {t.y, -t.x}, t, (e1 - e0) / k_max, s});
    }
  }
  return out;
}

// Convex hull, counter-clockwise, without collinear points (Andrew's chain).
std::vector<Vec2> hull_of(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(), [](Vec2 a, Vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  if (p.size() < 3) return p;
  std::vector<Vec2> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i - 1]) <= 0) --k;
    h[k++] = p[i - 1];
  }
  h.resize(k - 1);
  return h;
}

// The outline's area above the line y = level (its polygon closed along
// y = 0, clipped there).
double area_above(const std::vector<Vec2>& outline, double level) {
  std::vector<Vec2> clipped;
  const std::size_t n = outline.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2 a = outline[k], b = outline[(k + 1) % n];
    const bool ina = a.y >= level, inb = b.y >= level;
    if (ina) clipped.push_back(a);
    if (ina != inb) {
      const double t = (level - a.y) / (b.y - a.y);
      clipped.push_back({a.x + t * (b.x - a.x), level});
    }
  }
  return clipped.size() < 3 ? 0.0 : polygon_area(clipped);
}

struct Moved {
  std::vector<Vec2> outline;
  bool worn_away = false;
};

// The bar after each piece of its outline wore back by scale × its depth,
// in the frame of the worn shell (radius R + shell_depth): what is left is
// the bar less a strip under each piece (strips that overlap at a corner
// leave a notch); its convex hull is the worn bar, feet on the shell, thinned.
Moved move(const Bar& bar, const std::vector<Sample>& samples, const std::vector<double>& depth, double R,
           double shell_depth, double scale) {
  std::vector<Vec2> keep;
  auto in_a_strip = [&](Vec2 c) {
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const Sample& s = samples[i];
      const double d = scale * depth[i];
      if (!(d > 0)) continue;
      const double along = (c.x - s.p.x) * s.t.x + (c.y - s.p.y) * s.t.y;
      const double in = (s.p.x - c.x) * s.n.x + (s.p.y - c.y) * s.n.y;
      const double tol = 1e-9 * (s.len + d);
      if (std::fabs(along) < 0.5 * s.len - tol && in > -tol && in < d - tol) return true;
    }
    return false;
  };
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Sample& s = samples[i];
    const double d = scale * depth[i];
    for (double side : {-0.5, 0.5}) {
      const Vec2 c{s.p.x - d * s.n.x + side * s.len * s.t.x, s.p.y - d * s.n.y + side * s.len * s.t.y};
      if (polygon_signed_distance(bar.poly, c.x, c.y) <= 1e-9 * R && !in_a_strip(c)) keep.push_back(c);
    }
  }
  // The feet: the end pieces' worn lines carried on behind the worn shell,
  // to a quarter of the bar's height past its line (x = R + shell_depth in
  // this frame, where the hull is cut below): however far a foot lays back
  // and however deep the shell wore, the face meets the worn shell.
  if (!samples.empty()) {
    double u_min = R;
    for (const Vec2& v : bar.poly) u_min = std::min(u_min, v.x);
    const double beyond = R + shell_depth + 0.25 * (R - u_min);
    // A face that runs nearly along the shell (a flat top cut by the curved
    // shell, a ramp) is carried at most four times the bar's height and the
    // shell's depth, and from there straight down to the worn shell.
    const double cap = 4 * ((R - u_min) + shell_depth);
    auto foot = [&](const Sample& e, double d, double outward) {  // outward: −1 back along the path, +1 on
      const Vec2 start{e.p.x - d * e.n.x, e.p.y - d * e.n.y};
      const double dx = outward * e.t.x;  // how fast the line leaves the axis
      const double reach = dx > 0 ? (beyond - start.x) / dx : cap;
      const double r = std::max(std::min(reach, cap), 0.5 * e.len);
      const Vec2 end{start.x + outward * r * e.t.x, start.y + outward * r * e.t.y};
      keep.push_back(end);
      if (end.x < beyond) keep.push_back({beyond, end.y});
    };
    foot(samples.front(), scale * depth.front(), -1);
    foot(samples.back(), scale * depth.back(), +1);
  }
  Moved m;
  const std::vector<Vec2> hull = hull_of(keep);
  // Into the worn shell's frame, cut at its line (y = 0).
  const double R1 = R + shell_depth;
  std::vector<Vec2> h;
  for (const Vec2& v : hull) h.push_back({v.y, R1 - v.x});
  std::vector<Vec2> cut;
  for (std::size_t k = 0; k < h.size(); ++k) {
    const Vec2 a = h[k], b = h[(k + 1) % h.size()];
    if (a.y >= 0) cut.push_back(a);
    if ((a.y >= 0) != (b.y >= 0)) cut.push_back({a.x + (0 - a.y) / (b.y - a.y) * (b.x - a.x), 0.0});
  }
  if (cut.size() < 3) {
    m.worn_away = true;
    return m;
  }
  // From the leading foot (on the shell, the farthest ahead) round to the trailing one.
  std::size_t a = cut.size(), b = cut.size();
  for (std::size_t k = 0; k < cut.size(); ++k)
    if (cut[k].y == 0) {
      if (a == cut.size() || cut[k].x > cut[a].x) a = k;
      if (b == cut.size() || cut[k].x < cut[b].x) b = k;
    }
  if (a == cut.size() || a == b) {
    m.worn_away = true;
    return m;
  }
  std::vector<Vec2> o;
  for (std::size_t k = a;; k = (k + 1) % cut.size()) {
    o.push_back(cut[k]);
    if (k == b || o.size() > cut.size()) break;
  }
  // Thin: drop the corner that carries the least area while there are too
  // many or it carries almost none (a convex outline stays convex).
  const double total = std::max(polygon_area(o), 1e-300);
  while (o.size() > 3) {
    std::size_t best = 0;
    double least = 1e300;
    for (std::size_t k = 1; k + 1 < o.size(); ++k) {
      const double t = std::fabs(cross(o[k - 1], o[k], o[k + 1]));
      if (t < least) least = t, best = k;
    }
    if (static_cast<int>(o.size()) <= kLifterMaxPoints && 0.5 * least > 2e-4 * total) break;
    o.erase(o.begin() + static_cast<std::ptrdiff_t>(best));
  }
  double h_max = 0;
  for (const Vec2& v : o) h_max = std::max(h_max, v.y);
  m.worn_away = o.size() < 3 || h_max < kWornAwayHeight || !(o.front().x > o.back().x);
  m.outline = o;
  return m;
}

// The outline with its exposed faces moved into the bar by `delta` (m; <0:
// out of it), feet kept on the shell line (y = 0). Empty where a face
// would vanish or the result is not a valid outline.
std::vector<Vec2> offset_faces(const std::vector<Vec2>& o, double delta) {
  const std::size_t n = o.size();
  if (n < 3) return {};
  // Edge k runs from o[k] to o[k+1]; the outline runs counter-clockwise
  // (leading foot over the top to the trailing one), so inward is its left.
  struct Line {
    Vec2 p, t;
  };
  std::vector<Line> lines;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double l = std::hypot(o[k + 1].x - o[k].x, o[k + 1].y - o[k].y);
    if (!(l > 0)) return {};
    const Vec2 t{(o[k + 1].x - o[k].x) / l, (o[k + 1].y - o[k].y) / l};
    lines.push_back({{o[k].x - delta * t.y, o[k].y + delta * t.x}, t});
  }
  auto meet = [](const Line& a, const Line& b, Vec2& out) {
    const double den = a.t.x * b.t.y - a.t.y * b.t.x;
    if (std::fabs(den) < 1e-12) return false;
    const double s = ((b.p.x - a.p.x) * b.t.y - (b.p.y - a.p.y) * b.t.x) / den;
    out = {a.p.x + s * a.t.x, a.p.y + s * a.t.y};
    return true;
  };
  std::vector<Vec2> r(n);
  const Line shell{{0, 0}, {1, 0}};
  if (!meet(shell, lines.front(), r.front()) || !meet(lines.back(), shell, r.back())) return {};
  for (std::size_t k = 1; k + 1 < n; ++k)
    if (!meet(lines[k - 1], lines[k], r[k])) return {};
  // Each face keeps its direction (none turned over).
  for (std::size_t k = 0; k + 1 < n; ++k)
    if ((r[k + 1].x - r[k].x) * lines[k].t.x + (r[k + 1].y - r[k].y) * lines[k].t.y <= 0) return {};
  return r;
}

}  // namespace

WornLifter wear_lifter(const std::vector<Vec2>& outline, double R, const std::vector<double>& station_area,
                       double shell_depth) {
  const Bar bar = bar_of(outline, R);
  const double span = bar.path.to - bar.path.from, ds = span / kWearStations;
  const std::vector<Sample> samples = samples_of(bar, ds / 6);
  // Depth per station, smoothed over its neighbours (1 2 1, mirrored at the
  // ends: the volume stays), then at each sample between station centres.
  std::vector<double> d(kWearStations, 0.0);
  WornLifter w;
  for (int j = 0; j < kWearStations && j < static_cast<int>(station_area.size()); ++j) {
    d[j] = station_area[j] / ds;
    w.booked_area += station_area[j];
  }
  const double before = measure_profile(outline).area;
  auto removed = [&](const Moved& m) { return m.worn_away ? before : before - area_above(m.outline, shell_depth); };
  const double target = w.booked_area;
  Moved m;
  // A convex bar cannot take a deep notch: where wear gathers on a corner
  // the booked area comes off as a chamfer that reaches past the worn
  // stations. So: the depths smoothed (1 2 1, mirrored at the ends: the
  // volume stays) once, and then ever wider until a scale of at most
  // kMaxScale on them removes the booked area.
  constexpr double kMaxScale = 2;
  // Depths at the samples from station depths (interpolated between the
  // stations' centres).
  auto at_samples = [&](const std::vector<double>& st) {
    std::vector<double> depth;
    for (const Sample& s : samples) {
      const double u = (s.s - bar.path.from) / ds - 0.5;  // in station centres
      const int j0 = std::clamp(static_cast<int>(std::floor(u)), 0, kWearStations - 1);
      const int j1 = std::min(j0 + 1, kWearStations - 1);
      const double f = std::clamp(u - j0, 0.0, 1.0);
      depth.push_back(u <= 0 ? st[0] : (1 - f) * st[j0] + f * st[j1]);
    }
    return depth;
  };
  auto smooth = [&](std::vector<double> st, int passes) {
    for (int p = 0; p < passes; ++p) {
      std::vector<double> next(kWearStations);
      for (int j = 0; j < kWearStations; ++j)
        next[j] = 0.25 * st[std::max(j - 1, 0)] + 0.5 * st[j] + 0.25 * st[std::min(j + 1, kWearStations - 1)];
      st = next;
    }
    return st;
  };
  auto short_of = [&](const Moved& t) { return !t.worn_away && removed(t) < target; };
  // The fewest passes (1, 2, 4, ...) after which a scale of at most
  // kMaxScale removes the booked area; between that and half as many the
  // depths are blended, by the least share of the wider that does, so that
  // the worn shape moves on smoothly with the wear and never jumps as the
  // smoothing widens.
  std::vector<double> depth = at_samples(smooth(d, 1));
  w.spread = 1;
  if (target > 0 && short_of(move(bar, samples, depth, R, shell_depth, kMaxScale))) {
    std::vector<double> narrow = depth, wide;
    int passes = 2;
    for (; passes <= 256; passes *= 2) {
      wide = at_samples(smooth(d, passes));
      if (!short_of(move(bar, samples, wide, R, shell_depth, kMaxScale))) break;
      narrow = wide;
    }
    if (passes > 256) {
      depth = wide;
      w.spread = 256;
    } else {
      auto blend = [&](double f) {
        std::vector<double> x(narrow.size());
        for (std::size_t i = 0; i < x.size(); ++i) x[i] = (1 - f) * narrow[i] + f * wide[i];
        return x;
      };
      double lo = 0, hi = 1;
      for (int it = 0; it < 30; ++it) {
        const double mid = 0.5 * (lo + hi);
        (short_of(move(bar, samples, blend(mid), R, shell_depth, kMaxScale)) ? lo : hi) = mid;
      }
      depth = blend(hi);
      w.spread = passes;
    }
  }
  m = move(bar, samples, depth, R, shell_depth, target > 0 ? 1.0 : 0.0);
  w.scale = target > 0 ? 1.0 : 0.0;
  if (target > 0) {
    // The scale that removes the booked area: bracket it, then bisect.
    double lo = 0, hi = 1;
    while (short_of(m) && hi < kMaxScale) {
      lo = hi;
      hi = std::min(2 * hi, kMaxScale);
      m = move(bar, samples, depth, R, shell_depth, hi);
    }
    for (int it = 0; it < 60 && hi - lo > 1e-7 * hi; ++it) {
      const double mid = 0.5 * (lo + hi);
      (short_of(move(bar, samples, depth, R, shell_depth, mid)) ? lo : hi) = mid;
    }
    const Moved at_lo = move(bar, samples, depth, R, shell_depth, lo),
                at_hi = move(bar, samples, depth, R, shell_depth, hi);
    const bool take_hi = !at_hi.worn_away && std::fabs(removed(at_hi) - target) <= std::fabs(removed(at_lo) - target);
    w.scale = take_hi || at_lo.outline.empty() ? hi : lo;
    m = take_hi || at_lo.outline.empty() ? at_hi : at_lo;
    if (at_hi.worn_away && removed(at_lo) < 0.99 * target) m.worn_away = true;  // the stage wears it away
  }
  // The hull and the thinning make the removed area a step function of the
  // scale: the last step's residue comes off (or goes back) as a uniform
  // depth over the exposed faces, a fraction of a millimetre (secant).
  if (!m.worn_away && target > 0 && std::fabs(removed(m) - target) > 1e-6 * target) {
    double d0 = 0, r0 = removed(m) - target, d1 = -r0 / std::max(bar.path.to - bar.path.from, 1e-9), r1 = r0;
    std::vector<Vec2> best;
    for (int it = 0; it < 8; ++it) {
      const std::vector<Vec2> o = offset_faces(m.outline, d1);
      if (o.empty()) break;
      Moved t;
      t.outline = o;
      r1 = removed(t) - target;
      best = o;
      if (std::fabs(r1) <= 1e-6 * target || r1 == r0) break;
      const double d2 = d1 - r1 * (d1 - d0) / (r1 - r0);
      d0 = d1, r0 = r1, d1 = d2;
    }
    double h_max = 0;
    for (const Vec2& v : best) h_max = std::max(h_max, v.y);
    if (!best.empty() && std::fabs(r1) < std::fabs(removed(m) - target) &&
        profile_outline_fault(best, R + shell_depth, 0.0).empty() && h_max >= kWornAwayHeight)
      m.outline = best;
  }
  w.outline = m.outline;
  w.worn_away = m.worn_away;
  w.removed_area = removed(m);
  return w;
}

std::vector<StationPlace> station_places(const std::vector<Vec2>& outline, double R) {
  const Bar bar = bar_of(outline, R);
  const double ds = (bar.path.to - bar.path.from) / kWearStations;
  std::vector<StationPlace> out;
  for (int j = 0; j < kWearStations; ++j) {
    const Vec2 p = at_length(bar, bar.path.from + (j + 0.5) * ds);
    out.push_back({{p.y, R - p.x}, ds});
  }
  return out;
}

WornLifter wear_for_hours(const std::vector<Vec2>& outline, double R, const BarWearRates& rates, double hours) {
  std::vector<double> area(kWearStations, 0.0);
  for (int j = 0; j < kWearStations && j < static_cast<int>(rates.station_m3_s.size()); ++j)
    area[j] = rates.station_m3_s[j] * hours * 3600 / rates.length;
  return wear_lifter(outline, R, area, rates.shell_m_per_h * hours);
}

double top_wear_m_per_h(const std::vector<Vec2>& outline, double R, const BarWearRates& rates) {
  const std::vector<StationPlace> places = station_places(outline, R);
  const double h = measure_profile(outline).height;
  double sum = 0, best_y = -1, at_best = 0;
  int n = 0;
  for (int j = 0; j < kWearStations && j < static_cast<int>(rates.station_m3_s.size()); ++j) {
    const double rate =
        places[j].length > 0 ? rates.station_m3_s[j] * 3600 / (places[j].length * rates.length) : 0.0;
    if (places[j].centre.y >= 0.9 * h) sum += rate, ++n;
    if (places[j].centre.y > best_y) best_y = places[j].centre.y, at_best = rate;
  }
  return n > 0 ? sum / n : at_best;
}

double hours_to_lose(const std::vector<Vec2>& outline, double R, const BarWearRates& rates, double loss) {
  const double h0 = measure_profile(outline).height;
  const double top = top_wear_m_per_h(outline, R, rates);  // where the search starts
  if (!(top > 0) || !(loss > 0)) return -1;
  auto lost = [&](double hours) {
    const WornLifter w = wear_for_hours(outline, R, rates, hours);
    return w.worn_away ? h0 : h0 - measure_profile(w.outline).height;
  };
  // The first hours (on a doubling scan from the top's own rate) at which
  // the bar is down by `loss`, then bisection between the last scan point
  // short of it and the first past it. A shell that wears faster than the
  // top raises the bar at first; its height may then fall in a step (a
  // thin ridge going). A bar that would be worn through there never lost
  // `loss` while it stood: no hours.
  double lo = 0, hi = loss / top;
  for (int it = 0; it < 40 && lost(hi) < loss; ++it) {
    lo = hi;
    hi *= 2;
  }
  if (lost(hi) < loss) return -1;
  for (int it = 0; it < 80 && hi - lo > 1e-9 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (lost(mid) < loss ? lo : hi) = mid;
  }
  if (wear_for_hours(outline, R, rates, hi).worn_away) return -1;
  return hi;
}

}  // namespace mc
