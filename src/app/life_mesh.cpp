// A life study's mesh liners (life_mesh.h).
#include "app/life_mesh.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numeric>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/csv_read.h"
#include "io/stl.h"
#include "life/mesh_section.h"
#include "life/mesh_collapse.h"
#include "life/mesh_wear.h"

namespace mc::app::life {

namespace fs = std::filesystem;

namespace {

// The file name of worn mesh `walls_mesh` in a stage folder.
std::string mesh_file_name(const MillCase& c, int walls_mesh) {
  return worn_meshes(c).size() == 1 ? std::string("liner.stl") : fmt::format("liner-{}.stl", walls_mesh);
}

}  // namespace

std::vector<int> worn_meshes(const MillCase& c) {
  std::vector<int> out;
  const int liner = material_index(c, c.liner);
  for (std::size_t k = 0; k < c.meshes.size(); ++k) {
    const MeshSpec& m = c.meshes[k];
    if (!m.turning || m.part == MeshPart::ends) continue;
    const int mi = m.material.empty() ? liner : material_index(c, m.material);
    if (mi >= 0 && liner >= 0 && mi != liner) {
      const Material& a = c.materials[mi];
      const Material& b = c.materials[liner];
      if (a.wear_coefficient != b.wear_coefficient || a.impact_wear_coefficient != b.impact_wear_coefficient ||
          a.density != b.density || a.impact_wear_threshold_speed != b.impact_wear_threshold_speed)
        throw std::invalid_argument(fmt::format(
            "walls.mesh[{}].material = \"{}\": a life study wears its meshes at the liner's (\"{}\") wear "
            "coefficients and density, and \"{}\" has others; give the mesh the liner's material, or make it part "
            "= \"ends\" (not worn)",
            k, m.material, c.liner, m.material));
    }
    out.push_back(static_cast<int>(k));
  }
  return out;
}

std::vector<Triangle> stage_mesh_triangles(const fs::path& out, const MillCase& c, const StageMesh& m) {
  if (m.file.empty()) return placed_mesh_triangles(c.meshes.at(m.walls_mesh));
  return io::read_stl(out / m.file).triangles;
}

void check_worn_meshes(const MillCase& c, const std::vector<int>& worn, int axial_segments) {
  for (int k : worn) {
    const std::vector<Triangle> t = placed_mesh_triangles(c.meshes.at(k));
    std::size_t alone = 0;
    for (const std::vector<int>& part : mc::life::connected_parts(t)) alone += part.size() == 1 ? 1 : 0;
    if (t.size() >= 4 && 2 * alone > t.size())
      throw std::invalid_argument(fmt::format(
          "walls.mesh[{}]: {} of its {} triangles share no corner with another: the STL's corners are not welded "
          "(each triangle has its own copies), and a worn mesh would come apart; weld its vertices first (in "
          "MeshLab: Merge Close Vertices)",
          k, alone, t.size()));
    if (axial_segments > 0) {
      const double span = c.length / axial_segments;
      for (std::size_t i = 0; i < t.size(); ++i) {
        if (std::fabs(triangle_unit_normal(t[i]).z) > 0.5) continue;  // an end cap
        const double z0 = std::min({t[i].v[0].z, t[i].v[1].z, t[i].v[2].z});
        const double z1 = std::max({t[i].v[0].z, t[i].v[1].z, t[i].v[2].z});
        if (z1 - z0 > span * (1 + 1e-9))
          throw std::invalid_argument(fmt::format(
              "--axial-segments {}: walls.mesh[{}]: triangle {} runs {:.4g} m along the mill, longer than a segment "
              "({:.4g} m), so its wear cannot be told to one; give a finer mesh (check --write-lifters FILE "
              "--lifter-mesh MM makes one of bars) or fewer segments",
              axial_segments, k, i + 1, z1 - z0, span));
      }
    }
  }
}

double shell_share_covered(const MillCase& c, const std::vector<int>& worn) {
  if (c.lifter_rows > 0) return 0;  // the shell's elements leave out [lifters] bars' feet already
  const double R = 0.5 * c.diameter;
  double covered = 0;
  for (int k : worn) {
    if (c.meshes.at(k).part != MeshPart::lifters) continue;
    const std::vector<Triangle> t = placed_mesh_triangles(c.meshes.at(k));
    for (const std::vector<int>& part : mc::life::connected_parts(t)) {
      const double centre = mc::life::part_angle(t, part);
      double a0 = 1e9, a1 = -1e9, z0 = 1e9, z1 = -1e9;
      for (int i : part)
        for (const Vec3& v : t[i].v) {
          if (std::hypot(v.x, v.y) < R - 1e-3) continue;
          const double a = std::remainder(std::atan2(v.y, v.x) - centre, 2 * M_PI);
          a0 = std::min(a0, a), a1 = std::max(a1, a), z0 = std::min(z0, v.z), z1 = std::max(z1, v.z);
        }
      if (a1 > a0 && z1 > z0) covered += R * (a1 - a0) * (z1 - z0);
    }
  }
  return std::clamp(covered / (2 * M_PI * R * c.length), 0.0, 0.9);
}

void scale_shell_rates(StageResult& r, double f) {
  r.shell_mm_per_1000h *= f;
  for (WearParts* p : {&r.parts}) p->shell_sliding_mm_per_1000h *= f, p->shell_strike_W_m2 *= f;
  for (WearParts& p : r.halves) p.shell_sliding_mm_per_1000h *= f, p.shell_strike_W_m2 *= f;
}

void put_stage_meshes(MillCase& c, const fs::path& out, const Stage& s,
                      const std::vector<std::vector<Triangle>>* worn) {
  for (std::size_t j = 0; j < s.meshes.size(); ++j) {
    const StageMesh& m = s.meshes[j];
    if (m.file.empty()) continue;
    MeshSpec& spec = c.meshes.at(m.walls_mesh);
    const fs::path p = fs::absolute(out / m.file).lexically_normal();
    spec.file = spec.path = p.string();
    spec.units = "m";
    spec.offset = Vec3{};
    spec.angle_deg = 0;
    spec.flip = false;
    spec.triangles = worn ? worn->at(j) : io::read_stl(p).triangles;
  }
}

namespace {

// What each of a stage's mesh triangles (placed, every one) booked over
// the stage's hours at the mix, m³, from the run's wear.csv (which leaves
// a periodic slice's seam caps out: they book nothing).
std::vector<double> booked_volumes(const fs::path& run, const MillCase& c, int walls_mesh,
                                   const std::vector<Triangle>& placed, const WearMix& mix, double span_case_hours) {
  std::size_t kept = 0;
  for (const Triangle& t : placed) kept += on_periodic_seam(t, c) ? 0 : 1;
  const TriangleWear tw = read_triangle_wear(run / "wear.csv", walls_mesh, kept);
  std::vector<double> volume(placed.size(), 0.0);
  for (std::size_t t = 0, i = 0; t < placed.size(); ++t)
    if (!on_periodic_seam(placed[t], c)) {
      volume[t] = (mix.sliding * tw.sliding_m3_s[i] + mix.impact * tw.strike_W[i]) * span_case_hours * 3600.0;
      ++i;
    }
  return volume;
}


// Where a worn mesh must stay: inside the shell of radius R and between
// the end planes (within a micrometre per metre of them).
mc::life::MeshBounds mesh_bounds(const MillCase& c, double R) {
  // The planes a little outside the ends (a rounding of the mesh's z);
  // a vertex at either end, within that and 2 µm, is on its plane.
  const double z_tol = 1e-6 * std::max(1.0, c.length);
  return {R, -z_tol, c.length + z_tol, z_tol + 2e-6};
}

// The stage's mesh with its short edges collapsed at `share`, and its
// booked volumes carried (life/mesh_collapse.h): what the wear moved, as
// wear_kept_fit collapsed it.
mc::life::Collapsed collapsed_mesh(const MillCase& c, const std::vector<Triangle>& tris, const std::vector<double>& volume,
                                   double share) {
  const mc::life::MeshBounds b = mesh_bounds(c, 0);
  return mc::life::collapse_short_edges(tris, volume, b.z0, b.z1, share, b.on_end);
}

}  // namespace

std::vector<std::vector<Triangle>> wear_meshes(const fs::path& out, const MillCase& c, Stage& s, Stage& next,
                                               const WearMix& mix, double span_case_hours, double next_R,
                                               const MeshSmoothing& smoothing, int axial_segments) {
  next.meshes.clear();
  std::vector<std::vector<Triangle>> worn;
  const fs::path run = out / fmt::format("stage-{:02d}", s.index);
  for (StageMesh& m : s.meshes) {
    const std::vector<Triangle> placed = stage_mesh_triangles(out, c, m);
    const std::vector<double> booked = booked_volumes(run, c, m.walls_mesh, placed, mix, span_case_hours);
    const mc::life::MeshBounds bounds = mesh_bounds(c, next_R);
    const std::string name = fmt::format("walls.mesh[{}] worn from stage {} to {}", m.walls_mesh, s.index, next.index);
    // Short edges collapsed first; where the move still spoils a triangle
    // (a worn corner's strip), longer ones, up to the last share.
    const int segments = std::max(axial_segments, 1);
    const mc::life::FitWear f =
        mc::life::wear_kept_fit(placed, booked, bounds, smoothing.across_m, smoothing.along_m, name, segments);
    const mc::life::MeshWear& w = f.wear;
    m.collapsed = f.edges, m.collapse_share = f.share, m.collapse_m3 = f.collapse_m3;
    m.local_passes = f.local_passes, m.local_misfit = f.local_misfit, m.stretch_segments = segments;
    m.steps = f.steps, m.span_asked_m3 = f.span_asked_m3, m.span_removed_m3 = f.span_removed_m3;
    // Booked by the stage; removed by the collapses and the moves together.
    m.booked_m3 = 0;
    for (double v : booked) m.booked_m3 += v;
    m.removed_m3 = f.removed_m3;
    m.scale = w.scale;
    m.deepest_m = f.deepest_m;
    m.relaxed = f.relaxed;
    StageMesh n;
    n.walls_mesh = m.walls_mesh;
    n.file = fmt::format("stage-{:02d}/{}", next.index, mesh_file_name(c, m.walls_mesh));
    next.meshes.push_back(n);
    worn.push_back(w.triangles);
  }
  return worn;
}

void write_stage_meshes(const fs::path& out, const Stage& next, const std::vector<std::vector<Triangle>>& worn) {
  for (std::size_t j = 0; j < next.meshes.size(); ++j) {
    const StageMesh& n = next.meshes[j];
    std::error_code ec;
    fs::create_directories((out / n.file).parent_path(), ec);
    if (ec) throw std::runtime_error("cannot create " + (out / n.file).parent_path().string() + ": " + ec.message());
    io::write_file_atomic(out / n.file, io::stl_binary(worn.at(j), fmt::format("millcharge life: walls.mesh[{}] worn "
                                                                               "to stage {}, m",
                                                                               n.walls_mesh, next.index)));
  }
}

namespace {

// Mean and standard error (standard deviation over √n) of a list; NaN
// where it is empty (the error where it has one value).
std::pair<double, double> mean_se(const std::vector<double>& v) {
  if (v.empty()) return {NAN, NAN};
  const double n = static_cast<double>(v.size()), mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  double ss = 0;
  for (double x : v) ss += (x - mean) * (x - mean);
  return {mean, v.size() > 1 ? std::sqrt(ss / (n - 1) / n) : NAN};
}

std::string opt(double v, int digits) { return std::isfinite(v) ? fmt::format("{:.{}f}", v, digits) : std::string(); }

}  // namespace

namespace {

// Each worn mesh's bars' frames, from the new mesh: their centres' angles.
std::vector<std::vector<double>> bar_angles(const fs::path& out, const MillCase& c, const std::vector<Stage>& stages) {
  std::vector<std::vector<double>> angles;
  for (const StageMesh& m : stages.front().meshes) {
    const std::vector<Triangle> tris = stage_mesh_triangles(out, c, m);
    angles.emplace_back();
    for (const std::vector<int>& part : mc::life::connected_parts(tris))
      angles.back().push_back(mc::life::part_angle(tris, part));
  }
  return angles;
}

}  // namespace

std::vector<Stage> stages_drawn(const fs::path& out, const MillCase& c, const std::vector<Stage>& stages) {
  std::vector<Stage> shown = stages;
  if (stages.empty()) return shown;
  // The first worn mesh of part "lifters".
  std::size_t j = 0;
  while (j < stages.front().meshes.size() && c.meshes.at(stages.front().meshes[j].walls_mesh).part != MeshPart::lifters)
    ++j;
  if (j == stages.front().meshes.size()) return shown;
  const std::vector<double> angles = bar_angles(out, c, stages).at(j);
  for (Stage& s : shown) {
    s.se_height_mm.clear(), s.se_leading_deg.clear(), s.se_trailing_deg.clear();
    if (!s.ran) continue;
    const std::vector<Triangle> tris = stage_mesh_triangles(out, c, s.meshes.at(j));
    const std::vector<Vec2> mean =
        mc::life::mean_outline(mc::life::bar_sections(tris, angles, 0.5 * c.length, 0.5 * s.diameter));
    if (!mean.empty()) s.outlines = {mean};
  }
  return shown;
}

void write_mesh_table(const fs::path& out, const MillCase& c, const std::vector<Stage>& stages,
                      const MeshTableBasis& b) {
  std::string t =
      "stage,hours,case_hours,mesh,file,triangles,parts,"
      "mid_height_mm,mid_height_mm_se,mid_leading_angle_deg,mid_leading_angle_deg_se,mid_trailing_angle_deg,"
      "mid_trailing_angle_deg_se,ends_height_mm,ends_leading_angle_deg,ends_leading_angle_deg_se,"
      "ends_trailing_angle_deg,wear_kg_per_h,impact_wear_share,booked_cm3,removed_cm3,depth_scale,deepest_mm,"
      "collapsed_edges,collapse_cm3,relaxed_vertices,local_corrections,local_misfit,move_steps,smoothing_across_mm,smoothing_along_mm,wear_basis\n";
  if (stages.empty()) return;
  const std::vector<std::vector<double>> angles = bar_angles(out, c, stages);
  for (const Stage& s : stages) {
    if (!s.ran) break;
    const double R = 0.5 * s.diameter;
    for (std::size_t j = 0; j < s.meshes.size(); ++j) {
      const StageMesh& m = s.meshes[j];
      const std::vector<Triangle> tris = stage_mesh_triangles(out, c, m);
      const std::size_t parts = mc::life::connected_parts(tris).size();
      // The bars cut across at mid-length and a tenth of the length from each end.
      // Bars are measured on a mesh of part "lifters" only.
      const bool bars = c.meshes.at(m.walls_mesh).part == MeshPart::lifters;
      const std::vector<double> none;
      const std::vector<double>& a = bars ? angles.at(j) : none;
      const mc::life::BarMeasures mid = mc::life::measure_bars(tris, a, 0.5 * c.length, R);
      mc::life::BarMeasures ends = mc::life::measure_bars(tris, a, 0.1 * c.length, R);
      const mc::life::BarMeasures far = mc::life::measure_bars(tris, a, 0.9 * c.length, R);
      ends.height.insert(ends.height.end(), far.height.begin(), far.height.end());
      ends.leading_deg.insert(ends.leading_deg.end(), far.leading_deg.begin(), far.leading_deg.end());
      ends.trailing_deg.insert(ends.trailing_deg.end(), far.trailing_deg.begin(), far.trailing_deg.end());
      const auto mh = mean_se(mid.height), ml = mean_se(mid.leading_deg), mt = mean_se(mid.trailing_deg);
      const auto eh = mean_se(ends.height), el = mean_se(ends.leading_deg), et = mean_se(ends.trailing_deg);
      const double sliding = b.mix.sliding * s.r.mesh_sliding_m3_s.at(j), impact = b.mix.impact * s.r.mesh_strike_W.at(j);
      const bool carried = s.span_case_hours > 0;
      t += fmt::format("{},{:.6g},{:.6g},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.6g},{:.4f},{},{},{},{},{},{},{},{},{},{},{:.4g},{:.4g},{}\n",
                       s.index, s.case_hours / b.factor, s.case_hours, m.walls_mesh,
                       m.file.empty() ? c.meshes.at(m.walls_mesh).file : m.file, tris.size(), parts, opt(mh.first * 1000, 4),
                       opt(mh.second * 1000, 4), opt(ml.first, 3), opt(ml.second, 3), opt(mt.first, 3), opt(mt.second, 3),
                       opt(eh.first * 1000, 4), opt(el.first, 3), opt(el.second, 3), opt(et.first, 3),
                       (sliding + impact) * b.density * 3600.0 * b.factor,
                       sliding + impact > 0 ? impact / (sliding + impact) : 0.0,
                       carried ? fmt::format("{:.6g}", m.booked_m3 * 1e6) : "",
                       carried ? fmt::format("{:.6g}", m.removed_m3 * 1e6) : "",
                       carried ? fmt::format("{:.6g}", m.scale) : "",
                       carried ? fmt::format("{:.4f}", m.deepest_m * 1000) : "",
                       carried ? fmt::format("{}", m.collapsed) : "",
                       carried ? fmt::format("{:.6g}", m.collapse_m3 * 1e6) : "", carried ? fmt::format("{}", m.relaxed) : "",
                       carried && m.local_passes >= 0 ? fmt::format("{}", m.local_passes) : "",
                       carried && m.local_passes >= 0 ? fmt::format("{:.4f}", m.local_misfit) : "",
                       carried && m.steps > 0 ? fmt::format("{}", m.steps) : "", b.smoothing.across_m * 1000,
                       b.smoothing.along_m * 1000, b.basis);
    }
  }
  io::write_file_atomic(out / "life_meshes.csv", t);
}

void write_segment_table(const fs::path& out, const MillCase& c, const std::vector<Stage>& stages,
                         const MeshTableBasis& b, int segments) {
  std::string t =
      "stage,hours,case_hours,mesh,segment,z_from_m,z_to_m,bars,height_mm,height_mm_se,leading_angle_deg,"
      "leading_angle_deg_se,trailing_angle_deg,trailing_angle_deg_se,shell_wear_mm_per_1000h,booked_cm3,smoothed_cm3,"
      "removed_cm3,"
      "wear_basis\n";
  if (stages.empty() || segments < 1) return;
  const std::vector<std::vector<double>> angles = bar_angles(out, c, stages);
  const double span = c.length / segments;
  auto segment_of = [&](double z) { return std::clamp(static_cast<int>(std::floor(z / span)), 0, segments - 1); };
  for (std::size_t i = 0; i < stages.size(); ++i) {
    const Stage& s = stages[i];
    if (!s.ran) break;
    const double R = 0.5 * s.diameter;
    const fs::path run = out / fmt::format("stage-{:02d}", s.index);
    // The shell's depth rate per segment, from the stage's elements.
    std::vector<double> shell_rate(segments, 0.0), shell_area(segments, 0.0);
    {
      const io::CsvTable w = io::read_csv_strict(run / "wear.csv", "the stage's run wrote no liner wear");
      const int c_part = w.column("part"), c_z0 = w.column("z_from_m"), c_z1 = w.column("z_to_m"),
                c_area = w.column("area_m2"), c_sl = w.column("sliding_wear_mm_per_1000h"), c_st = w.column("strike_W");
      for (std::size_t k = 0; k < w.rows.size(); ++k) {
        if (w.rows[k][c_part] != "shell") continue;
        const double area = w.number(k, c_area);
        if (!(area > 0)) continue;
        const double mm = b.mix.sliding * w.number(k, c_sl) + b.mix.impact * w.number(k, c_st) / area * 3.6e9;
        // An element longer than a segment shares its area among the
        // segments it spans, by the length in each.
        const double z0 = w.number(k, c_z0), z1 = w.number(k, c_z1);
        for (int g = 0; g < segments; ++g) {
          const double overlap = std::min(z1, (g + 1) * span) - std::max(z0, g * span);
          if (!(overlap > 0) || !(z1 > z0)) continue;
          const double a = area * overlap / (z1 - z0);
          shell_rate[g] += mm * a, shell_area[g] += a;
        }
      }
    }
    for (std::size_t j = 0; j < s.meshes.size(); ++j) {
      const StageMesh& m = s.meshes[j];
      const std::vector<Triangle> tris = stage_mesh_triangles(out, c, m);
      // The step's volumes per segment: booked by the triangles, removed by their move.
      std::vector<double> booked(segments, 0.0), smoothed(segments, 0.0), removed(segments, 0.0);
      const bool carried = s.span_case_hours > 0 && i + 1 < stages.size() && j < stages[i + 1].meshes.size();
      bool moved = carried;  // what the move was asked and removed by segment is known
      if (carried) {
        const std::vector<Triangle> next = stage_mesh_triangles(out, c, stages[i + 1].meshes[j]);
        const std::vector<double> volume = booked_volumes(run, c, m.walls_mesh, tris, b.mix, s.span_case_hours);
        for (std::size_t q = 0; q < tris.size(); ++q)
          booked[segment_of((tris[q].v[0].z + tris[q].v[1].z + tris[q].v[2].z) / 3)] += volume[q];
        // What the move was asked and removed, as it recorded them by span
        // (a move in steps collapsed the mesh before each: the stage's mesh
        // and the next are not corner for corner).
        const std::size_t recorded = m.span_asked_m3.size();
        if (m.steps > 0 && recorded > 0 && recorded % static_cast<std::size_t>(segments) == 0) {
          for (std::size_t k = 0; k < recorded; ++k) {
            const std::size_t g = k / (recorded / static_cast<std::size_t>(segments));
            smoothed[g] += m.span_asked_m3[k], removed[g] += m.span_removed_m3[k];
          }
        } else if (m.steps > 1) {
          moved = false;  // recorded in spans these do not add up to, and not corner for corner
        } else {
          // The move was of the mesh with its short edges collapsed (where
          // the study collapsed any), corner for corner.
          const mc::life::Collapsed k = m.collapse_share > 0 ? collapsed_mesh(c, tris, volume, m.collapse_share)
                                                              : mc::life::Collapsed{tris, volume, 0, 0.0, {}};
          if (k.triangles.size() != next.size() ||
              std::abs(k.removed_m3 - m.collapse_m3) > 1e-9 * std::max(m.booked_m3, 1e-12) + 1e-15)
            throw std::invalid_argument(fmt::format("{}: {} triangles, where stage {}'s {} collapse to {}: not the mesh "
                                                    "this study wore",
                                                    (out / stages[i + 1].meshes[j].file).string(), next.size(), s.index,
                                                    tris.size(), k.triangles.size()));
          const std::vector<double> swept = mc::life::swept_volumes(k.triangles, next);
          // What the move was asked to remove: the booked less the collapse's own, where it took it.
          const std::vector<double> spread = mc::life::asked_volumes(k, b.smoothing.across_m, b.smoothing.along_m);
          for (std::size_t q = 0; q < k.triangles.size(); ++q) {
            const auto& v = k.triangles[q].v;
            const int g = segment_of((v[0].z + v[1].z + v[2].z) / 3);
            smoothed[g] += spread[q], removed[g] += swept[q];
          }
        }
      }
      for (int g = 0; g < segments; ++g) {
        const bool lifters = c.meshes.at(m.walls_mesh).part == MeshPart::lifters;
        const mc::life::BarMeasures bars =
            mc::life::measure_bars(tris, lifters ? angles.at(j) : std::vector<double>{}, (g + 0.5) * span, R);
        const auto h = mean_se(bars.height), l = mean_se(bars.leading_deg), tr = mean_se(bars.trailing_deg);
        t += fmt::format("{},{:.6g},{:.6g},{},{},{:.6g},{:.6g},{},{},{},{},{},{},{},{},{},{},{},{}\n", s.index,
                         s.case_hours / b.factor, s.case_hours, m.walls_mesh, g, g * span, (g + 1) * span,
                         bars.height.size(), opt(h.first * 1000, 4), opt(h.second * 1000, 4), opt(l.first, 3),
                         opt(l.second, 3), opt(tr.first, 3), opt(tr.second, 3),
                         shell_area[g] > 0 ? fmt::format("{:.6g}", shell_rate[g] / shell_area[g] * b.factor) : "",
                         carried ? fmt::format("{:.6g}", booked[g] * 1e6) : "",
                         moved ? fmt::format("{:.6g}", smoothed[g] * 1e6) : "",
                         moved ? fmt::format("{:.6g}", removed[g] * 1e6) : "", b.basis);
      }
    }
  }
  io::write_file_atomic(out / "life_segments.csv", t);
}

}  // namespace mc::app::life
