#include "life/plates.h"

#include <cmath>

#include "core/plate_wear.h"

namespace mc::life {

namespace {

double ring_area(int j, int rings, double R) {
  const double r0 = R * j / rings, r1 = R * (j + 1) / rings;
  return M_PI * (r1 * r1 - r0 * r0);
}

}  // namespace

PlateRates plate_rates(const PlateBooks& b, double sliding, double impact, double R) {
  PlateRates out;
  const int rings = b.rings(), sectors = b.sectors();
  for (int p = 0; p < 2; ++p) {
    for (int j = 0; j < rings; ++j) {
      const double a = ring_area(j, rings, R) / sectors;
      double sum = 0, sum2 = 0;
      for (int s = 0; s < sectors; ++s) {
        const double v = (sliding * b.sliding_m3_s[p][j][s] + impact * b.strike_W[p][j][s]) * 3600.0 / a;  // m/h
        sum += v, sum2 += v * v;
      }
      const double mean = sum / sectors;
      const double var = sectors > 1 ? std::max(0.0, (sum2 - sectors * mean * mean) / (sectors - 1)) : NAN;
      out.m_per_h[p].push_back(mean);
      out.se_m_per_h[p].push_back(std::sqrt(var / sectors));
    }
  }
  return out;
}

std::vector<double> plate_removed(const std::vector<double>& before, const std::vector<double>& after, double R) {
  const int rings = static_cast<int>(after.size());
  const std::vector<double> m0 = plate_ring_means(before, R / rings), m1 = plate_ring_means(after, R / rings);
  std::vector<double> out;
  for (int j = 0; j < rings; ++j) out.push_back((m1[j] - m0[j]) * ring_area(j, rings, R));
  return out;
}

PlateStep wear_plates(const std::array<std::vector<double>, 2>& depth, const PlateRates& rates, double hours,
                      double R) {
  PlateStep step;
  for (int p = 0; p < 2; ++p) {
    const int rings = static_cast<int>(rates.m_per_h[p].size());
    const std::vector<double> before = depth[p].empty() ? std::vector<double>(rings, 0.0) : depth[p];
    std::vector<double> booked(rings);
    for (int j = 0; j < rings; ++j) {
      booked[j] = rates.m_per_h[p][j] * hours;
      step.booked_m3[p].push_back(booked[j] * ring_area(j, rings, R));
    }
    const std::vector<double> inc = plate_increment(booked);
    step.depth[p] = before;
    for (int j = 0; j < rings; ++j) step.depth[p][j] += inc[j];
    step.removed_m3[p] = plate_removed(before, step.depth[p], R);
  }
  return step;
}

}  // namespace mc::life
