// Neighbour lists (binning + contacts kernels) against brute force.
#include <catch2/catch.hpp>

#include <cstdlib>

#include <algorithm>
#include <random>
#include <set>

#include "helpers.h"

using namespace mc;
using namespace mc::test;

namespace {

// A dense bed: small balls (radii −15 %/+5 %) on a jittered cubic lattice, with
// `n_big` big balls carved in at random places, so that big balls have many
// small neighbours (size ratio up to 10).
Scene random_packing(double r_small, double r_big, int n_big, double box, unsigned seed) {
  const Material steel{"steel", 7800, 2e11, 0.3};
  Scene sc = bare_scene(steel, steel, Interaction{}, ContactLaw::hertz);
  sc.numerics.dt = 1e-6;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> big;
  for (int tries = 0; tries < 1000 && static_cast<int>(big.size()) < n_big; ++tries) {
    const Vec3 c{r_big + (box - 2 * r_big) * u(rng), r_big + (box - 2 * r_big) * u(rng),
                 r_big + (box - 2 * r_big) * u(rng)};
    bool ok = true;
    for (const Vec3& o : big) ok = ok && (o - c).norm() > 2.05 * r_big;
    if (ok) big.push_back(c);
  }
  int id = 0;
  for (const Vec3& c : big) {
    Ball b;
    b.id = id++;
    b.radius = r_big;
    b.position = c;
    sc.balls.push_back(b);
  }
  const double pitch = 2.2 * r_small;  // gaps of 0.1–0.5 r_small, none negative
  for (double z = pitch; z < box; z += pitch)
    for (double y = pitch; y < box; y += pitch)
      for (double x = pitch; x < box; x += pitch) {
        const Vec3 p{x + 0.02 * r_small * (2 * u(rng) - 1), y + 0.02 * r_small * (2 * u(rng) - 1),
                     z + 0.02 * r_small * (2 * u(rng) - 1)};
        const double r = r_small * (0.85 + 0.2 * u(rng));
        bool ok = true;
        for (const Vec3& c : big) ok = ok && (c - p).norm() > r_big + r;
        if (!ok) continue;
        Ball b;
        b.id = id++;
        b.radius = r;
        b.position = p;
        sc.balls.push_back(b);
      }
  return sc;
}

// Pairs as (lower id, higher id).
std::set<std::pair<int, int>> brute_force(const std::vector<BallState>& balls, double skin, double guard) {
  std::set<std::pair<int, int>> out;
  for (const auto& a : balls)
    for (const auto& b : balls) {
      if (a.id >= b.id) continue;
      const double d = (a.position - b.position).norm();
      if (d < a.radius + b.radius + skin - guard) out.insert({a.id, b.id});
    }
  return out;
}

}  // namespace

TEST_CASE("neighbour search equals brute force on random packings", "[contacts]") {
  struct Case {
    double r_small, r_big;
    int n_big;
    double box;
  };
  // Equal sizes; two sizes of ratio 10; a dense mixture.
  const Case cases[] = {{0.005, 0.005, 0, 0.1}, {0.002, 0.02, 6, 0.1}, {0.003, 0.012, 20, 0.1}};
  unsigned seed = 1;
  for (const Case& c : cases) {
    Scene sc = random_packing(c.r_small, c.r_big, c.n_big, c.box, seed++);
    // A skin wider than the default, so that these loose packings list
    // more pairs than balls.
    sc.numerics.skin = 0.3 * c.r_small;
    const double skin = sc.numerics.skin;
    auto s = make_solver(context(), sc);
    const auto pairs = s->neighbour_pairs();
    const std::set<std::pair<int, int>> listed = test::unordered(pairs);
    CHECK(listed.size() == pairs.size());  // each pair once, in one list only
    const auto balls = s->balls();
    // Every pair inside the cutoff is listed (a float guard of 1e-6 m aside)...
    const auto must = brute_force(balls, skin, 1e-6);
    int missing = 0;
    for (const auto& p : must) missing += listed.count(p) == 0;
    // ...and nothing beyond it.
    const auto may = brute_force(balls, skin, -1e-6);
    int extra = 0;
    for (const auto& p : listed) extra += may.count(p) == 0;
    INFO("n " << sc.balls.size() << " listed " << listed.size() << " brute force " << must.size());
    CHECK(sc.balls.size() > 500);
    CHECK(must.size() > sc.balls.size());  // the case really has neighbours
    CHECK(missing == 0);
    CHECK(extra == 0);
  }
}

TEST_CASE("neighbour lists stay complete while the charge moves", "[contacts]") {
  // A settling, colliding bed rebuilds its lists many times; at every check
  // (600 of them, between status reads too) each touching pair must be
  // listed: with the status word read every step (a CPU device) and every 8
  // steps (MILLCHARGE_STATUS_EVERY; a GPU reads every kGpuStatusEvery), when
  // a rebuild flag may wait 8 steps. With a thin skin (10 um, half of it a
  // few steps of a 0.5 m/s ball's travel) 8 steps are too many: the solver
  // reads every step from the start, or from the step a ball gets that fast
  // (MC_FLAG_FAST).
  struct Case {
    double skin;    // m; 0: the default (20 % of the smallest radius)
    double speed;   // of the balls' start velocities
    const char* every;
    int every_after;
  };
  for (const Case& c : {Case{0.0, 1.0, "8", 8}, Case{1e-5, 1.0, "8", 1}, Case{1e-5, 0.2, "8", 1},
                        Case{1e-5, 1.0, "1", 1}}) {
    Scene sc = random_packing(0.004, 0.012, 5, 0.08, 7);
    sc.numerics.gravity = {0, -9.81, 0};
    sc.walls.shell_radius = 0.0;
    for (auto& b : sc.balls)
      b.velocity = {0.5 * c.speed * std::sin(b.id), 0.5 * c.speed * std::cos(b.id), 0.3 * c.speed * std::sin(3.0 * b.id)};
    sc.numerics.dt = 2e-6;
    sc.numerics.skin = c.skin;
    ::setenv("MILLCHARGE_STATUS_EVERY", c.every, 1);
    auto s = make_solver(context(), sc);
    ::unsetenv("MILLCHARGE_STATUS_EVERY");
    INFO("skin " << c.skin << " m, speed x" << c.speed << ", status read every " << c.every << " steps");
    long missing = 0, pairs = 0;
    for (int round = 0; round < 600; ++round) {
      s->advance(round % 2 ? 5 : 6);
      const std::set<std::pair<int, int>> listed = test::unordered(s->neighbour_pairs());
      const auto touching = brute_force(s->balls(), 0.0, 0.0);
      pairs += static_cast<long>(touching.size());
      for (const auto& p : touching) missing += listed.count(p) == 0;
    }
    CHECK(pairs > 100);  // the balls met
    CHECK(missing == 0);
    CHECK(s->rebuilds() > 2);
    CHECK(s->status_every() == c.every_after);
  }
}

TEST_CASE("a bad MILLCHARGE_STATUS_EVERY is refused with its name", "[contacts]") {
  Scene sc = random_packing(0.004, 0.012, 2, 0.04, 7);
  for (const char* bad : {"0", "65", "four", "8x"}) {
    ::setenv("MILLCHARGE_STATUS_EVERY", bad, 1);
    INFO(bad);
    CHECK_THROWS_WITH(make_solver(context(), sc), Catch::Contains("MILLCHARGE_STATUS_EVERY"));
  }
  ::unsetenv("MILLCHARGE_STATUS_EVERY");
}
