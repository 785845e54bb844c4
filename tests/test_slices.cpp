// Periodic axial slices (mill.ends = "periodic", cl/periodic.h): a ball that
// leaves one end enters at the other with its velocity and spin; a pair
// across the seam gets the force and spring of the same pair inside; the
// neighbour lists across the seam equal brute force with the minimum image;
// a slice too short is refused naming its keys; the shipped slices pack
// without overlaps across the seam and turn.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/charge_edit.h"
#include "core/liner.h"
#include "core/mill_case.h"
#include "helpers.h"
#include "io/case_file.h"
#include "io/energy_out.h"
#include "core/layout.hpp"
#include "sim/reference.h"

using namespace mc;
using namespace mc::test;

namespace {

// A periodic slice of `length` with no shell and no gravity: steel balls,
// linear contacts with a grip high enough that the tangential spring, not
// the sliding limit, carries most of a contact's tangential force.
Scene slice_scene(double length, Precision precision) {
  const Material steel{"steel", 7800, 2e11, 0.3};
  Interaction in;
  in.kn = 1e6;
  in.restitution = 0.5;
  in.mu_slide = 0.9;
  Scene sc = bare_scene(steel, steel, in, ContactLaw::linear, precision);
  sc.walls.length = length;
  sc.walls.periodic = true;
  sc.numerics.dt = 5e-6;
  return sc;
}

std::vector<Precision> precisions() {
  std::vector<Precision> p{Precision::single};
  if (context().info().fp64) p.insert(p.begin(), Precision::double_);
  return p;
}

const char* name_of(Precision p) { return p == Precision::double_ ? "double" : "float"; }

// z brought into [0, L).
double wrapped(double z, double L) { return z - L * std::floor(z / L); }

// The minimum image of dz.
double image(double dz, double L) { return dz - L * std::floor(dz / L + 0.5); }

std::unique_ptr<Solver> solver_with(const Scene& sc, const char* forces) {
  setenv("MILLCHARGE_FORCES", forces, 1);
  auto s = make_solver(context(), sc);
  unsetenv("MILLCHARGE_FORCES");
  return s;
}

Ball make_ball(int id, double r, Vec3 p, Vec3 v, Vec3 w) {
  Ball b;
  b.id = id;
  b.radius = r;
  b.position = p;
  b.velocity = v;
  b.omega = w;
  return b;
}

// Collisions closed in the books and their tangential losses, all types.
struct Closed {
  double count = 0, normal = 0, tangential = 0;
};
Closed closed(const BookSums& b) {
  Closed c;
  for (int t = 0; t < b.n_types; ++t)
    for (int k = 0; k < MC_SPECTRA_BINS; ++k) {
      c.count += b.at(t, k, MC_SPECTRA_COUNT);
      c.normal += b.at(t, k, MC_SPECTRA_NORMAL);
      c.tangential += b.at(t, k, MC_SPECTRA_TANGENTIAL);
    }
  return c;
}

}  // namespace

TEST_CASE("a ball crossing the seam of a slice keeps its velocity and spin", "[slices]") {
  const double L = 0.1, r = 0.01;
  for (Precision prec : precisions()) {
    INFO(name_of(prec));
    Scene sc = slice_scene(L, prec);
    // Two free balls far apart across the axis, one crossing each way.
    sc.balls = {make_ball(0, r, {0.01, -0.02, 0.095}, {0.1, -0.2, 2.0}, {30, -20, 10}),
                make_ball(1, r, {0.2, 0.0, 0.004}, {0.0, 0.05, -1.5}, {-5, 8, 40})};
    auto s = make_solver(context(), sc);
    ReferenceSolver ref(sc);
    const double dt = sc.numerics.dt;
    int crossings = 0;
    std::vector<double> last_z = {0.095, 0.004};
    std::vector<BallState> first;
    for (int chunk = 1; chunk <= 10; ++chunk) {
      s->advance(400);
      ref.advance(400);
      const double t = chunk * 400 * dt;
      const auto balls = s->balls();
      const auto ref_balls = ref.balls();
      for (int i = 0; i < 2; ++i) {
        const Ball& b0 = sc.balls[i];
        const BallState& b = balls[i];
        INFO("ball " << i << " chunk " << chunk << " z " << b.position.z);
        // Kept inside the period, where straight-line motion puts it (in
        // float, 4000 drifts of a step round off up to some 1e-5 m).
        CHECK(b.position.z >= 0.0);
        CHECK(b.position.z <= L);
        CHECK(std::fabs(image(b.position.z - wrapped(b0.position.z + b0.velocity.z * t, L), L)) < 5e-5);
        CHECK(b.position.x == Approx(b0.position.x + b0.velocity.x * t).margin(5e-5));
        CHECK(b.position.y == Approx(b0.position.y + b0.velocity.y * t).margin(5e-5));
        // Velocity and spin as given (to the precision), then unchanged to
        // the bit, through the seam.
        CHECK((b.velocity - b0.velocity).norm() < 1e-6 * b0.velocity.norm());
        CHECK((b.omega - b0.omega).norm() < 1e-6 * b0.omega.norm());
        if (!first.empty()) {
          CHECK(b.velocity.x == first[i].velocity.x);
          CHECK(b.velocity.y == first[i].velocity.y);
          CHECK(b.velocity.z == first[i].velocity.z);
          CHECK(b.omega.x == first[i].omega.x);
          CHECK(b.omega.y == first[i].omega.y);
          CHECK(b.omega.z == first[i].omega.z);
        }
        CHECK(b.force.norm() == 0.0);
        // The CPU reference wraps the same way.
        CHECK(std::fabs(image(b.position.z - ref_balls[i].position.z, L)) < 5e-5);
        if (std::fabs(b.position.z - last_z[i]) > 0.5 * L) ++crossings;
        last_z[i] = b.position.z;
      }
      if (first.empty()) first = balls;
    }
    CHECK(crossings >= 2);  // both went through the seam
  }
}

TEST_CASE("a pair touching across the seam gets the force and spring of the same pair inside", "[slices]") {
  const double L = 0.1, r = 0.01;
  // An oblique collision with spin: approaching along z, sliding along x,
  // so that its tangential spring builds up, sticks and slips.
  auto pair_at = [&](double zc, Precision prec) {
    Scene sc = slice_scene(L, prec);
    sc.balls = {make_ball(0, r, {0.0, 0.0, zc - 0.0101}, {0.3, 0.05, 0.4}, {5, -3, 8}),
                make_ball(1, r, {0.002, 0.001, zc + 0.0101}, {-0.3, 0.0, -0.4}, {-2, 6, 1})};
    return sc;
  };
  for (Precision prec : precisions()) {
    const bool dbl = prec == Precision::double_;
    // Float: the two runs round differently (z near 0.05 against z near 0
    // and 0.09), about a part in 10^5 of the overlap each step, and the
    // sticking and slipping amplify it: seen, 0.4 % of the largest force,
    // as much as the float kernel differs from the double reference.
    const double tol = dbl ? 1e-8 : 1e-2;
    for (const char* kernel : {"ball", "grouped"}) {
      INFO(name_of(prec) << ", " << kernel << " force kernel");
      const Scene inside = pair_at(0.05, prec), across = pair_at(0.0, prec);
      auto a = solver_with(inside, "ball");
      auto b = solver_with(across, kernel);
      ReferenceSolver ref(across);
      double f_max = 0, ft_max = 0, worst_f = 0, worst_t = 0, worst_v = 0, worst_w = 0, worst_ref = 0;
      double t_max = 0, v_max = 0, w_max = 0;
      for (int step = 0; step < 300; ++step) {
        a->advance(1);
        b->advance(1);
        ref.advance(1);
        const auto pa = a->balls(), pb = b->balls(), pr = ref.balls();
        for (int i = 0; i < 2; ++i) {
          f_max = std::max(f_max, pa[i].force.norm());
          // The tangential part: the force less its part along the normal.
          Vec3 n = pa[0].position - pa[1].position;
          n = n * (1.0 / n.norm());
          const Vec3 ft = pa[i].force - n * pa[i].force.dot(n);
          ft_max = std::max(ft_max, ft.norm());
          t_max = std::max(t_max, pa[i].torque.norm());
          v_max = std::max(v_max, pa[i].velocity.norm());
          w_max = std::max(w_max, pa[i].omega.norm());
          worst_f = std::max(worst_f, (pa[i].force - pb[i].force).norm());
          worst_t = std::max(worst_t, (pa[i].torque - pb[i].torque).norm());
          worst_v = std::max(worst_v, (pa[i].velocity - pb[i].velocity).norm());
          worst_w = std::max(worst_w, (pa[i].omega - pb[i].omega).norm());
          worst_ref = std::max(worst_ref, (pb[i].force - pr[i].force).norm());
          // The same place, half a period along.
          CHECK(std::fabs(image(pa[i].position.z - pb[i].position.z - 0.05, L)) < 1e-5);
        }
      }
      INFO("max force " << f_max << " N, tangential " << ft_max << " N; worst differences: force " << worst_f
                        << " N, torque " << worst_t << " N m, velocity " << worst_v << " m/s, spin " << worst_w
                        << " rad/s; kernel against the reference " << worst_ref << " N");
      // The contact happened, with a real tangential force...
      CHECK(f_max > 20.0);
      CHECK(ft_max > 0.1 * f_max);
      // ...and the pair across the seam felt the same, step by step.
      CHECK(worst_f <= tol * f_max);
      CHECK(worst_t <= tol * t_max);
      CHECK(worst_v <= tol * v_max);
      CHECK(worst_w <= tol * w_max);
      CHECK(worst_ref <= (dbl ? 1e-6 : 1e-2) * f_max);
      // One collision each, closed, with the same losses: the spring's
      // history, normal and tangential, was the same.
      const Closed ca = closed(a->read_books()), cb = closed(b->read_books());
      CHECK(ca.count == 1);
      CHECK(cb.count == 1);
      CHECK(ca.tangential > 0);
      CHECK(cb.normal == Approx(ca.normal).epsilon(dbl ? 1e-7 : 1e-2));
      CHECK(cb.tangential == Approx(ca.tangential).epsilon(dbl ? 1e-7 : 1e-2));
    }
  }
}

namespace {

// A loose bed filling a slice of length L (and L × L across): balls of
// radius 0.85–1.05 r on a jittered lattice whose z pitch tiles the period,
// the whole lattice shifted along z by a random amount and wrapped, so that
// pairs straddle the seam.
Scene periodic_packing(double r, double L, unsigned seed) {
  Scene sc = slice_scene(L, Precision::single);
  sc.numerics.dt = 2e-6;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double pitch = 2.2 * r;
  const int nz = static_cast<int>(std::floor(L / pitch));
  const double pz = L / nz, shift = L * u(rng);
  int id = 0;
  for (int iz = 0; iz < nz; ++iz)
    for (double y = pitch; y < L; y += pitch)
      for (double x = pitch; x < L; x += pitch) {
        const double jit = 0.02 * r;
        Ball b;
        b.id = id++;
        b.radius = r * (0.85 + 0.2 * u(rng));
        b.position = {x + jit * (2 * u(rng) - 1), y + jit * (2 * u(rng) - 1),
                      wrapped(iz * pz + shift + jit * (2 * u(rng) - 1), L)};
        sc.balls.push_back(b);
      }
  return sc;
}

// Pairs (lower id, higher id) within r_i + r_j + skin − guard, the minimum
// image along z.
std::set<std::pair<int, int>> brute_force(const std::vector<BallState>& balls, double L, double skin, double guard) {
  std::set<std::pair<int, int>> out;
  for (const auto& a : balls)
    for (const auto& b : balls) {
      if (a.id >= b.id) continue;
      Vec3 d = a.position - b.position;
      d.z = image(d.z, L);
      if (d.norm() < a.radius + b.radius + skin - guard) out.insert({a.id, b.id});
    }
  return out;
}

long across_seam(const std::set<std::pair<int, int>>& pairs, const std::vector<BallState>& balls, double L) {
  long n = 0;
  for (const auto& [i, j] : pairs) n += std::fabs(balls[i].position.z - balls[j].position.z) > 0.5 * L;
  return n;
}

}  // namespace

TEST_CASE("neighbour lists across the seam of a slice equal brute force with the minimum image", "[slices][contacts]") {
  const double r = 0.005, L = 0.1;
  Scene sc = periodic_packing(r, L, 3);
  sc.numerics.skin = 0.5 * r;
  const double skin = sc.numerics.skin;
  auto s = make_solver(context(), sc);
  {
    const auto pairs = s->neighbour_pairs();
    const std::set<std::pair<int, int>> listed = test::unordered(pairs);
    CHECK(listed.size() == pairs.size());  // each pair once
    const auto balls = s->balls();
    const auto must = brute_force(balls, L, skin, 1e-6);
    const auto may = brute_force(balls, L, skin, -1e-6);
    long missing = 0, extra = 0;
    for (const auto& p : must) missing += listed.count(p) == 0;
    for (const auto& p : listed) extra += may.count(p) == 0;
    INFO("n " << balls.size() << " listed " << listed.size() << " brute force " << must.size() << ", across the seam "
              << across_seam(must, balls, L));
    CHECK(balls.size() > 500);
    CHECK(must.size() > balls.size());
    CHECK(across_seam(must, balls, L) > 30);  // the seam really has pairs
    CHECK(missing == 0);
    CHECK(extra == 0);
  }
  // Moving: the bed expands and collides, balls cross the seam, the lists
  // are rebuilt; every pair that touches is listed.
  for (auto& b : sc.balls) b.velocity = {0.3 * std::sin(b.id), 0.3 * std::cos(b.id), 0.8 * std::sin(3.0 * b.id)};
  auto m = make_solver(context(), sc);
  long touching_across = 0, missing = 0, outside = 0;
  for (int sample = 0; sample < 40; ++sample) {
    m->advance(100);
    const auto balls = m->balls();
    const std::set<std::pair<int, int>> listed = test::unordered(m->neighbour_pairs());
    const auto touching = brute_force(balls, L, 0.0, 0.0);
    for (const auto& p : touching) missing += listed.count(p) == 0;
    touching_across += across_seam(touching, balls, L);
    for (const auto& b : balls) outside += b.position.z < 0.0 || b.position.z > L;
  }
  CHECK(missing == 0);
  CHECK(outside == 0);
  CHECK(touching_across > 0);
  CHECK(m->rebuilds() > 2);
}

namespace {

std::string error_of(const std::string& file, const std::vector<std::string>& sets) {
  try {
    io::read_case(io::case_dir() / file, sets);
  } catch (const io::CaseError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("a slice shorter than the shortest sensible one is refused naming mill.ends and mill.length", "[slices][case]") {
  // The lab mill's largest ball is 25.4 mm: the shortest slice is 4 of them.
  const MillCase ok = io::read_case(io::default_case(), {"mill.ends=periodic", "mill.length=0.11"});
  CHECK(ok.periodic);
  CHECK(derive(ok).shortest_slice == Approx(4 * 0.0254));
  const std::string e = error_of("lab.toml", {"mill.ends=periodic", "mill.length=0.1"});
  CHECK_THAT(e, Catch::Contains("mill.length: a periodic slice (mill.ends = \"periodic\") must be at least 4 "
                                "largest-ball diameters long, 0.1016 m for 25.4 mm balls (got 0.1 m)"));
  // The same length with end plates is a (short) whole mill.
  CHECK(error_of("lab.toml", {"mill.length=0.1"}).empty());
  CHECK_THAT(error_of("lab.toml", {"mill.ends=open"}), Catch::Contains("mill.ends: \"open\" is not one of"));
  // Written back, a slice stays a slice.
  CHECK(io::parse_case(io::case_to_toml(ok), "back.toml").periodic);
}

TEST_CASE("the shipped slices of the seed mills are accepted, pack across the seam and have no end plates", "[slices][case]") {
  for (const char* f : {"mill_a_slice.toml", "mill_b_slice.toml", "mill_c_slice.toml", "mill_d_slice.toml"}) {
    INFO(f);
    const MillCase c = io::read_case(io::case_dir() / f);
    const MillDerived d = derive(c);
    CHECK(c.periodic);
    CHECK(c.length >= d.shortest_slice + 2 * d.largest_ball_diameter);
    CHECK(c.length <= 12 * d.largest_ball_diameter);
    // The slice of the same mill: everything but the length and the ends.
    const std::string whole = std::string(f).substr(0, 6) + ".toml";
    const MillCase w = io::read_case(io::case_dir() / whole);
    CHECK(c.diameter == w.diameter);
    CHECK(c.speed_rpm == w.speed_rpm);
    CHECK(c.speed_fraction == w.speed_fraction);
    CHECK(c.filling == w.filling);
    CHECK(c.lifter_rows == w.lifter_rows);
    CHECK(c.contact.kn == w.contact.kn);
    CHECK(d.n_balls == Approx(derive(w).n_balls * c.length / w.length).epsilon(0.01));
  }
  // Packed: inside the period, nothing overlapping across the seam, and the
  // charge reaching both ends (no end gaps).
  const MillCase c = io::read_case(io::case_dir() / "mill_d_slice.toml", {"charge.filling=0.1"});
  const MillDerived d = derive(c);
  const Scene s = build_scene(c, d);
  REQUIRE(static_cast<long>(s.balls.size()) == d.n_balls);
  double z_lo = 1e300, z_hi = -1e300;
  for (const Ball& b : s.balls) {
    REQUIRE(b.position.z >= 0);
    REQUIRE(b.position.z < c.length);
    z_lo = std::min(z_lo, b.position.z);
    z_hi = std::max(z_hi, b.position.z);
  }
  CHECK(z_lo < 0.5 * d.largest_ball_diameter);
  CHECK(z_hi > c.length - 0.5 * d.largest_ball_diameter);
  CHECK(deepest_overlap(s) <= 0.0);
  // The same balls with z not wrapped would overlap across the seam if the
  // check did not take the minimum image: a ball near each end is close.
  long near_seam = 0;
  for (const Ball& a : s.balls)
    if (a.position.z < a.radius) ++near_seam;
  CHECK(near_seam > 10);
  const LinerLayout layout = liner_layout(s);
  CHECK(layout.first_plate == layout.size());
  for (const LinerElement& e : layout.elements) CHECK(e.part != LinerPart::plate);
}

TEST_CASE("a turning slice keeps its charge inside, resumes bit for bit and books nothing on end plates", "[slices][mill]") {
  MillCase c = io::read_case(io::default_case(), {"mill.ends=periodic", "mill.length=0.12", "charge.filling=0.25"});
  const MillDerived d = derive(c);
  Scene sc = build_scene(c, d);
  auto s = make_solver(context(), sc);
  s->advance(700);
  // A checkpoint's state, resumed in a new solver, ends as the unbroken run.
  const SolverState state = s->save_state();
  s->advance(800);
  auto resumed = make_solver(context(), sc);
  resumed->restore_state(state);
  resumed->advance(800);
  long differ = 0;
  const auto a = s->balls(), b = resumed->balls();
  for (std::size_t i = 0; i < a.size(); ++i)
    differ += !(a[i].position.x == b[i].position.x && a[i].position.z == b[i].position.z &&
                a[i].velocity.y == b[i].velocity.y && a[i].omega.z == b[i].omega.z);
  CHECK(differ == 0);
  CHECK(s->contact_stats().wall_contacts_per_ball > 0.01);  // the charge lies on the shell...
  const BookSums books = s->read_books();
  const int nm = static_cast<int>(sc.materials.size());
  double plate = 0;
  for (int m = 0; m < nm; ++m)
    for (int k = 0; k < MC_SPECTRA_BINS; ++k)
      plate += books.at(f64::wall_pair_type(m, MC_WALL_PLATE_LOW, nm), k, MC_SPECTRA_COUNT);
  CHECK(plate == 0);  // ...and met no end plate
  for (const BallState& b : s->balls()) {
    CHECK(b.position.z >= 0.0);
    CHECK(b.position.z <= c.length);
  }
  // Per metre: the slice's figures over its length.
  SpectraReport sr;
  sr.all.collisions_per_s = 120;
  LinerReport lr;
  lr.impact_W = 6;
  lr.parts.resize(1);
  lr.parts[0].name = "shell";
  lr.parts[0].impact_W = 3;
  const auto pm = io::per_metre_json(0.12, 24, 30, 12, sr, lr);
  CHECK(pm["power_W"]["torque"].get<double>() == Approx(200));
  CHECK(pm["power_W"]["dissipation"].get<double>() == Approx(250));
  CHECK(pm["torque_Nm"].get<double>() == Approx(100));
  CHECK(pm["collisions_per_s"].get<double>() == Approx(1000));
  CHECK(pm["liner_impact_power_W"].get<double>() == Approx(50));
  CHECK(pm["parts"][0]["impact_power_W"].get<double>() == Approx(25));
}
