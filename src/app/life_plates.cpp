#include "app/life_plates.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "core/liner_wear.h"
#include "core/plate_wear.h"
#include "io/atomic_file.h"
#include "io/csv_read.h"
#include "io/png_plot.h"

namespace mc::app::life {

namespace fs = std::filesystem;
using nlohmann::json;
using mc::life::PlateBooks;

PlateBooks read_plate_books(const fs::path& wear_csv, int rings, int sectors) {
  const io::CsvTable t = io::read_csv_strict(wear_csv, "the stage's run wrote no liner wear");
  const int c_part = t.column("part"), c_row = t.column("row"), c_bin = t.column("face_or_bin"),
            c_sec = t.column("sector"), c_area = t.column("area_m2"), c_sl = t.column("sliding_wear_mm_per_1000h"),
            c_st = t.column("strike_W");
  PlateBooks b;
  for (int p = 0; p < 2; ++p) {
    b.sliding_m3_s[p].assign(rings, std::vector<double>(sectors, NAN));
    b.strike_W[p].assign(rings, std::vector<double>(sectors, NAN));
  }
  int found = 0;
  for (std::size_t k = 0; k < t.rows.size(); ++k) {
    if (t.rows[k][c_part] != "plate") continue;
    const double p = t.number(k, c_row), ring = t.number(k, c_bin), sec = t.number(k, c_sec);
    auto whole_below = [](double v, int n) { return v >= 0 && v < n && v == std::floor(v); };
    if (!(whole_below(p, 2) && whole_below(ring, rings) && whole_below(sec, sectors)))
      throw std::invalid_argument(fmt::format("{}: plate {}, ring {}, sector {} is not one of this case's ({} rings, {} "
                                              "sectors; liner.plate_rings, liner.plate_sectors)",
                                              t.where(k), t.rows[k][c_row], t.rows[k][c_bin], t.rows[k][c_sec], rings,
                                              sectors));
    const int pi = static_cast<int>(p), ri = static_cast<int>(ring), si = static_cast<int>(sec);
    if (!std::isnan(b.strike_W[pi][ri][si]))
      throw std::invalid_argument(fmt::format("{}: plate {}, ring {}, sector {} booked twice", t.where(k), pi, ri, si));
    const double area = t.number(k, c_area), sl = t.number(k, c_sl), st = t.number(k, c_st);
    for (const auto& [v, col] : {std::pair{area, c_area}, std::pair{sl, c_sl}, std::pair{st, c_st}})
      if (!(std::isfinite(v) && v >= 0))
        throw std::invalid_argument(t.where(k) + ": " + t.header[col] + " " + t.rows[k][col] +
                                    " is not finite and >= 0; the file is damaged");
    b.sliding_m3_s[pi][ri][si] = sl * area / 3.6e9;  // mm per 1000 h over the area: m³/s
    b.strike_W[pi][ri][si] = st;
    ++found;
  }
  if (found != 2 * rings * sectors)
    throw std::invalid_argument(fmt::format("{}: {} end-plate rows where the case's two plates have {} rings of {} "
                                            "sectors",
                                            wear_csv.string(), found, rings, sectors));
  return b;
}

double bar_length(const Stage& s, double length) { return length + plate_depth_at_shell(s.plate_depth_m); }

json plate_books_json(const PlateBooks& b) {
  return {{"plate_sliding_wear_m3_per_s", b.sliding_m3_s}, {"plate_strike_W", b.strike_W}};
}

PlateBooks plate_books_of(const io::JsonAt& sliding, const io::JsonAt& strike, int rings, int sectors) {
  PlateBooks b;
  for (const auto& [a, into] : {std::pair{sliding, &b.sliding_m3_s}, std::pair{strike, &b.strike_W}}) {
    a.size(2, "end plates");
    for (std::size_t p = 0; p < 2; ++p) {
      a[p].size(rings, "rings (liner.plate_rings)");
      for (int r = 0; r < rings; ++r) {
        (*into)[p].push_back(a[p][r].numbers(sectors, "sectors (liner.plate_sectors)"));
        for (int s = 0; s < sectors; ++s)
          if ((*into)[p][r][s] < 0) a[p][r][s].fail("below 0");
      }
    }
  }
  return b;
}

std::array<std::vector<double>, 2> plate_rows_of(const io::JsonAt& a, int rings, double scale) {
  std::array<std::vector<double>, 2> out;
  a.size(2, "end plates");
  for (std::size_t p = 0; p < 2; ++p) {
    out[p] = a[p].numbers(rings, "rings (liner.plate_rings)");
    for (int r = 0; r < rings; ++r) {
      if (out[p][r] < 0) a[p][r].fail("below 0");
      out[p][r] *= scale;
    }
  }
  return out;
}

json plate_rows_json(const std::array<std::vector<double>, 2>& v, double scale) {
  json j = json::array();
  for (const auto& row : v) {
    json r = json::array();
    for (double x : row) r.push_back(x * scale);
    j.push_back(r);
  }
  return j;
}

void write_plate_table(const fs::path& out, const std::vector<Stage>& stages, const PlateTableBasis& b) {
  std::string t =
      "stage,hours,case_hours,plate,plate_z_m,ring,r_from_mm,r_to_mm,depth_mm,mean_depth_mm,wear_mm_per_1000h,"
      "wear_mm_per_1000h_se,step_booked_cm3,step_removed_cm3,wear_basis\n";
  for (const Stage& s : stages) {
    if (!s.ran || s.plate_depth_m[0].empty()) break;
    const double R = 0.5 * s.diameter;
    const int rings = static_cast<int>(s.plate_depth_m[0].size());
    const mc::life::PlateRates rates = mc::life::plate_rates(s.r.plates, b.mix.sliding, b.mix.impact, R);
    const bool step = !s.plate_booked_m3[0].empty();
    for (int p = 0; p < 2; ++p) {
      const std::vector<double> mean = plate_ring_means(s.plate_depth_m[p], R / rings);
      for (int j = 0; j < rings; ++j)
        t += fmt::format("{},{:.6g},{:.6g},{},{:g},{},{:.3f},{:.3f},{:.4f},{:.4f},{:.6g},{},{},{},{}\n", s.index,
                         s.case_hours / b.factor, s.case_hours, p, p == 0 ? 0.0 : b.length, j, 1e3 * R * j / rings,
                         1e3 * R * (j + 1) / rings, s.plate_depth_m[p][j] * 1e3, mean[j] * 1e3,
                         rates.m_per_h[p][j] * 1e6 * b.factor,
                         std::isfinite(rates.se_m_per_h[p][j]) ? fmt::format("{:.4g}", rates.se_m_per_h[p][j] * 1e6 * b.factor)
                                                               : std::string(),
                         step ? fmt::format("{:.6g}", s.plate_booked_m3[p][j] * 1e6) : "",
                         step ? fmt::format("{:.6g}", s.plate_removed_m3[p][j] * 1e6) : "", b.basis);
    }
  }
  io::write_file_atomic(out / "life_plates.csv", t);
}

void write_plate_picture(const fs::path& file, const std::string& title, const std::vector<Stage>& stages,
                         const PlateTableBasis& b, bool relative) {
  std::vector<io::LinePlot> plots(2);
  const std::uint32_t colours[] = {0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd, 0x8c564b, 0xe377c2, 0x7f7f7f,
                                   0xbcbd22, 0x17becf};
  for (int p = 0; p < 2; ++p) {
    io::LinePlot& lp = plots[p];
    lp.title = fmt::format("{}: the end plate at z = {:g} m, its face as the stages ran on it", title,
                           p == 0 ? 0.0 : b.length);
    lp.x_label = "distance from the axis, mm (dots: each ring's mean depth, the metal it lost over its area)";
    lp.y_label = "face, mm behind the new plate";
    lp.y_cover_hi = 0;
    int n = 0;
    for (const Stage& s : stages) {
      if (!s.ran || s.plate_depth_m[p].empty()) break;
      const double R = 0.5 * s.diameter;
      const int rings = static_cast<int>(s.plate_depth_m[p].size());
      // The face the kernels touch (core/plate_wear.h), by its corners.
      const std::vector<double>& d = s.plate_depth_m[p];
      const std::vector<double> mean = plate_ring_means(d, R / rings);
      io::PlotSeries face, means;
      face.label = fmt::format("{:.0f} h{}", s.case_hours / b.factor, relative ? " (relative)" : "");
      face.rgb = means.rgb = colours[n++ % 10];
      face.x.push_back(0), face.y.push_back(-d.front() * 1e3);
      for (int j = 0; j < rings; ++j) {
        const double w = R / rings;
        if (j > 0) face.x.push_back(1e3 * w * (j + 0.25)), face.y.push_back(-d[j] * 1e3);
        if (j + 1 < rings) face.x.push_back(1e3 * w * (j + 0.75)), face.y.push_back(-d[j] * 1e3);
        // The rings' mean depths as dots: NaN between them breaks the line.
        means.x.push_back(1e3 * w * (j + 0.5)), means.y.push_back(-mean[j] * 1e3);
        means.x.push_back(NAN), means.y.push_back(NAN);
      }
      face.x.push_back(1e3 * R), face.y.push_back(-d.back() * 1e3);
      means.markers = true;
      lp.series.push_back(face);
      lp.series.push_back(means);
    }
  }
  io::write_line_plots_png(file, plots);
}

}  // namespace mc::app::life
