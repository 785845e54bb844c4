#include "viewer/viewer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include "io/atomic_file.h"
#include "io/case_file.h"
#include "io/checkpoint.h"
#include "io/vtk.h"
#include "sim/mill_run.h"
#include "viewer/app.h"
#include "viewer/gl_sharing.h"
#include "viewer/screenshot.h"

namespace mc::viewer {

namespace fs = std::filesystem;

namespace {

constexpr double kG = 9.81;
constexpr double kTargetFrameS = 1.0 / 30;  // interactive: at least ~30 drawn frames per second

void glfw_error(int code, const char* what) { std::cerr << "millcharge view: GLFW error " << code << ": " << what << '\n'; }

ColourBy colour_from(const std::string& s) {
  if (s == "size") return ColourBy::size;
  if (s == "material") return ColourBy::material;
  if (s == "impact") return ColourBy::impact;
  return ColourBy::speed;
}

// The panel's colour bar's ramp (blue, cyan, green, yellow, red) at t in
// [0, 1]; below 0 (nothing on the element) a dark blue-grey.
glm::vec3 heat_colour(double t) {
  if (t < 0) return {0.22f, 0.24f, 0.30f};
  static const glm::vec3 stops[5] = {
      {0.15f, 0.30f, 0.95f}, {0.05f, 0.75f, 0.90f}, {0.25f, 0.85f, 0.25f}, {0.98f, 0.80f, 0.10f}, {0.90f, 0.15f, 0.10f}};
  const double u = std::clamp(t, 0.0, 1.0) * 4;
  const int k = std::min(3, static_cast<int>(u));
  return glm::mix(stops[k], stops[k + 1], static_cast<float>(u - k));
}

// The case `c` with the charge.filling at which it packs `n` balls: after
// an edit that kept the balls in a mill of another volume (taller or more
// lifters), the filling those balls fill. False when no filling gives n (a
// count that rounding per size class skips, or one past half full).
bool fill_for_count(MillCase& c, long n) {
  MillCase t = c;
  auto count = [&](double filling) {
    t.filling = filling;
    try {
      return derive(t).n_balls;
    } catch (const std::invalid_argument&) {
      return -1L;  // past what the case allows
    }
  };
  // The count grows with the filling (each class rounded): bisect between
  // fillings that pack fewer and more.
  const long now = count(c.filling);
  if (now <= 0) return false;
  double lo = c.filling, hi = c.filling;
  if (now < n) hi = std::min(0.5, c.filling * 1.5 * n / now);
  else lo = c.filling * 0.5 * n / now;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    const long m = count(mid);
    if (m == n) {
      c.filling = mid;
      return true;
    }
    if (m < 0 || m > n) hi = mid;
    else lo = mid;
  }
  return false;
}

}  // namespace

// ------------------------------------------------------------------ window

Window::Window(int width, int height, const std::string& title, bool vsync) {
  glfwSetErrorCallback(glfw_error);
  if (!glfwInit())
    throw std::runtime_error("cannot start GLFW: no display? (on a machine without one, run under xvfb-run)");
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!window_) {
    glfwTerminate();
    throw std::runtime_error("cannot open a window with OpenGL 3.3 core (no display, or the driver is too old)");
  }
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(vsync ? 1 : 0);
  glewExperimental = GL_TRUE;  // core profiles need it with GLEW 2.x
  const GLenum glew = glewInit();
  glGetError();  // glewInit leaves GL_INVALID_ENUM behind on core profiles
  if (glew != GLEW_OK) {
    glfwDestroyWindow(window_);
    glfwTerminate();
    throw std::runtime_error(std::string("cannot load OpenGL functions (GLEW): ") +
                             reinterpret_cast<const char*>(glewGetErrorString(glew)));
  }
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the working folder
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  imgui_ = true;
}

Window::~Window() {
  if (imgui_) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  glfwDestroyWindow(window_);
  glfwTerminate();
}

std::string Window::gl_version() const {
  const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return std::string(v ? v : "?") + ", " + (r ? r : "?");
}

// ------------------------------------------------------------------ app

App::App(const MillCase& c, const MillDerived& d, Scene scene, const ViewOptions& options)
    : opt_(options), scripted_(options.frames > 0), loaded_(c), case_(c), edit_(c), derived_(d) {
  window_ = std::make_unique<Window>(opt_.width, opt_.height, "millcharge view: " + c.name, !scripted_);
  if (!opt_.panel) panel_width_ = 0;
  make_context();
  balls_ = std::make_unique<BallRenderer>();
  mill_ = std::make_unique<MillRenderer>();
  feed_ = std::make_unique<InstanceFeed>(*ctx_, why_not_shared_);
  if (opt_.steps_per_frame > 0) {
    adaptive_ = false;
    fixed_steps_ = opt_.steps_per_frame;
  } else if (scripted_ && opt_.steps_per_frame == 0) {
    adaptive_ = false;  // reproducible pictures
    fixed_steps_ = 40;
  }
  style_.colour_by = colour_from(opt_.colour);
  liner_colour_ = opt_.liner == "impact"        ? 1
                  : opt_.liner == "wear"        ? 2
                  : opt_.liner == "sliding-wear" ? 3
                  : opt_.liner == "impact-wear"  ? 4
                                                 : 0;
  set_colour_ranges();
  install_solver(std::move(scene), !opt_.from, d.settle_damping);
  if (opt_.from) open_checkpoint(*opt_.from);
  slab_centre_ = static_cast<float>(0.5 * c.length);
  slab_width_ = static_cast<float>(std::min(c.length, 2.5 * derived_.largest_ball_diameter));
  camera_.frame_mill(0.5 * c.diameter, c.length);
  const float aspect = static_cast<float>(scene_width()) / std::max(1, opt_.height);
  if (opt_.camera == "iso") camera_.isometric(aspect);
  else camera_.end_view(aspect);
}

App::~App() {
  // GL objects go before the window's context.
  feed_.reset();
  mill_.reset();
  balls_.reset();
}

// The OpenCL context: one that shares with GL where the device offers
// cl_khr_gl_sharing and is the GL context's device; a plain one otherwise.
void App::make_context() {
  compute::DeviceInfo dev = compute::choose_device(opt_.device.empty() && std::getenv("MILLCHARGE_DEVICE")
                                                       ? std::getenv("MILLCHARGE_DEVICE")
                                                       : opt_.device);
  const char* gl_vendor = reinterpret_cast<const char*>(glGetString(GL_VENDOR));
  const char* gl_renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* interop = std::getenv("MILLCHARGE_INTEROP");
  if (interop && std::string(interop) == "0") {
    why_not_shared_ = "MILLCHARGE_INTEROP=0";
  } else if (!dev.gl_sharing) {
    why_not_shared_ = dev.name + " has no cl_khr_gl_sharing";
  } else if (!same_gl_cl_vendor(gl_vendor ? gl_vendor : "", gl_renderer ? gl_renderer : "", dev.platform_name)) {
    why_not_shared_ = std::string("the GL driver (") + (gl_vendor ? gl_vendor : "?") + ", " +
                      (gl_renderer ? gl_renderer : "?") + ") is not the OpenCL platform's (" + dev.platform_name + ")";
  } else {
    const auto props = gl_sharing_properties(window_->get());
    if (props.empty()) {
      why_not_shared_ = "the window's GL context is not a GLX one";
    } else {
      try {
        ctx_ = std::make_unique<compute::Context>(opt_.device, props);
      } catch (const compute::Error& e) {
        why_not_shared_ = e.what();
      }
    }
  }
  if (!ctx_) {
    // Once, here: the panel shows it too.
    if (dev.gl_sharing) std::cerr << "millcharge view: no CL-GL interop (" << why_not_shared_ << "); copying through the host\n";
    ctx_ = std::make_unique<compute::Context>(opt_.device);
  }
}

// Colour ranges: speed up to twice the tip speed (balls falling from the
// shoulder), the case's radii, 1 mW to 30 W dissipated. Again after each
// edit: a new speed or ball size moves them.
void App::set_colour_ranges() {
  colour_hi_[0] = static_cast<float>(2 * derived_.tip_speed);
  double rmin = 1e300, rmax = 0;
  for (const SizeClass& s : case_.sizes) rmin = std::min(rmin, 0.5 * s.diameter_min), rmax = std::max(rmax, 0.5 * s.diameter_max);
  colour_lo_[1] = static_cast<float>(rmin);
  colour_hi_[1] = static_cast<float>(rmax > rmin ? rmax : 1.2 * rmin);
  colour_lo_[3] = -3.0f;
  colour_hi_[3] = 1.5f;
}

double App::sim_time() const { return time_offset_ + (solver_ ? solver_->time_s() : 0.0); }

int App::scene_width() const { return std::max(1, opt_.width - static_cast<int>(panel_width_)); }

// view --from: the solver (just made for the run's case) takes the
// checkpoint's state, and the window goes on as the run was: settling, or
// turning at the case's speed.
void App::open_checkpoint(const io::Checkpoint& cp) {
  try {
    solver_->restore_state(cp.solver);
  } catch (const std::invalid_argument& e) {  // a state that does not fit its own case
    throw std::invalid_argument(opt_.from_dir + "/" + io::kCheckpointFile + ": " + e.what() +
                                "; the window cannot open on it");
  }
  time_offset_ = 0;
  step_offset_ = 0;
  const RunState& r = cp.run;
  // A state saved by the window once the mill turned is "settled" in phase
  // 1 (run --resume starts the mill at once): it turns on here too.
  settling_ = r.phase < 2 && !(r.phase == 1 && r.settled);
  if (settling_) {
    settle_from_ = r.phase == 1 ? r.settle_start_s : solver_->time_s();
    solver_->set_mill_omega(0);
    solver_->set_velocity_damping(derived_.settle_damping);
  } else {
    turning_from_ = r.turn_start_s > 0 || r.phase >= 2 ? r.turn_start_s : solver_->time_s();
    // The revolutions before, at the case's speed (a checkpoint holds no
    // history of speeds).
    revolutions_ = (solver_->time_s() - turning_from_) * derived_.omega / (2 * M_PI);
    solver_->set_mill_omega(derived_.omega);
    solver_->set_velocity_damping(0);
  }
  solver_->observe(true);  // the sums start here
  solver_->take_contact_profile();
  monitor_.clear();
  source_ = opt_.from_dir;
  source_time_ = solver_->time_s();
  opened_turning_ = !settling_;
  instances_stale_ = true;
}

// A new solver for `scene`; the old one's time carries on. With `settle` the
// mill stands still until the charge is at rest (as `run` settles it).
void App::install_solver(Scene scene, bool settle, double settle_damping) {
  const double t = sim_time();
  const long steps = step_offset_ + (solver_ ? solver_->steps() : 0);
  if (settle) scene.mill_omega = 0;
  auto next = make_solver(*ctx_, scene);  // the old solver stays if this throws
  next->set_velocity_damping(settle ? settle_damping : 0.0);
  solver_ = std::move(next);
  time_offset_ = t;
  step_offset_ = steps;
  scene_ = std::move(scene);
  n_balls_ = static_cast<int>(scene_.balls.size());
  scene_.balls.clear();  // the solver holds them now
  scene_.balls.shrink_to_fit();
  if (settle) {
    settling_ = true;
    settle_from_ = t;
    monitor_.clear();
    source_.clear();
  }
  show_scene();
}

// The walls, the liner and the balls' buffer drawn from scene_ and the
// solver now in hand.
void App::show_scene() {
  mill_->set_walls(scene_.walls);
  liner_.set_scene(scene_);
  mill_->set_liner(liner_.layout());
  liner_drawn_ = -1;
  balls_->resize(n_balls_);
  feed_->attach(*balls_);
  instances_stale_ = true;
}

// The steps; a blow-up (the solver throws) after an edit takes the state
// before the edit back, once. One with no edit to undo ends the session.
bool App::advance(int steps) {
  try {
    solver_->advance(steps);
    return true;
  } catch (const std::runtime_error& e) {
    if (dynamic_cast<const compute::Error*>(&e) || !revert_edit(e.what())) throw;
    return false;
  }
}

// Steps for this frame, then the balls into the vertex buffer and the sums
// into the monitor.
void App::step_frame() {
  int steps = 0;
  if (!paused_ || step_once_) {
    if (step_once_) steps = 1;
    else if (!adaptive_) steps = fixed_steps_;
    else {
      // What fits in the frame budget, and no faster than the speed limit.
      // Where drawing alone takes most of a frame (software GL, a loaded
      // machine), the simulation still gets as much as drawing takes, up to
      // a whole frame period: ~15 fps rather than a crawl of the charge.
      const double budget =
          std::max(kTargetFrameS - frame_overhead_s_, std::min(frame_overhead_s_, kTargetFrameS));
      const double per_step = s_per_step_ > 0 ? s_per_step_ : 1e-3;
      const double by_budget = budget / per_step;
      const double by_limit = speed_limit_ * std::max(last_frame_s_, 1.0 / 240) / solver_->dt();
      steps = static_cast<int>(std::clamp(std::min(by_budget, by_limit), 1.0, 200000.0));
    }
    step_once_ = false;
  }
  last_steps_ = steps;
  advance_s_ = 0;
  if (steps > 0) {
    const auto t0 = Clock::now();
    const double rev_before = revolutions_;  // a frame that starts in a hold is held whole
    if (advance(steps) && !settling_) revolutions_ += steps * solver_->dt() * derived_.omega / (2 * M_PI);
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    const double per = s / steps;
    s_per_step_ = s_per_step_ > 0 ? 0.8 * s_per_step_ + 0.2 * per : per;
    advance_s_ = s;
    feed_->update(*solver_, *balls_);
    const bool held = rev_before < hold_until_rev_;
    monitor_.after_steps(*solver_, sim_time(), !settling_, held || rev_before < hold_power_until_rev_, held);
    // An edit stays undoable for a revolution after its settle-in: a blow-up
    // later than that is not the edit's, and going back would throw away
    // all the turning since.
    if (undo_ && revolutions_ > hold_until_rev_ + kUndoRev) undo_.reset();
    liner_.after_steps(*solver_, sim_time(), !settling_, held, monitor_.profile(), monitor_.angles());
    steps_ += steps;
    window_steps_ += steps;
    instances_stale_ = false;
    if (settling_) {
      const double in_settle = sim_time() - settle_from_;
      const bool auto_settle = case_.settle < 0;
      const double max_settle = auto_settle ? 2.0 + 4.0 * std::sqrt(case_.diameter / kG) : case_.settle;
      const bool at_rest = auto_settle && in_settle > 0.1 && monitor_.rms_speed() < 0.01 * std::sqrt(kG * case_.diameter);
      if (at_rest || in_settle >= max_settle - 0.5 * solver_->dt()) {
        settling_ = false;
        turning_from_ = sim_time();
        revolutions_ = 0;
        hold_until_rev_ = 0;
        hold_power_until_rev_ = kStartHoldRev;  // as run's power.png leaves the start-up jolt out
        solver_->set_mill_omega(derived_.omega);
        solver_->set_velocity_damping(0);
        solver_->observe(true);
        solver_->take_contact_profile();
        monitor_.clear();
      }
    }
  } else if (instances_stale_) {
    feed_->update(*solver_, *balls_);
    instances_stale_ = false;
  }
}

glm::vec2 App::to_pixels(const glm::vec3& p) const {
  const float w = static_cast<float>(scene_width()), h = static_cast<float>(opt_.height);
  const glm::vec4 clip = camera_.projection(w / h) * camera_.view() * glm::vec4(p, 1.0f);
  const glm::vec3 ndc = glm::vec3(clip) / clip.w;
  return {panel_width_ + 0.5f * (ndc.x + 1) * w, 0.5f * (1 - ndc.y) * h};
}

void App::render() {
  int fb_w = 0, fb_h = 0;
  glfwGetFramebufferSize(window_->get(), &fb_w, &fb_h);
  glViewport(0, 0, fb_w, fb_h);
  glClearColor(0.11f, 0.12f, 0.14f, 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  // The scene right of the panel.
  const float scale = fb_w / static_cast<float>(std::max(1, opt_.width));
  const int x0 = static_cast<int>(panel_width_ * scale);
  glViewport(x0, 0, std::max(1, fb_w - x0), fb_h);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  const float aspect = static_cast<float>(scene_width()) / std::max(1, opt_.height);
  const glm::mat4 view = camera_.view(), proj = camera_.projection(aspect);
  colour_liner();
  mill_->draw(view, proj, camera_.orthographic(), solver_->mill_angle(), show_shell_,
              liner_colour_ != 0 && liner_.ready());
  style_.slab_from = slab_centre_ - 0.5f * slab_width_;
  style_.slab_to = slab_centre_ + 0.5f * slab_width_;
  const int mode = static_cast<int>(style_.colour_by);
  style_.range = {colour_lo_[mode], colour_hi_[mode]};
  balls_->draw(view, proj, camera_.orthographic(), style_);
  if (show_shell_) mill_->draw_near_shell(view, proj, camera_.orthographic(), solver_->mill_angle());
  MillMarks marks;
  marks.show = show_marks_ && !settling_ && monitor_.angles().found;
  marks.toe_deg = static_cast<float>(monitor_.angles().toe_deg);
  marks.shoulder_deg = static_cast<float>(monitor_.angles().shoulder_deg);
  marks.impact = liner_.ready() && std::isfinite(liner_.report().impact_point_deg);
  marks.impact_deg = static_cast<float>(liner_.report().impact_point_deg);
  mill_->draw_marks(view, proj, marks);
  glDisable(GL_DEPTH_TEST);
  glViewport(0, 0, fb_w, fb_h);
}

// The liner's elements coloured by impact power or wear rate (the sum, or
// sliding or impact wear alone) of the last
// 0.1 s (where the charge strikes as the liner turns through), on a log
// scale over three decades below the hottest element, when the monitor has
// new sums.
void App::colour_liner() {
  if (liner_colour_ == 0 || !liner_.ready() || liner_drawn_ == liner_.version()) return;
  const LinerReport& r = liner_.recent();
  std::vector<double> v(r.elements.size());
  double hi = 0;
  for (std::size_t e = 0; e < v.size(); ++e) {
    // Sliding or impact wear alone: its part of the element's wear depth.
    const LinerElementRates& x = r.elements[e];
    const double part = liner_colour_ == 3 ? x.sliding_m3_per_s : x.impact_m3_per_s;
    v[e] = liner_colour_ == 1   ? x.impact_W_m2
           : liner_colour_ == 2 ? x.wear_mm_per_1000h
           : x.wear_m3_per_s > 0 ? x.wear_mm_per_1000h * part / x.wear_m3_per_s
                                 : 0.0;
    hi = std::max(hi, v[e]);
  }
  liner_max_ = static_cast<float>(hi);
  std::vector<glm::vec3> colours(v.size());
  for (std::size_t e = 0; e < v.size(); ++e) colours[e] = heat_colour(hi > 0 && v[e] > 0 ? 1 + std::log10(v[e] / hi) / 3 : -1);
  mill_->set_liner_colours(colours);
  liner_drawn_ = liner_.version();
}

void App::handle_input() {
  const ImGuiIO& io = ImGui::GetIO();
  const float aspect = static_cast<float>(scene_width()) / std::max(1, opt_.height);
  if (!io.WantCaptureMouse && io.MousePos.x >= panel_width_) {
    if (ImGui::IsMouseDragging(ImGuiMouseButton_Left) && !io.KeyShift)
      camera_.orbit(io.MouseDelta.x, io.MouseDelta.y);
    if (ImGui::IsMouseDragging(ImGuiMouseButton_Right) || ImGui::IsMouseDragging(ImGuiMouseButton_Middle) ||
        (ImGui::IsMouseDragging(ImGuiMouseButton_Left) && io.KeyShift))
      camera_.pan(io.MouseDelta.x, io.MouseDelta.y, static_cast<float>(opt_.height));
    if (io.MouseWheel != 0) camera_.zoom(io.MouseWheel);
  }
  if (!io.WantCaptureKeyboard) {
    if (ImGui::IsKeyPressed(GLFW_KEY_SPACE)) paused_ = !paused_;
    if (ImGui::IsKeyPressed(GLFW_KEY_N)) step_once_ = true;
    if (ImGui::IsKeyPressed(GLFW_KEY_E)) camera_.end_view(aspect);
    if (ImGui::IsKeyPressed(GLFW_KEY_I)) camera_.isometric(aspect);
    if (ImGui::IsKeyPressed(GLFW_KEY_P)) screenshot_requested_ = true;
    if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE)) glfwSetWindowShouldClose(window_->get(), GLFW_TRUE);
  }
}

std::string App::stamp() const {
  const std::time_t t = std::time(nullptr);
  char s[32];
  std::strftime(s, sizeof s, "%Y%m%d-%H%M%S", std::localtime(&t));
  return s;
}

// Reads the back buffer: call after everything of the frame is drawn.
void App::take_screenshot(const std::string& path_in, bool announce) {
  const fs::path path = path_in.empty() ? fs::path("runs") / ("view-" + case_.name + "-" + stamp() + ".png") : fs::path(path_in);
  int fb_w = 0, fb_h = 0;
  glfwGetFramebufferSize(window_->get(), &fb_w, &fb_h);
  try {
    write_png(path, read_back_buffer(fb_w, fb_h));
    if (announce) message_ = "wrote " + path.string();
  } catch (const std::exception& e) {
    message_ = e.what();
    if (!announce) throw;
  }
}

// The state as a run folder: checkpoint.bin, which `millcharge run --resume
// DIR` turns on from (for the case's run.duration, its warm-up first) and
// `bench --from DIR` times, the case as edited, and the balls for ParaView.
// False when only the case and the balls could be written (message_ says
// why); throws what fails, which the panel shows.
bool App::save_state(const std::string& dir_in) {
  const fs::path dir = dir_in.empty() ? fs::path("runs") / ("view-" + case_.name + "-" + stamp()) : fs::path(dir_in);
  fs::create_directories(dir / "snapshots");
  const std::vector<BallState> balls = solver_->balls();
  io::Snapshot s;
  s.time_s = sim_time();
  for (const BallState& b : balls) {
    s.position.push_back({float(b.position.x), float(b.position.y), float(b.position.z)});
    s.velocity.push_back({float(b.velocity.x), float(b.velocity.y), float(b.velocity.z)});
    s.radius.push_back(float(b.radius));
    s.material.push_back(b.material);
    s.id.push_back(b.id);
  }
  io::write_vtp(dir / "charge.vtp", s);
  // A run rebuilds the case's charge and restores the state into it, so the
  // case must pack as many balls as the window holds. An edit of the lifters
  // keeps the balls in a mill of another volume: the case is saved with the
  // filling they fill there.
  MillCase saved = case_;
  char filled[128] = "";
  const bool fits = !scene_.bodies.empty() || n_balls_ == derived_.n_balls || fill_for_count(saved, n_balls_);
  if (fits && saved.filling != case_.filling)
    std::snprintf(filled, sizeof filled, " (charge.filling %.4g: what its %d balls fill)", saved.filling, n_balls_);
  const std::string case_text = io::case_to_toml(saved);
  io::write_file_atomic(dir / "case.toml", case_text);
  if (!fits) {
    message_ = "saved " + dir.string() + ": charge.vtp and case.toml; no checkpoint: no filling of this mill packs the " +
               std::to_string(n_balls_) + " balls in the window (Reset, or change the filling, to run it headless)";
    return false;
  }
  // On the window's clock (a solver made by an edit counts from zero).
  SolverState state = solver_->save_state();
  state.time_s += time_offset_;
  state.observed_since += time_offset_;
  state.steps += step_offset_;
  RunState run = run_state_from(sim_time(), !settling_, settle_from_, saved);
  if (!settling_) run.turn_start_s = turning_from_;  // the window turns on from it; run --resume starts its own
  io::write_checkpoint(dir / io::kCheckpointFile, io::Checkpoint{saved.name, case_text, run, std::move(state)});
  char when[48];
  std::snprintf(when, sizeof when, " at t = %.3f s", sim_time());
  message_ = "saved " + dir.string() + when + filled + ": run it on headless with millcharge run --resume " + dir.string();
  return true;
}

int App::run() {
  GLFWwindow* w = window_->get();
  start_ = window_from_ = Clock::now();
  auto last = Clock::now();
  while (!glfwWindowShouldClose(w)) {
    glfwPollEvents();
    if (!scripted_ && glfwGetWindowAttrib(w, GLFW_ICONIFIED)) {
      glfwWaitEventsTimeout(0.1);
      last = Clock::now();  // the time iconified is no frame's: the pacing goes on as before
      continue;
    }
    int ww = 0, wh = 0;
    glfwGetWindowSize(w, &ww, &wh);
    if (ww > 0 && wh > 0) opt_.width = ww, opt_.height = wh;

    scripted_edits();
    step_frame();

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    handle_input();
    if (opt_.panel) draw_panel();
    draw_labels();
    ImGui::Render();
    render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

    ++frames_;
    ++window_frames_;
    const bool last_frame = scripted_ && frames_ >= opt_.frames;
    if (last_frame && !opt_.screenshot.empty()) take_screenshot(opt_.screenshot, false);
    if (screenshot_requested_) {
      take_screenshot("", true);
      screenshot_requested_ = false;
    }
    glfwSwapBuffers(w);
    {  // the time from the command to the first frame, and to the first of the turning mill
      const double since = std::chrono::duration<double>(Clock::now() - opt_.started).count();
      if (first_frame_s_ < 0) first_frame_s_ = since;
      if (first_turning_frame_s_ < 0 && !settling_) first_turning_frame_s_ = since;
    }

    const auto t2 = Clock::now();
    last_frame_s_ = std::chrono::duration<double>(t2 - last).count();
    last = t2;
    // Everything in a frame but the steps: drawing, the copy, the sums.
    const double overhead = std::max(0.0, last_frame_s_ - advance_s_);
    frame_overhead_s_ = 0.8 * frame_overhead_s_ + 0.2 * overhead;
    const double window_s = std::chrono::duration<double>(t2 - window_from_).count();
    if (window_s >= 1.0) {
      fps_ = window_frames_ / window_s;
      steps_per_s_ = window_steps_ / window_s;
      window_frames_ = window_steps_ = 0;
      window_from_ = t2;
    }
    if (pending_ == Edit::apply) apply_case(edit_);
    if (pending_ == Edit::reset) reset();
    pending_ = Edit::none;
    if (last_frame) break;
  }
  if (!opt_.save_state_dir.empty()) {
    if (!save_state(opt_.save_state_dir)) throw std::runtime_error(message_);
    std::printf("millcharge view: %s\n", message_.c_str());
  }
  const double wall = std::chrono::duration<double>(Clock::now() - start_).count();
  std::fprintf(stderr,
               "millcharge view: %ld frames in %.1f s: %.2f drawn fps, %.0f steps/s, %.3g particle-updates/s "
               "(%d balls, %s steps per frame, %s)\n",
               frames_, wall, frames_ / wall, steps_ / wall, steps_ / wall * n_balls_, n_balls_,
               adaptive_ ? "adaptive" : std::to_string(fixed_steps_).c_str(), feed_->path().c_str());
  char turning[64] = "in no frame (still settling)";
  if (first_turning_frame_s_ >= 0) std::snprintf(turning, sizeof turning, "first drawn %.2f s after it", first_turning_frame_s_);
  std::fprintf(stderr, "millcharge view: first frame drawn %.2f s after the command; the turning mill %s\n",
               first_frame_s_, turning);
  if (scripted_ && !opt_.screenshot.empty()) {
    const glm::vec2 axis = to_pixels({0, 0, static_cast<float>(case_.length)});
    const glm::vec2 rim = to_pixels({static_cast<float>(0.5 * case_.diameter), 0, static_cast<float>(case_.length)});
    std::printf(
        "millcharge view: wrote %s (%dx%d): mill axis at pixel (%.1f, %.1f), shell radius %.1f px; "
        "%s %.3f s, %.1f %% of critical, %d balls\n",
        opt_.screenshot.c_str(), opt_.width, opt_.height, axis.x, axis.y, glm::length(rim - axis),
        settling_ ? "settling" : "turning", settling_ ? sim_time() - settle_from_ : sim_time() - turning_from_,
        100 * derived_.speed_fraction, n_balls_);
    if (liner_.ready()) {
      const LinerReport& r = liner_.report();
      char point[96] = "impact point not yet (too few impacts)";
      if (std::isfinite(r.impact_point_deg))
        std::snprintf(point, sizeof point, "impact point %.0f deg (%.0f %% of the impact power on bare liner)",
                      r.impact_point_deg, 100 * r.bare_liner_impact_share);
      std::printf("millcharge view: liner over the last %.2f s: impact %.4g W, shear %.4g W, wear %.3g kg/h (shell, "
                  "lifters, ends%s); %s\n",
                  r.window_s, r.impact_W, r.shear_W, r.wear_kg_per_h,
                  wear_coefficient_is_default(scene_.wall_material.wear_coefficient) ? "; relative: wear coefficient "
                                                                                      "not calibrated"
                                                                                    : "",
                  point);
    }
    if (opt_.from)
      std::printf("millcharge view: state from %s at t = %.4f s (%s)\n", opt_.from_dir.c_str(), source_time_,
                  opened_turning_ ? "turning" : "settling");
    if (!settling_)
      std::printf("millcharge view: turned %.4f rev from t = %.4f s to %.4f s (the sum of omega dt)\n", revolutions_,
                  turning_from_, sim_time());
    char since[160] = "window";
    if (last_edit_frame_ >= 0 && last_edit_s_ > turning_from_)
      std::snprintf(since, sizeof since, "window since the edit before frame %ld (t = %.4f s) and its %.2f rev of settle-in",
                    last_edit_frame_, last_edit_s_, kSettleInRev);
    const ChargeAngles all = monitor_.all_angles();
    if (all.found) {
      const MeanWithError toe = monitor_.toe_mean(), shoulder = monitor_.shoulder_mean();
      char batches[160] = "";
      if (toe.error >= 0)
        std::snprintf(batches, sizeof batches, "; batches of %.1f s: toe %.2f +- %.2f, shoulder %.2f +- %.2f deg (%d batches)",
                      ChargeMonitor::kProfileWindow * ChargeMonitor::kProfileEvery, toe.mean, toe.error, shoulder.mean,
                      shoulder.error, toe.batches);
      std::printf("millcharge view: toe %.2f deg, shoulder %.2f deg from the contact profile of the %.3f s turned in the "
                  "%s%s\n",
                  all.toe_deg, all.shoulder_deg, monitor_.all_span_s(), since, batches);
    }
    if (monitor_.mean_span_s() > 0) {
      const MeanWithError p = monitor_.mean_torque_power();
      char error[64] = " (no standard error: fewer than 3 batches)";
      if (p.error >= 0) std::snprintf(error, sizeof error, " +- %.2f", p.error);
      std::printf("millcharge view: torque power %.2f W%s, dissipation %.2f W over the %.3f s turned in the %s "
                  "(%d batches of %.1f s)\n",
                  p.mean, error, monitor_.mean_dissipation_power(), monitor_.mean_span_s(), since, p.batches,
                  ChargeMonitor::kPowerBatch * ChargeMonitor::kPowerEvery);
    }
  }
  return 0;
}

int run(const MillCase& c, const MillDerived& d, Scene scene, const ViewOptions& options) {
  App app(c, d, std::move(scene), options);
  return app.run();
}

}  // namespace mc::viewer
