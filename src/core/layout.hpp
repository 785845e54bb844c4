// Host mirrors of the structs in cl/layout.h, one set per precision: the
// header is included once with real = float (mc::f32) and once with
// real = double (mc::f64). mc::f64 also holds the physics functions of the
// shared headers, which the CPU reference runs.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

namespace mc::f32 {
using real = float;
#include "../../cl/mc_shim.h"
#include "../../cl/layout.h"
}  // namespace mc::f32

#undef MC_SHIM_H
#undef MC_LAYOUT_H

namespace mc::f64 {
using real = double;
#include "../../cl/mc_shim.h"
#include "../../cl/layout.h"
#include "../../cl/contact_law.h"
#include "../../cl/walls.h"
#include "../../cl/books.h"
#include "../../cl/periodic.h"
#include "../../cl/mesh.h"
#include "../../cl/ball_forces.h"
#include "../../cl/motion.h"
#include "../../cl/rigid.h"
#include "../../cl/body.h"
}  // namespace mc::f64

namespace mc {

static_assert(sizeof(f32::real4) == 16 && alignof(f32::real4) == 16);
static_assert(sizeof(f64::real4) == 32 && alignof(f64::real4) == 32);
static_assert(sizeof(f32::PairParams) == 8 * 4 && sizeof(f64::PairParams) == 8 * 8);
// The plates' depths, eleven reals and thirteen ints after the two 4-vectors; in double the
// struct ends padded to its 32-byte alignment (OpenCL C pads it the same way).
static_assert(sizeof(f32::SimParams) == 2 * 16 + 2 * MC_PLATE_NODES * 4 + 11 * 4 + 13 * 4);
static_assert(sizeof(f64::SimParams) == 2 * 32 + 2 * MC_PLATE_NODES * 8 + 11 * 8 + 13 * 4 + 20);
static_assert(sizeof(f32::MeshTriangle) == 4 * 16 + 8 * 4 && sizeof(f64::MeshTriangle) == 4 * 32 + 8 * 4);
static_assert(sizeof(f32::MeshGrid) == 16 + 4 * 4 + 8 * 4 && sizeof(f64::MeshGrid) == 32 + 4 * 8 + 8 * 4);
static_assert(sizeof(f32::BookParams) == 6 * 4 + 10 * 4 && sizeof(f64::BookParams) == 6 * 8 + 10 * 4);
static_assert(sizeof(f32::LifterPolygon) == MC_POLY_MAX_VERTS * 8 + 16 + 3 * 16 &&
              sizeof(f64::LifterPolygon) == MC_POLY_MAX_VERTS * 16 + 32 + 3 * 32);

// The types of one precision, for code templated on it.
template <class Real>
struct Layout;
template <>
struct Layout<float> {
  using real4 = f32::real4;
  using real2 = f32::real2;
  using int2 = f32::int2;
  using SimParams = f32::SimParams;
  using PairParams = f32::PairParams;
  using LifterPolygon = f32::LifterPolygon;
  using BookParams = f32::BookParams;
  using MeshTriangle = f32::MeshTriangle;
  using MeshGrid = f32::MeshGrid;
};
template <>
struct Layout<double> {
  using real4 = f64::real4;
  using real2 = f64::real2;
  using int2 = f64::int2;
  using SimParams = f64::SimParams;
  using PairParams = f64::PairParams;
  using LifterPolygon = f64::LifterPolygon;
  using BookParams = f64::BookParams;
  using MeshTriangle = f64::MeshTriangle;
  using MeshGrid = f64::MeshGrid;
};

}  // namespace mc
