#include "core/charge_edit.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <random>
#include <unordered_map>

#include "core/lifters.h"

namespace mc {

namespace {

// Balls in a hash grid of cells at least one largest diameter wide, for
// overlap queries while balls are added and removed. Along the axis of a
// periodic slice (period > 0) the cells tile the period and distances are
// taken to the nearest image.
class BallGrid {
 public:
  BallGrid(double cell, const std::vector<Ball>& balls, double period = 0) : cell_(cell), period_(period) {
    if (period_ > 0) {
      nz_ = std::max(1L, static_cast<long>(std::floor(period_ / cell_)));
      cell_z_ = period_ / nz_;
    }
    for (std::size_t k = 0; k < balls.size(); ++k) insert(static_cast<int>(k), balls[k]);
  }
  void insert(int k, const Ball& b) { cells_[key(b.position)].push_back(k); }
  // Whether a ball of radius r at p keeps `gap` from every listed ball.
  bool clear(const std::vector<Ball>& balls, const Vec3& p, double r, double gap, int skip = -1) const {
    bool ok = true;
    for_near(p, [&](int j) {
      if (j == skip || !ok) return;
      const Ball& o = balls[j];
      const double reach = r + o.radius + gap;
      const Vec3 d = separation(p, o.position);
      if (d.dot(d) < reach * reach) ok = false;
    });
    return ok;
  }
  template <class F>
  void for_near(const Vec3& p, F f) const {
    const long ix = cell_index(p.x), iy = cell_index(p.y), iz = z_index(p.z);
    long zs[3];
    int n_zs = 0;
    if (period_ > 0 && nz_ < 3) {
      for (long k = 0; k < nz_; ++k) zs[n_zs++] = k;
    } else {
      for (long k = -1; k <= 1; ++k) zs[n_zs++] = period_ > 0 ? ((iz + k) % nz_ + nz_) % nz_ : iz + k;
    }
    for (int q = 0; q < n_zs; ++q)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dx = -1; dx <= 1; ++dx) {
          auto it = cells_.find(pack(ix + dx, iy + dy, zs[q]));
          if (it != cells_.end())
            for (int j : it->second) f(j);
        }
  }
  // a − b, the nearest image along a periodic axis.
  Vec3 separation(const Vec3& a, const Vec3& b) const {
    Vec3 d = a - b;
    if (period_ > 0) d.z -= period_ * std::floor(d.z / period_ + 0.5);
    return d;
  }

 private:
  long cell_index(double v) const { return static_cast<long>(std::floor(v / cell_)); }
  long z_index(double z) const {
    if (period_ <= 0) return cell_index(z);
    const long k = static_cast<long>(std::floor(z / cell_z_)) % nz_;
    return k < 0 ? k + nz_ : k;
  }
  static long long pack(long x, long y, long z) {
    return ((static_cast<long long>(x) & 0x1fffff) << 42) | ((static_cast<long long>(y) & 0x1fffff) << 21) |
           (static_cast<long long>(z) & 0x1fffff);
  }
  long long key(const Vec3& p) const { return pack(cell_index(p.x), cell_index(p.y), z_index(p.z)); }
  double cell_;
  double period_ = 0, cell_z_ = 0;
  long nz_ = 1;
  std::unordered_map<long long, std::vector<int>> cells_;
};

// The mill's walls seen from the lab frame at one mill angle.
class WallProbe {
 public:
  WallProbe(const Walls& w, double mill_angle)
      : w_(w), c_(std::cos(-mill_angle)), s_(std::sin(-mill_angle)) {}
  // Signed clearance of a ball (centre p, radius r) from every wall: the
  // smallest gap; negative when it overlaps.
  double clearance(const Vec3& p, double r) const {
    double gap = 1e300;
    if (w_.shell_radius > 0) gap = std::min(gap, w_.shell_radius - std::hypot(p.x, p.y) - r);
    if (w_.has_end_plates()) gap = std::min({gap, p.z - r, w_.length - p.z - r});
    const double mx = c_ * p.x - s_ * p.y, my = s_ * p.x + c_ * p.y;  // mill frame
    for (const auto& poly : w_.lifters) gap = std::min(gap, polygon_signed_distance(poly, mx, my) - r);
    return gap;
  }

 private:
  const Walls& w_;
  double c_, s_;
};

}  // namespace

int size_class_of(const MillCase& c, const Ball& b) {
  const double dia = 2 * b.radius;
  int nearest = -1;
  double best = 1e300;
  for (std::size_t k = 0; k < c.sizes.size(); ++k) {
    const SizeClass& s = c.sizes[k];
    if (material_index(c, s.material) != b.material) continue;
    if (dia >= s.diameter_min * (1 - 1e-6) && dia <= s.diameter_max * (1 + 1e-6)) return static_cast<int>(k);
    const double off = std::max(s.diameter_min - dia, dia - s.diameter_max);
    if (off < best) best = off, nearest = static_cast<int>(k);
  }
  return nearest;
}

ChargeEditResult edit_charge(const MillCase& c, const MillDerived& d, std::vector<Ball> balls,
                             const ChargeEditOptions& o) {
  ChargeEditResult res;
  res.scene = build_walls(c, d);
  Scene& s = res.scene;
  s.mill_angle = o.mill_angle;
  s.mill_omega = o.mill_omega;
  const double R = s.walls.shell_radius;
  const WallProbe walls(s.walls, o.mill_angle);

  double rmax = 0.5 * d.largest_ball_diameter, rmin = 1e300;
  for (const Ball& b : balls) rmax = std::max(rmax, b.radius), rmin = std::min(rmin, b.radius);
  for (const SizeClass& sc : c.sizes) rmin = std::min(rmin, 0.5 * sc.diameter_min);
  const double gap = 0.02 * rmin;

  // 1. Balls the new walls overlap (a grown or added lifter) wait for a new place.
  std::vector<Ball> kept, homeless;
  kept.reserve(balls.size());
  for (std::size_t k = 0; k < balls.size(); ++k) balls[k].id = static_cast<int>(k);
  std::unique_ptr<WallProbe> before;
  if (o.previous_walls) before = std::make_unique<WallProbe>(*o.previous_walls, o.mill_angle);
  for (Ball& b : balls) {
    const double now = walls.clearance(b.position, b.radius);
    const bool deeper = !before || now < before->clearance(b.position, b.radius) - 1e-9 * b.radius;
    if (now < -o.allowed_overlap * b.radius && deeper) homeless.push_back(b);
    else kept.push_back(b);
  }

  // 2. A new filling: surplus balls of each class leave from the top.
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Ball> to_add = homeless;
  for (Ball& b : to_add) b.velocity = b.omega = Vec3{};
  if (o.match_counts) {
    std::vector<long> have(c.sizes.size(), 0);
    for (const std::vector<Ball>* set : {&kept, &homeless})
      for (const Ball& b : *set) {
        const int k = size_class_of(c, b);
        if (k >= 0) ++have[k];
      }
    for (std::size_t k = 0; k < c.sizes.size(); ++k) {
      long surplus = have[k] - d.class_counts[k];
      // The homeless go first, then the highest kept balls.
      for (auto it = to_add.begin(); surplus > 0 && it != to_add.end();) {
        if (size_class_of(c, *it) == static_cast<int>(k)) {
          it = to_add.erase(it);
          --surplus;
          ++res.removed;
        } else {
          ++it;
        }
      }
      if (surplus > 0) {
        std::vector<std::size_t> order(kept.size());
        std::iota(order.begin(), order.end(), 0);
        std::sort(order.begin(), order.end(),
                  [&](std::size_t a, std::size_t b) { return kept[a].position.y > kept[b].position.y; });
        std::vector<char> drop(kept.size(), 0);
        for (std::size_t i : order) {
          if (surplus == 0) break;
          if (size_class_of(c, kept[i]) != static_cast<int>(k)) continue;
          drop[i] = 1;
          --surplus;
          ++res.removed;
        }
        std::vector<Ball> rest;
        rest.reserve(kept.size());
        for (std::size_t i = 0; i < kept.size(); ++i)
          if (!drop[i]) rest.push_back(kept[i]);
        kept.swap(rest);
      }
      const SizeClass& sc = c.sizes[k];
      for (long i = 0; i > surplus; --i) {  // a deficit: new balls of this class
        Ball b;
        b.id = -1;  // new
        b.material = material_index(c, sc.material);
        b.radius = 0.5 * (sc.diameter_min + (sc.diameter_max - sc.diameter_min) * unit(rng));
        to_add.push_back(b);
      }
    }
  }

  // 3. Free places above the charge: candidate sites on a lattice as fine as
  // the smallest ball, the lowest first among those above every ball of their
  // column, each taken when the ball fits there (random sequential addition),
  // so new balls rest on or fall gently onto the charge.
  if (!to_add.empty()) {
    std::shuffle(to_add.begin(), to_add.end(), rng);  // sizes and materials mix
    const double pitch = 2 * rmin + 2 * gap;
    const int nx = std::max(1, static_cast<int>(std::floor(2 * R / pitch)));
    const int nz = std::max(1, static_cast<int>(std::floor((c.length - 2 * gap) / pitch)));
    const double x0 = -0.5 * (nx - 1) * pitch, z0 = 0.5 * (c.length - (nz - 1) * pitch);
    std::vector<double> column_top(static_cast<std::size_t>(nx) * nz, -1e300);
    auto column_of = [&](double x, double z) {
      const int ix = std::clamp(static_cast<int>(std::lround((x - x0) / pitch)), 0, nx - 1);
      const int iz = std::clamp(static_cast<int>(std::lround((z - z0) / pitch)), 0, nz - 1);
      return static_cast<std::size_t>(iz) * nx + ix;
    };
    for (const Ball& b : kept) {
      double& top = column_top[column_of(b.position.x, b.position.z)];
      top = std::max(top, b.position.y + b.radius);
    }
    struct Site {
      Vec3 p;
      double jitter;
    };
    std::vector<Site> sites;
    for (int iz = 0; iz < nz; ++iz)
      for (int ix = 0; ix < nx; ++ix) {
        const double x = x0 + ix * pitch, z = z0 + iz * pitch;
        const double top = column_top[static_cast<std::size_t>(iz) * nx + ix];
        const double y_from = std::max(-R + rmin + gap, top + rmax + gap);
        for (double y = y_from; y < R; y += pitch) {
          const Vec3 p{x, y, z};
          if (walls.clearance(p, rmin) >= gap) sites.push_back({p, unit(rng)});
        }
      }
    // Lowest first; the jitter spreads equal heights across the width.
    std::sort(sites.begin(), sites.end(), [&](const Site& a, const Site& b) {
      return a.p.y + 0.5 * pitch * a.jitter < b.p.y + 0.5 * pitch * b.jitter;
    });
    BallGrid grid(2 * rmax + 2 * gap, kept, s.walls.periodic ? s.walls.length : 0.0);
    // A site too small for one ball may still take a smaller one: each site
    // keeps the smallest radius that did not fit there (balls only come, so
    // nothing that large fits later either), and is passed over for good
    // once taken or too small for the smallest ball.
    std::vector<double> fails_from(sites.size(), 1e300);
    std::vector<char> taken(sites.size(), 0);
    std::size_t first_open = 0;
    for (Ball& b : to_add) {
      // Relocated balls keep their ids until the renumbering; new ones have −1.
      bool placed = false;
      for (std::size_t i = first_open; !placed && i < sites.size(); ++i) {
        if (taken[i] || b.radius >= fails_from[i]) continue;
        const Vec3 p = sites[i].p;
        if (walls.clearance(p, b.radius) < gap || !grid.clear(kept, p, b.radius, gap)) {
          fails_from[i] = b.radius;
          continue;
        }
        taken[i] = 1;
        b.position = p;
        kept.push_back(b);
        grid.insert(static_cast<int>(kept.size()) - 1, b);
        placed = true;
      }
      while (first_open < sites.size() && (taken[first_open] || fails_from[first_open] <= rmin)) ++first_open;
      if (!placed) ++res.removed;
      else if (b.id >= 0) ++res.moved;
      else ++res.added;
    }
  }
  s.balls = std::move(kept);
  for (std::size_t k = 0; k < s.balls.size(); ++k) s.balls[k].id = static_cast<int>(k);
  return res;
}

double deepest_overlap(const Scene& scene) {
  double worst = 0;
  double rmax = 0;
  for (const Ball& b : scene.balls) rmax = std::max(rmax, b.radius);
  if (scene.balls.empty()) return 0;
  const BallGrid grid(2 * rmax, scene.balls, scene.walls.periodic ? scene.walls.length : 0.0);
  const WallProbe walls(scene.walls, scene.mill_angle);
  for (std::size_t k = 0; k < scene.balls.size(); ++k) {
    const Ball& b = scene.balls[k];
    worst = std::max(worst, -walls.clearance(b.position, b.radius) / b.radius);
    grid.for_near(b.position, [&](int j) {
      if (j <= static_cast<int>(k)) return;
      const Ball& o = scene.balls[j];
      const double dist = grid.separation(b.position, o.position).norm();
      worst = std::max(worst, (b.radius + o.radius - dist) / std::min(b.radius, o.radius));
    });
  }
  return worst;
}

}  // namespace mc
