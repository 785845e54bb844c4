// Plain double vectors for the host side (the kernels have their own types).
#pragma once

#include <array>
#include <cmath>

namespace mc {

struct Vec2 {
  double x = 0, y = 0;
};

struct Vec3 {
  double x = 0, y = 0, z = 0;
  Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
  double dot(const Vec3& o) const { return x * o.x + y * o.y + z * o.z; }
  double norm() const { return std::sqrt(dot(*this)); }
};

// A wall triangle: its vertices counter-clockwise seen from the side it
// faces (the side its normal points to).
struct Triangle {
  std::array<Vec3, 3> v;
};

}  // namespace mc
