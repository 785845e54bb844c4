// Mesh-wall test scenes (tests/test_mesh.cpp, tests/test_mesh_cone.cpp): a
// plate of irregular triangles, one steel ball above a plate or a mesh, and
// what the solver makes of it at the first step.
#pragma once

#include <random>
#include <utility>
#include <vector>

#include "core/scene.h"
#include "helpers.h"

namespace mc::test {

inline const Material kSteel{"steel", 7800, 2e11, 0.3};

// A square plate [-h, h]² at z = 0 facing +z: an n × n grid of points, the
// inner ones moved at random by up to `jitter` of the spacing, each square
// cut along a random diagonal.
inline std::vector<Triangle> irregular_plate(double h, int n, double jitter, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double step = 2 * h / n;
  std::vector<Vec3> p((n + 1) * (n + 1));
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const bool inner = i > 0 && i < n && j > 0 && j < n;
      p[j * (n + 1) + i] = {-h + i * step + (inner ? jitter * step * u(rng) : 0.0),
                            -h + j * step + (inner ? jitter * step * u(rng) : 0.0), 0.0};
    }
  std::vector<Triangle> t;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Vec3 a = p[j * (n + 1) + i], b = p[j * (n + 1) + i + 1], c = p[(j + 1) * (n + 1) + i + 1],
                 d = p[(j + 1) * (n + 1) + i];
      if (u(rng) > 0) {
        t.push_back({{a, b, c}});
        t.push_back({{a, c, d}});
      } else {
        t.push_back({{a, b, d}});
        t.push_back({{b, c, d}});
      }
    }
  return t;
}

inline WallMesh mesh_of(std::vector<Triangle> t, const Scene& s) {
  WallMesh m;
  m.name = "plate";
  m.triangles = std::move(t);
  m.material = s.wall_material;
  m.interactions = {s.interaction(0, s.wall_index())};
  return m;
}

// One steel ball above a plate at z = 0 under gravity along −z: the
// analytic end plate (walls.length > 0) or a mesh.
inline Scene plate_scene(ContactLaw law, const std::vector<Triangle>* mesh) {
  Interaction in;
  in.restitution = 0.5;
  in.mu_slide = 0.3;
  in.mu_roll = 0.02;
  in.kn = 1e5;
  Scene s = bare_scene(kSteel, kSteel, in, law, Precision::double_);
  s.numerics.gravity = {0, 0, -9.81};
  s.numerics.dt = law == ContactLaw::linear ? 5e-5 : 2e-6;
  if (mesh) s.walls.meshes = {mesh_of(*mesh, s)};
  else s.walls.length = 50.0;  // the plate at z = 0; the other far away
  Ball b;
  b.radius = 0.02;
  b.position = {0.013, -0.021, 0.06};
  b.velocity = {0.8, 0.35, -0.9};
  b.omega = {4.0, -3.0, 2.0};
  s.balls = {b};
  return s;
}

inline Vec3 force_on(const Scene& s) {
  auto solver = make_solver(context(), s);
  return solver->balls().at(0).force;
}

inline double wall_contacts(const Scene& s) { return make_solver(context(), s)->contact_stats().wall_contacts_per_ball; }

}  // namespace mc::test
