// Short edges of a worn mesh collapsed before its next move (mesh_collapse.h).
#include "life/mesh_collapse.h"

#include <algorithm>
#include <iterator>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <utility>

#include "life/mesh_wear.h"

namespace mc::life {

namespace {

Vec3 cross3(const Vec3& a, const Vec3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

// A collapse may turn a neighbour's normal by at most this from the mesh
// as given; a vertex whose triangles' normals differ by more than
// kCreaseDegrees is on an edge of the shape, which a collapse keeps.
constexpr double kFoldDegrees = 60.0;
constexpr double kCreaseDegrees = 30.0;
constexpr int kPasses = 8;

// Six times the signed volume the surface encloses with the origin.
double volume6(const std::vector<Vec3>& p, const std::vector<std::array<int, 3>>& tri, const std::vector<char>& alive) {
  double v = 0;
  for (std::size_t t = 0; t < tri.size(); ++t)
    if (alive[t]) v += p[tri[t][0]].dot(cross3(p[tri[t][1]], p[tri[t][2]]));
  return v;
}

// Six times the signed volume triangle c encloses with the point o.
double tet6(const std::vector<Vec3>& p, const std::array<int, 3>& c, const Vec3& o) {
  return (p[c[0]] - o).dot(cross3(p[c[1]] - o, p[c[2]] - o));
}

}  // namespace

Collapsed collapse_short_edges(const std::vector<Triangle>& triangles, const std::vector<double>& volume_m3, double z0,
                               double z1, double share, double on_end_m) {
  if (volume_m3.size() != triangles.size())
    throw std::invalid_argument("collapse_short_edges: a volume per triangle is needed");
  WeldedMesh w = weld(triangles);
  std::vector<std::array<int, 3>>& tri = w.corners;
  std::vector<Vec3>& p = w.points;
  const std::size_t nt = tri.size();
  std::vector<char> alive(nt, 1);
  std::vector<double> volume = volume_m3, taken(nt, 0.0);
  auto on_end = [&](int v) {
    return z1 > z0 && (std::abs(p[v].z - z0) <= on_end_m || std::abs(p[v].z - z1) <= on_end_m);
  };
  auto area_vec = [&](const std::array<int, 3>& c) { return cross3(p[c[1]] - p[c[0]], p[c[2]] - p[c[0]]); };
  // The mesh as given: each triangle's normal, the vertices on an open
  // edge (held: a scan's rim stays where it is) and on a crease.
  std::vector<Vec3> given(nt);
  std::vector<std::vector<Vec3>> normals_at(p.size());
  std::map<std::pair<int, int>, int> uses;
  for (std::size_t t = 0; t < nt; ++t) {
    given[t] = area_vec(tri[t]);
    const double a = given[t].norm();
    for (int k = 0; k < 3; ++k) {
      if (a > 0) normals_at[tri[t][k]].push_back(given[t] * (1 / a));
      const int u = tri[t][k], v = tri[t][(k + 1) % 3];
      ++uses[{std::min(u, v), std::max(u, v)}];
    }
  }
  // Open: on an open edge (the mesh's rim, wherever it lies): never moved,
  // so that the volume between the mesh and the collapsed one is bounded
  // by the same rim.
  std::vector<char> open(p.size(), 0), crease(p.size(), 0);
  for (const auto& [e, n] : uses)
    if (n < 2) open[e.first] = open[e.second] = 1;
  const double cos_crease = std::cos(kCreaseDegrees * 3.14159265358979323846 / 180);
  for (std::size_t v = 0; v < p.size(); ++v)
    for (std::size_t a = 0; a < normals_at[v].size() && !crease[v]; ++a)
      for (std::size_t b = a + 1; b < normals_at[v].size() && !crease[v]; ++b)
        crease[v] = normals_at[v][a].dot(normals_at[v][b]) < cos_crease;
  const double volume_given = volume6(p, tri, alive);

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
      // Where the point goes: the rim's vertex, else an end plane's, else
      // a crease's keeps its place (a stays). Of two alike: two of the
      // rim stay apart (an edge across the rim); two of an end plane must
      // be of the same one, and meet half-way unless one is on a crease
      // (a bar's outline there), which keeps its place; two of a crease
      // meet half-way (a corner's strip between two creases), as two
      // plain vertices do.
      auto rank = [&](int v) { return open[v] ? 3 : on_end(v) ? 2 : crease[v] ? 1 : 0; };
      if (rank(b) > rank(a) || (rank(a) == 2 && rank(b) == 2 && crease[b] && !crease[a])) std::swap(a, b);
      if (rank(a) == 3 && rank(b) == 3) continue;
      if (rank(a) == 2 && rank(b) == 2 && std::abs(p[a].z - p[b].z) > 2 * on_end_m) continue;
      const bool keep_a = rank(a) > rank(b) || (rank(a) == 2 && rank(b) == 2 && crease[a] && !crease[b]);
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
      const Vec3 at = keep_a ? p[a] : (p[a] + p[b]) * 0.5;
      // No neighbour folds or shrinks to nothing.
      bool fine = true;
      for (int v : {a, b})
        for (int t : star[v]) {
          if (t == on_edge[0] || t == on_edge[1]) continue;
          const Vec3& before = given[t];
          std::array<Vec3, 3> q{p[tri[t][0]], p[tri[t][1]], p[tri[t][2]]};
          for (int k = 0; k < 3; ++k)
            if (tri[t][k] == a || tri[t][k] == b) q[k] = at;
          const Vec3 after = cross3(q[1] - q[0], q[2] - q[0]);
          if (!(after.dot(before) > cos_fold * after.norm() * before.norm()) || after.norm() < 1e-3 * before.norm())
            fine = false;
        }
      // The triangles round the point after: none, and the wear of the
      // edge's two would have nowhere to go.
      bool others = false;
      for (int v : {a, b})
        for (int t : star[v]) others = others || (t != on_edge[0] && t != on_edge[1]);
      if (!fine || !others) continue;
      // Nor two triangles of the same three corners after it (a closed
      // part of four vertices would fold into a two-sided sheet).
      {
        std::set<std::array<int, 3>> corners;
        bool twice = false;
        for (int v : {a, b})
          for (int t : star[v]) {
            if (t == on_edge[0] || t == on_edge[1]) continue;
            std::array<int, 3> c = tri[t];
            for (int& x : c)
              if (x == b) x = a;
            std::sort(c.begin(), c.end());
            twice = twice || !corners.insert(c).second;
          }
        if (twice) continue;
      }
      // Collapse: b becomes a at the point; the edge's triangles go, their
      // wear and what earlier collapses took there shared by area over the
      // triangles round the point, with what this one takes: the triangles
      // round it enclose the rest of the solid the same before and after
      // (their rim, the link, stays), so their six-volumes' difference is
      // the collapse's own. Taken about the point itself (a mill's
      // coordinates of metres lose no digits), every triangle round it
      // after the collapse has the point as a corner and encloses nothing
      // with it: the collapse's own is the six-volume before, over six.
      double before6 = 0;
      for (int v : {a, b})
        for (int t : star[v])
          if (v == a || std::find(tri[t].begin(), tri[t].end(), a) == tri[t].end()) before6 += tet6(p, tri[t], at);
      p[a] = at;
      double gone = 0, gone_taken = 0;
      for (int t : on_edge) alive[t] = 0, gone += volume[t], volume[t] = 0, gone_taken += taken[t], taken[t] = 0;
      std::vector<int> round;
      for (int v : {a, b})
        for (int t : star[v])
          if (alive[t] && std::find(round.begin(), round.end(), t) == round.end()) round.push_back(t);
      for (int t : round)
        for (int& v : tri[t])
          if (v == b) v = a;
      double area = 0;
      for (int t : round) area += area_vec(tri[t]).norm();
      const double own = before6 / 6;
      for (int t : round) {
        const double w = area > 0 ? area_vec(tri[t]).norm() / area : 1.0 / round.size();
        volume[t] += gone * w;
        taken[t] += (gone_taken + own) * w;
      }
      for (int v : na) locked[v] = 1;
      for (int v : nb) locked[v] = 1;
      ++done, ++out.edges;
    }
    if (done == 0) break;
  }
  out.removed_m3 = (volume_given - volume6(p, tri, alive)) / 6;
  for (std::size_t t = 0; t < nt; ++t) {
    if (!alive[t]) continue;
    out.triangles.push_back({{p[tri[t][0]], p[tri[t][1]], p[tri[t][2]]}});
    out.volume_m3.push_back(volume[t]);
    if (out.edges > 0) out.taken_m3.push_back(taken[t]);
  }
  return out;
}

std::vector<double> asked_volumes(const Collapsed& c, double across, double along) {
  double booked = 0;
  for (double v : c.volume_m3) booked += v;
  std::vector<double> v = c.volume_m3;
  if (!c.taken_m3.empty()) {
    if (c.taken_m3.size() != v.size()) throw std::invalid_argument("asked_volumes: a collapse's volume per triangle");
    for (std::size_t t = 0; t < v.size(); ++t) v[t] -= c.taken_m3[t];
  }
  v = smooth_wear(c.triangles, v, across, along);
  double sum = 0;
  for (double& x : v) sum += x = std::max(x, 0.0);
  const double left = booked - c.removed_m3;
  if (sum > 0 && left > 0)
    for (double& x : v) x *= left / sum;
  return v;
}

namespace {

// Each triangle's span of the mill (z0 to z1 in `segments`), by its centroid.
int span_of(const Triangle& t, const MeshBounds& b, int segments) {
  if (segments <= 1 || !(b.z1 > b.z0)) return 0;
  const double z = (t.v[0].z + t.v[1].z + t.v[2].z) / 3;
  return std::clamp(static_cast<int>(std::floor((z - b.z0) / (b.z1 - b.z0) * segments)), 0, segments - 1);
}

// Each triangle's stretch: its part (bar), and where `segments` > 1, the
// span of the mill between z0 and z1 its centroid lies in.
std::vector<int> stretches(const std::vector<Triangle>& triangles, const MeshBounds& b, int segments) {
  std::vector<int> out(triangles.size(), 0);
  const std::vector<std::vector<int>> parts = connected_parts(triangles);
  const int n = segments > 1 && b.z1 > b.z0 ? segments : 1;
  for (std::size_t p = 0; p < parts.size(); ++p)
    for (int t : parts[p]) out[t] = static_cast<int>(p) * n + span_of(triangles[t], b, n);
  return out;
}

// How far the stretches are from what they were asked: the largest
// |removed / asked − 1| over those asked at least a fifth of the mean
// stretch's (of those asked any), the volume misplaced over all
// (Σ |removed − asked| / Σ asked), and each stretch's ratio asked /
// removed (within 1/2 to 2; 2 where it removed nothing).
struct Misfit {
  double worst = 0, misplaced = 0;
  std::vector<double> ratio;
};
Misfit stretch_misfit(const std::vector<int>& stretch, const std::vector<double>& asked, const std::vector<double>& swept) {
  const int n = stretch.empty() ? 0 : *std::max_element(stretch.begin(), stretch.end()) + 1;
  std::vector<double> a(n, 0.0), r(n, 0.0), ratio(n, 1.0);
  for (std::size_t t = 0; t < stretch.size(); ++t) a[stretch[t]] += asked[t], r[stretch[t]] += swept[t];
  double whole = 0;
  int asked_any = 0;
  for (int k = 0; k < n; ++k)
    if (a[k] > 0) whole += a[k], ++asked_any;
  Misfit m;
  for (int k = 0; k < n; ++k) {
    if (a[k] > 0) ratio[k] = r[k] > 0 ? std::clamp(a[k] / r[k], 0.5, 2.0) : 2.0;
    if (a[k] > 0 && a[k] >= 0.2 * whole / asked_any) m.worst = std::max(m.worst, std::abs(r[k] / a[k] - 1));
    m.misplaced += std::abs(r[k] - a[k]);
  }
  m.misplaced = whole > 0 ? m.misplaced / whole : 0.0;
  m.ratio = std::move(ratio);
  return m;
}

// One move of the whole booked wear (wear_kept_fit, one step).
FitWear fit_once(const std::vector<Triangle>& triangles, const std::vector<double>& booked_m3, const MeshBounds& bounds,
                 double across, double along, const std::string& name, int segments, bool a_step) {
  double booked = 0;
  for (double v : booked_m3) booked += v;
  for (const double share : kCollapseShares) {
    if (share > 0 && !(booked > 0)) break;  // no wear, no collapse: the plain move's refusal stands
    FitWear f;
    if (share > 0) f.collapsed = collapse_short_edges(triangles, booked_m3, bounds.z0, bounds.z1, share, bounds.on_end);
    else f.collapsed = {triangles, booked_m3, 0, 0.0, {}};
    // What the collapse took (or gave back) counts against the stage's
    // wear: the move removes the rest, so that the two remove the booked.
    std::vector<double> volume = asked_volumes(f.collapsed, across, along);
    const double left = booked - f.collapsed.removed_m3;
    const bool last = share == kCollapseShares[std::size(kCollapseShares) - 1];
    if (booked > 0 && !(left > 0)) {
      if (last)
        throw MeshSpoiled(name + ": collapsing its short edges takes more than the " +
                          (a_step ? std::string("step's share of the stage's wear; more smoothing")
                                  : std::string("stage's wear; more smoothing or shorter stages")));
      continue;
    }
    try {
      f.wear = wear_mesh(f.collapsed.triangles, volume, bounds, 0, name);
    } catch (const MeshSpoiled&) {
      if (last || !(booked > 0)) throw;
      continue;
    }
    f.share = share;
    if (!(booked > 0)) return f;
    // Each stretch brought to what it was asked: its volumes scaled by its
    // ratio, the whole kept (the move's scale), and moved again.
    const std::vector<double> asked = volume;
    const std::vector<int> stretch = stretches(f.collapsed.triangles, bounds, segments);
    Misfit fit = stretch_misfit(stretch, asked, swept_volumes(f.collapsed.triangles, f.wear.triangles));
    while (fit.worst > kLocalTolerance && f.local_passes < kLocalPasses) {
      double sum = 0;
      for (std::size_t t = 0; t < volume.size(); ++t) sum += volume[t] *= fit.ratio[stretch[t]];
      for (double& v : volume) v *= left / sum;
      MeshWear next;
      try {
        next = wear_mesh(f.collapsed.triangles, volume, bounds, 0, name);
      } catch (const MeshSpoiled&) {
        break;  // the last move that passed stands
      } catch (const MeshOutside&) {
        break;  // past the shell or the ends at the corrected depths: likewise
      }
      // Taken where it misplaces less volume over all (the worst stretch
      // alone may be one that cannot move further).
      Misfit m = stretch_misfit(stretch, asked, swept_volumes(f.collapsed.triangles, next.triangles));
      if (!(m.misplaced < fit.misplaced)) break;
      f.wear = std::move(next), fit = std::move(m), ++f.local_passes;
    }
    f.local_misfit = fit.worst;
    return f;
  }
  throw std::logic_error("wear_kept_fit: no share");
}

}  // namespace

FitWear wear_kept_fit(const std::vector<Triangle>& triangles, const std::vector<double>& booked_m3,
                      const MeshBounds& bounds, double across, double along, const std::string& name, int segments,
                      int most_steps) {
  const int spans = std::max(segments, 1);
  double booked = 0;
  for (double v : booked_m3) booked += v;
  for (const int steps : kMoveSteps) {
    const bool last = steps >= most_steps || steps == kMoveSteps[std::size(kMoveSteps) - 1];
    FitWear whole;
    whole.steps = steps;
    whole.span_asked_m3.assign(spans, 0.0), whole.span_removed_m3.assign(spans, 0.0);
    std::vector<double> rest = booked_m3;  // the wear still to move, carried through each step's collapse
    try {
      for (int i = 0; i < steps; ++i) {
        // An equal share of what is left: the rest carried as the step's own
        // is; on the mesh the step before left.
        const double part = 1.0 / (steps - i);
        std::vector<double> volume = rest;
        for (double& v : volume) v *= part;
        FitWear f = fit_once(i == 0 ? triangles : whole.wear.triangles, volume, bounds, across, along, name, segments,
                             steps > 1);
        // What this step asked the move (the booked less the collapse's own) and what it removed, by span.
        const std::vector<double> asked = asked_volumes(f.collapsed, across, along);
        const std::vector<double> swept = swept_volumes(f.collapsed.triangles, f.wear.triangles);
        for (std::size_t t = 0; t < f.collapsed.triangles.size(); ++t) {
          const int g = span_of(f.collapsed.triangles[t], bounds, spans);
          whole.span_asked_m3[g] += asked[t], whole.span_removed_m3[g] += swept[t];
        }
        whole.edges += f.collapsed.edges;
        whole.collapse_m3 += f.collapsed.removed_m3;
        whole.removed_m3 += f.collapsed.removed_m3 + f.wear.removed_m3;
        whole.deepest_m += f.wear.deepest_m;
        whole.relaxed += f.wear.relaxed;
        whole.local_passes += f.local_passes;
        whole.local_misfit = std::max(whole.local_misfit, f.local_misfit);
        rest = f.collapsed.volume_m3;
        for (double& v : rest) v *= static_cast<double>(steps - i - 1);
        // What a stretch fell short of (or beyond) its ask, carried to the
        // steps left: its rest scaled to take it (never below nothing),
        // and the whole rest brought to what the stage has still to
        // remove (a stretch with nothing left to carry it on, or one
        // clipped at nothing, changes the others' share, not the total).
        // What a span's rest gained is asked of it again: it counts once.
        if (i + 1 < steps) {
          const std::vector<double> before = rest;
          const std::vector<int> stretch = stretches(f.collapsed.triangles, bounds, segments);
          const int n = stretch.empty() ? 0 : *std::max_element(stretch.begin(), stretch.end()) + 1;
          std::vector<double> short_of(n, 0.0), left(n, 0.0);
          for (std::size_t t = 0; t < stretch.size(); ++t)
            short_of[stretch[t]] += asked[t] - swept[t], left[stretch[t]] += rest[t];
          double sum = 0;
          for (std::size_t t = 0; t < stretch.size(); ++t) {
            if (left[stretch[t]] > 0) rest[t] *= std::max(0.0, 1 + short_of[stretch[t]] / left[stretch[t]]);
            sum += rest[t];
          }
          const double still = booked - whole.removed_m3;
          for (double& v : rest) v = sum > 0 && still > 0 ? v * still / sum : 0.0;
          for (std::size_t t = 0; t < rest.size(); ++t)
            whole.span_asked_m3[span_of(f.collapsed.triangles[t], bounds, spans)] -= rest[t] - before[t];
        }
        if (i == 0) whole.collapsed = std::move(f.collapsed), whole.share = f.share;
        whole.wear = std::move(f.wear);
      }
    } catch (const MeshSpoiled& e) {
      if (!last) continue;  // in more, shorter steps
      if (steps == 1) throw;
      throw MeshSpoiled(std::string(e.what()) + " (the stage's wear moved in " + std::to_string(steps) +
                        " steps)");
    }
    return whole;
  }
  throw std::logic_error("wear_kept_fit: no steps");
}

}  // namespace mc::life
