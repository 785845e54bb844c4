// The case's walls as the solver takes them (core/mill_case.h): its
// [[walls.mesh]] placed in the mill and checked, and the scene of its
// shell, end plates, lifters and meshes before the charge is added.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/mill_case.h"
#include "core/wall_mesh.h"

namespace mc {

namespace {

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void fail(const std::string& key, const std::string& what) {
  throw std::invalid_argument(key + ": " + what);
}

}  // namespace

std::vector<Triangle> placed_mesh_triangles(const MeshSpec& spec) {
  const double th = spec.angle_deg * kPi / 180.0, ct = std::cos(th), st = std::sin(th);
  std::vector<Triangle> placed;
  for (const Triangle& t0 : spec.triangles) {
    Triangle t = t0;
    if (spec.flip) std::swap(t.v[1], t.v[2]);
    for (Vec3& v : t.v) v = Vec3{ct * v.x - st * v.y, st * v.x + ct * v.y, v.z} + spec.offset;
    placed.push_back(t);
  }
  return placed;
}

bool on_periodic_seam(const Triangle& t, const MillCase& c) {
  if (!c.periodic) return false;
  const double z_tol = 1e-6 * std::max(1.0, c.length);
  bool low = true, high = true;
  for (const Vec3& v : t.v) {
    low = low && std::fabs(v.z) <= z_tol;
    high = high && std::fabs(v.z - c.length) <= z_tol;
  }
  return low || high;
}

std::vector<WallMesh> place_meshes(const MillCase& c) {
  std::vector<WallMesh> out;
  const int nm = static_cast<int>(c.materials.size());
  // Each ball material against wall material `mat`: the case's contact, or
  // its [[pairs]] entry for the two.
  auto interactions_with = [&](const std::string& mat) {
    std::vector<Interaction> v;
    for (int a = 0; a < nm; ++a) {
      Interaction in = c.contact;
      for (const PairOverride& p : c.pairs)
        if ((p.a == c.materials[a].name && p.b == mat) || (p.b == c.materials[a].name && p.a == mat)) in = p.interaction;
      v.push_back(in);
    }
    return v;
  };
  for (std::size_t k = 0; k < c.meshes.size(); ++k) {
    const MeshSpec& spec = c.meshes[k];
    const std::string key = "walls.mesh[" + std::to_string(k) + "]";
    WallMesh m;
    m.name = spec.file;
    m.turning = spec.turning;
    m.part = spec.part;
    const std::string mat = spec.material.empty() ? c.liner : spec.material;
    const int mi = material_index(c, mat);
    if (mi < 0) fail(key + ".material", "unknown material \"" + mat + "\"");
    m.material = c.materials[mi];
    m.interactions = interactions_with(mat);
    const std::vector<Triangle> placed = placed_mesh_triangles(spec);
    m.volume = closed_mesh_volume(placed);
    for (const Triangle& t : placed)
      if (!on_periodic_seam(t, c)) m.triangles.push_back(t);
    out.push_back(std::move(m));
  }
  // The ends (mill.ends = "cones", [end_lifters]): cone heads with their trunnion discs, and end
  // lifters, in the liner's material, turning with the mill.
  const double R = 0.5 * c.diameter;
  const int li = material_index(c, c.liner);
  auto end_mesh = [&](const char* name, std::vector<Triangle> t) {
    WallMesh m;
    m.name = name;
    m.part = MeshPart::ends;
    m.material = c.materials[li];
    m.interactions = interactions_with(c.liner);
    m.triangles = std::move(t);
    m.volume = 0;
    out.push_back(std::move(m));
  };
  EndsSpec ends = c.ends;
  ends.lifter_first_angle_deg = c.lifter_first_angle_deg;
  if (ends.cones())
    end_mesh("cone ends", cone_triangles(ends, R, c.length, std::clamp(4 * c.lifter_rows, 96, 256)));
  if (ends.lifter_rows > 0) end_mesh("end lifters", end_lifter_triangles(ends, R, c.length));
  Walls w;
  w.shell_radius = R;
  w.length = c.length;
  w.periodic = c.periodic;
  w.end_plates = !ends.cones();
  w.meshes = out;
  try {
    check_meshes(w);
  } catch (const std::invalid_argument& e) {
    // Name the key of the mesh at fault (check_meshes names its file).
    const std::string msg = e.what();
    for (std::size_t k = 0; k < out.size(); ++k)
      if (msg.rfind(out[k].name + ":", 0) == 0)
        fail(k < c.meshes.size() ? "walls.mesh[" + std::to_string(k) + "]" : std::string("ends"), msg);
    throw;
  }
  return out;
}

Scene build_walls(const MillCase& c, const MillDerived& d) {
  Scene s;
  // Ball materials are the case's materials; the liner is the wall material.
  s.materials = c.materials;
  s.wall_material = c.materials[material_index(c, c.liner)];
  const int nm = static_cast<int>(c.materials.size());
  s.set_all_interactions(c.contact);
  auto name_of = [&](int k) { return k == nm ? c.liner : c.materials[k].name; };
  for (int a = 0; a <= nm; ++a)
    for (int b = a; b <= nm; ++b)
      for (const PairOverride& p : c.pairs)
        if ((p.a == name_of(a) && p.b == name_of(b)) || (p.a == name_of(b) && p.b == name_of(a)))
          s.set_interaction(a, b, p.interaction);

  const double R = 0.5 * c.diameter;
  s.walls.shell_radius = R;
  s.walls.length = c.length;
  s.walls.periodic = c.periodic;
  s.walls.lifter_first_angle = c.lifter_first_angle_deg * kPi / 180.0;
  s.walls.lifters = lifter_rows(R, c.lifter_rows, c.lifter_pattern, s.walls.lifter_first_angle);
  s.walls.meshes = place_meshes(c);
  s.walls.end_plates = !c.ends.cones();
  for (int p = 0; p < 2; ++p) s.walls.plate_depth[p] = c.plate_depth[p];
  s.liner = c.liner_grid;
  s.numerics.law = c.law;
  s.numerics.precision = c.precision;
  s.numerics.dt = d.dt;
  s.mill_omega = d.omega;
  return s;
}

}  // namespace mc
