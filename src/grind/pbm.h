// The population balance of grinding (docs/grinding.md): size classes on a
// geometric series, the appearance function of broken material, specific
// breakage rates from three models (Austin's, Herbst & Fuerstenau's energy
// specific rates, and a mechanistic one from the run's normal energy
// spectrum), and the mill's product: batch grinding over time, or a
// continuous mill of tanks in series at a feed rate.
//
// Classes: class i holds the sizes from top[i+1] up to top[i] (metres,
// top[0] the largest); the last class holds everything below its top (the
// sink). Masses are fractions of the charge of ore, summing to 1.
#pragma once

#include <string>
#include <vector>

namespace mc::grind {

struct SizeSeries {
  std::vector<double> top_m;  // descending; top_m.size() classes, the last the sink
  int size() const { return static_cast<int>(top_m.size()); }
  // Geometric mean size of class i (the sink: its top over the ratio's root).
  double mid_m(int i) const;
};

// n classes from top down by a constant ratio (sqrt(2) or 2^(1/4)).
SizeSeries geometric_series(double top_m, double ratio, int n);

// Austin's cumulative breakage function: the fraction of broken material
// of a class finer than x, for u = x / (the class's lower size):
// B(u) = phi u^gamma + (1 - phi) u^beta, capped at 1.
struct AustinBreakage {
  double phi = 0.5, gamma = 1.0, beta = 4.0;
  double cumulative(double u) const;
};

// b[i][j] (i > j): the fraction of what breaks out of class j that lands in
// class i; each column sums to 1 (the sink takes the rest).
std::vector<std::vector<double>> breakage_matrix(const SizeSeries& s, const AustinBreakage& b);

// Tavares' energy-dependent appearance function (Tavares' review, KONA 34,
// 2017; Carvalho & Tavares, Miner. Eng. 43-44, 2013): an event of
// mass-specific energy e gives its broken particles
//   t10 = A (1 - exp(-b' e / E50b)),
// E50b the median fracture energy of the particles the event breaks, and
// each other t_n (the share finer than the parent's size / n) follows from
// t10 by the regularized incomplete beta function,
//   t_n = I_{t10}(alpha_n, beta_n)
// (t10 and t_n as fractions). The cumulative B(u) of u = size / parent's
// size is 1 at u = 1 and t_n at u = 1/n (t10 at 0.1), log-log linear
// between them, and below the smallest 1/n the last segment's power law.
struct T10Breakage {
  double a = 0.5;        // A, t10's limit at high energy (a fraction)
  double b_prime = 1.0;  // b'
  std::vector<double> n, alpha, beta;  // n ascending, > 1, 10 left out
  double t10(double e_over_e50b) const;
  double tn(std::size_t k, double t10) const;  // t_n[k] at this t10
  double cumulative(double u, double t10) const;
};

// The regularized incomplete beta function I_x(a, b), a, b > 0, 0 <= x <= 1
// (continued fraction, Lentz's method, to 1e-14).
double incomplete_beta(double x, double a, double b);

// Batch grinding, dm_i/dt = -S_i m_i + sum_{j<i} b_ij S_j m_j, from m0 over
// time t (S per unit of t): the linear system's exact solution,
// m(t) = exp(A t) m0, the exponential by scaling and squaring (its cost
// grows with log(S_max t) only; equal rates are fine). The sink does not
// break (its S is ignored).
std::vector<double> batch_grind(const std::vector<double>& m0, const std::vector<double>& S,
                                const std::vector<std::vector<double>>& b, double t);

// The same equations stepped by fourth-order Runge-Kutta, steps of at most
// 0.01 / max S (the tests' reference; its cost grows with S_max t).
std::vector<double> batch_grind_rk4(const std::vector<double>& m0, const std::vector<double>& S,
                                    const std::vector<std::vector<double>>& b, double t);

// The same equations' closed form (Reid 1965): valid where the S_i differ.
std::vector<double> reid_batch(const std::vector<double>& m0, const std::vector<double>& S,
                               const std::vector<std::vector<double>>& b, double t);

// A continuous mill of `tanks` perfectly mixed tanks in series, each of
// mean residence time tau / tanks: the steady product of a feed (each tank:
// (I + tau_k (S - b S)) m_out = m_in, solved down the classes).
std::vector<double> continuous_grind(const std::vector<double>& feed, const std::vector<double>& S,
                                     const std::vector<std::vector<double>>& b, double tau, int tanks);

// Whiten's classification curve (as given by Napier-Munn, Morrell, Morrison
// & Kojovic 1996, Mineral Comminution Circuits, JKMRC): the fraction of
// particles of size x that reports to the overflow (the fine product),
//   E(x) = C (1 + beta beta* y) (e^alpha - 1) / (e^(alpha beta* y) + e^alpha - 2),
// y = x / d50c, C = 1 - bypass (the share of the fines that is classified;
// the rest goes to the underflow with the water), alpha the sharpness and
// beta the fish hook (0: none), beta* chosen so that E(d50c) = C / 2.
struct WhitenClassifier {
  double d50c_m = 0, alpha = 3, bypass = 0, beta = 0;
  double beta_star() const;
  double to_overflow(double x_m) const;
};

// A continuous mill closed by a classifier: fresh feed (class flows, t/h)
// joined by the classifier's underflow, ground in the mill (tanks in series,
// mean residence time holdup / the mill's whole feed), the mill's product
// split by the classifier at each class's geometric mean size. Solved by
// substitution to the steady state, where the overflow carries out the
// fresh feed's mass.
struct ClosedCircuit {
  std::vector<double> product;       // overflow, t/h by class
  std::vector<double> underflow;     // returned to the mill, t/h
  std::vector<double> mill_product;  // t/h
  double circulating_load = 0;       // underflow / fresh feed
  double residence_min = 0;          // the mill's, at the steady state
  int iterations = 0;
  bool converged = false;
};
ClosedCircuit closed_circuit(const SizeSeries& s, const std::vector<double>& fresh_t_h, const std::vector<double>& S,
                             const std::vector<std::vector<double>>& b, double holdup_t, int tanks,
                             const WhitenClassifier& c);

// Cumulative passing at each class's top (passing[i]: finer than top[i]).
std::vector<double> passing(const std::vector<double>& m);

// The size that p of the mass passes (0 < p < 1), log-linear between the
// class tops; NaN if the finest top already passes less than p.
double passing_size(const SizeSeries& s, const std::vector<double>& m, double p);

// Class masses of a feed given as cumulative passing at sieve sizes
// (descending sizes, passing in 0..1, the first sieve passing 1): the
// passing made monotone (adjacent violators pooled toward the finer sieves), then
// interpolated log-linearly at the class tops; the masses sum to 1.
std::vector<double> feed_masses(const SizeSeries& s, const std::vector<double>& sieve_m,
                                const std::vector<double>& passing);

// ---------------------------------------------------------------- rates

// Austin: S_i = a (x_i / 1 mm)^alpha / (1 + (x_i / mu)^lambda), per minute,
// x_i the class's top.
struct AustinRates {
  double a_per_min = 0, alpha = 1, mu_m = 0, lambda = 2;
};
std::vector<double> austin_rates(const SizeSeries& s, const AustinRates& r);

// Herbst & Fuerstenau: S_i^E = S1E exp(z1 ln(x_i/x1) + z2 ln²(x_i/x1)),
// t/kWh, with x_i the class's geometric mean; S_i = S_i^E P / H.
struct EnergyRates {
  double s1e_t_per_kWh = 0, x1_m = 0, zeta1 = 0, zeta2 = 0;
};
std::vector<double> energy_specific_rates(const SizeSeries& s, const EnergyRates& r);  // t/kWh

// Tavares' breakage probability: an upper-truncated lognormal of the
// mass-specific energy with median E50(d) = Einf (1 + (d0/d)^phi), spread
// sigma and truncation Emax = emax_ratio · E50.
struct Fracture {
  double e_inf_J_kg = 0, d0_m = 0, phi = 1, sigma = 0.8, emax_ratio = 10;
  double e50(double d_m) const;
  double broken(double e_J_kg, double d_m) const;  // fraction broken, 0..1
};

// One class of the normal energy spectrum: collisions per second whose
// normal loss is about energy_J, and how many ball radii (R_eff) they have.
struct SpectrumBin {
  double collisions_per_s = 0, energy_J = 0, r_eff_m = 0;
};

// The mass a collision catches of particles of size d between surfaces of
// effective radius R_eff: a monolayer where the gap is under d,
// m = packing · (pi²/3) · rho · d² · R_eff (docs/grinding.md).
double captured_mass(double d_m, double r_eff_m, double ore_density, double packing);

// The median fracture energy of the particles of size d that an event of
// specific energy e breaks: P(E50b) = P(e) / 2 (0 where P(e) is 0).
double median_broken_energy(const Fracture& f, double e_J_kg, double d_m);

// The appearance matrix of Tavares' t10 in a mill of this spectrum: for each
// class j, the t10 appearance of each collision bin (its specific energy
// E_k / m_cap,j) weighted by the mass the bin breaks of class j
// (N_k m_cap,j P_j). The parent's size is the class's geometric mean, for
// the energy and for B(u) alike; the progeny still coarser than the class's
// lower size stay in it, so each column is what leaves the class, summing
// to 1 as breakage_matrix's, and `leaving` (optional) says which share of
// the broken mass that is (the rates are S_j times it). A class nothing
// breaks gets that of an event at its E50 (its rate is 0).
// t10_mean (optional): each class's mass-weighted mean t10.
std::vector<std::vector<double>> t10_breakage_matrix(const SizeSeries& s, const std::vector<SpectrumBin>& spectrum,
                                                     const Fracture& f, const T10Breakage& t, double ore_density,
                                                     double packing, std::vector<double>* t10_mean = nullptr,
                                                     std::vector<double>* leaving = nullptr);

// S_i (per second) = efficiency / H · sum_k N_k · m_cap,i · P_i(E_k / m_cap,i).
std::vector<double> spectrum_rates(const SizeSeries& s, const std::vector<SpectrumBin>& spectrum,
                                   const Fracture& f, double ore_density, double packing, double efficiency,
                                   double holdup_kg);

}  // namespace mc::grind
