#include "core/mill_case.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <queue>
#include <random>
#include <sstream>
#include <stdexcept>

#include "core/drum.h"
#include "core/wall_mesh.h"
#include "core/morrell.h"
#include "core/plate_wear.h"

namespace mc {

namespace {

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void fail(const std::string& key, const std::string& what) {
  throw std::invalid_argument(key + ": " + what);
}

std::string num(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

// Mean of d³ for diameters uniform on [a, b].
double mean_cube(double a, double b) {
  if (b - a < 1e-12 * b) return a * a * a;
  return (b * b * b * b - a * a * a * a) / (4.0 * (b - a));
}

double sphere_volume(double d) { return kPi / 6.0 * d * d * d; }

// Limits that keep a case's memory and time bounded (derive() refuses more).
constexpr double kMaxBalls = 50e6;
constexpr double kMaxColumns = 10e6;
constexpr double kMaxCells = 200e6;
constexpr double kMaxSteps = 1e11;

// The columns and grid cells build_scene() uses, in double (no overflow).
struct PackingGrid {
  double columns, cells;
};
PackingGrid packing_grid(const MillCase& c, double d_min, double d_max) {
  const double R = 0.5 * c.diameter, rmin = 0.5 * d_min, rmax = 0.5 * d_max;
  const double gap = 0.02 * rmin, pitch = 2 * rmin + 2 * gap, cell = 2 * rmax + 2 * gap;
  const double nx = std::floor((2 * R - 2 * gap) / pitch);
  const double nz = std::max(1.0, std::floor((c.length - 2 * gap) / pitch));
  const double gx = std::ceil(2 * R / cell) + 1, gz = std::ceil(c.length / cell) + 1;
  return {nx * nz, gx * gx * gz};
}

}  // namespace

int material_index(const MillCase& c, const std::string& name) {
  for (std::size_t k = 0; k < c.materials.size(); ++k)
    if (c.materials[k].name == name) return static_cast<int>(k);
  return -1;
}

MillDerived derive(const MillCase& c) {
  MillDerived d;
  const double R = 0.5 * c.diameter;
  if (!(c.diameter > 0)) fail("mill.diameter", "must be > 0 m (got " + num(c.diameter) + ")");
  if (!(c.length > 0)) fail("mill.length", "must be > 0 m (got " + num(c.length) + ")");
  if (!(c.diameter <= 1000)) fail("mill.diameter", "must be at most 1000 m (got " + num(c.diameter) + ")");
  if (!(c.length <= 1000)) fail("mill.length", "must be at most 1000 m (got " + num(c.length) + ")");
  if (material_index(c, c.liner) < 0) fail("mill.liner", "unknown material \"" + c.liner + "\"");
  if (c.sizes.empty()) fail("charge.size", "the charge needs at least one size class");
  // Materials first: the ball counts divide by the densities.
  for (const Material& m : c.materials) {
    const std::string key = "materials." + m.name;
    if (!(m.density > 0)) fail(key + ".density", "must be > 0 kg/m³ (got " + num(m.density) + ")");
    if (!(m.youngs_modulus > 0)) fail(key + ".youngs_modulus", "must be > 0 Pa (got " + num(m.youngs_modulus) + ")");
    if (!(m.poisson_ratio > -1 && m.poisson_ratio < 0.5))
      fail(key + ".poisson_ratio", "must be in (-1, 0.5) (got " + num(m.poisson_ratio) + ")");
    // A clump's component books the strike with its body's mass (cl/body.h).
    for (const SizeClass& s : c.sizes)
      if (m.impact_wear_coefficient > 0 && !s.shape.empty())
        fail(key + ".impact_wear_coefficient", "impact wear with a charge of clumps: a component's strike is booked "
                                               "with its body's whole mass, so the wear would be overcounted");
  }

  // Size classes.
  double d_min = 1e300, fsum = 0;
  for (std::size_t k = 0; k < c.sizes.size(); ++k) {
    const SizeClass& s = c.sizes[k];
    const std::string key = "charge.size[" + std::to_string(k) + "]";
    if (!(s.diameter_min > 0)) fail(key + ".diameter", "must be > 0 m (got " + num(s.diameter_min) + ")");
    if (!(s.diameter_max >= s.diameter_min))
      fail(key + ".diameter_max", "must be >= diameter_min (" + num(s.diameter_min) + " m)");
    if (material_index(c, s.material) < 0) fail(key + ".material", "unknown material \"" + s.material + "\"");
    if (!(s.fraction > 0 && s.fraction <= 1)) fail(key + ".fraction", "must be in (0, 1] (got " + num(s.fraction) + ")");
    d.largest_ball_diameter = std::max(d.largest_ball_diameter, s.diameter_max);
    d_min = std::min(d_min, s.diameter_min);
    fsum += s.fraction;
  }
  if (std::abs(fsum - 1.0) > 1e-6)
    fail("charge.size", "the fractions sum to " + num(fsum) + ", not 1");
  const double dmax = d.largest_ball_diameter;
  if (dmax > 0.25 * c.diameter)
    fail("charge.size", "the largest ball (" + num(dmax) + " m) is more than a quarter of the mill diameter");
  if (dmax * 1.05 > c.length)
    fail("mill.length", "the mill (" + num(c.length) + " m) is shorter than the largest ball (" + num(dmax) + " m)");
  d.shortest_slice = kSliceDiameters * dmax;
  if (c.periodic && c.length < d.shortest_slice)
    fail("mill.length", "a periodic slice (mill.ends = \"periodic\") must be at least " + num(kSliceDiameters) +
                            " largest-ball diameters long, " + num(d.shortest_slice) + " m for " + num(1000 * dmax) +
                            " mm balls (got " + num(c.length) + " m): lengthen the slice or use mill.ends = \"plates\"");

  // Speed.
  d.critical_rpm = 42.3 / std::sqrt(c.diameter - dmax);
  if (c.speed_rpm > 0) {
    d.speed_rpm = c.speed_rpm;
    d.speed_fraction = c.speed_rpm / d.critical_rpm;
  } else {
    d.speed_fraction = c.speed_fraction;
    d.speed_rpm = c.speed_fraction * d.critical_rpm;
  }
  if (!(d.speed_fraction > 0 && d.speed_fraction <= 2.0))
    fail(c.speed_rpm > 0 ? "mill.speed_rpm" : "mill.speed_fraction",
         "the speed must be between 0 and 200 % of critical (" + num(d.critical_rpm) + " rpm); got " +
             num(100 * d.speed_fraction) + " %");
  d.omega = d.speed_rpm * 2 * kPi / 60.0;
  d.revolution_s = 60.0 / d.speed_rpm;
  d.tip_speed = d.omega * R;

  // Lifters: inside the shell, clear of each other, room for a ball above.
  double lifter_area = 0;
  if (c.lifter_rows < 0) fail("lifters.rows", "must be >= 0");
  if (c.lifter_rows > 0) {
    if (c.lifter_pattern.empty()) fail("lifters.profile", "rows > 0 needs at least one profile");
    const double spacing = 2 * kPi / c.lifter_rows;
    std::vector<double> half_angle;
    for (std::size_t k = 0; k < c.lifter_pattern.size(); ++k) {
      const LifterProfile& p = c.lifter_pattern[k];
      const std::string key = "lifters.profile[" + std::to_string(k) + "]";
      if (p.polygon()) {
        const std::vector<Vec2> o = profile_outline(p);
        if (static_cast<int>(o.size()) > kLifterMaxPoints)
          fail(key + ".points", std::to_string(o.size()) + " points: a profile has at most " +
                                    std::to_string(kLifterMaxPoints));
        const std::string fault = profile_outline_fault(o, R, dmax);
        if (!fault.empty()) fail(key + ".points", fault);
        const double base_half = std::max(std::fabs(o.front().x), std::fabs(o.back().x));
        if (base_half >= R) fail(key + ".points", "the lifter is wider than the mill");
        half_angle.push_back(std::asin(std::min(1.0, base_half / R)));
        continue;
      }
      if (!(p.height > 0)) fail(key + ".height", "must be > 0 m (got " + num(p.height) + ")");
      if (!(p.height < R - dmax))
        fail(key + ".height", num(p.height) + " m leaves no room for a ball between the lifter and the axis "
                                             "(shell radius " + num(R) + " m)");
      if (!(p.top_width > 0)) fail(key + ".top_width", "must be > 0 m (got " + num(p.top_width) + ")");
      if (!(p.face_angle_deg >= 0 && p.face_angle_deg < 60))
        fail(key + ".face_angle", "must be in [0, 60) degrees (got " + num(p.face_angle_deg) + ")");
      const double base_half = 0.5 * p.top_width + p.height * std::tan(p.face_angle_deg * kPi / 180.0);
      if (base_half >= R) fail(key + ".top_width", "the lifter is wider than the mill");
      half_angle.push_back(std::asin(std::min(1.0, base_half / R)));
    }
    for (int k = 0; k < c.lifter_rows; ++k) {
      // Row k and the next row round (the last row's next is row 0).
      const std::size_t a = k % c.lifter_pattern.size(), b = ((k + 1) % c.lifter_rows) % c.lifter_pattern.size();
      if (half_angle[a] + half_angle[b] >= spacing)
        fail("lifters.rows", std::to_string(c.lifter_rows) + " rows of these profiles overlap at the shell: use fewer "
                             "rows or narrower lifters");
      // A bar may lean over the next one above their feet: the bars inside
      // the shell must not meet.
      const auto bars = bars_on_shell(
          {lifter_polygon(R, c.lifter_pattern[a], 0.0), lifter_polygon(R, c.lifter_pattern[b], spacing)}, R);
      if (c.lifter_rows >= 2 && convex_polygons_overlap(bars[0], bars[1], 1e-9 * R))
        fail("lifters.profile[" + std::to_string(c.lifter_pattern[a].polygon() ? a : b) + "].points",
             "the bar reaches over the next one: with " + std::to_string(c.lifter_rows) +
                 " rows the bars meet inside the mill though their feet do not; use fewer rows or lean it less");
      const LifterProfile& p = c.lifter_pattern[a];
      lifter_area += p.polygon() ? measure_profile(profile_outline(p)).area
                                 : p.height * (p.top_width + p.height * std::tan(p.face_angle_deg * kPi / 180.0));
    }
  }
  d.lifter_volume = lifter_area * c.length;
  // Closed meshes of liners and lifters that turn with the mill take their
  // volume from the mill's (open ones cannot say what they enclose).
  const EndsSpec& e = c.ends;
  if (e.cones() && !(e.trunnion_diameter < c.diameter - 2 * d.largest_ball_diameter))
    fail("mill.trunnion_diameter", num(e.trunnion_diameter) + " m leaves the cones no room: it must be less than "
                                   "the mill diameter less two largest balls (" +
                                       num(c.diameter - 2 * d.largest_ball_diameter) + " m)");
  if (e.lifter_rows > 0) {
    if (c.periodic) fail("end_lifters.rows", "a periodic slice (mill.ends = \"periodic\") has no ends to carry lifters");
    if (!(e.lifter_height < 0.25 * c.length))
      fail("end_lifters.height", num(e.lifter_height) + " m is more than a quarter of the mill's length");
    if (!(e.lifter_inner_diameter < c.diameter - 2 * e.lifter_height))
      fail("end_lifters.inner_diameter", "must be less than the diameter less twice the bars' height");
    if (!(e.lifter_width * e.lifter_rows < kPi * std::max(e.lifter_inner_diameter, e.cones() ? e.trunnion_diameter : c.diameter / 3)))
      fail("end_lifters.rows", std::to_string(e.lifter_rows) + " bars " + num(e.lifter_width) +
                                   " m wide overlap towards the axis: use fewer or narrower bars");
  }
  if (!c.meshes.empty() || e.cones() || e.lifter_rows > 0)
    for (const WallMesh& m : place_meshes(c))
      if (m.turning && m.part != MeshPart::ends) d.lifter_volume += m.volume;
  d.mill_volume = kPi * R * R * c.length - d.lifter_volume;
  for (const auto& depth : c.plate_depth) d.mill_volume += plate_worn_volume(depth, R);  // worn plates' dishes
  // Cone heads add two frusta, from the shell to the trunnion.
  if (e.cones()) {
    const double rt = 0.5 * e.trunnion_diameter, h = cone_depth(e, R);
    d.mill_volume += 2 * kPi * h / 3 * (R * R + R * rt + rt * rt);
  }
  if (!(d.mill_volume > 0 && std::isfinite(d.mill_volume)))
    fail("lifters.profile", "the lifters leave no room in the mill (free volume " + num(d.mill_volume) + " m³)");

  // Charge.
  if (!(c.filling > 0 && c.filling <= 0.5))
    fail("charge.filling", "must be in (0, 0.5]: above half full the charge cannot tumble (got " + num(c.filling) + ")");
  if (!(c.porosity >= 0.2 && c.porosity <= 0.7))
    fail("charge.porosity", "must be in [0.2, 0.7] (got " + num(c.porosity) + ")");
  d.charge_solid_volume = c.filling * d.mill_volume * (1 - c.porosity);
  std::vector<double> mean_volume(c.sizes.size());
  for (std::size_t k = 0; k < c.sizes.size(); ++k)
    mean_volume[k] = kPi / 6.0 * mean_cube(c.sizes[k].diameter_min, c.sizes[k].diameter_max);
  // Ball counts, in double first: an absurd case (a huge mill, tiny balls)
  // must be refused by the count, not overflow a long.
  std::vector<double> counts(c.sizes.size(), 0.0);
  if (c.number_fractions) {
    double per_ball = 0;
    for (std::size_t k = 0; k < c.sizes.size(); ++k) per_ball += c.sizes[k].fraction * mean_volume[k];
    const double n_total = d.charge_solid_volume / per_ball;
    for (std::size_t k = 0; k < c.sizes.size(); ++k) counts[k] = n_total * c.sizes[k].fraction;
  } else {
    double vol_weight = 0;
    for (const SizeClass& s : c.sizes) vol_weight += s.fraction / c.materials[material_index(c, s.material)].density;
    for (std::size_t k = 0; k < c.sizes.size(); ++k) {
      const SizeClass& s = c.sizes[k];
      const double share = s.fraction / c.materials[material_index(c, s.material)].density / vol_weight;
      counts[k] = share * d.charge_solid_volume / mean_volume[k];
    }
  }
  double n_total = 0;
  for (double n : counts) n_total += std::max(1.0, n);
  if (!(n_total <= kMaxBalls))
    fail("charge", "the case needs " + num(n_total) + " balls (a " + num(c.diameter) + " m x " + num(c.length) +
                       " m mill, smallest ball " + num(d_min) + " m, charge.filling " + num(c.filling) +
                       "), more than the 50 million supported: use larger balls, a lower filling or a smaller mill");
  d.class_counts.assign(c.sizes.size(), 0);
  for (std::size_t k = 0; k < c.sizes.size(); ++k) d.class_counts[k] = std::max(1L, std::lround(counts[k]));
  double solid = 0;
  for (std::size_t k = 0; k < c.sizes.size(); ++k) {
    d.n_balls += d.class_counts[k];
    solid += d.class_counts[k] * mean_volume[k];
    d.charge_mass += d.class_counts[k] * mean_volume[k] * c.materials[material_index(c, c.sizes[k].material)].density;
  }
  d.filling_from_counts = solid / (1 - c.porosity) / d.mill_volume;

  // The initial packing (build_scene) drops balls in columns one smallest
  // ball apart and finds neighbours in a grid of cells one largest ball wide:
  // both grow with the mill's size in balls, whatever the filling.
  const PackingGrid g = packing_grid(c, d_min, dmax);
  if (!(g.columns <= kMaxColumns))
    fail("charge.size", "the mill (" + num(c.diameter) + " m x " + num(c.length) + " m) is too large for its smallest balls (" +
                            num(d_min) + " m): placing them needs " + num(g.columns) +
                            " columns, more than 10 million; use larger balls or a smaller mill");
  if (!(g.cells <= kMaxCells))
    fail("charge.size", "the mill (" + num(c.diameter) + " m x " + num(c.length) + " m) is too large for its largest balls (" +
                            num(dmax) + " m): placing them needs a grid of " + num(g.cells) +
                            " cells, more than 200 million; use larger balls or a smaller mill");

  // Contact pairs and the shortest contact.
  auto check_interaction = [&](const Interaction& in, const std::string& key) {
    if (!(in.restitution > 0 && in.restitution <= 1))
      fail(key + ".restitution", "must be in (0, 1] (got " + num(in.restitution) + ")");
    if (!(in.mu_slide >= 0 && in.mu_slide <= 10)) fail(key + ".friction", "must be in [0, 10] (got " + num(in.mu_slide) + ")");
    if (!(in.mu_roll >= 0 && in.mu_roll <= 1))
      fail(key + ".rolling_friction", "must be in [0, 1] (got " + num(in.mu_roll) + ")");
    if (!(in.kn > 0)) fail(key + ".stiffness", "must be > 0 N/m (got " + num(in.kn) + ")");
    if (!(in.kt_over_kn > 0 && in.kt_over_kn <= 1))
      fail(key + ".tangential_stiffness_ratio", "must be in (0, 1] (got " + num(in.kt_over_kn) + ")");
  };
  check_interaction(c.contact, "contact");
  for (std::size_t k = 0; k < c.pairs.size(); ++k) {
    const std::string key = "contact.pair[" + std::to_string(k) + "]";
    if (material_index(c, c.pairs[k].a) < 0) fail(key + ".materials", "unknown material \"" + c.pairs[k].a + "\"");
    if (material_index(c, c.pairs[k].b) < 0) fail(key + ".materials", "unknown material \"" + c.pairs[k].b + "\"");
    check_interaction(c.pairs[k].interaction, key);
  }
  auto pair_of = [&](const std::string& a, const std::string& b) -> const Interaction& {
    for (const PairOverride& p : c.pairs)
      if ((p.a == a && p.b == b) || (p.a == b && p.b == a)) return p.interaction;
    return c.contact;
  };
  d.contact_time = 1e300;
  const double v_impact = std::max(d.tip_speed, 1.0);
  for (const SizeClass& si : c.sizes)
    for (const SizeClass& sj : c.sizes) {
      const Material& mi = c.materials[material_index(c, si.material)];
      const Material& mj = c.materials[material_index(c, sj.material)];
      const double m1 = mi.density * sphere_volume(si.diameter_min);
      const double m2 = mj.density * sphere_volume(sj.diameter_min);
      const double m_eff = m1 * m2 / (m1 + m2);
      double tc;
      if (c.law == ContactLaw::linear) {
        tc = contact_time_linear(pair_of(si.material, sj.material).kn, m_eff);
      } else {
        const double e_star = 1.0 / ((1 - mi.poisson_ratio * mi.poisson_ratio) / mi.youngs_modulus +
                                     (1 - mj.poisson_ratio * mj.poisson_ratio) / mj.youngs_modulus);
        const double r1 = 0.5 * si.diameter_min, r2 = 0.5 * sj.diameter_min;
        tc = contact_time_hertz(e_star, r1 * r2 / (r1 + r2), m_eff, v_impact);
      }
      d.contact_time = std::min(d.contact_time, tc);
    }

  // Time step and run times.
  if (!(c.steps_per_contact >= 8 && c.steps_per_contact <= 1000))
    fail("run.steps_per_contact", "must be in [8, 1000] (got " + num(c.steps_per_contact) + ")");
  if (!(d.contact_time > 0 && d.contact_time < 1e300))
    fail("contact.stiffness", "the shortest contact lasts " + num(d.contact_time) +
                                  " s: check the stiffness, the materials and the ball sizes");
  d.dt_auto = !(c.dt > 0);
  if (c.dt < 0) fail("run.dt", "must be > 0 s or \"auto\" (got " + num(c.dt) + ")");
  d.dt = d.dt_auto ? d.contact_time / c.steps_per_contact : c.dt;
  if (!d.dt_auto && d.dt > d.contact_time / 8)
    fail("run.dt", num(c.dt) + " s is too large for the contact stiffness: the shortest contact lasts " +
                       num(d.contact_time) + " s and needs at least 8 steps (dt <= " + num(d.contact_time / 8) +
                       " s); use dt = \"auto\" or a softer contact");
  if (!(c.tolerance > 0 && c.tolerance < 1))
    fail("run.tolerance", "must be in (0, 1), the standard error of the power's mean relative to it, e.g. 0.01 "
                          "for 1 % (got " + num(c.tolerance) + ")");
  if (!(c.settle_damping <= 200))
    fail("run.settle_damping", "must be at most 200 1/s or \"auto\" (got " + num(c.settle_damping) + ")");
  if (c.duration_auto) {
    if (!(c.warmup >= 0 && c.warmup <= 1e6)) fail("run.warmup", "must be >= 0 s (got " + num(c.warmup) + ")");
    if (c.max_duration >= 0 && !(c.max_duration >= c.warmup + d.revolution_s))
      fail("run.max_duration", "must leave at least one revolution (" + num(d.revolution_s) +
                                   " s) after the warm-up of " + num(c.warmup) + " s (got " + num(c.max_duration) +
                                   " s)");
    d.turn_limit_s = c.max_duration >= 0 ? c.max_duration : c.warmup + kAutoRevolutions * d.revolution_s;
  } else {
    if (!(c.duration > 0)) fail("run.duration", "must be > 0 s or \"auto\" (got " + num(c.duration) + ")");
    if (!(c.warmup >= 0 && c.warmup < c.duration))
      fail("run.warmup", "must be in [0, duration = " + num(c.duration) + " s) (got " + num(c.warmup) + ")");
    d.turn_limit_s = c.duration;
  }
  d.settle_damping = c.settle_damping >= 0 ? c.settle_damping : kSettleDamping * std::sqrt(9.81 / c.diameter);
  if (!(c.output_interval >= d.dt)) fail("run.output_interval", "must be at least one step (" + num(d.dt) + " s)");
  if (c.snapshot_interval < 0) fail("run.snapshot_interval", "must be >= 0 s (0: no snapshots)");
  if (!(c.checkpoint_interval >= 0))
    fail("run.checkpoint_interval", "must be >= 0 s (0: checkpoints only on a signal and at the end)");
  if (c.settle > 60) fail("run.settle", "must be at most 60 s or \"auto\"");
  const char* turn_key = c.duration_auto ? "run.max_duration" : "run.duration";
  const double steps = (d.turn_limit_s + std::max(c.settle, 0.0)) / d.dt;
  if (!(steps <= kMaxSteps))
    fail(turn_key, num(d.turn_limit_s) + " s at dt " + num(d.dt) + " s is " + num(steps) +
                       " steps, more than 1e11: shorten the run, or raise run.dt or soften the contacts");
  if (c.snapshot_interval > 0 && !(d.turn_limit_s / c.snapshot_interval <= 1e5))
    fail("run.snapshot_interval", num(c.snapshot_interval) + " s gives " + num(d.turn_limit_s / c.snapshot_interval) +
                                      " snapshots, more than 100000");
  return d;
}

ClumpShape size_class_shape(const MillCase& c, const std::string& name, const std::string& key) {
  for (const ClumpShape& sh : c.shapes)
    if (sh.name == name) return sh;
  try {
    return library_shape(name);
  } catch (const std::invalid_argument& e) {
    std::string list;
    for (const ClumpShape& sh : c.shapes) list += (list.empty() ? "" : ", ") + sh.name;
    throw std::invalid_argument(key + ": " + e.what() +
                                (list.empty() ? std::string() : "; the case's [[charge.shape]] are " + list));
  }
}

Scene build_scene(const MillCase& c, const MillDerived& d) {
  Scene s = build_walls(c, d);
  const double R = 0.5 * c.diameter;

  // The balls, shuffled so the sizes mix, are dropped one by one onto the
  // lowest of a grid of columns in x–z (pitch just over the smallest
  // diameter) and rest where they first touch nothing: above the balls already
  // placed (checked exactly through a cell grid), inside the shell, clear of
  // the lifters and the end plates. The charge fills the mill from the bottom.
  // A periodic slice has no end plates: its columns tile the period, a ball
  // may straddle the seam (its z is wrapped), and balls are kept apart
  // across the seam through the minimum image.
  const bool periodic = c.periodic;
  const double L = c.length;
  auto image_dz = [&](double dz) { return periodic ? dz - L * std::floor(dz / L + 0.5) : dz; };
  std::mt19937_64 rng(c.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // A class of clumps: its shape at a volume-equivalent diameter of 1 in
  // its principal frame, that shape's volume and principal moments (per
  // unit density), and the radius of the sphere about its centre that
  // holds it (which places it clear of the walls).
  struct ClassShape {
    bool clump = false;
    ClumpShape unit;
    double volume = 0, bound = 0.5;
    Vec3 moments;
  };
  std::vector<ClassShape> shapes(c.sizes.size());
  for (std::size_t k = 0; k < c.sizes.size(); ++k) {
    if (c.sizes[k].shape.empty()) continue;
    ClassShape& cs = shapes[k];
    cs.clump = true;
    cs.unit = normalised_shape(size_class_shape(c, c.sizes[k].shape, "charge.size[" + std::to_string(k) + "].shape"), 1.0);
    const ClumpMassProperties mp = clump_mass_properties(cs.unit);
    cs.volume = mp.volume;
    cs.moments = mp.principal;
    cs.bound = 0;
    for (const ClumpSphere& q : cs.unit.spheres) cs.bound = std::max(cs.bound, q.centre.norm() + q.radius);
  }
  struct Pending {
    double radius;  // a ball's; a clump's volume-equivalent one
    int material;
    int size_class;
  };
  std::vector<Pending> pending;
  pending.reserve(d.n_balls);
  double rmin = 1e300;
  for (std::size_t k = 0; k < c.sizes.size(); ++k) {
    const SizeClass& sc = c.sizes[k];
    const int mat = material_index(c, sc.material);
    rmin = std::min(rmin, 0.5 * sc.diameter_min);
    for (long i = 0; i < d.class_counts[k]; ++i)
      pending.push_back(
          {0.5 * (sc.diameter_min + (sc.diameter_max - sc.diameter_min) * unit(rng)), mat, static_cast<int>(k)});
  }
  std::shuffle(pending.begin(), pending.end(), rng);
  // The bodies placed so far, and each placed ball's body (-1: free); ids
  // are renumbered at the end so that the components come last.
  struct Placed {
    Body body;
    int size_class;
  };
  std::vector<Placed> placed_bodies;
  std::vector<int> ball_body;

  const double rmax = 0.5 * d.largest_ball_diameter;
  const double gap = 0.02 * rmin;
  // Columns.
  const double pitch = 2 * rmin + 2 * gap;
  struct Column {
    double x, z, top;
  };
  std::vector<Column> columns;
  const int nx = static_cast<int>(std::floor((2 * R - 2 * gap) / pitch));
  const int nz = periodic ? std::max(1, static_cast<int>(std::floor(L / pitch)))
                          : std::max(1, static_cast<int>(std::floor((c.length - 2 * gap) / pitch)));
  const double pitch_z = periodic ? L / nz : pitch;
  const double z0 = periodic ? 0.5 * pitch_z : 0.5 * (c.length - (nz - 1) * pitch);
  for (int ix = 0; ix < nx; ++ix) {
    const double x = -0.5 * (nx - 1) * pitch + ix * pitch;
    if (std::abs(x) + rmin + gap >= R) continue;
    for (int iz = 0; iz < nz; ++iz) columns.push_back({x, z0 + iz * pitch_z, -R});
  }
  // The lowest column first; stale heap entries are skipped.
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> lowest;
  for (int k = 0; k < static_cast<int>(columns.size()); ++k) lowest.push({columns[k].top, k});
  std::vector<char> closed(columns.size(), 0);

  // Placed balls in a cell grid (cells 2·rmax wide) for the exact overlap test.
  const double cell = 2 * rmax + 2 * gap;
  const int gx = static_cast<int>(std::ceil(2 * R / cell)) + 1;
  // A slice's z cells tile the period (taken modulo gz).
  const int gz = periodic ? std::max(1, static_cast<int>(std::floor(L / cell)))
                          : static_cast<int>(std::ceil(c.length / cell)) + 1;
  const double cell_z = periodic ? L / gz : cell;
  // Each cell holds the first and last of its balls, next_in_cell links them
  // in the order placed (8 bytes a cell: derive() bounds the cells).
  std::vector<int> grid(static_cast<std::size_t>(gx) * gx * gz, -1), grid_last(grid.size(), -1);
  std::vector<int> next_in_cell;
  next_in_cell.reserve(pending.size());
  auto cell_of = [&](double v, double lo, int n) {
    return static_cast<int>(std::clamp(std::floor((v - lo) / cell), 0.0, static_cast<double>(n - 1)));
  };
  auto cell_z_of = [&](double z) {
    if (!periodic) return cell_of(z, 0.0, gz);
    const int k = static_cast<int>(std::floor(z / cell_z)) % gz;
    return k < 0 ? k + gz : k;
  };
  // The z cells next to cell iz (itself included), each once.
  auto z_neighbours = [&](int iz, int* out) {
    int n = 0;
    if (periodic && gz < 3) {
      for (int k = 0; k < gz; ++k) out[n++] = k;
    } else if (periodic) {
      for (int k = -1; k <= 1; ++k) out[n++] = (iz + k + gz) % gz;
    } else {
      for (int k = std::max(0, iz - 1); k <= std::min(gz - 1, iz + 1); ++k) out[n++] = k;
    }
    return n;
  };
  auto cell_index = [&](int ix, int iy, int iz) { return (static_cast<std::size_t>(iz) * gx + iy) * gx + ix; };
  auto grid_at = [&](int ix, int iy, int iz) { return grid[cell_index(ix, iy, iz)]; };

  struct Bound {
    double cx, cy, r;
  };
  std::vector<Bound> bounds;
  for (const auto& poly : s.walls.lifters) {
    double cx = 0, cy = 0;
    for (const Vec2& v : poly) cx += v.x / poly.size(), cy += v.y / poly.size();
    double r = 0;
    for (const Vec2& v : poly) r = std::max(r, std::hypot(v.x - cx, v.y - cy));
    bounds.push_back({cx, cy, r});
  }
  // Mesh walls: balls are placed inside the radius the liner and lifter
  // meshes leave free, and clear of the end meshes' reach into the mill
  // (the charge settles into what is left).
  double mesh_ring = R, mesh_z_lo = 0, mesh_z_hi = c.length;
  for (const WallMesh& m : s.walls.meshes)
    for (const Triangle& t : m.triangles) {
      if (m.part != MeshPart::ends) {
        for (int e = 0; e < 3; ++e) {  // the triangle's nearest approach to the axis, over its edges
          const Vec3 a = t.v[e], b = t.v[(e + 1) % 3];
          const double ex = b.x - a.x, ey = b.y - a.y, l2 = ex * ex + ey * ey;
          const double u = l2 > 0 ? std::clamp(-(a.x * ex + a.y * ey) / l2, 0.0, 1.0) : 0.0;
          mesh_ring = std::min(mesh_ring, std::hypot(a.x + u * ex, a.y + u * ey));
        }
      } else {
        const double zmin = std::min({t.v[0].z, t.v[1].z, t.v[2].z}), zmax = std::max({t.v[0].z, t.v[1].z, t.v[2].z});
        if (zmax <= 0.5 * c.length) mesh_z_lo = std::max(mesh_z_lo, zmax);
        else if (zmin >= 0.5 * c.length) mesh_z_hi = std::min(mesh_z_hi, zmin);
      }
    }
  auto clear_of_lifters = [&](double x, double y, double r) {
    if (std::hypot(x, y) + r + gap > mesh_ring) return false;
    for (std::size_t k = 0; k < bounds.size(); ++k) {
      if (std::hypot(x - bounds[k].cx, y - bounds[k].cy) > bounds[k].r + r + gap) continue;
      if (polygon_signed_distance(s.walls.lifters[k], x, y) < r + gap) return false;
    }
    return true;
  };
  // The lowest y >= y0 at (x, z) where a ball of radius r overlaps no placed
  // ball; each overlap lifts it onto that ball.
  auto rest_height = [&](double x, double y0, double z, double r) {
    double y = y0;
    for (bool moved = true; moved;) {
      moved = false;
      const int ix = cell_of(x, -R, gx), iy = cell_of(y, -R, gx);
      int zs[3];
      const int n_zs = z_neighbours(cell_z_of(z), zs);
      for (int q = 0; q < n_zs; ++q)
        for (int cy = std::max(0, iy - 1); cy <= std::min(gx - 1, iy + 1); ++cy)
          for (int cx = std::max(0, ix - 1); cx <= std::min(gx - 1, ix + 1); ++cx)
            for (int j = grid_at(cx, cy, zs[q]); j >= 0; j = next_in_cell[j]) {
              const Ball& b = s.balls[j];
              const double reach = r + b.radius + gap;
              const double dx = x - b.position.x, dz = image_dz(z - b.position.z), dy = y - b.position.y;
              if (dx * dx + dy * dy + dz * dz >= reach * reach) continue;
              const double h2 = reach * reach - dx * dx - dz * dz;
              y = b.position.y + std::sqrt(std::max(0.0, h2)) + 1e-9 * R;
              moved = true;
            }
    }
    return y;
  };

  // A clump's components about the point (x, y, z) at orientation q: the
  // lowest y >= y0 where none of them overlaps a placed ball.
  auto rest_height_clump = [&](const std::vector<Vec3>& offsets, const std::vector<double>& radii, double x,
                               double y0, double z) {
    double y = y0;
    for (bool moved = true; moved;) {
      moved = false;
      for (std::size_t q = 0; q < offsets.size(); ++q) {
        const Vec3& o = offsets[q];
        const double zq = periodic ? z + o.z - L * std::floor((z + o.z) / L) : z + o.z;
        const double yq = rest_height(x + o.x, y + o.y, zq, radii[q]);
        if (yq > y + o.y) {
          y = yq - o.y;
          moved = true;
        }
      }
    }
    return y;
  };
  auto add_to_grid = [&](const Ball& b) {
    const std::size_t at =
        cell_index(cell_of(b.position.x, -R, gx), cell_of(b.position.y, -R, gx), cell_z_of(b.position.z));
    next_in_cell.push_back(-1);
    if (grid_last[at] >= 0) next_in_cell[grid_last[at]] = b.id;
    else grid[at] = b.id;
    grid_last[at] = b.id;
  };

  s.balls.reserve(pending.size());
  for (const Pending& pend : pending) {
    const ClassShape& cs = shapes[pend.size_class];
    const double d_eq = 2 * pend.radius;
    // A clump: a random orientation (uniform on the rotations, Shoemake's
    // method) and its components about its centre; the sphere that holds
    // it stands for it at the walls.
    std::array<double, 4> orient{0, 0, 0, 1};
    std::vector<Vec3> offsets;
    std::vector<double> radii;
    if (cs.clump) {
      const double u1 = unit(rng), u2 = 2 * kPi * unit(rng), u3 = 2 * kPi * unit(rng);
      const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
      orient = {a * std::sin(u2), a * std::cos(u2), b * std::sin(u3), b * std::cos(u3)};
      for (const ClumpSphere& q : cs.unit.spheres) {
        offsets.push_back(rotate(orient, q.centre * d_eq));
        radii.push_back(q.radius * d_eq);
      }
    }
    const Pending p{cs.clump ? cs.bound * d_eq : pend.radius, pend.material, pend.size_class};
    bool placed = false;
    while (!lowest.empty() && !placed) {
      const auto [top, k] = lowest.top();
      lowest.pop();
      if (closed[k] || top != columns[k].top) continue;  // closed, or a stale entry
      const Column& col = columns[k];
      const double ring = R - p.radius - gap;  // centre circle clear of the shell
      const double x = col.x + 0.1 * pitch * (2 * unit(rng) - 1);
      const double z_jittered = col.z + 0.1 * pitch * (2 * unit(rng) - 1);
      const double z = periodic ? z_jittered - L * std::floor(z_jittered / L)
                                : std::clamp(z_jittered, mesh_z_lo + p.radius + gap, mesh_z_hi - p.radius - gap);
      if (std::abs(x) >= ring) {
        closed[k] = 1;
        continue;
      }
      const double ceil_y = std::sqrt(ring * ring - x * x);
      double y = std::max(-ceil_y, col.top + (cs.clump ? pend.radius : p.radius) + gap);
      for (;;) {
        y = cs.clump ? rest_height_clump(offsets, radii, x, y, z) : rest_height(x, y, z, p.radius);
        if (y > ceil_y || clear_of_lifters(x, y, p.radius)) break;
        y += 0.25 * p.radius;
      }
      if (y > ceil_y) {
        closed[k] = 1;  // this column is full
        continue;
      }
      if (!cs.clump) {
        Ball b;
        b.id = static_cast<int>(s.balls.size());
        b.material = p.material;
        b.radius = p.radius;
        b.position = {x, y, z};
        add_to_grid(b);
        s.balls.push_back(b);
        ball_body.push_back(-1);
        columns[k].top = y + p.radius;
      } else {
        Body body;
        const double density = c.materials[p.material].density;
        body.mass = density * cs.volume * std::pow(d_eq, 3);
        body.inertia = cs.moments * (density * std::pow(d_eq, 5));
        body.position = {x, y, z};
        body.orientation = orient;
        body.first = static_cast<int>(s.balls.size());
        body.count = static_cast<int>(offsets.size());
        double top = y;
        for (std::size_t q = 0; q < offsets.size(); ++q) {
          Ball b;
          b.id = static_cast<int>(s.balls.size());
          b.material = p.material;
          b.radius = radii[q];
          b.position = {x + offsets[q].x, y + offsets[q].y, z + offsets[q].z};
          if (periodic) b.position.z -= L * std::floor(b.position.z / L);
          b.body = static_cast<int>(placed_bodies.size());
          b.offset = cs.unit.spheres[q].centre * d_eq;
          add_to_grid(b);
          s.balls.push_back(b);
          ball_body.push_back(b.body);
          top = std::max(top, b.position.y + b.radius);
        }
        placed_bodies.push_back({body, p.size_class});
        columns[k].top = top;
      }
      lowest.push({columns[k].top, k});
      placed = true;
    }
    if (!placed) {
      std::ostringstream m;
      const long free_balls = std::count(ball_body.begin(), ball_body.end(), -1);
      m << "charge.filling: only " << free_balls + static_cast<long>(placed_bodies.size()) << " of " << d.n_balls
        << " particles fit in the mill before settling; lower the filling or use fewer, larger size classes";
      throw std::invalid_argument(m.str());
    }
  }
  if (placed_bodies.empty()) return s;
  // Ids: the free balls first, in the order placed, then each body's
  // components (core/scene.h).
  std::vector<Ball> balls;
  balls.reserve(s.balls.size());
  for (std::size_t i = 0; i < s.balls.size(); ++i)
    if (ball_body[i] < 0) {
      balls.push_back(s.balls[i]);
      balls.back().id = static_cast<int>(balls.size()) - 1;
    }
  std::vector<std::vector<int>> members(placed_bodies.size());
  for (std::size_t i = 0; i < s.balls.size(); ++i)
    if (ball_body[i] >= 0) members[ball_body[i]].push_back(static_cast<int>(i));
  for (std::size_t b = 0; b < placed_bodies.size(); ++b) {
    Body body = placed_bodies[b].body;
    body.first = static_cast<int>(balls.size());
    for (int i : members[b]) {
      balls.push_back(s.balls[i]);
      balls.back().id = static_cast<int>(balls.size()) - 1;
    }
    s.bodies.push_back(body);
  }
  s.balls = std::move(balls);
  return s;
}

double settled_filling(const Scene& scene, const std::vector<Vec3>& xyr) {
  const double R = scene.walls.shell_radius;
  if (xyr.empty() || !(R > 0)) return 0;
  // The free surface: the top of the highest ball in columns across the
  // middle half of the mill's width, averaged.
  double rmax = 0;
  for (const Vec3& b : xyr) rmax = std::max(rmax, b.z);
  const double width = 4 * rmax;
  const int n_cols = std::max(1, static_cast<int>(R / width));
  std::vector<double> top(n_cols, -1e300);
  for (const Vec3& b : xyr) {
    const int k = static_cast<int>(std::floor((b.x + 0.5 * R) / width));
    if (k >= 0 && k < n_cols) top[k] = std::max(top[k], b.y + b.z);
  }
  double level = 0;
  int used = 0;
  for (double t : top)
    if (t > -1e299) level += t, ++used;
  if (used == 0) return 0;
  level = std::clamp(level / used, -R, R);
  // Segment of the circle below y = level.
  const double h = level + R;  // depth of the segment
  const double segment = R * R * std::acos((R - h) / R) - (R - h) * std::sqrt(std::max(0.0, 2 * R * h - h * h));
  double lifter_area = 0, free_area = kPi * R * R;
  for (const auto& poly : scene.walls.lifters) {
    // Area of the part of the polygon inside the shell and below the level,
    // by sampling (the polygons are small): a 24×24 grid on their box.
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (const Vec2& v : poly) x0 = std::min(x0, v.x), x1 = std::max(x1, v.x), y0 = std::min(y0, v.y), y1 = std::max(y1, v.y);
    const int n = 24;
    double inside = 0, below = 0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const double x = x0 + (i + 0.5) * (x1 - x0) / n, y = y0 + (j + 0.5) * (y1 - y0) / n;
        if (polygon_signed_distance(poly, x, y) > 0 || std::hypot(x, y) > R) continue;
        inside += 1;
        if (y < level) below += 1;
      }
    const double cell = (x1 - x0) * (y1 - y0) / (n * n);
    free_area -= inside * cell;
    lifter_area += below * cell;
  }
  return (segment - lifter_area) / free_area;
}

MorrellInput morrell_input(const MillCase& c, const MillDerived& d) {
  MorrellInput m;
  m.diameter = c.diameter;
  m.length = c.length;
  m.filling = d.filling_from_counts;
  m.speed_fraction = d.speed_fraction;
  m.speed_rpm = d.speed_rpm;
  m.charge_density = d.charge_mass / (d.filling_from_counts * d.mill_volume);
  return m;
}

}  // namespace mc
