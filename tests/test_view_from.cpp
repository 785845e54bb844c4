// view --from RUN, the part that needs no window: a run folder that cannot
// be opened on (no checkpoint, another format version, a cut or damaged
// file, a case that disagrees with the run's) is refused before any window
// opens, with one message naming the cause, status 2 and nothing written.
// The window itself is tested under Xvfb (test_viewer.cpp, label viewer).
// Also: a checkpoint read while it is being written is read whole.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "io/checkpoint.h"

namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("millcharge-test-view-from-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(p);
  return p;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void spit(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes; }

// The binary with `args`, no display (a window that opened would fail
// differently, with status 1); its stderr into `err`.
int run_cmd(const std::string& args, std::string& err) {
  const fs::path log = scratch("stderr.txt");
  const int st = std::system(("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(MC_BINARY) + " " + args +
                              " >/dev/null 2>'" + log.string() + "'")
                                 .c_str());
  err = slurp(log);
  fs::remove(log);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

}  // namespace

TEST_CASE("view --from refuses a folder it cannot open on: status 2, the cause named, nothing written", "[view]") {
  const fs::path run = scratch("run");
  std::string err;
  REQUIRE(run_cmd("run --quiet --set run.duration=0.02 --set run.settle=0.01 --set run.warmup=0 "
                  "--set run.output_interval=0.01 --out '" + run.string() + "'",
                  err) == 0);
  const std::string good = slurp(run / mc::io::kCheckpointFile);
  REQUIRE(good.size() > 1000);
  const fs::path bad = scratch("bad"), png = scratch("shot.png"), saved = scratch("saved");
  fs::create_directories(bad);
  for (const char* f : {"case.toml", "timeseries.csv"}) fs::copy_file(run / f, bad / f);
  // Each refusal: status 2, its cause in one line, no picture, no state.
  auto refused = [&](const std::string& args, const std::string& expect) {
    INFO("view " << args);
    std::string e;
    CHECK(run_cmd("view " + args + " --frames 2 --screenshot '" + png.string() + "' --save-state '" + saved.string() +
                      "'",
                  e) == 2);
    INFO(e);
    CHECK(e.find(expect) != std::string::npos);
    CHECK(e.rfind("millcharge: ", 0) == 0);
    CHECK(std::count(e.begin(), e.end(), '\n') == 1);
    CHECK(!fs::exists(png));
    CHECK(!fs::exists(saved));
  };
  const std::string from_bad = "--from '" + bad.string() + "'";

  // A folder without a checkpoint.
  refused(from_bad, "checkpoint.bin: cannot open the checkpoint (is this a run folder?); the window cannot open on it");
  // Another version of the format: the u32 after the magic line.
  {
    std::string other = good;
    const std::uint32_t v = 99;
    std::memcpy(&other[std::strlen("millcharge checkpoint\n")], &v, sizeof v);
    spit(bad / mc::io::kCheckpointFile, other);
    refused(from_bad, "format version 99, this millcharge reads 1; the window cannot open on it");
  }
  // Cut short, damaged, not a checkpoint at all.
  spit(bad / mc::io::kCheckpointFile, good.substr(0, good.size() / 2));
  refused(from_bad, "truncated");
  {
    std::string flipped = good;
    flipped[flipped.size() / 2] ^= 0x5a;
    spit(bad / mc::io::kCheckpointFile, flipped);
    refused(from_bad, "checksum mismatch: the file is damaged; the window cannot open on it");
  }
  spit(bad / mc::io::kCheckpointFile, "[mill]\ndiameter = 1\n");
  refused(from_bad, "not a millcharge checkpoint");

  // A case file, or --set, that disagrees with the run's case: the key named
  // with both values. The run's length keys do not count (the case file says
  // 6 s, the run 0.02 s), nor does a --set that agrees.
  const std::string from_run = "--from '" + run.string() + "'";
  refused(from_run + " " + MC_ASSET_DIR + "/cases/lab.toml --set mill.speed_fraction=0.6",
          "disagrees with the run's case (mill.speed_fraction 0.6 given, 0.75 in the run; run.settle 'auto' given, "
          "0.01 in the run)");
  refused(from_run + " --set lifters.rows=16", "--set disagrees with the run's case (lifters.rows 16 given, 12 in the run)");
  refused(from_run + " " + MC_ASSET_DIR + "/cases/mill_b.toml", "(charge.filling 0.175 given, 0.3 in the run; ");
  refused(from_run + " --precision double", "the checkpoint holds float state");
  // What agrees passes those checks: the window is then all that is missing
  // (status 1, no display), and still nothing is written.
  std::string e;
  CHECK(run_cmd("view " + from_run + " " + MC_ASSET_DIR + "/cases/lab.toml --set run.settle=0.01 --frames 2", e) == 1);
  CHECK(e.find("no display") != std::string::npos);
  CHECK(run_cmd("view " + from_run + " --set lifters.rows=12 --frames 2", e) == 1);
  CHECK(e.find("no display") != std::string::npos);

  // --save-state into a folder that holds a run.
  CHECK(run_cmd("view --frames 2 --save-state '" + run.string() + "'", e) == 2);
  CHECK(e.find("already holds a run (checkpoint.bin)") != std::string::npos);
  fs::remove_all(run);
  fs::remove_all(bad);
}

TEST_CASE("a checkpoint rewritten in place while it is read is read whole, once it holds still", "[checkpoint][view]") {
  const fs::path dir = scratch("inplace");
  fs::create_directories(dir);
  mc::io::Checkpoint cp;
  cp.case_name = "lab";
  cp.case_toml = std::string(200000, '#');  // big enough to write in parts
  cp.run.phase = 2;
  cp.solver.time_s = 1.25;
  cp.solver.n_balls = 3;
  const fs::path f = dir / mc::io::kCheckpointFile;
  mc::io::write_checkpoint(f, cp);
  const std::string whole = slurp(f);
  // A writer that writes in place, in ten parts 50 ms apart (a copy from a
  // server under way): a reader that begins after its first part waits for
  // the rest and gets the whole file.
  spit(f, whole.substr(0, whole.size() / 10));
  std::thread writer([&] {
    std::ofstream out(f, std::ios::binary | std::ios::app);
    for (int k = 1; k < 10; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      const std::size_t from = whole.size() * k / 10, to = whole.size() * (k + 1) / 10;
      out.write(whole.data() + from, static_cast<std::streamsize>(to - from));
      out.flush();
    }
  });
  const auto t0 = std::chrono::steady_clock::now();
  mc::io::Checkpoint read;
  CHECK_NOTHROW(read = mc::io::read_complete_checkpoint(f, 10.0));
  writer.join();
  CHECK(read.solver.time_s == 1.25);
  CHECK(read.case_toml == cp.case_toml);
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > 0.3);
  // A cut file that holds still is refused at once, as read_checkpoint refuses it.
  spit(f, whole.substr(0, whole.size() / 2));
  const auto t1 = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH(mc::io::read_complete_checkpoint(f, 10.0), Catch::Contains("truncated"));
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count() < 2.0);
  // A writer that renames (write_checkpoint, as runs write): a reader in a
  // loop sees only whole files, old or new.
  mc::io::write_checkpoint(f, cp);
  std::thread renamer([&] {
    for (int k = 0; k < 20; ++k) {
      mc::io::Checkpoint next = cp;
      next.solver.time_s = 2.0 + k;
      mc::io::write_checkpoint(f, next);
    }
  });
  for (int k = 0; k < 40; ++k) {
    const double t = mc::io::read_checkpoint(f).solver.time_s;
    CHECK((t == 1.25 || t >= 2.0));
  }
  renamer.join();
  fs::remove_all(dir);
}
