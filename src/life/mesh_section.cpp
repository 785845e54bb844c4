// Lifter bars of a mesh liner measured across (mesh_section.h).
#include "life/mesh_section.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "core/lifters.h"
#include "life/mesh_wear.h"

namespace mc::life {

double part_angle(const std::vector<Triangle>& triangles, const std::vector<int>& part) {
  std::vector<Triangle> tris;
  for (int t : part) tris.push_back(triangles[t]);
  double x = 0, y = 0;
  for (const Vec3& v : weld(tris).points) x += v.x, y += v.y;  // each vertex once
  return std::atan2(y, x);
}

std::vector<Vec2> bar_section(const std::vector<Triangle>& triangles, const std::vector<int>& part, double z,
                              double angle, double R) {
  std::vector<Triangle> tris;
  for (int t : part) tris.push_back(triangles[t]);
  const WeldedMesh w = weld(tris);
  // A vertex on the plane counts as above it: each edge that crosses is
  // one whose ends lie on either side, the same for both its triangles.
  auto above = [&](int i) { return w.points[i].z >= z; };
  using Edge = std::pair<int, int>;
  auto edge = [](int a, int b) { return a < b ? Edge{a, b} : Edge{b, a}; };
  std::map<Edge, std::vector<Edge>> next;  // each crossing edge to the crossing edges it shares a triangle with
  for (const auto& c : w.corners) {
    std::vector<Edge> cut;
    for (int k = 0; k < 3; ++k)
      if (above(c[k]) != above(c[(k + 1) % 3])) cut.push_back(edge(c[k], c[(k + 1) % 3]));
    if (cut.size() != 2) continue;
    next[cut[0]].push_back(cut[1]);
    next[cut[1]].push_back(cut[0]);
  }
  if (next.empty()) return {};
  // One loop, or one chain from an end (an open mesh).
  Edge start = next.begin()->first;
  for (const auto& [e, n] : next) {
    if (n.size() > 2) return {};
    if (n.size() == 1) start = e;
  }
  std::vector<Edge> path{start};
  Edge prev{-1, -1}, at = start;
  for (;;) {
    const std::vector<Edge>& n = next[at];
    const Edge* step = nullptr;
    for (const Edge& e : n)
      if (e != prev && !(path.size() > 1 && e == path[path.size() - 2])) step = &e;
    if (!step || *step == start) break;
    prev = at, at = *step;
    path.push_back(at);
    if (path.size() > next.size()) return {};
  }
  if (path.size() != next.size()) return {};  // more than one loop
  // The crossings in the bar's frame.
  const double c = std::cos(angle), s = std::sin(angle);
  std::vector<Vec2> loop;
  for (const Edge& e : path) {
    const Vec3 a = w.points[e.first], b = w.points[e.second];
    const double f = (z - a.z) / (b.z - a.z);
    const Vec3 p = a + (b - a) * f;
    loop.push_back({-s * p.x + c * p.y, R - (c * p.x + s * p.y)});
  }
  // A plane through a vertex crosses each edge below it at the vertex
  // itself: one point.
  {
    std::vector<Vec2> once;
    for (const Vec2& p : loop)
      if (once.empty() || std::hypot(p.x - once.back().x, p.y - once.back().y) > 1e-12) once.push_back(p);
    while (once.size() > 1 && std::hypot(once.front().x - once.back().x, once.front().y - once.back().y) <= 1e-12)
      once.pop_back();
    loop.swap(once);
  }
  double area2 = 0;
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const Vec2 a = loop[k], b = loop[(k + 1) % loop.size()];
    area2 += a.x * b.y - b.x * a.y;
  }
  if (area2 < 0) std::reverse(loop.begin(), loop.end());  // counter-clockwise: leading foot, top, trailing foot
  const auto lead = std::max_element(loop.begin(), loop.end(), [](Vec2 a, Vec2 b) { return a.x < b.x; });
  std::rotate(loop.begin(), lead, loop.end());
  const auto trail = std::min_element(loop.begin(), loop.end(), [](Vec2 a, Vec2 b) { return a.x < b.x; });
  loop.erase(trail + 1, loop.end());
  // The feet where the faces meet the shell's tangent (y = 0), as a
  // parametric bar's outline has them: each face's lowest edge carried
  // down. (On the shell itself the feet stand x²/2R above the tangent:
  // 9 mm at 92 mm from a 0.45 m shell's bar centre, where a face angle
  // read from a tenth of the height up would begin.)
  auto foot = [](Vec2 f, Vec2 up) {
    const double dy = up.y - f.y;
    if (!(f.y > 0) || !(dy > 1e-9)) return f;
    return Vec2{f.x - (up.x - f.x) * f.y / dy, 0.0};
  };
  if (loop.size() >= 3) {
    loop.front() = foot(loop[0], loop[1]);
    loop.back() = foot(loop[loop.size() - 1], loop[loop.size() - 2]);
  }
  return loop;
}

std::vector<Vec2> mean_outline(const std::vector<std::vector<Vec2>>& outlines, int samples) {
  std::vector<Vec2> mean(samples + 1, Vec2{0, 0});
  int n = 0;
  for (const std::vector<Vec2>& o : outlines) {
    if (o.size() < 2) continue;
    std::vector<double> at{0};  // length along the outline at each point
    for (std::size_t k = 1; k < o.size(); ++k) at.push_back(at.back() + std::hypot(o[k].x - o[k - 1].x, o[k].y - o[k - 1].y));
    if (!(at.back() > 0)) continue;
    std::size_t seg = 1;
    for (int j = 0; j <= samples; ++j) {
      const double s = at.back() * j / samples;
      while (seg + 1 < o.size() && at[seg] < s) ++seg;
      const double span = at[seg] - at[seg - 1], f = span > 0 ? std::clamp((s - at[seg - 1]) / span, 0.0, 1.0) : 0.0;
      mean[j].x += o[seg - 1].x + f * (o[seg].x - o[seg - 1].x);
      mean[j].y += o[seg - 1].y + f * (o[seg].y - o[seg - 1].y);
    }
    ++n;
  }
  if (n == 0) return {};
  for (Vec2& p : mean) p = {p.x / n, p.y / n};
  return mean;
}

std::vector<std::vector<Vec2>> bar_sections(const std::vector<Triangle>& triangles, const std::vector<double>& angles,
                                            double z, double R) {
  std::vector<std::vector<Vec2>> out;
  const std::vector<std::vector<int>> parts = connected_parts(triangles);
  for (std::size_t k = 0; k < parts.size() && k < angles.size(); ++k) {
    std::vector<Vec2> o = bar_section(triangles, parts[k], z, angles[k], R);
    if (o.size() < 3) continue;
    // A cut wider or higher than half the shell's radius is not a bar (a
    // liner welded into one surface, a shell plate): left out.
    double x0 = o[0].x, x1 = o[0].x, y1 = o[0].y;
    for (const Vec2& p : o) x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
    if (x1 - x0 > 0.5 * R || y1 > 0.5 * R) continue;
    out.push_back(std::move(o));
  }
  return out;
}

BarMeasures measure_bars(const std::vector<Triangle>& triangles, const std::vector<double>& angles, double z,
                         double R) {
  BarMeasures m;
  for (const std::vector<Vec2>& o : bar_sections(triangles, angles, z, R)) {
    const ProfileMeasures p = measure_profile(o);
    m.height.push_back(p.height);
    m.leading_deg.push_back(p.leading_angle_deg);
    m.trailing_deg.push_back(p.trailing_angle_deg);
  }
  return m;
}

}  // namespace mc::life
