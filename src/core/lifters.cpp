#include "core/lifters.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mc {

std::vector<Vec2> lifter_polygon(double shell_radius, const LifterProfile& p, double angle) {
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

std::vector<Triangle> lifter_triangles(const std::vector<std::vector<Vec2>>& bars, double length) {
  std::vector<Triangle> out;
  for (const auto& poly : bars) {
    const std::size_t n = poly.size();
    auto at = [&](std::size_t k, double z) { return Vec3{poly[k % n].x, poly[k % n].y, z}; };
    for (std::size_t k = 0; k < n; ++k) {  // counter-clockwise polygon: (dy, -dx) points out
      out.push_back({{at(k, 0), at(k + 1, 0), at(k + 1, length)}});
      out.push_back({{at(k, 0), at(k + 1, length), at(k, length)}});
    }
    for (std::size_t k = 1; k + 1 < n; ++k) {
      out.push_back({{at(0, 0), at(k + 1, 0), at(k, 0)}});                 // z = 0, facing -z
      out.push_back({{at(0, length), at(k, length), at(k + 1, length)}});  // z = length, facing +z
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
