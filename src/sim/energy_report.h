// Where the energy went over a run's averaging window, from the solver's
// books (solver.h BookSums): the collision energy spectra per pair type, the
// liner's impact, shear and wear per element and per part, and the impact
// point of the cataracting charge. Plain numbers for the outputs (io/) and
// the viewer; no OpenCL, no files.
#pragma once

#include <string>
#include <vector>

#include "core/liner.h"
#include "core/scene.h"
#include "sim/charge_profile.h"
#include "sim/solver.h"

namespace mc {

// Rates over the window: collisions per second, power in W.
struct CollisionRates {
  std::string pair;             // "steel-steel", "steel-shell", ... or "all"
  bool wall = false;
  double collisions_per_s = 0;
  double power_W = 0, normal_W = 0, tangential_W = 0, rolling_W = 0;
  double mean_energy_J = 0;     // lost per collision
  double mean_impact_speed_m_s = 0;
  double mean_contact_s = 0;    // duration of a collision
  // The normal energy spectrum: in a bin, the collisions whose normal loss
  // (not the whole) falls in it, and those normal losses; over a pair type
  // or all bins they are the collisions and normal_W again.
  double by_normal_collisions_per_s = 0, by_normal_W = 0;
  // The severity spectra (cl/layout.h): in a bin, the collisions whose
  // energy over their own R* falls in it, that energy's rate and their mean
  // R*. Impact: the energy at first touch, 1/2 m* vn^2; loss: the normal
  // loss. Over a pair type or all bins: the collisions again, the impact
  // power and normal_W.
  double impact_collisions_per_s = 0, impact_W = 0, impact_r_eff_m = 0;
  double loss_collisions_per_s = 0, loss_W = 0, loss_r_eff_m = 0;
};

struct SpectraBin {
  int type = 0;                 // pair type (core/liner.h)
  int bin = 0;
  double energy_from_J = 0, energy_to_J = 0;  // bin 0: from 0 (and losses <= 0)
  double severity_from_J_m = 0, severity_to_J_m = 0;  // E / R*, the severity spectra's bin
  CollisionRates rates;
};

struct SpectraReport {
  double window_s = 0;
  std::vector<CollisionRates> types;  // one per pair type of the balls' materials
  CollisionRates all;
  std::vector<SpectraBin> bins;       // every type × bin, type-major
  double closed_W = 0;                // collisions that closed in the window
  double open_change_W = 0;           // change of what open contacts hold
  double unrecorded_W = 0;            // contacts without a record (a full pool)
  double books_W = 0;                 // closed + open change + unrecorded
  double dissipation_W = 0;           // the solver's dissipation over the window
};

struct LinerElementRates {
  double impacts_per_s = 0;
  double impact_W = 0, shear_W = 0;          // normal and tangential losses on it
  double impact_W_m2 = 0, shear_W_m2 = 0;
  // Wear: sliding (Archard) and impact (Bitter's deformation wear, the
  // strike energy times the material's impact wear coefficient), and their
  // sum (wear_m3_per_s and what follows from it).
  double sliding_m3_per_s = 0, impact_m3_per_s = 0;
  double strike_W = 0;                       // the strike energy the impact wear reads, J/s
  double wear_m3_per_s = 0;
  double wear_mm_per_1000h = 0;              // depth worn, at this rate
  double wear_kg_per_h = 0;
};

// Sums over a part of the liner: the shell, each lifter face over all rows,
// the end plates.
struct LinerPartRates {
  std::string name;  // "shell", "lifter leading faces", "lifter tops", "lifter trailing faces", "end plates"
  double area_m2 = 0, impacts_per_s = 0, impact_W = 0, shear_W = 0, wear_kg_per_h = 0;
  double sliding_kg_per_h = 0, impact_kg_per_h = 0, strike_W = 0;  // wear_kg_per_h = sliding + impact
  double mean_wear_mm_per_1000h = 0, worst_wear_mm_per_1000h = 0;
};

struct LinerReport {
  double window_s = 0;
  std::vector<LinerElementRates> elements;  // in layout order
  std::vector<LinerPartRates> parts;
  // The mesh walls' wear (in the part "mesh walls") by what each mesh stands
  // for (core/scene.h MeshPart order: shell, lifters, ends), kg/h.
  double mesh_wear_kg_per_h_by_part[3] = {0, 0, 0};
  double impacts_per_s = 0, impact_W = 0, shear_W = 0, wear_kg_per_h = 0;
  double sliding_kg_per_h = 0, impact_kg_per_h = 0, strike_W = 0;
  int worst_element = -1;
  double worst_wear_mm_per_1000h = 0;
  // The lab frame: impact power on the shell and lifters per degree
  // (counter-clockwise from 3 o'clock), and how much of the liner there the
  // charge covers: the contact profile over its peak (the bed), at most 1.
  // Impact power on bare liner weighs each degree's by the share left bare,
  // 1 − coverage: the cataract's landing on liner above the toe counts, the
  // bed's own rubbing does not. The impact point is where that bare-liner
  // impact power peaks (smoothed over 9 degrees) from the shoulder to 45
  // degrees past the toe; it lies on bare liner where the charge covers less
  // than half of it, else on the toe. NaN where the toe or shoulder is not
  // known.
  std::vector<double> impact_W_per_deg;
  std::vector<double> coverage;  // per degree, 0..1
  double toe_deg = 0, shoulder_deg = 0;  // the charge's, that the above are taken with
  double bare_liner_impact_W = 0, bare_liner_impact_share = 0;
  double impact_point_deg = 0;
  bool impact_point_on_liner = false;  // before the toe: on bare liner above it
  // The same along the mill: by the liner's axial bins (the layout's
  // axial_bins, equal spans of the length or a slice's period), each bin's
  // impact power on the shell and lifters (W) and its impact point, found as
  // above from the bin's own impact power per degree with the whole mill's
  // coverage, toe and shoulder. NaN where a bin booked no impact power on
  // bare liner along the arc; empty where the toe is not known or the books
  // have no axial profile (a run resumed mid-window from a state saved
  // before they were kept).
  std::vector<double> impact_W_by_axial, impact_point_deg_by_axial;
};

// A lifter profile's wear stations (core/lifters.h kWearStations), from its
// leading foot over the top to its trailing foot: the mean of its rows (rows
// k, k + profiles, ...). Where it lies in the bar's frame (m) and the rates.
struct LifterStation {
  int profile = 0, station = 0;
  double x_m = 0, y_m = 0, length_m = 0;
  double impacts_per_s = 0, impact_W = 0, shear_W = 0;
  double strike_W = 0;             // the strike energy the impact wear reads, J/s
  double sliding_m3_per_s = 0, impact_m3_per_s = 0;  // of one row over the mill's (or slice's) length
  double wear_m3_per_s = 0;        // their sum
  double wear_mm_per_1000h = 0;    // depth, at this rate
};
// `outlines`: each profile's outline (core/lifters.h profile_outline);
// `length` the mill's (or the slice's) length, m; `impact_k` the liner's
// impact wear coefficient, m³/J.
std::vector<LifterStation> lifter_stations(const BookSums& books, double window_s,
                                           const std::vector<std::vector<Vec2>>& outlines, double shell_radius,
                                           double length, double impact_k);

// The wear of the shell and the lifters (a mesh counted by the part it
// stands for), kg/h: what plants weigh as shell liners, and what scales
// with the mill's length; not the end plates.
double shell_lifters_wear_kg_per_h(const LinerReport& r);

// The liner's books over one half of the window (RunSummary::half_books):
// the first half as taken, or the second (the whole less the first); the
// spectra and the impact profile are left empty. False where the run has
// no halves or they do not fit these books.
bool liner_books_half(const BookSums& whole, const std::vector<double>& first_half, int half, BookSums& out);

// Each liner element's impact wear coefficient (m³/J): its mesh's
// material's, or the liner's.
std::vector<double> liner_impact_coefficients(const Scene& scene);

SpectraReport spectra_report(const Scene& scene, const BookSums& books, double window_s, double open_start_J,
                             double open_end_J, double dissipated_J);

// `contact_profile`: the window's counts of balls touching the shell or a
// lifter per degree (the run's toe and shoulder come from it), `angles` those.
LinerReport liner_report(const Scene& scene, const LinerLayout& layout, const BookSums& books, double window_s,
                         const std::vector<long>& contact_profile, const ChargeAngles& angles);

}  // namespace mc
