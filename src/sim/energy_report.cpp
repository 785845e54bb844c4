#include "sim/energy_report.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/layout.hpp"
#include "core/liner_wear.h"

namespace mc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Collision sums of one spectra cell (or a sum of cells) into rates.
struct CellSums {
  double count = 0, normal = 0, tangential = 0, rolling = 0, speed = 0, steps = 0, by_normal = 0, by_normal_e = 0;
  double impact = 0, impact_e = 0, impact_r = 0, loss = 0, loss_e = 0, loss_r = 0;
  void add(const BookSums& b, int row, int bin) {
    impact += b.at(row, bin, MC_SPECTRA_IMPACT);
    impact_e += b.at(row, bin, MC_SPECTRA_IMPACT_ENERGY);
    impact_r += b.at(row, bin, MC_SPECTRA_IMPACT_RADIUS);
    loss += b.at(row, bin, MC_SPECTRA_LOSS);
    loss_e += b.at(row, bin, MC_SPECTRA_LOSS_ENERGY);
    loss_r += b.at(row, bin, MC_SPECTRA_LOSS_RADIUS);
    count += b.at(row, bin, MC_SPECTRA_COUNT);
    normal += b.at(row, bin, MC_SPECTRA_NORMAL);
    tangential += b.at(row, bin, MC_SPECTRA_TANGENTIAL);
    rolling += b.at(row, bin, MC_SPECTRA_ROLLING);
    speed += b.at(row, bin, MC_SPECTRA_SPEED);
    steps += b.at(row, bin, MC_SPECTRA_STEPS);
    by_normal += b.at(row, bin, MC_SPECTRA_BY_NORMAL);
    by_normal_e += b.at(row, bin, MC_SPECTRA_BY_NORMAL_ENERGY);
  }
  void add(const CellSums& o) {
    count += o.count, normal += o.normal, tangential += o.tangential, rolling += o.rolling, speed += o.speed,
        steps += o.steps, by_normal += o.by_normal, by_normal_e += o.by_normal_e;
    impact += o.impact, impact_e += o.impact_e, impact_r += o.impact_r, loss += o.loss, loss_e += o.loss_e,
        loss_r += o.loss_r;
  }
  CollisionRates rates(double window_s, double dt) const {
    CollisionRates r;
    const double w = window_s > 0 ? window_s : 1;
    r.collisions_per_s = count / w;
    r.normal_W = normal / w;
    r.tangential_W = tangential / w;
    r.rolling_W = rolling / w;
    r.power_W = r.normal_W + r.tangential_W + r.rolling_W;
    r.mean_energy_J = count > 0 ? (normal + tangential + rolling) / count : 0;
    r.mean_impact_speed_m_s = count > 0 ? speed / count : 0;
    r.mean_contact_s = count > 0 ? steps * dt / count : 0;
    r.by_normal_collisions_per_s = by_normal / w;
    r.by_normal_W = by_normal_e / w;
    r.impact_collisions_per_s = impact / w;
    r.impact_W = impact_e / w;
    r.impact_r_eff_m = impact > 0 ? impact_r / impact : 0;
    r.loss_collisions_per_s = loss / w;
    r.loss_W = loss_e / w;
    r.loss_r_eff_m = loss > 0 ? loss_r / loss : 0;
    return r;
  }
};

// Whether angle a (deg) lies on the counter-clockwise arc from `from` to `to`.
bool on_arc(double a, double from, double to) {
  auto wrap = [](double x) { return std::fmod(std::fmod(x, 360.0) + 360.0, 360.0); };
  return wrap(a - from) < wrap(to - from);
}

}  // namespace

double shell_lifters_wear_kg_per_h(const LinerReport& r) {
  double kg_h = r.mesh_wear_kg_per_h_by_part[static_cast<int>(MeshPart::shell)] +
                r.mesh_wear_kg_per_h_by_part[static_cast<int>(MeshPart::lifters)];
  for (const LinerPartRates& p : r.parts)
    if (p.name != "end plates" && p.name != "mesh walls") kg_h += p.wear_kg_per_h;
  return kg_h;
}

SpectraReport spectra_report(const Scene& scene, const BookSums& books, double window_s, double open_start_J,
                             double open_end_J, double dissipated_J) {
  SpectraReport r;
  r.window_s = window_s;
  const double w = window_s > 0 ? window_s : 1;
  const double dt = scene.numerics.dt;
  const int nm = static_cast<int>(scene.materials.size());
  // Types of the materials the balls are made of (a case may list others,
  // the liner's among them).
  std::vector<bool> used(nm, scene.balls.empty());
  for (const Ball& b : scene.balls) used.at(b.material) = true;
  auto type_used = [&](int t) {
    const int balls = nm * (nm + 1) / 2;
    if (t >= balls) return static_cast<bool>(used[(t - balls) / 3]);
    for (int a = 0; a < nm; ++a)
      for (int b = a; b < nm; ++b)
        if (a * nm - a * (a - 1) / 2 + (b - a) == t) return used[a] && used[b];
    return false;
  };
  CellSums all;
  for (int t = 0; t < books.n_types; ++t) {
    if (!type_used(t)) continue;
    CellSums type;
    for (int b = 0; b < MC_SPECTRA_BINS; ++b) {
      CellSums cell;
      cell.add(books, t, b);
      type.add(cell);
      SpectraBin sb;
      sb.type = t;
      sb.bin = b;
      sb.energy_from_J = b == 0 ? 0.0 : spectra_edge_J(b);
      sb.energy_to_J = b == MC_SPECTRA_BINS - 1 ? std::numeric_limits<double>::infinity() : spectra_edge_J(b + 1);
      sb.severity_from_J_m = sb.energy_from_J / MC_SPECTRA_R_REF;
      sb.severity_to_J_m = sb.energy_to_J / MC_SPECTRA_R_REF;
      sb.rates = cell.rates(window_s, dt);
      sb.rates.pair = pair_type_name(scene, t);
      sb.rates.wall = pair_type_is_wall(nm, t);
      r.bins.push_back(sb);
    }
    CollisionRates tr = type.rates(window_s, dt);
    tr.pair = pair_type_name(scene, t);
    tr.wall = pair_type_is_wall(nm, t);
    r.types.push_back(tr);
    all.add(type);
  }
  r.all = all.rates(window_s, dt);
  r.all.pair = "all";
  double unrecorded = 0;
  for (int f : {MC_SPECTRA_NORMAL, MC_SPECTRA_TANGENTIAL, MC_SPECTRA_ROLLING})
    unrecorded += books.at(books.n_types, 0, f);
  r.closed_W = r.all.power_W;
  r.open_change_W = (open_end_J - open_start_J) / w;
  r.unrecorded_W = unrecorded / w;
  r.books_W = r.closed_W + r.open_change_W + r.unrecorded_W;
  r.dissipation_W = dissipated_J / w;
  return r;
}

bool liner_books_half(const BookSums& whole, const std::vector<double>& first_half, int half, BookSums& out) {
  const std::size_t nl = whole.liner.size(), ns = whole.stations.size();
  if (first_half.size() != nl + ns || nl == 0) return false;
  out = BookSums{};
  out.n_types = whole.n_types;
  out.n_elements = whole.n_elements;
  out.n_stations = whole.n_stations;
  out.liner.assign(first_half.begin(), first_half.begin() + static_cast<std::ptrdiff_t>(nl));
  out.stations.assign(first_half.begin() + static_cast<std::ptrdiff_t>(nl), first_half.end());
  if (half == 1) {
    for (std::size_t q = 0; q < nl; ++q) out.liner[q] = whole.liner[q] - out.liner[q];
    for (std::size_t q = 0; q < ns; ++q) out.stations[q] = whole.stations[q] - out.stations[q];
  }
  return true;
}

// An element's impact wear coefficient: its mesh's material's, or the liner's.
static double impact_coefficient(const Scene& scene, const LinerElement& el) {
  return el.impact_wear_coefficient >= 0 ? el.impact_wear_coefficient : scene.wall_material.impact_wear_coefficient;
}

std::vector<double> liner_impact_coefficients(const Scene& scene) {
  const LinerLayout layout = liner_layout(scene);
  std::vector<double> k;
  for (const LinerElement& el : layout.elements) k.push_back(impact_coefficient(scene, el));
  return k;
}

LinerReport liner_report(const Scene& scene, const LinerLayout& layout, const BookSums& books, double window_s,
                         const std::vector<long>& contact_profile, const ChargeAngles& angles) {
  LinerReport r;
  r.window_s = window_s;
  r.toe_deg = angles.found ? angles.toe_deg : kNaN;
  r.shoulder_deg = angles.found ? angles.shoulder_deg : kNaN;
  const double w = window_s > 0 ? window_s : 1;
  const double density = scene.wall_material.density;
  const char* names[] = {"shell", "lifter leading faces", "lifter tops", "lifter trailing faces", "end plates",
                         "mesh walls"};
  const int n_parts = layout.first_mesh < layout.size() ? 6 : 5;  // meshes only where there are some
  r.parts.resize(n_parts);
  for (int p = 0; p < n_parts; ++p) r.parts[p].name = names[p];
  r.elements.resize(layout.elements.size());
  for (std::size_t e = 0; e < layout.elements.size(); ++e) {
    const LinerElement& el = layout.elements[e];
    LinerElementRates& x = r.elements[e];
    const int ei = static_cast<int>(e);
    x.impacts_per_s = books.liner_at(ei, MC_LINER_IMPACTS) / w;
    x.impact_W = books.liner_at(ei, MC_LINER_NORMAL) / w;
    x.shear_W = books.liner_at(ei, MC_LINER_SHEAR) / w;
    x.sliding_m3_per_s = books.liner_at(ei, MC_LINER_WEAR) / w;
    x.strike_W = books.liner_at(ei, MC_LINER_STRIKE) / w;
    x.impact_m3_per_s = x.strike_W * impact_coefficient(scene, el);
    x.wear_m3_per_s = x.sliding_m3_per_s + x.impact_m3_per_s;
    if (el.area_m2 > 0) {
      x.impact_W_m2 = x.impact_W / el.area_m2;
      x.shear_W_m2 = x.shear_W / el.area_m2;
      x.wear_mm_per_1000h = x.wear_m3_per_s / el.area_m2 * 1000.0 * 3600.0 * 1000.0;
    }
    const double rho = el.density > 0 ? el.density : density;
    x.wear_kg_per_h = x.wear_m3_per_s * rho * 3600.0;
    const int part = el.part == LinerPart::shell ? 0 : el.part == LinerPart::plate ? 4 : el.part == LinerPart::mesh ? 5 : 1 + el.bin;
    if (el.part == LinerPart::mesh && el.row >= 0 && el.row < static_cast<int>(scene.walls.meshes.size()))
      r.mesh_wear_kg_per_h_by_part[static_cast<int>(scene.walls.meshes[el.row].part)] += x.wear_kg_per_h;
    LinerPartRates& pr = r.parts[part];
    pr.area_m2 += el.area_m2;
    pr.impacts_per_s += x.impacts_per_s;
    pr.impact_W += x.impact_W;
    pr.shear_W += x.shear_W;
    pr.wear_kg_per_h += x.wear_kg_per_h;
    pr.sliding_kg_per_h += x.sliding_m3_per_s * rho * 3600.0;
    pr.impact_kg_per_h += x.impact_m3_per_s * rho * 3600.0;
    pr.strike_W += x.strike_W;
    pr.worst_wear_mm_per_1000h = std::max(pr.worst_wear_mm_per_1000h, x.wear_mm_per_1000h);
    r.impacts_per_s += x.impacts_per_s;
    r.impact_W += x.impact_W;
    r.shear_W += x.shear_W;
    r.wear_kg_per_h += x.wear_kg_per_h;
    r.sliding_kg_per_h += x.sliding_m3_per_s * rho * 3600.0;
    r.impact_kg_per_h += x.impact_m3_per_s * rho * 3600.0;
    r.strike_W += x.strike_W;
    if (r.worst_element < 0 || x.wear_mm_per_1000h > r.worst_wear_mm_per_1000h) {
      r.worst_element = ei;
      r.worst_wear_mm_per_1000h = x.wear_mm_per_1000h;
    }
  }
  for (LinerPartRates& pr : r.parts)
    if (pr.area_m2 > 0) pr.mean_wear_mm_per_1000h = pr.wear_kg_per_h / density / 3600.0 / pr.area_m2 * 3.6e9;

  // The lab frame: impact power per degree, how much of the liner the charge
  // covers there, the bare liner's share, the impact point.
  const int nb = static_cast<int>(books.impact_profile.size());
  r.impact_W_per_deg.resize(nb);
  double total = 0;
  for (int b = 0; b < nb; ++b) total += r.impact_W_per_deg[b] = books.impact_profile[b] / w;
  r.coverage.assign(nb, 0.0);
  const int np = static_cast<int>(contact_profile.size());
  if (np > 0 && nb > 0) {
    std::vector<double> s(np, 0.0);  // the profile smoothed over 5 bins, as the toe finder does
    for (int k = 0; k < np; ++k)
      for (int j = -2; j <= 2; ++j) s[k] += contact_profile[((k + j) % np + np) % np] / 5.0;
    const double peak = *std::max_element(s.begin(), s.end());
    for (int b = 0; b < nb && peak > 0; ++b) r.coverage[b] = std::min(1.0, s[static_cast<std::size_t>(b) * np / nb] / peak);
  }
  if (!angles.found || nb == 0 || !(total > 0)) {
    r.bare_liner_impact_W = r.bare_liner_impact_share = r.impact_point_deg = kNaN;
    return r;
  }
  // Where impact power per degree `w_per_deg` peaks on bare liner, from the
  // shoulder to 45 degrees past the toe; its bin in `at`.
  auto impact_point = [&](const std::vector<double>& w_per_deg, int& at, double* bare_W, bool need_bare) {
    std::vector<double> bare(nb);
    for (int b = 0; b < nb; ++b) {
      bare[b] = w_per_deg[b] * (1 - r.coverage[b]);
      if (bare_W) *bare_W += bare[b];
    }
    const double deg_per_bin = 360.0 / nb;
    const int half = static_cast<int>(std::lround(4.0 / deg_per_bin));
    double best = -1, point = kNaN;
    at = 0;
    for (int b = 0; b < nb; ++b) {
      const double a = (b + 0.5) * deg_per_bin;
      if (!on_arc(a, r.shoulder_deg, r.toe_deg + 45.0)) continue;
      double sm = 0;
      for (int d = -half; d <= half; ++d) sm += bare[((b + d) % nb + nb) % nb];
      if (sm > best) best = sm, point = a, at = b;
    }
    return need_bare && !(best > 0) ? kNaN : point;
  };
  int at = 0;
  r.impact_point_deg = impact_point(r.impact_W_per_deg, at, &r.bare_liner_impact_W, false);
  r.bare_liner_impact_share = r.bare_liner_impact_W / total;
  r.impact_point_on_liner = r.coverage[at] < 0.5;
  // Along the mill, bin by bin.
  const int na = books.impact_axial_bins;
  if (na > 0 && books.impact_profile_axial.size() == static_cast<std::size_t>(na) * nb) {
    for (int k = 0; k < na; ++k) {
      std::vector<double> per_deg(nb);
      double sum = 0;
      for (int b = 0; b < nb; ++b) sum += per_deg[b] = books.impact_profile_axial[static_cast<std::size_t>(k) * nb + b] / w;
      int at_k = 0;
      r.impact_W_by_axial.push_back(sum);
      r.impact_point_deg_by_axial.push_back(sum > 0 ? impact_point(per_deg, at_k, nullptr, true) : kNaN);
    }
  }
  return r;
}

std::vector<LifterStation> lifter_stations(const BookSums& books, double window_s,
                                           const std::vector<std::vector<Vec2>>& outlines, double R, double length,
                                           double impact_k) {
  std::vector<LifterStation> out;
  const int kinds = static_cast<int>(outlines.size());
  const int rows = books.n_stations / kWearStations;
  if (kinds == 0 || rows == 0 || !(window_s > 0)) return out;
  for (int k = 0; k < kinds; ++k) {
    const std::vector<StationPlace> places = station_places(outlines[k], R);
    int n_rows = 0;
    for (int row = k; row < rows; row += kinds) ++n_rows;
    for (int j = 0; j < kWearStations; ++j) {
      LifterStation st;
      st.profile = k;
      st.station = j;
      st.x_m = places[j].centre.x;
      st.y_m = places[j].centre.y;
      st.length_m = places[j].length;
      for (int row = k; row < rows; row += kinds) {
        const std::size_t at = (static_cast<std::size_t>(row) * kWearStations + j) * MC_LINER_FIELDS;
        st.impacts_per_s += books.stations[at + MC_LINER_IMPACTS];
        st.impact_W += books.stations[at + MC_LINER_NORMAL];
        st.shear_W += books.stations[at + MC_LINER_SHEAR];
        st.sliding_m3_per_s += books.stations[at + MC_LINER_WEAR];
        st.strike_W += books.stations[at + MC_LINER_STRIKE];
      }
      const double per = 1.0 / (n_rows * window_s);
      st.impacts_per_s *= per;
      st.impact_W *= per;
      st.shear_W *= per;
      st.sliding_m3_per_s *= per;
      st.strike_W *= per;
      st.impact_m3_per_s = st.strike_W * impact_k;
      st.wear_m3_per_s = st.sliding_m3_per_s + st.impact_m3_per_s;
      const double area = st.length_m * length;
      st.wear_mm_per_1000h = area > 0 ? st.wear_m3_per_s / area * 3.6e9 : 0.0;
      out.push_back(st);
    }
  }
  return out;
}

}  // namespace mc
