// What `millcharge run` reports once the mill has turned: summary.json, the
// pictures, spectra.csv, wear.csv and the liner's ParaView files, and the
// result lines on stdout (docs/outputs.md).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/liner.h"
#include "core/mill_case.h"
#include "core/morrell.h"
#include "core/scene.h"
#include "io/vtk.h"
#include "sim/batch_means.h"
#include "sim/energy_report.h"
#include "sim/mill_run.h"
#include "sim/solver.h"

namespace mc::app {

// A run that has turned to its end, as the report reads it.
struct FinishedRun {
  const MillCase& c;
  const MillDerived& d;
  const Scene& scene;
  const RunSummary& s;
  Solver& solver;
  std::string device;                 // the device's label
  std::filesystem::path out;          // the run folder
  io::PvdIndex& pvd;                  // charge.pvd, which gains the liner's snapshots
  const std::vector<double>& t_series;  // the power plot's points
  const std::vector<double>& p_torque;
  const std::vector<double>& p_diss;
};

// The standard errors of a run's means, each from its revolutions' means
// (batch means, sim/batch_means.h).
struct Errors {
  BatchMeans power, dissipation, torque, arm, toe, shoulder, com;
  BatchMeans collisions, collision_power, impacts, impact, shear, wear;
};

// The liner's consumption: steel worn per kWh the mill draws (its torque
// power), in grams, by what wears (core/liner_wear.h grams_per_kWh). The
// shell and the lifter bars are what plants weigh as "shell liners"; the
// end plates (and mesh walls, where the case has them) apart; `all` is
// every part. `relative` where the liner's wear coefficient is the default
// stand-in (core/scene.h): then the figures are relative, not a plant's.
struct LinerConsumption {
  double power_W = 0;
  double shell_lifters_kg_h = 0, end_plates_kg_h = 0, mesh_kg_h = 0, all_kg_h = 0;
  double shell_lifters_g_kWh = 0, end_plates_g_kWh = 0, mesh_g_kWh = 0, all_g_kWh = 0;
  bool has_end_plates = false, has_meshes = false;
  bool relative = false;
};
LinerConsumption liner_consumption(const LinerReport& liner, double power_W, double wear_coefficient);

// What the files and the console share: the model beside the DEM, the
// errors, the spectra and the liner over the window.
struct RunReport {
  MorrellInput mi;
  MorrellResult m;
  double toe = 0, shoulder = 0, m_with_dem = 0;
  Errors err;
  int per_rev = 1, window_revs = 0;
  double rel_err = 0;
  // How the standard errors were had: "whole revolutions", "rough" (batches
  // of less than one revolution), or "none"; `sem_why` says why, and what
  // run length gives one.
  std::string sem_kind, sem_why;
  LinerLayout layout;
  SpectraReport spectra;
  LinerReport liner;
  LinerConsumption consumption;
};

RunReport report_of(const FinishedRun& r);
// spectra.csv, wear.csv, lifter_wear.csv and summary.json first, then the
// pictures, liner.vtp and the liner beside each snapshot (a warning each
// where one cannot be written).
// Returns the files that could not be written (each was a warning).
std::vector<std::string> write_run_results(const FinishedRun& r, const RunReport& rep);
// The result lines: power, per metre, convergence, angles, collisions,
// liner, impact point, Morrell, speed, the files.
void print_run_results(const FinishedRun& r, const RunReport& rep, const std::vector<std::string>& not_written);

}  // namespace mc::app
