/* mc_shim.h — lets the shared headers in cl/ compile both as OpenCL C and as
 * C++. On the device `real` is float, or double with -D MC_DOUBLE. On the host
 * the includer defines `real` (and the vector types below are declared in the
 * including namespace), so one host build can hold both layouts. */
#ifndef MC_SHIM_H
#define MC_SHIM_H

#ifdef __OPENCL_VERSION__
/* ---------------------------------------------------------------- device */
#ifdef MC_DOUBLE
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double real;
typedef double2 real2;
typedef double3 real3;
typedef double4 real4;
#define MC_REAL_EPS DBL_EPSILON
#else
typedef float real;
typedef float2 real2;
typedef float3 real3;
typedef float4 real4;
#define MC_REAL_EPS FLT_EPSILON
#endif
/* No contraction of a*b+c into one fused multiply-add: OpenCL C allows it
 * by default, and a compiler that contracts decides per call site (NVIDIA's
 * did, and so does PoCL on a CPU with FMA), so the same law was rounded
 * differently in the two force kernels and in the CPU reference. Each
 * operation is rounded as written, on every device. -DMC_FP_CONTRACT (in
 * MILLCHARGE_CL_OPTIONS) lets the compiler contract, to measure what this
 * costs (docs/performance.md). */
#ifndef MC_FP_CONTRACT
#pragma OPENCL FP_CONTRACT OFF
#endif
/* Everything shared is inlined: PoCL otherwise keeps the contact law as a
 * call that passes its structs through memory. */
#define MC_FN inline __attribute__((always_inline))
#define MC_GLOBAL __global
#define MC_CONST __constant
#define make_real2(x, y) ((real2)((x), (y)))
#define make_real3(x, y, z) ((real3)((x), (y), (z)))
#define make_real4(x, y, z, w) ((real4)((x), (y), (z), (w)))
#define xyz_of(v) ((v).xyz)
#define R(x) ((real)(x))
#define MC_ATOMIC_OR(ptr, bits) atomic_or((ptr), (bits))
#define MC_ATOMIC_INC(ptr) atomic_inc(ptr)
#define MC_ATOMIC_ADD(ptr, v) atomic_add((ptr), (v))
#define MC_ROUND_LONG(x) convert_long_rte(x)

#else
/* ------------------------------------------------------------------ host */
/* The includer has declared `real` before including; these types live in the
 * includer's namespace. Alignment matches OpenCL's: a 4-vector is aligned to
 * its size, a 2-vector likewise. */
#define MC_FN inline
#define MC_GLOBAL
#define MC_CONST
#define R(x) ((real)(x))
#define MC_ATOMIC_OR(ptr, bits) (*(ptr) |= (bits))
#define MC_ATOMIC_INC(ptr) ((*(ptr))++)
#define MC_ATOMIC_ADD(ptr, v) mc_add_returning_old((ptr), (v))
#define MC_ROUND_LONG(x) static_cast<long>(std::llrint(x))
#define MC_REAL_EPS (std::numeric_limits<real>::epsilon())

typedef unsigned int uint;
typedef unsigned long ulong;
inline uint mc_add_returning_old(uint* p, uint v) {
  const uint old = *p;
  *p = old + v;
  return old;
}

struct alignas(2 * sizeof(real)) real2 { real x, y; };
struct alignas(4 * sizeof(real)) real4 { real x, y, z, w; };
struct real3 { real x, y, z; };
struct alignas(8) int2 { int x, y; };

inline real2 make_real2(real x, real y) { return real2{x, y}; }
inline real3 make_real3(real x, real y, real z) { return real3{x, y, z}; }
inline real4 make_real4(real x, real y, real z, real w) { return real4{x, y, z, w}; }
inline real3 xyz_of(const real4& v) { return real3{v.x, v.y, v.z}; }

inline real3 operator+(real3 a, real3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline real3 operator-(real3 a, real3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline real3 operator-(real3 a) { return {-a.x, -a.y, -a.z}; }
inline real3 operator*(real s, real3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline real3 operator*(real3 a, real s) { return {s * a.x, s * a.y, s * a.z}; }
inline real3 operator/(real3 a, real s) { return {a.x / s, a.y / s, a.z / s}; }
inline real3& operator+=(real3& a, real3 b) { a = a + b; return a; }
inline real3& operator-=(real3& a, real3 b) { a = a - b; return a; }
inline real dot(real3 a, real3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline real3 cross(real3 a, real3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline real2 operator+(real2 a, real2 b) { return {a.x + b.x, a.y + b.y}; }
inline real2 operator-(real2 a, real2 b) { return {a.x - b.x, a.y - b.y}; }
inline real2 operator*(real s, real2 a) { return {s * a.x, s * a.y}; }
inline real dot(real2 a, real2 b) { return a.x * b.x + a.y * b.y; }
using std::sqrt; using std::fabs; using std::fmin; using std::fmax; using std::pow;
using std::sin; using std::cos; using std::atan2; using std::floor; using std::log10;
#endif

#endif /* MC_SHIM_H */
