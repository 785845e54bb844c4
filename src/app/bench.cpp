// millcharge bench: the solver timed on a turning charge, one JSON line.
#include "app/commands.h"
#include "app/prepare.h"
#include "core/version.h"
#include "core/clump.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <numeric>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "compute/context.h"
#include "core/charge_edit.h"
#include "core/lifters.h"
#include "core/liner.h"
#include "core/mill_case.h"
#include "core/wall_mesh.h"
#include "core/morrell.h"
#include "io/atomic_file.h"
#include "io/case_file.h"
#include "io/checkpoint.h"
#include "io/energy_out.h"
#include "io/png_plot.h"
#include "io/stl.h"
#include "io/vtk.h"
#include "sim/batch_means.h"
#include "sim/energy_report.h"
#include "sim/mill_run.h"
#include "sim/solver.h"
#include "viewer/viewer.h"

namespace mc::app {

namespace fs = std::filesystem;

namespace {

// The charge of checkpoint `cp` (the run of case `p`) laid anew `tile` times
// end to end along the mill axis, in the same mill made `tile` times as
// long: a settled, turning charge of `tile` times the balls with the same
// work per ball, for timing large charges without a warm-up that a small
// machine cannot afford. The balls keep their positions (shifted by a
// length per copy), velocities and spins; contact springs start afresh (so
// `tile` 1 gives the same state as the others, per ball), and the end
// plates between copies are gone.
Prepared tile_charge(compute::Context& ctx, const Prepared& p, const io::Checkpoint& cp, int tile) {
  std::vector<BallState> slice;
  {
    auto solver = make_solver(ctx, p.scene);
    solver->restore_state(cp.solver);
    slice = solver->balls();
  }
  for (const SizeClass& sc : p.c.sizes)
    if (!sc.shape.empty())
      throw std::invalid_argument("--tile: " + p.c.name + "'s charge is of clumps (charge.size.shape = \"" + sc.shape +
                                  "\"), and only a charge of balls is tiled; run the longer mill from its case");
  const long total = static_cast<long>(slice.size()) * tile;
  if (total > 500'000'000L)
    throw std::invalid_argument("--tile " + std::to_string(tile) + ": " + thousands(total) +
                                " balls is more than a run can hold (at most 500,000,000)");
  Prepared t = p;
  t.c.length = p.c.length * tile;
  if (tile > 1) t.c.name = p.c.name + " x" + std::to_string(tile);
  t.d = derive(t.c);
  std::vector<Ball> balls;
  balls.reserve(static_cast<std::size_t>(total));
  for (int k = 0; k < tile; ++k)
    for (const BallState& s : slice) {
      Ball b;
      b.id = static_cast<int>(balls.size());
      b.material = s.material;
      b.radius = s.radius;
      b.position = {s.position.x, s.position.y, s.position.z + k * p.c.length};
      b.velocity = s.velocity;
      b.omega = s.omega;
      balls.push_back(b);
    }
  ChargeEditOptions eo;
  eo.mill_angle = cp.solver.mill_angle;
  eo.mill_omega = t.d.omega;
  ChargeEditResult r = edit_charge(t.c, t.d, std::move(balls), eo);
  if (r.added != 0 || r.removed != 0 || r.moved != 0)
    throw std::invalid_argument("--tile " + std::to_string(tile) + ": " + std::to_string(r.moved + r.removed) +
                                " balls of " + cp.case_name + "'s charge overlap the walls of the longer mill");
  t.scene = std::move(r.scene);
  return t;
}

}  // namespace

// The benchmark: the case's charge packed and turning for a warm-up, then
// timed steps with the observers a run has (a row of observables every output
// interval, ten contact-profile samples per row), then a shorter pass with
// stage timing for the shares. One JSON line on stdout.
int cmd_bench(const BenchOptions& o) {
  using clock = std::chrono::steady_clock;
  Prepared p;
  io::Checkpoint cp;
  if (!o.from.empty()) {
    if (!o.c.case_path.empty() || !o.c.overrides.empty())
      throw std::invalid_argument("--from " + o.from + ": the case is the run's own; a CASE or --set cannot be given with it");
    p = prepare_from_checkpoint(o.from, cp, "");
    if (!o.c.precision.empty() && (o.c.precision == "double") != (p.c.precision == Precision::double_))
      throw std::invalid_argument("--from " + o.from + ": the checkpoint holds " +
                                  (p.c.precision == Precision::double_ ? "double" : "float") + " state");
  } else {
    p = prepare(o.c, io::case_dir() / "bench_100k.toml");
  }
  if (o.tile > 0 && o.from.empty())
    throw std::invalid_argument("--tile " + std::to_string(o.tile) + ": needs --from DIR (the charge to repeat)");
  compute::Context ctx(o.c.device);
  auto note = [&](const std::string& s) {
    if (!o.quiet) std::fprintf(stderr, "bench: %s\n", s.c_str());
  };
  if (o.tile > 0) p = tile_charge(ctx, p, cp, o.tile);
  const MillCase& c = p.c;
  const MillDerived& d = p.d;
  const long n = static_cast<long>(p.scene.balls.size());
  note(c.name + ": " + thousands(n) + " balls on " + ctx.info().label());
  const auto t_build = clock::now();
  const bool both = o.books == "both";
  Scene scene = p.scene;
  scene.numerics.energy_books = o.books != "off";
  auto solver = make_solver(ctx, scene);
  if (!o.from.empty() && o.tile == 0) solver->restore_state(cp.solver);
  solver->set_mill_omega(d.omega);
  const double warmup_s = o.warmup >= 0 ? o.warmup : o.from.empty() ? 0.25 : 0.0;
  const long warmup = std::lround(warmup_s / d.dt);
  const long out_steps = std::max(1L, std::lround(c.output_interval / d.dt));
  const long profile_every = std::max(1L, out_steps / 10);
  // Steps in chunks between the observers' calls, as run_mill makes them;
  // `since_row` counts a solver's steps since its last row.
  auto steps = [&](Solver& sv, long& since_row, long count) {
    for (long done = 0; done < count;) {
      const long chunk = std::min(count - done, profile_every - since_row % profile_every);
      sv.advance(chunk);
      done += chunk;
      since_row += chunk;
      if (since_row % profile_every == 0) sv.sample_contact_profile();
      if (since_row >= out_steps) {
        sv.observe(true);
        (void)sv.take_contact_profile();
        since_row = 0;
      }
    }
    ctx.finish();
  };
  long since_row = 0;
  const auto t_warm = clock::now();
  note("kernels built and charge uploaded in " + duration_text(std::chrono::duration<double>(t_warm - t_build).count()) +
       "; warm-up " + thousands(warmup) + " steps");
  steps(*solver, since_row, warmup);
  const double warm_s = std::chrono::duration<double>(clock::now() - t_warm).count();
  // Without the books: a second solver from the same state, timed in turn
  // with the first, part by part, so that the machine's drift falls on both.
  std::unique_ptr<Solver> plain;
  long plain_since_row = since_row;
  if (both) {
    Scene off = p.scene;
    off.numerics.energy_books = false;
    plain = make_solver(ctx, off);
    plain->restore_state(solver->save_state());
    plain->set_mill_omega(d.omega);
  }
  long n_steps = o.steps;
  if (n_steps <= 0) {
    const double rate = warmup > 0 && warm_s > 0 ? warmup / warm_s : 100.0;
    n_steps = std::clamp(std::lround(10.0 * rate), 100L, 100000L);
  }
  note("timing " + thousands(n_steps) + " steps" + (both ? ", with the energy books and without, in turn" : ""));
  const long rebuilds0 = solver->rebuilds();
  // Timed in ten parts, each drained: on a shared machine a neighbour's burst
  // slows some parts, so the parts' spread says how far to trust the total,
  // and the best part is the figure least disturbed.
  const int n_parts = static_cast<int>(std::min(10L, n_steps));
  std::vector<double> part_rates, plain_rates;
  double wall = 0, plain_wall = 0;
  auto timed = [&](Solver& sv, long& since, long part, double& sum) {
    const auto t0 = clock::now();
    steps(sv, since, part);
    const double s = std::chrono::duration<double>(clock::now() - t0).count();
    sum += s;
    return s > 0 ? static_cast<double>(n) * part / s : 0.0;
  };
  for (int k = 0; k < n_parts; ++k) {
    const long part = n_steps * (k + 1) / n_parts - n_steps * k / n_parts;
    part_rates.push_back(timed(*solver, since_row, part, wall));
    if (plain) plain_rates.push_back(timed(*plain, plain_since_row, part, plain_wall));
  }
  std::sort(part_rates.begin(), part_rates.end());
  std::sort(plain_rates.begin(), plain_rates.end());
  const long rebuilds = solver->rebuilds() - rebuilds0;
  const ContactStats cs = solver->contact_stats();
  const std::size_t plain_bytes = plain ? plain->device_bytes() : 0;
  const std::size_t bytes = solver->device_bytes();
  plain.reset();

  // The shares: a shorter pass with the queue drained after every stage.
  const long stage_steps = std::max(20L, n_steps / 4);
  note("stage timing over " + thousands(stage_steps) + " steps");
  solver->set_stage_timing(true);
  steps(*solver, since_row, stage_steps);
  const StageTimes st = solver->stage_times();
  solver->set_stage_timing(false);

  const double total = st.total() > 0 ? st.total() : 1.0;
  nlohmann::ordered_json j;
  j["case"] = c.name;
  j["n_particles"] = n;
  j["steps"] = n_steps;
  j["wall_s"] = wall;
  j["particle_updates_per_s"] = static_cast<double>(n) * n_steps / wall;
  j["steps_per_s"] = n_steps / wall;
  j["parts"] = n_parts;
  j["part_updates_per_s"] = {{"min", part_rates.front()},
                             {"median", part_rates[part_rates.size() / 2]},
                             {"max", part_rates.back()}};
  j["energy_books"] = o.books == "off" ? "off" : "on";
  if (both) {
    // The same steps without the books, timed in turn with the ones above.
    const double plain_rate = static_cast<double>(n) * n_steps / plain_wall;
    j["books_off"] = {{"particle_updates_per_s", plain_rate},
                      {"part_updates_per_s",
                       {{"min", plain_rates.front()},
                        {"median", plain_rates[plain_rates.size() / 2]},
                        {"max", plain_rates.back()}}},
                      {"bytes_per_ball", static_cast<double>(plain_bytes) / n}};
    // How much slower the books make a step: by the totals, and by the
    // parts' medians (less moved by a neighbour's burst).
    j["books_cost"] = {{"total", wall / plain_wall - 1},
                       {"median_parts", plain_rates[plain_rates.size() / 2] / part_rates[part_rates.size() / 2] - 1}};
  } else {
    j["books_off"] = nullptr;
    j["books_cost"] = nullptr;
  }
  j["contacts_per_ball"] = cs.ball_contacts_per_ball;
  j["wall_contacts_per_ball"] = cs.wall_contacts_per_ball;
  j["list_entries_per_ball"] = cs.list_entries_per_ball;
  j["rebuild_every_steps"] = number_or_null(rebuilds > 0 ? static_cast<double>(n_steps) / rebuilds : std::nan(""));
  j["device"] = ctx.info().name;
  j["device_type"] = ctx.info().type;
  j["platform"] = ctx.info().platform_name;
  j["compute_units"] = ctx.info().compute_units;
  j["precision"] = c.precision == Precision::double_ ? "double" : "float";
  j["law"] = c.law == ContactLaw::hertz ? "hertz" : "linear";
  j["forces_kernel"] = solver->forces_kernel();
  j["status_every"] = solver->status_every();
  j["dt_s"] = d.dt;
  j["device_bytes"] = bytes;
  j["bytes_per_ball"] = static_cast<double>(bytes) / n;
  j["warmup_steps"] = warmup;
  j["from"] = o.from.empty() ? nlohmann::json() : nlohmann::json(o.from);
  j["tile"] = o.tile > 0 ? nlohmann::json(o.tile) : nlohmann::json();
  j["stage_steps"] = stage_steps;
  j["stage_timed_updates_per_s"] = static_cast<double>(n) * stage_steps / total;
  j["stages"] = {{"binning", st.binning_s / total},
                 {"contacts", st.contacts_s / total},
                 {"forces", st.forces_s / total},
                 {"motion", st.motion_s / total},
                 {"reductions", st.reductions_s / total}};
  j["build"] = {{"version", version()}, {"commit", build_commit()}};
  std::printf("%s\n", j.dump().c_str());
  return 0;
}

}  // namespace mc::app
