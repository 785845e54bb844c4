// Short edges of a worn mesh collapsed before its next move (mesh_collapse.h).
#include "life/mesh_collapse.h"

#include <algorithm>
#include <iterator>
#include <cmath>
#include <set>
#include <stdexcept>
#include <utility>

#include "life/mesh_wear.h"

namespace mc::life {

namespace {

Vec3 cross3(const Vec3& a, const Vec3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

// A collapse may turn a neighbour's normal by at most this.
constexpr double kFoldDegrees = 60.0;
constexpr int kPasses = 8;

}  // namespace

Collapsed collapse_short_edges(const std::vector<Triangle>& triangles, const std::vector<double>& volume_m3, double z0,
                               double z1, double share) {
  if (volume_m3.size() != triangles.size())
    throw std::invalid_argument("collapse_short_edges: a volume per triangle is needed");
  WeldedMesh w = weld(triangles);
  std::vector<std::array<int, 3>>& tri = w.corners;
  std::vector<Vec3>& p = w.points;
  const std::size_t nt = tri.size();
  std::vector<char> alive(nt, 1);
  std::vector<double> volume = volume_m3;
  auto on_end = [&](int v) {
    return z1 > z0 && (std::abs(p[v].z - z0) <= 2e-6 || std::abs(p[v].z - z1) <= 2e-6);
  };
  auto area_vec = [&](const std::array<int, 3>& c) { return cross3(p[c[1]] - p[c[0]], p[c[2]] - p[c[0]]); };

  // The median edge length of the mesh as given.
  std::vector<double> lengths;
  for (const auto& c : tri)
    for (int k = 0; k < 3; ++k)
      if (c[k] < c[(k + 1) % 3]) lengths.push_back((p[c[k]] - p[c[(k + 1) % 3]]).norm());
  Collapsed out;
  if (lengths.empty()) {
    out.triangles = triangles, out.volume_m3 = volume_m3;
    return out;
  }
  std::nth_element(lengths.begin(), lengths.begin() + static_cast<long>(lengths.size() / 2), lengths.end());
  const double limit = share * lengths[lengths.size() / 2];
  const double cos_fold = std::cos(kFoldDegrees * 3.14159265358979323846 / 180);

  for (int pass = 0; pass < kPasses; ++pass) {
    std::vector<std::vector<int>> star(p.size());
    for (std::size_t t = 0; t < nt; ++t)
      if (alive[t])
        for (int k = 0; k < 3; ++k) star[tri[t][k]].push_back(static_cast<int>(t));
    // The short edges, shortest first.
    std::vector<std::pair<double, std::pair<int, int>>> edges;
    for (std::size_t t = 0; t < nt; ++t) {
      if (!alive[t]) continue;
      for (int k = 0; k < 3; ++k) {
        const int a = tri[t][k], b = tri[t][(k + 1) % 3];
        const double len = (p[a] - p[b]).norm();
        if (a < b && len < limit) edges.push_back({len, {a, b}});
      }
    }
    if (edges.empty()) break;
    std::sort(edges.begin(), edges.end());
    std::vector<char> locked(p.size(), 0);
    int done = 0;
    for (const auto& [len, e] : edges) {
      int a = e.first, b = e.second;
      if (locked[a] || locked[b]) continue;
      if (on_end(b) && !on_end(a)) std::swap(a, b);  // a stays; the point keeps an end vertex's place
      // The triangles on the edge: two, for a closed surface.
      std::vector<int> on_edge;
      for (int t : star[a])
        if (std::find(tri[t].begin(), tri[t].end(), b) != tri[t].end()) on_edge.push_back(t);
      if (on_edge.size() != 2) continue;
      // The link condition: a and b share no neighbour but the two opposite corners.
      std::set<int> na, nb;
      for (int t : star[a])
        for (int v : tri[t]) na.insert(v);
      for (int t : star[b])
        for (int v : tri[t]) nb.insert(v);
      int common = 0;
      for (int v : na)
        if (v != a && v != b && nb.count(v)) ++common;
      if (common != 2) continue;
      Vec3 at = on_end(a) ? p[a] : (p[a] + p[b]) * 0.5;
      if (on_end(a) && on_end(b) && std::abs(p[a].z - p[b].z) <= 4e-6) at = (p[a] + p[b]) * 0.5;
      // No neighbour folds or shrinks to nothing.
      bool fine = true;
      for (int v : {a, b})
        for (int t : star[v]) {
          if (t == on_edge[0] || t == on_edge[1]) continue;
          const Vec3 before = area_vec(tri[t]);
          std::array<Vec3, 3> q{p[tri[t][0]], p[tri[t][1]], p[tri[t][2]]};
          for (int k = 0; k < 3; ++k)
            if (tri[t][k] == a || tri[t][k] == b) q[k] = at;
          const Vec3 after = cross3(q[1] - q[0], q[2] - q[0]);
          if (!(after.dot(before) > cos_fold * after.norm() * before.norm()) || after.norm() < 1e-3 * before.norm())
            fine = false;
        }
      if (!fine) continue;
      // Collapse: b becomes a at the point; the edge's triangles go, their
      // wear shared by area over the triangles round the point.
      p[a] = at;
      double gone = 0;
      for (int t : on_edge) alive[t] = 0, gone += volume[t], volume[t] = 0;
      std::vector<int> round;
      for (int v : {a, b})
        for (int t : star[v])
          if (alive[t] && std::find(round.begin(), round.end(), t) == round.end()) round.push_back(t);
      for (int t : round)
        for (int& v : tri[t])
          if (v == b) v = a;
      double area = 0;
      for (int t : round) area += area_vec(tri[t]).norm();
      for (int t : round) volume[t] += area > 0 ? gone * area_vec(tri[t]).norm() / area : gone / round.size();
      for (int v : na) locked[v] = 1;
      for (int v : nb) locked[v] = 1;
      ++done, ++out.edges;
    }
    if (done == 0) break;
  }
  for (std::size_t t = 0; t < nt; ++t) {
    if (!alive[t]) continue;
    out.triangles.push_back({{p[tri[t][0]], p[tri[t][1]], p[tri[t][2]]}});
    out.volume_m3.push_back(volume[t]);
  }
  return out;
}

FitWear wear_kept_fit(const std::vector<Triangle>& triangles, const std::vector<double>& booked_m3,
                      const MeshBounds& bounds, double across, double along, const std::string& name) {
  for (const double share : kCollapseShares) {
    FitWear f;
    f.collapsed = collapse_short_edges(triangles, booked_m3, bounds.z0, bounds.z1, share);
    const std::vector<double> spread = smooth_wear(f.collapsed.triangles, f.collapsed.volume_m3, across, along);
    try {
      f.wear = wear_mesh(f.collapsed.triangles, spread, bounds, 0, name);
    } catch (const MeshSpoiled&) {
      if (share == kCollapseShares[std::size(kCollapseShares) - 1]) throw;
      continue;
    }
    f.share = share;
    return f;
  }
  throw std::logic_error("wear_kept_fit: no share");
}

}  // namespace mc::life
