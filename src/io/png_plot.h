// PNG pictures of a run, drawn in software (no GL needed): a line plot of
// series against time, and an end view of the charge with toe and shoulder.
// Shapes and text are anti-aliased; text is DejaVu Sans (built in) rendered
// with stb_truetype, and files are written with
// stb_image_write through io/atomic_file.h.
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/vec.h"

namespace mc::io {

// The font every picture's text is drawn in: DejaVu Sans, built into the
// program (plot_font_data.cpp), so that no run needs a font file.
// MILLCHARGE_FONT, when set, names a TrueType file to draw in instead; one
// that cannot be read is a warning on stderr, and the built-in font is used.
std::filesystem::path plot_font_path();  // MILLCHARGE_FONT, or empty
std::string plot_font_in_use();          // "built in", or MILLCHARGE_FONT's file
std::string plot_font_warning();         // why MILLCHARGE_FONT's file is not in use; empty if it is or is unset

// Draws a picture with `draw`; a picture that cannot be drawn (a write
// error, a bad MILLCHARGE_FONT is not one) is a warning on stderr that
// names the file, never an end to the command. Returns whether it was drawn.
bool draw_or_warn(const std::filesystem::path& file, const std::function<void()>& draw);

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  std::uint32_t rgb = 0x1f77b4;  // 0xRRGGBB
  bool markers = false;          // a dot at every point
  bool dashed = false;           // a dashed line (a model beside the data)
  // A shaded band under the line (an interval about each point), as long
  // as x where given; NaN breaks it.
  std::vector<double> band_lo = {}, band_hi = {};
};

// A horizontal line at y = value (a mean, a target) from x_from to x_to
// (across the whole plot when x_to <= x_from), its label in the legend.
struct RefLine {
  double value = 0;
  double x_from = 0, x_to = 0;
  std::uint32_t rgb = 0x222222;
  bool dashed = false;
  std::string label;
};

struct LinePlot {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  std::vector<RefLine> ref_lines;  // drawn over the series, listed after them in the legend
  // Optional shaded span on the x axis (the averaging window), its label in
  // the legend beside a swatch of its colour.
  double span_from = 0, span_to = 0;
  std::string span_label;
  bool pad_x = false;  // leave room beside the first and last x (for markers)
  bool log_x = false;  // a log x axis (x <= 0 left out)
  bool equal_aspect = false;  // a unit as long on both axes (a shape drawn true)
  // The y axis reaches at least these where they are finite (a span that
  // keeps small changes small, or a zero to measure from).
  double y_cover_lo = NAN, y_cover_hi = NAN;
};

// "874.4 ± 2.8 W": a value and its standard error to the error's second
// significant digit (whole numbers for errors of 10 and more); the value
// alone, to one decimal, without a finite positive error.
std::string value_with_error(double value, double sem, const std::string& unit);

// Throws std::runtime_error when the file cannot be written.
void write_line_plot_png(const std::filesystem::path& path, const LinePlot& plot, int width = 960,
                         int height = 560);
// Several plots one under the other in one picture.
void write_line_plots_png(const std::filesystem::path& path, const std::vector<LinePlot>& plots, int width = 960,
                          int height_each = 420);

struct EndViewBall {
  double x = 0, y = 0, z = 0;  // lab frame, m
  double radius = 0;           // m
  double speed = 0;            // m/s, sets the colour
};

// Looking along −z at the mill's cross-section: x to the right, y up. Angles
// in degrees counter-clockwise from 3 o'clock (Morrell's convention).
struct EndView {
  std::string title;
  double shell_radius = 0;                    // m
  std::vector<std::vector<Vec2>> lifters;     // lab-frame polygons
  std::vector<EndViewBall> balls;
  double toe_deg = -1, shoulder_deg = -1;     // < 0: not marked
  double impact_deg = -1;                     // the impact point; < 0 (or NaN): not marked
  bool has_com = false;
  double com_x = 0, com_y = 0;                // centre of mass, m
  double max_speed = 0;                       // colour scale top; 0: from the balls
};

void write_end_view_png(const std::filesystem::path& path, const EndView& view, int size = 800);

// A heat map of rectangles (the liner unrolled): each cell a value coloured
// on a log scale over `decades` below the largest (a cell of 0 is grey),
// outlined when asked (the lifters). Vertical lines mark angles.
struct HeatCell {
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  double value = 0;
  bool outline = false;
};

struct HeatMap {
  std::string title, x_label, y_label, unit;
  double x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;
  std::vector<HeatCell> cells;
  double decades = 3;
  struct Mark {
    double x = 0;
    std::string label;
    std::uint32_t rgb = 0xc51b8a;
  };
  std::vector<Mark> marks_x;  // labelled vertical lines
  // A curve over the map on its own y axis (the map's y range), drawn in
  // ink and named in the panel's corner; none where empty.
  std::vector<std::pair<double, double>> curve;
  std::string curve_label;
};

// Bars with their values written above them.
struct BarChart {
  std::string title, y_label;
  std::vector<std::pair<std::string, double>> bars;
  std::uint32_t rgb = 0x4c72b0;
};

// The maps stacked top to bottom, then the bar chart (if it has bars), in
// one picture. Throws std::runtime_error when the file cannot be written.
void write_heat_maps_png(const std::filesystem::path& path, const std::vector<HeatMap>& maps, const BarChart& bars,
                         int width = 1100);

}  // namespace mc::io
