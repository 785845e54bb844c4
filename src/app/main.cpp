// millcharge — the command line (DESIGN.md, "Command line"):
//   millcharge run   [CASE] [--out DIR] [--duration S] [--device SPEC]
//                    [--precision float|double] [--set KEY=VALUE]... [--force] [--quiet]
//   millcharge run   --resume DIR [--duration S|auto] [--set run.max_duration=S] [--device SPEC] [--quiet]
//   millcharge view  [CASE] [same options] [--frames N --screenshot FILE.png]
//                    [--steps-per-frame N] [--camera end|iso] [--colour MODE] [--liner MODE] [--size WxH]
//                    [--no-panel] [--edit FRAME:KEY=VALUE]... [--from RUN] [--save-state DIR]
//   millcharge check CASE [--set KEY=VALUE]...
//   millcharge bench [CASE] [--steps N] [--warmup N] [--device SPEC]
//                    [--precision float|double] [--set KEY=VALUE]... [--quiet]
//   millcharge devices
//   millcharge grind RUN_DIR --ore ORE.toml [--time MIN,...] [--feed-rate T/H] [--target-p80 UM]
//                    [--classifier D50C_UM [--sharpness A] [--bypass B]]
//                    [--tanks N] [--bond P1_UM] [--scale-from LAB_RUN] [--out DIR] [--quiet]
//   millcharge grind RUN_DIR --ore START.toml --fit TEST.toml [--fit-params NAME,...] [--sieve-errors MODEL] [--out DIR]
//   millcharge grind RUN_DIR --ore START.toml --bond P1_UM --fit-wi WI [--fit-params NAME]
//   millcharge sweep check FILE | run FILE --local [N]|--slurm|--print | collect DIR
// Exit status: 0 done; 2 bad input (a message names the key; nothing written);
// 1 any other failure (device, blow-up, disk).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/version.h"
#include "app/cli_checks.h"
#include "app/commands.h"
#include "app/grind.h"
#include "app/life_options.h"
#include "app/sweep.h"
#include "compute/context.h"

namespace {

void add_case_options(CLI::App* cmd, mc::app::CaseOptions& o, bool with_run_options,
                      const char* default_case = "lab.toml") {
  cmd->add_option("case", o.case_path, std::string("case file (TOML); default: assets/cases/") + default_case);
  cmd->add_option("--set", o.overrides, "override a case key, e.g. --set mill.speed_fraction=0.8 (repeatable)")
      ->type_name("KEY=VALUE");
  if (with_run_options) {
    cmd->add_option_function<std::string>(
           "--duration",
           [&o](const std::string& v) {
             if (v == "auto") {
               o.duration_auto = true;
               return;
             }
             std::size_t used = 0;
             double s = 0;
             try {
               s = std::stod(v, &used);
             } catch (const std::exception&) {
               used = 0;
             }
             if (used != v.size() || !(s > 0) || !std::isfinite(s))
               throw CLI::ValidationError("--duration", "expected seconds > 0 or \"auto\", got \"" + v + "\"");
             o.duration = s;
           },
           "seconds of turning, or auto: until the power converges (overrides run.duration)")
        ->type_name("S|auto");
    cmd->add_option("--device", o.device, "OpenCL device: auto, gpu, cpu, P:D, pocl, nvidia, amd, intel, rusticl, mesa or part of a name");
    cmd->add_option("--precision", o.precision, "float or double (overrides run.precision)")
        ->check(CLI::IsMember({"float", "double"}));
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"millcharge: 3D DEM of tumbling mill charges on OpenCL"};
  app.set_version_flag("--version", mc::version_line(), "print the version and the commit it was built from");
  app.require_subcommand(1);
  auto* devices = app.add_subcommand("devices", "list OpenCL platforms and devices");

  mc::app::RunOptions ro;
  auto* run = app.add_subcommand("run", "run a mill case headless and write its results");
  add_case_options(run, ro.c, true);
  run->add_option("--out", ro.out, "output folder (default runs/CASE-DATE-TIME)");
  run->add_flag("--force", ro.force, "replace an earlier run in --out");
  run->add_flag("--quiet", ro.quiet, "no progress lines");
  run->add_option("--resume", ro.resume,
                  "continue the run in DIR from its checkpoint (checkpoint.bin); with --duration (or --set "
                  "run.max_duration=, run.tolerance=) a finished run is turned longer")
      ->type_name("DIR");
  // Fault injection for the failure tests; not for users.
  run->add_option("--inject-nan-at", ro.poison_at_s, "")->group("");

  mc::app::ViewOptions vo;
  auto* view = app.add_subcommand("view", "watch the charge in a window and change the mill while it turns");
  add_case_options(view, vo.c, false);  // no --duration: the window runs until it is closed
  view->add_option("--device", vo.c.device, "OpenCL device: auto, gpu, cpu, P:D, pocl, nvidia, amd, intel, rusticl, mesa or part of a name");
  view->add_option("--precision", vo.c.precision, "float or double (overrides run.precision)")
      ->check(CLI::IsMember({"float", "double"}));
  view->add_option("--frames", vo.frames, "draw N frames, then exit (scripted: fixed steps per frame)")
      ->check(mc::app::cli::count(1, 100000000));
  view->add_option("--screenshot", vo.screenshot, "write the last frame to FILE.png (with --frames)")
      ->type_name("FILE.png");
  std::string steps_per_frame;
  view->add_option("--steps-per-frame", steps_per_frame,
                   "simulation steps per drawn frame, or auto: as many as keep ~30 fps "
                   "(default: auto; 40 with --frames, for reproducible pictures)")
      ->type_name("N|auto");
  view->add_option("--camera", vo.camera, "end (axial, default) or iso")->check(CLI::IsMember({"end", "iso"}));
  view->add_option("--colour", vo.colour, "colour the balls by speed, size, material or impact")
      ->check(CLI::IsMember({"speed", "size", "material", "impact"}));
  view->add_option("--liner", vo.liner,
                   "colour the liner plain, by impact power or by wear rate of the last 0.1 s (wear: sliding + "
                   "impact; sliding-wear, impact-wear: each alone)")
      ->check(CLI::IsMember({"plain", "impact", "wear", "sliding-wear", "impact-wear"}));
  std::string size;
  view->add_option("--size", size, "window size in pixels (default 1280x800)")->type_name("WxH");
  view->add_flag("--no-panel", vo.no_panel, "draw the mill only, without the ImGui panel");
  view->add_option("--edit", vo.edits,
                   "before frame FRAME, change a case key as the panel does (repeatable), "
                   "e.g. --edit 50:lifters.profile.0.height=0.04")
      ->type_name("FRAME:KEY=VALUE");
  view->add_option("--from", vo.from,
                   "open on the state in RUN's checkpoint (a run folder, finished or still running) with its case, "
                   "and turn on from there")
      ->type_name("RUN");
  view->add_option("--save-state", vo.save_state,
                   "after the last of --frames, save the state into DIR as the panel's Save state does (for "
                   "run --resume DIR and bench --from DIR)")
      ->type_name("DIR");

  mc::app::LifeOptions lo;
  auto* life = app.add_subcommand("life", "the liner over its life: run, wear the lifters and shell, run again");
  add_case_options(life, lo.c, true);
  mc::app::add_life_options(life, lo);

  mc::app::LifeCompareOptions lco;
  auto* life_compare = app.add_subcommand(
      "life-compare", "life studies side by side: their figures at the same hours, with their standard errors, and "
                      "measured points beside them");
  life_compare->add_option("studies", lco.studies, "the life studies' folders (their --out)")->required();
  life_compare->add_option("--label", lco.labels, "a name for each study in the table and the picture, in the studies' "
                                                  "order (repeatable; default: the folders' names)")
      ->type_name("TEXT")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  life_compare->add_option("--at", lco.at, "the operating hours to table, comma-separated (default: four steps to the "
                                           "shortest study's end)")
      ->delimiter(',')
      ->check(mc::app::cli::non_negative("h"))
      ->type_name("H,...");
  life_compare->add_option("--measured", lco.measured,
                           "a measured point set beside the studies (repeatable), e.g. leading_angle_deg@4000=47.1; "
                           "columns: leading_angle_deg, height_mm, trailing_angle_deg, shell_wear_mm")
      ->type_name("COLUMN@HOURS=VALUE")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  life_compare->add_option("--profile", lco.profile, "the lifter profile followed (default 0)")
      ->check(mc::app::cli::count(0, 1000));
  life_compare->add_option("--out", lco.out, "folder for compare.csv and compare.png (default runs/life-compare)");
  life_compare->add_flag("--quiet", lco.quiet, "no table on the console");

  mc::app::CaseOptions co;
  auto* check = app.add_subcommand("check", "validate a case and print its derived values");
  add_case_options(check, co, false);
  check->add_option("--write-lifters", co.write_lifters,
                    "write the case's lifter bars, cut at the shell, as a binary STL (metres, mill frame): a start "
                    "for CAD, or a [[walls.mesh]] file")
      ->type_name("FILE");
  check->add_option("--lifter-mesh", co.lifter_mesh_mm,
                    "with --write-lifters: cut each face into triangles at most MM across (default: two per face), "
                    "a mesh fine enough for a life study to round its edges")
      ->check(mc::app::cli::between(0.5, 1000))
      ->type_name("MM");

  mc::app::BenchOptions bo;
  auto* bench = app.add_subcommand("bench", "time the solver on a turning charge; prints one JSON line");
  add_case_options(bench, bo.c, true, "bench_100k.toml");
  bench->add_option("--steps", bo.steps, "timed steps (default: about 10 s worth)")
      ->check(mc::app::cli::count_from(1));
  bench->add_option("--warmup", bo.warmup,
                    "simulated seconds of the turning mill before the timing (default 0.25; 0 with --from)")
      ->check(mc::app::cli::non_negative("s"));
  bench->add_option("--from", bo.from, "start from the checkpoint of a run in DIR (a settled, turning charge)")
      ->type_name("DIR");
  bench->add_option("--tile", bo.tile,
                    "with --from: the checkpoint's balls laid anew (fresh contact springs) N times end to end "
                    "along the axis, in a mill N times as long (a settled charge of N times the balls, no warm-up)")
      ->check(mc::app::cli::count(1, 10000))
      ->type_name("N");
  bench->add_option("--books", bo.books,
                    "time with the energy books (spectra, liner sums) on, off, or both in turn (default both)")
      ->check(CLI::IsMember({"both", "on", "off"}));
  bench->add_flag("--quiet", bo.quiet, "no progress lines");

  mc::app::GrindOptions go;
  std::string grind_times;
  auto* grind = app.add_subcommand(
      "grind", "the product size a finished run's mill makes of an ore: batch times or a continuous feed rate");
  grind->add_option("run", go.run_dir, "a finished run's folder (summary.json, case.toml, spectra.csv)")->required();
  grind->add_option("--ore", go.ore, "the ore's breakage parameters and feed (TOML; docs/grinding.md)")
      ->required()
      ->type_name("FILE");
  grind->add_option("--time", grind_times, "batch grinding times in minutes, comma-separated (default 1,2,4,8,16)")
      ->type_name("MIN,...");
  grind->add_option("--feed-rate", go.feed_rate_t_h, "a continuous mill fed at this rate (t/h)")
      ->check(mc::app::cli::positive("t/h"));
  grind->add_option("--target-p80", go.target_p80_um, "the continuous feed rate whose product has this P80 (um)")
      ->check(mc::app::cli::positive("um"));
  grind->add_option("--tanks", go.tanks, "tanks in series for the continuous mill (default: the ore file's, or 1)")
      ->check(mc::app::cli::count(1, 1000));
  grind->add_option("--bond", go.bond_p1_um,
                    "Bond's locked-cycle ball mill test closed at this sieve (um): Gbp and the work index")
      ->check(mc::app::cli::positive("um"))
      ->type_name("P1_UM");
  grind->add_option("--classifier", go.classifier_d50c_um,
                    "close the continuous mill with a classifier of this corrected cut size d50c (um): its "
                    "underflow returns to the mill (Whiten's curve)")
      ->check(mc::app::cli::positive("um"))
      ->type_name("D50C_UM");
  grind->add_option("--sharpness", go.classifier_alpha, "the classifier's sharpness alpha (default 3)")
      ->check(mc::app::cli::positive());
  grind->add_option("--bypass", go.classifier_bypass,
                    "the share of the fines that bypasses the classifier to the underflow (default 0)")
      ->check(mc::app::cli::between(0.0, 0.95));
  std::string fit_params;
  grind->add_option("--fit", go.fit_tests,
                    "fit the ore to this laboratory batch test (TOML) through the run, the test's mill (or the run "
                    "its `run` key names): writes the fitted ore, its residuals, fit.json and fit.png; give it "
                    "again for tests fitted together")
      ->type_name("TEST")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  CLI::Option* fit_params_opt = grind->add_option("--fit-params", fit_params,
                    "the ore parameters --fit or --fit-wi moves, comma-separated (default: the rate model's scale, "
                    "efficiency for the spectrum model)")
      ->type_name("NAME,...");
  grind->add_option("--sieve-errors", go.sieve_errors,
                    "with --fit: how the sieve errors are taken: auto (default: as independent, unless the residuals "
                    "correlate along the sieves, then as correlated), independent, or correlated (from one sieve to "
                    "the next, rho estimated)")
      ->check(CLI::IsMember({"auto", "independent", "correlated"}))
      ->type_name("MODEL");
  grind->add_option("--fit-wi", go.fit_wi_kWh_t,
                    "with --bond P1_UM: set one parameter so that Bond's test gives this measured work index (kWh/t)")
      ->check(mc::app::cli::positive("kWh/t"))
      ->type_name("WI");
  grind->add_option("--scale-from", go.scale_from,
                    "a laboratory run: beside the spectrum model's products, Herbst & Fuerstenau's scale-up (the "
                    "ore's energy-specific rates in that run, at this mill's power and hold-up)")
      ->type_name("LAB_RUN");
  std::vector<std::string> next_times;
  grind->add_option("--next-test", go.next_tests,
                    "a run of a mill a next batch test could be made in (normal energy spectrum): rank the candidate "
                    "tests by the interval they would leave on a product of the fitted ore; give it again for more "
                    "mills")
      ->type_name("RUN")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  grind->add_option("--next-times", next_times,
                    "with --next-test: one candidate set of grinding times in minutes, comma-separated; give it again "
                    "for more (default 0.5,1,2,4,8 and 1,2,4,8,16 and 2,4,8,16,32)")
      ->type_name("MIN,...")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  grind->add_option("--next-for", go.next_for,
                    "with --next-test: the product to narrow: wi (Bond's work index, with --bond), throughput (with "
                    "--target-p80) or p80:K (the K-th product's P80); default wi, else throughput, else p80:1")
      ->type_name("WHAT");
  std::string next_draws, next_seed, next_refit;
  grind->add_option("--next-draws", next_draws,
                    "with --next-test: simulated tests refitted per candidate to size its expected width (default 8)")
      ->type_name("N");
  grind->add_option("--next-seed", next_seed, "with --next-test: the seed of those draws (default 1)")->type_name("S");
  grind->add_option("--next-refit", next_refit,
                    "with --next-test: refit only the first K candidates of the linear ranking (default 3; 0: "
                    "the linear ranking alone)")
      ->type_name("K");
  grind->add_option("--out", go.out, "folder for the results (default RUN/grind, RUN/fit for a fit)");
  grind->add_flag("--quiet", go.quiet, "no summary lines");

  mc::app::SweepCli sweep;
  mc::app::add_sweep_commands(app, sweep);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (*devices) return mc::app::cmd_devices();
    if (int status = 0; mc::app::run_sweep(sweep, status)) return status;
    if (*check) return mc::app::cmd_check(co);
    if (*run) return mc::app::cmd_run(ro);
    if (*life) return mc::app::cmd_life(lo);
    if (*life_compare) return mc::app::cmd_life_compare(lco);
    if (*bench) return mc::app::cmd_bench(bo);
    if (*grind) {
      std::size_t start = 0;
      while (start < grind_times.size()) {
        const std::size_t end = std::min(grind_times.find(',', start), grind_times.size());
        const std::string item = grind_times.substr(start, end - start);
        char* stop = nullptr;
        const double t = std::strtod(item.c_str(), &stop);
        if (item.empty() || *stop != '\0' || !(t > 0) || !std::isfinite(t))
          throw std::invalid_argument("--time " + grind_times + ": expected minutes > 0, comma-separated, got \"" +
                                      item + "\"");
        go.times_min.push_back(t);
        start = end + 1;
      }
      for (const std::string& set : next_times) {
        std::vector<double> ts;
        std::string before;
        for (std::size_t start = 0; start <= set.size();) {
          const std::size_t end = std::min(set.find(',', start), set.size());
          const std::string item = set.substr(start, end - start);
          char* stop = nullptr;
          const double t = std::strtod(item.c_str(), &stop);
          if (item.empty() || *stop != '\0' || !(t > 0) || !std::isfinite(t))
            throw std::invalid_argument("--next-times " + set + ": expected minutes > 0, comma-separated, got \"" +
                                        item + "\"");
          if (!ts.empty() && !(t > ts.back()))
            throw std::invalid_argument("--next-times " + set + ": " + item + " does not follow " + before +
                                        ": times must ascend");
          ts.push_back(t);
          before = item;
          start = end + 1;
        }
        go.next_times.push_back(ts);
      }
      // A whole number >= least, or one message naming the option.
      auto whole = [](const char* option, const std::string& text, long long least, const char* what) {
        char* stop = nullptr;
        errno = 0;
        const long long v = std::strtoll(text.c_str(), &stop, 10);
        if (text.empty() || *stop != '\0' || v < least)
          throw std::invalid_argument(std::string(option) + " " + text + ": expected " + what);
        if (errno == ERANGE || v > 1000000000LL)
          throw std::invalid_argument(std::string(option) + " " + text + ": expected " + what + ", at most 1000000000");
        return v;
      };
      for (const auto& [option, text] : {std::pair<const char*, const std::string*>{"--next-draws", &next_draws},
                                         {"--next-seed", &next_seed},
                                         {"--next-refit", &next_refit}})
        if (!text->empty() && go.next_tests.empty())
          throw std::invalid_argument(std::string(option) + ": the refits of a next test; give --next-test RUN");
      if (!next_draws.empty())
        go.next_draws = static_cast<int>(whole("--next-draws", next_draws, 1, "a whole number of draws, 1 or more"));
      if (!next_seed.empty())
        go.next_seed = static_cast<std::uint64_t>(whole("--next-seed", next_seed, 0, "a whole number, 0 or more"));
      if (!next_refit.empty())
        go.next_refit = static_cast<int>(whole("--next-refit", next_refit, 0, "a whole number of candidates, 0 or more"));
      if (fit_params_opt->count() > 0 && fit_params.empty())
        throw std::invalid_argument("--fit-params \"\": names no parameter; name one or more (e.g. --fit-params "
                                    "efficiency), or leave the option out for the rate model's scale");
      for (std::size_t start = 0; start < fit_params.size();) {
        const std::size_t end = std::min(fit_params.find(',', start), fit_params.size());
        const std::string item = fit_params.substr(start, end - start);
        if (item.empty()) throw std::invalid_argument("--fit-params " + fit_params + ": an empty name");
        go.fit_params.push_back(item);
        start = end + 1;
      }
      return mc::app::cmd_grind(go);
    }
    if (*view) {
      if (steps_per_frame == "auto") vo.steps_per_frame = -1;
      else if (!steps_per_frame.empty()) {
        char* end = nullptr;
        const long n = std::strtol(steps_per_frame.c_str(), &end, 10);
        if (*end != '\0' || n < 1 || n > 1000000)
          throw std::invalid_argument("--steps-per-frame " + steps_per_frame + ": expected a count >= 1 or auto");
        vo.steps_per_frame = static_cast<int>(n);
      }
      if (!size.empty() && (std::sscanf(size.c_str(), "%dx%d", &vo.width, &vo.height) != 2 || vo.width < 320 ||
                            vo.height < 240 || vo.width > 8192 || vo.height > 8192))
        throw std::invalid_argument("--size " + size + ": expected WxH in pixels, e.g. 1280x800");
      return mc::app::cmd_view(vo);
    }
  } catch (const std::invalid_argument& e) {
    std::cerr << "millcharge: " << e.what() << '\n';
    return 2;
  } catch (const mc::compute::Error& e) {
    std::cerr << "millcharge: OpenCL: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "millcharge: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
