// millcharge_law_probe: what one ball-ball contact costs when the contact
// law runs in SIMD lanes, against the same law one pair at a time
// (cl/law_probe.cl). Issue 5's question of what limits the next factor of
// two on a CPU: in the solver's per-ball loop the law runs one pair at a
// time. Usage:
//   build/millcharge_law_probe [--device SPEC] [--pairs N]
// Prints one line per form: nanoseconds per pair (the best of 30 launches).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "compute/buffer.h"
#include "compute/context.h"
#include "compute/program.h"
#include "core/scene.h"
#include "core/layout.hpp"
#include "sim/tables.h"

namespace {

using namespace mc;
using compute::Buffer;

// Steel on steel as a case's defaults give it (Material's), Hertz, e = 0.4,
// friction 0.4, rolling friction 0.01: the coefficients the solver derives.
Scene steel_scene() {
  Scene s;
  s.materials = {Material{"steel"}};
  s.wall_material = Material{"steel"};
  Interaction in;
  in.restitution = 0.4;
  in.mu_slide = 0.4;
  in.mu_roll = 0.01;
  s.set_all_interactions(in);
  s.numerics.law = ContactLaw::hertz;
  return s;
}

// A lattice of 20 mm balls 19.9 mm apart (every pair of neighbours overlaps
// by 0.1 mm), random speeds and spins; `pairs` neighbour pairs in the order
// of their lower ball, as a half list holds them.
struct Charge {
  std::vector<f32::real4> pos, vel, omega;
  std::vector<int> ball_i, ball_j;
  std::vector<float> spring;
};

Charge make_charge(const Scene& scene, int pairs) {
  const int side = 60, layers = (pairs / 3) / ((side - 1) * (side - 1)) + 2;
  const int balls = side * side * layers;
  const float r = 0.01f;
  Ball ball;
  ball.radius = r;
  const float m = static_cast<float>(ball_mass(scene, ball));
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1, 1);
  Charge c;
  for (int b = 0; b < balls; ++b) {
    const int x = b % side, y = (b / side) % side, z = b / (side * side);
    c.pos.push_back({0.0199f * x, 0.0199f * y, 0.0199f * z, r});
    c.vel.push_back({0.5f * u(rng), 0.5f * u(rng), 0.5f * u(rng), 1 / m});
    c.omega.push_back({20 * u(rng), 20 * u(rng), 20 * u(rng), 1 / (0.4f * m * r * r)});
  }
  // Each ball lists its +x, +y and +z neighbours that lie in the lattice.
  for (int b = 0; static_cast<int>(c.ball_i.size()) < pairs; ++b) {
    const int x = b % side, y = (b / side) % side;
    const int next[3] = {x + 1 < side ? b + 1 : -1, y + 1 < side ? b + side : -1, b + side * side};
    for (int d = 0; d < 3 && static_cast<int>(c.ball_i.size()) < pairs; ++d)
      if (next[d] >= 0) {
        c.ball_i.push_back(b);
        c.ball_j.push_back(next[d]);
      }
  }
  c.spring.resize(3 * static_cast<std::size_t>(pairs));
  for (float& s : c.spring) s = 1e-6f * u(rng);
  return c;
}

double time_form(compute::Context& ctx, const f64::PairParams& steel, const Charge& c, bool lanes,
                 double* force_check) {
  compute::BuildOptions opt;
  if (lanes) opt.define("MC_PROBE_LANES");
  compute::Program prog(ctx, {"law_probe.cl"}, opt, false);
  compute::Kernel k(prog, "law_probe");
  const int n = static_cast<int>(c.ball_i.size());
  auto upload = [&](auto& buf, const auto& v) {
    buf.host.assign(v.begin(), v.end());
    buf.write_to_device();
  };
  Buffer<f32::PairParams> pairs(ctx, 1, "pairs");
  pairs.host[0] = {float(steel.kn),      float(steel.kt_over_kn), float(steel.e_star),  float(steel.g_star),
                   float(steel.damping), float(steel.mu_slide),   float(steel.mu_roll), float(steel.restitution)};
  pairs.write_to_device();
  Buffer<int> bi(ctx, n, "ball_i"), bj(ctx, n, "ball_j");
  Buffer<f32::real4> pos(ctx, c.pos.size(), "pos"), vel(ctx, c.pos.size(), "vel"), om(ctx, c.pos.size(), "omega");
  Buffer<float> spring(ctx, c.spring.size(), "spring"), out(ctx, 10 * static_cast<std::size_t>(n), "out");
  upload(bi, c.ball_i);
  upload(bj, c.ball_j);
  upload(pos, c.pos);
  upload(vel, c.vel);
  upload(om, c.omega);
  upload(spring, c.spring);
  k.args(pairs, bi, bj, pos, vel, om, spring, out, n, 5e-6);
  std::vector<double> t;
  for (int r = 0; r < 31; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    k.launch(n);
    ctx.finish();
    if (r > 0) t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  out.read_from_device();
  double sum = 0;
  for (int p = 0; p < n; ++p) sum += std::fabs(out.host[p]) + std::fabs(out.host[n + p]) + std::fabs(out.host[2 * n + p]);
  *force_check = sum / n;
  return *std::min_element(t.begin(), t.end()) / n;
}

}  // namespace

int main(int argc, char** argv) {
  std::string device;
  int pairs = 300000;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--device" && a + 1 < argc) {
      device = argv[++a];
    } else if (arg == "--pairs" && a + 1 < argc) {
      pairs = std::atoi(argv[++a]);
    } else {
      std::fprintf(stderr, "usage: millcharge_law_probe [--device SPEC] [--pairs N]\n");
      return 2;
    }
  }
  if (pairs < 1000) {
    std::fprintf(stderr, "millcharge_law_probe: --pairs must be at least 1000 (got %d)\n", pairs);
    return 2;
  }
  try {
    compute::Context ctx(device);
    const Scene scene = steel_scene();
    const f64::PairParams steel = scene_tables(scene).pairs[0];
    const Charge c = make_charge(scene, pairs);
    double f_one = 0, f_lanes = 0;
    const double one = time_form(ctx, steel, c, false, &f_one);
    const double lanes = time_form(ctx, steel, c, true, &f_lanes);
    std::printf("device: %s, %d compute units; %d touching pairs, float, Hertz\n", ctx.info().label().c_str(),
                ctx.info().compute_units, pairs);
    std::printf("one pair at a time: %.1f ns per pair (mean |F| %.4g N)\n", 1e9 * one, f_one);
    std::printf("in SIMD lanes:      %.1f ns per pair (mean |F| %.4g N), %.1fx\n", 1e9 * lanes, f_lanes, one / lanes);
    // Both forms run the same arithmetic: their forces agree.
    if (!(std::fabs(f_one - f_lanes) <= 1e-4 * f_one)) {
      std::fprintf(stderr, "millcharge_law_probe: the two forms disagree (%.6g vs %.6g N)\n", f_one, f_lanes);
      return 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "millcharge_law_probe: %s\n", e.what());
    return 1;
  }
}
