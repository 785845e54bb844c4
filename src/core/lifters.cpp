#include "core/lifters.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace mc {

namespace {

double cross(Vec2 a, Vec2 b, Vec2 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

// A foot of an outline carried down its edge (from `inner`, the next point
// in) to height y_base behind the shell; straight down where the edge lies
// flat on the shell.
Vec2 foot_behind_shell(Vec2 foot, Vec2 inner, double y_base) {
  const double rise = inner.y - foot.y;
  if (!(rise > 1e-12 * (std::fabs(inner.x - foot.x) + rise))) return {foot.x, y_base};
  return {inner.x + (foot.x - inner.x) * (inner.y - y_base) / rise, y_base};
}

// The x of an outline's side (points from a foot up to the top) at height y.
double side_x_at(const std::vector<Vec2>& side, double y) {
  for (std::size_t k = 0; k + 1 < side.size(); ++k) {
    const Vec2 a = side[k], b = side[k + 1];
    if ((a.y - y) * (b.y - y) <= 0 && a.y != b.y) return a.x + (b.x - a.x) * (y - a.y) / (b.y - a.y);
  }
  return side.empty() ? 0.0 : side.back().x;
}

}  // namespace

std::vector<Vec2> profile_outline(const LifterProfile& p) {
  if (p.polygon()) {
    std::vector<Vec2> o = p.points;
    if (o.front().x < o.back().x) std::reverse(o.begin(), o.end());  // from the leading foot
    return o;
  }
  const double half_top = 0.5 * p.top_width;
  const double half_base = half_top + p.height * std::tan(p.face_angle_deg * M_PI / 180.0);
  return {{half_base, 0}, {half_top, p.height}, {-half_top, p.height}, {-half_base, 0}};
}

std::string profile_outline_fault(const std::vector<Vec2>& o, double R, double room) {
  auto mm = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", v * 1000);
    return std::string(b);
  };
  auto at = [&](std::size_t k) { return "point " + std::to_string(k) + " (" + mm(o[k].x) + ", " + mm(o[k].y) + " mm)"; };
  const std::size_t n = o.size();
  if (n < 3) return std::to_string(n) + " points: a profile needs at least 3 (two feet on the shell and a top)";
  double h = 0;
  for (const Vec2& v : o) h = std::max(h, v.y);
  const double tol = 1e-9 + 1e-9 * h;
  if (std::fabs(o.front().y) > tol || std::fabs(o.back().y) > tol)
    return "the first and last points are the feet and lie on the shell (y = 0); " +
           at(std::fabs(o.front().y) > tol ? 0 : n - 1) + " does not";
  for (std::size_t k = 1; k + 1 < n; ++k) {
    if (o[k].y < 0) return at(k) + " reaches outside the shell (y < 0)";
    if (!(o[k].y > tol)) return at(k) + " lies on the shell: only the feet may";
  }
  if (!(h < R - room)) {
    char b[160];
    std::snprintf(b, sizeof b, "the profile is %.4g m high and reaches the axis or leaves no room for a ball (shell "
                  "radius %.4g m)", h, R);
    std::string msg = b;
    // Higher than the radius, yet a fit in millimetres: a unit slip.
    if (h > R && h / 1000 < R - room) msg += "; are the points in millimetres? give units = \"mm\"";
    return msg;
  }
  for (std::size_t k = 0; k < n; ++k)
    if (std::hypot(o[k].x, o[k].y) > R) return at(k) + " lies farther from the bar's centre than the shell's radius";
  for (std::size_t k = 0; k + 1 < n; ++k)
    if (std::hypot(o[k + 1].x - o[k].x, o[k + 1].y - o[k].y) <= tol) return at(k) + " and the next coincide";
  if (!(o.front().x - o.back().x > tol)) return "the feet coincide";
  // Closed by the shell from the trailing foot to the leading one, the outline
  // must turn left at every point, once round: convex and not crossing itself.
  double turned = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2 prev = o[(k + n - 1) % n], cur = o[k], next = o[(k + 1) % n];
    const double c = cross(prev, cur, next);
    const double scale = std::hypot(cur.x - prev.x, cur.y - prev.y) * std::hypot(next.x - cur.x, next.y - cur.y);
    if (c < -1e-9 * scale)
      return at(k) + " makes the outline non-convex (or crossing itself): the contact needs a convex bar; give its "
                     "convex hull, or split it into convex bars";
    turned += std::atan2(c, (cur.x - prev.x) * (next.x - cur.x) + (cur.y - prev.y) * (next.y - cur.y));
  }
  if (std::fabs(turned - 2 * M_PI) > 1e-6) return "the outline crosses itself (it winds more than once)";
  double area = 0;
  for (std::size_t k = 0; k < n; ++k) area += 0.5 * (o[k].x * o[(k + 1) % n].y - o[(k + 1) % n].x * o[k].y);
  if (!(std::fabs(area) > 1e-6 * h * h))
    return "the outline encloses no area to speak of (as much as a square " + mm(std::sqrt(std::fabs(area))) +
           " mm on a side): a needle or a line, not a bar";
  return "";
}

ProfileMeasures measure_profile(const std::vector<Vec2>& o) {
  ProfileMeasures m;
  if (o.size() < 2) return m;
  std::size_t top = 0;
  for (std::size_t k = 0; k < o.size(); ++k) {
    if (o[k].y > o[top].y) top = k;
    const Vec2 a = o[k], b = o[(k + 1) % o.size()];
    m.area += 0.5 * (a.x * b.y - b.x * a.y);
  }
  m.height = o[top].y;
  const std::vector<Vec2> lead(o.begin(), o.begin() + top + 1);           // foot up to the top
  const std::vector<Vec2> trail(o.rbegin(), o.rend() - top);               // foot up to the top
  const double y0 = 0.1 * m.height, y1 = 0.9 * m.height;
  m.leading_angle_deg = std::atan2(side_x_at(lead, y0) - side_x_at(lead, y1), y1 - y0) * 180 / M_PI;
  m.trailing_angle_deg = std::atan2(side_x_at(trail, y1) - side_x_at(trail, y0), y1 - y0) * 180 / M_PI;
  for (std::size_t k = 0; k + 1 < o.size(); ++k) {
    const Vec2 a = o[k], b = o[k + 1];
    if (std::min(a.y, b.y) >= 0.5 * m.height && std::fabs(b.y - a.y) <= std::fabs(b.x - a.x))
      m.top_width += std::fabs(b.x - a.x);
  }
  return m;
}

WearPath lifter_wear_path(const std::vector<Vec2>& poly, double R) {
  WearPath w;
  const std::size_t n = poly.size();
  if (n < 2) return w;
  auto out = [&](std::size_t k) { return std::hypot(poly[k % n].x, poly[k % n].y) > R; };
  auto crossing = [&](Vec2 a, Vec2 b) {  // t in [0, 1] of |a + t(b − a)| = R
    const double ex = b.x - a.x, ey = b.y - a.y;
    const double qa = ex * ex + ey * ey, qb = 2 * (a.x * ex + a.y * ey), qc = a.x * a.x + a.y * a.y - R * R;
    const double disc = std::max(0.0, qb * qb - 4 * qa * qc);
    double t = (-qb + std::sqrt(disc)) / (2 * qa);
    if (t < 0 || t > 1) t = (-qb - std::sqrt(disc)) / (2 * qa);
    return std::clamp(t, 0.0, 1.0);
  };
  std::size_t start = n;
  for (std::size_t k = 0; k < n && start == n; ++k)
    if (out(k) && !out(k + 1)) start = k;
  double along = 0;
  if (start == n) {  // wholly inside the shell: the whole perimeter
    for (std::size_t k = 0; k < n; ++k) along += std::hypot(poly[(k + 1) % n].x - poly[k].x, poly[(k + 1) % n].y - poly[k].y);
    w.to = along;
    return w;
  }
  w.start = static_cast<int>(start);
  for (std::size_t j = 0; j < n; ++j) {
    const Vec2 a = poly[(start + j) % n], b = poly[(start + j + 1) % n];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    if (j == 0) w.from = crossing(a, b) * len;
    if (j > 0 && !out(start + j) && out(start + j + 1)) {
      w.to = along + crossing(a, b) * len;
      break;
    }
    along += len;
  }
  return w;
}

FaceSplit lifter_face_split(const std::vector<Vec2>& poly, double R, Vec2 centre) {
  FaceSplit f;
  const WearPath path = lifter_wear_path(poly, R);
  f.from = path.from;
  f.to = path.to;
  f.top_from = f.top_to = 0.5 * (path.from + path.to);
  const std::size_t n = poly.size();
  if (n < 2) return f;
  // The exposed outline's edges in path order, each with its ends' length
  // along the path, height above the shell and place along its tangent.
  struct Piece {
    double s0, s1, y0, y1, x0, x1;
  };
  const Vec2 ahead{-centre.y, centre.x};
  auto height = [&](Vec2 p) { return R - (p.x * centre.x + p.y * centre.y); };
  auto across = [&](Vec2 p) { return p.x * ahead.x + p.y * ahead.y; };
  std::vector<Piece> pieces;
  double along = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const Vec2 a = poly[(path.start + j) % n], b = poly[(path.start + j + 1) % n];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    const double s0 = std::max(along, path.from), s1 = std::min(along + len, path.to);
    if (len > 0 && s1 > s0) {
      auto at = [&](double s) {
        const double t = (s - along) / len;
        return Vec2{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
      };
      const Vec2 p0 = at(s0), p1 = at(s1);
      pieces.push_back({s0, s1, height(p0), height(p1), across(p0), across(p1)});
    }
    along += len;
  }
  if (pieces.empty()) return f;
  double h = 0;
  for (const Piece& q : pieces) h = std::max({h, q.y0, q.y1});
  if (!(h > 0)) return f;
  const double tol = 1e-9 * h;
  auto flat_top = [&](const Piece& q) {
    return std::min(q.y0, q.y1) >= 0.5 * h - tol && std::fabs(q.y1 - q.y0) <= std::fabs(q.x1 - q.x0);
  };
  // The run of flat edges above half the height that holds the summit.
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    if (!(std::max(pieces[i].y0, pieces[i].y1) >= h - tol && flat_top(pieces[i]))) continue;
    std::size_t lo = i, hi = i;
    while (lo > 0 && flat_top(pieces[lo - 1])) --lo;
    while (hi + 1 < pieces.size() && flat_top(pieces[hi + 1])) ++hi;
    f.top_from = pieces[lo].s0;
    f.top_to = pieces[hi].s1;
    return f;
  }
  // A pointed bar: its top is where it stands above 90 % of its height (one
  // stretch round the summit, the outline being convex).
  const double level = 0.9 * h;
  double lo = path.to, hi = path.from;
  for (const Piece& q : pieces) {
    auto take = [&](double s) {
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    };
    if (q.y0 >= level) take(q.s0);
    if (q.y1 >= level) take(q.s1);
    if ((q.y0 - level) * (q.y1 - level) < 0) take(q.s0 + (q.s1 - q.s0) * (level - q.y0) / (q.y1 - q.y0));
  }
  if (lo < hi) {
    f.top_from = lo;
    f.top_to = hi;
  }
  return f;
}

std::vector<Vec2> lifter_polygon(double shell_radius, const LifterProfile& p, double angle) {
  if (p.polygon()) {
    // The outline E from the leading foot to the trailing foot, its feet
    // carried down their edges a quarter of its height behind the shell,
    // in the trapezoid's vertex order: E[m−2], trailing base, leading base,
    // E[1] .. E[m−3].
    const std::vector<Vec2> e = profile_outline(p);
    const std::size_t m = e.size();
    if (m < 3) throw std::invalid_argument("a lifter profile needs at least 3 points");
    double h = 0;
    for (const Vec2& v : e) h = std::max(h, v.y);
    const double y_base = -0.25 * h;
    std::vector<Vec2> local{e[m - 2], foot_behind_shell(e[m - 1], e[m - 2], y_base),
                            foot_behind_shell(e[0], e[1], y_base)};
    for (std::size_t k = 1; k + 2 < m; ++k) local.push_back(e[k]);
    if (local.size() > static_cast<std::size_t>(kLifterMaxPoints))
      throw std::invalid_argument("a lifter profile has at most " + std::to_string(kLifterMaxPoints) + " points");
    const double c = std::cos(angle), s = std::sin(angle);
    std::vector<Vec2> out;
    for (const Vec2& v : local) {
      const double u = shell_radius - v.y, t = v.x;
      out.push_back({u * c - t * s, u * s + t * c});
    }
    return out;
  }
  if (!(p.height > 0 && p.height < shell_radius))
    throw std::invalid_argument("lifter height must be in (0, shell radius)");
  if (!(p.top_width > 0)) throw std::invalid_argument("lifter top_width must be > 0");
  if (!(p.face_angle_deg >= 0 && p.face_angle_deg < 60))
    throw std::invalid_argument("lifter face_angle must be in [0, 60) degrees");
  const double tan_face = std::tan(p.face_angle_deg * M_PI / 180.0);
  const double r_top = shell_radius - p.height;
  const double r_base = shell_radius + 0.25 * p.height;  // behind the shell
  const double half_top = 0.5 * p.top_width;
  const double half_base = half_top + (r_base - r_top) * tan_face;
  const double c = std::cos(angle), s = std::sin(angle);
  auto at = [&](double u, double t) { return Vec2{u * c - t * s, u * s + t * c}; };
  return {at(r_top, -half_top), at(r_base, -half_base), at(r_base, half_base), at(r_top, half_top)};
}

std::vector<std::vector<Vec2>> lifter_rows(double shell_radius, int rows,
                                           const std::vector<LifterProfile>& pattern,
                                           double first) {
  std::vector<std::vector<Vec2>> out;
  if (rows <= 0 || pattern.empty()) return out;
  for (int k = 0; k < rows; ++k)
    out.push_back(lifter_polygon(shell_radius, pattern[k % pattern.size()],
                                 first + 2.0 * M_PI * k / rows));
  return out;
}

std::vector<Triangle> lifter_triangles(const std::vector<std::vector<Vec2>>& bars, double length, double max_edge) {
  std::vector<Triangle> out;
  const int nz = max_edge > 0 ? std::max(1, static_cast<int>(std::ceil(length / max_edge - 1e-9))) : 1;
  for (const auto& poly : bars) {
    const std::size_t n = poly.size();
    // The outline with each edge cut into pieces of at most max_edge.
    std::vector<Vec2> ring;
    for (std::size_t k = 0; k < n; ++k) {
      const Vec2 a = poly[k], b = poly[(k + 1) % n];
      const double len = std::hypot(b.x - a.x, b.y - a.y);
      const int na = max_edge > 0 ? std::max(1, static_cast<int>(std::ceil(len / max_edge - 1e-9))) : 1;
      for (int i = 0; i < na; ++i) {
        const double f = static_cast<double>(i) / na;
        ring.push_back({a.x + f * (b.x - a.x), a.y + f * (b.y - a.y)});
      }
    }
    const std::size_t m = ring.size();
    auto at = [&](std::size_t k, int j) {
      return Vec3{ring[k % m].x, ring[k % m].y, j == nz ? length : length * j / nz};
    };
    for (std::size_t k = 0; k < m; ++k)  // counter-clockwise polygon: (dy, -dx) points out
      for (int j = 0; j < nz; ++j) {
        out.push_back({{at(k, j), at(k + 1, j), at(k + 1, j + 1)}});
        out.push_back({{at(k, j), at(k + 1, j + 1), at(k, j + 1)}});
      }
    if (m == n) {  // the ends as fans from the first vertex
      for (std::size_t k = 1; k + 1 < n; ++k) {
        out.push_back({{at(0, 0), at(k + 1, 0), at(k, 0)}});     // z = 0, facing -z
        out.push_back({{at(0, nz), at(k, nz), at(k + 1, nz)}});  // z = length, facing +z
      }
    } else {  // fans from the centroid, through every point of the cut edges
      Vec2 c{0, 0};
      for (const Vec2& v : poly) c = {c.x + v.x / n, c.y + v.y / n};
      const Vec3 c0{c.x, c.y, 0}, c1{c.x, c.y, length};
      for (std::size_t k = 0; k < m; ++k) {
        out.push_back({{c0, at(k + 1, 0), at(k, 0)}});
        out.push_back({{c1, at(k, nz), at(k + 1, nz)}});
      }
    }
  }
  return out;
}

std::vector<std::vector<Vec2>> bars_on_shell(const std::vector<std::vector<Vec2>>& bars, double R) {
  std::vector<std::vector<Vec2>> out;
  auto inside = [&](Vec2 v) { return std::hypot(v.x, v.y) <= R; };
  auto crossing = [&](Vec2 a, Vec2 b) {  // |a + t(b − a)| = R, t in [0, 1]
    const double ex = b.x - a.x, ey = b.y - a.y;
    const double qa = ex * ex + ey * ey, qb = 2 * (a.x * ex + a.y * ey), qc = a.x * a.x + a.y * a.y - R * R;
    const double disc = std::max(0.0, qb * qb - 4 * qa * qc);
    double t = (-qb + std::sqrt(disc)) / (2 * qa);
    if (t < 0 || t > 1) t = (-qb - std::sqrt(disc)) / (2 * qa);
    t = std::clamp(t, 0.0, 1.0);
    return Vec2{a.x + t * ex, a.y + t * ey};
  };
  for (const auto& poly : bars) {
    std::vector<Vec2> clipped;
    const std::size_t n = poly.size();
    for (std::size_t k = 0; k < n; ++k) {
      const Vec2 a = poly[k], b = poly[(k + 1) % n];
      if (inside(a)) clipped.push_back(a);
      if (inside(a) != inside(b)) clipped.push_back(crossing(a, b));
    }
    out.push_back(clipped);
  }
  return out;
}

bool convex_polygons_overlap(const std::vector<Vec2>& a, const std::vector<Vec2>& b, double tol) {
  // Separating axes: the edges' normals of both; apart when one separates
  // them by more than -tol (touching within tol is not overlapping).
  for (const auto* poly : {&a, &b}) {
    const std::size_t n = poly->size();
    for (std::size_t k = 0; k < n; ++k) {
      const Vec2 p = (*poly)[k], q = (*poly)[(k + 1) % n];
      const double nx = q.y - p.y, ny = p.x - q.x, len = std::hypot(nx, ny);
      if (!(len > 0)) continue;
      double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
      for (const Vec2& v : a) {
        const double d = (v.x * nx + v.y * ny) / len;
        amin = std::min(amin, d);
        amax = std::max(amax, d);
      }
      for (const Vec2& v : b) {
        const double d = (v.x * nx + v.y * ny) / len;
        bmin = std::min(bmin, d);
        bmax = std::max(bmax, d);
      }
      if (amax <= bmin + tol || bmax <= amin + tol) return false;
    }
  }
  return true;
}

double polygon_signed_distance(const std::vector<Vec2>& poly, double x, double y) {
  bool inside = true;
  double best = 1e300;
  const std::size_t n = poly.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2 a = poly[k], b = poly[(k + 1) % n];
    const double ex = b.x - a.x, ey = b.y - a.y;
    if ((x - a.x) * ey - (y - a.y) * ex > 0) inside = false;  // outside this edge (CCW)
    const double t = std::clamp(((x - a.x) * ex + (y - a.y) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
    best = std::min(best, std::hypot(x - (a.x + t * ex), y - (a.y + t * ey)));
  }
  return inside ? -best : best;
}

}  // namespace mc
