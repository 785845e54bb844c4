// The grind tests' laboratory mill: a short run of the Bond test's mill
// (285 balls), made once per test program and removed when it ends, and
// a folder removed when its holder goes.
#pragma once

#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

#include "app/commands.h"

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

}  // namespace mc::test
