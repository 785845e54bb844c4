// The device tables of a scene, derived once in double: run parameters (all
// but the grid), the material-pair table and the lifter polygons. The solver
// converts them to its precision; the CPU reference uses them as they are,
// so both always see the same derived values.
#pragma once

#include <array>
#include <vector>

#include "core/wall_mesh.h"

#include "core/scene.h"
#include "core/layout.hpp"
#include "sim/solver.h"

namespace mc {

struct SceneTables {
  f64::SimParams params{};  // grid fields left zero
  std::vector<f64::PairParams> pairs;
  std::vector<f64::LifterPolygon> lifters;  // at least one entry
  f64::BookParams books{};                  // spectra and liner (core/liner.h)
  // Mesh walls (cl/mesh.h): triangles in the device order, each feature's
  // (smooth patch, wall type), each set's grid (cells not yet filled:
  // mesh_cells), the pair table ball material × mesh material (at least
  // one entry each).
  std::vector<f64::MeshTriangle> mesh_tris;
  std::vector<f64::int2> mesh_feature;
  // The triangles round each feature (cl/mesh.h Meshes.adj): features + 1
  // starts, counted from the table's beginning, then the lists.
  std::vector<int> mesh_adj;
  std::array<f64::MeshGrid, MC_MESH_SETS> mesh_grid{};
  std::vector<f64::PairParams> mesh_pairs;
  int mesh_cells = 0;  // both sets' cells
  // Each set's triangles as the host has them, for binning on the host.
  std::array<std::vector<Triangle>, MC_MESH_SETS> mesh_set_triangles;
  std::array<MeshGridSpec, MC_MESH_SETS> mesh_grid_specs;
  // The axial extent of every mesh triangle (mesh_z1 < mesh_z0: no meshes).
  double mesh_z0 = 1e300, mesh_z1 = -1e300;
};

// The mesh grid's cells on the host, as cl/mesh_bin.cl fills them on the
// device: starts (mesh_cells + 1) and the triangles of each cell.
void mesh_cells_host(const SceneTables& t, std::vector<int>& starts, std::vector<int>& tris);

SceneTables scene_tables(const Scene& scene);

// The rigid bodies of a scene (cl/body.h) as the device holds them, in
// double; empty vectors but for one entry each when there are none.
struct BodyTables {
  int n_bodies = 0;
  int first_component = 0;  // ids from here on are components (n balls: none)
  std::vector<f64::int2> body_comp;   // per body: first component id, count
  std::vector<int> body_of;           // per component (id − first_component): its body
  std::vector<f64::real4> comp_offset;  // per component: centre in the body frame
  std::vector<f64::real4> body_pos, body_vel, body_quat, body_angmom, body_inv_inertia;
};
BodyTables body_tables(const Scene& scene);

// The balls sorted by id, with each body's components placed, moving and
// spinning as its body (core/scene.h Body), and each ball's 1/m and 1/I for
// the device's velocity and spin w: a free ball's own; a component's body's
// 1/M and largest principal 1/I (cl/body.h).
struct DeviceBall {
  Ball ball;
  double inv_mass = 0, inv_inertia = 0;
};
std::vector<DeviceBall> device_balls(const Scene& scene);

// A ball as the host reports it, velocities synchronised to the step:
// v(n) = v(n−½) + ½·dt·F(n)/m (the arrays hold 1/m and 1/I in .w).
template <class real4>
BallState ball_state(int id, int material, const real4& p, const real4& v, const real4& w,
                     const real4& f, const real4& t, double dt) {
  const double h = 0.5 * dt;
  BallState b;
  b.id = id;
  b.material = material;
  b.radius = p.w;
  b.position = {p.x, p.y, p.z};
  b.velocity = {v.x + h * f.x * v.w, v.y + h * f.y * v.w, v.z + h * f.z * v.w};
  b.omega = {w.x + h * t.x * w.w, w.y + h * t.y * w.w, w.z + h * t.z * w.w};
  b.force = {f.x, f.y, f.z};
  b.torque = {t.x, t.y, t.z};
  return b;
}

// A body as the host reports it, from the device arrays (cl/body.h):
// v(n) and L(n) from v(n−½), L(n−½) and F(n), T(n).
template <class real4>
BodyState body_state(const real4& p, const real4& v, const real4& q, const real4& L, const real4& inv_i,
                     const real4& f, const real4& t, double dt) {
  const double h = 0.5 * dt;
  BodyState b;
  b.position = {p.x, p.y, p.z};
  b.velocity = {v.x + h * f.x * p.w, v.y + h * f.y * p.w, v.z + h * f.z * p.w};
  b.orientation = {double(q.x), double(q.y), double(q.z), double(q.w)};
  const std::array<double, 4> qi{-double(q.x), -double(q.y), -double(q.z), double(q.w)};
  const Vec3 tb = rotate(qi, Vec3{t.x, t.y, t.z});
  const Vec3 Lb{L.x + h * tb.x, L.y + h * tb.y, L.z + h * tb.z};
  const Vec3 wb{Lb.x * inv_i.x, Lb.y * inv_i.y, Lb.z * inv_i.z};
  b.angular_momentum = rotate(b.orientation, Lb);
  b.omega = rotate(b.orientation, wb);
  b.kinetic_J = 0.5 * b.velocity.dot(b.velocity) / p.w;
  b.rotational_J = 0.5 * (Lb.x * wb.x + Lb.y * wb.y + Lb.z * wb.z);
  return b;
}

}  // namespace mc
