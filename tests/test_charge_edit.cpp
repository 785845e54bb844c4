// Changing a mill's case under a charge (core/charge_edit, the viewer's live
// edits): grown lifters, a new filling, friction; no deep overlaps left, the
// ball counts the case asks for, surplus balls taken from the top, and the
// solver runs on without a blow-up.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "core/charge_edit.h"
#include "helpers.h"
#include "io/case_file.h"

using namespace mc;

namespace {

struct Lab {
  MillCase c;
  MillDerived d;
  Scene scene;
};

Lab lab(const std::vector<std::string>& overrides = {}) {
  Lab l;
  l.c = io::read_case(io::default_case(), overrides);
  l.d = derive(l.c);
  l.scene = build_scene(l.c, l.d);
  return l;
}

double top_y(const std::vector<Ball>& balls) {
  double y = -1e300;
  for (const Ball& b : balls) y = std::max(y, b.position.y);
  return y;
}

}  // namespace

TEST_CASE("charge edit: grown lifters move the balls in their way out, no deep overlap is left", "[charge_edit]") {
  const Lab l = lab();
  REQUIRE(deepest_overlap(l.scene) < 1e-9);  // the packing leaves gaps
  MillCase c = l.c;
  c.lifter_pattern[0].height = 0.07;  // from 25 mm
  const MillDerived d = derive(c);
  ChargeEditOptions o;
  o.previous_walls = &l.scene.walls;
  const ChargeEditResult r = edit_charge(c, d, l.scene.balls, o);
  INFO("moved " << r.moved << ", removed " << r.removed << ", added " << r.added);
  CHECK(r.moved > 50);  // 12 bars, 45 mm taller, in a charge at J 0.3
  CHECK(r.removed == 0);
  CHECK(r.added == 0);
  CHECK(r.scene.balls.size() == l.scene.balls.size());
  CHECK(deepest_overlap(r.scene) <= o.allowed_overlap + 1e-9);
  CHECK(r.scene.walls.lifters.size() == 12);
  bool ids_in_order = true;
  for (std::size_t k = 0; k < r.scene.balls.size(); ++k) ids_in_order &= r.scene.balls[k].id == static_cast<int>(k);
  CHECK(ids_in_order);

  // The same walls again move nothing: balls pressed into a lifter by an
  // impact are not what the edit is about.
  ChargeEditOptions again;
  again.previous_walls = &r.scene.walls;
  const ChargeEditResult same = edit_charge(c, d, r.scene.balls, again);
  CHECK(same.moved == 0);
  CHECK(same.scene.balls.size() == r.scene.balls.size());
}

TEST_CASE("charge edit: a new filling brings the counts to the case's, adding above and removing from the top",
          "[charge_edit]") {
  const Lab l = lab();
  const long n0 = static_cast<long>(l.scene.balls.size());
  ChargeEditOptions o;
  o.match_counts = true;
  o.previous_walls = &l.scene.walls;

  MillCase more = l.c;
  more.filling = 0.4;
  const MillDerived dm = derive(more);
  const ChargeEditResult up = edit_charge(more, dm, l.scene.balls, o);
  CHECK(static_cast<long>(up.scene.balls.size()) == dm.n_balls);
  CHECK(up.added == dm.n_balls - n0);
  CHECK(up.removed == 0);
  CHECK(deepest_overlap(up.scene) < 1e-9);
  // The new balls lie above the old charge's top.
  double new_low = 1e300;
  for (std::size_t k = n0; k < up.scene.balls.size(); ++k) new_low = std::min(new_low, up.scene.balls[k].position.y);
  CHECK(new_low > top_y(l.scene.balls) - 2 * 0.0254);

  MillCase less = l.c;
  less.filling = 0.2;
  const MillDerived dl = derive(less);
  const ChargeEditResult down = edit_charge(less, dl, l.scene.balls, o);
  CHECK(static_cast<long>(down.scene.balls.size()) == dl.n_balls);
  CHECK(down.removed == n0 - dl.n_balls);
  // Taken from the top: the kept balls are the lowest ones.
  std::vector<double> ys;
  for (const Ball& b : l.scene.balls) ys.push_back(b.position.y);
  std::sort(ys.begin(), ys.end());
  CHECK(top_y(down.scene.balls) <= ys[dl.n_balls - 1] + 1e-12);
}

TEST_CASE("charge edit: the solver runs on after lifters grow and balls are added while the mill turns",
          "[charge_edit]") {
  Lab l = lab({"run.settle=0"});
  auto solver = make_solver(test::context(), l.scene);
  solver->advance(1500);  // 0.03 s: the mill turning at 75 %
  std::vector<Ball> balls;
  for (const BallState& b : solver->balls())
    balls.push_back(Ball{b.id, b.material, b.radius, b.position, b.velocity, b.omega});

  MillCase c = l.c;
  c.lifter_pattern[0].height = 0.06;
  c.filling = 0.36;
  const MillDerived d = derive(c);
  ChargeEditOptions o;
  o.match_counts = true;
  o.mill_angle = solver->mill_angle();
  o.mill_omega = d.omega;
  o.previous_walls = &l.scene.walls;
  const ChargeEditResult r = edit_charge(c, d, balls, o);
  CHECK(r.moved > 20);
  CHECK(static_cast<long>(r.scene.balls.size()) == d.n_balls);
  CHECK(r.scene.mill_angle == Approx(solver->mill_angle()));
  CHECK(deepest_overlap(r.scene) <= o.allowed_overlap + 1e-9);

  auto next = make_solver(test::context(), r.scene);
  REQUIRE_NOTHROW(next->advance(2000));  // 0.04 s
  double v_max = 0;
  for (const BallState& b : next->balls()) v_max = std::max(v_max, b.velocity.norm());
  // Nothing is shot out: the fastest ball is no faster than a fall from the
  // top of the mill (4.2 m/s) would make it.
  CHECK(v_max < 4.2);
  CHECK(v_max > 0.1);  // and the charge moves
}
