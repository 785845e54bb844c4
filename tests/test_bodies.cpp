// Rigid bodies of spheres (clumps, cl/body.h) in the solver: a free
// asymmetric body keeps its angular momentum and energy and the kernels
// agree with the CPU reference; a flat clump dropped tilted comes to rest
// on its flat face; a peanut sliding across its axis starts rolling at the
// closed form's speed; a turning drum of clumps keeps its books; a saved
// state resumes bit for bit; the case keys and their refusals.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/clump.h"
#include "core/drum.h"
#include "core/mill_case.h"
#include "checks.h"
#include "helpers.h"
#include "text_file.h"
#include "io/case_file.h"
#include "sim/mill_run.h"
#include "sim/reference.h"

using namespace mc;
using namespace mc::test;
namespace fs = std::filesystem;

namespace {

// One clump of `shape` (volume-equivalent diameter d) at `at`, turned by q,
// its components ids first .. first + n - 1.
void add_clump(Scene& sc, const ClumpShape& shape, double d, double density, Vec3 at, std::array<double, 4> q,
               Vec3 velocity = {}, Vec3 omega = {}) {
  const ClumpShape unit = normalised_shape(shape, 1.0);
  const ClumpMassProperties mp = clump_mass_properties(unit);
  Body b;
  b.mass = density * mp.volume * d * d * d;
  b.inertia = mp.principal * (density * std::pow(d, 5));
  b.position = at;
  b.velocity = velocity;
  b.omega = omega;
  b.orientation = q;
  b.first = static_cast<int>(sc.balls.size());
  b.count = static_cast<int>(unit.spheres.size());
  for (const ClumpSphere& s : unit.spheres) {
    Ball ball;
    ball.id = static_cast<int>(sc.balls.size());
    ball.radius = s.radius * d;
    ball.offset = s.centre * d;
    ball.position = at + rotate(q, ball.offset);
    ball.body = static_cast<int>(sc.bodies.size());
    sc.balls.push_back(ball);
  }
  sc.bodies.push_back(b);
}

std::array<double, 4> axis_angle(Vec3 axis, double angle) {
  const double n = axis.norm(), s = std::sin(0.5 * angle) / n;
  return {axis.x * s, axis.y * s, axis.z * s, std::cos(0.5 * angle)};
}

double dist(Vec3 a, Vec3 b) { return (a - b).norm(); }

// A floor: the end plate at z = 0 of a mill with no shell, gravity along -z.
Scene floor_scene(ContactLaw law, Precision prec, double restitution, double mu) {
  const Material rock{"rock", 2700, 5e9, 0.25};
  Interaction in;
  in.restitution = restitution;
  in.mu_slide = mu;
  in.mu_roll = 0;
  in.kn = 2e5;
  Scene sc = bare_scene(rock, rock, in, law, prec);
  sc.walls.length = 1.0;  // plates at z = 0 and z = 1; no shell
  sc.numerics.gravity = {0, 0, -9.81};
  return sc;
}

}  // namespace

TEST_CASE("a free asymmetric clump keeps L and its energy, and the kernels follow the CPU reference", "[bodies]") {
  for (Precision prec : {Precision::double_, Precision::single}) {
    const Material rock{"rock", 2700, 5e9, 0.25};
    Scene sc = bare_scene(rock, rock, Interaction{}, ContactLaw::hertz, prec);
    sc.numerics.dt = 1e-4;
    // A rock (three unequal moments), spun about a line between its axes of
    // least and greatest moment, so that its spin axis wanders (the
    // asymmetric top), drifting; and a free ball beside it.
    Ball ball;
    ball.radius = 0.01;
    ball.position = {0.5, 0, 0};
    ball.velocity = {0.1, 0, 0};
    sc.balls = {ball};
    add_clump(sc, library_shape("rock"), 0.05, 2700, {0, 0, 0}, axis_angle({0.3, 1, 0.2}, 0.7), {0.2, -0.1, 0.05},
              {30, 2, 25});
    auto s = make_solver(context(), sc);
    ReferenceSolver ref(sc);
    const BodyState b0 = s->bodies().at(0);
    const double e0 = b0.kinetic_J + b0.rotational_J;
    const Vec3 L0 = b0.angular_momentum;
    double worst_e = 0, worst_l = 0;
    for (int k = 0; k < 20; ++k) {
      s->advance(500);
      if (prec == Precision::double_) ref.advance(500);
      const BodyState b = s->bodies().at(0);
      worst_e = std::max(worst_e, std::fabs(b.kinetic_J + b.rotational_J - e0) / e0);
      worst_l = std::max(worst_l, dist(b.angular_momentum, L0) / L0.norm());
    }
    const BodyState b = s->bodies().at(0);
    const double t = s->time_s();
    std::printf("free rock, %s, %.1f s (%.0f turns): |dE|/E %.2e, |dL|/|L| %.2e, spin axis moved %.1f deg in the body\n",
                prec == Precision::double_ ? "double" : "float", t, t * b.omega.norm() / (2 * kPi), worst_e, worst_l,
                std::acos(std::min(1.0, b.omega.dot(b0.omega) / (b.omega.norm() * b0.omega.norm()))) * 180 / kPi);
    INFO((prec == Precision::double_ ? "double" : "float"));
    // The splitting keeps L exactly but for rounding, and the energy within
    // a bounded O((ω dt)²) wobble (in float, rounding over 50,000 turns).
    CHECK(worst_e < (prec == Precision::double_ ? 1e-6 : 2e-4));
    CHECK(worst_l < (prec == Precision::double_ ? 1e-12 : 2e-4));
    // The centre drifts at its velocity; the spin axis is not fixed in the lab.
    CHECK(b.position.x == Approx(0.2 * t).margin(prec == Precision::double_ ? 1e-12 : 1e-4));
    CHECK(b.omega.dot(b0.omega) / (b.omega.norm() * b0.omega.norm()) < 0.999);
    // The components sit where the body puts them.
    const auto balls = s->balls();
    for (std::size_t c = 1; c < balls.size(); ++c) {
      const Vec3 expect = b.position + rotate(b.orientation, sc.balls[c].offset);
      CHECK(dist(balls[c].position, expect) < (prec == Precision::double_ ? 1e-12 : 1e-6));
    }
    if (prec == Precision::double_) {
      const auto rb = ref.balls();
      double worst = 0;
      for (std::size_t c = 0; c < balls.size(); ++c) worst = std::max(worst, dist(balls[c].position, rb[c].position));
      std::printf("  kernels against the CPU reference: worst component position difference %.2e m\n", worst);
      CHECK(worst < 1e-12);
    }
  }
}

TEST_CASE("a flat clump dropped tilted comes to rest on its flat face", "[bodies][physics]") {
  for (ContactLaw law : {ContactLaw::hertz, ContactLaw::linear}) {
    Scene sc = floor_scene(law, Precision::single, 0.3, 0.5);
    const double d = 0.03;
    // flat4: four spheres in a square in the body's y-z plane (its axis of
    // least moment along x is the square's normal... the largest moment is
    // about the normal of the plane): tilted 35 degrees, dropped 5 mm.
    const ClumpShape shape = library_shape("flat4");
    const ClumpShape unit = normalised_shape(shape, d);
    double r = unit.spheres[0].radius;
    // The body axis normal to the square: the one its centres do not span.
    Vec3 normal{1, 0, 0};
    for (Vec3 axis : {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}}) {
      double spread = 0;
      for (const ClumpSphere& s : unit.spheres) spread += std::fabs(s.centre.dot(axis));
      if (spread < 1e-9 * d) normal = axis;
    }
    // Turn the normal onto +z, then tilt 35 degrees about x.
    std::array<double, 4> q{0, 0, 0, 1};
    if (normal.x > 0.5) q = axis_angle({0, 1, 0}, -kPi / 2);
    else if (normal.y > 0.5) q = axis_angle({1, 0, 0}, kPi / 2);
    const std::array<double, 4> tilt = axis_angle({1, 0.2, 0}, 35 * kPi / 180);
    auto mul = [](const std::array<double, 4>& a, const std::array<double, 4>& b) {
      return std::array<double, 4>{a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
                                   a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
                                   a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
                                   a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]};
    };
    q = mul(tilt, q);
    double lowest = 1e9;
    for (const ClumpSphere& s : unit.spheres) lowest = std::min(lowest, rotate(q, s.centre).z - s.radius);
    add_clump(sc, shape, d, 2700, {0.5, 0.5, 0.005 - lowest}, q);
    const Material rock = sc.materials[0];
    const double m = sc.bodies[0].mass;
    const double k_contact = law == ContactLaw::linear ? 2e5 : 0;
    sc.numerics.dt = law == ContactLaw::linear ? kPi * std::sqrt(m / 4 / k_contact) / 40
                                               : contact_time_hertz(rock.youngs_modulus / (2 * (1 - 0.0625)), r, m, 0.4) / 40;
    auto s = make_solver(context(), sc);
    s->advance(static_cast<long>(1.5 / sc.numerics.dt));
    const BodyState b = s->bodies().at(0);
    const auto balls = s->balls();
    double z_min = 1e9, z_max = -1e9;
    for (const BallState& c : balls) z_min = std::min(z_min, c.position.z), z_max = std::max(z_max, c.position.z);
    const Vec3 n_lab = rotate(b.orientation, normal);
    std::printf("flat4 dropped 35 deg tilted, %s: after 1.5 s its plane is %.3f deg from the floor, components at "
                "z %.5f..%.5f m (radius %.5f), speed %.2e m/s, spin %.2e rad/s\n",
                law == ContactLaw::hertz ? "hertz" : "linear", std::acos(std::min(1.0, std::fabs(n_lab.z))) * 180 / kPi,
                z_min, z_max, r, b.velocity.norm(), b.omega.norm());
    INFO((law == ContactLaw::hertz ? "hertz" : "linear"));
    CHECK(std::fabs(n_lab.z) > std::cos(0.5 * kPi / 180));  // flat within half a degree
    // Each of the four rests on the floor: its centre a radius up, less the
    // overlap that carries its share of the weight (under 2 % of r here).
    CHECK(z_min > 0.97 * r);
    CHECK(z_max < 1.001 * r);
    CHECK(b.velocity.norm() < 1e-3);
    CHECK(b.omega.norm() < 0.05);
  }
}

TEST_CASE("a peanut sliding across its axis rolls at v0 / (1 + I / (m r^2))", "[bodies][physics]") {
  // Both spheres on the floor, the long axis (the least moment, body x)
  // along the lab's y, pushed along x: friction slows the slide and spins
  // it up about its long axis until the contact points stop slipping,
  // v = ω r, when v = v0 / (1 + I_x / (M r²)) (r the spheres' radius).
  for (ContactLaw law : {ContactLaw::hertz, ContactLaw::linear}) {
    Scene sc = floor_scene(law, Precision::double_, 0.5, 0.3);
    const double d = 0.03, v0 = 0.5;
    const ClumpShape unit = normalised_shape(library_shape("peanut"), d);
    const double r = unit.spheres[0].radius;
    const std::array<double, 4> q = axis_angle({0, 0, 1}, kPi / 2);  // body x onto lab y
    add_clump(sc, library_shape("peanut"), d, 2700, {0.5, 0.5, r * 0.9999}, q, {v0, 0, 0});
    const Body& body = sc.bodies[0];
    const double m = body.mass;
    sc.numerics.dt = law == ContactLaw::linear ? kPi * std::sqrt(m / 2 / 2e5) / 40
                                               : contact_time_hertz(5e9 / (2 * (1 - 0.0625)), r, m / 2, 0.2) / 40;
    auto s = make_solver(context(), sc);
    // Slipping lasts v0 (2/7-like fraction) / (μ g): about 0.05 s; run 0.2 s.
    s->advance(static_cast<long>(0.2 / sc.numerics.dt));
    const BodyState b = s->bodies().at(0);
    const double expect = v0 / (1 + body.inertia.x / (m * r * r));
    std::printf("peanut rolling, %s: v %.5f m/s (closed form %.5f), omega r / v %.5f, I_x / (m r^2) %.4f\n",
                law == ContactLaw::hertz ? "hertz" : "linear", b.velocity.x, expect, b.omega.norm() * r / b.velocity.x,
                body.inertia.x / (m * r * r));
    INFO((law == ContactLaw::hertz ? "hertz" : "linear"));
    CHECK(b.velocity.x == Approx(expect).epsilon(0.01));
    CHECK(b.omega.norm() * r == Approx(b.velocity.x).epsilon(0.01));
    CHECK(std::fabs(b.velocity.y) < 1e-3 * v0);
  }
}

namespace {

// The lab mill made small (0.4 x 0.05 m, about 190 particles) with its
// charge of one shape.
std::vector<std::string> small_mill(const std::string& shape, const std::string& law) {
  return {"mill.diameter=0.4",          "mill.length=0.05",        "lifters.profile.0.height=0.015",
          "lifters.profile.0.top_width=0.02", "charge.size.0.shape=" + shape, "contact.law=" + law,
          "run.warmup=0.6",             "run.duration=1.6",        "run.snapshot_interval=0",
          "run.checkpoint_interval=0"};
}

}  // namespace

TEST_CASE("a charge of clumps: counts and mass as the case asks, no overlaps, inside the mill", "[bodies][case]") {
  for (const char* shape : {"peanut", "rock"}) {
    const MillCase c = io::read_case(io::default_case(), small_mill(shape, "linear"));
    const MillDerived d = derive(c);
    const Scene sc = build_scene(c, d);
    // The same case with balls draws the same diameters: its mass is what
    // the clumps' volume-equivalent diameters ask for.
    MillCase balls_case = c;
    balls_case.sizes[0].shape.clear();
    const Scene balls = build_scene(balls_case, d);
    double ball_mass_kg = 0;
    for (const Ball& b : balls.balls) ball_mass_kg += mc::ball_mass(balls, b);
    double mass = 0;
    std::size_t spheres = 0;
    for (const Body& b : sc.bodies) mass += b.mass, spheres += b.count;
    const double R = 0.5 * c.diameter;
    double worst_overlap = -1, worst_out = -1;
    for (const Ball& a : sc.balls) {
      worst_out = std::max(worst_out, std::hypot(a.position.x, a.position.y) + a.radius - R);
      for (const Ball& b : sc.balls)
        if (a.id < b.id && a.body != b.body)
          worst_overlap = std::max(worst_overlap, a.radius + b.radius - dist(a.position, b.position));
    }
    std::printf("charge of %s: %zu bodies of %zu spheres, %.4f kg (as balls %.4f kg), closest components %.2e m "
                "apart, closest to the shell %.2e m\n",
                shape, sc.bodies.size(), spheres, mass, ball_mass_kg, -worst_overlap, -worst_out);
    INFO(shape);
    CHECK(static_cast<long>(sc.bodies.size()) == d.n_balls);
    CHECK(sc.balls.size() == spheres);
    CHECK(mass == Approx(ball_mass_kg).epsilon(1e-4));
    CHECK(worst_overlap < 0);
    CHECK(worst_out < 0);
  }
}

TEST_CASE("a rock shape from its ellipsoid: count spheres, the axes' order, written out as spheres", "[bodies][case]") {
  const fs::path dir = fs::temp_directory_path() / ("millcharge_ellipsoid_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "slab.toml";
  {
    std::string text = read_text(io::default_case());
    text += "\n[[charge.shape]]\nname = \"slab\"\nellipsoid = [30, 60, 20]  # mm, any order\ncount = 9\nseed = 4\n";
    std::ofstream(file) << text;
  }
  const MillCase c = io::read_case(file, {"charge.size.0.shape=slab", "mill.length=0.05"});
  REQUIRE(c.shapes.size() == 1);
  const ClumpShape& sh = c.shapes[0];
  CHECK(sh.name == "slab");
  CHECK(sh.spheres.size() == 9);
  // The library's rock generator on the sorted axes 1 : 0.5 : 0.333.
  const ClumpShape same = rock_shape(9, 0.5, 1.0 / 3.0, 4);
  REQUIRE(same.spheres.size() == 9);
  for (std::size_t k = 0; k < 9; ++k) CHECK(sh.spheres[k].radius == same.spheres[k].radius);
  // Its principal moments follow the axes: the spread along them 1 : 0.5 : 0.33.
  const ClumpMassProperties p = clump_mass_properties(sh);
  const double var_x = (p.principal.y + p.principal.z - p.principal.x) / 2;  // ∫x² per unit density
  const double var_z = (p.principal.x + p.principal.y - p.principal.z) / 2;
  std::printf("slab from ellipsoid [30, 60, 20]: 9 spheres, principal moments %.4g %.4g %.4g (x 1e3), "
              "rms extent ratio %.3f (ellipsoid 0.333)\n",
              1e3 * p.principal.x, 1e3 * p.principal.y, 1e3 * p.principal.z, std::sqrt(var_z / var_x));
  CHECK(std::sqrt(var_z / var_x) == Approx(1.0 / 3.0).epsilon(0.25));
  // The resolved case lists the spheres, so a run folder's case.toml reads
  // back to the same shape without the generator.
  const fs::path resolved = dir / "resolved.toml";
  std::ofstream(resolved) << io::case_to_toml(c);
  const MillCase back = io::read_case(resolved);
  REQUIRE(back.shapes.size() == 1);
  REQUIRE(back.shapes[0].spheres.size() == 9);
  for (std::size_t k = 0; k < 9; ++k) {
    CHECK(back.shapes[0].spheres[k].radius == Approx(sh.spheres[k].radius).epsilon(1e-12));
    CHECK(back.shapes[0].spheres[k].centre.y == Approx(sh.spheres[k].centre.y).epsilon(1e-12).margin(1e-15));
  }
  CHECK(derive(back).n_balls == derive(c).n_balls);
  fs::remove_all(dir);
}

TEST_CASE("a turning mill of clumps: torque power = dissipation + dE/dt, both laws", "[bodies][power][books]") {
  // Two-sphere peanuts under the linear law, four-sphere flat clumps under
  // Hertz (the 12-sphere rock costs six times as much for the same check).
  for (const auto& [shape, law] : {std::pair<const char*, const char*>{"peanut", "linear"}, {"flat4", "hertz"}}) {
    std::vector<std::string> sets = small_mill(shape, law);
    sets.push_back("run.warmup=0.5");
    sets.push_back("run.duration=1.3");
    const checks::LabRun r = checks::lab_run(context(), sets);
    const RunSummary& s = r.s;
    const double residual = (s.torque_power_W - s.dissipation_power_W - s.energy_change_W) / s.torque_power_W;
    std::printf("mill of %s, %s: torque %.3f W, dissipation %.3f W, dE/dt %.3f W, residual %.2f %%\n", shape, law,
                s.torque_power_W, s.dissipation_power_W, s.energy_change_W, 100 * residual);
    INFO(shape << " " << law);
    CHECK(s.torque_power_W > 1.0);
    CHECK(std::fabs(residual) < 0.02);
  }
}

TEST_CASE("a saved state of clumps resumes bit for bit", "[bodies][checkpoint]") {
  const MillCase c = io::read_case(io::default_case(), small_mill("rock", "linear"));
  const MillDerived d = derive(c);
  const Scene sc = build_scene(c, d);
  auto a = make_solver(context(), sc);
  a->advance(3000);
  const SolverState mid = a->save_state();
  a->advance(3000);
  auto b = make_solver(context(), sc);
  b->restore_state(mid);
  b->advance(3000);
  const auto ba = a->balls(), bb = b->balls();
  const auto ka = a->bodies(), kb = b->bodies();
  REQUIRE(ba.size() == bb.size());
  REQUIRE(ka.size() == kb.size());
  int differ = 0;
  for (std::size_t i = 0; i < ba.size(); ++i)
    differ += ba[i].position.x != bb[i].position.x || ba[i].position.y != bb[i].position.y ||
              ba[i].position.z != bb[i].position.z || ba[i].velocity.x != bb[i].velocity.x;
  for (std::size_t k = 0; k < ka.size(); ++k)
    differ += ka[k].orientation != kb[k].orientation || ka[k].angular_momentum.x != kb[k].angular_momentum.x;
  CHECK(differ == 0);
  // The bodies moved: the state is not a charge at rest.
  CHECK(a->observe(false).kinetic_J > 0);
}

namespace {

// A charge of clumps fallen and tumbling for 0.3 s (so that most components
// touch something), then 200 steps on the device and in the CPU reference,
// in double: positions, body velocities and spins compared.
void clumps_against_reference(const fs::path& case_file, const std::vector<std::string>& sets,
                              const std::string& label) {
  const MillCase c = io::read_case(case_file, sets);
  const MillDerived d = derive(c);
  Scene sc = build_scene(c, d);
  {
    auto pre = make_solver(context(), sc);
    pre->advance(static_cast<long>(0.3 / sc.numerics.dt));
    take_motion(*pre, sc);
    const auto bodies = pre->bodies();
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      sc.bodies[k].position = bodies[k].position;
      sc.bodies[k].velocity = bodies[k].velocity;
      sc.bodies[k].omega = bodies[k].omega;
      sc.bodies[k].orientation = bodies[k].orientation;
    }
  }
  auto dev = make_solver(context(), sc);
  ReferenceSolver ref(sc);
  dev->advance(200);
  ref.advance(200);
  const auto a = dev->balls(), b = ref.balls();
  const auto ka = dev->bodies(), kb = ref.bodies();
  double dx = 0, dv = 0, dw = 0, vmax = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    dx = std::max(dx, dist(a[i].position, b[i].position));
    vmax = std::max(vmax, b[i].velocity.norm());
  }
  for (std::size_t k = 0; k < ka.size(); ++k) {
    dv = std::max(dv, dist(ka[k].velocity, kb[k].velocity));
    dw = std::max(dw, dist(ka[k].omega, kb[k].omega));
  }
  const ContactStats cs = dev->contact_stats();
  const double per_body = static_cast<double>(a.size()) / ka.size();
  std::printf("clumps, kernels vs reference, %s, %zu bodies, 200 steps: max |dx| %.3g m, body |dv| %.3g m/s, "
              "|dw| %.3g rad/s (vmax %.3g m/s; per body %.2f contacts with others, %.2f with walls)\n",
              label.c_str(), ka.size(), dx, dv, dw, vmax, cs.ball_contacts_per_ball * per_body,
              cs.wall_contacts_per_ball * per_body);
  INFO(label);
  CHECK(vmax > 0.05);
  CHECK(cs.ball_contacts_per_ball * per_body > 1.5);  // a bed, not a cloud
  CHECK(cs.wall_contacts_per_ball > 0);
  CHECK(dx < 1e-10);
  CHECK(dv < 1e-8);
  CHECK(dw < 1e-6);
}

}  // namespace

TEST_CASE("clumps tumbling in a turning mill: the kernels equal the CPU reference", "[bodies][reference]") {
  if (!context().info().fp64) {
    WARN("no cl_khr_fp64 on " << context().info().label() << ": skipped");
    return;
  }
  for (const char* law : {"linear", "hertz"}) {
    std::vector<std::string> sets = small_mill("rock", law);
    sets.push_back("run.precision=double");
    clumps_against_reference(io::default_case(), sets, std::string("rock, ") + law);
  }
}

TEST_CASE("clumps against STL lifters and across a slice's seam: the kernels equal the CPU reference",
          "[bodies][reference][mesh][slice]") {
  if (!context().info().fp64) {
    WARN("no cl_khr_fp64 on " << context().info().label() << ": skipped");
    return;
  }
  // The lab mill with its lifters from an STL file, a thin charge of peanuts.
  clumps_against_reference(io::case_dir() / "lab_stl.toml",
                           {"charge.size.0.shape=peanut", "charge.filling=0.08", "contact.law=hertz",
                            "run.precision=double"},
                           "peanut, STL lifters");
  // A periodic slice: bodies and pairs cross the seam.
  std::vector<std::string> sets = small_mill("flat4", "linear");
  sets.push_back("mill.ends=periodic");
  sets.push_back("mill.length=0.11");
  sets.push_back("run.precision=double");
  clumps_against_reference(io::default_case(), sets, "flat4, periodic slice");
}
