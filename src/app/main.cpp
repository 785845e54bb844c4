// millcharge — command line. This first version runs the built-in laboratory
// drum; case files (`run CASE`) come with the mill issue.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <stdexcept>

#include "compute/context.h"
#include "core/drum.h"
#include "sim/solver.h"

namespace {

int cmd_devices() {
  const auto devices = mc::compute::list_devices();
  if (devices.empty()) {
    std::cerr << "millcharge: no OpenCL platform found: install an OpenCL driver "
                 "(scripts/setup.sh installs PoCL for the CPU)\n";
    return 1;
  }
  for (const auto& d : devices)
    std::printf("%s\n    %s, %d compute units, %.1f GiB, fp64 %s, gl sharing %s\n", d.label().c_str(),
                d.version.c_str(), d.compute_units, d.global_mem_bytes / 1073741824.0,
                d.fp64 ? "yes" : "no", d.gl_sharing ? "yes" : "no");
  return 0;
}

struct RunOptions {
  double duration = 2.0;
  double warmup = 1.0;
  std::string device;
  std::string precision = "float";
  std::string law = "linear";
  int balls = 400;
  double speed = 0.75;
};

int cmd_run(const RunOptions& o) {
  mc::DrumSpec spec;
  spec.n_balls = o.balls;
  spec.speed_fraction = o.speed;
  spec.precision = o.precision == "double" ? mc::Precision::double_ : mc::Precision::single;
  spec.law = o.law == "hertz" ? mc::ContactLaw::hertz : mc::ContactLaw::linear;
  const mc::Scene scene = mc::make_drum(spec);
  mc::compute::Context ctx(o.device);
  auto solver = mc::make_solver(ctx, scene);
  const double dt = solver->dt();
  const double rev_s = 2 * M_PI / scene.mill_omega;
  std::printf("millcharge: lab drum D %.2f m, %d balls, %.0f %% of critical (%.1f rpm), dt %.3g s, %s, %s\n",
              spec.diameter, spec.n_balls, 100 * spec.speed_fraction, scene.mill_omega * 60 / (2 * M_PI), dt,
              o.precision.c_str(), ctx.info().label().c_str());
  const auto t0 = std::chrono::steady_clock::now();
  const long chunk = std::max(1L, static_cast<long>(0.1 / dt));
  bool warm = false;
  double sum_torque_power = 0, sum_diss = 0, span = 0;
  while (solver->time_s() < o.duration) {
    solver->advance(chunk);
    const mc::Observables ob = solver->observe(true);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (solver->time_s() > o.warmup) {
      if (warm) {
        sum_torque_power += ob.torque_power_W * ob.interval_s;
        sum_diss += ob.dissipation_power_W * ob.interval_s;
        span += ob.interval_s;
      }
      warm = true;
    }
    std::printf("t %6.2f s  rev %5.2f  torque power %8.3f W  dissipation %8.3f W  KE %.4f J  %.3g updates/s\n",
                solver->time_s(), solver->time_s() / rev_s, ob.torque_power_W, ob.dissipation_power_W,
                ob.kinetic_J, spec.n_balls * solver->steps() / wall);
    std::fflush(stdout);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("{\"n_particles\": %d, \"steps\": %ld, \"simulated_s\": %.4f, \"power_W\": {\"torque\": %.4f, "
              "\"dissipation\": %.4f}, \"wall_s\": %.2f, \"particle_updates_per_s\": %.4g, \"rebuilds\": %ld}\n",
              spec.n_balls, solver->steps(), solver->time_s(), span > 0 ? sum_torque_power / span : 0.0,
              span > 0 ? sum_diss / span : 0.0, wall, spec.n_balls * solver->steps() / wall,
              solver->rebuilds());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"millcharge: 3D DEM of tumbling mill charges on OpenCL"};
  app.require_subcommand(1);
  auto* devices = app.add_subcommand("devices", "list OpenCL platforms and devices");
  RunOptions ro;
  auto* run = app.add_subcommand("run", "run the laboratory drum headless");
  run->add_option("--duration", ro.duration, "simulated seconds")->check(CLI::PositiveNumber);
  run->add_option("--warmup", ro.warmup, "seconds before averaging")->check(CLI::NonNegativeNumber);
  run->add_option("--device", ro.device, "auto, gpu, cpu, P:D or part of a name");
  run->add_option("--precision", ro.precision)->check(CLI::IsMember({"float", "double"}));
  run->add_option("--law", ro.law)->check(CLI::IsMember({"linear", "hertz"}));
  run->add_option("--balls", ro.balls, "number of balls")->check(CLI::PositiveNumber);
  run->add_option("--speed", ro.speed, "fraction of critical speed")->check(CLI::Range(0.05, 2.0));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (*devices) return cmd_devices();
    if (*run) return cmd_run(ro);
  } catch (const std::invalid_argument& e) {
    std::cerr << "millcharge: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "millcharge: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
