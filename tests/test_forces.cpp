// The kernels against the CPU reference (same physics functions, brute-force
// lists, no reordering, double), ball by ball, matched by id.
#include <catch2/catch.hpp>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "core/drum.h"
#include "helpers.h"
#include "sim/reference.h"

using namespace mc;
using namespace mc::test;

namespace {

struct Diff {
  double pos = 0, vel = 0, omega = 0;
};

Diff compare(const std::vector<BallState>& a, const std::vector<BallState>& b) {
  REQUIRE(a.size() == b.size());
  Diff d;
  for (std::size_t i = 0; i < a.size(); ++i) {
    REQUIRE(a[i].id == b[i].id);
    d.pos = std::max(d.pos, (a[i].position - b[i].position).norm());
    d.vel = std::max(d.vel, (a[i].velocity - b[i].velocity).norm());
    d.omega = std::max(d.omega, (a[i].omega - b[i].omega).norm());
  }
  return d;
}

// Where the drums below settle: in double, on the device under test when it
// has cl_khr_fp64, else on the first device that has (PoCL beside Mesa's
// rusticl, which has no fp64), so that every device starts from the same
// bed; on the device under test in float when none has.
compute::Context& settling_context(Precision& precision) {
  precision = Precision::double_;
  if (context().info().fp64) return context();
  static std::unique_ptr<compute::Context> fp64;
  if (!fp64)
    for (const compute::DeviceInfo& d : compute::list_devices())
      if (d.fp64) {
        fp64 = std::make_unique<compute::Context>(std::to_string(d.platform_index) + ":" +
                                                  std::to_string(d.device_index));
        break;
      }
  if (fp64) return *fp64;
  precision = Precision::single;
  return context();
}

// The drum of `spec` after 0.25 s of turning (settled as above), as a scene:
// the balls where they came to, the lifters where they were then.
Scene settled_drum(const DrumSpec& spec) {
  Scene sc = make_drum(spec);
  Scene settle = sc;
  compute::Context& settling = settling_context(settle.numerics.precision);
  auto pre = make_solver(settling, settle);
  pre->advance(static_cast<long>(0.25 / sc.numerics.dt));
  take_motion(*pre, sc);
  return sc;
}

}  // namespace

TEST_CASE("kernels equal the CPU reference ball by ball on a dense turning charge", "[forces][reference]") {
  // Both precisions where the device has cl_khr_fp64; float alone on one
  // without it (Mesa's rusticl on llvmpipe, the `rusticl` tier).
  std::vector<Precision> precisions = {Precision::single};
  if (context().info().fp64) precisions.insert(precisions.begin(), Precision::double_);
  else WARN("no cl_khr_fp64 on " << context().info().label() << ": float only");
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    for (Precision prec : precisions) {
      DrumSpec spec;
      spec.n_balls = 300;
      spec.law = law;
      spec.precision = prec;
      // Settled first so the comparison is on a dense bed with many contacts,
      // shell, plate and lifter contacts among them.
      const Scene sc = settled_drum(spec);
      auto dev = make_solver(context(), sc);
      ReferenceSolver ref(sc);
      const long steps = 200;
      dev->advance(steps);
      ref.advance(steps);
      const auto a = dev->balls();
      const auto b = ref.balls();
      const Diff d = compare(a, b);
      // Scale: the fastest ball's speed.
      double vmax = 0;
      for (const auto& x : b) vmax = std::max(vmax, x.velocity.norm());
      const bool dbl = prec == Precision::double_;
      std::printf("kernel vs reference %-6s %-6s %ld steps: max |dx| %.3g m, |dv| %.3g m/s, |dw| %.3g rad/s (vmax %.3g)\n",
                  law == ContactLaw::hertz ? "hertz" : "linear", dbl ? "double" : "float", steps, d.pos, d.vel,
                  d.omega, vmax);
      INFO((law == ContactLaw::hertz ? "hertz " : "linear ") << (dbl ? "double" : "float"));
      CHECK(vmax > 0.05);  // the charge is moving
      if (dbl) {
        // Only the order of summation differs.
        CHECK(d.pos < 1e-10);
        CHECK(d.vel < 1e-8);
        CHECK(d.omega < 1e-5);
      } else {
        // Float state: stiff contacts amplify round-off to about 1 % of the
        // speed scale in 200 steps; a wrong neighbour or a lost spring would
        // show as an O(1) difference.
        CHECK(d.pos < 1e-5);
        CHECK(d.vel < 0.03 * vmax);
        CHECK(d.omega < 0.03 * vmax / spec.radius_min);
      }
    }
  }
}

namespace {

// A solver built with MILLCHARGE_FORCES and MILLCHARGE_CL_OPTIONS set for
// its construction only.
std::unique_ptr<Solver> solver_with(const Scene& sc, const char* forces, const char* cl_options) {
  setenv("MILLCHARGE_FORCES", forces, 1);
  if (cl_options) setenv("MILLCHARGE_CL_OPTIONS", cl_options, 1);
  auto s = make_solver(context(), sc);
  unsetenv("MILLCHARGE_FORCES");
  unsetenv("MILLCHARGE_CL_OPTIONS");
  return s;
}

// Balls whose position, velocity or spin differ in any bit.
long count_differing(const std::vector<BallState>& a, const std::vector<BallState>& b) {
  REQUIRE(a.size() == b.size());
  auto same = [](const Vec3& u, const Vec3& v) { return u.x == v.x && u.y == v.y && u.z == v.z; };
  long differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!(same(a[i].position, b[i].position) && same(a[i].velocity, b[i].velocity) && same(a[i].omega, b[i].omega)))
      ++differ;
  return differ;
}

}  // namespace

TEST_CASE("the grouped force kernel gives the per-ball kernel's forces bit for bit", "[forces]") {
  for (ContactLaw law : {ContactLaw::hertz, ContactLaw::linear}) {
    DrumSpec spec;
    spec.n_balls = 300;  // five work-groups of 64, the last one part-full
    spec.law = law;
    const Scene sc = settled_drum(spec);
    INFO((law == ContactLaw::hertz ? "hertz" : "linear"));
    const long steps = 200;
    auto ball = solver_with(sc, "ball", nullptr);
    CHECK(std::string(ball->forces_kernel()) == "ball");
    ball->advance(steps);
    const auto want = ball->balls();
    double vmax = 0;
    for (const auto& b : want) vmax = std::max(vmax, b.velocity.norm());
    CHECK(vmax > 0.05);  // the charge is moving
    // 0.2 pairs per ball would be 13 per work-group: more than two rounds of
    // 4 (below) hold.
    CHECK(ball->contact_stats().ball_contacts_per_ball > 0.4);

    // The default (two rounds of 64 queued pairs), one round, and two rounds
    // of 4, so that both rounds are full and the pairs past them are run by
    // their ball: the same forces, so the same state after 200 steps, bit
    // for bit.
    for (const char* options : {static_cast<const char*>(nullptr), "-DMC_FG_ROUNDS=1", "-DMC_FG_ROUND=4"}) {
      INFO((options ? options : "default"));
      auto grouped = solver_with(sc, "grouped", options);
      CHECK(std::string(grouped->forces_kernel()) == "grouped");
      grouped->advance(steps);
      CHECK(count_differing(grouped->balls(), want) == 0);
    }
    {  // and in double precision
      INFO("double");
      Scene scd = sc;
      scd.numerics.precision = Precision::double_;
      auto a = solver_with(scd, "ball", nullptr);
      auto b = solver_with(scd, "grouped", nullptr);
      a->advance(steps);
      b->advance(steps);
      CHECK(count_differing(a->balls(), b->balls()) == 0);
    }

    // A queue of one pair per ball: the rest are run in the walk and added
    // after the queued one, a different order of summation, so only
    // round-off apart (after one step, before stiff contacts amplify it).
    auto one = solver_with(sc, "grouped", "-DMC_FG_QUEUE=1");
    auto ref = solver_with(sc, "ball", nullptr);
    one->advance(1);
    ref->advance(1);
    const Diff d = compare(one->balls(), ref->balls());
    double v1 = 0;
    for (const auto& b : ref->balls()) v1 = std::max(v1, b.velocity.norm());
    CHECK(d.pos < 1e-9);
    CHECK(d.vel < 1e-5 * v1);
  }
}

TEST_CASE("a bad MILLCHARGE_FORCES is refused with its name", "[forces]") {
  DrumSpec spec;
  spec.n_balls = 50;
  const Scene sc = make_drum(spec);
  setenv("MILLCHARGE_FORCES", "fast", 1);
  std::string message;
  try {
    make_solver(context(), sc);
  } catch (const std::invalid_argument& e) {
    message = e.what();
  }
  unsetenv("MILLCHARGE_FORCES");
  CHECK(message.find("MILLCHARGE_FORCES=fast") != std::string::npos);
}

TEST_CASE("the reactions added in the motion kernel give the separate kernels' state bit for bit", "[forces]") {
  // react_motion adds a step's reactions at the next step's start: one
  // launch fewer a step. Any split of the steps into advance() calls, the
  // books and the observables must not see the difference.
  for (ContactLaw law : {ContactLaw::hertz, ContactLaw::linear}) {
    DrumSpec spec;
    spec.n_balls = 300;
    spec.law = law;
    const Scene sc = settled_drum(spec);
    INFO((law == ContactLaw::hertz ? "hertz" : "linear"));
    setenv("MILLCHARGE_FUSED_MOTION", "0", 1);
    auto apart = make_solver(context(), sc);
    unsetenv("MILLCHARGE_FUSED_MOTION");
    auto fused = make_solver(context(), sc);
    apart->advance(300);
    for (long chunk : {1L, 2L, 37L, 60L, 200L}) fused->advance(chunk);
    CHECK(fused->steps() == apart->steps());
    CHECK(count_differing(fused->balls(), apart->balls()) == 0);
    const Observables a = apart->observe(false), f = fused->observe(false);
    CHECK(f.kinetic_J == a.kinetic_J);
    CHECK(f.dissipated_J == a.dissipated_J);
    CHECK(f.wall_work_J == a.wall_work_J);
    CHECK(f.elastic_J == a.elastic_J);
    double vmax = 0;
    for (const auto& b : apart->balls()) vmax = std::max(vmax, b.velocity.norm());
    CHECK(vmax > 0.05);  // the charge is moving
    CHECK(apart->contact_stats().ball_contacts_per_ball > 0.4);
  }
}
