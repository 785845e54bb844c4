// An ore in a mill that draws a known power (docs/grinding.md): the ore's
// hold-up, its specific breakage rates by the ore's rate model, and the
// mill's products: batch grinding for a time, a continuous mill at a feed
// rate, open or closed by a classifier, and the feed rate whose product
// has a target P80.
#pragma once

#include <string>
#include <vector>

#include "grind/ore.h"
#include "grind/pbm.h"

namespace mc::grind {

// The ore in the mill (kg): the ore's holdup_kg, else its powder filling
// of the ball bed's voids (the bed's porosity, the mill's filling and
// volume) packed at the ore bed's own porosity.
double mill_holdup_kg(const Ore& ore, double ball_bed_porosity, double filling, double mill_volume_m3);

// Each class's specific breakage rate, S per minute and S^E in t/kWh (the
// one from the other by the power and the hold-up); the sink's are 0.
// `spectrum`: the run's normal energy spectrum, for the spectrum model
// (with Tavares' t10, the rates of the mass that leaves each class).
struct MillRates {
  std::vector<double> S_per_min, SE_t_per_kWh;
};
MillRates mill_rates(const Ore& ore, const std::vector<SpectrumBin>& spectrum, double power_W, double holdup_kg);

// The appearance matrix b_ij of the ore in this mill: Austin's B, or
// Tavares' t10 from the collisions of the spectrum (t10_breakage_matrix).
// t10_mean (optional): each class's mean t10 (t10 only; left empty else).
std::vector<std::vector<double>> appearance_matrix(const Ore& ore, const std::vector<SpectrumBin>& spectrum,
                                                   std::vector<double>* t10_mean = nullptr);

// The mill: the fresh feed's class masses (summing to 1), the rates, the
// appearance matrix, the power and the hold-up, tanks in series, and the
// classifier when the circuit is closed.
struct Circuit {
  SizeSeries sizes;
  std::vector<double> feed;
  std::vector<double> S_per_min;
  std::vector<std::vector<double>> b;
  std::vector<double> t10_mean;  // Tavares' t10: each class's mean t10 in this mill; empty for Austin's B
  double power_kW = 0, holdup_t = 0;
  int tanks = 1;
  bool closed = false;
  WhitenClassifier classifier;
};

// A product: class masses per unit of feed and what it took.
struct Product {
  std::string label;  // named by the caller
  double t_min = 0, feed_t_h = 0, kWh_t = 0, p80_m = 0;
  double circulating_load = -1;  // a closed circuit's; < 0: open
  bool converged = true;
  std::vector<double> m;
};

// The charge ground for t_min minutes.
Product batch_product(const Circuit& c, double t_min);
// The steady product fed at feed_t_h, open or closed.
Product continuous_product(const Circuit& c, double feed_t_h);

// The feed rate whose product has P80 target_m, bisected between the
// slowest and the fastest feed.
constexpr double kSlowestFeed_t_h = 1e-9, kFastestFeed_t_h = 1e6;
struct TargetFeed {
  enum class Outcome {
    met,
    coarse_when_slowest,  // even at the slowest feed the P80 is not below the target
    fine_when_fastest,    // even at the fastest feed the P80 is not above it
    missed,               // the bisection's product is off the target by more than 1 %
  };
  Outcome outcome = Outcome::met;
  double p80_slowest_m = 0, p80_fastest_m = 0;  // 0 where the P80 is below the finest class
  double rate_t_h = 0;                          // met or missed: the rate bisected to
  Product product;                              // met or missed: the product at that rate
};
TargetFeed feed_rate_for_p80(const Circuit& c, double target_m);

}  // namespace mc::grind
