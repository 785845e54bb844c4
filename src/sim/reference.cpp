#include "sim/reference.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "sim/layout.hpp"

namespace mc {

using namespace mc::f64;

struct ReferenceSolver::State {
  SimParams sp{};
  std::vector<PairParams> pairs;
  std::vector<LifterPolygon> lifters;
  std::vector<real4> pos, vel, omega, force, torque, accum, pos_at_build;
  std::vector<int2> info;
  std::vector<int> wall_key;
  std::vector<real4> wall_hist;
  std::vector<int> neigh_start, neigh_count, neigh_index;
  std::vector<real4> neigh_hist;
  std::map<std::pair<int, int>, real4> history;  // (i, j) → spring, by index
  int status = 0;
  double time = 0, angle = 0, omega_mill = 0;
  int n = 0;

  void build_lists() {
    // Every pair within touching distance, with its spring carried over.
    std::map<std::pair<int, int>, real4> kept;
    neigh_index.clear();
    neigh_hist.clear();
    for (int i = 0; i < n; ++i) {
      neigh_start[i] = static_cast<int>(neigh_index.size());
      for (int j = 0; j < n; ++j) {
        if (j == i) continue;
        const double dx = pos[i].x - pos[j].x, dy = pos[i].y - pos[j].y, dz = pos[i].z - pos[j].z;
        const double cut = pos[i].w + pos[j].w;
        if (dx * dx + dy * dy + dz * dz >= cut * cut) continue;
        neigh_index.push_back(j);
        auto it = history.find({i, j});
        neigh_hist.push_back(it != history.end() ? it->second : real4{0, 0, 0, 0});
      }
      neigh_count[i] = static_cast<int>(neigh_index.size()) - neigh_start[i];
    }
  }
  void save_history() {
    history.clear();
    for (int i = 0; i < n; ++i)
      for (int k = neigh_start[i]; k < neigh_start[i] + neigh_count[i]; ++k)
        history[{i, neigh_index[k]}] = neigh_hist[k];
  }
  void forces() {
    build_lists();
    MillState mill{angle, omega_mill};
    for (int i = 0; i < n; ++i)
      ball_forces(i, &sp, pairs.data(), lifters.data(), mill, pos.data(), vel.data(), omega.data(),
                  info.data(), neigh_start.data(), neigh_count.data(), neigh_index.data(),
                  neigh_hist.data(), wall_key.data(), wall_hist.data(), force.data(), torque.data(),
                  accum.data(), &status);
    save_history();
  }
};

ReferenceSolver::ReferenceSolver(const Scene& scene) : s_(std::make_unique<State>()) {
  validate(scene);
  State& s = *s_;
  s.n = static_cast<int>(scene.balls.size());
  const int nm = scene.wall_index();
  for (int a = 0; a <= nm; ++a)
    for (int b = 0; b <= nm; ++b) {
      const PairCoefficients c = pair_coefficients(scene, a, b);
      s.pairs.push_back({c.kn, c.kt_over_kn, c.e_star, c.g_star, c.damping, c.mu_slide, c.mu_roll,
                         c.restitution});
    }
  const Walls& w = scene.walls;
  double r_max = 0;
  for (const Ball& b : scene.balls) r_max = std::max(r_max, b.radius);
  double reach = w.shell_radius;
  for (const auto& poly : w.lifters) {
    LifterPolygon p{};
    p.n_vertices = static_cast<int>(poly.size());
    for (std::size_t v = 0; v < poly.size(); ++v) {
      p.vertices[v] = {poly[v].x, poly[v].y};
      reach = std::min(reach, std::hypot(poly[v].x, poly[v].y));
    }
    s.lifters.push_back(p);
  }
  if (s.lifters.empty()) s.lifters.push_back(LifterPolygon{});
  const int nl = static_cast<int>(w.lifters.size());
  SimParams& sp = s.sp;
  sp.gravity = {scene.numerics.gravity.x, scene.numerics.gravity.y, scene.numerics.gravity.z, 0};
  sp.dt = scene.numerics.dt;
  sp.skin = scene.numerics.skin > 0 ? scene.numerics.skin : default_skin(scene);
  sp.shell_radius = w.shell_radius;
  sp.length = w.length;
  sp.lifter_reach = std::max(0.0, reach - 1.01 * r_max);
  sp.lifter_first_angle = w.lifter_first_angle;
  sp.lifter_spacing = nl > 0 ? 2.0 * M_PI / nl : 1.0;
  sp.n_balls = s.n;
  sp.n_materials = nm;
  sp.n_lifters = nl;
  sp.law = scene.numerics.law == ContactLaw::hertz ? MC_LAW_HERTZ : MC_LAW_LINEAR;

  std::vector<Ball> balls = scene.balls;
  std::sort(balls.begin(), balls.end(), [](const Ball& a, const Ball& b) { return a.id < b.id; });
  const int n = s.n;
  s.pos.resize(n); s.vel.resize(n); s.omega.resize(n); s.force.resize(n); s.torque.resize(n);
  s.accum.assign(n, real4{0, 0, 0, 0}); s.pos_at_build.resize(n); s.info.resize(n);
  s.wall_key.assign(static_cast<std::size_t>(n) * MC_MAX_WALL_CONTACTS, MC_WALL_NONE);
  s.wall_hist.assign(static_cast<std::size_t>(n) * MC_MAX_WALL_CONTACTS, real4{0, 0, 0, 0});
  s.neigh_start.assign(n, 0); s.neigh_count.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    const Ball& b = balls[i];
    const double m = ball_mass(scene, b);
    s.pos[i] = {b.position.x, b.position.y, b.position.z, b.radius};
    s.vel[i] = {b.velocity.x, b.velocity.y, b.velocity.z, 1.0 / m};
    s.omega[i] = {b.omega.x, b.omega.y, b.omega.z, 1.0 / (0.4 * m * b.radius * b.radius)};
    s.info[i] = {b.id, b.material};
  }
  s.pos_at_build = s.pos;
  s.angle = scene.mill_angle;
  s.omega_mill = scene.mill_omega;
  s.forces();
  const double h = 0.5 * sp.dt;
  for (int i = 0; i < n; ++i) {
    s.vel[i].x -= h * s.force[i].x * s.vel[i].w;
    s.vel[i].y -= h * s.force[i].y * s.vel[i].w;
    s.vel[i].z -= h * s.force[i].z * s.vel[i].w;
    s.omega[i].x -= h * s.torque[i].x * s.omega[i].w;
    s.omega[i].y -= h * s.torque[i].y * s.omega[i].w;
    s.omega[i].z -= h * s.torque[i].z * s.omega[i].w;
  }
}

ReferenceSolver::~ReferenceSolver() = default;

void ReferenceSolver::advance(long steps) {
  State& s = *s_;
  for (long k = 0; k < steps; ++k) {
    for (int i = 0; i < s.n; ++i)
      s.status |= integrate_ball(i, &s.sp, s.pos.data(), s.vel.data(), s.omega.data(),
                                 s.force.data(), s.torque.data(), s.pos_at_build.data());
    if (s.status & MC_FLAG_NOT_FINITE) throw std::runtime_error("reference: blow-up");
    s.status = 0;
    s.time += s.sp.dt;
    s.angle = std::fmod(s.angle + s.omega_mill * s.sp.dt, 2.0 * M_PI);
    s.forces();
  }
}

std::vector<BallState> ReferenceSolver::balls() const {
  const State& s = *s_;
  std::vector<BallState> out(s.n);
  const double h = 0.5 * s.sp.dt;
  for (int i = 0; i < s.n; ++i) {
    const real4 &p = s.pos[i], &v = s.vel[i], &w = s.omega[i], &f = s.force[i], &t = s.torque[i];
    BallState& b = out[i];
    b.id = s.info[i].x;
    b.material = s.info[i].y;
    b.radius = p.w;
    b.position = {p.x, p.y, p.z};
    b.velocity = {v.x + h * f.x * v.w, v.y + h * f.y * v.w, v.z + h * f.z * v.w};
    b.omega = {w.x + h * t.x * w.w, w.y + h * t.y * w.w, w.z + h * t.z * w.w};
    b.force = {f.x, f.y, f.z};
    b.torque = {t.x, t.y, t.z};
  }
  std::sort(out.begin(), out.end(), [](const BallState& a, const BallState& b) { return a.id < b.id; });
  return out;
}

double ReferenceSolver::time_s() const { return s_->time; }

}  // namespace mc
