#include "core/plate_wear.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/layout.hpp"

namespace mc {

static_assert(kMaxWornPlateRings == MC_PLATE_NODES, "the kernels hold MC_PLATE_NODES depths per plate");

namespace {

// ∫ rho · (a + b rho) drho from r0 to r1.
double moment(double a, double b, double r0, double r1) {
  return a * (r1 * r1 - r0 * r0) / 2 + b * (r1 * r1 * r1 - r0 * r0 * r0) / 3;
}

// Ring j's mean as weights on the depths of rings j-1, j and j+1 (unit
// width; the ramps span a quarter-ring either side of each edge).
struct Row {
  double lo = 0, mid = 0, hi = 0;
};

std::vector<Row> mean_rows(int n) {
  std::vector<Row> rows(n);
  const double q = 0.25;
  for (int j = 0; j < n; ++j) {
    const double r0 = j, r1 = j + 1.0, area = (r1 * r1 - r0 * r0) / 2;
    Row& w = rows[j];
    const double a = j == 0 ? r0 : r0 + q, b = j == n - 1 ? r1 : r1 - q;
    w.mid += moment(1, 0, a, b);  // the flat middle
    if (j > 0) {
      // The outer half of the ramp from ring j-1: depth d[j-1] + (d[j] - d[j-1]) (rho - (r0 - q)) / (2q).
      const double s = r0 - q;
      w.lo += moment(1 + s / (2 * q), -1 / (2 * q), r0, a);
      w.mid += moment(-s / (2 * q), 1 / (2 * q), r0, a);
    }
    if (j < n - 1) {
      // The inner half of the ramp to ring j+1: d[j] + (d[j+1] - d[j]) (rho - (r1 - q)) / (2q).
      const double s = r1 - q;
      w.mid += moment(1 + s / (2 * q), -1 / (2 * q), b, r1);
      w.hi += moment(-s / (2 * q), 1 / (2 * q), b, r1);
    }
    w.lo /= area, w.mid /= area, w.hi /= area;
  }
  return rows;
}

// The rows solved for x (Thomas algorithm).
std::vector<double> solve(const std::vector<Row>& rows, const std::vector<double>& t) {
  const int n = static_cast<int>(t.size());
  std::vector<double> b(n), d(t), x(n);
  for (int j = 0; j < n; ++j) b[j] = rows[j].mid;
  for (int j = 1; j < n; ++j) {
    const double m = rows[j].lo / b[j - 1];
    b[j] -= m * rows[j - 1].hi;
    d[j] -= m * d[j - 1];
  }
  x[n - 1] = d[n - 1] / b[n - 1];
  for (int j = n - 2; j >= 0; --j) x[j] = (d[j] - rows[j].hi * x[j + 1]) / b[j];
  return x;
}

}  // namespace

double plate_surface_depth(const std::vector<double>& depth, double width, double rho, double* slope) {
  const int n = static_cast<int>(depth.size());
  if (slope) *slope = 0;
  if (n == 0 || !(width > 0)) return 0;
  const double u = rho / width;  // in rings
  const int j = std::clamp(static_cast<int>(std::floor(u)), 0, n - 1);
  const double f = u - j;  // within ring j
  if (f < 0.25 && j > 0) {  // the ramp from ring j-1
    const double t = (f + 0.25) / 0.5;
    if (slope) *slope = (depth[j] - depth[j - 1]) / (0.5 * width);
    return depth[j - 1] + t * (depth[j] - depth[j - 1]);
  }
  if (f > 0.75 && j < n - 1) {  // the ramp to ring j+1
    const double t = (f - 0.75) / 0.5;
    if (slope) *slope = (depth[j + 1] - depth[j]) / (0.5 * width);
    return depth[j] + t * (depth[j + 1] - depth[j]);
  }
  return depth[j];
}

std::vector<double> plate_bend_radii(std::size_t rings, double width) {
  std::vector<double> out;
  for (std::size_t k = 1; k < rings; ++k) out.push_back((k - 0.25) * width), out.push_back((k + 0.25) * width);
  return out;
}

std::vector<Triangle> plate_face_triangles(const std::vector<double>& depth, double R, int segments) {
  const std::size_t n = depth.size();
  const double width = n > 0 ? R / static_cast<double>(n) : R;
  std::vector<double> radii = {0.0};
  for (double b : plate_bend_radii(n, width)) radii.push_back(b);
  radii.push_back(R);
  auto at = [&](double r, int k) {
    const double a = 2 * 3.14159265358979323846 * k / segments;
    return Vec3{r * std::cos(a), r * std::sin(a), -plate_surface_depth(depth, width, r)};
  };
  std::vector<Triangle> out;
  for (int k = 0; k < segments; ++k)
    for (std::size_t i = 0; i + 1 < radii.size(); ++i) {
      const Vec3 p00 = at(radii[i], k), p01 = at(radii[i], k + 1), p10 = at(radii[i + 1], k), p11 = at(radii[i + 1], k + 1);
      if (i == 0) out.push_back({{p00, p10, p11}});  // at the axis: one triangle
      else out.push_back({{p00, p10, p11}}), out.push_back({{p00, p11, p01}});
    }
  return out;
}

std::vector<double> plate_ring_means(const std::vector<double>& depth, double /*width*/) {
  const int n = static_cast<int>(depth.size());
  const std::vector<Row> rows = mean_rows(n);
  std::vector<double> m(n);
  for (int j = 0; j < n; ++j)
    m[j] = rows[j].mid * depth[j] + (j > 0 ? rows[j].lo * depth[j - 1] : 0) + (j + 1 < n ? rows[j].hi * depth[j + 1] : 0);
  return m;
}

double plate_worn_volume(const std::vector<double>& depth, double R) {
  const int n = static_cast<int>(depth.size());
  if (n == 0) return 0;
  const std::vector<double> m = plate_ring_means(depth, R / n);
  double v = 0;
  for (int j = 0; j < n; ++j) {
    const double r0 = R * j / n, r1 = R * (j + 1) / n;
    v += m[j] * M_PI * (r1 * r1 - r0 * r0);
  }
  return v;
}

std::vector<double> plate_increment(const std::vector<double>& booked) {
  const int n = static_cast<int>(booked.size());
  if (n == 0) return {};
  const std::vector<Row> rows = mean_rows(n);
  // The complementarity problem x >= 0, A x >= t, x (A x - t) = 0: A is
  // strictly diagonally dominant with a positive diagonal, so it has one
  // solution, and projected Gauss-Seidel reaches it (each sweep shrinks the
  // error by the rows' off-diagonal share over their diagonal, under 1/6).
  // It starts from the solve without holds, clamped.
  std::vector<double> x = solve(rows, booked);
  for (double& v : x) v = std::max(v, 0.0);
  double scale = 0;
  for (double t : booked) scale = std::max(scale, std::fabs(t));
  for (int sweep = 0; sweep < 1000; ++sweep) {
    double change = 0;
    for (int j = 0; j < n; ++j) {
      const double rest = (j > 0 ? rows[j].lo * x[j - 1] : 0) + (j + 1 < n ? rows[j].hi * x[j + 1] : 0);
      const double v = std::max(0.0, (booked[j] - rest) / rows[j].mid);
      change = std::max(change, std::fabs(v - x[j]));
      x[j] = v;
    }
    if (change <= 1e-15 * scale) break;
  }
  return x;
}

double plate_depth_at_shell(const std::array<std::vector<double>, 2>& depth) {
  double d = 0;
  for (const std::vector<double>& plate : depth)
    if (!plate.empty()) d += plate.back();  // the last ring's face is flat out to the shell
  return d;
}

std::string check_plate_depths(const std::array<std::vector<double>, 2>& depth, int rings, double R, double length) {
  std::ostringstream m;
  if (!(length > 0))
    return ": worn plates need a mill closed by flat end plates (mill.ends = \"plates\"), not a slice or cone heads";
  if (!(R > 0)) return ": worn plates need a shell (mill.diameter > 0)";
  if (rings > kMaxWornPlateRings) {
    m << ": liner.plate_rings = " << rings << " cuts the plates into more rings than a worn plate may have ("
      << kMaxWornPlateRings << ")";
    return m.str();
  }
  for (int p = 0; p < 2; ++p) {
    if (depth[p].size() != static_cast<std::size_t>(rings)) {
      m << "[" << p << "]: " << depth[p].size() << " depths for " << rings
        << " rings (liner.plate_rings): give one per ring, from the axis out";
      return m.str();
    }
    for (int j = 0; j < rings; ++j)
      if (!(depth[p][j] >= 0 && depth[p][j] < length)) {
        m << "[" << p << "][" << j << "]: must be >= 0 and less than the mill's length (" << 1000 * length
          << " mm; got " << depth[p][j] * 1000 << " mm)";
        return m.str();
      }
  }
  return "";
}

}  // namespace mc
