#include "core/liner.h"

#include <algorithm>
#include <cmath>

#include "core/lifters.h"
#include "core/plate_wear.h"
#include "core/wall_mesh.h"

namespace mc {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kArcSegments = 3;  // per element's arc in the outlines

double wrap(double a) {
  a = std::fmod(a, 2 * kPi);
  return a < 0 ? a + 2 * kPi : a;
}

// Signed difference b − a of two angles, in (−π, π].
double angle_diff(double a, double b) {
  double d = std::fmod(b - a, 2 * kPi);
  if (d > kPi) d -= 2 * kPi;
  if (d <= -kPi) d += 2 * kPi;
  return d;
}

Vec3 on_circle(double r, double theta, double z) { return {r * std::cos(theta), r * std::sin(theta), z}; }

}  // namespace

FootAngles lifter_foot_angles(const std::vector<Vec2>& poly, double R, double centre) {
  // Signed: a bar wholly ahead of its row's centre has a negative trail.
  FootAngles f{-1e300, -1e300};
  bool crossed = false;
  const std::size_t n = poly.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2 a = poly[k], b = poly[(k + 1) % n];
    // |a + t(b − a)| = R for t in [0, 1].
    const double ex = b.x - a.x, ey = b.y - a.y;
    const double qa = ex * ex + ey * ey, qb = 2 * (a.x * ex + a.y * ey), qc = a.x * a.x + a.y * a.y - R * R;
    const double disc = qb * qb - 4 * qa * qc;
    if (qa <= 0 || disc < 0) continue;
    for (double sgn : {-1.0, 1.0}) {
      const double t = (-qb + sgn * std::sqrt(disc)) / (2 * qa);
      if (t < 0 || t > 1) continue;
      const double d = angle_diff(centre, std::atan2(a.y + t * ey, a.x + t * ex));
      f.lead = std::max(f.lead, d);
      f.trail = std::max(f.trail, -d);
      crossed = true;
    }
  }
  if (!crossed)  // wholly inside the shell: the vertices' spread
    for (const Vec2& v : poly) {
      const double d = angle_diff(centre, std::atan2(v.y, v.x));
      f.lead = std::max(f.lead, d);
      f.trail = std::max(f.trail, -d);
    }
  if (poly.empty()) f = FootAngles{};
  return f;
}

LinerLayout liner_layout(const Scene& scene) {
  LinerLayout L;
  const Walls& w = scene.walls;
  const LinerGrid& g = scene.liner;
  const double R = w.shell_radius;
  L.shell_radius = R;
  L.length = w.length;
  L.n_lifters = static_cast<int>(w.lifters.size());
  const int nl = L.n_lifters;
  const double spacing = nl > 0 ? 2 * kPi / nl : 2 * kPi;
  for (int k = 0; k < nl; ++k) {
    L.lifter_centre.push_back(wrap(w.lifter_first_angle + k * spacing));
    const FootAngles f = R > 0 ? lifter_foot_angles(w.lifters[k], R, L.lifter_centre[k]) : FootAngles{};
    L.lifter_lead_angle.push_back(f.lead);
    L.lifter_trail_angle.push_back(f.trail);
    L.lifter_half_angle.push_back(0.5 * (f.lead + f.trail));
  }
  L.shell_bins = nl > 0 ? g.shell_bins : g.smooth_shell_bins;
  // Axial bins: about square shell elements, at most 32.
  double bare = 2 * kPi;
  if (nl > 0) {
    bare = 0;
    for (int k = 0; k < nl; ++k) bare += spacing - L.lifter_lead_angle[k] - L.lifter_trail_angle[(k + 1) % nl];
    bare /= nl;
  }
  const double elem_width = R * bare / L.shell_bins;
  if (g.axial_bins > 0) L.axial_bins = g.axial_bins;
  else if (w.length > 0 && elem_width > 0)
    L.axial_bins = std::clamp(static_cast<int>(std::lround(w.length / elem_width)), 1, 32);
  else
    L.axial_bins = 1;
  L.plate_rings = g.plate_rings;
  L.plate_sectors = g.plate_sectors > 0 ? g.plate_sectors : nl > 0 ? nl : 12;
  const int A = L.axial_bins;
  const double len = w.length > 0 ? w.length : 0;
  // Worn end plates lie behind their planes: the shell and the bars reach
  // into the dish, and their end bins take its depth at the shell.
  const bool dish = w.plates_worn() && w.has_end_plates();
  const double dish0 = dish ? w.plate_depth[0].back() : 0, dish1 = dish ? w.plate_depth[1].back() : 0;
  auto z_of = [&](int a) { return a == 0 ? -dish0 : a == A ? len + dish1 : len * a / A; };

  // Shell: gap by gap, bins over the bare arc, each in axial bins.
  const int gaps = nl > 0 ? nl : 1;
  for (int k = 0; k < gaps; ++k) {
    const double from = nl > 0 ? L.lifter_centre[k] + L.lifter_lead_angle[k] : 0.0;
    const double to = nl > 0 ? L.lifter_centre[k] + spacing - L.lifter_trail_angle[(k + 1) % nl] : 2 * kPi;
    for (int j = 0; j < L.shell_bins; ++j)
      for (int a = 0; a < A; ++a) {
        LinerElement e;
        e.part = LinerPart::shell;
        e.row = k;
        e.bin = j;
        e.axial = a;
        e.theta0 = from + (to - from) * j / L.shell_bins;
        e.theta1 = from + (to - from) * (j + 1) / L.shell_bins;
        e.z0 = z_of(a);
        e.z1 = z_of(a + 1);
        e.r0 = e.r1 = R;
        e.area_m2 = R * (e.theta1 - e.theta0) * (e.z1 - e.z0);
        for (int s = 0; s <= kArcSegments; ++s)
          e.outline.push_back(on_circle(R, e.theta0 + (e.theta1 - e.theta0) * s / kArcSegments, e.z0));
        for (int s = kArcSegments; s >= 0; --s)
          e.outline.push_back(on_circle(R, e.theta0 + (e.theta1 - e.theta0) * s / kArcSegments, e.z1));
        L.elements.push_back(e);
      }
  }

  // Lifters: each row's leading face, top and trailing face, by their place
  // along the bar's exposed outline (lifter_face_split), as polylines.
  L.first_lifter = L.size();
  for (int k = 0; k < nl; ++k) {
    const std::vector<Vec2>& poly = w.lifters[k];
    const double c = L.lifter_centre[k];
    const FaceSplit split = lifter_face_split(poly, R, Vec2{std::cos(c), std::sin(c)});
    const WearPath path = lifter_wear_path(poly, R);
    std::vector<Vec2> strip[3];  // each face's stretch of the outline
    double face_len[3] = {0, 0, 0};
    const double cuts[4] = {split.from, split.top_from, split.top_to, split.to};
    const std::size_t n = poly.size();
    double along = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const Vec2 a = poly[(path.start + j) % n], b = poly[(path.start + j + 1) % n];
      const double len = std::hypot(b.x - a.x, b.y - a.y);
      for (int f = 0; f < 3 && len > 0; ++f) {
        const double s0 = std::max(along, cuts[f]), s1 = std::min(along + len, cuts[f + 1]);
        if (!(s1 > s0)) continue;
        auto at = [&](double s) {
          const double t = (s - along) / len;
          return Vec2{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
        };
        if (strip[f].empty()) strip[f].push_back(at(s0));
        strip[f].push_back(at(s1));
        face_len[f] += s1 - s0;
      }
      along += len;
    }
    for (int f = 0; f < 3; ++f)
      for (int a = 0; a < A; ++a) {
        LinerElement e;
        e.part = LinerPart::lifter;
        e.row = k;
        e.bin = f;
        e.axial = a;
        e.z0 = z_of(a);
        e.z1 = z_of(a + 1);
        e.theta0 = e.theta1 = c;
        e.r0 = e.r1 = R;
        if (!strip[f].empty()) {
          e.r0 = 1e300;
          e.r1 = 0;
          for (const Vec2& p : strip[f]) {
            e.r0 = std::min(e.r0, std::hypot(p.x, p.y));
            e.r1 = std::max(e.r1, std::hypot(p.x, p.y));
          }
        }
        e.area_m2 = face_len[f] * (e.z1 - e.z0);
        for (const Vec2& p : strip[f]) e.outline.push_back({p.x, p.y, e.z0});
        for (auto it = strip[f].rbegin(); it != strip[f].rend(); ++it) e.outline.push_back({it->x, it->y, e.z1});
        L.elements.push_back(e);
      }
  }

  // End plates: rings and sectors at z = 0, then z = length (a periodic
  // slice has none).
  L.first_plate = L.size();
  const double ring_w = (R > 0 ? R : 1.0) / L.plate_rings;
  const int plates = w.periodic || !w.end_plates ? 0 : 2;  // a slice or cone heads have none
  for (int plate = 0; plate < plates; ++plate)
    for (int ring = 0; ring < L.plate_rings; ++ring)
      for (int s = 0; s < L.plate_sectors; ++s) {
        LinerElement e;
        e.part = LinerPart::plate;
        e.row = plate;
        e.bin = ring;
        e.sector = s;
        e.r0 = ring * ring_w;
        e.r1 = (ring + 1) * ring_w;
        e.theta0 = 2 * kPi * s / L.plate_sectors;
        e.theta1 = 2 * kPi * (s + 1) / L.plate_sectors;
        e.z0 = e.z1 = plate == 0 ? 0.0 : len;
        e.area_m2 = 0.5 * (e.r1 * e.r1 - e.r0 * e.r0) * (e.theta1 - e.theta0);
        // Drawn on the plate's face: its plane, or a worn plate's dish
        // (core/plate_wear.h), with the points where the dish bends along
        // each radial side, so that the outline follows it.
        const std::vector<double>& depth = w.plate_depth[plate];
        const double dw = dish && !depth.empty() ? R / static_cast<double>(depth.size()) : 0;
        auto at = [&](double rho, double th) {
          Vec3 p = on_circle(rho, th, e.z0);
          if (dw > 0) p.z += (plate == 0 ? -1 : 1) * plate_surface_depth(depth, dw, rho);
          return p;
        };
        std::vector<double> bends;  // between r0 and r1, outward
        if (dw > 0)
          for (double b : plate_bend_radii(depth.size(), dw))
            if (b > e.r0 && b < e.r1) bends.push_back(b);
        for (int q = 0; q <= kArcSegments; ++q) e.outline.push_back(at(e.r1, e.theta0 + (e.theta1 - e.theta0) * q / kArcSegments));
        for (auto b = bends.rbegin(); b != bends.rend(); ++b) e.outline.push_back(at(*b, e.theta1));
        for (int q = kArcSegments; q >= 0; --q) e.outline.push_back(at(e.r0, e.theta0 + (e.theta1 - e.theta0) * q / kArcSegments));
        for (double b : bends) e.outline.push_back(at(b, e.theta0));
        if (plate == 1) std::reverse(e.outline.begin(), e.outline.end());
        L.elements.push_back(e);
      }

  // Mesh triangles, one element each, in the device order.
  L.first_mesh = L.size();
  for (const MeshTriangleRef& ref : mesh_device_order(w.meshes)) {
    const WallMesh& m = w.meshes[ref.mesh];
    const Triangle& t = m.triangles[ref.triangle];
    LinerElement e;
    e.part = LinerPart::mesh;
    e.row = ref.mesh;
    e.bin = ref.triangle;
    e.still = !m.turning;
    e.density = m.material.density;
    e.impact_wear_coefficient = m.material.impact_wear_coefficient;
    const Vec3 ab = t.v[1] - t.v[0], ac = t.v[2] - t.v[0];
    const Vec3 n{ab.y * ac.z - ab.z * ac.y, ab.z * ac.x - ab.x * ac.z, ab.x * ac.y - ab.y * ac.x};
    e.area_m2 = 0.5 * n.norm();
    const Vec3 c = (t.v[0] + t.v[1] + t.v[2]) * (1.0 / 3.0);
    e.theta0 = e.theta1 = wrap(std::atan2(c.y, c.x));
    e.z0 = std::min({t.v[0].z, t.v[1].z, t.v[2].z});
    e.z1 = std::max({t.v[0].z, t.v[1].z, t.v[2].z});
    e.r0 = 1e300;
    e.r1 = 0;
    for (const Vec3& v : t.v) {
      e.r0 = std::min(e.r0, std::hypot(v.x, v.y));
      e.r1 = std::max(e.r1, std::hypot(v.x, v.y));
    }
    e.outline = {t.v[0], t.v[1], t.v[2]};
    L.elements.push_back(e);
  }
  return L;
}

int n_pair_types(int nm) { return nm * (nm + 1) / 2 + 3 * nm; }

bool pair_type_is_wall(int nm, int type) { return type >= nm * (nm + 1) / 2; }

std::string pair_type_name(const Scene& scene, int type) {
  const int nm = static_cast<int>(scene.materials.size());
  const int balls = nm * (nm + 1) / 2;
  if (type >= balls) {
    const int m = (type - balls) / 3, w = (type - balls) % 3;
    // Mesh walls book as their part; ends that are meshes (cone heads, end
    // lifters) are more than a plate.
    bool end_meshes = false;
    for (const WallMesh& mesh : scene.walls.meshes) end_meshes = end_meshes || mesh.part == MeshPart::ends;
    const char* ends = scene.walls.has_end_plates() && !end_meshes ? "end plate" : "ends";
    const char* walls[] = {"shell", "lifter", ends};
    return scene.materials.at(m).name + "-" + walls[w];
  }
  for (int a = 0; a < nm; ++a)
    for (int b = a; b < nm; ++b)
      if (a * nm - a * (a - 1) / 2 + (b - a) == type) return scene.materials[a].name + "-" + scene.materials[b].name;
  return "type " + std::to_string(type);
}

}  // namespace mc
