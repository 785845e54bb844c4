// The viewer's state and loop (Dear ImGui's example_glfw_opengl3 loop: poll,
// skip while iconified, step, new frame, widgets, render, swap). viewer.cpp
// runs the simulation, edits.cpp applies edits; panel.cpp draws the ImGui
// panel.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "compute/context.h"
#include "core/mill_case.h"
#include "core/scene.h"
#include "sim/solver.h"
#include "viewer/ball_renderer.h"
#include "viewer/camera.h"
#include "viewer/charge_monitor.h"
#include "viewer/gl.h"
#include "viewer/instance_feed.h"
#include "viewer/liner_monitor.h"
#include "viewer/mill_renderer.h"
#include "viewer/viewer.h"

namespace mc::viewer {

// GLFW, the window with its GL 3.3 core context, GLEW and Dear ImGui, torn
// down in reverse order.
class Window {
 public:
  Window(int width, int height, const std::string& title, bool vsync);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
  GLFWwindow* get() const { return window_; }
  std::string gl_version() const;

 private:
  GLFWwindow* window_ = nullptr;
  bool imgui_ = false;
};

// What the panel (or a scripted --edit) asks for after the frame.
enum class Edit { none, apply, reset };

class App {
 public:
  App(const MillCase& c, const MillDerived& d, Scene scene, const ViewOptions& options);
  ~App();
  int run();

 private:
  // viewer.cpp
  void make_context();
  // With `settle` the mill stands and the balls' velocities are damped at
  // `settle_damping` (1/s, run.settle_damping) until the charge is at rest.
  void install_solver(Scene scene, bool settle, double settle_damping = 0);
  void show_scene();  // walls, liner and ball buffer from scene_ and the solver
  void step_frame();
  bool advance(int steps);  // the solver's steps; false: a blow-up after an edit reverted it
  void set_colour_ranges();  // from the case as now
  // edits.cpp
  void apply_case(const MillCase& next);  // the panel's or a script's new case
  void reset();                           // the current case from a fresh packing
  void scripted_edits();
  void set_speed_fraction(double fraction);
  void keep_undo();                          // the state before an edit, for a revert
  bool revert_edit(const std::string& why);  // after a blow-up
  void restart_averages();                   // after an applied edit
  // viewer.cpp
  void render();
  void handle_input();
  void open_checkpoint(const io::Checkpoint& cp);  // view --from
  void take_screenshot(const std::string& path, bool announce);
  bool save_state(const std::string& dir_in);  // "" : runs/view-CASE-TIME; false: no checkpoint
  double sim_time() const;
  int scene_width() const;  // pixels right of the panel
  glm::vec2 to_pixels(const glm::vec3& p) const;  // lab frame → window pixels from the top left
  std::string stamp() const;
  // panel.cpp
  void draw_panel();
  void panel_stats();
  void panel_run();
  void panel_mill();
  void panel_charge();
  void panel_view();
  void panel_plots();
  void panel_output();
  void draw_labels();
  void colour_liner();

  ViewOptions opt_;
  bool scripted_;
  MillCase loaded_;   // as read, with --set applied: for the panel's "file" values
  MillCase case_;     // as now
  MillCase edit_;     // what the panel shows and edits
  MillDerived derived_;
  Scene scene_;       // walls and pairs now; balls as last installed
  int n_balls_ = 0;

  std::unique_ptr<Window> window_;
  std::unique_ptr<compute::Context> ctx_;
  std::string why_not_shared_;
  std::unique_ptr<Solver> solver_;
  std::unique_ptr<BallRenderer> balls_;
  std::unique_ptr<MillRenderer> mill_;
  std::unique_ptr<InstanceFeed> feed_;
  Camera camera_;
  ChargeMonitor monitor_;
  LinerMonitor liner_;
  int liner_colour_ = 0;    // 0 plain, 1 impact power, 2 wear rate, 3 sliding wear, 4 impact wear
  long liner_drawn_ = -1;   // the liner report's version the colours show
  float liner_max_ = 0;     // the colour scale's top (the hottest element)
  BallStyle style_;
  float colour_lo_[4] = {0, 0, 0, -2}, colour_hi_[4] = {1, 1, 1, 2};
  bool show_shell_ = true, show_marks_ = true;
  float slab_centre_ = 0, slab_width_ = 0;

  // simulation
  // After every applied edit nothing is plotted or averaged until the mill
  // has turned this much (the start-up jolt: tangential springs dropped,
  // moved or added balls at rest, the charge taking its new shape).
  static constexpr double kSettleInRev = 0.25;
  static constexpr double kUndoRev = 1.0;  // revolutions after the settle-in an edit stays undoable
  static constexpr double kStartHoldRev = 0.05;  // the power, after the mill starts from rest
  double revolutions_ = 0;           // turned in the window: the sum of ω·dt over 2π
  double hold_until_rev_ = 0;        // power and profiles held before this
  double hold_power_until_rev_ = 0;  // the power alone held before this
  long last_edit_frame_ = -1;        // the last applied edit, for the report
  double last_edit_s_ = -1;
  // The state before the last edit: a blow-up after it goes back there.
  struct Undo {
    MillCase c;
    MillDerived d;
    Scene scene;  // walls, pairs and the balls then
    SolverState state;
    double time_offset = 0, revolutions = 0;
    long step_offset = 0;
  };
  std::unique_ptr<Undo> undo_;
  bool settling_ = true;
  double settle_from_ = 0;   // viewer time when settling began
  double time_offset_ = 0;   // simulated time of earlier solvers
  long step_offset_ = 0;     // and their steps
  double turning_from_ = 0;  // viewer time when the mill started
  bool paused_ = false;
  bool step_once_ = false;
  bool adaptive_ = true;
  int fixed_steps_ = 40;
  float speed_limit_ = 1.0f;  // × real time at most
  double s_per_step_ = 0;     // wall seconds per step, smoothed
  double frame_overhead_s_ = 0.01;  // wall seconds per frame besides stepping, smoothed
  double advance_s_ = 0;            // wall seconds of this frame's steps
  int last_steps_ = 0;
  bool instances_stale_ = true;
  Edit pending_ = Edit::none;
  std::uint32_t edit_seed_ = 1;

  // statistics
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_ = Clock::now();
  Clock::time_point window_from_ = Clock::now();
  long frames_ = 0, steps_ = 0;          // all
  long window_frames_ = 0, window_steps_ = 0;
  double fps_ = 0, steps_per_s_ = 0;
  double last_frame_s_ = 0;

  // where the state came from: the run folder of the checkpoint (view
  // --from), empty for a fresh packing of the case
  std::string source_;
  double source_time_ = 0;   // simulated time of the checkpoint
  bool opened_turning_ = false;  // the checkpoint's mill turned
  double first_frame_s_ = -1, first_turning_frame_s_ = -1;  // wall s from the command

  // messages
  std::string message_;
  bool screenshot_requested_ = false;
  double ball_scale_ = 1.0;   // of the loaded case's diameters
  float panel_width_ = 360;
};

}  // namespace mc::viewer
