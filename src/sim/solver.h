// The DEM solver: owns the device state of one scene and runs the step
//   motion → (binning → contacts when a ball has moved half the skin) → forces
// entirely in OpenCL kernels. Observers read device reductions.
#pragma once

#include <cstddef>
#include <memory>
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
  double total_energy() const { return kinetic_J + rotational_J + potential_J + elastic_J; }
};

inline constexpr int kProfileBins = 360;

class Solver {
 public:
  virtual ~Solver() = default;
  virtual void advance(long steps) = 0;
  virtual std::vector<BallState> balls() = 0;  // sorted by id
  virtual Observables observe(bool reset = true) = 0;
  // Each listed pair as (id, neighbour id), both directions, for tests.
  virtual std::vector<std::pair<int, int>> neighbour_pairs() = 0;
  virtual void set_mill_omega(double omega_rad_s) = 0;

  // Where the charge touches the mill: each call adds, for every ball now
  // touching the shell or a lifter, one count to the bin of its lab-frame
  // angle (kProfileBins bins from 3 o'clock, counter-clockwise).
  virtual void sample_contact_profile() = 0;
  // The counts since the last take; resets them.
  virtual std::vector<long> take_contact_profile() = 0;

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
};

// Builds the kernels for the scene's precision and law, uploads the scene and
// evaluates the first forces. Throws std::invalid_argument for a bad scene and
// compute::Error for device trouble.
std::unique_ptr<Solver> make_solver(compute::Context& ctx, const Scene& scene);

// Skin used when the scene leaves it at 0: 30 % of the smallest radius.
double default_skin(const Scene& scene);

}  // namespace mc
