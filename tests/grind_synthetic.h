// Synthetic batch tests for the interval tests (no DEM run): a made-up
// ball mill's spectrum and a harder second mill, a known ore, seeded
// uniform scatter, and the usual 5 times x 13 sieves test of an ore.
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "grind/circuit.h"
#include "grind/fit.h"
#include "grind/ore.h"
#include "grind/pbm.h"
#include "io/ore_file.h"

namespace mc::test {

// A ball mill's spectrum, made up: collisions from 0.5 mJ to 50 mJ, fewer
// the harder, between surfaces of 10 mm effective radius.
inline std::vector<grind::SpectrumBin> synthetic_spectrum() {
  std::vector<grind::SpectrumBin> s;
  for (int k = 0; k < 12; ++k) {
    const double e = 5e-4 * std::pow(10.0, k / 5.5);
    s.push_back({2e4 * std::pow(e / 5e-4, -1.2), e, 0.01});
  }
  return s;
}
// A second mill, made up: fewer collisions, ten times harder.
inline std::vector<grind::SpectrumBin> harder_spectrum() {
  std::vector<grind::SpectrumBin> s = synthetic_spectrum();
  for (grind::SpectrumBin& b : s) b.energy_J *= 10, b.collisions_per_s /= 20;
  return s;
}
constexpr double kPower_W = 80, kHoldup_kg = 1.2;

inline grind::Ore known_ore() {
  grind::Ore o = mc::io::read_ore(std::filesystem::path(MC_ASSET_DIR) / "ores" / "example_spectrum.toml");
  o.efficiency = 0.35;
  return o;
}

// Uniform scatter in [-1, 1], the same on every machine (xorshift64, as
// test_grind_fit.cpp's).
struct Scatter {
  std::uint64_t state;
  explicit Scatter(std::uint64_t seed) : state(88172645463325252ULL + seed * 0x9E3779B97F4A7C15ULL) {}
  double next() {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return 2.0 * static_cast<double>(state >> 11) / 9007199254740992.0 - 1.0;
  }
};

// 5 times x 13 sieves (3.35 mm and the √2 series from 2.36 mm), the ore's
// products in the mill of `spectrum` with ±noise_pp of uniform scatter.
// Not clipped to 0..1: readings clipped near 1 scatter less than the rest,
// s² pooled over every reading comes out below the scatter of those that
// carry the information, and the intervals narrower than they should be
// (docs/grinding-intervals.md: 0.939 unclipped, less clipped).
inline grind::BatchTest synthetic_test(const grind::Ore& ore, double noise_pp, std::uint64_t seed,
                                       const std::vector<grind::SpectrumBin>& spectrum = synthetic_spectrum(),
                                       std::vector<double> times = {0.5, 1, 2, 4, 8}, bool clipped = false) {
  grind::BatchTest t;
  t.sieve_m.push_back(3.35e-3);
  for (int k = 0; k < 12; ++k) t.sieve_m.push_back(2.36e-3 / std::pow(std::sqrt(2.0), k));
  for (double x : t.sieve_m) t.feed_passing.push_back(grind::passing_at(ore.sizes, ore.feed, x));
  t.feed_passing[0] = 1;
  t.times_min = std::move(times);
  t.holdup_kg = kHoldup_kg;
  t.noise_pp = noise_pp;
  t.passing = grind::batch_test_products(ore, spectrum, kPower_W, kHoldup_kg, t);
  Scatter s(seed);
  for (auto& row : t.passing)
    for (std::size_t k = 1; k < row.size(); ++k) {
      row[k] += noise_pp / 100 * s.next();
      if (clipped) row[k] = std::min(1.0, std::max(0.0, row[k]));
    }
  return t;
}

// The product outside the test: P80 (um) after 20 min in the first mill.
inline std::vector<double> p80_at_20_min(const grind::Ore& o) {
  const auto spectrum = synthetic_spectrum();
  const grind::MillRates r = grind::mill_rates(o, spectrum, kPower_W, kHoldup_kg);
  const std::vector<double> m = grind::batch_grind(o.feed, r.S_per_min, grind::appearance_matrix(o, spectrum), 20);
  return {grind::passing_size(o.sizes, m, 0.8) * 1e6};
}

// A third mill's product: P80 (um) after 10 min with two kinds of collision.
inline std::vector<double> p80_third_mill(const grind::Ore& o) {
  const std::vector<grind::SpectrumBin> third = {{3e3, 4e-3, 0.015}, {300, 4e-2, 0.015}};
  const grind::MillRates r = grind::mill_rates(o, third, 200, 5);
  return {grind::passing_size(o.sizes, grind::batch_grind(o.feed, r.S_per_min, grind::appearance_matrix(o, third), 10),
                              0.8) *
          1e6};
}

}  // namespace mc::test
