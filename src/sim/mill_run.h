// A mill run: settle the charge with the mill at rest, turn it for the case's
// duration, and measure. Rows of observables at the output interval, the
// contact profile for toe and shoulder, snapshots through a hook; averages
// over the largest whole number of revolutions after the warm-up.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/mill_case.h"
#include "sim/batch_means.h"
#include "sim/charge_profile.h"
#include "sim/solver.h"

namespace mc {

// One row of timeseries.csv: means over the row's interval, energies and the
// centre of mass at its end. Times count from when the mill starts turning.
struct TimeRow {
  double time_s = 0;
  double revolutions = 0;
  double interval_s = 0;
  double torque_Nm = 0;
  double torque_power_W = 0;
  double dissipation_power_W = 0;
  double kinetic_J = 0, rotational_J = 0, potential_J = 0, elastic_J = 0;
  ChargeAngles angles;       // from this row's contact samples
  double com_angle_deg = 0;  // centre of mass, counter-clockwise from 3 o'clock
  double torque_arm_power_W = 0;  // ω·M·g·x̄
  double neighbours_per_ball = 0;
  bool averaged = false;     // inside the averaging window
};

struct RunProgress {
  std::string phase;         // "settle" or "turn"
  double simulated_s = 0;    // in this phase
  double revolutions = 0;
  long steps = 0;            // all steps so far
  double steps_per_s = 0;    // recent
  double updates_per_s = 0;  // balls × steps per wall second, recent
  double done = 0;           // fraction of the run's steps
  double eta_s = 0;          // wall seconds left, estimated (an auto run: to its cap)
  double relative_error = -1; // an auto run: the power's standard error over its mean so far; < 0: not yet
};

// Means over one batch of the averaging window, 1/kBatchesPerRevolution of a
// revolution: the base batches of the standard errors (sim/batch_means.h).
// NaN where a batch has no value (no toe found in it).
struct WindowBatch {
  double span_s = 0;
  double torque_power_W = 0, dissipation_power_W = 0, torque_Nm = 0, torque_arm_power_W = 0;
  double toe_deg = 0, shoulder_deg = 0, com_angle_deg = 0;
  // from the energy books: collisions that closed in it, and the liner's sums
  double collisions_per_s = 0, collision_power_W = 0;
  double liner_impacts_per_s = 0, liner_impact_W = 0, liner_shear_W = 0, wear_kg_per_h = 0;
};
// Its fields in one list, for the checkpoint and for the summary.
inline constexpr double WindowBatch::* kWindowBatchFields[] = {
    &WindowBatch::span_s,           &WindowBatch::torque_power_W,     &WindowBatch::dissipation_power_W,
    &WindowBatch::torque_Nm,        &WindowBatch::torque_arm_power_W, &WindowBatch::toe_deg,
    &WindowBatch::shoulder_deg,     &WindowBatch::com_angle_deg,      &WindowBatch::collisions_per_s,
    &WindowBatch::collision_power_W, &WindowBatch::liner_impacts_per_s, &WindowBatch::liner_impact_W,
    &WindowBatch::liner_shear_W,    &WindowBatch::wear_kg_per_h};

// What the batch being turned has summed so far, and where the row and the
// books stood at its last cut: a batch ends inside a row, so its share of
// that row is the row's sums then minus the sums at the cut.
struct BatchTally {
  double span = 0, work = 0, diss = 0, torque_time = 0;  // exact, from the solver's sums
  double arm_time = 0, rows_span = 0, comx = 0, comy = 0, rows = 0;  // rows that end in it
  double row_span = 0, row_work = 0, row_diss = 0, row_torque_time = 0;  // the row's sums at the cut
  // the books' totals since the window began, at the last revolution's end
  double collisions = 0, collision_J = 0, impacts = 0, impact_J = 0, shear_J = 0, wear_m3 = 0;
};
inline constexpr double BatchTally::* kTallyFields[] = {
    &BatchTally::span,       &BatchTally::work,     &BatchTally::diss,
    &BatchTally::torque_time, &BatchTally::arm_time, &BatchTally::rows_span, &BatchTally::comx,
    &BatchTally::comy,       &BatchTally::rows,     &BatchTally::row_span,
    &BatchTally::row_work,   &BatchTally::row_diss, &BatchTally::row_torque_time,
    &BatchTally::collisions, &BatchTally::collision_J, &BatchTally::impacts,
    &BatchTally::impact_J,   &BatchTally::shear_J,  &BatchTally::wear_m3};

struct RunSummary {
  double settle_s = 0;              // simulated settling time
  double settle_wall_s = 0;         // wall time of settling
  bool settled = false;             // the charge came to rest
  double settled_filling = 0;       // J of the settled bed's surface level
  double turning_s = 0;             // simulated time with the mill turning
  double revolutions = 0;
  long steps = 0;                   // all steps, settling included
  double simulated_s = 0;           // settling + turning
  // averaging window
  double window_from_s = 0, window_to_s = 0;
  double window_revolutions = 0;
  bool whole_revolutions = false;   // false: less than one revolution after the warm-up
  double torque_Nm = 0;
  double torque_power_W = 0;
  double dissipation_power_W = 0;
  double energy_change_W = 0;       // d(kinetic + rotational + potential + elastic)/dt
  double torque_arm_power_W = 0;    // ω·M·g·x̄, the Hogg–Fuerstenau torque arm
  double imbalance = 0;             // (torque − dissipation) / torque power
  ChargeAngles angles;              // from the window's contact profile
  double com_angle_deg = 0;
  double neighbours_per_ball = 0;
  std::vector<long> profile;        // the window's contact counts per bin
  // The energy books over the window: the spectra of the collisions that
  // closed in it, the liner's sums and the impact profile (solver.h), and
  // what the open contacts held at its start and its end.
  BookSums books;
  double open_loss_start_J = 0, open_loss_end_J = 0;
  double dissipated_J = 0;          // over the window
  double window_s = 0;              // simulated seconds of the window
  double mill_angle_end = 0;        // rad, at the end (the liner's place in pictures)
  double wall_s = 0;                // wall time of settling and turning
  double updates_per_s = 0;         // balls × steps / wall_s
  bool interrupted = false;         // stopped on request, checkpoint written
  // The window's batches (the base batches of the standard errors; whole
  // revolutions of them), and how the turning ended.
  std::vector<WindowBatch> window_batches;
  int batches_per_revolution = kBatchesPerRevolution;
  // The liner's books (BookSums liner, then stations) over the window's
  // first half of its batches, and that half's seconds; empty where the
  // run has none (an auto duration, a window of one batch, an extended run).
  std::vector<double> half_books;
  double half_window_s = 0;
  bool duration_auto = false;
  bool converged = false;           // auto: the power's standard error reached the tolerance
  bool capped = false;              // auto: stopped at the cap without converging
};

// Where a run stands, beside the solver's own state: what a checkpoint holds
// so that a resumed run takes the same steps and the same averages.
struct RunState {
  int phase = 0;                 // 0 settling, 1 turning, 2 done
  double settle_start_s = 0;     // solver time when settling began
  bool settled = false;
  double settle_s = 0;
  double settle_wall_s = 0;      // wall seconds the settling took
  double settled_filling = 0;
  double turn_start_s = 0;       // solver time when the mill started
  long turn_step = 0;            // steps of the turning mill done
  std::vector<long> window_profile;
  double open_loss_start = 0;    // what the open contacts held when the window began
  double e_window_start = 0, e_end = 0, work = 0, diss = 0, torque_time = 0, arm_time = 0, span = 0,
         comx = 0, comy = 0, neigh = 0;
  long rows_in_window = 0;
  std::vector<WindowBatch> batches;     // closed batches of the window
  BatchTally batch;                     // the open one
  std::vector<long> batch_profile;      // its rows' contact profile
  std::vector<double> half_books;       // RunSummary::half_books, once taken
  double half_window_s = 0;
  // Batches a revolution is cut into (kBatchesPerRevolution; 1 in
  // checkpoints written when the batches were whole revolutions).
  int batches_per_revolution = kBatchesPerRevolution;
  long stop_step = -1;                       // auto: the turning step it stopped at (converged)
  long rows = 0;                 // rows handed to on_row
  long snapshots = 0;            // snapshots handed to on_snapshot
  double wall_s = 0;             // wall seconds spent before this call
  // An extended run: the turning step before which its window may not begin
  // (where the run it extends had ended; 0: anywhere after the warm-up).
  long window_floor_step = 0;
  // Whether the window's books have begun: 1 yes, 0 no, -1 not recorded
  // (older checkpoints: begun once the step passed the window's start).
  int window_begun = -1;
  // The part of the row that straddles the window's start turned before it
  // (rows fall on multiples of the output interval, the window anywhere).
  double pre_span = 0, pre_work = 0, pre_diss = 0, pre_torque_time = 0;
};

// Where the turning ends and the averaging window lies, in steps of the
// turning mill: what run_mill follows, from the case, the state's floor
// and an auto run's stop.
struct TurnPlan {
  long turn_steps = 0;    // the turning ends here
  long warm_steps = 0;
  long window_start = 0;  // the averaging window begins here
  long revolutions = 0;   // whole revolutions in the window (0: less than one)
  double rev_steps = 0;   // steps of one revolution
  bool whole = false;     // the window holds whole revolutions
};
TurnPlan plan_turning(const MillCase& c, const MillDerived& d, double dt, long window_floor_step = 0,
                      long stop_step = -1);

// The state from which a run goes on with a changed duration (`run
// --resume DIR --duration S`): the finished or interrupted run's state `st`
// under `old_c`, carried on under `new_c`. Where the new plan's window is the
// one already begun (same start, same batches so far) it goes on; where it
// would begin before the point reached, a new window begins no earlier than
// that point, with its books from zero. Throws std::invalid_argument naming
// the key when the new duration ends at or before the point reached.
RunState extend_run(const RunState& st, const MillCase& old_c, const MillDerived& old_d, const MillCase& new_c,
                    const MillDerived& new_d, double dt);

// The longest the charge settles before the mill starts (run.settle, or
// when it is "auto" the cap on waiting for the charge to come to rest).
double max_settle_s(const MillCase& c);

// Where a run stands that goes on from a state made elsewhere (the viewer's
// "save state"), the solver at time `now_s`: still settling since
// `settle_start_s`, or, `settled`, with the charge ready, so that run_mill
// starts the mill at once and plans its warm-up and window from there.
RunState run_state_from(double now_s, bool settled, double settle_start_s, const MillCase& c);

struct RunHooks {
  std::function<void(const TimeRow&)> on_row;
  std::function<void(double turning_s)> on_snapshot;  // read the solver's balls there
  std::function<void(const RunProgress&)> on_progress;
  // Checkpoints: on_checkpoint is called every checkpoint_interval_s of
  // simulated time (0: never) at a chunk boundary, when stop_requested()
  // turns true (then the run returns with `interrupted`), and at the end.
  std::function<void(const RunState&)> on_checkpoint;
  std::function<bool()> stop_requested;
  double checkpoint_interval_s = 0;
  // Fault injection for the failure tests: a NaN velocity for ball 0 once the
  // simulated time passes this (< 0: never).
  double poison_at_s = -1;
};

// Runs the case on a solver made from build_scene(c, d). `state` says where
// to begin (a default RunState: from the start; one from a checkpoint, with
// the solver restored from the same checkpoint: from there). Throws what the
// solver throws (blow-ups, device errors).
RunSummary run_mill(Solver& solver, const Scene& scene, const MillCase& c, const MillDerived& d,
                    const RunHooks& hooks, RunState state = {});

}  // namespace mc
