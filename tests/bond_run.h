// The grind tests' laboratory mill: a short run of the Bond test's mill
// (285 balls), made once per test program and removed when it ends, and
// a folder removed when its holder goes.
#pragma once

#include <catch2/catch.hpp>

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "app/commands.h"
#include "app/grind.h"
#include "grind_synthetic.h"
#include "io/batch_test_file.h"
#include "io/run_folder.h"

namespace mc::test {

// A folder removed when this goes.
struct TempDir {
  std::filesystem::path path;
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

inline const std::filesystem::path& short_bond_run() {
  static const TempDir out{[] {
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("millcharge_test_bond_run_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    mc::app::RunOptions o;
    o.c.case_path = std::string(MC_ASSET_DIR) + "/cases/bond.toml";
    o.c.overrides = {"run.settle=0.05", "run.warmup=0.1", "run.output_interval=0.01", "run.snapshot_interval=0",
                     "run.checkpoint_interval=0"};
    o.c.duration = 0.4;
    o.out = dir.string();
    o.quiet = true;
    REQUIRE(mc::app::cmd_run(o) == 0);
    return dir;
  }()};
  return out.path;
}

// A synthetic 5 x 13 test of `truth` (±1 pp, seed `seed`) in the short
// Bond run, written to DIR/test.toml and fitted from the example spectrum
// ore with η and σ free: DIR/fit/ore_fitted.toml.
inline std::filesystem::path fit_synthetic_in_bond_run(const grind::Ore& truth, std::uint64_t seed,
                                                       const std::filesystem::path& dir) {
  const std::filesystem::path run_dir = short_bond_run();
  const mc::io::Run run = mc::io::read_run(run_dir, true);
  mc::io::BatchTestFile tf;
  tf.title = "synthetic";
  tf.test = synthetic_test(truth, 1.0, seed, run.spectrum, {1, 2, 4, 8, 16}, true);
  std::ofstream(dir / "test.toml") << mc::io::batch_test_toml(tf);
  mc::app::GrindOptions o;
  o.run_dir = run_dir.string();
  o.ore = (std::filesystem::path(MC_ASSET_DIR) / "ores" / "example_spectrum.toml").string();
  o.fit_tests = {(dir / "test.toml").string()};
  o.fit_params = {"efficiency", "sigma"};
  o.out = (dir / "fit").string();
  o.quiet = true;
  REQUIRE(mc::app::cmd_grind(o) == 0);
  return dir / "fit" / "ore_fitted.toml";
}

}  // namespace mc::test
