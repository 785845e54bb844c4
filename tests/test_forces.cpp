// The kernels against the CPU reference (same physics functions, brute-force
// lists, no reordering, double), ball by ball, matched by id.
#include <catch2/catch.hpp>

#include <cstdio>

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

}  // namespace

TEST_CASE("kernels equal the CPU reference ball by ball on a dense turning charge", "[forces][reference]") {
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    for (Precision prec : {Precision::double_, Precision::single}) {
      DrumSpec spec;
      spec.n_balls = 300;
      spec.law = law;
      spec.precision = prec;
      Scene sc = make_drum(spec);
      // Settle first so the comparison is on a dense bed with many contacts,
      // shell, plate and lifter contacts among them.
      {
        Scene settle = sc;
        settle.numerics.precision = Precision::double_;
        auto pre = make_solver(context(), settle);
        pre->advance(static_cast<long>(0.25 / sc.numerics.dt));
        const auto settled = pre->balls();
        sc.mill_angle = pre->mill_angle();  // the lifters stay where the balls settled
        for (std::size_t i = 0; i < sc.balls.size(); ++i) {
          sc.balls[i].position = settled[i].position;
          sc.balls[i].velocity = settled[i].velocity;
          sc.balls[i].omega = settled[i].omega;
        }
      }
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
