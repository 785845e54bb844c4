// The window's live edits (the panel's or --edit's): a new speed, a new
// scene from the balls as they are, or a new charge packed afresh; the
// averages start again after each, and a blow-up after one goes back to the
// state before it.
#include <cstdio>
#include <string>
#include <vector>

#include "core/charge_edit.h"
#include "io/case_file.h"
#include "viewer/app.h"

namespace mc::viewer {

namespace {

// The solver's balls as a scene's (balls of their own: a charge of clumps
// is packed afresh on an edit).
std::vector<Ball> balls_as_they_are(Solver& solver) {
  const std::vector<BallState> now = solver.balls();
  std::vector<Ball> balls(now.size());
  for (std::size_t k = 0; k < now.size(); ++k) {
    Ball& b = balls[k];
    b.id = now[k].id;
    b.material = now[k].material;
    b.radius = now[k].radius;
    b.position = now[k].position;
    b.velocity = now[k].velocity;
    b.omega = now[k].omega;
  }
  return balls;
}

}  // namespace

void App::set_speed_fraction(double fraction) {
  MillCase next = case_;
  next.speed_fraction = fraction;
  next.speed_rpm = 0;
  try {
    const MillDerived nd = derive(next);
    // The state before the edit, its speed too, is what a blow-up goes back
    // to; a slider dragged over several frames is one edit: the state before
    // the drag.
    if (!settling_ && last_edit_frame_ < frames_ - 1) keep_undo();
    derived_ = nd;
    case_ = next;
    edit_.speed_fraction = fraction;
    edit_.speed_rpm = 0;
    if (!settling_) {
      solver_->set_mill_omega(derived_.omega);
      restart_averages();
    }
    set_colour_ranges();
  } catch (const std::invalid_argument& e) {
    message_ = e.what();
  }
}

// The averages start again after an edit, and take nothing from the
// settle-in: the mill turns kSettleInRev first. The plots mark the edit.
void App::restart_averages() {
  last_edit_frame_ = frames_;
  last_edit_s_ = sim_time();
  if (settling_) return;  // the averages begin when the mill starts
  monitor_.restart();
  liner_.clear();
  hold_until_rev_ = hold_power_until_rev_ = revolutions_ + kSettleInRev;
}

// The state before an edit (the case, the walls, the balls and springs), so
// that a blow-up after it goes back there.
void App::keep_undo() {
  if (!scene_.bodies.empty()) {  // clumps: their bodies' state is not a scene's balls; no revert
    undo_.reset();
    return;
  }
  auto u = std::make_unique<Undo>();
  u->c = case_;
  u->d = derived_;
  u->scene = scene_;
  u->scene.balls = balls_as_they_are(*solver_);
  u->scene.mill_angle = solver_->mill_angle();
  u->scene.mill_omega = settling_ ? 0.0 : derived_.omega;
  u->state = solver_->save_state();
  u->time_offset = time_offset_;
  u->step_offset = step_offset_;
  u->revolutions = revolutions_;
  undo_ = std::move(u);
}

// After a blow-up: the state before the last edit, if there was one, with
// its case; the panel says what happened. False when there is none.
bool App::revert_edit(const std::string& why) {
  if (!undo_ || settling_) return false;
  std::unique_ptr<Undo> u = std::move(undo_);
  try {
    auto next = make_solver(*ctx_, u->scene);
    next->restore_state(u->state);
    solver_ = std::move(next);
  } catch (const std::exception&) {
    return false;
  }
  time_offset_ = u->time_offset;
  step_offset_ = u->step_offset;
  revolutions_ = u->revolutions;
  case_ = edit_ = u->c;
  derived_ = u->d;
  scene_ = u->scene;
  n_balls_ = static_cast<int>(scene_.balls.size());
  scene_.balls.clear();
  solver_->set_mill_omega(derived_.omega);
  solver_->set_velocity_damping(0);
  solver_->observe(true);
  solver_->take_contact_profile();
  show_scene();
  set_colour_ranges();
  restart_averages();
  char at[48];
  std::snprintf(at, sizeof at, "%.4f s", sim_time());
  message_ = "the solver blew up after the edit (" + why + "); the edit is undone: the state before it, at t = " + at +
             ", turns on";
  std::fprintf(stderr, "millcharge view: %s\n", message_.c_str());
  return true;
}

namespace {

bool same_sizes(const MillCase& a, const MillCase& b) {
  if (a.sizes.size() != b.sizes.size() || a.number_fractions != b.number_fractions || a.seed != b.seed ||
      a.materials.size() != b.materials.size())
    return false;
  for (std::size_t k = 0; k < a.sizes.size(); ++k)
    if (a.sizes[k].diameter_min != b.sizes[k].diameter_min || a.sizes[k].diameter_max != b.sizes[k].diameter_max ||
        a.sizes[k].material != b.sizes[k].material || a.sizes[k].fraction != b.sizes[k].fraction)
      return false;
  for (std::size_t k = 0; k < a.materials.size(); ++k)
    if (a.materials[k].name != b.materials[k].name || a.materials[k].density != b.materials[k].density) return false;
  return a.diameter == b.diameter && a.length == b.length && a.periodic == b.periodic;
}

}  // namespace

// A new case from the panel or a script. Speed alone is a new ω; anything
// else is a new scene made from the balls as they are (core/charge_edit),
// except a new charge (sizes, materials, mill size), which is packed afresh
// and settles. On a bad value the old case stays and the panel says why.
void App::apply_case(const MillCase& next) {
  try {
    const MillDerived nd = derive(next);
    MillCase speed_only = case_;
    speed_only.speed_fraction = next.speed_fraction;
    speed_only.speed_rpm = next.speed_rpm;
    if (io::case_to_toml(speed_only) == io::case_to_toml(next)) {
      if (!settling_) keep_undo();
      case_ = next;
      derived_ = nd;
      if (!settling_) solver_->set_mill_omega(derived_.omega);
      restart_averages();
      set_colour_ranges();
      char buf[96];
      std::snprintf(buf, sizeof buf, "speed %.1f %% of critical, %.2f rpm", 100 * nd.speed_fraction, nd.speed_rpm);
      message_ = buf;
      return;
    }
    if (!same_sizes(case_, next) || !scene_.bodies.empty()) {  // clumps are packed afresh
      Scene s = build_scene(next, nd);
      s.mill_angle = solver_->mill_angle();
      install_solver(std::move(s), true, nd.settle_damping);
      undo_.reset();
      message_ = "new charge: " + std::to_string(n_balls_) + " balls packed afresh; they settle, then the mill turns";
    } else {
      std::vector<Ball> balls = balls_as_they_are(*solver_);
      ChargeEditOptions o;
      o.match_counts = next.filling != case_.filling || next.porosity != case_.porosity;
      o.mill_angle = solver_->mill_angle();
      o.mill_omega = settling_ ? 0.0 : nd.omega;
      o.previous_walls = &scene_.walls;
      o.seed = ++edit_seed_;
      ChargeEditResult r = edit_charge(next, nd, std::move(balls), o);
      if (!settling_) keep_undo();
      install_solver(std::move(r.scene), false);
      if (settling_) solver_->set_velocity_damping(nd.settle_damping);  // an edit while the charge settles
      char buf[160];
      std::snprintf(buf, sizeof buf, "applied: %d balls (%ld added, %ld removed, %ld moved out of lifters)",
                    n_balls_, r.added, r.removed, r.moved);
      message_ = buf;
    }
    case_ = next;
    derived_ = nd;
    restart_averages();
    set_colour_ranges();
  } catch (const std::invalid_argument& e) {
    message_ = std::string("not applied: ") + e.what();
  } catch (const compute::Error& e) {
    message_ = std::string("not applied (OpenCL): ") + e.what();
  }
  edit_ = case_;
}

void App::reset() {
  try {
    Scene s = build_scene(case_, derived_);
    install_solver(std::move(s), true, derived_.settle_damping);
    undo_.reset();
    time_offset_ = settle_from_ = 0;  // the clock starts again
    step_offset_ = 0;
    message_ = "reset: a fresh charge settles";
    source_.clear();
  } catch (const std::exception& e) {
    message_ = std::string("reset failed: ") + e.what();
  }
}

// --edit FRAME:KEY=VALUE: the case with that --set applied, as if from the panel.
void App::scripted_edits() {
  for (const auto& [frame, kv] : opt_.edits) {
    if (frame != frames_) continue;
    try {
      apply_case(io::parse_case(io::case_to_toml(case_), case_.name + ".toml", {kv}));
    } catch (const std::invalid_argument& e) {
      message_ = std::string("not applied: ") + e.what();
    }
    std::printf("millcharge view: frame %ld: %s: %s\n", frames_, kv.c_str(), message_.c_str());
    std::fflush(stdout);
  }
}

}  // namespace mc::viewer
