// The DEM solver: owns the device state of one scene and runs the step
//   motion → (binning → contacts when a ball has moved half the skin) → forces
// entirely in OpenCL kernels. Observers read device reductions.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "compute/context.h"
#include "core/scene.h"

namespace mc {

// One ball as the host sees it, velocities synchronised to the step time.
struct BallState {
  int id = 0;
  int material = 0;
  double radius = 0;
  Vec3 position, velocity, omega, force, torque;
};

// Sums over the charge. The *_power_W and wall_torque_Nm values are means
// over the interval since the last reset; energies are at the current step.
struct Observables {
  double interval_s = 0;
  double wall_torque_Nm = 0;       // torque of the walls on the charge about +z
  double torque_power_W = 0;       // work done by the turning walls per second
  double dissipation_power_W = 0;  // energy lost in contacts per second
  double dissipated_J = 0;         // energy lost in the interval
  double wall_work_J = 0;          // work of the walls in the interval
  double kinetic_J = 0;            // translational
  double rotational_J = 0;
  double potential_J = 0;          // gravity, zero at the mill axis
  double elastic_J = 0;            // stored in contacts
  double neighbours_per_ball = 0;  // list entries per ball
  double charge_mass_kg = 0;
  double com_x_m = 0, com_y_m = 0; // centre of mass in the lab frame now
  // What the contacts open now have lost since they began (their records):
  // with the spectra's closed collisions, the books of the dissipation.
  double open_loss_normal_J = 0, open_loss_tangential_J = 0, open_loss_rolling_J = 0;
  double total_energy() const { return kinetic_J + rotational_J + potential_J + elastic_J; }
  double open_loss_J() const { return open_loss_normal_J + open_loss_tangential_J + open_loss_rolling_J; }
};

// The energy books' sums since they were last reset, decoded from the
// device's 64-bit integers (cl/books.h; layout in cl/layout.h).
struct BookSums {
  int n_types = 0;     // spectra rows; row n_types holds contacts without a record
  int n_elements = 0;
  // spectra[(row · MC_SPECTRA_BINS + bin) · MC_SPECTRA_FIELDS + field]:
  // collisions, normal, tangential and rolling losses (J), the sum of their
  // impact speeds (m/s) and of their steps in contact
  std::vector<double> spectra;
  // liner[element · MC_LINER_FIELDS + field]: impacts, impact energy (J),
  // shear energy (J), Archard wear volume (m³), strike energy (J)
  std::vector<double> liner;
  // stations[(row · MC_WEAR_STATIONS + station) · MC_LINER_FIELDS + field]:
  // the same sums per lifter row over its wear stations, along its exposed
  // outline from the leading foot to the trailing one (cl/layout.h)
  int n_stations = 0;
  std::vector<double> stations;
  std::vector<double> impact_profile;  // J on the shell and lifters per degree, lab frame
  // The same by the liner's axial bins: [axial · MC_IMPACT_BINS + degree].
  int impact_axial_bins = 0;
  std::vector<double> impact_profile_axial;
  double at(int row, int bin, int field) const;
  double liner_at(int element, int field) const;
  // Closed collisions' losses in all rows (J).
  double closed_loss_J() const;
};

// Lower edge of a spectra bin, J (cl/books.h spectra_edge).
double spectra_edge_J(int bin);

inline constexpr int kProfileBins = 360;

// Where a step's time goes, for the benchmark: wall seconds per stage, taken
// with the queue drained after each stage (so only while timing is on).
struct StageTimes {
  double binning_s = 0;     // cell of each ball, sort, reorder of the state
  double contacts_s = 0;    // neighbour lists and the history carry-over
  double forces_s = 0;      // contact and wall forces
  double motion_s = 0;      // integration and the status word
  double reductions_s = 0;  // observables and the contact profile
  double total() const { return binning_s + contacts_s + forces_s + motion_s + reductions_s; }
};

// Contacts now, for reports: ball-ball contacts per ball (each pair counted
// by both balls, the coordination number), wall contacts per ball, and
// neighbour-list entries per ball.
struct ContactStats {
  double ball_contacts_per_ball = 0;
  double wall_contacts_per_ball = 0;
  double list_entries_per_ball = 0;
};

// The whole state a solver continues from, for checkpoints: host scalars and
// the device arrays that live across steps, byte for byte in the device's
// layout (scratch arrays are left out). Restoring it into a solver built for
// the same scene, precision and device continues the run bit for bit.
struct SolverState {
  int real_bytes = 0;  // 4 float, 8 double
  long n_balls = 0;
  double time_s = 0;
  long steps = 0;
  long rebuilds = 0;
  double mill_angle = 0;
  double mill_omega = 0;
  double observed_since = 0;
  int pending_flags = 0;  // the last step's status, not yet acted on
  std::vector<std::pair<std::string, std::vector<unsigned char>>> arrays;  // name → bytes
};

// A rigid body (core/scene.h Body) as the solver has it at the step:
// velocities synchronised as a ball's (v(n), L(n)).
struct BodyState {
  Vec3 position;                       // centre of mass, m
  Vec3 velocity;                       // m/s
  Vec3 omega;                          // rad/s, lab frame
  Vec3 angular_momentum;               // kg·m²/s, lab frame
  std::array<double, 4> orientation{};  // unit quaternion (x, y, z, w), body → lab
  double kinetic_J = 0, rotational_J = 0;
};

class Solver {
 public:
  virtual ~Solver() = default;
  virtual void advance(long steps) = 0;
  virtual std::vector<BallState> balls() = 0;  // sorted by id
  virtual std::vector<BodyState> bodies() = 0;  // in the scene's order
  virtual Observables observe(bool reset = true) = 0;
  // Each listed pair as (id, neighbour id), once (as the list holding it
  // has it), for tests.
  virtual std::vector<std::pair<int, int>> neighbour_pairs() = 0;
  virtual void set_mill_omega(double omega_rad_s) = 0;
  // Viscous damping of every ball's velocity and spin, dv/dt = -rate·v, for
  // settling the charge (0, the default: none). Not part of SolverState:
  // whoever restores a state sets it again.
  virtual void set_velocity_damping(double rate_per_s) = 0;

  // Where the charge touches the mill: each call adds, for every ball now
  // touching the shell or a lifter, one count to the bin of its lab-frame
  // angle (kProfileBins bins from 3 o'clock, counter-clockwise).
  virtual void sample_contact_profile() = 0;
  // The counts since the last take; resets them.
  virtual std::vector<long> take_contact_profile() = 0;

  // Stage timing (off by default): turning it on drains the queue after
  // every stage, which costs a little; reset by turning it on again.
  virtual void set_stage_timing(bool on) = 0;
  virtual StageTimes stage_times() const = 0;
  virtual ContactStats contact_stats() = 0;

  // The energy books (collision spectra of closed contacts, liner sums,
  // impact profile) since the last reset; reset_books zeroes them (the
  // start of an averaging window). Synchronises.
  virtual BookSums read_books() = 0;
  virtual void reset_books() = 0;
  // Contacts that found the record pool full so far (each kept no spring
  // until the pool was packed): zero in a healthy run.
  virtual long records_refused() = 0;

  virtual SolverState save_state() = 0;
  // Throws std::invalid_argument when the state does not fit this solver.
  virtual void restore_state(const SolverState& state) = 0;
  // Fault injection for the failure tests: the ball with this id gets a NaN
  // velocity.
  virtual void poison_ball(int id) = 0;
  // The viewer's data for every ball (cl/instances.h: centre, radius, speed,
  // material, dissipation power since the last observe(true), id) written
  // into `out`, which holds at least balls × MC_INSTANCE_FLOATS floats: a
  // device buffer, or an OpenCL view of a GL buffer that the caller has
  // acquired. The kernel is built on the first call. Enqueued only: the
  // caller finishes the queue before reading or drawing.
  virtual void write_instances(const cl::Buffer& out);

  virtual double time_s() const = 0;
  virtual long steps() const = 0;
  virtual long rebuilds() const = 0;
  virtual double mill_angle() const = 0;
  virtual double dt() const = 0;
  virtual std::size_t device_bytes() const = 0;
  virtual const compute::DeviceInfo& device() const = 0;
  // Which force kernel runs: "ball" (a ball per work-item, the default) or
  // "grouped" (a work-group's touching pairs queued and their law run a
  // pair per work-item; MILLCHARGE_FORCES=grouped). Both give the same
  // forces bit for bit.
  virtual const char* forces_kernel() const = 0;
  // Steps between the host's reads of the status word (rebuild, record-pool
  // and blow-up flags): 1 on a CPU device, kGpuStatusEvery on a GPU, or
  // MILLCHARGE_STATUS_EVERY (1-64). Each read waits for the queue to reach
  // it; between reads the host enqueues steps without waiting. The lists
  // stay exact: the motion kernel flags a rebuild that many steps early.
  virtual int status_every() const = 0;
};

inline constexpr int kGpuStatusEvery = 4;

// Builds the kernels for the scene's precision and law, uploads the scene and
// evaluates the first forces. Throws std::invalid_argument for a bad scene or
// a bad MILLCHARGE_FORCES, and compute::Error for device trouble.
std::unique_ptr<Solver> make_solver(compute::Context& ctx, const Scene& scene);

// Skin used when the scene leaves it at 0: 20 % of the smallest radius (a
// thinner skin lists fewer pairs and rebuilds more often; at 20 % a dense
// charge rebuilds every 25-100 steps and lists about 6 pairs per ball), or
// more in a big mill: room for kSkinSteps steps between rebuilds at
// sqrt(2 g D), at most the smallest radius (mill D's 0.26 m slice at the
// seed's dt: 0.72 of the smallest radius, a rebuild every ~40 steps instead
// of 9, 1.2 to 1.9 times the steps per second).
inline constexpr double kSkinSteps = 30;
double default_skin(const Scene& scene);

}  // namespace mc
