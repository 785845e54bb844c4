// Reads of memory that no kernel wrote. A GPU hands out device memory as
// the last program left it; PoCL's is usually zero, so such a read passes
// every CPU test and breaks on the first GPU. Here every device buffer of
// one solver starts as 0xFF bytes (NaN reals, -1 ints) and of another as
// zeros (compute::Context::new_buffer_fill): if a kernel reads a byte it
// did not write first, the two runs differ.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "compute/buffer.h"
#include "core/drum.h"
#include "helpers.h"

using namespace mc;
using namespace mc::test;

namespace {

struct Run {
  std::vector<BallState> balls;
  Observables obs;
  BookSums books;
};

Run run_with_fill(const Scene& sc, unsigned char fill, const char* forces, long steps) {
  compute::Context& ctx = context();
  const unsigned char before = ctx.new_buffer_fill();
  ctx.set_new_buffer_fill(fill);
  ::setenv("MILLCHARGE_FORCES", forces, 1);
  auto s = make_solver(ctx, sc);
  ::unsetenv("MILLCHARGE_FORCES");
  Run r;
  s->advance(steps);
  r.obs = s->observe(true);
  r.books = s->read_books();
  r.balls = s->balls();
  ctx.set_new_buffer_fill(before);
  return r;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

long differing_balls(const std::vector<BallState>& a, const std::vector<BallState>& b) {
  long n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const BallState &p = a[i], &q = b[i];
    const bool same = same_bits(p.position.x, q.position.x) && same_bits(p.position.y, q.position.y) &&
                      same_bits(p.position.z, q.position.z) && same_bits(p.velocity.x, q.velocity.x) &&
                      same_bits(p.velocity.y, q.velocity.y) && same_bits(p.velocity.z, q.velocity.z) &&
                      same_bits(p.omega.x, q.omega.x) && same_bits(p.omega.y, q.omega.y) &&
                      same_bits(p.omega.z, q.omega.z);
    n += same ? 0 : 1;
  }
  return n;
}

}  // namespace

TEST_CASE("a new device buffer holds the context's fill byte, not what the device held", "[poison][device]") {
  compute::Context& ctx = context();
  const unsigned char before = ctx.new_buffer_fill();
  for (unsigned char fill : {0xFF, 0x00}) {
    ctx.set_new_buffer_fill(fill);
    compute::Buffer<float> reals(ctx, 1000, "poison probe");
    compute::Buffer<int> ints(ctx, 1000, "poison probe");
    reals.read_from_device();
    ints.read_from_device();
    for (int k : {0, 499, 999}) {
      INFO("fill " << int(fill) << ", element " << k);
      if (fill == 0xFF) {
        CHECK(std::isnan(reals.host[k]));
        CHECK(ints.host[k] == -1);
      } else {
        CHECK(reals.host[k] == 0.0f);
        CHECK(ints.host[k] == 0);
      }
    }
  }
  ctx.set_new_buffer_fill(before);
}

TEST_CASE("no kernel reads device memory it did not write: poisoned buffers give the same run", "[poison][device]") {
  for (ContactLaw law : {ContactLaw::hertz, ContactLaw::linear})
    for (const char* forces : {"ball", "grouped"}) {
      DrumSpec spec;
      spec.n_balls = 300;  // five work-groups of 64 for the grouped kernel, the last part-full
      spec.law = law;
      const Scene sc = make_drum(spec);
      // Long enough for the charge to fall into contact, for list rebuilds
      // and for the record pool to be packed.
      const long steps = 4000;
      const Run zero = run_with_fill(sc, 0x00, forces, steps);
      const Run poison = run_with_fill(sc, 0xFF, forces, steps);
      INFO((law == ContactLaw::hertz ? "hertz" : "linear") << ", " << forces << " forces");
      std::printf("poison %-6s %-7s: %ld of %zu balls differ, dissipated %.9g J (zeros) and %.9g J (poison)\n",
                  law == ContactLaw::hertz ? "hertz" : "linear", forces,
                  differing_balls(zero.balls, poison.balls), zero.balls.size(), zero.obs.dissipated_J,
                  poison.obs.dissipated_J);
      CHECK(zero.obs.dissipated_J > 0);  // the balls met, so the contact code ran
      CHECK(differing_balls(zero.balls, poison.balls) == 0);
      CHECK(same_bits(zero.obs.dissipated_J, poison.obs.dissipated_J));
      CHECK(same_bits(zero.obs.elastic_J, poison.obs.elastic_J));
      CHECK(same_bits(zero.obs.torque_power_W, poison.obs.torque_power_W));
      CHECK(zero.books.spectra == poison.books.spectra);
      CHECK(zero.books.liner == poison.books.liner);
    }
}
