#include "checks.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <stdexcept>

#include "core/drum.h"
#include "helpers.h"
#include "io/case_file.h"
#include "core/layout.hpp"

namespace mc::checks {

using test::bare_scene;
using test::kPi;
using test::rigid_wall;
using test::sphere_mass;

HertzTheory hertz_theory(double e_star, double r_eff, double m_eff, double v) {
  HertzTheory h;
  h.delta_max = std::pow(15.0 * m_eff * v * v / (16.0 * e_star * std::sqrt(r_eff)), 0.4);
  h.f_max = 4.0 / 3.0 * e_star * std::sqrt(r_eff) * std::pow(h.delta_max, 1.5);
  h.t_contact = 2.868 * std::pow(m_eff * m_eff / (r_eff * e_star * e_star * v), 0.2);
  return h;
}

namespace {

struct Measured {
  double delta_max = 0, f_max = 0, t_contact = 0;
  Vec3 v_after, w_after;
};

// Steps until the contact has ended; the overlap comes from `overlap_of`.
// Entry and exit are interpolated inside their steps.
template <class OverlapFn>
Measured run_impact(Solver& s, int ball, OverlapFn overlap_of, long max_steps) {
  Measured m;
  bool touched = false;
  double prev_overlap = 0;
  double t_first = 0;
  for (long k = 0; k < max_steps; ++k) {
    const auto b = s.balls();
    const double ov = overlap_of(b);
    const double f = b[ball].force.norm();
    if (ov > 0) {
      if (!touched) t_first = s.time_s() - s.dt() * ov / (ov - prev_overlap);
      touched = true;
      m.delta_max = std::max(m.delta_max, ov);
      m.f_max = std::max(m.f_max, f);
    } else if (touched) {
      const double t_last = s.time_s() - s.dt() * (-ov) / (prev_overlap - ov);
      m.t_contact = t_last - t_first;
      m.v_after = b[ball].velocity;
      m.w_after = b[ball].omega;
      return m;
    }
    prev_overlap = ov;
    s.advance(1);
  }
  throw std::runtime_error("the contact did not end within " + std::to_string(max_steps) + " steps");
}

Material material_of(const BenchMaterial& b) { return Material{b.name, b.density, b.youngs_modulus, b.poisson_ratio}; }

}  // namespace

const std::vector<BenchMaterial>& chung_ooi_1_materials() {
  static const std::vector<BenchMaterial> m = {{"glass", 4.8e10, 0.20, 2800, 274e-6, 10.70e3, 40.3e-6},
                                               {"limestone", 2.0e10, 0.25, 2500, 368e-6, 7.11e3, 54.2e-6}};
  return m;
}

NormalImpact chung_ooi_1(compute::Context& ctx, const BenchMaterial& bm, Precision precision) {
  const double r = 0.010, v = 10.0;
  const Material mat = material_of(bm);
  Interaction in;
  in.restitution = 1.0;
  in.mu_slide = 0.0;
  Scene sc = bare_scene(mat, mat, in, ContactLaw::hertz, precision);
  const double m = sphere_mass(bm.density, r);
  const PairCoefficients pc = pair_coefficients(sc, 0, 0);
  NormalImpact out;
  out.theory = hertz_theory(pc.e_star, r / 2, m / 2, 2 * v);
  sc.numerics.dt = out.theory.t_contact / 400;
  Ball a, b;
  a.id = 0; a.radius = r; a.position = {-r - 0.2 * out.theory.delta_max, 0, 0}; a.velocity = {v, 0, 0};
  b.id = 1; b.radius = r; b.position = {r + 0.2 * out.theory.delta_max, 0, 0}; b.velocity = {-v, 0, 0};
  sc.balls = {a, b};
  auto s = make_solver(ctx, sc);
  const Measured me = run_impact(
      *s, 0, [&](const std::vector<BallState>& bs) { return 2 * r - (bs[1].position - bs[0].position).norm(); },
      2000);
  out.delta_max = me.delta_max;
  out.f_max = me.f_max;
  out.t_contact = me.t_contact;
  out.rebound_speed_ratio = -me.v_after.x / v;
  return out;
}

const std::vector<BenchMaterial>& chung_ooi_2_materials() {
  static const std::vector<BenchMaterial> m = {{"Al alloy", 7.0e10, 0.30, 2699, 49.7e-6, 11.37e3, 0.732e-3},
                                               {"Mg alloy", 4.0e10, 0.35, 1800, 52.1e-6, 7.23e3, 0.767e-3}};
  return m;
}

NormalImpact chung_ooi_2(compute::Context& ctx, const BenchMaterial& bm) {
  const double r = 0.10, v = 0.2;
  const Material mat = material_of(bm);
  Interaction in;
  in.restitution = 1.0;
  in.mu_slide = 0.0;
  Scene sc = bare_scene(mat, rigid_wall(), in, ContactLaw::hertz);
  sc.walls.length = 10.0;  // the end plate at z = 0 is the wall
  const double m = sphere_mass(bm.density, r);
  const PairCoefficients pc = pair_coefficients(sc, 0, 1);
  NormalImpact out;
  out.theory = hertz_theory(pc.e_star, r, m, v);
  sc.numerics.dt = out.theory.t_contact / 400;
  Ball a;
  a.radius = r;
  a.position = {0, 0, r + 0.2 * out.theory.delta_max};
  a.velocity = {0, 0, -v};
  sc.balls = {a};
  auto s = make_solver(ctx, sc);
  const Measured me =
      run_impact(*s, 0, [&](const std::vector<BallState>& bs) { return r - bs[0].position.z; }, 2000);
  out.delta_max = me.delta_max;
  out.f_max = me.f_max;
  out.t_contact = me.t_contact;
  out.rebound_speed_ratio = me.v_after.z / v;
  return out;
}

const std::vector<Material>& chung_ooi_3_materials() {
  static const std::vector<Material> m = {{"alumina", 4000, 3.8e11, 0.23}, {"cast iron", 7000, 1.0e11, 0.25}};
  return m;
}

double chung_ooi_3(compute::Context& ctx, ContactLaw law, const Material& mat, double e) {
  const double r = 0.0025, v = 3.9;
  Interaction in;
  in.restitution = e;
  in.mu_slide = 0.0;
  in.kn = 1.0e7;
  Scene sc = bare_scene(mat, rigid_wall(), in, law);
  sc.walls.length = 1.0;
  const double m = sphere_mass(mat.density, r);
  const PairCoefficients pc = pair_coefficients(sc, 0, 1);
  const double tc =
      law == ContactLaw::hertz ? hertz_theory(pc.e_star, r, m, v).t_contact : kPi * std::sqrt(m / in.kn);
  sc.numerics.dt = tc / 200;
  Ball a;
  a.radius = r;
  a.position = {0, 0, r + 1e-7};
  a.velocity = {0, 0, -v};
  sc.balls = {a};
  auto s = make_solver(ctx, sc);
  const Measured me =
      run_impact(*s, 0, [&](const std::vector<BallState>& bs) { return r - bs[0].position.z; }, 4000);
  return me.v_after.z / v;
}

const std::vector<Material>& chung_ooi_4_materials() {
  static const std::vector<Material> m = {{"alumina", 4000, 3.8e11, 0.23}, {"Al alloy", 2700, 7.0e10, 0.33}};
  return m;
}

ObliqueImpact chung_ooi_4(compute::Context& ctx, const Material& mat, double theta_deg) {
  const double e = 0.98, mu = 0.092, r = 0.0025, speed = 3.9;
  Interaction in;
  in.restitution = e;
  in.mu_slide = mu;
  Scene sc = bare_scene(mat, rigid_wall(), in, ContactLaw::hertz);
  sc.walls.length = 1.0;
  const double th = theta_deg * kPi / 180;
  const double vn = speed * std::cos(th), vt = speed * std::sin(th);
  const double m = sphere_mass(mat.density, r);
  const PairCoefficients pc = pair_coefficients(sc, 0, 1);
  sc.numerics.dt = hertz_theory(pc.e_star, r, m, vn).t_contact / 200;
  Ball a;
  a.radius = r;
  a.position = {0, 0, r + 1e-7};
  a.velocity = {vt, 0, -vn};
  sc.balls = {a};
  auto s = make_solver(ctx, sc);
  const Measured me =
      run_impact(*s, 0, [&](const std::vector<BallState>& bs) { return r - bs[0].position.z; }, 4000);
  ObliqueImpact out;
  out.et_theory = 1 - mu * (1 + e) / std::tan(th);
  out.spin_theory = 5 * mu * (1 + e) * vn / (2 * r);
  out.et = me.v_after.x / vt;
  // Friction acts along −x at the contact below the centre: spin about +y.
  out.spin = me.w_after.y;
  return out;
}

Rolling sliding_to_rolling(compute::Context& ctx, ContactLaw law) {
  const Material steel{"steel", 7800, 2e11, 0.3};
  Interaction in;
  in.restitution = 0.5;
  in.mu_slide = 0.3;
  in.kn = 1e6;
  Scene sc = bare_scene(steel, steel, in, law);
  sc.numerics.gravity = {0, 0, -9.81};
  sc.walls.length = 10.0;  // the floor is the plate z = 0
  sc.wall_material.wear_coefficient = 1e-13;  // the k docs/validation.md states (any k: the books are linear in it)
  const double r = 0.01, v0 = 1.0;
  const double m = sphere_mass(7800, r);
  // Resting overlap under gravity, so the ball starts settled.
  const PairCoefficients pc = pair_coefficients(sc, 0, 1);
  const double w = m * 9.81;
  const double rest = law == ContactLaw::hertz ? std::pow(w / (4.0 / 3.0 * pc.e_star * std::sqrt(r)), 2.0 / 3.0)
                                               : w / in.kn;
  sc.numerics.dt = law == ContactLaw::hertz ? 2e-6 : kPi * std::sqrt(m / in.kn) / 40;
  Ball b;
  b.radius = r;
  b.position = {0, 0, r - rest};
  b.velocity = {v0, 0, 0};
  sc.balls = {b};
  auto s = make_solver(ctx, sc);
  // Sliding lasts 2·v0/(7·μ·g) ≈ 0.097 s; run well past it.
  const double t_slide = 2 * v0 / (7 * 0.3 * 9.81);
  s->advance(static_cast<long>(1.5 * t_slide / sc.numerics.dt));
  const auto bs = s->balls();
  Rolling out;
  out.speed_ratio = bs[0].velocity.x / v0;
  out.slip_ratio = bs[0].omega.y * r / bs[0].velocity.x;
  const BookSums books = s->read_books();
  for (int e = 0; e < books.n_elements; ++e) {
    out.shear_J += books.liner_at(e, MC_LINER_SHEAR);
    out.wear_m3 += books.liner_at(e, MC_LINER_WEAR);
  }
  const double slid = v0 * v0 / (7 * in.mu_slide * 9.81);
  out.shear_theory_J = in.mu_slide * w * slid;
  out.wear_theory_m3 = sc.wall_material.wear_coefficient * w * slid;
  return out;
}

ShellFlight shell_flight(compute::Context& ctx, double phi) {
  // With sliding and rolling friction high, the ball turns with the shell as
  // one body until the normal force vanishes. Slip starts where
  // sin α = μ(φ² − cos α), within 0.1° of cos α = φ² for μ = 1000. The
  // damping sees velocities half a step old (leapfrog, as LIGGGHTS' velocity
  // Verlet), which on a circular path reads as a normal speed v·ω·dt/2 and
  // shifts the departure by O(dt): 2.2° at φ = 0.9 with 40 steps per
  // contact, so 160 are used here.
  const Material steel{"steel", 7800, 2e11, 0.3};
  Interaction in;
  in.restitution = 0.3;
  in.mu_slide = 1000.0;
  in.mu_roll = 1000.0;
  // Soft enough that the overlap (~2.5e-5 m) is hundreds of float ulps at
  // 0.5 m from the axis; with kn = 1e6 it is ~8 ulps and round-off jitter
  // opens the contact early.
  in.kn = 2e4;
  Scene sc = bare_scene(steel, steel, in, ContactLaw::linear);
  sc.numerics.gravity = {0, -9.81, 0};
  const double D = 1.02, r = 0.01, Rb = 0.5 * D - r, g = 9.81;
  sc.walls.shell_radius = 0.5 * D;
  sc.walls.length = 0.1;
  const double omega = phi * std::sqrt(g / Rb);
  sc.mill_omega = omega;
  const double m = sphere_mass(7800, r);
  sc.numerics.dt = kPi * std::sqrt(m / in.kn) / 160;
  Ball b;
  b.radius = r;
  const double rest = m * g * (1 + phi * phi) / in.kn;
  b.position = {0, -(Rb + rest), 0.05};
  b.velocity = {omega * Rb, 0, 0};
  b.omega = {0, 0, omega};
  sc.balls = {b};
  auto s = make_solver(ctx, sc);

  ShellFlight out;
  const double alpha = std::acos(phi * phi);
  out.departure_theory_deg = alpha * 180 / kPi;
  out.landing_theory_deg = 3 * out.departure_theory_deg;
  out.flight_theory_s = 4 * omega * Rb * std::sin(alpha) / g;
  // Departure: the first sample on the rising side past 3 o'clock with the
  // ball clear of the shell; landing: the first sample after it touching the
  // shell again, its angle counter-clockwise from the top.
  const long max_steps = static_cast<long>(1.0 / (omega / (2 * kPi)) / sc.numerics.dt);
  double t_departure = 0;
  for (long k = 0; k < max_steps; k += 10) {
    s->advance(10);
    const Vec3 p = s->balls()[0].position;
    const double rho = std::hypot(p.x, p.y);
    if (out.departure_deg < 0) {
      if (p.y > 0 && p.x > 0 && rho + r < 0.5 * D) {
        out.departure_deg = std::atan2(p.x, p.y) * 180 / kPi;
        t_departure = s->time_s();
      }
    } else if (rho + r >= 0.5 * D) {
      out.landing_deg = std::fmod(std::atan2(-p.x, p.y) * 180 / kPi + 360, 360);
      out.flight_s = s->time_s() - t_departure;
      break;
    }
  }
  return out;
}

ElasticBox elastic_box(compute::Context& ctx, ContactLaw law) {
  // e = 1, μ = 0, no rolling resistance: only the integrator can change the
  // energy (kinetic + rotational + gravity + elastic in contacts).
  DrumSpec spec;
  spec.n_balls = 300;
  spec.restitution = 1.0;
  spec.mu_slide = 0.0;
  spec.mu_roll = 0.0;
  spec.speed_fraction = 0.0;
  spec.law = law;
  Scene sc = make_drum(spec);
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (Ball& b : sc.balls) b.velocity = {gauss(rng), gauss(rng), gauss(rng)};
  auto s = make_solver(ctx, sc);
  const double e0 = s->observe(true).total_energy();
  const double scale = s->observe(false).kinetic_J;  // gravity's zero is arbitrary
  ElasticBox out;
  for (int k = 0; k < 10; ++k) {
    s->advance(1000);
    const Observables o = s->observe(true);
    out.worst_drift = std::max(out.worst_drift, std::fabs(o.total_energy() - e0) / scale);
    out.samples_with_contacts += o.elastic_J > 0;
  }
  out.dissipated_J = s->observe(false).dissipated_J;
  return out;
}

PowerBalance drum_power_balance(compute::Context& ctx, ContactLaw law) {
  DrumSpec spec;  // 0.3 m drum, 8 lifters, 75 % of critical
  spec.n_balls = 300;
  spec.law = law;
  return drum_power_balance(ctx, spec, 1.5, 3);  // warm-up: charge lifted and cycling
}

PowerBalance drum_power_balance(compute::Context& ctx, const DrumSpec& spec, double warmup_s, int revolutions,
                                const char* forces) {
  const Scene sc = make_drum(spec);
  if (forces) ::setenv("MILLCHARGE_FORCES", forces, 1);
  auto s = make_solver(ctx, sc);
  if (forces) ::unsetenv("MILLCHARGE_FORCES");
  const double rev_s = 2 * kPi / sc.mill_omega;
  s->advance(static_cast<long>(warmup_s / sc.numerics.dt));
  const double e_start = s->observe(true).total_energy();
  s->advance(static_cast<long>(revolutions * rev_s / sc.numerics.dt));
  const Observables o = s->observe(true);
  PowerBalance out;
  out.window_s = o.interval_s;
  out.torque_power_W = o.torque_power_W;
  out.dissipation_power_W = o.dissipation_power_W;
  out.energy_change_W = (o.total_energy() - e_start) / o.interval_s;
  out.torque_times_omega_W = o.wall_torque_Nm * sc.mill_omega;
  return out;
}

LabRun lab_run(compute::Context& ctx, const std::vector<std::string>& overrides) {
  return case_run(ctx, io::default_case(), overrides);
}

LabRun case_run(compute::Context& ctx, const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  LabRun r;
  r.c = io::read_case(file, overrides);
  r.d = derive(r.c);
  r.scene = build_scene(r.c, r.d);
  auto solver = make_solver(ctx, r.scene);
  r.s = run_mill(*solver, r.scene, r.c, r.d, {});
  return r;
}

}  // namespace mc::checks
