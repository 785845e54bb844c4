#include "app/life_options.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <set>
#include <stdexcept>

#include "app/cli_checks.h"

namespace mc::app {

void add_life_options(CLI::App* life, LifeOptions& lo) {
  life->add_option("--out", lo.out, "study folder (default runs/CASE-life); a study there resumes");
  life->add_option("--stages", lo.stages, "worn stages after the new liner")
      ->check(cli::count(1, 100))
      ->required();
  life->add_option("--hours", lo.hours, "operating hours the study covers, in equal stages")
      ->check(cli::positive("h"));
  life->add_option("--until-height", lo.until_height_mm, "or: until the tallest lifters are this high")
      ->check(cli::positive("mm"))
      ->type_name("MM");
  life->add_option("--calibrate-loss", lo.calibrate_loss_mm,
                   "measured: the lifters lost MM of height in --calibrate-hours H (sets the hours)")
      ->check(cli::positive("mm"))
      ->type_name("MM");
  life->add_option("--calibrate-hours", lo.calibrate_hours, "the hours of --calibrate-loss")
      ->check(cli::positive("h"))
      ->type_name("H");
  life->add_option("--calibrate-rate", lo.calibrate_rate_kg_h,
                   "measured: the new shell liner (shell and lifters) wears KG/H (sets the hours)")
      ->check(cli::positive("kg/h"))
      ->type_name("KG/H");
  life->add_option("--calibrate-consumption", lo.calibrate_consumption_g_kWh,
                   "measured: the new shell and lifters wear G_PER_KWH grams of steel per kWh the mill draws (sets "
                   "the hours; end plates not counted)")
      ->check(cli::positive("g/kWh"))
      ->type_name("G_PER_KWH");
  life->add_option("--impact-share", lo.impact_share,
                   "the share S (0 to 1) of the new shell and lifters' wear that impact wear does, the rest sliding "
                   "(sets both wear coefficients; the hours stay those of the case's, or a calibration's)")
      ->check(cli::between(0, 1))
      ->type_name("S");
  life->add_option("--shell-wear-ratio", lo.shell_wear_ratio,
                   "the shell plates' wear coefficients over the lifter bars' (default 1: one liner steel): the "
                   "shell wears R times what the bars' coefficients give it")
      ->check(cli::between(0.01, 100))
      ->type_name("R");
  life->add_option("--mesh-smoothing", lo.mesh_smoothing_mm,
                   "a mesh liner's booked wear averaged over the surface around each triangle, a Gaussian of MM "
                   "standard deviation across the mill's axis (default: the largest ball's radius)")
      ->check(cli::between(0.1, 1000))
      ->type_name("MM");
  life->add_option("--axial-segments", lo.axial_segments,
                   "the bars and the shell measured in N equal spans along the mill (bars of [lifters] worn as a mesh "
                   "twin), and a mesh moved so that each bar removes its wear in each span: life_segments.csv")
      ->check(cli::count(1, 32))
      ->type_name("N");
  life->add_option("--lifter-mesh", lo.lifter_mesh_mm,
                   "with --axial-segments on a mill of [lifters]: the bars worn as a mesh of triangles at most MM "
                   "across (default: the largest ball's radius, at most half a segment)")
      ->check(cli::between(0.5, 1000))
      ->type_name("MM");
  life->add_option("--mesh-smoothing-along", lo.mesh_smoothing_along_mm,
                   "and of MM along the axis (default: four times --mesh-smoothing)")
      ->check(cli::between(0.1, 10000))
      ->type_name("MM");
  life->add_flag("--hold-plates", lo.hold_plates,
                 "the end plates stay as they are (by default they wear by their rings, as the shell and bars do)");
  life->add_flag("--force", lo.force, "start the study again in an --out that holds one");
  life->add_flag("--quiet", lo.quiet, "no progress lines from the stages' runs");
}

namespace {

// Set by the sweep for every study: its folder, a fresh start, the log.
const std::set<std::string> kSweepSets = {"out", "force", "quiet"};

}  // namespace

std::vector<std::string> sweep_life_option_names() {
  CLI::App app;
  LifeOptions o;
  add_life_options(&app, o);
  std::vector<std::string> out;
  for (const CLI::Option* opt : app.get_options()) {
    const std::string name = opt->get_single_name();
    if (opt->get_lnames().empty() || name == "help" || kSweepSets.count(name)) continue;
    out.push_back(name);
  }
  return out;
}

LifeOptions life_options_from(const std::vector<std::string>& args) {
  const std::vector<std::string> names = sweep_life_option_names();
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  for (const std::string& a : args) {
    const std::string name = a.substr(2, a.find('=') - 2);
    if (kSweepSets.count(name))
      throw std::invalid_argument("life." + name + ": " +
                                  (name == "out" ? std::string("the sweep gives each study its case's folder, cases/NAME")
                                                 : "--" + name + " is not for a sweep's studies (a study resumes "
                                                   "itself; its runs' progress goes to run.log)"));
    if (std::find(names.begin(), names.end(), name) == names.end())
      throw std::invalid_argument("life." + name + ": not an option of millcharge life (its options: " + list + ")");
  }
  CLI::App app;
  LifeOptions o;
  add_life_options(&app, o);
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw std::invalid_argument(std::string("life: ") + e.what());
  }
  return o;
}

}  // namespace mc::app
