// millcharge life: the liner over its life (docs/liner-life.md). A study
// above runs, like a sweep: run a stage on the liner as it is, take each
// lifter wear station's and the shell's wear rate, move the lifters' faces
// and the shell by the stage's wear, and run the next stage on the worn
// liner. life.json holds the study's state (written before the first run and
// after each step, so a killed study resumes where it stopped; life_state.h
// reads it back strictly); life.csv, life.png and life.pvd are the whole life.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/life_mesh.h"
#include "app/life_options.h"
#include "app/life_plates.h"
#include "app/life_picture.h"
#include "app/life_state.h"
#include "app/prepare.h"
#include "app/sweep_runs.h"
#include "core/lifters.h"
#include "core/liner.h"
#include "core/liner_wear.h"
#include "core/plate_wear.h"
#include "io/atomic_file.h"
#include "io/case_file.h"
#include "io/csv_read.h"
#include "io/json_read.h"
#include "io/stl.h"
#include "life/bar_twin.h"
#include "io/png_plot.h"
#include "core/scene.h"

namespace mc::app {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using life::kFormat;
using life::Stage;
using life::StageResult;
using life::bar_length;

// The request a study was started with: a study resumes only with the same.
json request_of(const LifeOptions& o, const Prepared& p) {
  return {{"case", fs::absolute(p.path).lexically_normal().string()},
          {"overrides", case_overrides(o.c)},
          {"stages", o.stages},
          {"hours", o.hours},
          {"until_height_mm", o.until_height_mm},
          {"calibrate_loss_mm", o.calibrate_loss_mm},
          {"calibrate_hours", o.calibrate_hours},
          {"calibrate_rate_kg_h", o.calibrate_rate_kg_h}};
}

// The request with --calibrate-consumption where it was given (a study
// started before the option resumes with the request it wrote).
json request_with_consumption(const LifeOptions& o, const Prepared& p) {
  json r = request_of(o, p);
  if (o.calibrate_consumption_g_kWh > 0) r["calibrate_consumption_g_per_kWh"] = o.calibrate_consumption_g_kWh;
  if (o.impact_share >= 0) r["impact_share"] = o.impact_share;
  if (o.shell_wear_ratio != 1) r["shell_wear_ratio"] = o.shell_wear_ratio;
  return r;
}

// The case hours in which stage s's wear takes `loss` mm off profile k's
// height above the shell (core/liner_wear.h hours_to_lose); negative when
// that wear does not lower it.
double span_for_loss(const Stage& s, int k, double length, double loss) {
  const BarWearRates rates{s.r.station_m3_s[k], bar_length(s, length), s.r.shell_mm_per_1000h * 1e-6};
  return hours_to_lose(s.outlines[k], 0.5 * s.diameter, rates, loss * 1e-3);
}

struct Study {
  std::vector<Stage> stages;
  double factor = 1;           // calibrated hours = case hours / factor
  std::string calibration;     // how the factor was found
  int tallest = 0;             // the profile the height figures follow
  double wear_coefficient = 0; // the case's (the liner material's)
  double impact_coefficient = 0;  // the case's impact wear coefficient, m³/J
  double density = 0;          // the liner's, kg/m³
  life::WearMix mix;           // how the two wears add (life_state.h)
  bool calibrated = false;     // by a measured figure (--calibrate-...)
  // Hours and wear rates are relative: the default wear coefficient, not
  // calibrated (core/scene.h kWearRelative).
  bool relative() const { return !calibrated && wear_coefficient_is_default(wear_coefficient); }
  // life.csv's wear_basis: what its hours and wear rates stand on.
  const char* basis() const { return calibrated ? "calibrated" : relative() ? "relative" : "case_coefficient"; }
};

double height_of(const Stage& s, int k) { return measure_profile(s.outlines[k]).height; }

// With --impact-share (or --shell-wear-ratio), the mix that gives the new
// liner that share, and every stage's wear at it; else the case's own mix,
// as the runs wrote it.
void mix_stages(Study& st, const LifeOptions& o) {
  if (o.impact_share < 0 && o.shell_wear_ratio == 1) return;
  st.mix = life::mix_for_share(st.stages.front().r, o.impact_share >= 0 ? o.impact_share : NAN,
                               st.impact_coefficient, st.density, o.shell_wear_ratio);
  for (Stage& s : st.stages)
    if (s.ran) life::apply_mix(s.r, st.mix, st.density);
}

// The share of a stage's shell and lifter wear that impact does, at the
// study's mix.
double impact_share_of(const Study& st, const StageResult& r) {
  return life::impact_share(r, st.mix, st.density);
}

// The calibration factor from the stages so far.
void calibrate(Study& st, const LifeOptions& o, double length) {
  const Stage& s0 = st.stages.front();
  st.calibrated = o.calibrate_rate_kg_h > 0 || o.calibrate_loss_mm > 0 || o.calibrate_consumption_g_kWh > 0;
  if (o.calibrate_consumption_g_kWh > 0) {
    const double g = grams_per_kWh(s0.r.liner_kg_h, s0.r.power_W);
    if (!(g > 0))
      throw std::invalid_argument(fmt::format(
          "--calibrate-consumption {:g}: the new liner's run booked no wear on the shell and the lifters ({:.4g} kg/h at "
          "{:.4g} W); nothing to set the measured consumption against",
          o.calibrate_consumption_g_kWh, s0.r.liner_kg_h, s0.r.power_W));
    st.factor = o.calibrate_consumption_g_kWh / g;
    st.calibration = fmt::format("the new shell and lifters' consumption, {:.6g} g/kWh measured against {:.6g} g/kWh "
                                 "at the case's wear coefficient",
                                 o.calibrate_consumption_g_kWh, g);
    return;
  }
  if (o.calibrate_rate_kg_h > 0) {
    if (!(s0.r.liner_kg_h > 0))
      throw std::invalid_argument("--calibrate-rate: the new liner's run booked no wear on the shell and the lifters; "
                                  "nothing to set the measured rate against");
    st.factor = o.calibrate_rate_kg_h / s0.r.liner_kg_h;
    st.calibration = fmt::format("the new shell liner's wear rate, {:.4g} kg/h measured against {:.4g} kg/h at the "
                                 "case's wear coefficient",
                                 o.calibrate_rate_kg_h, s0.r.liner_kg_h);
    return;
  }
  if (!(o.calibrate_loss_mm > 0)) {
    st.factor = 1;
    st.calibration = st.relative() ? std::string("none: the case's wear coefficient is the default stand-in; hours and "
                                                 "wear rates are ") + kWearRelative
                                   : "none: the case's wear coefficient";
    return;
  }
  // Height lost against case hours; where it reaches the measured loss.
  const int k = st.tallest;
  const double h0 = height_of(s0, k) * 1000;
  double at = -1;
  for (std::size_t i = 1; i < st.stages.size() && at < 0; ++i) {
    const double l0 = h0 - height_of(st.stages[i - 1], k) * 1000, l1 = h0 - height_of(st.stages[i], k) * 1000;
    if (l1 >= o.calibrate_loss_mm && l1 > l0)
      at = st.stages[i - 1].case_hours +
           (o.calibrate_loss_mm - l0) / (l1 - l0) * (st.stages[i].case_hours - st.stages[i - 1].case_hours);
  }
  std::string how = "interpolated between stages";
  if (at < 0) {  // not reached yet: on at the rate the last stage's wear lowers the bar
    const Stage& last = st.stages.back();
    const double lost = h0 - height_of(last, k) * 1000, left = o.calibrate_loss_mm - lost;
    double span = span_for_loss(last, k, length, left);
    // Worn for all the hours at once, a bar whose top outwears the shell
    // may still be lowered slower than the rounding of its top and the
    // shell's fall take it apart: then on at the rate at which the stage's
    // wear takes the first part of the rest off.
    int parts = 1;
    for (int n = 2; n <= 16 && !(span > 0); n *= 2) {
      const double first = span_for_loss(last, k, length, left / n);
      if (first > 0) span = first * n, parts = n;
    }
    if (!(span > 0))
      throw std::invalid_argument(fmt::format(
          "--calibrate-loss {:g}: the wear of stage {} does not lower the lifters (profile {}, {:.1f} mm high) by the "
          "rest of the loss before it wears them through (a shell that wears faster than their tops raises them), "
          "so no hours bring the loss measured; give --calibrate-rate, or check the case's wear coefficients",
          o.calibrate_loss_mm, last.index, k, height_of(last, k) * 1000));
    at = last.case_hours + span;
    how = parts == 1 ? "extrapolated at the last stage's wear (the study has not reached it yet)"
                     : fmt::format("extrapolated at the rate the last stage's wear takes the first 1/{} of the rest "
                                   "off (the study has not reached it yet)",
                                   parts);
  }
  st.factor = at / o.calibrate_hours;
  st.calibration = fmt::format("the lifters lost {:g} mm of height in {:g} h ({})", o.calibrate_loss_mm,
                               o.calibrate_hours, how);
}

fs::path stage_dir(const fs::path& out, int i) { return out / fmt::format("stage-{:02d}", i); }

// The stage's case: the study's case with the stage's liner. A worn mill
// turns at the new one's rpm (a fixed-speed drive) and holds the same charge
// (the filling of its larger free volume).
MillCase stage_case(const Prepared& base, const Stage& s, const fs::path& out,
                    const std::vector<std::vector<Triangle>>* worn = nullptr) {
  MillCase c = base.c;
  if (s.index == 0) return c;
  c.diameter = s.diameter;
  life::put_stage_meshes(c, out, s, worn);
  for (std::size_t k = 0; k < s.outlines.size(); ++k) {
    LifterProfile p;
    p.points = s.outlines[k];
    c.lifter_pattern[k] = p;
  }
  if (!s.plate_depth_m[0].empty()) c.plate_depth = s.plate_depth_m;
  c.speed_rpm = base.d.speed_rpm;
  c.speed_fraction = 0;
  c.filling = s.filling;
  return c;
}

void save(const fs::path& out, const json& request, const Study& st, const std::string& stopped) {
  life::Calibration cal;
  cal.factor = st.factor;
  cal.how = st.calibration;
  cal.basis = st.basis();
  cal.case_wear_coefficient = st.wear_coefficient;
  cal.mix = st.mix;
  life::save_life_state(out, request, st.stages, cal, stopped);
}

void write_table(const fs::path& out, const Study& st, double length) {
  std::string t =
      "stage,hours,case_hours,profile,height_mm,top_width_mm,leading_angle_deg,trailing_angle_deg,area_mm2,"
      "worn_area_mm2,shell_wear_mm,diameter_m,power_W,power_sem_W,toe_deg,shoulder_deg,impact_point_deg,"
      "bare_liner_impact_share,shell_lifters_wear_kg_per_h,shell_lifters_g_per_kWh,top_wear_mm_per_1000h,stage_hours,"
      "booked_mm2,removed_mm2,wear_basis,impact_wear_share,height_mm_se,leading_angle_deg_se,"
      "trailing_angle_deg_se\n";
  std::vector<double> worn(st.stages.front().outlines.size(), 0.0);
  const std::vector<life::StageSe> errors = life::cumulative_se(st.stages);
  auto se = [](double v) { return std::isfinite(v) ? fmt::format("{:.4f}", v) : std::string(); };
  for (const Stage& s : st.stages) {
    if (!s.ran) break;
    for (std::size_t k = 0; k < s.outlines.size(); ++k) {
      const ProfileMeasures m = measure_profile(s.outlines[k]);
      const double top =  // mm per hour
          top_wear_m_per_h(s.outlines[k], 0.5 * s.diameter, BarWearRates{s.r.station_m3_s[k], bar_length(s, length)}) * 1000;
      const bool carried = s.span_case_hours > 0;
      t += fmt::format(
          "{},{:.6g},{:.6g},{},{:.4f},{:.4f},{:.3f},{:.3f},{:.4f},{:.4f},{:.4f},{:.6f},{:.6g},{:.4g},{:.3f},{:.3f},{:.3f},"
          "{:.4f},{:.6g},{:.6g},{:.6g},{},{},{},{},{:.4f},{},{},{}\n",
          s.index, s.case_hours / st.factor, s.case_hours, k, m.height * 1000, m.top_width * 1000, m.leading_angle_deg,
          m.trailing_angle_deg, m.area * 1e6, worn[k], s.shell_wear_m * 1000, s.diameter, s.r.power_W, s.r.power_sem_W,
          s.r.toe_deg, s.r.shoulder_deg, s.r.impact_deg, s.r.bare_share, s.r.liner_kg_h * st.factor,
          grams_per_kWh(s.r.liner_kg_h, s.r.power_W) * st.factor, top * 1000 * st.factor, carried ? fmt::format("{:.6g}", s.span_case_hours / st.factor) : "",
          carried ? fmt::format("{:.6g}", s.booked_mm2[k]) : "", carried ? fmt::format("{:.6g}", s.removed_mm2[k]) : "", st.basis(),
          impact_share_of(st, s.r), se(errors[s.index].height_mm[k]), se(errors[s.index].leading_deg[k]),
          se(errors[s.index].trailing_deg[k]));
      if (carried) worn[k] += s.removed_mm2[k];
    }
    // A liner whose bars are meshes (life_meshes.csv follows them): the
    // stage's row without a profile.
    if (s.outlines.empty())
      t += fmt::format("{},{:.6g},{:.6g},,,,,,,,{:.4f},{:.6f},{:.6g},{:.4g},{:.3f},{:.3f},{:.3f},{:.4f},{:.6g},{:.6g},,{},,,{},{:.4f},,,\n",
                       s.index, s.case_hours / st.factor, s.case_hours, s.shell_wear_m * 1000, s.diameter, s.r.power_W,
                       s.r.power_sem_W, s.r.toe_deg, s.r.shoulder_deg, s.r.impact_deg, s.r.bare_share,
                       s.r.liner_kg_h * st.factor, grams_per_kWh(s.r.liner_kg_h, s.r.power_W) * st.factor,
                       s.span_case_hours > 0 ? fmt::format("{:.6g}", s.span_case_hours / st.factor) : "", st.basis(),
                       impact_share_of(st, s.r));
  }
  io::write_file_atomic(out / "life.csv", t);
  // The worn liner of each stage in ParaView, on the study's hours.
  std::string pvd = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (const Stage& s : st.stages)
    if (s.ran)
      pvd += fmt::format("    <DataSet timestep=\"{:.6g}\" part=\"0\" file=\"stage-{:02d}/liner.vtp\"/>\n",
                         s.case_hours / st.factor, s.index);
  pvd += "  </Collection>\n</VTKFile>\n";
  io::write_file_atomic(out / "life.pvd", pvd);
}

// The new liner's consumption, and what the study's hours stand on.
void print_new_liner(const Study& st) {
  const Stage& s0 = st.stages.front();
  const double g = grams_per_kWh(s0.r.liner_kg_h, s0.r.power_W);
  std::printf("life            new liner: shell and lifters %.4g g/kWh (%.4g kg/h of %.4g W) at wear coefficients "
              "%.4g m3/(N m) sliding and %.4g m3/J impact (%.1f %% of it by impact)%s\n",
              g, s0.r.liner_kg_h, s0.r.power_W, st.wear_coefficient * st.mix.sliding, st.mix.impact,
              100 * impact_share_of(st, s0.r),
              st.relative() ? (std::string("; hours and wear rates ") + kWearRelative).c_str() : "");
}

// How the hours were set, when the study ends.
void print_calibration(const Study& st) {
  if (st.calibrated)
    std::printf("life            calibrated on %s: the case's hours / %.6g; the wear coefficients that give these "
                "hours, %.4g m3/(N m) sliding and %.4g m3/J impact, would make them the case's own\n",
                st.calibration.c_str(), st.factor, st.wear_coefficient * st.mix.sliding * st.factor,
                st.mix.impact * st.factor);
  else if (st.relative())
    std::printf("life            hours and wear rates are %s: give --calibrate-consumption G_PER_KWH (or "
                "--calibrate-rate, --calibrate-loss) to make them operating hours\n",
                kWearRelative);
}

// The options' ranges are checked as they are parsed (main.cpp); here, how
// they go together.
void check_options(const LifeOptions& o) {
  if (o.stages < 1) throw std::invalid_argument("--stages N: how many worn stages follow the new liner (1 to 100)");
  const bool by_hours = o.hours > 0, by_height = o.until_height_mm > 0;
  if (by_hours == by_height)
    throw std::invalid_argument("give one of --hours H (operating hours the study covers) and --until-height MM");
  const bool loss = o.calibrate_loss_mm > 0 || o.calibrate_hours > 0, rate = o.calibrate_rate_kg_h > 0;
  const bool use = o.calibrate_consumption_g_kWh > 0;
  if (use && (rate || loss))
    throw std::invalid_argument(std::string("--calibrate-consumption and ") +
                                (rate ? "--calibrate-rate" : "--calibrate-loss") +
                                ": give one measured figure (each alone sets the hours)");
  if (loss && rate) throw std::invalid_argument("--calibrate-rate and --calibrate-loss: give one measured figure");
  if (loss && !(o.calibrate_loss_mm > 0 && o.calibrate_hours > 0))
    throw std::invalid_argument("--calibrate-loss MM goes with --calibrate-hours H (the lifters lost MM in H hours)");
}

}  // namespace

namespace {

// What stands on the end plates and so holds them as they are ("" when
// nothing): end lifters, or a mesh (bars drawn to the ends) with a vertex
// on an end plane. A plate worn under them would open a gap below them.
std::string plates_held_by(const Prepared& base) {
  const MillCase& c = base.c;
  if (c.ends.lifter_rows > 0) return "end_lifters stand on them";
  const Walls& w = base.scene.walls;
  const double tol = 1e-6 * std::max(w.length, 1e-3);
  for (std::size_t k = 0; k < w.meshes.size(); ++k)
    for (const Triangle& t : w.meshes[k].triangles)
      for (const Vec3& v : t.v)
        if (std::fabs(v.z) < tol || std::fabs(v.z - w.length) < tol)
          return (k < c.meshes.size() ? fmt::format("walls.mesh[{}]", k) : w.meshes[k].name) + " stands on them";
  return "";
}

}  // namespace

void check_life(const LifeOptions& o, const Prepared& base) {
  check_options(o);
  const MillCase& c = base.c;
  const std::vector<int> worn = life::worn_meshes(c);
  // The bars of [lifters] (none where rows = 0: a mesh liner's bars are its own).
  const std::size_t profiles = c.lifter_rows > 0 ? c.lifter_pattern.size() : 0;
  if (profiles == 0 && worn.empty())
    throw std::invalid_argument("lifters.rows = 0: a life study wears lifter bars, of [lifters] or of a [[walls.mesh]] "
                                "of part \"lifters\" or \"shell\" that turns with the mill; this mill has neither");
  if (profiles == 0 && (o.until_height_mm > 0 || o.calibrate_loss_mm > 0))
    throw std::invalid_argument(std::string(o.until_height_mm > 0 ? "--until-height" : "--calibrate-loss") +
                                ": lifters.rows = 0: the lifters' height is followed on the bars of [lifters], and "
                                "this mill's bars are a mesh; give --hours, and calibrate by --calibrate-consumption "
                                "or --calibrate-rate");
  if (!worn.empty() && c.periodic)
    throw std::invalid_argument(fmt::format(
        "mill.ends = \"periodic\": walls.mesh[{}] would wear unevenly along the slice, and a worn triangle that "
        "leans along the axis breaks the slice's repeat (its seams); wear the mesh in a whole mill (mill.ends = "
        "\"plates\"), or give the bars as [lifters] in the slice",
        worn.front()));
  if (o.axial_segments > 0 && !(c.length / o.axial_segments >= base.d.largest_ball_diameter))
    throw std::invalid_argument(fmt::format("--axial-segments {}: segments of {:.4g} m, shorter than the largest ball "
                                            "({:.4g} m); give at most {}",
                                            o.axial_segments, c.length / o.axial_segments,
                                            base.d.largest_ball_diameter,
                                            static_cast<int>(std::floor(c.length / base.d.largest_ball_diameter))));
  life::check_worn_meshes(c, worn, o.axial_segments);
  if (base.scene.walls.has_end_plates() && !o.hold_plates && plates_held_by(base).empty() &&
      c.liner_grid.plate_rings > kMaxWornPlateRings)
    throw std::invalid_argument(fmt::format("liner.plate_rings = {}: a life study wears each end plate ring by ring, "
                                            "at most {} rings; give fewer, or --hold-plates",
                                            c.liner_grid.plate_rings, kMaxWornPlateRings));
  if (!worn.empty() && o.shell_wear_ratio != 1)
    throw std::invalid_argument(fmt::format("--shell-wear-ratio {:g}: walls.mesh[{}] is worn as a liner of its own; "
                                            "the ratio sets the shell plates' wear against the bars' of [lifters] only",
                                            o.shell_wear_ratio, worn.front()));
  for (std::size_t k = 0; k < c.sizes.size() && o.impact_share > 0; ++k)
    if (!c.sizes[k].shape.empty())
      throw std::invalid_argument(fmt::format(
          "--impact-share {:g}: charge.size[{}] is a class of clumps, whose components' strikes are booked with "
          "their bodies' whole mass: impact wear would be overcounted",
          o.impact_share, k));
  if (o.calibrate_rate_kg_h > 0 && c.periodic)
    throw std::invalid_argument(fmt::format(
        "--calibrate-rate {:g}: mill.ends = \"periodic\": the case is a {:g} m slice of a longer mill, and a whole "
        "mill's kg/h (its ends and its full length) cannot be set against a slice's; calibrate a slice by its "
        "consumption, --calibrate-consumption G_PER_KWH, or by the height its lifters lost, --calibrate-loss MM "
        "--calibrate-hours H",
        o.calibrate_rate_kg_h, c.length));
  if (!(base.scene.wall_material.wear_coefficient > 0) && !(base.scene.wall_material.impact_wear_coefficient > 0))
    throw std::invalid_argument("materials." + c.liner + ".wear_coefficient is 0: a life study needs the liner's "
                                "wear coefficient > 0, or its impact_wear_coefficient (their size sets only the hours; "
                                "--calibrate-consumption, --calibrate-loss or --calibrate-rate fix those)");
  const double h_new = [&] {
    double h = 0;
    for (std::size_t k = 0; k < profiles; ++k)
      h = std::max(h, measure_profile(profile_outline(c.lifter_pattern[k])).height);
    return h;
  }();
  if (o.until_height_mm > 0 && !(o.until_height_mm < h_new * 1000))
    throw std::invalid_argument(fmt::format("--until-height {:g}: the new lifters are {:.4g} mm high; give less",
                                            o.until_height_mm, h_new * 1000));
  if (o.calibrate_loss_mm > 0 && !(o.calibrate_loss_mm < h_new * 1000))
    throw std::invalid_argument(fmt::format("--calibrate-loss {:g}: more than the new lifters' height, {:.4g} mm",
                                            o.calibrate_loss_mm, h_new * 1000));
}

namespace {

// The mesh smoothing as resolved for the case (life/mesh_wear.h smooth_wear).
life::MeshSmoothing smoothing_of(const LifeOptions& o, const Prepared& base) {
  life::MeshSmoothing smoothing;
  smoothing.across_m = o.mesh_smoothing_mm > 0 ? o.mesh_smoothing_mm * 1e-3 : 0.5 * base.d.largest_ball_diameter;
  smoothing.along_m = o.mesh_smoothing_along_mm > 0 ? o.mesh_smoothing_along_mm * 1e-3 : 4 * smoothing.across_m;
  return smoothing;
}

// A twin of more triangles than this is refused before it is built.
constexpr double kMaxTwinTriangles = 2e7;

// What a study whose bars of [lifters] wear as their mesh twin cannot do,
// refused before the twin is made (the messages name the bars the user gave).
void check_twin(const LifeOptions& o, const Prepared& base) {
  const MillCase& c = base.c;
  if (o.lifter_mesh_mm > 0 && !(o.axial_segments > 0 && c.lifter_rows > 0))
    throw std::invalid_argument(
        "--lifter-mesh: only with --axial-segments on a mill of [lifters] bars (whose twin it cuts); "
        "a mesh liner's triangles are its own");
  if (!(o.axial_segments > 0 && c.lifter_rows > 0)) return;
  const std::string why = fmt::format("--axial-segments {}: the bars of [lifters] then wear as a mesh (their twin, "
                                      "triangle by triangle)", o.axial_segments);
  if (c.periodic)
    throw std::invalid_argument(why + ", and mill.ends = \"periodic\" makes a slice that repeats along the mill: "
                                      "its ends cannot wear otherwise than its middle; give the whole mill "
                                      "(mill.ends = \"plates\")");
  if (o.until_height_mm > 0 || o.calibrate_loss_mm > 0)
    throw std::invalid_argument(std::string(o.until_height_mm > 0 ? "--until-height" : "--calibrate-loss") + ": " +
                                why + ", whose height the study does not follow; give --hours, and calibrate by "
                                "--calibrate-consumption or --calibrate-rate (or take the wear coefficient a study "
                                "without segments calibrated on the height: its life.json)");
  if (c.ends.cones() || !c.plate_depth[0].empty() || !c.plate_depth[1].empty())
    throw std::invalid_argument(
        why + ", cut at the end planes; " +
        (c.ends.cones() ? std::string("this mill's ends are cones (mill.ends = \"cones\"), not planes")
                        : std::string("this mill's end plates are worn ([liner] plate_depth_mm), and its bars reach "
                                      "into their dish")) +
        "; give the bars as a mesh of your own ([[walls.mesh]], docs/liner-life-mesh.md)");
  if (o.lifter_mesh_mm * 1e-3 > c.length / o.axial_segments * (1 + 1e-9))
    throw std::invalid_argument(fmt::format(
        "--lifter-mesh {:g}: triangles up to {:g} mm along the mill, longer than a segment ({:.4g} mm of "
        "--axial-segments {}), so their wear cannot be told to one; give at most {:.4g}",
        o.lifter_mesh_mm, o.lifter_mesh_mm, c.length / o.axial_segments * 1e3, o.axial_segments,
        c.length / o.axial_segments * 1e3));
  if (o.shell_wear_ratio != 1)
    throw std::invalid_argument(fmt::format("--shell-wear-ratio {:g}: ", o.shell_wear_ratio) + why +
                                " of the liner's steel, and the ratio sets the shell's wear against bars of "
                                "[lifters] only");
}

}  // namespace

Prepared life_base(const LifeOptions& o, const Prepared& given, const fs::path& out, double* twin_edge_m) {
  check_twin(o, given);
  *twin_edge_m = 0;
  if (!(o.axial_segments > 0 && given.c.lifter_rows > 0)) return given;
  const double edge = o.lifter_mesh_mm > 0 ? o.lifter_mesh_mm * 1e-3
                                           : mc::life::default_twin_edge(given.d.largest_ball_diameter,
                                                                         given.c.length, o.axial_segments);
  // Refused before it is built: a mesh past what a device could hold.
  const double triangles = mc::life::twin_triangle_estimate(given.c, given.d, edge);
  if (triangles > kMaxTwinTriangles)
    throw std::invalid_argument(fmt::format(
        "--lifter-mesh {:.4g}{}: the bars' twin would have about {:.3g} triangles (at most {:.0e}); give a coarser "
        "mesh",
        edge * 1e3, o.lifter_mesh_mm > 0 ? "" : " (the default)", triangles, kMaxTwinTriangles));
  Prepared t = given;
  t.c = mc::life::with_bar_twin(given.c, mc::life::bar_twin_triangles(given.c, given.d, edge),
                                fs::absolute(out / "new-bars.stl").lexically_normal().string());
  t.d = derive(t.c);
  t.scene = build_scene(t.c, t.d);
  *twin_edge_m = edge;
  return t;
}


json life_request(const LifeOptions& o, const Prepared& base, double twin_edge_m) {
  json request = request_with_consumption(o, base);
  if (twin_edge_m > 0) request["bars_as_mesh_mm"] = twin_edge_m * 1e3;
  const life::MeshSmoothing smoothing = smoothing_of(o, base);
  if (!life::worn_meshes(base.c).empty())  // as resolved: a study resumes with the smoothing it began with
    request["mesh_smoothing_mm"] = smoothing.across_m * 1e3, request["mesh_smoothing_along_mm"] = smoothing.along_m * 1e3;
  if (base.scene.walls.has_end_plates())
    request["end_plates"] = o.hold_plates || !plates_held_by(base).empty() ? "held" : "worn";
  return request;
}

int cmd_life(const LifeOptions& o) {
  const Prepared given = prepare(o.c);
  const fs::path out = o.out.empty() ? fs::path("runs") / (given.c.name + "-life") : fs::path(o.out);
  // With --axial-segments, bars of [lifters] wear as their mesh twin.
  double twin_edge_m = 0;
  const Prepared base = life_base(o, given, out, &twin_edge_m);
  const bool twin = twin_edge_m > 0;
  check_life(o, base);
  const MillCase& c = base.c;
  const std::vector<int> worn = life::worn_meshes(c);
  const std::size_t profiles = c.lifter_rows > 0 ? c.lifter_pattern.size() : 0;
  const double shell_covered = life::shell_share_covered(c, worn);
  // How far a mesh liner's booked wear is spread (life/mesh_wear.h smooth_wear).
  const life::MeshSmoothing smoothing = smoothing_of(o, base);
  json request = life_request(o, base, twin_edge_m);
  // Whether the end plates wear, and their rings and sectors as the books cut them.
  bool plates = request.value("end_plates", "") == "worn";
  std::error_code ec;
  if (!o.force && fs::exists(out / "life.json", ec)) {
    // A study begun before the plates wore holds them to its end; a study
    // of other options is refused before its state is read for these.
    json there;
    try {
      there = io::read_json_file(out / "life.json", "");
    } catch (const std::exception&) {
    }  // read_life_state names what is wrong with it
    if (there.is_object() && there.contains("request") && there["request"].is_object()) {
      if (life::begun_before_plates(there["request"], request)) plates = false;
      const std::string differs = life::request_difference(there["request"], request);
      if (!differs.empty())
        throw std::invalid_argument("--out " + out.string() + " holds a life study of another case or options (" +
                                    (out / "life.json").string() + ": " + differs +
                                    "); give the same to resume it, or --force to start again");
    }
  }
  if (const std::string by = plates_held_by(base); !by.empty() && base.scene.walls.has_end_plates() && !o.quiet)
    std::printf("life            the end plates stay as they are: %s\n", by.c_str());
  const LinerLayout plate_layout = liner_layout(base.scene);
  const int plate_rings = plates ? plate_layout.plate_rings : 0, plate_sectors = plates ? plate_layout.plate_sectors : 0;
  std::array<std::vector<double>, 2> plate_start;  // from the case's own plates, worn or new
  if (plates)
    for (int p = 0; p < 2; ++p)
      plate_start[p] = c.plate_depth[p].empty() ? std::vector<double>(plate_rings, 0.0) : c.plate_depth[p];
  Study st;
  st.wear_coefficient = base.scene.wall_material.wear_coefficient;
  st.impact_coefficient = base.scene.wall_material.impact_wear_coefficient;
  st.density = base.scene.wall_material.density;
  st.mix.impact = st.impact_coefficient;
  for (std::size_t k = 0; k < profiles; ++k)
    if (measure_profile(profile_outline(c.lifter_pattern[k])).height >
        measure_profile(profile_outline(c.lifter_pattern[st.tallest])).height)
      st.tallest = static_cast<int>(k);
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw std::invalid_argument("--out " + out.string() + ": exists and is not a folder");
  if (fs::exists(out / "life.json", ec) && !o.force) {
    // The whole state is read and checked before anything is written: a
    // damaged one is refused and the study left as it is.
    // (its request was compared with this one's above)
    life::LifeState state = life::read_life_state(
        out / "life.json", {profiles, base.d.largest_ball_diameter, worn, plate_rings, plate_sectors, plate_start});
    st.stages = std::move(state.stages);
    std::printf("life            resuming %s at stage %d\n", out.string().c_str(), st.stages.back().index);
  } else {
    // Empty, or a sweep's case folder before its study began (its log).
    if (fs::exists(out, ec) && !file_not_of_a_sweep(out).empty())
      throw std::invalid_argument("--out " + out.string() + ": exists and holds no life study; choose another folder");
    if (o.force) {
      for (int i = 0; fs::exists(stage_dir(out, i), ec); ++i) fs::remove_all(stage_dir(out, i), ec);
      for (const char* f : {"life.json", "life.csv", "life.png", "life.pvd", "life_meshes.csv", "life_segments.csv", "life_plates.csv",
                            "life_plates.png", "new-bars.stl"})
        fs::remove(out / f, ec);
      fs::remove_all(out / "cases", ec);
    }
    Stage s0;
    s0.diameter = c.diameter;
    s0.filling = c.filling;
    for (std::size_t k = 0; k < profiles; ++k) s0.outlines.push_back(profile_outline(c.lifter_pattern[k]));
    for (int k : worn) {
      life::StageMesh m;
      m.walls_mesh = k;
      s0.meshes.push_back(m);
    }
    if (plates) s0.plate_depth_m = plate_start;
    st.stages.push_back(s0);
    // The state before the first run, so that a study killed in stage 0
    // resumes.
    fs::create_directories(out, ec);
    if (ec) throw std::runtime_error("cannot create " + out.string() + ": " + ec.message());
    save(out, request, st, "");
  }
  fs::create_directories(out / "cases", ec);
  if (ec) throw std::runtime_error("cannot create " + (out / "cases").string() + ": " + ec.message());
  if (twin) {  // the same bytes on a resume
    io::write_file_atomic(out / "new-bars.stl", io::stl_binary(c.meshes.back().triangles, c.name + " lifters, m"));
    if (!o.quiet)
      std::printf("life            the %d bars of [lifters] as a mesh of %s triangles at most %.4g mm across: %s\n",
                  given.c.lifter_rows, thousands(static_cast<long>(c.meshes.back().triangles.size())).c_str(),
                  twin_edge_m * 1e3, (out / "new-bars.stl").string().c_str());
  }
  const double length = c.length;
  // The bars' length before the study wears the plates: the mill's, and
  // where the case's plates are worn and held, their dish at the shell
  // (a stage that wears them adds its own: life_plates.h bar_length).
  const double bars_length =
      length + (!plates && base.scene.walls.has_end_plates() ? plate_depth_at_shell(base.scene.walls.plate_depth) : 0.0);
  const double V0 = base.d.mill_volume;

  for (;;) {
    Stage& s = st.stages.back();
    const fs::path dir = stage_dir(out, s.index);
    if (!s.ran) {
      // The stage's case file and its run (resumed from its checkpoint
      // after a kill).
      const fs::path case_file = out / "cases" / fmt::format("stage-{:02d}.toml", s.index);
      if (!fs::exists(dir / "summary.json", ec)) {
        RunOptions ro;
        ro.c.device = o.c.device;
        ro.quiet = o.quiet;
        if (fs::exists(dir / "checkpoint.bin", ec) && fs::exists(dir / "case.toml", ec)) {
          ro.resume = dir.string();
        } else {
          io::write_file_atomic(case_file, io::case_to_toml(stage_case(base, s, out)));
          ro.c.case_path = case_file.string();
          ro.out = dir.string();
          ro.force = true;
        }
        std::printf("life            stage %d: %s\n", s.index, dir.string().c_str());
        std::fflush(stdout);
        if (const int rc = cmd_run(ro); rc != 0) return rc;
      }
      s.r = life::read_stage_result(dir, static_cast<int>(profiles), worn, st.density, plate_rings, plate_sectors);
      // The shell's depth over the area the mesh bars leave bare.
      if (shell_covered > 0) life::scale_shell_rates(s.r, 1 / (1 - shell_covered));
      s.ran = true;
    }
    mix_stages(st, o);
    calibrate(st, o, bars_length);
    save(out, request, st, "");
    write_table(out, st, bars_length);
    if (!worn.empty())
      life::write_mesh_table(out, c, st.stages, {st.factor, st.basis(), st.mix, st.density, smoothing});
    if (o.axial_segments > 0)
      life::write_segment_table(out, c, st.stages, {st.factor, st.basis(), st.mix, st.density, smoothing},
                                o.axial_segments);
    const life::PlateTableBasis plate_basis{st.factor, st.mix, length, st.basis()};
    if (plates) {
      life::write_plate_table(out, st.stages, plate_basis);
      io::draw_or_warn(out / "life_plates.png", [&] {
        life::write_plate_picture(out / "life_plates.png", c.name, st.stages, plate_basis, st.relative());
      });
    }
    if (s.index == 0 && !o.quiet) print_new_liner(st);
    io::draw_or_warn(out / "life.png", [&] {
      // The panels along the mill apart: a fault in them costs only them.
      std::vector<io::LinePlot> along;
      if (o.axial_segments > 0) {
        try {
          along = life::along_plots(c.name, out, st.relative());
        } catch (const std::exception& e) {
          std::fprintf(stderr, "warning: life.png drawn without its panels along the mill: %s\n", e.what());
        }
      }
      life::write_life_picture(out / "life.png", c.name,
                               profiles == 0 && !worn.empty() ? life::stages_drawn(out, c, st.stages) : st.stages,
                               {st.factor, st.relative(), bars_length}, along);
    });

    // Stop, or plan the next stage's wear (in hours at the case's wear
    // coefficient: the shapes depend on those alone).
    const int i = s.index;
    const double hours_now = s.case_hours / st.factor;
    const double h_now = s.outlines.empty() ? 0.0 : height_of(s, st.tallest) * 1000;
    std::string stopped;
    double span = 0;
    if (o.hours > 0) {
      // Equal stages of the calibrated hours. A calibration on a measured
      // loss moves the hours axis as the study goes (it is extrapolated
      // until the study has worn that far): then stages are added, up to
      // three times those asked, until the hours are covered.
      const double step = o.hours / o.stages, left = o.hours - hours_now;
      const std::string hours_words = life::hours_label(st.relative());
      if (left <= 0.05 * step)
        stopped = left > 1e-6 * o.hours
                      ? fmt::format("{:g} {} reached (the last stage at {:.0f}, within 5 % of a stage of them)",
                                    o.hours, hours_words, hours_now)
                      : fmt::format("{:g} {} reached", o.hours, hours_words);
      else if (i >= 3 * o.stages)
        stopped = fmt::format("{} stages run; they cover {:.0f} of the {:g} {} asked", i, hours_now, o.hours, hours_words);
      else span = std::min(step, left) * st.factor;
    } else {
      // Each stage takes an equal share of the height left: the hours in
      // which this stage's wear lowers the bar by it.
      if (h_now <= o.until_height_mm + 0.05) stopped = fmt::format("the lifters are down to {:.1f} mm", h_now);
      else if (i >= 3 * o.stages) stopped = fmt::format("{} stages run; the lifters are still {:.1f} mm high", i, h_now);
      else span = span_for_loss(s, st.tallest, bars_length, (h_now - o.until_height_mm) / std::max(1, o.stages - i));
      if (stopped.empty() && !(span > 0))
        throw std::invalid_argument(fmt::format(
            "--until-height {:g}: the wear of stage {} ({}) does not lower the lifters (profile {}, {:.1f} mm high) by "
            "this stage's share before it wears them through (a shell that wears faster than their tops raises them); "
            "give --hours",
            o.until_height_mm, i, dir.string(), st.tallest, h_now));
    }
    if (!stopped.empty()) {
      save(out, request, st, stopped);
      print_calibration(st);
      std::printf("life            done: %s; %s/{life.csv, life.png, life.pvd}\n", stopped.c_str(), out.string().c_str());
      return 0;
    }

    // The wear of the stage's hours: the shell back by its mean depth, each
    // profile by its stations'.
    Stage next;
    next.index = i + 1;
    next.case_hours = s.case_hours + span;
    s.span_case_hours = span;
    s.shell_depth_m = s.r.shell_mm_per_1000h * 1e-6 * span;  // mm per 1000 h to m per h, times the hours
    const double R = 0.5 * s.diameter;
    s.booked_mm2.clear(), s.removed_mm2.clear(), s.scale.clear(), s.spread.clear();
    s.se_height_mm.clear(), s.se_leading_deg.clear(), s.se_trailing_deg.clear();
    std::vector<life::MixedWear> halves;
    for (const life::WearParts& h : s.r.halves) halves.push_back(life::mixed(h, st.mix, st.density));
    for (std::size_t k = 0; k < s.outlines.size(); ++k) {
      // As the plan wore it (span_for_loss): the same rates, the same hours.
      const WornLifter w =
          wear_for_hours(s.outlines[k], R, BarWearRates{s.r.station_m3_s[k], bar_length(s, bars_length), s.r.shell_mm_per_1000h * 1e-6}, span);
      if (w.worn_away) {
        const std::string why = fmt::format(
            "lifters.profile[{}]: stage {} wears the lifter away within its {:.4g} h (it is {:.1f} mm high now); the "
            "study stops at stage {} (life.csv holds stages 0 to {}); ask for less (--hours or --until-height)",
            k, i + 1, span / st.factor, measure_profile(s.outlines[k]).height * 1000, i, i);
        s.span_case_hours = 0;
        save(out, request, st, why);
        throw std::invalid_argument(why);
      }
      s.booked_mm2.push_back(w.booked_area * 1e6);
      s.removed_mm2.push_back(w.removed_area * 1e6);
      s.scale.push_back(w.scale);
      s.spread.push_back(w.spread);
      next.outlines.push_back(w.outline);
      if (halves.size() == 2) {  // the same hours at each half's rates
        ProfileMeasures m[2];
        for (int h = 0; h < 2; ++h) {
          const WornLifter wh = wear_for_hours(
              s.outlines[k], R, BarWearRates{halves[h].station_m3_s[k], bar_length(s, bars_length), halves[h].shell_mm_per_1000h * 1e-6},
              span);
          if (wh.worn_away) m[h].height = m[h].leading_angle_deg = m[h].trailing_angle_deg = NAN;
          else m[h] = measure_profile(wh.outline);
        }
        // (a half that wears the bar away has no shape to measure: NaN)
        s.se_height_mm.push_back(0.5 * std::fabs(m[0].height - m[1].height) * 1000);
        s.se_leading_deg.push_back(0.5 * std::fabs(m[0].leading_angle_deg - m[1].leading_angle_deg));
        s.se_trailing_deg.push_back(0.5 * std::fabs(m[0].trailing_angle_deg - m[1].trailing_angle_deg));
      }
    }
    // A step without a standard error for every profile has none.
    for (const auto* v : {&s.se_height_mm, &s.se_leading_deg, &s.se_trailing_deg})
      if (v->size() != s.outlines.size() || std::any_of(v->begin(), v->end(), [](double x) { return !std::isfinite(x); }))
        s.se_height_mm.clear(), s.se_leading_deg.clear(), s.se_trailing_deg.clear();
    next.diameter = s.diameter + 2 * s.shell_depth_m;
    next.shell_wear_m = s.shell_wear_m + s.shell_depth_m;
    // The mesh liners by their triangles' wear; then the same charge in
    // the larger free volume. Nothing of the next stage is written until
    // its case is known to be valid; a step that cannot be taken stops the
    // study by name, the stages run kept.
    std::vector<std::vector<Triangle>> worn_now;
    auto stop = [&](const std::string& why) {
      s.span_case_hours = 0;
      save(out, request, st, why);
      throw std::invalid_argument(why);
    };
    try {
      worn_now = life::wear_meshes(out, c, s, next, st.mix, span, 0.5 * next.diameter, smoothing,
                                     o.axial_segments);
    } catch (const std::invalid_argument& e) {
      stop(fmt::format("{}; the study stops at stage {} (life.csv holds stages 0 to {}); ask for shorter stages (more "
                       "--stages) or a wider --mesh-smoothing",
                       e.what(), i, i));
    }
    // The end plates by their rings' wear; a dish the kernels cannot take
    // stops the study.
    if (plates) {
      const mc::life::PlateStep ps =
          mc::life::wear_plates(s.plate_depth_m, mc::life::plate_rates(s.r.plates, st.mix.sliding, st.mix.impact, R),
                                span, R);
      const std::string why = check_plate_depths(ps.depth, plate_rings, 0.5 * next.diameter, length);
      if (!why.empty())
        stop(fmt::format("stage {}: the end plates worn that far are not a dish this model takes "
                         "(liner.plate_depth_mm{}); the study stops at stage {} (life.csv holds stages 0 to {})",
                         i + 1, why, i, i));
      next.plate_depth_m = ps.depth;
      s.plate_booked_m3 = ps.booked_m3;
      s.plate_removed_m3 = ps.removed_m3;
    }
    Stage probe = next;
    probe.filling = c.filling;
    try {
      const MillDerived nd = derive(stage_case(base, probe, out, &worn_now));
      next.filling = c.filling * V0 / nd.mill_volume;
    } catch (const std::invalid_argument& e) {
      stop(fmt::format("stage {}: the worn liner is not a valid case: {}; the study stops at stage {} (life.csv holds "
                       "stages 0 to {})",
                       i + 1, e.what(), i, i));
    }
    life::write_stage_meshes(out, next, worn_now);
    for (std::size_t k = 0; k < s.outlines.size(); ++k)
      std::printf("life            stage %d -> %d: profile %zu worn %.4g mm2 (booked %.4g mm2, depth scale %.3f, "
                  "smoothed %dx), shell %.3f mm\n",
                  i, i + 1, k, s.removed_mm2[k], s.booked_mm2[k], s.scale[k], s.spread[k], s.shell_depth_m * 1000);
    for (const life::StageMesh& m : s.meshes)
      std::printf("life            stage %d -> %d: walls.mesh[%d] worn %.4g cm3 (booked %.4g cm3%s, depth scale %.3f, "
                  "deepest %s%.3f mm, each bar%s within %.2f %% of its share after %d correction%s): %s\n",
                  i, i + 1, m.walls_mesh, m.removed_m3 * 1e6, m.booked_m3 * 1e6,
                  m.steps > 1 ? fmt::format(", moved in {} steps", m.steps).c_str() : "", m.scale,
                  m.steps > 1 ? "at most " : "", m.deepest_m * 1000,
                  o.axial_segments > 1 ? " in each segment" : "", m.local_misfit * 100, m.local_passes,
                  m.local_passes == 1 ? "" : "s", (out / next.meshes[&m - s.meshes.data()].file).string().c_str());
    if (plates)
      for (int p = 0; p < 2; ++p) {
        double booked = 0, removed = 0, deepest = 0;
        for (int j = 0; j < plate_rings; ++j)
          booked += s.plate_booked_m3[p][j], removed += s.plate_removed_m3[p][j],
              deepest = std::max(deepest, next.plate_depth_m[p][j]);
        std::printf("life            stage %d -> %d: end plate at z = %g m worn %.4g cm3 (booked %.4g cm3), its "
                    "deepest ring %.3f mm\n",
                    i, i + 1, p == 0 ? 0.0 : length, removed * 1e6, booked * 1e6, deepest * 1000);
      }
    st.stages.push_back(next);
    save(out, request, st, "");
  }
}

}  // namespace mc::app
