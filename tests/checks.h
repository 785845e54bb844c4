// The physics checks of ../shared/reference/VERIFICATION.md as functions
// that set up a scene, run it on a device and return what was measured
// beside what theory or the published table says. The Catch tests assert on
// them (test_contact_law, test_motion, test_drum, test_mill); the
// validation report (tools/validate.cpp, scripts/validate.sh) prints them as
// rows. One setup, so the report shows what the tests test.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "compute/context.h"
#include "core/drum.h"
#include "core/mill_case.h"
#include "core/scene.h"
#include "sim/mill_run.h"

namespace mc::checks {

// ---- Chung & Ooi (2011), VERIFICATION.md §1 ----

// Hertz theory of a normal impact at approach speed v.
struct HertzTheory {
  double delta_max = 0, f_max = 0, t_contact = 0;
};
HertzTheory hertz_theory(double e_star, double r_eff, double m_eff, double v);

// A material of the benchmarks with the values of the paper's table.
struct BenchMaterial {
  const char* name;
  double youngs_modulus, poisson_ratio, density;
  double table_delta, table_force, table_time;  // the paper's δmax, Fmax, tc (SI)
};

struct NormalImpact {
  HertzTheory theory;
  double delta_max = 0, f_max = 0, t_contact = 0;
  double rebound_speed_ratio = 0;  // speed after / speed before
};

// Test 1: two equal spheres head-on, R 10 mm, 10 m/s each, e = 1.
const std::vector<BenchMaterial>& chung_ooi_1_materials();  // glass, limestone
NormalImpact chung_ooi_1(compute::Context& ctx, const BenchMaterial& m, Precision precision);

// Test 2: a sphere (R 0.1 m) onto a rigid wall at 0.2 m/s, e = 1, μ = 0.
const std::vector<BenchMaterial>& chung_ooi_2_materials();  // Al alloy, Mg alloy
NormalImpact chung_ooi_2(compute::Context& ctx, const BenchMaterial& m);

// Test 3: a sphere (R 2.5 mm) onto a wall at 3.9 m/s with input e; returns
// the rebound ratio.
const std::vector<Material>& chung_ooi_3_materials();  // alumina, cast iron
double chung_ooi_3(compute::Context& ctx, ContactLaw law, const Material& m, double e);

// Test 4: oblique impact at |v| 3.9 m/s and incidence theta (from the
// normal), e 0.98, μ 0.092; in the sliding range (θ ≥ 32.5°) theory gives
// the tangential restitution and the rebound spin.
struct ObliqueImpact {
  double et = 0, et_theory = 0;        // tangential restitution
  double spin = 0, spin_theory = 0;    // rad/s
};
const std::vector<Material>& chung_ooi_4_materials();  // alumina, Al alloy
ObliqueImpact chung_ooi_4(compute::Context& ctx, const Material& m, double theta_deg);

// ---- single balls, VERIFICATION.md §2 and §3 ----

// A ball sliding on a floor (μ 0.3) from 1 m/s: after 1.5 times the
// sliding time it rolls at 5/7 of that speed with ω r = v.
// While it slides the contact point slips s = v0²/(7 μ g): the liner's
// books take shear work μ m g s and Archard wear k m g s (k the floor's
// wear_coefficient).
struct Rolling {
  double speed_ratio = 0;  // v / v0
  double slip_ratio = 0;   // ω r / v
  double shear_J = 0, shear_theory_J = 0;      // the floor's shear energy, and μ m g s
  double wear_m3 = 0, wear_theory_m3 = 0;      // its Archard volume, and k m g s
};
Rolling sliding_to_rolling(compute::Context& ctx, ContactLaw law);

// A ball carried on a smooth turning shell (D 1.02 m, centre path
// Rb = 0.5 m) at the fraction phi of critical speed, no slip: it leaves
// where cos α = φ² (α from the top vertical, before the top), flies a
// parabola and lands 3α past the top (counter-clockwise, the way the mill
// turns) after 4 ω Rb sin α / g.
struct ShellFlight {
  double departure_deg = -1, departure_theory_deg = 0;
  double landing_deg = -1, landing_theory_deg = 0;
  double flight_s = -1, flight_theory_s = 0;
};
ShellFlight shell_flight(compute::Context& ctx, double phi);

// ---- the whole solver ----

// 300 balls with random velocities in a closed drum, e = 1, μ = 0, no
// rolling resistance, 10⁴ steps: the worst |E − E0| over the initial
// kinetic energy.
struct ElasticBox {
  double worst_drift = 0;  // fraction of the initial kinetic energy
  long samples_with_contacts = 0;
  double dissipated_J = 0;
};
ElasticBox elastic_box(compute::Context& ctx, ContactLaw law);

// The 0.3 m drum (300 balls, 8 lifters, 75 % of critical) turned 1.5 s, then
// three revolutions measured: the walls' power against the dissipation
// plus the change of the charge's energy.
struct PowerBalance {
  double window_s = 0;
  double torque_power_W = 0, dissipation_power_W = 0, energy_change_W = 0;
  double torque_times_omega_W = 0;  // wall torque × ω, against torque_power_W
  // (torque − dissipation − dE/dt) / torque
  double imbalance() const { return (torque_power_W - dissipation_power_W - energy_change_W) / torque_power_W; }
};
PowerBalance drum_power_balance(compute::Context& ctx, ContactLaw law);
// The same books of any drum: turned warmup_s, then whole revolutions
// measured. `forces` names the force kernel (MILLCHARGE_FORCES), or null.
PowerBalance drum_power_balance(compute::Context& ctx, const DrumSpec& spec, double warmup_s, int revolutions,
                                const char* forces = nullptr);

// The lab mill (assets/cases/lab.toml) with overrides, e.g.
// {"mill.speed_fraction=0.5", "mill.length=0.1"}, run as `millcharge run`
// runs it (settle, turn, average), without writing files.
struct LabRun {
  MillCase c;
  MillDerived d;
  Scene scene;  // as built for the run (its balls as packed)
  RunSummary s;
};
LabRun lab_run(compute::Context& ctx, const std::vector<std::string>& overrides);
// The same for any case file.
LabRun case_run(compute::Context& ctx, const std::filesystem::path& file, const std::vector<std::string>& overrides);

}  // namespace mc::checks
