// life.png's panels (life_picture.h).
#include "app/life_picture.h"

#include "app/life_plates.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <nlohmann/json.hpp>

#include "core/lifters.h"
#include "core/liner_wear.h"
#include "core/scene.h"
#include "io/csv_read.h"
#include "io/json_read.h"

namespace mc::app::life {

namespace {

// A panel's y axis covers at least `half` either side of its values' middle,
// so that a change smaller than that does not fill the panel.
void at_least(io::LinePlot& p, double half) {
  double lo = INFINITY, hi = -INFINITY;
  for (const io::PlotSeries& s : p.series)
    for (double v : s.y)
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!(lo <= hi)) return;
  const double mid = 0.5 * (lo + hi);
  p.y_cover_lo = std::min(lo, mid - half);
  p.y_cover_hi = std::max(hi, mid + half);
}


std::uint32_t ramp(double t) {  // blue (new) to red (worn)
  const auto mix = [&](int a, int b) { return static_cast<std::uint32_t>(std::lround(a + (b - a) * t)); };
  return (mix(0x1f, 0xd6) << 16) | (mix(0x77, 0x27) << 8) | mix(0xb4, 0x28);
}

// A colour per lifter profile (its height, its faces, its top's wear).
std::uint32_t profile_colour(int k, int shade) {
  static const std::uint32_t dark[] = {0x1f77b4, 0x2ca02c, 0x9467bd, 0x8c564b};
  static const std::uint32_t light[] = {0xd62728, 0xff7f0e, 0xe377c2, 0x17becf};
  return shade == 0 ? dark[k % 4] : light[k % 4];
}

// "a / b / c" of each profile's measure, to `digits` decimals.
template <class F>
std::string per_profile(const Stage& s, int digits, F measure) {
  std::string t;
  for (std::size_t k = 0; k < s.outlines.size(); ++k)
    t += (k ? " / " : "") + fmt::format("{:.{}f}", measure(measure_profile(s.outlines[k])), digits);
  return t;
}

// The stages whose profiles are drawn: all up to kProfilesDrawn, else the
// first, the last and evenly between.
std::vector<const Stage*> drawn_of(const std::vector<const Stage*>& ran) {
  const int n = static_cast<int>(ran.size());
  if (n <= kProfilesDrawn) return ran;
  std::vector<const Stage*> out;
  for (int q = 0; q < kProfilesDrawn; ++q) {
    const int i = static_cast<int>(std::lround(static_cast<double>(q) * (n - 1) / (kProfilesDrawn - 1)));
    if (out.empty() || out.back() != ran[i]) out.push_back(ran[i]);
  }
  return out;
}

io::LinePlot profiles_plot(const std::string& name, const std::vector<const Stage*>& ran, const LifeAxis& axis) {
  const std::vector<const Stage*> drawn = drawn_of(ran);
  const int kinds = static_cast<int>(ran.front()->outlines.size());
  io::LinePlot prof;
  prof.title = name + ": lifter profiles from new (blue) to worn (red), each on its own worn shell" +
               (drawn.size() < ran.size() ? fmt::format(" ({} of {} stages)", drawn.size(), ran.size()) : "");
  prof.x_label = kinds > 1 ? "along the shell (mm), leading face to the right; profiles 0 to " +
                                 std::to_string(kinds - 1) + " left to right"
                           : "along the shell (mm), leading face to the right";
  prof.y_label = "height above the shell (mm)";
  prof.equal_aspect = true;
  const bool many = kinds > 1;
  double x_shift = 0;
  for (int k = 0; k < kinds; ++k) {
    double widest = 0;
    for (const Stage* s : drawn) {
      io::PlotSeries ser;
      const double t = drawn.size() > 1 ? static_cast<double>(s->index - drawn.front()->index) /
                                              (drawn.back()->index - drawn.front()->index)
                                        : 0.0;
      ser.rgb = ramp(t);
      // The bar's own frame: y from the tangent of the stage's (worn) shell
      // under its centre, so that its top stands at the height measured.
      for (const Vec2& v : s->outlines[k]) {
        ser.x.push_back(v.x * 1000 + x_shift);
        ser.y.push_back(v.y * 1000);
        widest = std::max(widest, std::fabs(v.x) * 1000);
      }
      if (k == 0)  // one entry per stage: its colour is all its profiles'
        ser.label = fmt::format("{:.0f} h{}: {} mm high, face {} deg{}", s->case_hours / axis.factor,
                                axis.relative ? " (relative)" : "",
                                per_profile(*s, 1, [](const ProfileMeasures& m) { return m.height * 1000; }),
                                per_profile(*s, 1, [](const ProfileMeasures& m) { return m.leading_angle_deg; }),
                                s->shell_wear_m > 0 ? fmt::format(", shell worn {:.1f} mm", s->shell_wear_m * 1000) : "");
      prof.series.push_back(ser);
    }
    // The shell under the bar (the worn one's radius; each stage's shell
    // touches the same line under the bar's centre).
    io::PlotSeries arc;
    arc.rgb = 0x7f7f7f;
    arc.dashed = true;
    const double R = 0.5 * drawn.back()->diameter * 1000, w = 1.2 * widest;
    for (int q = 0; q <= 40; ++q) {
      const double x = -w + 2 * w * q / 40;
      arc.x.push_back(x + x_shift);
      arc.y.push_back(R - std::sqrt(std::max(0.0, R * R - x * x)));  // it rises towards the axis off the centre line
    }
    if (k == 0) arc.label = many ? "the shell under each bar" : "the shell under the bar";
    prof.series.push_back(arc);
    x_shift += 2.4 * widest;
  }
  return prof;
}

}  // namespace

std::string hours_label(bool relative) {
  return relative ? std::string("hours (") + kWearRelative + ")" : "operating hours";
}

std::vector<io::LinePlot> life_plots(const std::string& name, const std::vector<Stage>& stages, const LifeAxis& axis) {
  std::vector<const Stage*> ran;
  for (const Stage& s : stages)
    if (s.ran) ran.push_back(&s);
  std::vector<io::LinePlot> plots;
  if (ran.empty()) return plots;
  const int kinds = static_cast<int>(ran.front()->outlines.size());
  plots.push_back(profiles_plot(name, ran, axis));

  auto over_hours = [&](const std::string& title, const std::string& y_label) {
    io::LinePlot p;
    p.title = name + ": " + title;
    p.x_label = hours_label(axis.relative);
    p.y_label = y_label;
    p.pad_x = true;
    return p;
  };
  auto series = [&](const std::string& label, std::uint32_t rgb, auto value) {
    io::PlotSeries s;
    s.label = label;
    s.rgb = rgb;
    s.markers = true;
    for (const Stage* x : ran) {
      s.x.push_back(x->case_hours / axis.factor);
      s.y.push_back(value(*x));
    }
    return s;
  };
  auto named = [&](const std::string& what, int k) {
    return kinds > 1 ? what + " (profile " + std::to_string(k) + ")" : what;
  };

  // The power: its axis at least ±5 % of the mean, so that the noise of a
  // stage's window (a percent or so) does not fill the panel.
  io::LinePlot power = over_hours("power draw", "power (W), axis at least \u00b15 % of mean");
  double mean = 0;
  bool any_se = false;
  for (const Stage* s : ran) {
    mean += s->r.power_W / ran.size();
    any_se = any_se || (std::isfinite(s->r.power_sem_W) && s->r.power_sem_W > 0);
  }
  power.y_cover_lo = 0.95 * mean, power.y_cover_hi = 1.05 * mean;
  power.series.push_back(series("torque power", 0x1f77b4, [](const Stage& s) { return s.r.power_W; }));
  if (any_se) {  // a band only where a stage has a standard error; one legend entry for both edges
    power.series.push_back(series("\u00b1 2 standard errors", 0x9ecae1, [](const Stage& s) { return s.r.power_W + 2 * s.r.power_sem_W; }));
    power.series.back().dashed = true;
    power.series.push_back(series("", 0x9ecae1, [](const Stage& s) { return s.r.power_W - 2 * s.r.power_sem_W; }));
    power.series.back().dashed = true;
  }
  plots.push_back(power);

  io::LinePlot low = over_hours("where the charge lands", "angle (deg, from 3 o'clock)");
  low.series.push_back(series("toe", 0x9467bd, [](const Stage& s) { return s.r.toe_deg; }));
  low.series.push_back(series("impact point", 0xd62728, [](const Stage& s) { return s.r.impact_deg; }));
  at_least(low, 5);
  plots.push_back(low);
  io::LinePlot high = over_hours("where the charge leaves the shell", "angle (deg, from 3 o'clock)");
  high.series.push_back(series("shoulder", 0x2ca02c, [](const Stage& s) { return s.r.shoulder_deg; }));
  at_least(high, 5);
  plots.push_back(high);

  io::LinePlot height = over_hours("the lifters' height (bands: \u00b1 2 standard errors of the wear's noise)",
                                   "height above the shell (mm)");
  io::LinePlot faces = over_hours("the lifters' face angles (bands: \u00b1 2 standard errors)",
                                  "face angle from the radial line (deg)");
  const std::vector<StageSe> errors = cumulative_se(stages);
  // A line and its band of ± 2 standard errors (from the halves of each
  // stage's window, added up over the stages before).
  auto with_band = [&](io::PlotSeries s, auto se_of) {
    for (std::size_t i = 0; i < ran.size() && i < s.y.size(); ++i) {
      const double e = 2 * se_of(errors[ran[i]->index]);
      s.band_lo.push_back(s.y[i] - e), s.band_hi.push_back(s.y[i] + e);
    }
    return s;
  };
  for (int k = 0; k < kinds; ++k) {
    height.series.push_back(with_band(series(named("height", k), profile_colour(k, 0), [k](const Stage& s) {
      return measure_profile(s.outlines[k]).height * 1000;
    }), [k](const StageSe& e) { return e.height_mm[k]; }));
    faces.series.push_back(with_band(series(named("leading face", k), profile_colour(k, 1), [k](const Stage& s) {
      return measure_profile(s.outlines[k]).leading_angle_deg;
    }), [k](const StageSe& e) { return e.leading_deg[k]; }));
    faces.series.push_back(with_band(series(named("trailing face", k), profile_colour(k, 0), [k](const Stage& s) {
      return measure_profile(s.outlines[k]).trailing_angle_deg;
    }), [k](const StageSe& e) { return e.trailing_deg[k]; }));
  }
  // The height from the shell up (a few mm lost shows as a few mm), the
  // angles over at least 10 deg.
  height.y_cover_lo = 0;
  at_least(faces, 5);
  plots.push_back(height);
  plots.push_back(faces);

  // The reline criteria of docs/liner-life.md beside the bars' height: how
  // much of the charge's impact lands on bare liner, and how fast the bars'
  // tops and the shell wear.
  io::LinePlot bare = over_hours("reline criterion: impact power on bare liner (not on the toe)",
                                 "share of the liner's impact power (%)");
  bare.y_cover_lo = 0, bare.y_cover_hi = 100;
  bare.series.push_back(series("on bare liner", 0xd62728, [](const Stage& s) { return 100 * s.r.bare_share; }));
  plots.push_back(bare);
  io::LinePlot rate = over_hours("reline criterion: wear rate",
                                 axis.relative ? "mm per 1000 h (relative)" : "mm per 1000 operating hours");
  rate.y_cover_lo = 0;
  // (the bars' wear stations: none where the bars are a mesh)
  for (int k = 0; k < kinds && k < static_cast<int>(ran.front()->r.station_m3_s.size()); ++k)
    rate.series.push_back(series(named("lifter top", k), profile_colour(k, 0), [&axis, k](const Stage& s) {
      const BarWearRates r{s.r.station_m3_s[k], bar_length(s, axis.length)};
      return top_wear_m_per_h(s.outlines[k], 0.5 * s.diameter, r) * 1e6 * axis.factor;
    }));
  rate.series.push_back(series("shell (mean)", 0x7f7f7f, [&axis](const Stage& s) {
    return s.r.shell_mm_per_1000h * axis.factor;
  }));
  plots.push_back(rate);
  return plots;
}

std::vector<io::LinePlot> along_plots(const std::string& name, const std::filesystem::path& out, bool relative) {
  std::vector<io::LinePlot> plots;
  const std::filesystem::path table = out / "life_segments.csv";
  if (!std::filesystem::exists(table)) return plots;
  const io::CsvTable t = io::read_csv_strict(table);
  const int c_stage = t.column("stage"), c_hours = t.column("hours"), c_mesh = t.column("mesh");
  const int c_seg = t.column("segment"), c_bars = t.column("bars"), c_z0 = t.column("z_from_m"),
            c_z1 = t.column("z_to_m");
  // An empty field (a figure that could not be measured) is NaN, which
  // breaks a line or a band.
  auto num = [&](std::size_t r, int c) { return t.rows[r][c].empty() ? NAN : std::stod(t.rows[r][c]); };
  // (a bin's end at -0 or a rounding below zero is printed 0)
  auto span_label = [](double z0, double z1) {
    auto tidy = [](double z) { return std::abs(z) < 1e-9 ? 0.0 : z; };
    return fmt::format("{:.3g} to {:.3g} m", tidy(z0), tidy(z1));
  };
  // The bars per (mesh, segment): a line each, blue at z = 0 to red at the
  // far end; meshes without bars (a shell) left out.
  struct Key {
    int mesh, segment;
    bool operator<(const Key& o) const { return mesh != o.mesh ? mesh < o.mesh : segment < o.segment; }
  };
  std::map<Key, std::size_t> first_row;
  int segments = 0;
  std::set<int> meshes;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    if (!(num(r, c_bars) > 0)) continue;
    const Key k{static_cast<int>(num(r, c_mesh)), static_cast<int>(num(r, c_seg))};
    first_row.try_emplace(k, r);
    meshes.insert(k.mesh);
    segments = std::max(segments, k.segment + 1);
  }
  auto panel = [&](const std::string& title, const std::string& y_label) {
    io::LinePlot p;
    p.title = name + ": along the mill: " + title;
    p.x_label = hours_label(relative);
    p.y_label = y_label;
    p.pad_x = true;
    return p;
  };
  auto per_segment = [&](const std::string& col) {
    const int c = t.column(col), ce = t.column(col + "_se");
    std::vector<io::PlotSeries> series;
    for (const auto& [k, r0] : first_row) {
      io::PlotSeries s;
      s.label = (meshes.size() > 1 ? fmt::format("mesh {}, ", k.mesh) : std::string()) +
                span_label(num(r0, c_z0), num(r0, c_z1));
      s.rgb = ramp(segments > 1 ? static_cast<double>(k.segment) / (segments - 1) : 0.0);
      s.markers = true;
      s.dashed = k.mesh != *meshes.begin();
      for (std::size_t r = 0; r < t.rows.size(); ++r) {
        if (static_cast<int>(num(r, c_mesh)) != k.mesh || static_cast<int>(num(r, c_seg)) != k.segment ||
            !(num(r, c_bars) > 0))
          continue;
        const double v = num(r, c), e = 2 * num(r, ce);
        s.x.push_back(num(r, c_hours)), s.y.push_back(v), s.band_lo.push_back(v - e), s.band_hi.push_back(v + e);
      }
      series.push_back(std::move(s));
    }
    return series;
  };
  if (!first_row.empty()) {
    io::LinePlot face = panel("the lifters' leading face per segment (bands: \u00b1 2 standard errors of the "
                              "segment's mean bar)",
                              "face angle from the radial line (deg)");
    face.series = per_segment("leading_angle_deg");
    at_least(face, 5);
    io::LinePlot height = panel("the lifters' height per segment (bands: \u00b1 2 standard errors of the segment's "
                                "mean bar)",
                                "height above the shell (mm)");
    height.series = per_segment("height_mm");
    height.y_cover_lo = 0;
    plots.push_back(face);
    plots.push_back(height);
  }
  // The impact point per axial bin of the liner, from each stage's run;
  // the widest spread over the stages where every bin has a point.
  std::map<int, double> hours;
  for (std::size_t r = 0; r < t.rows.size(); ++r) hours[static_cast<int>(num(r, c_stage))] = num(r, c_hours);
  io::LinePlot impact = panel("the impact point per liner bin", "angle (deg, from 3 o'clock)");
  double widest = NAN, widest_at = NAN;
  for (const auto& [i, h] : hours) {
    const std::filesystem::path summary = out / fmt::format("stage-{:02d}", i) / "summary.json";
    if (!std::filesystem::exists(summary)) continue;
    const nlohmann::json j = io::read_json_file(summary);
    const nlohmann::json liner = j.is_object() ? j.value("liner", nlohmann::json()) : nlohmann::json();
    const nlohmann::json along = liner.is_object() ? liner.value("impact_point_along", nlohmann::json()) : nlohmann::json();
    if (!along.is_array() || along.empty()) continue;
    if (impact.series.size() < along.size()) impact.series.resize(along.size());
    double lo = INFINITY, hi = -INFINITY;
    bool every = true;
    for (std::size_t b = 0; b < along.size(); ++b) {
      io::PlotSeries& s = impact.series[b];
      const nlohmann::json bin = along[b].is_object() ? along[b] : nlohmann::json::object();
      if (s.label.empty()) {
        const nlohmann::json z0 = bin.value("z0_m", nlohmann::json()), z1 = bin.value("z1_m", nlohmann::json());
        s.label = z0.is_number() && z1.is_number() ? span_label(z0.get<double>(), z1.get<double>())
                                                   : fmt::format("bin {}", b);
        s.rgb = ramp(along.size() > 1 ? static_cast<double>(b) / (along.size() - 1) : 0.0);
        s.markers = true;
      }
      const nlohmann::json v = bin.value("impact_point_deg", nlohmann::json());
      if (!v.is_number()) {  // a bin with no impact on bare liner
        every = false;
        continue;
      }
      s.x.push_back(h), s.y.push_back(v.get<double>());
      lo = std::min(lo, s.y.back()), hi = std::max(hi, s.y.back());
    }
    if (every && along.size() > 1 && !(hi - lo < widest)) widest = hi - lo, widest_at = h;
  }
  if (!impact.series.empty()) {
    if (std::isfinite(widest))
      impact.title += fmt::format(" (widest spread {:.1f} deg, at {:.0f} h{})", widest, widest_at,
                                  relative ? ", relative" : "");
    at_least(impact, 5);
    plots.push_back(impact);
  }
  return plots;
}

void write_life_picture(const std::filesystem::path& file, const std::string& name, const std::vector<Stage>& stages,
                        const LifeAxis& axis, const std::vector<io::LinePlot>& extra) {
  std::vector<io::LinePlot> plots = life_plots(name, stages, axis);
  plots.insert(plots.end(), extra.begin(), extra.end());
  io::write_line_plots_png(file, plots, 960, 380);
}

}  // namespace mc::app::life
