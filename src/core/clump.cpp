#include "core/clump.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace mc {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Eigenvalues and eigenvectors of a symmetric 3×3 matrix by cyclic Jacobi
// rotations; values ascending, vectors as the columns of `vectors`.
void symmetric_eigen(Mat3 a, Vec3& values, Mat3& vectors) {
  Mat3 v{};
  for (int i = 0; i < 3; ++i) v[i][i] = 1;
  for (int sweep = 0; sweep < 64; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double scale = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (off <= 1e-30 * scale || off == 0) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0) continue;
        const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; ++k) {  // A ← Jᵀ A J
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
  }
  std::array<int, 3> order = {0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int i, int j) { return a[i][i] < a[j][j]; });
  const double d[3] = {a[order[0]][order[0]], a[order[1]][order[1]], a[order[2]][order[2]]};
  values = {d[0], d[1], d[2]};
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) vectors[k][c] = v[k][order[c]];
  // A right-handed frame: the third axis the cross product of the first two.
  const Vec3 e0{vectors[0][0], vectors[1][0], vectors[2][0]}, e1{vectors[0][1], vectors[1][1], vectors[2][1]};
  const Vec3 e2{e0.y * e1.z - e0.z * e1.y, e0.z * e1.x - e0.x * e1.z, e0.x * e1.y - e0.y * e1.x};
  vectors[0][2] = e2.x, vectors[1][2] = e2.y, vectors[2][2] = e2.z;
}

std::string sphere_text(std::size_t k) { return "sphere " + std::to_string(k); }

}  // namespace

double ClumpMassProperties::equivalent_diameter() const { return std::cbrt(6 * volume / kPi); }

ClumpMassProperties clump_mass_properties(const ClumpShape& s, int n) {
  ClumpMassProperties p;
  if (s.spheres.empty() || n < 2) return p;
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const ClumpSphere& b : s.spheres) {
    x0 = std::min(x0, b.centre.x - b.radius), x1 = std::max(x1, b.centre.x + b.radius);
    y0 = std::min(y0, b.centre.y - b.radius), y1 = std::max(y1, b.centre.y + b.radius);
  }
  const double dx = (x1 - x0) / n, dy = (y1 - y0) / n;
  // Sums over the union: V, ∫x, ∫y, ∫z, ∫x², ∫y², ∫z², ∫xy, ∫xz, ∫yz.
  double V = 0, Mx = 0, My = 0, Mz = 0, Sxx = 0, Syy = 0, Szz = 0, Sxy = 0, Sxz = 0, Syz = 0;
  std::vector<std::pair<double, double>> chords;
  for (int i = 0; i < n; ++i) {
    const double x = x0 + (i + 0.5) * dx;
    for (int j = 0; j < n; ++j) {
      const double y = y0 + (j + 0.5) * dy;
      chords.clear();
      for (const ClumpSphere& b : s.spheres) {
        const double rho2 = (x - b.centre.x) * (x - b.centre.x) + (y - b.centre.y) * (y - b.centre.y);
        const double h2 = b.radius * b.radius - rho2;
        if (h2 > 0) {
          const double h = std::sqrt(h2);
          chords.emplace_back(b.centre.z - h, b.centre.z + h);
        }
      }
      if (chords.empty()) continue;
      std::sort(chords.begin(), chords.end());
      // Merge the chords: each stretch of z inside any sphere once.
      double a = chords[0].first, e = chords[0].second;
      auto add = [&](double z1, double z2) {
        const double L = z2 - z1, S1 = 0.5 * (z2 * z2 - z1 * z1), S2 = (z2 * z2 * z2 - z1 * z1 * z1) / 3;
        V += L, Mx += x * L, My += y * L, Mz += S1;
        Sxx += x * x * L, Syy += y * y * L, Szz += S2;
        Sxy += x * y * L, Sxz += x * S1, Syz += y * S1;
      };
      for (std::size_t k = 1; k < chords.size(); ++k) {
        if (chords[k].first > e) {
          add(a, e);
          a = chords[k].first;
          e = chords[k].second;
        } else {
          e = std::max(e, chords[k].second);
        }
      }
      add(a, e);
    }
  }
  const double dA = dx * dy;
  V *= dA, Mx *= dA, My *= dA, Mz *= dA, Sxx *= dA, Syy *= dA, Szz *= dA, Sxy *= dA, Sxz *= dA, Syz *= dA;
  p.volume = V;
  if (!(V > 0)) return p;
  const Vec3 c{Mx / V, My / V, Mz / V};
  p.centroid = c;
  // Second moments about the centroid.
  const double xx = Sxx - V * c.x * c.x, yy = Syy - V * c.y * c.y, zz = Szz - V * c.z * c.z;
  const double xy = Sxy - V * c.x * c.y, xz = Sxz - V * c.x * c.z, yz = Syz - V * c.y * c.z;
  p.inertia = {{{yy + zz, -xy, -xz}, {-xy, xx + zz, -yz}, {-xz, -yz, xx + yy}}};
  symmetric_eigen(p.inertia, p.principal, p.axes);
  return p;
}

namespace {

// A shape in units far from 1 (radii of 1e-200 or 1e200: a shape scales, so
// any unit is allowed) would overflow or underflow in its volume (r³) and
// moments (r⁵). Such a shape is brought near 1 by a power of two, which is
// exact; a shape already near 1 is left as it is, to the bit.
ClumpShape near_unit(const ClumpShape& s) {
  double r_max = 0;
  for (const ClumpSphere& b : s.spheres) r_max = std::max(r_max, b.radius);
  if (!(r_max > 0) || !std::isfinite(r_max) || (r_max > 0x1p-20 && r_max < 0x1p20)) return s;
  const int e = std::ilogb(r_max);
  ClumpShape out = s;
  for (ClumpSphere& b : out.spheres) {
    b.centre = {std::ldexp(b.centre.x, -e), std::ldexp(b.centre.y, -e), std::ldexp(b.centre.z, -e)};
    b.radius = std::ldexp(b.radius, -e);
  }
  return out;
}

}  // namespace

ClumpShape normalised_shape(const ClumpShape& shape, double d_eq, int n) {
  const ClumpShape s = near_unit(shape);
  const ClumpMassProperties p = clump_mass_properties(s, n);
  if (!(p.volume > 0) || !(d_eq > 0)) throw std::invalid_argument("shape " + s.name + ": no volume to scale");
  const double k = d_eq / p.equivalent_diameter();
  ClumpShape out;
  out.name = s.name;
  for (const ClumpSphere& b : s.spheres) {
    const Vec3 r = b.centre - p.centroid;
    // Coordinates along the principal axes (the columns of `axes`).
    const Vec3 q{r.x * p.axes[0][0] + r.y * p.axes[1][0] + r.z * p.axes[2][0],
                 r.x * p.axes[0][1] + r.y * p.axes[1][1] + r.z * p.axes[2][1],
                 r.x * p.axes[0][2] + r.y * p.axes[1][2] + r.z * p.axes[2][2]};
    out.spheres.push_back({q * k, b.radius * k});
  }
  return out;
}

void check_shape(const ClumpShape& s, const std::string& key) {
  if (s.spheres.empty()) throw std::invalid_argument(key + ": the shape has no spheres");
  double r_max = 0;
  for (std::size_t k = 0; k < s.spheres.size(); ++k) {
    const ClumpSphere& b = s.spheres[k];
    if (!std::isfinite(b.centre.x) || !std::isfinite(b.centre.y) || !std::isfinite(b.centre.z))
      throw std::invalid_argument(key + ": " + sphere_text(k) + "'s centre is not a finite point");
    if (!std::isfinite(b.radius) || !(b.radius > 0)) {
      std::ostringstream m;
      m << key << ": " << sphere_text(k) << "'s radius must be > 0 (got " << b.radius << ")";
      throw std::invalid_argument(m.str());
    }
    r_max = std::max(r_max, b.radius);
  }
  // Every sphere within 100 largest radii of the first's centre: a body,
  // not a scatter of unrelated balls (a typo in a coordinate, or mm for m).
  // In units of the largest radius, so that no unit overflows.
  auto in_radii = [r_max](const Vec3& c) { return Vec3{c.x / r_max, c.y / r_max, c.z / r_max}; };
  const Vec3 c0 = in_radii(s.spheres[0].centre);
  for (std::size_t k = 1; k < s.spheres.size(); ++k) {
    const double d = (in_radii(s.spheres[k].centre) - c0).norm();
    if (!(d <= 100)) {
      std::ostringstream m;
      m << key << ": " << sphere_text(k) << " lies " << d * r_max << " from sphere 0, more than 100 times the largest radius ("
        << r_max << "): a body's spheres overlap or nearly touch";
      throw std::invalid_argument(m.str());
    }
  }
}

std::vector<std::string> library_shape_names() { return {"sphere", "peanut", "flat4", "rod5", "rock"}; }

ClumpShape library_shape(const std::string& name) {
  ClumpShape s;
  s.name = name;
  if (name == "sphere") {
    s.spheres = {{{0, 0, 0}, 1}};
  } else if (name == "peanut") {
    s.spheres = {{{-0.5, 0, 0}, 1}, {{0.5, 0, 0}, 1}};
  } else if (name == "flat4") {
    const double h = std::sqrt(0.5);
    s.spheres = {{{h, h, 0}, 1}, {{-h, h, 0}, 1}, {{-h, -h, 0}, 1}, {{h, -h, 0}, 1}};
  } else if (name == "rod5") {
    for (int k = -2; k <= 2; ++k) s.spheres.push_back({{0.8 * k, 0, 0}, 1});
  } else if (name == "rock") {
    s = rock_shape(12, 0.8, 0.6, 1);
    s.name = name;
  } else {
    std::string list;
    for (const std::string& n : library_shape_names()) list += (list.empty() ? "" : ", ") + n;
    throw std::invalid_argument("unknown shape \"" + name + "\" (the library has " + list + ")");
  }
  return s;
}

ClumpShape rock_shape(int n_spheres, double b, double c, unsigned seed) {
  if (n_spheres < 2 || n_spheres > 64) throw std::invalid_argument("a rock has 2 to 64 spheres");
  if (!(b <= 1 && c <= b && c > 0.2)) throw std::invalid_argument("a rock's axes need 1 >= b >= c > 0.2");
  // Points inside the ellipsoid x² + (y/b)² + (z/c)² <= 1.
  std::vector<Vec3> pts;
  const int g = 28;
  for (int i = 0; i < g; ++i)
    for (int j = 0; j < g; ++j)
      for (int k = 0; k < g; ++k) {
        const Vec3 u{-1 + (i + 0.5) * 2.0 / g, -1 + (j + 0.5) * 2.0 / g, -1 + (k + 0.5) * 2.0 / g};
        if (u.dot(u) <= 1) pts.push_back({u.x, u.y * b, u.z * c});
      }
  // The surface: 4,000 points spread over it (a Fibonacci lattice mapped
  // onto the ellipsoid); a point's inscribed radius is its distance to the
  // nearest of them.
  std::vector<Vec3> surface;
  const int m = 4000;
  const double golden = kPi * (3 - std::sqrt(5.0));
  for (int k = 0; k < m; ++k) {
    const double z = 1 - (k + 0.5) * 2.0 / m, r = std::sqrt(1 - z * z), a = golden * k;
    surface.push_back({r * std::cos(a), b * r * std::sin(a), c * z});
  }
  auto inscribed = [&](const Vec3& q) {
    double d = 1e300;
    for (const Vec3& p : surface) d = std::min(d, (p - q).dot(p - q));
    return std::sqrt(d);
  };
  // Candidate centres: 1,500 of the inside points, drawn with the seed
  // (mt19937's sequence is fixed by the standard, so a seed gives the same
  // rock everywhere). Greedy cover: each sphere the candidate's inscribed
  // sphere that covers the most inside points not yet covered.
  std::mt19937 rng(seed);
  std::vector<Vec3> cand;
  std::vector<double> cand_r;
  std::vector<char> picked(pts.size(), 0);
  const std::size_t n_cand = std::min<std::size_t>(1500, pts.size());
  while (cand.size() < n_cand) {
    const std::size_t k = rng() % pts.size();
    if (picked[k]) continue;
    picked[k] = 1;
    cand.push_back(pts[k]);
    cand_r.push_back(inscribed(pts[k]));
  }
  std::vector<char> covered(pts.size(), 0);
  ClumpShape s;
  s.name = "rock";
  for (int sphere = 0; sphere < n_spheres; ++sphere) {
    std::size_t best = 0;
    long best_gain = -1;
    for (std::size_t k = 0; k < cand.size(); ++k) {
      const double r2 = cand_r[k] * cand_r[k];
      long gain = 0;
      for (std::size_t p = 0; p < pts.size(); ++p)
        if (!covered[p] && (pts[p] - cand[k]).dot(pts[p] - cand[k]) <= r2) ++gain;
      if (gain > best_gain) best_gain = gain, best = k;
    }
    const double r2 = cand_r[best] * cand_r[best];
    for (std::size_t p = 0; p < pts.size(); ++p)
      if ((pts[p] - cand[best]).dot(pts[p] - cand[best]) <= r2) covered[p] = 1;
    s.spheres.push_back({cand[best], cand_r[best]});
  }
  return s;
}

}  // namespace mc
