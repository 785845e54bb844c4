#include "core/plate_wear.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace mc {

namespace {

// ∫ rho · (a + b rho) drho from r0 to r1.
double moment(double a, double b, double r0, double r1) {
  return a * (r1 * r1 - r0 * r0) / 2 + b * (r1 * r1 * r1 - r0 * r0 * r0) / 3;
}

// The coefficients of ring j's mean on the nodes j-1, j, j+1 (unit width).
struct Row {
  double lo = 0, mid = 0, hi = 0;
};

std::vector<Row> mean_rows(int n) {
  std::vector<Row> rows(n);
  for (int j = 0; j < n; ++j) {
    const double r0 = j, c = j + 0.5, r1 = j + 1.0;
    const double area = (r1 * r1 - r0 * r0) / 2;
    Row& w = rows[j];
    // [r0, c]: from node j-1 (at c - 1) to node j, or flat at node j in ring 0.
    if (j == 0) {
      w.mid += moment(1, 0, r0, c);
    } else {  // node j-1 weight (c - rho), node j weight (rho - (c - 1))
      w.lo += moment(c, -1, r0, c);
      w.mid += moment(1 - c, 1, r0, c);
    }
    // [c, r1]: from node j to node j+1 (at c + 1), or flat in the last ring.
    if (j == n - 1) {
      w.mid += moment(1, 0, c, r1);
    } else {  // node j weight (c + 1 - rho), node j+1 weight (rho - c)
      w.mid += moment(c + 1, -1, c, r1);
      w.hi += moment(-c, 1, c, r1);
    }
    w.lo /= area, w.mid /= area, w.hi /= area;
  }
  return rows;
}

// Solves the rings' means for the nodes not held at 0 (Thomas algorithm on
// the free nodes, the held ones known).
std::vector<double> solve(const std::vector<Row>& rows, const std::vector<double>& t, const std::vector<bool>& held) {
  const int n = static_cast<int>(t.size());
  std::vector<double> a(n), b(n), c(n), d(n), x(n, 0.0);
  for (int j = 0; j < n; ++j) {
    a[j] = j > 0 && !held[j - 1] ? rows[j].lo : 0;
    c[j] = j + 1 < n && !held[j + 1] ? rows[j].hi : 0;
    b[j] = rows[j].mid;
    d[j] = t[j];
    if (held[j]) a[j] = 0, c[j] = 0, b[j] = 1, d[j] = 0;
  }
  // A held node's column is zero in its neighbours' rows (its value is 0);
  // its own row only pins it. The rings of held nodes are not matched.
  for (int j = 1; j < n; ++j) {
    const double m = a[j] / b[j - 1];
    b[j] -= m * c[j - 1];
    d[j] -= m * d[j - 1];
  }
  x[n - 1] = d[n - 1] / b[n - 1];
  for (int j = n - 2; j >= 0; --j) x[j] = (d[j] - c[j] * x[j + 1]) / b[j];
  return x;
}

}  // namespace

std::vector<double> plate_surface_nodes(const std::vector<double>& ring_depth) {
  const int n = static_cast<int>(ring_depth.size());
  if (n == 0) return {};
  const std::vector<Row> rows = mean_rows(n);
  std::vector<bool> held(n, false);
  std::vector<double> x;
  // Each pass holds at least one more node: at most n passes.
  for (int pass = 0; pass <= n; ++pass) {
    x = solve(rows, ring_depth, held);
    bool more = false;
    for (int j = 0; j < n; ++j)
      if (!held[j] && x[j] < 0) held[j] = true, more = true;
    if (!more) break;
  }
  for (double& v : x) v = std::max(v, 0.0);
  // Where nodes are held, the rings beside them take metal their depths
  // did not book: the free nodes are scaled so that the plate as a whole
  // loses its rings' volume (ring j's area is (2j + 1) times the first's).
  double want = 0, have = 0;
  for (int j = 0; j < n; ++j) {
    const double m = rows[j].mid * x[j] + (j > 0 ? rows[j].lo * x[j - 1] : 0) + (j + 1 < n ? rows[j].hi * x[j + 1] : 0);
    want += (2 * j + 1) * ring_depth[j];
    have += (2 * j + 1) * m;
  }
  if (have > 0 && std::count(held.begin(), held.end(), true) > 0)
    for (double& v : x) v *= want / have;
  return x;
}

double plate_surface_depth(const std::vector<double>& nodes, double width, double rho, double* slope) {
  const int n = static_cast<int>(nodes.size());
  if (slope) *slope = 0;
  if (n == 0 || !(width > 0)) return 0;
  const double u = rho / width - 0.5;
  if (u <= 0) return nodes.front();
  if (u >= n - 1) return nodes.back();
  const int j = static_cast<int>(std::floor(u));
  const double f = u - j;
  if (slope) *slope = (nodes[j + 1] - nodes[j]) / width;
  return nodes[j] + f * (nodes[j + 1] - nodes[j]);
}

std::vector<double> plate_ring_means(const std::vector<double>& nodes, double /*width*/) {
  const int n = static_cast<int>(nodes.size());
  const std::vector<Row> rows = mean_rows(n);
  std::vector<double> m(n);
  for (int j = 0; j < n; ++j)
    m[j] = rows[j].mid * nodes[j] + (j > 0 ? rows[j].lo * nodes[j - 1] : 0) + (j + 1 < n ? rows[j].hi * nodes[j + 1] : 0);
  return m;
}

double plate_worn_volume(const std::vector<double>& ring_depth, double R) {
  const int n = static_cast<int>(ring_depth.size());
  double v = 0;
  for (int j = 0; j < n; ++j) {
    const double r0 = R * j / n, r1 = R * (j + 1) / n;
    v += ring_depth[j] * M_PI * (r1 * r1 - r0 * r0);
  }
  return v;
}

std::string check_plate_depths(const std::array<std::vector<double>, 2>& depth, int rings, double R, double length) {
  std::ostringstream m;
  if (!(length > 0))
    return ": worn plates need a mill closed by flat end plates (mill.ends = \"plates\"), not a slice or cone heads";
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
    // The kernels take the surface as its tangent plane: at most 45° off.
    const std::vector<double> nodes = plate_surface_nodes(depth[p]);
    const double width = R / rings;
    for (int j = 0; j + 1 < rings; ++j)
      if (std::fabs(nodes[j + 1] - nodes[j]) > width) {
        m << "[" << p << "]: rings " << j << " and " << j + 1
          << " differ too much: the worn surface between them would slope by more than 45° (a step of "
          << std::fabs(nodes[j + 1] - nodes[j]) * 1000 << " mm over a ring's " << width * 1000 << " mm)";
        return m.str();
      }
  }
  return "";
}

}  // namespace mc
