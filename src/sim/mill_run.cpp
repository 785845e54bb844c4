#include "sim/mill_run.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <limits>

#include "sim/batch_means.h"
#include "sim/energy_report.h"
#include "core/layout.hpp"

namespace mc {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double angle_deg(double x, double y) {
  double a = std::atan2(y, x) * 180.0 / kPi;
  return a < 0 ? a + 360.0 : a;
}

// Steps per second over the last few reports, for progress and time left.
class Rate {
 public:
  void add(long steps, double wall) {
    if (has_) {
      const double dt = wall - last_wall_;
      if (dt > 0) rate_ = rate_ > 0 ? 0.7 * rate_ + 0.3 * (steps - last_steps_) / dt : (steps - last_steps_) / dt;
    }
    has_ = true;
    last_steps_ = steps;
    last_wall_ = wall;
  }
  double per_s() const { return rate_; }

 private:
  bool has_ = false;
  long last_steps_ = 0;
  double last_wall_ = 0, rate_ = 0;
};

}  // namespace

// The turning: a fixed duration averaged over the largest whole number of
// revolutions that end with it, or (auto) revolutions from the end of the
// warm-up until the power's mean converges, at most as many as the cap
// holds. Revolution k of the window ends at step window_start + k·rev_steps;
// each is cut into batches, the base batches of the errors. Neither window
// begins before the floor (an extended run's window, after the point the
// run it extends had reached).
TurnPlan plan_turning(const MillCase& c, const MillDerived& d, double dt, long window_floor_step, long stop_step) {
  TurnPlan p;
  p.rev_steps = d.revolution_s / dt;
  const long floor_steps = std::max(0L, window_floor_step);
  if (c.duration_auto) {
    p.warm_steps = static_cast<long>(std::ceil(c.warmup / dt));
    p.window_start = std::max(p.warm_steps, floor_steps);
    const long limit = std::lround(d.turn_limit_s / dt);
    p.revolutions =
        std::max(1L, static_cast<long>(std::floor((limit - p.window_start) / p.rev_steps + 1e-9)));
    p.turn_steps = p.window_start + std::lround(p.revolutions * p.rev_steps);
    p.whole = true;
  } else {
    p.turn_steps = std::max(1L, std::lround(c.duration / dt));
    p.warm_steps = std::min(p.turn_steps, static_cast<long>(std::ceil(c.warmup / dt)));
    const long lo = std::min(p.turn_steps, std::max(p.warm_steps, floor_steps));
    p.revolutions = static_cast<long>(std::floor((p.turn_steps - lo) / p.rev_steps));
    if (p.revolutions >= 1) {
      p.window_start = p.turn_steps - std::lround(p.revolutions * p.rev_steps);
      p.whole = true;
    } else {
      p.window_start = lo;
      p.revolutions = 0;
    }
  }
  if (stop_step >= 0) p.turn_steps = stop_step;  // an auto run that stopped (converged)
  return p;
}

namespace {

// Batches of a plan's window: its whole revolutions' batches, or in a
// window of less than a revolution its whole batches of 1/per_rev of one
// (a short run's rough error).
long window_batches(const TurnPlan& p, int per_rev) {
  if (p.revolutions > 0) return p.revolutions * per_rev;
  if (!(p.rev_steps > 0) || p.turn_steps <= p.window_start) return 0;
  return static_cast<long>(std::floor((p.turn_steps - p.window_start) / (p.rev_steps / per_rev) + 1e-9));
}

// Batches of the window that have ended by turning step s under a plan.
long batches_ended_by(const TurnPlan& p, int per_rev, long s) {
  const long n = window_batches(p, per_rev);
  long k = 0;
  while (k < n) {
    const long next = k + 1;
    const long end = p.window_start + (next % per_rev == 0 ? std::lround((next / per_rev) * p.rev_steps)
                                                           : std::lround(next * p.rev_steps / per_rev));
    if (end > s) break;
    k = next;
  }
  return k;
}

std::string seconds_text(double s) {
  char b[64];
  std::snprintf(b, sizeof b, "%.4g s", s);
  return b;
}

}  // namespace

RunState extend_run(const RunState& st, const MillCase& old_c, const MillDerived& old_d, const MillCase& new_c,
                    const MillDerived& new_d, double dt) {
  RunState out = st;
  if (st.phase < 2) return out;  // still settling: the turning is planned when it begins
  const long s = st.turn_step;
  const int per_rev = std::max(1, st.batches_per_revolution);
  const TurnPlan before = plan_turning(old_c, old_d, dt, st.window_floor_step, st.stop_step);
  // The new plan with the window where an unbroken run of the new case has it.
  TurnPlan after = plan_turning(new_c, new_d, dt, st.window_floor_step, -1);
  const std::string key = new_c.duration_auto ? "run.max_duration" : "run.duration";
  const double turned = s * dt;
  if (after.turn_steps <= s) {
    const double asked = new_c.duration_auto ? new_d.turn_limit_s : new_c.duration;
    throw std::invalid_argument(key + ": " + seconds_text(asked) + " ends where the run already is: it has turned " +
                                seconds_text(turned) + "; give a longer duration to extend it");
  }
  const bool begun = st.window_begun == 1 || (st.window_begun < 0 && s >= before.window_start);
  out.phase = 2;
  out.stop_step = -1;
  if (!begun) {
    // Nothing booked yet: the window may begin anywhere from here on.
    if (after.window_start < s) out.window_floor_step = s;
    return out;
  }
  // The window already begun goes on when the new plan keeps it: same start,
  // the same batches closed by now (an auto run given a larger cap or a
  // smaller tolerance; a run whose window still begins at the warm-up).
  if (after.window_start == before.window_start &&
      batches_ended_by(after, per_rev, s) == static_cast<long>(st.batches.size())) {
    // Its halves move with its end: the first half's books are taken again
    // if the middle is still to come, else the run has none.
    out.half_books.clear();
    out.half_window_s = 0;
    return out;
  }
  // Otherwise a new window, no earlier than here: its books from zero.
  out.window_floor_step = s;
  out.window_begun = 0;
  out.window_profile.assign(out.window_profile.size(), 0);
  out.batch_profile.assign(out.batch_profile.size(), 0);
  out.batches.clear();
  out.half_books.clear();
  out.half_window_s = 0;
  out.batch = BatchTally{};
  out.work = out.diss = out.torque_time = out.arm_time = out.span = out.comx = out.comy = out.neigh = 0;
  out.rows_in_window = 0;
  out.pre_span = out.pre_work = out.pre_diss = out.pre_torque_time = 0;
  out.batches_per_revolution = kBatchesPerRevolution;
  return out;
}

double max_settle_s(const MillCase& c) { return c.settle < 0 ? 2.0 + 4.0 * std::sqrt(c.diameter / kG) : c.settle; }

RunState run_state_from(double now_s, bool settled, double settle_start_s, const MillCase& c) {
  RunState st;
  st.phase = 1;
  if (!settled) {
    st.settle_start_s = settle_start_s;
    return st;
  }
  // Settling has lasted its longest already, so run_mill starts the mill at
  // once; the time before counts as settling (at least the longest).
  st.settle_start_s = std::min(0.0, now_s - max_settle_s(c));
  st.settled = true;
  return st;
}

RunSummary run_mill(Solver& solver, const Scene& scene, const MillCase& c, const MillDerived& d,
                    const RunHooks& hooks, RunState st) {
  RunSummary sum;
  const double dt = solver.dt();
  const long n = static_cast<long>(scene.balls.size());
  const auto wall0 = Clock::now();
  Rate rate;
  double last_report = -1e9;
  if (st.window_profile.empty()) st.window_profile.assign(kProfileBins, 0);
  if (st.batch_profile.empty()) st.batch_profile.assign(kProfileBins, 0);

  const TurnPlan plan = plan_turning(c, d, dt, st.window_floor_step, st.stop_step);
  const double rev_steps = plan.rev_steps;
  long turn_steps = plan.turn_steps;
  const long window_start = plan.window_start;
  sum.whole_revolutions = plan.whole;
  const int per_rev = std::max(1, st.batches_per_revolution);
  const long n_batches = window_batches(plan, per_rev);
  sum.batches_per_revolution = per_rev;

  auto report = [&](const char* phase, double sim, double revs, double done, bool force) {
    const double wall = seconds_since(wall0);
    if (!hooks.on_progress || (!force && wall - last_report < 0.5)) return;
    rate.add(solver.steps(), wall);
    last_report = wall;
    RunProgress p;
    p.phase = phase;
    p.simulated_s = sim;
    p.revolutions = revs;
    p.steps = solver.steps();
    p.steps_per_s = rate.per_s();
    p.updates_per_s = rate.per_s() * n;
    p.done = done;
    const long left = std::max(0L, static_cast<long>((1 - done) * turn_steps));
    p.eta_s = rate.per_s() > 0 ? left / rate.per_s() : 0;
    if (c.duration_auto && st.batches.size() >= 2) {
      std::vector<double> power;
      for (const WindowBatch& m : st.batches) power.push_back(m.torque_power_W);
      const BatchMeans b = batch_means(power);
      if (b.mean != 0) p.relative_error = b.sem / std::fabs(b.mean);
    }
    hooks.on_progress(p);
  };

  // Checkpoints at chunk boundaries: every interval of simulated time, and on
  // a stop request (then the run returns). They read the solver's state and
  // leave it as it was, so a run with checkpoints takes the same steps.
  double next_checkpoint =
      hooks.checkpoint_interval_s > 0
          ? (std::floor(solver.time_s() / hooks.checkpoint_interval_s + 1e-9) + 1) * hooks.checkpoint_interval_s
          : 1e300;
  auto checkpoint = [&]() {
    if (!hooks.on_checkpoint) return;
    RunState copy = st;
    copy.wall_s = st.wall_s + seconds_since(wall0);
    hooks.on_checkpoint(copy);
  };
  bool poisoned = false;
  // After a chunk: fault injection, a stop request, a periodic checkpoint.
  auto after_chunk = [&]() -> bool {
    if (hooks.poison_at_s >= 0 && !poisoned && solver.time_s() >= hooks.poison_at_s) {
      solver.poison_ball(0);
      poisoned = true;
    }
    if (hooks.stop_requested && hooks.stop_requested()) {
      checkpoint();
      return true;
    }
    if (solver.time_s() >= next_checkpoint - 0.5 * dt) {
      checkpoint();
      while (next_checkpoint <= solver.time_s() + 0.5 * dt) next_checkpoint += hooks.checkpoint_interval_s;
    }
    return false;
  };
  auto finish = [&](bool interrupted) {
    sum.interrupted = interrupted;
    sum.wall_s = st.wall_s + seconds_since(wall0);
    sum.steps = solver.steps();
    sum.updates_per_s = sum.wall_s > 0 ? static_cast<double>(n) * sum.steps / sum.wall_s : 0;
    return sum;
  };

  // ---- settle: the mill at rest until the charge is still ----
  const double omega = d.omega;
  const double rest_speed = 0.01 * std::sqrt(kG * c.diameter);
  const bool auto_settle = c.settle < 0;
  const double max_settle = max_settle_s(c);
  const long chunk = std::max(1L, std::lround(0.02 / dt));
  if (st.phase == 0) {
    solver.set_mill_omega(0.0);
    st.settle_start_s = solver.time_s();
    solver.observe(true);
    st.phase = 1;
  }
  if (st.phase == 1) {
    // Viscous damping while the mill is at rest brings the charge to rest
    // sooner; the turning mill has none (set again on a resumed run).
    solver.set_velocity_damping(d.settle_damping);
    const double t_start = st.settle_start_s;
    while (solver.time_s() - t_start < max_settle - 0.5 * dt) {
      const long left = std::lround((max_settle - (solver.time_s() - t_start)) / dt);
      solver.advance(std::min(chunk, std::max(1L, left)));
      const Observables o = solver.observe(true);
      const double v_rms = std::sqrt(2 * (o.kinetic_J) / o.charge_mass_kg);
      report("settle", solver.time_s() - t_start, 0, 0, false);
      if (auto_settle && solver.time_s() - t_start > 0.1 && v_rms < rest_speed) {
        st.settled = true;
        break;
      }
      if (after_chunk()) return finish(true);
    }
    solver.set_velocity_damping(0.0);
    st.settle_s = solver.time_s() - t_start;
    st.settle_wall_s = st.wall_s + seconds_since(wall0);
    if (!auto_settle) st.settled = true;
    {  // the filling the settled bed reaches
      const auto balls = solver.balls();
      std::vector<Vec3> xyr;
      xyr.reserve(balls.size());
      for (const BallState& b : balls) xyr.push_back({b.position.x, b.position.y, b.radius});
      st.settled_filling = settled_filling(scene, xyr);
    }
  }
  sum.settle_s = st.settle_s;
  sum.settle_wall_s = st.settle_wall_s;
  sum.settled = st.settled;
  sum.settled_filling = st.settled_filling;

  // ---- turn ----
  const long out_steps = std::max(1L, std::lround(c.output_interval / dt));
  const long profile_every = std::max(1L, out_steps / 10);
  const long snap_steps = c.snapshot_interval > 0 ? std::max(1L, std::lround(c.snapshot_interval / dt)) : 0;
  // Row k ends at the step nearest k output intervals after the start of the
  // turning, wherever the window begins, so that a run and the same run
  // extended write the same rows (a duration that is a whole number of
  // intervals ends on a row's end). A window that begins inside a row takes
  // the row's part after its start (pre_*).
  auto row_end_step = [&](long k) { return std::lround(k * c.output_interval / dt); };
  auto next_boundary = [&](long s) {
    long k = std::max(1L, static_cast<long>(std::floor(s * dt / c.output_interval)));
    while (k > 1 && row_end_step(k - 1) > s) --k;
    while (row_end_step(k) <= s) ++k;
    return std::min(row_end_step(k), turn_steps);
  };
  // The end of the batch being turned (none before the window, or when the
  // window holds no whole revolution). A batch that closes a revolution ends
  // where that revolution does.
  auto batch_end = [&]() {
    const long k = static_cast<long>(st.batches.size()) + 1;
    if (k > n_batches) return LONG_MAX;
    return window_start + (k % per_rev == 0 ? std::lround((k / per_rev) * rev_steps)
                                            : std::lround(k * rev_steps / per_rev));
  };

  if (st.phase == 1) {
    solver.set_mill_omega(omega);
    st.turn_start_s = solver.time_s();
    solver.observe(true);
    solver.take_contact_profile();
    if (hooks.on_snapshot && snap_steps > 0) {
      hooks.on_snapshot(0.0);
      ++st.snapshots;
    }
    const Observables o = solver.observe(false);
    st.e_window_start = o.total_energy();
    st.open_loss_start = o.open_loss_J();
    solver.reset_books();
    st.window_begun = window_start == 0 ? 1 : 0;
    st.phase = 2;
  }
  const double time0 = st.turn_start_s;
  if (st.window_begun < 0) st.window_begun = st.turn_step >= window_start ? 1 : 0;  // an older checkpoint

  long& s = st.turn_step;
  BatchTally& rev = st.batch;
  // The batch's share of the row so far, from the row's running sums.
  auto add_row_share = [&](double span, double work, double diss, double torque_time) {
    rev.span += span - rev.row_span;
    rev.work += work - rev.row_work;
    rev.diss += diss - rev.row_diss;
    rev.torque_time += torque_time - rev.row_torque_time;
    rev.row_span = span, rev.row_work = work, rev.row_diss = diss, rev.row_torque_time = torque_time;
  };
  auto end_row = [&]() {
    const Observables o = solver.observe(true);
    const std::vector<long> prof = solver.take_contact_profile();
    TimeRow r;
    r.time_s = solver.time_s() - time0;
    r.revolutions = r.time_s / d.revolution_s;
    r.interval_s = o.interval_s;
    r.torque_Nm = o.wall_torque_Nm;
    r.torque_power_W = o.torque_power_W;
    r.dissipation_power_W = o.dissipation_power_W;
    r.kinetic_J = o.kinetic_J;
    r.rotational_J = o.rotational_J;
    r.potential_J = o.potential_J;
    r.elastic_J = o.elastic_J;
    r.angles = toe_and_shoulder(prof);
    r.com_angle_deg = angle_deg(o.com_x_m, o.com_y_m);
    r.torque_arm_power_W = omega * o.charge_mass_kg * kG * o.com_x_m;
    r.neighbours_per_ball = o.neighbours_per_ball;
    r.averaged = s > window_start;
    if (r.averaged) {
      // the row's part inside the window: all of it but what came before
      // the window's start, when the window began inside it
      const double in_span = o.interval_s - st.pre_span;
      for (int k = 0; k < kProfileBins; ++k) st.window_profile[k] += prof[k];
      st.work += o.wall_work_J - st.pre_work;
      st.diss += o.dissipated_J - st.pre_diss;
      st.torque_time += o.wall_torque_Nm * o.interval_s - st.pre_torque_time;
      st.arm_time += r.torque_arm_power_W * in_span;
      st.span += in_span;
      st.comx += o.com_x_m;
      st.comy += o.com_y_m;
      st.neigh += o.neighbours_per_ball;
      ++st.rows_in_window;
      if (static_cast<long>(st.batches.size()) < n_batches) {  // the row ends in the open batch
        add_row_share(o.interval_s, o.wall_work_J, o.dissipated_J, o.wall_torque_Nm * o.interval_s);
        rev.row_span = rev.row_work = rev.row_diss = rev.row_torque_time = 0;
        for (int k = 0; k < kProfileBins; ++k) st.batch_profile[k] += prof[k];
        rev.arm_time += r.torque_arm_power_W * in_span;
        rev.rows_span += in_span;
        rev.comx += o.com_x_m;
        rev.comy += o.com_y_m;
        rev.rows += 1;
      }
      st.pre_span = st.pre_work = st.pre_diss = st.pre_torque_time = 0;
    }
    st.e_end = o.total_energy();
    ++st.rows;
    if (hooks.on_row) hooks.on_row(r);
  };
  // A batch ends: its means, and (auto, at a revolution's end) whether the
  // run stops here.
  // Each liner element's impact wear coefficient, for the batches' wear.
  const std::vector<double> impact_k = liner_impact_coefficients(scene);
  auto end_batch = [&]() {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    WindowBatch m;
    const double span = rev.span > 0 ? rev.span : 1.0;
    m.span_s = rev.span;
    m.torque_power_W = rev.work / span;
    m.dissipation_power_W = rev.diss / span;
    m.torque_Nm = rev.torque_time / span;
    m.torque_arm_power_W = rev.rows_span > 0 ? rev.arm_time / rev.rows_span : nan;
    const ChargeAngles a = toe_and_shoulder(st.batch_profile);
    m.toe_deg = a.found ? a.toe_deg : nan;
    m.shoulder_deg = a.found ? a.shoulder_deg : nan;
    m.com_angle_deg = rev.rows > 0 ? angle_deg(rev.comx / rev.rows, rev.comy / rev.rows) : nan;
    // The books' totals since the window began; this batch's part.
    const BookSums books = solver.read_books();
    const CollisionRates all = spectra_report(scene, books, 1.0, 0, 0, 0).all;  // per 1 s: totals
    double impacts = 0, impact_J = 0, shear_J = 0, wear_m3 = 0;
    for (int e = 0; e < books.n_elements; ++e) {
      impacts += books.liner_at(e, MC_LINER_IMPACTS);
      impact_J += books.liner_at(e, MC_LINER_NORMAL);
      shear_J += books.liner_at(e, MC_LINER_SHEAR);
      wear_m3 += books.liner_at(e, MC_LINER_WEAR) + impact_k[e] * books.liner_at(e, MC_LINER_STRIKE);
    }
    m.collisions_per_s = (all.collisions_per_s - rev.collisions) / span;
    m.collision_power_W = (all.power_W - rev.collision_J) / span;
    m.liner_impacts_per_s = (impacts - rev.impacts) / span;
    m.liner_impact_W = (impact_J - rev.impact_J) / span;
    m.liner_shear_W = (shear_J - rev.shear_J) / span;
    m.wear_kg_per_h = (wear_m3 - rev.wear_m3) / span * scene.wall_material.density * 3600.0;
    st.batches.push_back(m);
    // Half way through a window of known length, the liner's books so far:
    // the wear of each half apart (how far a stage's wear can be trusted).
    if (!c.duration_auto && n_batches >= 2 && st.half_books.empty() &&
        static_cast<long>(st.batches.size()) == n_batches / 2) {
      st.half_books = books.liner;
      st.half_books.insert(st.half_books.end(), books.stations.begin(), books.stations.end());
      for (const WindowBatch& x : st.batches) st.half_window_s += x.span_s;
    }
    // The next batch begins with the row's sums at this cut and the
    // books' totals now.
    BatchTally next;
    next.row_span = rev.row_span, next.row_work = rev.row_work, next.row_diss = rev.row_diss;
    next.row_torque_time = rev.row_torque_time;
    next.collisions = all.collisions_per_s, next.collision_J = all.power_W;
    next.impacts = impacts, next.impact_J = impact_J, next.shear_J = shear_J, next.wear_m3 = wear_m3;
    rev = next;
    std::fill(st.batch_profile.begin(), st.batch_profile.end(), 0L);
    if (c.duration_auto && st.batches.size() % per_rev == 0) {
      std::vector<double> power;
      for (const WindowBatch& x : st.batches) power.push_back(x.torque_power_W);
      if (converged(batch_means(power), c.tolerance)) {
        st.stop_step = s;
        turn_steps = s;
      }
    }
  };

  // The window's books begin: the energies and the open contacts' losses
  // now, the books from zero, and the part of the row turned so far kept
  // out of the window's sums (and out of its first batch's).
  auto begin_window = [&]() {
    const Observables o = solver.observe(false);
    st.e_window_start = o.total_energy();
    st.open_loss_start = o.open_loss_J();
    solver.reset_books();
    st.pre_span = o.interval_s;
    st.pre_work = o.wall_work_J;
    st.pre_diss = o.dissipated_J;
    st.pre_torque_time = o.wall_torque_Nm * o.interval_s;
    rev.row_span = st.pre_span, rev.row_work = st.pre_work, rev.row_diss = st.pre_diss;
    rev.row_torque_time = st.pre_torque_time;
    st.window_begun = 1;
  };

  // A checkpoint written before runs kept their revolutions: those already
  // turned count as unknown.
  while (st.phase == 2 && batch_end() != LONG_MAX && batch_end() <= s) {
    WindowBatch unknown;
    for (auto field : kWindowBatchFields) unknown.*field = std::numeric_limits<double>::quiet_NaN();
    st.batches.push_back(unknown);
  }
  if (st.phase == 2 && s == window_start && !st.window_begun) begin_window();
  while (st.phase == 2 && s < turn_steps) {
    const long row_end = next_boundary(s);
    const long rev_end = batch_end();
    long next = std::min(row_end, rev_end);
    if (!st.window_begun && window_start > s) next = std::min(next, window_start);
    const long next_profile = (s / profile_every + 1) * profile_every;
    next = std::min(next, next_profile);
    if (snap_steps > 0) next = std::min(next, (s / snap_steps + 1) * snap_steps);
    solver.advance(next - s);
    s = next;
    if (s % profile_every == 0) solver.sample_contact_profile();
    if (s == row_end) {
      end_row();
    } else if (s == rev_end) {  // inside a row: the row's sums so far, left running
      const Observables o = solver.observe(false);
      add_row_share(o.interval_s, o.wall_work_J, o.dissipated_J, o.wall_torque_Nm * o.interval_s);
    }
    if (s == rev_end) end_batch();
    if (s != row_end && s == turn_steps) end_row();  // stopped inside a row: a short last row
    if (s == window_start && !st.window_begun) begin_window();
    if (hooks.on_snapshot && snap_steps > 0 && (s % snap_steps == 0 || s == turn_steps)) {
      hooks.on_snapshot(solver.time_s() - time0);
      ++st.snapshots;
    }
    const double turned = solver.time_s() - time0;
    report("turn", turned, turned / d.revolution_s, static_cast<double>(s) / turn_steps, s == turn_steps);
    if (s < turn_steps && after_chunk()) return finish(true);
  }
  st.phase = 3;

  const double span = st.span;
  sum.turning_s = solver.time_s() - time0;
  sum.revolutions = sum.turning_s / d.revolution_s;
  sum.simulated_s = sum.settle_s + sum.turning_s;
  sum.window_from_s = window_start * dt;
  sum.window_to_s = sum.turning_s;
  sum.window_revolutions = span / d.revolution_s;
  if (span > 0) {
    sum.torque_power_W = st.work / span;
    sum.dissipation_power_W = st.diss / span;
    sum.torque_Nm = st.torque_time / span;
    sum.torque_arm_power_W = st.arm_time / span;
    sum.energy_change_W = (st.e_end - st.e_window_start) / span;
    sum.com_angle_deg = angle_deg(st.comx / st.rows_in_window, st.comy / st.rows_in_window);
    sum.neighbours_per_ball = st.neigh / st.rows_in_window;
  }
  sum.imbalance = sum.torque_power_W != 0 ? (sum.torque_power_W - sum.dissipation_power_W) / sum.torque_power_W : 0;
  sum.profile = st.window_profile;
  sum.books = solver.read_books();
  sum.open_loss_start_J = st.open_loss_start;
  sum.open_loss_end_J = solver.observe(false).open_loss_J();
  sum.dissipated_J = st.diss;
  sum.window_s = span;
  sum.mill_angle_end = solver.mill_angle();
  sum.angles = toe_and_shoulder(st.window_profile);
  sum.window_batches = st.batches;
  sum.half_books = st.half_books;
  sum.half_window_s = st.half_window_s;
  sum.duration_auto = c.duration_auto;
  sum.converged = c.duration_auto && st.stop_step >= 0;
  sum.capped = c.duration_auto && st.stop_step < 0;
  checkpoint();
  return finish(false);
}

}  // namespace mc
