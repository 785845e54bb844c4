// A life study's state, written and read back strictly (life_state.h).
#include "app/life_state.h"

#include <fmt/format.h>

#include <algorithm>
#include <iterator>
#include <stdexcept>

#include "app/life_plates.h"
#include "app/prepare.h"
#include "core/lifters.h"
#include "io/atomic_file.h"
#include "io/csv_read.h"
#include "io/json_read.h"
#include "life/mesh_collapse.h"

namespace mc::app::life {

namespace fs = std::filesystem;
using nlohmann::json;
using io::JsonAt;

namespace {

json points_json(const std::vector<Vec2>& o) {
  json a = json::array();
  for (const Vec2& v : o) a.push_back({v.x, v.y});
  return a;
}

json parts_json(const WearParts& p) {
  return {{"liner_sliding_wear_kg_per_h", p.liner_sliding_kg_h},
          {"liner_strike_W", p.liner_strike_W},
          {"shell_sliding_wear_kg_per_h", p.shell_sliding_kg_h},
          {"shell_strike_W", p.shell_strike_W},
          {"shell_sliding_wear_mm_per_1000h", p.shell_sliding_mm_per_1000h},
          {"shell_strike_W_per_m2", p.shell_strike_W_m2},
          {"station_sliding_wear_m3_per_s", p.station_sliding_m3_s},
          {"station_strike_W", p.station_strike_W}};
}

json stage_json(const Stage& s) {
  json j;
  j["index"] = s.index;
  j["case_hours"] = s.case_hours;
  j["diameter_m"] = s.diameter;
  j["filling"] = s.filling;
  j["shell_wear_m"] = s.shell_wear_m;
  j["profiles"] = json::array();
  for (const auto& o : s.outlines) j["profiles"].push_back(points_json(o));
  j["ran"] = s.ran;
  if (s.ran) {
    const StageResult& r = s.r;
    j["result"] = {{"power_W", r.power_W},       {"power_sem_W", number_or_null(r.power_sem_W)},
                   {"toe_deg", number_or_null(r.toe_deg)}, {"shoulder_deg", number_or_null(r.shoulder_deg)},
                   {"impact_point_deg", number_or_null(r.impact_deg)},
                   {"bare_liner_impact_share", number_or_null(r.bare_share)},
                   {"liner_wear_kg_per_h", r.liner_kg_h}, {"shell_wear_mm_per_1000h", r.shell_mm_per_1000h},
                   {"station_wear_m3_per_s", r.station_m3_s}};
    j["result"].update(parts_json(r.parts));
    if (!r.halves.empty()) j["result"]["halves"] = {parts_json(r.halves[0]), parts_json(r.halves[1])};
    if (!s.meshes.empty())
      j["result"]["mesh_sliding_wear_m3_per_s"] = r.mesh_sliding_m3_s, j["result"]["mesh_strike_W"] = r.mesh_strike_W;
    if (!r.plates.empty()) j["result"].update(plate_books_json(r.plates));
  }
  if (!s.plate_depth_m[0].empty()) j["plate_depth_mm"] = plate_rows_json(s.plate_depth_m, 1e3);
  if (!s.meshes.empty()) {
    j["meshes"] = json::array();
    for (const StageMesh& m : s.meshes) {
      json x = {{"walls_mesh", m.walls_mesh}, {"file", m.file}};
      if (s.span_case_hours > 0)
        x["wear"] = {{"booked_m3", m.booked_m3}, {"removed_m3", m.removed_m3}, {"scale", m.scale},
                     {"deepest_m", m.deepest_m}, {"relaxed_vertices", m.relaxed}, {"collapsed_edges", m.collapsed}, {"collapse_share", m.collapse_share}, {"collapse_m3", m.collapse_m3}};
      if (s.span_case_hours > 0 && m.local_passes >= 0)
        x["wear"]["local_passes"] = m.local_passes, x["wear"]["local_misfit"] = m.local_misfit;
      if (s.span_case_hours > 0 && m.stretch_segments > 0) x["wear"]["stretch_segments"] = m.stretch_segments;
      if (s.span_case_hours > 0 && m.steps > 0)
        x["wear"]["steps"] = m.steps, x["wear"]["span_asked_m3"] = m.span_asked_m3,
        x["wear"]["span_removed_m3"] = m.span_removed_m3;
      j["meshes"].push_back(x);
    }
  }
  if (s.span_case_hours > 0)
    j["wear"] = {{"span_case_hours", s.span_case_hours}, {"shell_depth_m", s.shell_depth_m},
                 {"booked_mm2", s.booked_mm2}, {"removed_mm2", s.removed_mm2}, {"scale", s.scale},
                 {"spread", s.spread}};
  if (s.span_case_hours > 0 && !s.plate_booked_m3[0].empty())
    j["wear"]["plate_booked_m3"] = plate_rows_json(s.plate_booked_m3),
    j["wear"]["plate_removed_m3"] = plate_rows_json(s.plate_removed_m3);
  if (s.span_case_hours > 0 && !s.se_height_mm.empty())
    j["wear"]["step_se"] = {{"height_mm", s.se_height_mm},
                            {"leading_angle_deg", s.se_leading_deg},
                            {"trailing_angle_deg", s.se_trailing_deg}};
  return j;
}

// A bar's outline: points of two finite numbers, a valid profile by the
// case reader's check on the stage's shell.
std::vector<Vec2> outline_of(const JsonAt& a, double R, double room) {
  const std::size_t n = a.size();
  if (n == 0) a.fail("empty list");
  if (n > static_cast<std::size_t>(kLifterMaxPoints))
    a.fail(fmt::format("{} points: a profile has at most {}", n, kLifterMaxPoints));
  std::vector<Vec2> o;
  for (std::size_t k = 0; k < n; ++k) {
    const std::vector<double> xy = a[k].numbers(2, "coordinates (x, y in m)");
    o.push_back({xy[0], xy[1]});
  }
  const std::string fault = profile_outline_fault(o, R, room);
  if (!fault.empty()) a.fail(fault);
  return o;
}

WearParts parts_of(const JsonAt& r, std::size_t profiles) {
  WearParts x;
  r.object();
  x.liner_sliding_kg_h = r["liner_sliding_wear_kg_per_h"].number_at_least(0);
  x.liner_strike_W = r["liner_strike_W"].number_at_least(0);
  x.shell_sliding_kg_h = r["shell_sliding_wear_kg_per_h"].number_at_least(0);
  x.shell_strike_W = r["shell_strike_W"].number_at_least(0);
  x.shell_sliding_mm_per_1000h = r["shell_sliding_wear_mm_per_1000h"].number_at_least(0);
  x.shell_strike_W_m2 = r["shell_strike_W_per_m2"].number_at_least(0);
  for (const auto& [key, into] : {std::pair{"station_sliding_wear_m3_per_s", &x.station_sliding_m3_s},
                                  std::pair{"station_strike_W", &x.station_strike_W}}) {
    const JsonAt a = r[key];
    a.size(profiles, "profiles");
    for (std::size_t k = 0; k < profiles; ++k) {
      into->push_back(a[k].numbers(kWearStations, "wear stations"));
      for (int j = 0; j < kWearStations; ++j)
        if ((*into)[k][j] < 0) a[k][j].fail("below 0");
    }
  }
  return x;
}

StageResult result_of(const JsonAt& r, std::size_t profiles, std::size_t meshes) {
  StageResult x;
  r.object();
  if (meshes > 0) {
    x.mesh_sliding_m3_s = r["mesh_sliding_wear_m3_per_s"].numbers(meshes, "worn meshes");
    x.mesh_strike_W = r["mesh_strike_W"].numbers(meshes, "worn meshes");
    for (std::size_t k = 0; k < meshes; ++k) {
      if (x.mesh_sliding_m3_s[k] < 0) r["mesh_sliding_wear_m3_per_s"][k].fail("below 0");
      if (x.mesh_strike_W[k] < 0) r["mesh_strike_W"][k].fail("below 0");
    }
  }
  x.power_W = r["power_W"].number();
  x.power_sem_W = r["power_sem_W"].number_or_nan();
  x.toe_deg = r["toe_deg"].number_or_nan();
  x.shoulder_deg = r["shoulder_deg"].number_or_nan();
  x.impact_deg = r["impact_point_deg"].number_or_nan();
  x.bare_share = r["bare_liner_impact_share"].number_or_nan();
  x.liner_kg_h = r["liner_wear_kg_per_h"].number_at_least(0);
  x.shell_mm_per_1000h = r["shell_wear_mm_per_1000h"].number_at_least(0);
  const JsonAt st = r["station_wear_m3_per_s"];
  st.size(profiles, "profiles");
  for (std::size_t k = 0; k < profiles; ++k) {
    x.station_m3_s.push_back(st[k].numbers(kWearStations, "wear stations"));
    for (int j = 0; j < kWearStations; ++j)
      if (x.station_m3_s[k][j] < 0) st[k][j].fail("a wear rate below 0");
  }
  // The parts, where the study wrote them; a study begun before impact
  // wear holds sliding wear alone.
  if (!r.has("station_sliding_wear_m3_per_s")) {
    x.parts.liner_sliding_kg_h = x.liner_kg_h;
    x.parts.shell_sliding_mm_per_1000h = x.shell_mm_per_1000h;
    x.parts.station_sliding_m3_s = x.station_m3_s;
    x.parts.station_strike_W.assign(profiles, std::vector<double>(kWearStations, 0.0));
    return x;
  }
  x.parts = parts_of(r, profiles);
  if (r.has("halves")) {
    const JsonAt h = r["halves"];
    h.size(2, "halves of the averaging window");
    for (std::size_t k = 0; k < 2; ++k) x.halves.push_back(parts_of(h[k], profiles));
  }
  return x;
}

void wear_of(const JsonAt& w, std::size_t profiles, Stage& s) {
  w.object();
  s.span_case_hours = w["span_case_hours"].number();
  if (!(s.span_case_hours > 0)) w["span_case_hours"].fail("must be > 0");
  s.shell_depth_m = w["shell_depth_m"].number_at_least(0);
  s.booked_mm2 = w["booked_mm2"].numbers(profiles, "profiles");
  s.removed_mm2 = w["removed_mm2"].numbers(profiles, "profiles");
  s.scale = w["scale"].numbers(profiles, "profiles");
  const JsonAt sp = w["spread"];
  sp.size(profiles, "profiles");
  for (std::size_t k = 0; k < profiles; ++k) s.spread.push_back(static_cast<int>(sp[k].whole()));
  if (w.has("step_se")) {
    const JsonAt e = w["step_se"];
    for (const auto& [key, into] : {std::pair{"height_mm", &s.se_height_mm},
                                    std::pair{"leading_angle_deg", &s.se_leading_deg},
                                    std::pair{"trailing_angle_deg", &s.se_trailing_deg}}) {
      *into = e[key].numbers(profiles, "profiles");
      for (std::size_t k = 0; k < profiles; ++k)
        if ((*into)[k] < 0) e[key][k].fail("below 0");
    }
  }
}

Stage stage_of(const JsonAt& j, int i, const StateShape& shape, const Stage* before) {
  Stage s;
  j.object();
  const long index = j["index"].whole();
  if (index != i) j["index"].fail(fmt::format("{} where {} is due (the stages in order from 0)", index, i));
  s.index = i;
  s.case_hours = j["case_hours"].number_at_least(0);
  // The hours add up: a stage starts where the one before it and its wear end.
  const double due = before ? before->case_hours + before->span_case_hours : 0.0;
  if (std::fabs(s.case_hours - due) > 1e-9 * std::max(1.0, due))
    j["case_hours"].fail(fmt::format("{:.9g} where {:.9g} is due (the stage before and its wear's hours)", s.case_hours,
                                     due));
  s.diameter = j["diameter_m"].number();
  if (!(s.diameter > 0)) j["diameter_m"].fail("must be > 0");
  s.filling = j["filling"].number();
  if (!(s.filling > 0 && s.filling < 1)) j["filling"].fail("must be between 0 and 1");
  s.shell_wear_m = j["shell_wear_m"].number_at_least(0);
  const JsonAt profiles = j["profiles"];
  profiles.size(shape.profiles, "lifter profiles of the case");
  for (std::size_t k = 0; k < shape.profiles; ++k)
    s.outlines.push_back(outline_of(profiles[k], 0.5 * s.diameter, shape.largest_ball_m));
  s.ran = j["ran"].boolean();
  if (s.ran) s.r = result_of(j["result"], shape.profiles, shape.meshes.size());
  if (j.has("wear")) wear_of(j["wear"], shape.profiles, s);
  // The end plates, where the study wears them; none where it holds them.
  const int rings = shape.plate_rings;
  if (rings == 0) {
    const char* held = "this study holds its end plates (it began without worn plates)";
    if (j.has("plate_depth_mm")) j["plate_depth_mm"].fail(held);
    if (s.ran && j["result"].has("plate_strike_W")) j["result"]["plate_strike_W"].fail(held);
    if (j.has("wear") && j["wear"].has("plate_booked_m3")) j["wear"]["plate_booked_m3"].fail(held);
  }
  if (rings > 0) {
    s.plate_depth_m = plate_rows_of(j["plate_depth_mm"], rings, 1e-3);
    if (i == 0)  // the case's own plates, worn or new
      for (int p = 0; p < 2; ++p)
        for (int r = 0; r < rings; ++r)
          if (std::fabs(s.plate_depth_m[p][r] - shape.plate_start[p][r]) > 1e-9 * std::max(1e-3, shape.plate_start[p][r]))
            j["plate_depth_mm"][p][r].fail(fmt::format("{:.9g} mm where the case's plate is {:.9g} mm deep",
                                                       s.plate_depth_m[p][r] * 1e3, shape.plate_start[p][r] * 1e3));
    if (s.ran)
      s.r.plates = plate_books_of(j["result"]["plate_sliding_wear_m3_per_s"], j["result"]["plate_strike_W"], rings,
                                  shape.plate_sectors);
    if (j.has("wear")) {
      s.plate_booked_m3 = plate_rows_of(j["wear"]["plate_booked_m3"], rings);
      s.plate_removed_m3 = plate_rows_of(j["wear"]["plate_removed_m3"], rings);
    }
    // The depths add up: a stage starts where the one before it ended,
    // never shallower, its face having lost the step's removed volume.
    if (before) {
      if (before->plate_booked_m3[0].empty()) j["plate_depth_mm"].fail("the stage before has no step on the plates");
      for (int p = 0; p < 2; ++p) {
        const std::vector<double> removed =
            mc::life::plate_removed(before->plate_depth_m[p], s.plate_depth_m[p], 0.5 * before->diameter);
        for (int r = 0; r < rings; ++r) {
          if (s.plate_depth_m[p][r] < before->plate_depth_m[p][r])
            j["plate_depth_mm"][p][r].fail("shallower than the stage before's: a worn plate only deepens");
          const double had = before->plate_removed_m3[p][r];
          if (std::fabs(removed[r] - had) > 1e-6 * std::max(std::fabs(had), 1e-9))
            j["plate_depth_mm"][p][r].fail(fmt::format(
                "the face between it and the stage before's holds {:.9g} cm3 where the step removed {:.9g} cm3",
                removed[r] * 1e6, had * 1e6));
        }
      }
    }
  }
  if (!shape.meshes.empty() || j.has("meshes")) {
    const JsonAt m = j["meshes"];
    m.size(shape.meshes.size(), "worn meshes of the case ([[walls.mesh]] of part \"lifters\" or \"shell\" that turn)");
    for (std::size_t k = 0; k < shape.meshes.size(); ++k) {
      StageMesh x;
      x.walls_mesh = static_cast<int>(m[k]["walls_mesh"].whole());
      if (x.walls_mesh != shape.meshes[k])
        m[k]["walls_mesh"].fail(fmt::format("{} where the case's worn mesh is walls.mesh[{}]", x.walls_mesh, shape.meshes[k]));
      x.file = m[k]["file"].text();
      if (i == 0 && !x.file.empty()) m[k]["file"].fail("stage 0 runs on the case's own mesh (\"\")");
      if (i > 0 && x.file.empty()) m[k]["file"].fail("empty: a worn stage runs on the mesh its study wrote");
      if (m[k].has("wear")) {
        const JsonAt w = m[k]["wear"];
        x.booked_m3 = w["booked_m3"].number_at_least(0);
        x.removed_m3 = w["removed_m3"].number_at_least(0);
        x.scale = w["scale"].number_at_least(0);
        x.deepest_m = w["deepest_m"].number_at_least(0);
        // Not in a study's state written before meshes were relaxed.
        if (w.has("relaxed_vertices")) x.relaxed = static_cast<int>(w["relaxed_vertices"].number_at_least(0));
        if (w.has("collapsed_edges")) x.collapsed = static_cast<int>(w["collapsed_edges"].number_at_least(0));
        if (w.has("collapse_share")) x.collapse_share = w["collapse_share"].number_at_least(0);
        if (w.has("collapse_m3")) x.collapse_m3 = w["collapse_m3"].number();
        if (w.has("local_passes")) x.local_passes = static_cast<int>(w["local_passes"].number_at_least(0));
        if (w.has("local_misfit")) x.local_misfit = w["local_misfit"].number_at_least(0);
        if (w.has("stretch_segments")) {
          const long n = w["stretch_segments"].whole();
          if (n < 1 || n > 32) w["stretch_segments"].fail(fmt::format("{}: spans are 1 to 32", n));
          x.stretch_segments = static_cast<int>(n);
        }
        if (w.has("steps")) {
          const long steps = w["steps"].whole();
          if (std::find(std::begin(mc::life::kMoveSteps), std::end(mc::life::kMoveSteps), steps) ==
              std::end(mc::life::kMoveSteps))
            w["steps"].fail(fmt::format("{}: a move is made in 1, 2, 4 or 8 steps", steps));
          x.steps = static_cast<int>(steps);
          const std::size_t spans = static_cast<std::size_t>(std::max(x.stretch_segments, 1));
          x.span_asked_m3 = w["span_asked_m3"].numbers(spans, "stretch segments");
          x.span_removed_m3 = w["span_removed_m3"].numbers(spans, "stretch segments");
        }
      }
      s.meshes.push_back(x);
    }
  }
  return s;
}

}  // namespace

LifeState read_life_state(const fs::path& file, const StateShape& shape) {
  const json doc = io::read_json_file(file);
  const JsonAt top(doc, file.string());
  top.object();
  const std::string format = top["format"].text();
  if (format == "millcharge life 1")
    top["format"].fail("\"" + format + "\": a study started by a millcharge whose default wear coefficient was "
                       "1e-13 and whose life.csv named its kg/h otherwise; this one reads \"" + kFormat +
                       "\". Finish it with the millcharge that started it, or start it again here with --force (its "
                       "stages run again)");
  if (format != kFormat) top["format"].fail("\"" + format + "\", this millcharge reads \"" + kFormat + "\"");
  LifeState st;
  top["request"].object();
  st.request = doc.at("request");
  const JsonAt cal = top["calibration"];
  if (!(cal["factor"].number() > 0)) cal["factor"].fail("must be > 0");
  (void)cal["how"].text();
  const std::string basis = cal["hours_and_wear_rates"].text();
  if (basis != "calibrated" && basis != "relative" && basis != "case_coefficient")
    cal["hours_and_wear_rates"].fail("\"" + basis + "\", not one of \"calibrated\", \"relative\", \"case_coefficient\"");
  (void)cal["case_wear_coefficient_m3_per_N_m"].number_at_least(0);  // 0 where the case wears by impact alone
  // One of the two wears at least: the sliding coefficient 0 where impact
  // does all the wear.
  const double sliding = cal["wear_coefficient_m3_per_N_m"].number_at_least(0);
  const double impact =
      cal.has("impact_wear_coefficient_m3_per_J") ? cal["impact_wear_coefficient_m3_per_J"].number_at_least(0) : 0.0;
  if (!(sliding > 0) && !(impact > 0))
    cal["wear_coefficient_m3_per_N_m"].fail("must be > 0 where impact_wear_coefficient_m3_per_J is 0 or missing");
  const JsonAt stages = top["stages"];
  const std::size_t n = stages.size();
  if (n == 0) stages.fail("empty list: the study holds no stage");
  for (std::size_t i = 0; i < n; ++i) {
    // Named "FILE: stage i: key" rather than by the list's index.
    const JsonAt named = JsonAt(stages[i].value(), file.string()).part(fmt::format("stage {}", i));
    st.stages.push_back(stage_of(named, static_cast<int>(i), shape, i > 0 ? &st.stages[i - 1] : nullptr));
    const Stage& s = st.stages.back();
    const bool last = i + 1 == n;
    // What the study writes: every stage but the last has run and carried
    // its wear to the next; the last carries none.
    if (!last && !s.ran) named.fail(fmt::format("ran: false, yet stage {} follows", i + 1));
    if (!last && !(s.span_case_hours > 0)) named.fail(fmt::format("wear: missing, yet stage {} follows", i + 1));
    if (last && s.span_case_hours > 0)
      named.fail(fmt::format("wear: carried to a stage {} that the file lacks", i + 1));
  }
  if (top.has("stopped")) st.stopped = top["stopped"].text();
  return st;
}

std::string request_difference(const json& there, const json& asked) {
  if (there == asked) return "";
  std::vector<std::string> keys;
  for (const auto& [k, v] : asked.items()) keys.push_back(k);
  if (there.is_object())
    for (const auto& [k, v] : there.items())
      if (!asked.contains(k)) keys.push_back(k);
  for (const std::string& k : keys) {
    const json a = there.is_object() && there.contains(k) ? there.at(k) : json("(none)");
    const json b = asked.contains(k) ? asked.at(k) : json("(none)");
    if (a != b) return fmt::format("{}: {} there, {} asked", k, a.dump(), b.dump());
  }
  return "the request differs";
}

bool begun_before_plates(const json& there, json& asked) {
  if (!asked.contains("end_plates") || !there.is_object() || there.contains("end_plates")) return false;
  asked.erase("end_plates");
  return true;
}

void save_life_state(const fs::path& out, const json& request, const std::vector<Stage>& stages,
                     const Calibration& cal, const std::string& stopped) {
  json j;
  j["format"] = kFormat;
  j["request"] = request;
  j["calibration"] = {{"factor", cal.factor},
                      {"how", cal.how},
                      {"hours_and_wear_rates", cal.basis},
                      {"case_wear_coefficient_m3_per_N_m", cal.case_wear_coefficient},
                      {"wear_coefficient_m3_per_N_m", cal.case_wear_coefficient * cal.mix.sliding * cal.factor},
                      {"impact_wear_coefficient_m3_per_J", cal.mix.impact * cal.factor}};
  if (std::isfinite(cal.mix.share)) j["calibration"]["impact_share"] = cal.mix.share;
  j["stages"] = json::array();
  for (const Stage& s : stages) j["stages"].push_back(stage_json(s));
  if (!stopped.empty()) j["stopped"] = stopped;
  io::write_file_atomic(out / "life.json", j.dump(1) + "\n");
}

TriangleWear read_triangle_wear(const fs::path& wear_csv, int mesh, std::size_t triangles) {
  const io::CsvTable t = io::read_csv_strict(wear_csv, "the stage's run wrote no liner wear");
  const int c_part = t.column("part"), c_row = t.column("row"), c_bin = t.column("face_or_bin"),
            c_area = t.column("area_m2"), c_sl = t.column("sliding_wear_mm_per_1000h"), c_st = t.column("strike_W");
  TriangleWear w;
  w.sliding_m3_s.assign(triangles, NAN);
  w.strike_W.assign(triangles, NAN);
  std::size_t found = 0;
  for (std::size_t k = 0; k < t.rows.size(); ++k) {
    if (t.rows[k][c_part] != "mesh" || t.number(k, c_row) != mesh) continue;
    const double b = t.number(k, c_bin), area = t.number(k, c_area), sl = t.number(k, c_sl), st = t.number(k, c_st);
    if (!(b >= 0 && b < static_cast<double>(triangles) && b == std::floor(b)))
      throw std::invalid_argument(fmt::format("{}: triangle {} of mesh {} is not one of its {} triangles", t.where(k),
                                              t.rows[k][c_bin], mesh, triangles));
    const std::size_t i = static_cast<std::size_t>(b);
    if (!std::isnan(w.strike_W[i]))
      throw std::invalid_argument(fmt::format("{}: triangle {} of mesh {} booked twice", t.where(k), i, mesh));
    for (const auto& [v, col] : {std::pair{area, c_area}, std::pair{sl, c_sl}, std::pair{st, c_st}})
      if (!(std::isfinite(v) && v >= 0))
        throw std::invalid_argument(t.where(k) + ": " + t.header[col] + " " + t.rows[k][col] +
                                    " is not finite and >= 0; the file is damaged");
    w.sliding_m3_s[i] = sl * area / 3.6e9;  // mm per 1000 h over the area: m³/s
    w.strike_W[i] = st;
    ++found;
  }
  if (found != triangles)
    throw std::invalid_argument(fmt::format("{}: mesh {} has {} triangle rows where its mesh has {} triangles",
                                            wear_csv.string(), mesh, found, triangles));
  return w;
}

StageResult read_stage_result(const fs::path& dir, int profiles, const std::vector<int>& meshes, double density,
                              int plate_rings, int plate_sectors) {
  StageResult r;
  if (plate_rings > 0) r.plates = read_plate_books(dir / "wear.csv", plate_rings, plate_sectors);
  const fs::path sj = dir / "summary.json";
  const json doc = io::read_json_file(sj, "the stage's run wrote no summary");
  const JsonAt j(doc, sj.string());
  const std::string not_run = "; not a millcharge run's summary";
  try {
    r.power_W = j["power_W"]["torque"].number();
    r.power_sem_W = j["power_W"]["torque_sem"].number_or_nan();
    r.toe_deg = j["toe_deg"].number_or_nan();
    r.shoulder_deg = j["shoulder_deg"].number_or_nan();
    const JsonAt l = j["liner"];
    r.impact_deg = l["impact_point_deg"].number_or_nan();
    r.bare_share = l["bare_liner_impact_share"].number_or_nan();
    const JsonAt parts = l["parts"];
    for (std::size_t k = 0; k < parts.size(); ++k) {
      const JsonAt p = parts[k];
      const std::string name = p["part"].text();
      if (name != "shell" && name.rfind("lifter", 0) != 0) continue;
      // A run before impact wear has sliding wear alone.
      const bool split = p.has("sliding_wear_kg_per_h");
      const double kg_h = p["wear_kg_per_h"].number(), sliding = split ? p["sliding_wear_kg_per_h"].number() : kg_h;
      const double strike = split ? p["strike_power_W"].number() : 0.0;
      r.liner_kg_h += kg_h;
      r.parts.liner_sliding_kg_h += sliding;
      r.parts.liner_strike_W += strike;
      if (name == "shell") {
        r.parts.shell_sliding_kg_h = sliding;
        r.parts.shell_strike_W = strike;
        r.shell_mm_per_1000h = p["mean_wear_mm_per_1000h"].number();
        r.parts.shell_sliding_mm_per_1000h = kg_h > 0 ? r.shell_mm_per_1000h * sliding / kg_h : r.shell_mm_per_1000h;
        const double area = p["area_m2"].number();
        r.parts.shell_strike_W_m2 = area > 0 ? strike / area : 0.0;
      }
    }
    // The halves of the window, where the run has them.
    if (l.has("halves")) {
      const JsonAt h = l["halves"];
      h.size(2, "halves of the averaging window");
      r.halves.resize(2);
      for (std::size_t k = 0; k < 2; ++k) {
        WearParts& x = r.halves[k];
        x.liner_sliding_kg_h = h[k]["shell_lifters_sliding_wear_kg_per_h"].number_at_least(0);
        x.liner_strike_W = h[k]["shell_lifters_strike_W"].number_at_least(0);
        x.shell_sliding_kg_h = h[k]["shell_sliding_wear_kg_per_h"].number_at_least(0);
        x.shell_strike_W = h[k]["shell_strike_W"].number_at_least(0);
        x.shell_sliding_mm_per_1000h = h[k]["shell_sliding_wear_mm_per_1000h"].number_at_least(0);
        x.shell_strike_W_m2 = h[k]["shell_strike_W_per_m2"].number_at_least(0);
      }
    }
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(e.what() + not_run);
  }
  if (profiles == 0) r.halves.clear();  // a liner whose bars are meshes: no lifter stations
  const io::CsvTable t = profiles == 0 ? io::CsvTable{}
                                       : io::read_csv_strict(dir / "lifter_wear.csv", "the stage's run wrote no lifter wear");
  if (profiles > 0) {
  const int c_p = t.column("profile"), c_s = t.column("station"), c_w = t.column("wear_m3_per_s");
  const bool split = t.has("sliding_wear_m3_per_s");  // a run before impact wear has sliding wear alone
  const int c_sl = split ? t.column("sliding_wear_m3_per_s") : c_w, c_st = split ? t.column("strike_W") : -1;
  const bool halves = !r.halves.empty() && t.has("first_half_strike_W");
  const int c_h[4] = {halves ? t.column("first_half_sliding_wear_m3_per_s") : -1,
                      halves ? t.column("first_half_strike_W") : -1,
                      halves ? t.column("second_half_sliding_wear_m3_per_s") : -1,
                      halves ? t.column("second_half_strike_W") : -1};
  if (!halves) r.halves.clear();
  r.station_m3_s.assign(profiles, std::vector<double>(kWearStations, 0.0));
  r.parts.station_sliding_m3_s = r.parts.station_strike_W = r.station_m3_s;
  for (WearParts& h : r.halves) h.station_sliding_m3_s = h.station_strike_W = r.station_m3_s;
  for (std::size_t k = 0; k < t.rows.size(); ++k) {
    const double pf = t.number(k, c_p), sf = t.number(k, c_s), w = t.number(k, c_w);
    if (!(pf >= 0 && pf < profiles && pf == std::floor(pf) && sf >= 0 && sf < kWearStations && sf == std::floor(sf)))
      throw std::invalid_argument(t.where(k) + ": profile " + t.rows[k][c_p] + ", station " + t.rows[k][c_s] +
                                  " is not one of this case's");
    if (!(std::isfinite(w) && w >= 0))
      throw std::invalid_argument(t.where(k) + ": wear_m3_per_s " + t.rows[k][c_w] +
                                  " is not a wear rate (finite, >= 0); the file is damaged");
    const int pi = static_cast<int>(pf), si = static_cast<int>(sf);
    auto rate = [&](int col) {
      const double v = col >= 0 ? t.number(k, col) : 0.0;
      if (!(std::isfinite(v) && v >= 0))
        throw std::invalid_argument(t.where(k) + ": " + t.header[col] + " " + t.rows[k][col] +
                                    " is not a rate (finite, >= 0); the file is damaged");
      return v;
    };
    r.station_m3_s[pi][si] = w;
    r.parts.station_sliding_m3_s[pi][si] = rate(c_sl);
    r.parts.station_strike_W[pi][si] = rate(c_st);
    for (std::size_t h = 0; h < r.halves.size(); ++h) {
      r.halves[h].station_sliding_m3_s[pi][si] = rate(c_h[2 * h]);
      r.halves[h].station_strike_W[pi][si] = rate(c_h[2 * h + 1]);
    }
  }
  }
  // The worn meshes' triangles: their sums, part of the liner's.
  if (!meshes.empty()) {
    const io::CsvTable t = io::read_csv_strict(dir / "wear.csv", "the stage's run wrote no liner wear");
    const int c_part = t.column("part"), c_row = t.column("row"), c_area = t.column("area_m2"),
              c_sl = t.column("sliding_wear_mm_per_1000h"), c_st = t.column("strike_W"), c_kg = t.column("wear_kg_per_h");
    r.mesh_sliding_m3_s.assign(meshes.size(), 0.0);
    r.mesh_strike_W.assign(meshes.size(), 0.0);
    for (std::size_t k = 0; k < t.rows.size(); ++k) {
      if (t.rows[k][c_part] != "mesh") continue;
      const auto it = std::find(meshes.begin(), meshes.end(), static_cast<int>(t.number(k, c_row)));
      if (it == meshes.end()) continue;
      const double area = t.number(k, c_area), sl = t.number(k, c_sl), st = t.number(k, c_st), kg = t.number(k, c_kg);
      if (!(std::isfinite(area) && std::isfinite(sl) && std::isfinite(st) && std::isfinite(kg) && area >= 0 &&
            sl >= 0 && st >= 0 && kg >= 0))
        throw std::invalid_argument(t.where(k) + ": a mesh triangle's wear that is not finite and >= 0; the file is damaged");
      const std::size_t m = static_cast<std::size_t>(it - meshes.begin());
      r.mesh_sliding_m3_s[m] += sl * area / 3.6e9;
      r.mesh_strike_W[m] += st;
      r.liner_kg_h += kg;
    }
    for (std::size_t m = 0; m < meshes.size(); ++m) {
      r.parts.liner_sliding_kg_h += r.mesh_sliding_m3_s[m] * density * 3600.0;
      r.parts.liner_strike_W += r.mesh_strike_W[m];
    }
  }
  return r;
}

std::vector<StageSe> cumulative_se(const std::vector<Stage>& stages) {
  std::vector<StageSe> out;
  if (stages.empty()) return out;
  const std::size_t profiles = stages.front().outlines.size();
  StageSe var{std::vector<double>(profiles, 0.0), std::vector<double>(profiles, 0.0),
              std::vector<double>(profiles, 0.0)};
  for (const Stage& s : stages) {
    StageSe e = var;
    for (std::size_t k = 0; k < profiles; ++k)
      e.height_mm[k] = std::sqrt(var.height_mm[k]), e.leading_deg[k] = std::sqrt(var.leading_deg[k]),
      e.trailing_deg[k] = std::sqrt(var.trailing_deg[k]);
    out.push_back(e);
    const bool has = s.span_case_hours > 0 && s.se_height_mm.size() == profiles;
    for (std::size_t k = 0; k < profiles; ++k) {
      var.height_mm[k] += has ? s.se_height_mm[k] * s.se_height_mm[k] : NAN;
      var.leading_deg[k] += has ? s.se_leading_deg[k] * s.se_leading_deg[k] : NAN;
      var.trailing_deg[k] += has ? s.se_trailing_deg[k] * s.se_trailing_deg[k] : NAN;
    }
  }
  return out;
}

WearMix mix_for_share(const StageResult& s0, double share, double case_impact, double density, double shell) {
  WearMix m;
  m.share = share;
  m.shell = shell;
  const double kg_h_per_W = density * 3600.0;  // per m³/J of impact coefficient
  const WearParts& p = s0.parts;
  const double total = p.liner_sliding_kg_h + case_impact * p.liner_strike_W * kg_h_per_W;  // at the case's
  // What each coefficient acts on, the shell's part weighed by its ratio.
  const double sliding = p.liner_sliding_kg_h + (shell - 1) * p.shell_sliding_kg_h;
  const double strike = p.liner_strike_W + (shell - 1) * p.shell_strike_W;
  if (!std::isfinite(share)) {  // the case's own mix, the shell's wear scaled
    m.sliding = 1, m.impact = case_impact;
    return m;
  }
  if (share > 0 && !(p.liner_strike_W > 0))
    throw std::invalid_argument(fmt::format(
        "--impact-share {:g}: the new liner's run booked no strike energy on the shell and the lifters, so impact "
        "wear cannot take a share of its wear",
        share));
  if (share < 1 && !(p.liner_sliding_kg_h > 0))
    throw std::invalid_argument(fmt::format(
        "--impact-share {:g}: the new liner's run booked no sliding wear on the shell and the lifters (is the "
        "liner's wear_coefficient 0?), so sliding cannot take the rest; give --impact-share 1",
        share));
  if (!(total > 0))
    throw std::invalid_argument(fmt::format("--impact-share {:g}: the new liner's run booked no wear at all", share));
  m.sliding = share < 1 ? (1 - share) * total / sliding : 0.0;
  m.impact = share > 0 ? share * total / (strike * kg_h_per_W) : 0.0;
  return m;
}

MixedWear mixed(const WearParts& p, const WearMix& mix, double density) {
  MixedWear w;
  const double sliding = p.liner_sliding_kg_h + (mix.shell - 1) * p.shell_sliding_kg_h;
  const double strike = p.liner_strike_W + (mix.shell - 1) * p.shell_strike_W;
  w.liner_kg_h = mix.sliding * sliding + mix.impact * strike * density * 3600.0;
  // W/m² times m³/J is m/s: 3.6e9 of it is mm per 1000 h.
  w.shell_mm_per_1000h =
      mix.shell * (mix.sliding * p.shell_sliding_mm_per_1000h + mix.impact * p.shell_strike_W_m2 * 3.6e9);
  w.station_m3_s = p.station_sliding_m3_s;
  for (std::size_t k = 0; k < w.station_m3_s.size(); ++k)
    for (std::size_t j = 0; j < w.station_m3_s[k].size(); ++j)
      w.station_m3_s[k][j] = mix.sliding * p.station_sliding_m3_s[k][j] + mix.impact * p.station_strike_W[k][j];
  return w;
}

double impact_share(const StageResult& r, const WearMix& mix, double density) {
  const WearParts& p = r.parts;
  const double strike = p.liner_strike_W + (mix.shell - 1) * p.shell_strike_W;
  return r.liner_kg_h > 0 ? mix.impact * strike * density * 3600.0 / r.liner_kg_h : 0.0;
}

void apply_mix(StageResult& r, const WearMix& mix, double density) {
  MixedWear w = mixed(r.parts, mix, density);
  r.liner_kg_h = w.liner_kg_h;
  r.shell_mm_per_1000h = w.shell_mm_per_1000h;
  r.station_m3_s = std::move(w.station_m3_s);
}

}  // namespace mc::app::life
