#include "io/energy_out.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "io/atomic_file.h"
#include "io/png_plot.h"
#include "core/layout.hpp"

namespace mc::io {

namespace {

constexpr double kDeg = 180.0 / 3.14159265358979323846;

nlohmann::json num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::ordered_json rates_json(const CollisionRates& c) {
  nlohmann::ordered_json j;
  j["pair"] = c.pair;
  j["collisions_per_s"] = num(c.collisions_per_s);
  j["power_W"] = num(c.power_W);
  j["normal_W"] = num(c.normal_W);
  j["tangential_W"] = num(c.tangential_W);
  j["rolling_W"] = num(c.rolling_W);
  j["mean_energy_J"] = num(c.mean_energy_J);
  j["mean_impact_speed_m_s"] = num(c.mean_impact_speed_m_s);
  j["mean_contact_s"] = num(c.mean_contact_s);
  // The impact energy at first touch (1/2 m* vn^2) beside the normal loss.
  j["impact_W"] = num(c.impact_W);
  j["mean_impact_energy_J"] = num(c.impact_collisions_per_s > 0 ? c.impact_W / c.impact_collisions_per_s : 0.0);
  j["mean_r_eff_m"] = num(c.impact_r_eff_m);
  return j;
}

const char* part_name(LinerPart p) {
  return p == LinerPart::shell ? "shell" : p == LinerPart::lifter ? "lifter" : p == LinerPart::mesh ? "mesh" : "plate";
}

const char* face_name(int f) {
  return f == static_cast<int>(LifterFace::leading) ? "leading" : f == static_cast<int>(LifterFace::top) ? "top"
                                                                                                         : "trailing";
}

}  // namespace

void write_spectra_csv(const std::filesystem::path& path, const SpectraReport& r) {
  std::string t =
      "pair,bin,energy_from_J,energy_to_J,collisions_per_s,power_W,normal_W,tangential_W,rolling_W,"
      "mean_impact_speed_m_s,mean_contact_s,normal_spectrum_collisions_per_s,normal_spectrum_W,"
      "severity_from_J_per_m,severity_to_J_per_m,impact_collisions_per_s,impact_W,impact_r_eff_m,"
      "loss_collisions_per_s,loss_W,loss_r_eff_m\n";
  char line[768];
  for (const SpectraBin& b : r.bins) {
    const CollisionRates& q = b.rates;
    std::snprintf(line, sizeof line,
                  "%s,%d,%.6g,%.6g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%.9g,%.9g,%.6g,%.6g,%.9g,%.9g,%.9g,%.9g,%.9g,"
                  "%.9g\n",
                  q.pair.c_str(), b.bin, b.energy_from_J, b.energy_to_J, q.collisions_per_s, q.power_W, q.normal_W,
                  q.tangential_W, q.rolling_W, q.mean_impact_speed_m_s, q.mean_contact_s,
                  q.by_normal_collisions_per_s, q.by_normal_W, b.severity_from_J_m, b.severity_to_J_m,
                  q.impact_collisions_per_s, q.impact_W, q.impact_r_eff_m, q.loss_collisions_per_s, q.loss_W,
                  q.loss_r_eff_m);
    t += line;
  }
  write_file_atomic(path, t);
}

std::string element_name(const LinerLayout& layout, int e) {
  const LinerElement& el = layout.elements.at(e);
  char b[128];
  if (el.part == LinerPart::shell)
    std::snprintf(b, sizeof b, "shell between rows %d and %d, bin %d, axial %d", el.row,
                  layout.n_lifters > 0 ? (el.row + 1) % layout.n_lifters : el.row, el.bin, el.axial);
  else if (el.part == LinerPart::lifter)
    std::snprintf(b, sizeof b, "lifter row %d, %s face, axial %d", el.row, face_name(el.bin), el.axial);
  else if (el.part == LinerPart::mesh)
    std::snprintf(b, sizeof b, "mesh %d, triangle %d", el.row + 1, el.bin + 1);
  else
    std::snprintf(b, sizeof b, "end plate at z = %s, ring %d, sector %d", el.row == 0 ? "0" : "length", el.bin,
                  el.sector);
  return b;
}

// A wear volume rate (m³/s) over an area (m²) as a depth, mm per 1000 h.
static double depth_mm_per_1000h(double m3_per_s, double area_m2) { return area_m2 > 0 ? m3_per_s / area_m2 * 3.6e9 : 0.0; }

void write_wear_csv(const std::filesystem::path& path, const LinerLayout& layout, const LinerReport& r) {
  std::string t =
      "element,part,row,face_or_bin,sector,axial,theta_from_deg,theta_to_deg,z_from_m,z_to_m,r_from_m,r_to_m,"
      "area_m2,impacts_per_s,impact_W,shear_W,impact_W_per_m2,shear_W_per_m2,wear_mm_per_1000h,wear_kg_per_h,"
      "strike_W,sliding_wear_mm_per_1000h,impact_wear_mm_per_1000h\n";
  char line[768];
  for (std::size_t e = 0; e < layout.elements.size(); ++e) {
    const LinerElement& el = layout.elements[e];
    const LinerElementRates& x = r.elements.at(e);
    const std::string bin = el.part == LinerPart::lifter ? face_name(el.bin) : std::to_string(el.bin);
    std::snprintf(line, sizeof line,
                  "%zu,%s,%d,%s,%d,%d,%.4f,%.4f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,"
                  "%.6g\n",
                  e, part_name(el.part), el.row, bin.c_str(), el.sector, el.axial, el.theta0 * kDeg,
                  el.theta1 * kDeg, el.z0, el.z1, el.r0, el.r1, el.area_m2, x.impacts_per_s, x.impact_W, x.shear_W,
                  x.impact_W_m2, x.shear_W_m2, x.wear_mm_per_1000h, x.wear_kg_per_h, x.strike_W,
                  depth_mm_per_1000h(x.sliding_m3_per_s, el.area_m2), depth_mm_per_1000h(x.impact_m3_per_s, el.area_m2));
    t += line;
  }
  write_file_atomic(path, t);
}

void write_lifter_wear_csv(const std::filesystem::path& path, const std::vector<LifterStation>& stations,
                           const std::vector<std::vector<LifterStation>>& halves) {
  std::string t =
      "profile,station,x_mm,y_mm,length_mm,impacts_per_s,impact_W,shear_W,wear_m3_per_s,wear_mm_per_1000h,strike_W,"
      "sliding_wear_m3_per_s,impact_wear_m3_per_s,first_half_sliding_wear_m3_per_s,first_half_strike_W,"
      "second_half_sliding_wear_m3_per_s,second_half_strike_W\n";
  const bool split = halves.size() == 2 && halves[0].size() == stations.size() && halves[1].size() == stations.size();
  char line[640];
  for (std::size_t k = 0; k < stations.size(); ++k) {
    const LifterStation& s = stations[k];
    std::snprintf(line, sizeof line, "%d,%d,%.4f,%.4f,%.4f,%.6g,%.6g,%.6g,%.9g,%.6g,%.9g,%.9g,%.9g", s.profile,
                  s.station, s.x_m * 1000, s.y_m * 1000, s.length_m * 1000, s.impacts_per_s, s.impact_W, s.shear_W,
                  s.wear_m3_per_s, s.wear_mm_per_1000h, s.strike_W, s.sliding_m3_per_s, s.impact_m3_per_s);
    t += line;
    if (split)
      std::snprintf(line, sizeof line, ",%.9g,%.9g,%.9g,%.9g\n", halves[0][k].sliding_m3_per_s, halves[0][k].strike_W,
                    halves[1][k].sliding_m3_per_s, halves[1][k].strike_W);
    else
      std::snprintf(line, sizeof line, ",,,,\n");
    t += line;
  }
  write_file_atomic(path, t);
}

nlohmann::ordered_json spectra_json(const SpectraReport& r) {
  nlohmann::ordered_json j;
  j["window_s"] = num(r.window_s);
  j["total"] = rates_json(r.all);
  j["by_pair"] = nlohmann::json::array();
  for (const CollisionRates& c : r.types) j["by_pair"].push_back(rates_json(c));
  nlohmann::ordered_json b;
  b["closed_collisions_W"] = num(r.closed_W);
  b["open_contacts_change_W"] = num(r.open_change_W);
  b["unrecorded_W"] = num(r.unrecorded_W);
  b["spectra_W"] = num(r.books_W);
  b["dissipation_W"] = num(r.dissipation_W);
  b["difference"] = r.dissipation_W != 0 ? num((r.books_W - r.dissipation_W) / r.dissipation_W) : nlohmann::json();
  j["books"] = b;
  return j;
}

nlohmann::ordered_json liner_json(const LinerLayout& layout, const LinerReport& r, const Material& liner) {
  nlohmann::ordered_json j;
  j["window_s"] = num(r.window_s);
  j["elements"] = layout.size();
  j["wear_coefficient_m3_per_N_m"] = liner.wear_coefficient;
  j["impact_wear_coefficient_m3_per_J"] = liner.impact_wear_coefficient;
  j["impact_wear_threshold_speed_m_s"] = liner.impact_wear_threshold_speed;
  j["impacts_per_s"] = num(r.impacts_per_s);
  j["impact_power_W"] = num(r.impact_W);
  j["shear_power_W"] = num(r.shear_W);
  j["strike_power_W"] = num(r.strike_W);
  j["wear_kg_per_h"] = num(r.wear_kg_per_h);
  j["sliding_wear_kg_per_h"] = num(r.sliding_kg_per_h);
  j["impact_wear_kg_per_h"] = num(r.impact_kg_per_h);
  j["worst_wear_mm_per_1000h"] = num(r.worst_wear_mm_per_1000h);
  j["worst_element"] = r.worst_element >= 0 ? nlohmann::json(element_name(layout, r.worst_element)) : nlohmann::json();
  j["impact_point_deg"] = num(r.impact_point_deg);
  j["impact_point_on"] = std::isfinite(r.impact_point_deg) ? nlohmann::json(r.impact_point_on_liner ? "liner" : "toe")
                                                           : nlohmann::json();
  j["bare_liner_impact_power_W"] = num(r.bare_liner_impact_W);
  j["bare_liner_impact_share"] = num(r.bare_liner_impact_share);
  // Along the mill: each axial bin's span (m from z = 0: the shell's
  // elements', whose end bins reach into worn end plates), its impact power
  // on the shell and lifters and its impact point.
  nlohmann::json along = nlohmann::json::array();
  const std::size_t na = r.impact_point_deg_by_axial.size();
  for (std::size_t k = 0; k < na && k < r.impact_W_by_axial.size() && k < layout.elements.size(); ++k)
    along.push_back({{"z0_m", layout.elements[k].z0},
                     {"z1_m", layout.elements[k].z1},
                     {"impact_power_W", num(r.impact_W_by_axial[k])},
                     {"impact_point_deg", num(r.impact_point_deg_by_axial[k])}});
  j["impact_point_along"] = along;
  // The lab frame's impact power on the shell and lifters in 5 degree bins
  // from 3 o'clock, counter-clockwise (W each).
  nlohmann::json prof = nlohmann::json::array();
  for (std::size_t b = 0; b + 5 <= r.impact_W_per_deg.size(); b += 5) {
    double sum = 0;
    for (std::size_t k = b; k < b + 5; ++k) sum += r.impact_W_per_deg[k];
    prof.push_back(sum);
  }
  j["impact_W_by_5deg"] = prof;
  j["parts"] = nlohmann::json::array();
  for (const LinerPartRates& p : r.parts) {
    nlohmann::ordered_json q;
    q["part"] = p.name;
    q["area_m2"] = num(p.area_m2);
    q["impacts_per_s"] = num(p.impacts_per_s);
    q["impact_power_W"] = num(p.impact_W);
    q["shear_power_W"] = num(p.shear_W);
    q["wear_kg_per_h"] = num(p.wear_kg_per_h);
    q["strike_power_W"] = num(p.strike_W);
    q["sliding_wear_kg_per_h"] = num(p.sliding_kg_per_h);
    q["impact_wear_kg_per_h"] = num(p.impact_kg_per_h);
    q["mean_wear_mm_per_1000h"] = num(p.mean_wear_mm_per_1000h);
    q["worst_wear_mm_per_1000h"] = num(p.worst_wear_mm_per_1000h);
    j["parts"].push_back(q);
  }
  return j;
}

nlohmann::ordered_json per_metre_json(double length_m, double torque_power_W, double dissipation_power_W,
                                      double torque_Nm, const SpectraReport& spectra, const LinerReport& liner) {
  const double L = length_m > 0 ? length_m : std::nan("");
  nlohmann::ordered_json j;
  j["length_m"] = num(length_m);
  j["power_W"] = {{"torque", num(torque_power_W / L)}, {"dissipation", num(dissipation_power_W / L)}};
  j["torque_Nm"] = num(torque_Nm / L);
  j["collisions_per_s"] = num(spectra.all.collisions_per_s / L);
  j["collision_power_W"] = num(spectra.all.power_W / L);
  j["liner_impact_power_W"] = num(liner.impact_W / L);
  j["liner_shear_power_W"] = num(liner.shear_W / L);
  j["shell_lifters_wear_kg_per_h"] = num(shell_lifters_wear_kg_per_h(liner) / L);  // what scales with the length
  // The parts' power per metre: a whole mill's end plates against its
  // shell and lifters (a slice has no end plates).
  j["parts"] = nlohmann::json::array();
  for (const LinerPartRates& p : liner.parts) {
    nlohmann::ordered_json q;
    q["part"] = p.name;
    q["impact_power_W"] = num(p.impact_W / L);
    q["shear_power_W"] = num(p.shear_W / L);
    q["wear_kg_per_h"] = num(p.wear_kg_per_h / L);
    j["parts"].push_back(q);
  }
  return j;
}

void write_spectra_png(const std::filesystem::path& path, const std::string& title, const SpectraReport& r) {
  static const std::uint32_t colours[] = {0x1f77b4, 0xd62728, 0x2ca02c, 0xff7f0e, 0x9467bd, 0x8c564b, 0xe377c2, 0x17becf};
  LinePlot cumulative, rate;
  cumulative.title = title + ": where the collisions' power lies";
  cumulative.x_label = "energy lost per collision (J)";
  cumulative.y_label = "power of collisions up to it (W)";
  rate.title = "collisions per second in each bin (10 a decade)";
  rate.x_label = "energy lost per collision (J)";
  rate.y_label = "collisions per second";
  cumulative.log_x = rate.log_x = true;
  auto add = [&](const std::string& name, std::uint32_t rgb, auto keep) {
    PlotSeries c{name, {}, {}, rgb}, q{name, {}, {}, rgb};
    double sum = 0, first = -1, last = -1;
    for (const SpectraBin& b : r.bins) {
      if (!keep(b) || b.bin == 0 || b.bin == MC_SPECTRA_BINS - 1) continue;
      sum += b.rates.power_W;
      c.x.push_back(b.energy_to_J);
      c.y.push_back(sum);
      q.x.push_back(std::sqrt(b.energy_from_J * b.energy_to_J));
      q.y.push_back(b.rates.collisions_per_s);
      if (b.rates.collisions_per_s > 0) {
        if (first < 0) first = static_cast<double>(c.x.size() - 1);
        last = static_cast<double>(c.x.size() - 1);
      }
    }
    if (first < 0) return;
    // From a bin below the first collisions to the last's top.
    const std::size_t from = static_cast<std::size_t>(std::max(0.0, first - 1)), to = static_cast<std::size_t>(last) + 1;
    auto cut = [&](std::vector<double>& v) { v = std::vector<double>(v.begin() + from, v.begin() + std::min(to, v.size())); };
    for (auto* v : {&c.x, &c.y, &q.x, &q.y}) cut(*v);
    cumulative.series.push_back(c);
    rate.series.push_back(q);
  };
  std::size_t k = 0;
  for (const CollisionRates& t : r.types) {
    if (t.collisions_per_s <= 0) continue;
    add(t.pair, colours[k++ % 8], [&](const SpectraBin& b) { return b.rates.pair == t.pair; });
  }
  // All types together, over the span of the types' lines.
  if (cumulative.series.size() > 1) {
    std::vector<double> power(MC_SPECTRA_BINS, 0.0), top(MC_SPECTRA_BINS, 0.0);
    for (const SpectraBin& b : r.bins) power[b.bin] += b.rates.power_W, top[b.bin] = b.energy_to_J;
    double lo = INFINITY, hi = -INFINITY;
    for (const PlotSeries& p : cumulative.series) lo = std::min(lo, p.x.front()), hi = std::max(hi, p.x.back());
    PlotSeries all{"all", {}, {}, 0x222222};
    double acc = 0;
    for (int b = 1; b + 1 < MC_SPECTRA_BINS; ++b) {
      acc += power[b];
      if (top[b] >= lo && top[b] <= hi) all.x.push_back(top[b]), all.y.push_back(acc);
    }
    cumulative.series.push_back(all);
  }
  write_line_plots_png(path, {cumulative, rate});
}

void write_liner_png(const std::filesystem::path& path, const std::string& title, const LinerLayout& layout,
                     const LinerReport& r, bool relative) {
  // Over whole revolutions every row of a steady mill sees the same cycle,
  // so the map is one repeat of the lifter pattern (rows whose bars cover
  // the same arc of shell), averaged over its repeats: x the angle from
  // the first row's centre, y the axial position.
  const int nl = layout.n_lifters;
  int period = 1;
  if (nl > 0) {
    for (period = 1; period < nl; ++period) {
      if (nl % period != 0) continue;
      bool repeats = true;
      for (int k = 0; k < nl && repeats; ++k)
        repeats = std::fabs(layout.lifter_lead_angle[k] - layout.lifter_lead_angle[(k + period) % nl]) < 1e-9 &&
                  std::fabs(layout.lifter_trail_angle[k] - layout.lifter_trail_angle[(k + period) % nl]) < 1e-9;
      if (repeats) break;
    }
  }
  const double spacing = nl > 0 ? 360.0 / nl : 360.0;
  const int repeats = nl > 0 ? nl / period : 1;
  HeatMap impact, wear, sliding, by_impact;
  // With impact wear, the sum and each wear alone.
  const bool both = r.impact_kg_per_h > 0;
  const std::string rel = relative ? " (relative: wear coefficient not calibrated)" : "";
  impact.title = title + ": impact power on the liner";
  wear.title = (both ? "wear rate, sliding + impact" : "wear rate") + rel;
  sliding.title = "sliding wear (Archard)" + rel;
  by_impact.title = "impact wear (Bitter's deformation wear)" + rel;
  impact.unit = "W/m\u00b2";
  wear.unit = sliding.unit = by_impact.unit = "mm/1000 h";
  for (HeatMap* m : {&impact, &wear, &sliding, &by_impact}) {
    m->x_label = nl > 0 ? "degrees from a lifter row's centre, counter-clockwise (rows outlined: trailing | top | leading "
                          "face), averaged over the " + std::to_string(repeats) + " repeats of the pattern"
                        : "angle in the mill frame (deg, counter-clockwise)";
    m->y_label = "axial position (m)";
    m->x_lo = nl > 0 ? -layout.lifter_trail_angle[0] * kDeg : 0;
    m->x_hi = m->x_lo + period * spacing;
    // (the end bins reach into worn end plates' dish: core/liner.cpp)
    m->y_lo = 0;
    m->y_hi = layout.length > 0 ? layout.length : 1;
    for (const LinerElement& e : layout.elements)
      if (e.part == LinerPart::shell || e.part == LinerPart::lifter)
        m->y_lo = std::min(m->y_lo, e.z0), m->y_hi = std::max(m->y_hi, e.z1);
  }
  // Cells by (row in the pattern, part, bin, axial): the mean over repeats.
  struct Cell {
    double x0, x1, z0, z1, impact = 0, wear = 0, sliding = 0, by_impact = 0;
    bool outline;
    int count = 0;
  };
  std::map<std::array<int, 4>, Cell> cells;
  for (int e = 0; e < layout.size(); ++e) {
    const LinerElement& el = layout.elements[e];
    if (el.part == LinerPart::plate || el.part == LinerPart::mesh) continue;
    const int row = nl > 0 ? el.row % period : 0;
    const double base = nl > 0 ? (layout.lifter_centre[el.row] - layout.lifter_centre[0]) * kDeg - spacing * (el.row - row)
                               : 0;  // the pattern's first row at 0
    double x0, x1;
    if (el.part == LinerPart::shell) {
      x0 = el.theta0 * kDeg - (nl > 0 ? layout.lifter_centre[el.row] * kDeg : 0) + base;
      x1 = x0 + (el.theta1 - el.theta0) * kDeg;
    } else {  // the bar's width on the shell in three: trailing, top, leading
      // From its trailing foot to its leading one, as the shell cells meet it.
      const double trail = layout.lifter_trail_angle[el.row] * kDeg, lead = layout.lifter_lead_angle[el.row] * kDeg;
      const int third = el.bin == static_cast<int>(LifterFace::trailing) ? 0
                        : el.bin == static_cast<int>(LifterFace::top)    ? 1
                                                                          : 2;
      x0 = base - trail + (lead + trail) * third / 3;
      x1 = base - trail + (lead + trail) * (third + 1) / 3;
    }
    Cell& c = cells[{row, static_cast<int>(el.part), el.bin, el.axial}];
    c.x0 = x0, c.x1 = x1, c.z0 = el.z0, c.z1 = layout.length > 0 ? el.z1 : 1;
    c.outline = el.part == LinerPart::lifter;
    c.impact += r.elements.at(e).impact_W_m2;
    c.wear += r.elements.at(e).wear_mm_per_1000h;
    c.sliding += depth_mm_per_1000h(r.elements.at(e).sliding_m3_per_s, el.area_m2);
    c.by_impact += depth_mm_per_1000h(r.elements.at(e).impact_m3_per_s, el.area_m2);
    ++c.count;
  }
  for (const auto& [key, c] : cells) {
    impact.cells.push_back({c.x0, c.x1, c.z0, c.z1, c.impact / c.count, c.outline});
    wear.cells.push_back({c.x0, c.x1, c.z0, c.z1, c.wear / c.count, c.outline});
    sliding.cells.push_back({c.x0, c.x1, c.z0, c.z1, c.sliding / c.count, c.outline});
    by_impact.cells.push_back({c.x0, c.x1, c.z0, c.z1, c.by_impact / c.count, c.outline});
  }
  // Where the liner is struck, in the lab frame: impact power per degree.
  // The colour is the impact power of each degree (grey: none); the curve
  // on the y axis is the share of that degree's liner under the charge.
  HeatMap strike;
  strike.title = "impact power on the shell and lifters per degree, lab frame (grey: no impacts)";
  strike.unit = "W/deg";
  strike.x_label = "degrees counter-clockwise from 3 o'clock (the mill turns counter-clockwise)";
  strike.y_label = "contact / peak";
  strike.x_lo = 0;
  strike.x_hi = 360;
  strike.y_lo = 0;
  strike.y_hi = 1;
  const std::size_t nb = r.impact_W_per_deg.size();
  for (std::size_t b = 0; b < nb; ++b)
    strike.cells.push_back({b * 360.0 / nb, (b + 1) * 360.0 / nb, 0, 1, r.impact_W_per_deg[b], false});
  for (std::size_t b = 0; b < r.coverage.size(); ++b)
    strike.curve.push_back({(b + 0.5) * 360.0 / r.coverage.size(), r.coverage[b]});
  strike.curve_label = "curve: the charge's contact with the liner, over its most-contacted degree";
  if (std::isfinite(r.impact_point_deg)) {
    char s[96];
    std::snprintf(s, sizeof s, "impact point %.0f, %.0f %% on bare liner", r.impact_point_deg,
                  100 * r.bare_liner_impact_share);
    strike.marks_x.push_back({r.impact_point_deg, s, 0xc51b8a});
  }
  // charge.png's colours, and the viewer's: toe red, shoulder orange,
  // impact magenta.
  strike.marks_x.push_back({r.shoulder_deg, "shoulder", 0xe6700a});
  strike.marks_x.push_back({r.toe_deg, "toe", 0xd62728});
  BarChart bars;
  bars.title = relative ? "mean wear rate of each part (mm per 1000 h, relative: not calibrated)"
                       : "mean wear rate of each part (mm per 1000 h)";
  for (const LinerPartRates& p : r.parts) bars.bars.push_back({p.name, p.mean_wear_mm_per_1000h});
  if (both) write_heat_maps_png(path, {impact, wear, sliding, by_impact, strike}, bars);
  else write_heat_maps_png(path, {impact, wear, strike}, bars);
}

PolyMesh liner_mesh(const LinerLayout& layout, const LinerReport* r, double mill_angle, double time_s) {
  PolyMesh m;
  m.time_s = time_s;
  const double c = std::cos(mill_angle), s = std::sin(mill_angle);
  const std::size_t n = layout.elements.size();
  std::vector<float> impact(n, 0), shear(n, 0), wear(n, 0), impacts(n, 0), kgh(n, 0), area(n, 0);
  std::vector<float> sliding(n, 0), by_impact(n, 0);
  std::vector<int> part(n), row(n), bin(n);
  for (std::size_t e = 0; e < n; ++e) {
    const LinerElement& el = layout.elements[e];
    std::vector<int> poly;
    const double ce = el.still ? 1.0 : c, se = el.still ? 0.0 : s;  // a still mesh is in the lab frame
    for (const Vec3& p : el.outline) {
      poly.push_back(static_cast<int>(m.points.size()));
      m.points.push_back({static_cast<float>(ce * p.x - se * p.y), static_cast<float>(se * p.x + ce * p.y),
                          static_cast<float>(p.z)});
    }
    m.polygons.push_back(poly);
    if (r) {
      const LinerElementRates& x = r->elements.at(e);
      impact[e] = static_cast<float>(x.impact_W_m2);
      shear[e] = static_cast<float>(x.shear_W_m2);
      wear[e] = static_cast<float>(x.wear_mm_per_1000h);
      impacts[e] = static_cast<float>(x.impacts_per_s);
      kgh[e] = static_cast<float>(x.wear_kg_per_h);
      sliding[e] = static_cast<float>(depth_mm_per_1000h(x.sliding_m3_per_s, el.area_m2));
      by_impact[e] = static_cast<float>(depth_mm_per_1000h(x.impact_m3_per_s, el.area_m2));
    }
    area[e] = static_cast<float>(el.area_m2);
    part[e] = static_cast<int>(el.part);
    row[e] = el.row;
    bin[e] = el.bin;
  }
  m.cell_floats = {{"impact_power_W_per_m2", impact}, {"shear_power_W_per_m2", shear},
                   {"wear_mm_per_1000h", wear},       {"impacts_per_s", impacts},
                   {"wear_kg_per_h", kgh},            {"area_m2", area},
                   {"sliding_wear_mm_per_1000h", sliding}, {"impact_wear_mm_per_1000h", by_impact}};
  m.cell_ints = {{"part", part}, {"row", row}, {"face_or_bin", bin}};
  return m;
}

}  // namespace mc::io
