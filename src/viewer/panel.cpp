// The ImGui panel on the left of the window: statistics, run control, the
// mill and charge parameters that change while the mill turns, the view,
// live plots and output buttons. Sliders that need a new scene apply when
// released, so one drag is one rebuild.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <imgui.h>

#include "io/case_file.h"
#include "viewer/app.h"
#include "viewer/label_layout.h"

namespace mc::viewer {

namespace {

std::string si(double v, const char* unit) {
  char buf[64];
  const double a = std::fabs(v);
  if (a >= 1e9) std::snprintf(buf, sizeof buf, "%.3g G%s", v / 1e9, unit);
  else if (a >= 1e6) std::snprintf(buf, sizeof buf, "%.3g M%s", v / 1e6, unit);
  else if (a >= 1e3) std::snprintf(buf, sizeof buf, "%.3g k%s", v / 1e3, unit);
  else std::snprintf(buf, sizeof buf, "%.3g %s", v, unit);
  return buf;
}

// The units of the balls' colours, by ColourBy (material: none).
constexpr const char* kColourUnits[] = {"m/s", "m (radius)", "", "log10 W dissipated"};

// A colour bar with the shader's ramp (shaders/balls.vert).
void colour_bar(float lo, float hi, const char* unit) {
  const ImVec4 stops[5] = {{0.15f, 0.30f, 0.95f, 1}, {0.05f, 0.75f, 0.90f, 1}, {0.25f, 0.85f, 0.25f, 1},
                           {0.98f, 0.80f, 0.10f, 1}, {0.90f, 0.15f, 0.10f, 1}};
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const ImVec2 p = ImGui::GetCursorScreenPos();
  const float w = ImGui::GetContentRegionAvail().x, h = 10;
  for (int k = 0; k < 4; ++k) {
    const float x0 = p.x + w * k / 4, x1 = p.x + w * (k + 1) / 4;
    dl->AddRectFilledMultiColor({x0, p.y}, {x1, p.y + h}, ImGui::GetColorU32(stops[k]), ImGui::GetColorU32(stops[k + 1]),
                                ImGui::GetColorU32(stops[k + 1]), ImGui::GetColorU32(stops[k]));
  }
  ImGui::Dummy({w, h});
  ImGui::Text("%.3g", lo);
  ImGui::SameLine(w * 0.5f - 20);
  ImGui::TextUnformatted(unit);
  char hi_text[32];
  std::snprintf(hi_text, sizeof hi_text, "%.3g", hi);
  ImGui::SameLine(w - ImGui::CalcTextSize(hi_text).x);
  ImGui::TextUnformatted(hi_text);
}

bool released() { return ImGui::IsItemDeactivatedAfterEdit(); }

}  // namespace

void App::draw_panel() {
  ImGui::SetNextWindowPos({0, 0});
  ImGui::SetNextWindowSize({panel_width_, static_cast<float>(opt_.height)});
  ImGui::Begin("millcharge", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_NoTitleBar);
  ImGui::PushItemWidth(-150);
  panel_stats();
  if (ImGui::CollapsingHeader("Run", ImGuiTreeNodeFlags_DefaultOpen)) panel_run();
  if (ImGui::CollapsingHeader("Plots", ImGuiTreeNodeFlags_DefaultOpen)) panel_plots();
  if (ImGui::CollapsingHeader("Mill", ImGuiTreeNodeFlags_DefaultOpen)) panel_mill();
  if (ImGui::CollapsingHeader("Charge", ImGuiTreeNodeFlags_DefaultOpen)) panel_charge();
  if (ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen)) panel_view();
  if (ImGui::CollapsingHeader("Output", ImGuiTreeNodeFlags_DefaultOpen)) panel_output();
  ImGui::PopItemWidth();
  ImGui::End();
}

void App::panel_stats() {
  if (scene_.bodies.empty())
    ImGui::Text("%s: %d balls", case_.name.c_str(), n_balls_);
  else  // a charge of clumps: its spheres are what the kernels step
    ImGui::Text("%s: %zu clumps and balls, %d spheres", case_.name.c_str(),
                scene_.bodies.size() + static_cast<std::size_t>(scene_.bodies.front().first), n_balls_);
  ImGui::TextWrapped("device %s", solver_->device().label().c_str());
  ImGui::TextWrapped("data path: %s", feed_->path().c_str());
  ImGui::Text("%.1f fps drawn, %d steps/frame", fps_, last_steps_);
  ImGui::Text("%s steps/s, %s particle-updates/s", si(steps_per_s_, "").c_str(),
              si(steps_per_s_ * n_balls_, "").c_str());
  const double t = sim_time();
  if (settling_)
    ImGui::TextColored({1, 0.8f, 0.3f, 1}, "settling %.3f s (mill at rest)", t - settle_from_);
  else {
    ImGui::Text("turning %.3f s, %.2f rev", t - turning_from_, revolutions_);
    ImGui::Text("t %.3f s, dt %.3g s", t, solver_->dt());
  }
  if (!settling_ && revolutions_ < hold_until_rev_)
    ImGui::TextColored({1, 0.8f, 0.3f, 1}, "edited: averages from %.2f rev (%.2f rev of settle-in)", hold_until_rev_,
                       kSettleInRev);
  // What the balls' colours mean, where it is always in sight (the View
  // section below sets it).
  if (style_.colour_by != ColourBy::material) {
    const char* names[] = {"speed", "size", "", "impact energy"};
    const int mode = static_cast<int>(style_.colour_by);
    ImGui::Text("colour: %s", names[mode]);
    colour_bar(colour_lo_[mode], colour_hi_[mode], kColourUnits[mode]);
  } else {
    ImGui::TextUnformatted("colour: material");
  }
  if (source_.empty())
    ImGui::TextWrapped("state: a fresh packing of %s", case_.name.c_str());
  else
    ImGui::TextWrapped("state: from %s at t %.3f s%s", source_.c_str(), source_time_,
                       io::case_to_toml(case_) == io::case_to_toml(loaded_) ? "" : ", edited");
}

void App::panel_run() {
  if (ImGui::Button(paused_ ? "Resume (space)" : "Pause (space)")) paused_ = !paused_;
  ImGui::SameLine();
  if (ImGui::Button("Step (n)")) step_once_ = true;
  ImGui::SameLine();
  if (ImGui::Button("Reset")) {
    edit_ = case_;
    pending_ = Edit::reset;
  }
  ImGui::Checkbox("adapt steps per frame", &adaptive_);
  if (adaptive_) {
    ImGui::SliderFloat("speed limit, x real time", &speed_limit_, 0.01f, 10.0f, "%.2f",
                       ImGuiSliderFlags_Logarithmic);
  } else {
    ImGui::SliderInt("steps per frame", &fixed_steps_, 1, 5000, "%d", ImGuiSliderFlags_Logarithmic);
  }
  ImGui::Text("simulated/real: %.3f", steps_per_s_ * solver_->dt());
}

void App::panel_mill() {
  float pct = static_cast<float>(100 * derived_.speed_fraction);
  if (ImGui::SliderFloat("speed, % critical", &pct, 10.0f, 150.0f, "%.1f %%")) set_speed_fraction(pct / 100.0);
  float rpm = static_cast<float>(derived_.speed_rpm);
  ImGui::InputFloat("rpm", &rpm, 0, 0, "%.2f");
  if (released() && rpm > 0) set_speed_fraction(rpm / derived_.critical_rpm);
  ImGui::Text("critical %.2f rpm, tip %.2f m/s", derived_.critical_rpm, derived_.tip_speed);

  float j = static_cast<float>(edit_.filling);
  ImGui::SliderFloat("filling J", &j, 0.05f, 0.5f, "%.3f");
  if (ImGui::IsItemEdited()) edit_.filling = j;
  if (released()) pending_ = Edit::apply;

  ImGui::Separator();
  ImGui::TextUnformatted("lifters (applied on release)");
  int rows = edit_.lifter_rows;
  ImGui::SliderInt("rows", &rows, 0, 48);
  if (ImGui::IsItemEdited()) {
    edit_.lifter_rows = rows;
    if (edit_.lifter_pattern.empty()) edit_.lifter_pattern.push_back(LifterProfile{});
  }
  if (released()) pending_ = Edit::apply;
  bool high_low = edit_.lifter_pattern.size() >= 2;
  if (ImGui::Checkbox("high/low pattern", &high_low)) {
    if (edit_.lifter_pattern.empty()) edit_.lifter_pattern.push_back(LifterProfile{});
    if (high_low) {
      LifterProfile low = edit_.lifter_pattern[0];
      low.height *= 0.6;
      for (Vec2& v : low.points) v.y *= 0.6;
      edit_.lifter_pattern.resize(1);
      edit_.lifter_pattern.push_back(low);
    } else {
      edit_.lifter_pattern.resize(1);
    }
    pending_ = Edit::apply;
  }
  for (std::size_t k = 0; k < edit_.lifter_pattern.size(); ++k) {
    LifterProfile& p = edit_.lifter_pattern[k];
    ImGui::PushID(static_cast<int>(k));
    if (edit_.lifter_pattern.size() > 1) ImGui::TextUnformatted(k == 0 ? "high rows" : "low rows");
    if (p.polygon()) {
      // A measured or worn outline: its measures, and a way back to h x w x theta.
      const ProfileMeasures m = measure_profile(profile_outline(p));
      ImGui::Text("outline of %zu points: %.1f mm high, top %.1f mm", p.points.size(), 1000 * m.height,
                  1000 * m.top_width);
      ImGui::Text("faces %.1f deg leading, %.1f deg trailing", m.leading_angle_deg, m.trailing_angle_deg);
      if (ImGui::Button("edit as h x w x face angle")) {
        p.height = m.height;
        p.top_width = std::max(m.top_width, 0.002);
        p.face_angle_deg = std::clamp(0.5 * (m.leading_angle_deg + m.trailing_angle_deg), 0.0, 59.0);
        p.points.clear();
        pending_ = Edit::apply;
      }
      ImGui::PopID();
      continue;
    }
    float h = static_cast<float>(1000 * p.height), w = static_cast<float>(1000 * p.top_width),
          a = static_cast<float>(p.face_angle_deg);
    if (ImGui::SliderFloat("height, mm", &h, 2.0f, static_cast<float>(250 * case_.diameter), "%.1f")) p.height = h / 1000;
    if (released()) pending_ = Edit::apply;
    if (ImGui::SliderFloat("top width, mm", &w, 2.0f, static_cast<float>(200 * case_.diameter), "%.1f"))
      p.top_width = w / 1000;
    if (released()) pending_ = Edit::apply;
    if (ImGui::SliderFloat("face angle, deg", &a, 0.0f, 59.0f, "%.1f")) p.face_angle_deg = a;
    if (released()) pending_ = Edit::apply;
    ImGui::PopID();
  }
}

void App::panel_charge() {
  float scale = static_cast<float>(ball_scale_);
  ImGui::SliderFloat("ball size x", &scale, 0.6f, 1.6f, "%.2f");
  if (ImGui::IsItemEdited()) {
    ball_scale_ = scale;
    edit_.sizes = loaded_.sizes;
    for (SizeClass& s : edit_.sizes) {
      s.diameter_min *= ball_scale_;
      s.diameter_max *= ball_scale_;
    }
  }
  if (released()) pending_ = Edit::apply;
  for (const SizeClass& s : edit_.sizes)
    ImGui::Text("  %s %.1f-%.1f mm", s.material.c_str(), 1000 * s.diameter_min, 1000 * s.diameter_max);

  float mu = static_cast<float>(edit_.contact.mu_slide);
  if (ImGui::SliderFloat("friction", &mu, 0.0f, 1.0f, "%.2f")) {
    edit_.contact.mu_slide = mu;
    for (PairOverride& p : edit_.pairs) p.interaction.mu_slide = mu;
  }
  if (released()) pending_ = Edit::apply;
  float e = static_cast<float>(edit_.contact.restitution);
  if (ImGui::SliderFloat("restitution", &e, 0.05f, 0.95f, "%.2f")) {
    edit_.contact.restitution = e;
    for (PairOverride& p : edit_.pairs) p.interaction.restitution = e;
  }
  if (released()) pending_ = Edit::apply;
  ImGui::TextDisabled("(friction and restitution of every pair)");
}

void App::panel_view() {
  const float aspect = static_cast<float>(scene_width()) / std::max(1, opt_.height);
  if (ImGui::Button("End view (e)")) camera_.end_view(aspect);
  ImGui::SameLine();
  if (ImGui::Button("Isometric (i)")) camera_.isometric(aspect);
  ImGui::SameLine();
  bool ortho = camera_.orthographic();
  if (ImGui::Checkbox("ortho", &ortho)) camera_.set_orthographic(ortho);
  const char* modes[] = {"speed", "size", "material", "impact energy"};
  int mode = static_cast<int>(style_.colour_by);
  if (ImGui::Combo("colour by", &mode, modes, 4)) style_.colour_by = static_cast<ColourBy>(mode);
  if (style_.colour_by != ColourBy::material) {
    ImGui::DragFloatRange2("range", &colour_lo_[mode], &colour_hi_[mode], 0.01f);
    colour_bar(colour_lo_[mode], colour_hi_[mode], kColourUnits[mode]);
  }
  ImGui::Checkbox("axial slab", &style_.slab);
  if (style_.slab) {
    ImGui::SliderFloat("slab centre, m", &slab_centre_, 0.0f, static_cast<float>(case_.length), "%.3f");
    ImGui::SliderFloat("slab width, m", &slab_width_, 0.005f, static_cast<float>(case_.length), "%.3f");
  }
  const char* liner_modes[] = {"plain", "impact power", "wear rate", "sliding wear", "impact wear"};
  if (ImGui::Combo("liner", &liner_colour_, liner_modes, 5)) liner_drawn_ = -1;
  if (liner_colour_ != 0) {
    if (!liner_.ready()) ImGui::TextDisabled("(the liner's sums come once the mill turns)");
    else {
      const bool relative = wear_coefficient_is_default(scene_.wall_material.wear_coefficient);
      colour_bar(liner_max_ / 1000, liner_max_,
                 liner_colour_ == 1 ? "W/m^2, log" : relative ? "mm per 1000 h, log, relative" : "mm per 1000 h, log");
      const LinerReport& r = liner_.report();
      ImGui::TextWrapped("liner: impact %.3g W, shear %.3g W, wear %.3g kg/h (sliding %.3g, impact %.3g; shell, "
                         "lifters, ends)%s",
                         r.impact_W, r.shear_W, r.wear_kg_per_h, r.sliding_kg_per_h, r.impact_kg_per_h,
                         relative ? ", relative: wear coefficient not calibrated" : "");
    }
  }
  if (liner_.ready() && std::isfinite(liner_.report().impact_point_deg)) {
    const LinerReport& r = liner_.report();
    ImGui::Text("impact point %.0f deg, on the %s; %.0f %% of impact power on bare liner", r.impact_point_deg,
                r.impact_point_on_liner ? "bare liner" : "toe", 100 * r.bare_liner_impact_share);
  } else if (liner_colour_ != 0 && liner_.ready()) {
    ImGui::TextDisabled("impact point: not yet (too few impacts)");
  }
  ImGui::Checkbox("shell", &show_shell_);
  ImGui::SameLine();
  ImGui::Checkbox("toe/shoulder marks", &show_marks_);
  ImGui::TextDisabled("drag: orbit, right/shift-drag: pan, wheel: zoom");
}

void App::panel_plots() {
  const auto& tq = monitor_.torque_power();
  const auto& ds = monitor_.dissipation_power();
  float hi = 1;
  for (float v : tq) hi = std::max(hi, v);
  for (float v : ds) hi = std::max(hi, v);
  hi *= 1.1f;
  const float w = ImGui::GetContentRegionAvail().x;
  // Each applied edit as a vertical line in the plot just drawn, where the
  // first point after it lies.
  auto marks = [](const std::vector<int>& at, std::size_t n) {
    if (n < 2) return;
    const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
    const ImVec2 pad = ImGui::GetStyle().FramePadding;
    ImDrawList* dl = ImGui::GetWindowDrawList();
    for (int k : at) {
      const float x = lo.x + pad.x + (hi.x - lo.x - 2 * pad.x) * static_cast<float>(k) / static_cast<float>(n - 1);
      dl->AddLine({x, lo.y + 1}, {x, hi.y - 1}, IM_COL32(255, 70, 200, 255), 2.0f);
    }
  };
  char label[128];
  const MeanWithError p = monitor_.mean_torque_power();
  const bool held = !settling_ && revolutions_ < hold_until_rev_;
  if (held) std::snprintf(label, sizeof label, "torque power: edited, held %.2f rev", kSettleInRev);
  else if (p.error >= 0) std::snprintf(label, sizeof label, "torque power, mean %.0f +- %.0f W", p.mean, p.error);
  else std::snprintf(label, sizeof label, "torque power, mean %.0f W", p.mean);
  ImGui::PlotLines("##torque", tq.data(), static_cast<int>(tq.size()), 0, label, 0, hi, {w, 48});
  marks(monitor_.power_marks(), tq.size());
  std::snprintf(label, sizeof label, "dissipation, mean %.0f W", monitor_.mean_dissipation_power());
  ImGui::PlotLines("##dissipation", ds.data(), static_cast<int>(ds.size()), 0, label, 0, hi, {w, 48});
  marks(monitor_.power_marks(), ds.size());
  const ChargeAngles& a = monitor_.angles();
  if (a.found) std::snprintf(label, sizeof label, "toe %.0f deg", a.toe_deg);
  else std::snprintf(label, sizeof label, "toe (no band yet)");
  ImGui::PlotLines("##toe", monitor_.toe().data(), static_cast<int>(monitor_.toe().size()), 0, label, FLT_MAX,
                   FLT_MAX, {w, 36});
  marks(monitor_.angle_marks(), monitor_.toe().size());
  if (a.found) std::snprintf(label, sizeof label, "shoulder %.0f deg", a.shoulder_deg);
  else std::snprintf(label, sizeof label, "shoulder (no band yet)");
  ImGui::PlotLines("##shoulder", monitor_.shoulder().data(), static_cast<int>(monitor_.shoulder().size()), 0, label,
                   FLT_MAX, FLT_MAX, {w, 36});
  marks(monitor_.angle_marks(), monitor_.shoulder().size());
}

void App::panel_output() {
  if (ImGui::Button("Screenshot (p)")) screenshot_requested_ = true;
  ImGui::SameLine();
  if (ImGui::Button("Save state")) {
    try {
      save_state("");
    } catch (const std::exception& e) {
      message_ = std::string("save failed: ") + e.what();
    }
  }
  if (!message_.empty()) ImGui::TextWrapped("%s", message_.c_str());
}

// Toe and shoulder named beside their marks in the picture.
void App::draw_labels() {
  if (!show_marks_ || settling_ || !monitor_.angles().found) return;
  ImDrawList* dl = ImGui::GetForegroundDrawList();
  const float R = static_cast<float>(0.5 * case_.diameter), z = static_cast<float>(case_.length);
  std::vector<LabelBox> taken;
  auto label = [&](double deg, const char* name, ImU32 colour, float radius) {
    const float a = static_cast<float>(deg * M_PI / 180.0);
    char text[48];
    std::snprintf(text, sizeof text, "%s %.0f", name, deg);
    const ImVec2 size = ImGui::CalcTextSize(text);
    // Beside its mark, inside the picture whatever the zoom; a label that
    // would cover one already drawn moves outward along its ray.
    auto along = [&](float r) {
      const glm::vec2 p = to_pixels({r * R * std::cos(a), r * R * std::sin(a), z});
      return std::pair<float, float>(p.x, p.y);
    };
    const LabelBox b = place_label(along, size.x, size.y, radius, kMarkLabelStep, 8, panel_width_ + 2,
                                   static_cast<float>(opt_.width) - 2, 2.0f, static_cast<float>(opt_.height) - 2, taken);
    taken.push_back(b);
    dl->AddRectFilled({b.x0 - 3, b.y0 - 1}, {b.x1 + 3, b.y1 + 1}, IM_COL32(28, 31, 36, 220), 3.0f);
    dl->AddText({b.x0, b.y0}, colour, text);
  };
  // Outside every wedge (mill_renderer.cpp: out to 1.36 R), in the marks'
  // colours (charge.png's: toe red, shoulder orange, impact magenta).
  label(monitor_.angles().toe_deg, "toe", IM_COL32(235, 60, 60, 255), kMarkLabelRadius);
  label(monitor_.angles().shoulder_deg, "shoulder", IM_COL32(245, 140, 30, 255), kMarkLabelRadius);
  if (liner_.ready() && std::isfinite(liner_.report().impact_point_deg))
    label(liner_.report().impact_point_deg, "impact", IM_COL32(255, 50, 215, 255), kMarkLabelRadius);
}

}  // namespace mc::viewer
