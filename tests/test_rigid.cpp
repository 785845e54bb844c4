// The rotation of a rigid body (cl/rigid.h), in double and in float: the
// torque-free symmetric and asymmetric tops against their closed forms
// (the asymmetric one in Jacobi's elliptic functions, Landau & Lifshitz,
// Mechanics, §37) over many periods, what the splitting conserves, and a
// constant torque's impulse.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

namespace rigid_f64 {
using real = double;
#include "../cl/mc_shim.h"
#include "../cl/rigid.h"
}  // namespace rigid_f64
#undef MC_SHIM_H
#undef MC_RIGID_H
namespace rigid_f32 {
using real = float;
#include "../cl/mc_shim.h"
#include "../cl/rigid.h"
}  // namespace rigid_f32

namespace {

// Jacobi's sn, cn, dn of u for the parameter m = k² < 1, by the
// arithmetic-geometric mean and descending Landen (Abramowitz & Stegun
// 16.4.3); dn from dn² = 1 − m sn² (A&S's cos φ0 / cos(φ1 − φ0) is 0/0 at
// odd multiples of K).
void jacobi(double u, double m, double& sn, double& cn, double& dn) {
  double a[20], c[20];
  a[0] = 1;
  double b = std::sqrt(1 - m);
  c[0] = std::sqrt(m);
  int n = 0;
  while (std::fabs(c[n]) > 1e-16 && n < 18) {
    a[n + 1] = 0.5 * (a[n] + b);
    c[n + 1] = 0.5 * (a[n] - b);
    b = std::sqrt(a[n] * b);
    ++n;
  }
  double phi = std::ldexp(a[n] * u, n);
  for (int k = n; k > 0; --k) phi = 0.5 * (phi + std::asin(c[k] / a[k] * std::sin(phi)));
  sn = std::sin(phi);
  cn = std::cos(phi);
  dn = std::sqrt(1 - m * sn * sn);
}

template <class V>
double len(V v) {
  return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
}

}  // namespace

TEST_CASE("quaternions: a turn about a body axis keeps the lab-frame angular momentum", "[rigid]") {
  using namespace rigid_f64;
  real4 q = quat_normalised(make_real4(0.3, -0.2, 0.5, 0.8));
  const real3 v = make_real3(0.7, -1.1, 0.4);
  const real3 back = quat_rotate_inverse(q, quat_rotate(q, v));
  CHECK(back.x == Approx(v.x).margin(1e-15));
  CHECK(back.y == Approx(v.y).margin(1e-15));
  CHECK(back.z == Approx(v.z).margin(1e-15));
  CHECK(len(quat_rotate(q, v)) == Approx(len(v)).epsilon(1e-15));
  real3 L = make_real3(1.0, 2.0, -0.5);
  const real3 lab = quat_rotate(q, L);
  for (int k = 0; k < 3; ++k) {
    rigid_turn(k, 0.37 + k, &q, &L);
    const real3 now = quat_rotate(q, L);
    CHECK(now.x == Approx(lab.x).margin(1e-14));
    CHECK(now.y == Approx(lab.y).margin(1e-14));
    CHECK(now.z == Approx(lab.z).margin(1e-14));
  }
  // A turn about z by a quarter turn takes the body's x axis to the lab's y.
  real4 r = make_real4(0, 0, 0, 1);
  real3 dummy = make_real3(0, 0, 0);
  rigid_turn(2, 0.5 * M_PI, &r, &dummy);
  const real3 x_lab = quat_rotate(r, make_real3(1, 0, 0));
  CHECK(x_lab.x == Approx(0).margin(1e-15));
  CHECK(x_lab.y == Approx(1).margin(1e-15));
}

TEST_CASE("a free symmetric top: the spin precesses in the body at (Iz - Ix)/Ix wz, to second order", "[rigid]") {
  using namespace rigid_f64;
  const double I = 1.0, Iz = 2.5, w0 = 0.3, wz = 1.2;
  const real3 inv = make_real3(1 / I, 1 / I, 1 / Iz);
  const double Omega = (Iz - I) / I * wz, period = 2 * M_PI / Omega;
  // Fifty periods of the precession at n steps a period: the worst
  // deviation from wx = w0 cos(Omega t), wy = w0 sin(Omega t) (Euler:
  // I dwx/dt = (I - Iz) wy wz, I dwy/dt = (Iz - I) wz wx), and wz's.
  auto worst = [&](int n) {
    real4 q = make_real4(0, 0, 0, 1);
    real3 L = make_real3(I * w0, 0, Iz * wz);
    const double dt = period / n;
    double w = 0, wz_dev = 0;
    for (int s = 1; s <= 50 * n; ++s) {
      rigid_free_rotation(dt, inv, &q, &L);
      const double t = s * dt;
      w = std::max({w, std::fabs(L.x / I - w0 * std::cos(Omega * t)), std::fabs(L.y / I - w0 * std::sin(Omega * t))});
      wz_dev = std::max(wz_dev, std::fabs(L.z / Iz - wz));
    }
    return std::make_pair(w, wz_dev);
  };
  const auto [coarse, coarse_z] = worst(500);
  const auto [fine, fine_z] = worst(1000);
  INFO("deviations " << coarse << " and " << fine << "; wz " << coarse_z << " and " << fine_z);
  CHECK(fine < 3e-3 * w0);
  CHECK(coarse / fine == Approx(4).epsilon(0.1));  // second order
  CHECK(fine_z < 1e-5 * wz);
  CHECK(coarse_z / fine_z == Approx(4).epsilon(0.1));
}

TEST_CASE("a free asymmetric top against Jacobi's closed form, over twenty periods", "[rigid]") {
  // I1 < I2 < I3 and M² > 2 E I2: w1 = A cn τ, w2 = B sn τ, w3 = C dn τ
  // (Landau & Lifshitz §37), τ = t sqrt((I3 - I2)(M² - 2 E I1) / (I1 I2 I3)).
  const double I1 = 1.0, I2 = 2.0, I3 = 3.0;
  const double w1 = 0.4, w3 = 0.9;  // w2 = 0 at t = 0
  const double E2 = I1 * w1 * w1 + I3 * w3 * w3, M2 = I1 * I1 * w1 * w1 + I3 * I3 * w3 * w3;
  REQUIRE(M2 > E2 * I2);
  const double A = std::sqrt((E2 * I3 - M2) / (I1 * (I3 - I1)));
  const double B = std::sqrt((E2 * I3 - M2) / (I2 * (I3 - I2)));
  const double C = std::sqrt((M2 - E2 * I1) / (I3 * (I3 - I1)));
  const double rate = std::sqrt((I3 - I2) * (M2 - E2 * I1) / (I1 * I2 * I3));
  const double m = (I2 - I1) * (E2 * I3 - M2) / ((I3 - I2) * (M2 - E2 * I1));
  REQUIRE(A == Approx(w1).epsilon(1e-12));
  REQUIRE(C == Approx(w3).epsilon(1e-12));
  const double K = std::comp_ellint_1(std::sqrt(m));
  const double period = 4 * K / rate;  // of w1 and w2

  auto run = [&](auto tag, double tolerance) {
    using real = decltype(tag);
    typename std::conditional<std::is_same<real, double>::value, rigid_f64::real4, rigid_f32::real4>::type q{0, 0, 0, 1};
    typename std::conditional<std::is_same<real, double>::value, rigid_f64::real3, rigid_f32::real3>::type L{
        real(I1 * w1), real(0), real(I3 * w3)};
    decltype(L) inv{real(1 / I1), real(1 / I2), real(1 / I3)};
    const double dt = period / 2000;
    const int steps = 20 * 2000;
    double worst = 0;
    for (int s = 1; s <= steps; ++s) {
      if constexpr (std::is_same<real, double>::value)
        rigid_f64::rigid_free_rotation(dt, inv, &q, &L);
      else
        rigid_f32::rigid_free_rotation(real(dt), inv, &q, &L);
      if (s % 50 == 0) {
        double sn, cn, dn;
        jacobi(rate * s * dt, m, sn, cn, dn);
        worst = std::max({worst, std::fabs(L.x / I1 - A * cn), std::fabs(L.y / I2 - B * sn),
                          std::fabs(L.z / I3 - C * dn)});
      }
    }
    INFO("worst deviation from the closed form " << worst);
    CHECK(worst < tolerance);
  };
  run(double{}, 2e-4);  // the phase error after 20 periods at 2000 steps a period
  run(float{}, 5e-4);   // float, as the kernels run by default
}

TEST_CASE("the splitting keeps |L| and the lab-frame L to rounding and the energy without drift", "[rigid]") {
  using namespace rigid_f64;
  // Spun near the unstable middle axis: the body flips over and over (the
  // tennis racket), the hardest motion for an integrator.
  const real3 I = make_real3(1.0, 2.0, 3.0), inv = make_real3(1.0, 0.5, 1.0 / 3.0);
  real4 q = quat_normalised(make_real4(0.1, 0.2, -0.3, 0.9));
  real3 L = make_real3(0.02 * I.x, 1.0 * I.y, 0.01 * I.z);
  const real3 L_lab0 = quat_rotate(q, L);
  auto energy = [&] { return 0.5 * (L.x * L.x / I.x + L.y * L.y / I.y + L.z * L.z / I.z); };
  const double E0 = energy(), M0 = len(L);
  const double dt = 2e-3;
  double worst_first = 0, worst_second = 0, worst_lab = 0;
  const int steps = 200000;  // t = 400: about 25 flips
  for (int s = 1; s <= steps; ++s) {
    rigid_free_rotation(dt, inv, &q, &L);
    const double e = std::fabs(energy() - E0) / E0;
    (s <= steps / 2 ? worst_first : worst_second) = std::max(s <= steps / 2 ? worst_first : worst_second, e);
    if (s % 1000 == 0) {
      const real3 lab = quat_rotate(q, L);
      worst_lab = std::max({worst_lab, std::fabs(lab.x - L_lab0.x), std::fabs(lab.y - L_lab0.y),
                            std::fabs(lab.z - L_lab0.z)});
    }
  }
  CHECK(len(L) == Approx(M0).epsilon(1e-12));
  CHECK(worst_lab < 1e-10 * M0);
  CHECK(worst_first < 1e-4);
  // No drift: the second half strays no further than the first.
  CHECK(worst_second < 1.5 * worst_first);
}

TEST_CASE("a constant torque: the angular momentum gains its impulse, whatever the spin", "[rigid]") {
  using namespace rigid_f64;
  const real3 inv = make_real3(1.0, 0.5, 0.25);
  real4 q = quat_normalised(make_real4(0.2, 0.1, 0.4, 0.9));
  real3 L = make_real3(0.3, -0.2, 0.5);
  const real3 T = make_real3(0.0, 0.0, 0.8);  // lab frame
  const real3 L_lab0 = quat_rotate(q, L);
  const double dt = 1e-3;
  for (int s = 0; s < 1000; ++s) {
    rigid_kick(dt, T, q, &L);
    rigid_free_rotation(dt, inv, &q, &L);
  }
  const real3 lab = quat_rotate(q, L);
  CHECK(lab.x == Approx(L_lab0.x).margin(1e-12));
  CHECK(lab.y == Approx(L_lab0.y).margin(1e-12));
  CHECK(lab.z == Approx(L_lab0.z + 0.8).margin(1e-12));
  // ω in the lab frame is I⁻¹ L turned out of the body.
  const real3 w = rigid_omega_lab(q, L, inv);
  const real3 wb = quat_rotate_inverse(q, w);
  CHECK(wb.x == Approx(L.x * 1.0).margin(1e-14));
  CHECK(wb.y == Approx(L.y * 0.5).margin(1e-14));
  CHECK(wb.z == Approx(L.z * 0.25).margin(1e-14));
}
