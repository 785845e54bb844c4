// Runs that survive: checkpoints and --resume (bit for bit), signals, damaged
// checkpoints, and the failure paths (NaN, a ball leaving the mill, too many
// wall contacts, neighbour lists that must grow).
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "helpers.h"
#include "core/drum.h"
#include "io/case_file.h"
#include "io/checkpoint.h"
#include "sim/mill_run.h"
#include "core/layout.hpp"

namespace fs = std::filesystem;
using namespace mc;

namespace {

// A short lab run: 0.05 s of settling, 0.2 s of turning, checkpoints every
// 0.05 s. About 12,000 steps.
const std::string kShort =
    " --quiet --set run.duration=0.2 --set run.settle=0.05 --set run.warmup=0.05"
    " --set run.checkpoint_interval=0.05 --set run.snapshot_interval=0.1";

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("millcharge-test-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(p);
  return p;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

int run_cmd(const std::string& args, std::string* err = nullptr) {
  const fs::path log = scratch("stderr.txt");
  const int st = std::system((std::string(MC_BINARY) + " " + args + " >/dev/null 2>'" + log.string() + "'").c_str());
  if (err) *err = slurp(log);
  fs::remove(log);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

// Starts the binary in the background; returns its pid.
pid_t spawn(const std::string& args) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = "exec " + std::string(MC_BINARY) + " " + args + " >/dev/null 2>&1";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

// Waits until the run's checkpoint reads back with the mill turning.
bool wait_for_turning_checkpoint(const fs::path& dir, double seconds) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until) {
    try {
      if (io::read_checkpoint(dir / io::kCheckpointFile).run.phase == 2) return true;
    } catch (const std::exception&) {
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

void require_same_state(const io::Checkpoint& a, const io::Checkpoint& b) {
  REQUIRE(a.solver.steps == b.solver.steps);
  CHECK(a.solver.time_s == b.solver.time_s);
  CHECK(a.solver.mill_angle == b.solver.mill_angle);
  CHECK(a.run.rows == b.run.rows);
  CHECK(a.run.work == b.run.work);
  CHECK(a.run.diss == b.run.diss);
  CHECK(a.run.window_profile == b.run.window_profile);
  REQUIRE(a.solver.arrays.size() == b.solver.arrays.size());
  for (std::size_t k = 0; k < a.solver.arrays.size(); ++k) {
    INFO("array " << a.solver.arrays[k].first);
    CHECK(a.solver.arrays[k].first == b.solver.arrays[k].first);
    CHECK(a.solver.arrays[k].second == b.solver.arrays[k].second);
  }
}

}  // namespace

TEST_CASE("SIGKILL during a run, then --resume, ends bit for bit where an unbroken run ends", "[checkpoint]") {
  const fs::path a = scratch("unbroken"), b = scratch("killed");
  REQUIRE(run_cmd("run" + kShort + " --out '" + a.string() + "'") == 0);

  const pid_t pid = spawn("run" + kShort + " --out '" + b.string() + "'");
  REQUIRE(pid > 0);
  const bool turning = wait_for_turning_checkpoint(b, 120);
  ::kill(pid, SIGKILL);
  int st = 0;
  ::waitpid(pid, &st, 0);
  REQUIRE(turning);
  REQUIRE(WIFSIGNALED(st));
  CHECK(!fs::exists(b / "summary.json"));
  const io::Checkpoint mid = io::read_checkpoint(b / io::kCheckpointFile);
  CHECK(mid.solver.time_s < 0.25 - 1e-6);  // killed before the end

  std::string err;
  REQUIRE(run_cmd("run --quiet --resume '" + b.string() + "'", &err) == 0);
  INFO(err);
  require_same_state(io::read_checkpoint(a / io::kCheckpointFile), io::read_checkpoint(b / io::kCheckpointFile));
  // No row lost or written twice.
  CHECK(slurp(a / "timeseries.csv") == slurp(b / "timeseries.csv"));
  CHECK(slurp(a / "charge.pvd") == slurp(b / "charge.pvd"));
  // A finished run is not resumed again.
  CHECK(run_cmd("run --quiet --resume '" + b.string() + "'", &err) == 2);
  CHECK(err.find("complete") != std::string::npos);
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST_CASE("SIGTERM stops a run with a checkpoint and a message saying how to go on", "[checkpoint]") {
  const fs::path dir = scratch("sigterm");
  const fs::path log = scratch("sigterm.txt");
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = "exec " + std::string(MC_BINARY) + " run" + kShort + " --out '" + dir.string() +
                            "' >/dev/null 2>'" + log.string() + "'";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const bool turning = wait_for_turning_checkpoint(dir, 120);
  ::kill(pid, SIGTERM);
  int st = 0;
  ::waitpid(pid, &st, 0);
  REQUIRE(turning);
  REQUIRE(WIFEXITED(st));
  CHECK(WEXITSTATUS(st) == 128 + SIGTERM);
  const std::string err = slurp(log);
  CHECK(err.find("stopped by SIGTERM") != std::string::npos);
  CHECK(err.find("--resume " + dir.string()) != std::string::npos);
  const io::Checkpoint cp = io::read_checkpoint(dir / io::kCheckpointFile);
  CHECK(cp.run.phase == 2);
  CHECK(run_cmd("run --quiet --resume '" + dir.string() + "'") == 0);
  CHECK(fs::exists(dir / "summary.json"));
  fs::remove_all(dir);
  fs::remove(log);
}

TEST_CASE("a truncated, damaged or foreign checkpoint is refused with a message", "[checkpoint]") {
  const fs::path dir = scratch("damaged");
  REQUIRE(run_cmd("run --quiet --set run.duration=0.02 --set run.settle=0.01 --set run.warmup=0 "
                  "--set run.output_interval=0.01 --out '" + dir.string() + "'") == 0);
  const fs::path f = dir / io::kCheckpointFile;
  const std::string good = slurp(f);
  REQUIRE(good.size() > 1000);
  fs::remove(dir / "summary.json");  // so that --resume would run
  auto write = [&](const std::string& bytes) { std::ofstream(f, std::ios::binary | std::ios::trunc) << bytes; };
  auto refused = [&](const std::string& bytes, const std::string& expect) {
    write(bytes);
    CHECK_THROWS_WITH(io::read_checkpoint(f), Catch::Contains(expect));
    std::string err;
    CHECK(run_cmd("run --quiet --resume '" + dir.string() + "'", &err) == 2);
    CHECK(err.find(expect) != std::string::npos);
    CHECK(err.find("cannot be resumed") != std::string::npos);
  };
  refused(good.substr(0, good.size() / 2), "truncated");
  refused(good.substr(0, 30), "truncated");
  std::string flipped = good;
  flipped[flipped.size() / 2] ^= 0x5a;
  refused(flipped, "checksum mismatch");
  refused("[mill]\ndiameter = 1\n", "not a millcharge checkpoint");
  refused("", "not a millcharge checkpoint");
  refused(good + "xx", "stray bytes");
  // The time series the checkpoint counts is read back strictly: a damaged
  // row is refused by its line, and the file is left as it was.
  write(good);
  const fs::path ts = dir / "timeseries.csv";
  const std::string rows = slurp(ts);
  {
    std::string bad = rows;
    const std::size_t row1 = bad.find('\n') + 1;  // line 2
    bad.replace(row1, bad.find(',', row1) - row1, "abc");
    std::ofstream(ts, std::ios::binary | std::ios::trunc) << bad;
    std::string err;
    CHECK(run_cmd("run --quiet --resume '" + dir.string() + "'", &err) == 2);
    INFO(err);
    CHECK(err.find("timeseries.csv:2: \"abc\" is not a number") != std::string::npos);
    CHECK(slurp(ts) == bad);
    // Cut inside the rows the checkpoint counts.
    const std::string cut = rows.substr(0, rows.size() - 3);
    std::ofstream(ts, std::ios::binary | std::ios::trunc) << cut;
    CHECK(run_cmd("run --quiet --resume '" + dir.string() + "'", &err) == 2);
    CHECK(err.find("whole rows, the checkpoint") != std::string::npos);
    std::ofstream(ts, std::ios::binary | std::ios::trunc) << rows;
  }
  // The good files still resume (here: only writes the summary again).
  CHECK(run_cmd("run --quiet --resume '" + dir.string() + "'") == 0);
  fs::remove_all(dir);
}

TEST_CASE("a NaN stops the run naming the likely causes, and the last good checkpoint stays", "[checkpoint][failure]") {
  const fs::path dir = scratch("nan");
  std::string err;
  const int status = run_cmd("run" + kShort + " --inject-nan-at 0.12 --out '" + dir.string() + "'", &err);
  CHECK(status == 1);
  CHECK(err.find("NaN") != std::string::npos);
  CHECK(err.find("dt") != std::string::npos);
  CHECK(err.find("last good checkpoint") != std::string::npos);
  CHECK(!fs::exists(dir / "summary.json"));
  const io::Checkpoint cp = io::read_checkpoint(dir / io::kCheckpointFile);
  CHECK(cp.solver.time_s <= 0.12);
  CHECK(cp.solver.time_s >= 0.09);
  fs::remove_all(dir);
}

TEST_CASE("a ball shot through the shell stops the run: it left the mill", "[failure]") {
  Scene s = test::bare_scene(Material{"steel"}, Material{"liner"}, Interaction{}, ContactLaw::linear);
  s.walls.shell_radius = 0.2;
  s.walls.length = 0.1;
  s.numerics.dt = 1e-5;
  Ball b;
  b.radius = 0.01;
  b.position = {0.15, 0, 0.05};
  b.velocity = {5000, 0, 0};  // 5 cm per step: straight through the shell
  s.balls = {b};
  auto solver = make_solver(test::context(), s);
  CHECK_THROWS_WITH(solver->advance(20), Catch::Contains("left the mill") && Catch::Contains("dt"));
}

TEST_CASE("a ball touching more walls than it has history slots stops the run", "[failure]") {
  // A slice shorter than the ball (both end plates), against the shell, and
  // wedged between two lifter bars: five walls at once.
  Scene s = test::bare_scene(Material{"steel"}, Material{"liner"}, Interaction{}, ContactLaw::linear);
  s.walls.shell_radius = 0.1;
  s.walls.length = 0.019;
  s.walls.lifters = {{{0.07, 0.0098}, {0.1, 0.0098}, {0.1, 0.03}, {0.07, 0.03}},
                     {{0.07, -0.03}, {0.1, -0.03}, {0.1, -0.0098}, {0.07, -0.0098}}};
  s.numerics.dt = 1e-6;
  s.numerics.gravity = {0, 0, 0};
  Ball b;
  b.radius = 0.01;
  b.position = {0.0901, 0, 0.0095};
  s.balls = {b};
  auto solver = make_solver(test::context(), s);
  CHECK_THROWS_WITH(solver->advance(5), Catch::Contains("walls at once"));
}

TEST_CASE("neighbour lists grow past their first size and drop no contact", "[failure]") {
  // An FCC block: 12 neighbours per inner ball, about 5 listed pairs per
  // ball (each pair once), more than the one per ball the lists start with.
  Scene s = test::bare_scene(Material{"steel"}, Material{"liner"}, Interaction{}, ContactLaw::linear);
  const double r = 0.005, a = 2 * std::sqrt(2.0) * r * 1.001;
  const Vec3 basis[4] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  int id = 0;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 5; ++k)
        for (const Vec3& q : basis) {
          Ball b;
          b.id = id++;
          b.radius = r;
          b.position = {(i + q.x) * a, (j + q.y) * a, (k + q.z) * a};
          s.balls.push_back(b);
        }
  auto solver = make_solver(test::context(), s);
  const auto pairs = solver->neighbour_pairs();
  CHECK(pairs.size() > 4 * s.balls.size());
  const std::set<std::pair<int, int>> listed = test::unordered(pairs);
  CHECK(listed.size() == pairs.size());
  const double cut = 2 * r + default_skin(s);
  std::size_t expected = 0;
  for (const Ball& p : s.balls)
    for (const Ball& q : s.balls)
      if (p.id < q.id && (p.position - q.position).norm() < cut) {
        ++expected;
        CHECK(listed.count({p.id, q.id}) == 1);
      }
  CHECK(listed.size() == expected);
}

namespace {

template <class T>
std::vector<T> state_array(const SolverState& st, const std::string& name) {
  for (const auto& [key, bytes] : st.arrays)
    if (key == name) {
      std::vector<T> out(bytes.size() / sizeof(T));
      std::memcpy(out.data(), bytes.data(), bytes.size());
      return out;
    }
  FAIL("state array " << name << " missing");
  return {};
}

template <class T>
void set_state_array(SolverState& st, const std::string& from, const std::string& to, const std::vector<T>& v) {
  for (auto& entry : st.arrays)
    if (entry.first == from) {
      entry.first = to;
      entry.second.resize(v.size() * sizeof(T));
      std::memcpy(entry.second.data(), v.data(), entry.second.size());
    }
}

// Rewrites a state of today's form (each pair once, in the lower ball's list:
// "neigh_half_link", springs in contact records) in the forms earlier
// versions saved: the springs in the list entries ("neigh_hist") and wall
// slots ("wall_hist"), no records; with `full`, in full lists, each pair in
// both balls' lists with the spring seen from each side ("neigh_link"); with
// `plain` too, in the still earlier form without the touching flag
// ("neigh_index"), where a spring of zero marked a pair apart. Returns the
// touching pairs.
int to_old_lists(SolverState& st, bool full, bool plain) {
  const auto start = state_array<int>(st, "neigh_start");
  const auto count = state_array<int>(st, "neigh_count");
  const auto link = state_array<int>(st, "neigh_half_link");
  const auto rec = state_array<int>(st, "neigh_rec");
  const auto records = state_array<float>(st, "records");  // two float4 a record
  const auto wall_key = state_array<int>(st, "wall_key");
  const auto wall_rec = state_array<int>(st, "wall_rec");
  std::vector<float> hist(3 * link.size(), 0.0f), wall_hist(3 * wall_key.size(), 0.0f);
  for (std::size_t k = 0; k < link.size(); ++k)
    if (link[k] < 0 && rec[k] >= 0)
      for (int c = 0; c < 3; ++c) hist[3 * k + c] = records[8 * rec[k] + c];
  for (std::size_t q = 0; q < wall_key.size(); ++q)
    if (wall_key[q] != -1 && wall_rec[q] >= 0)
      for (int c = 0; c < 3; ++c) wall_hist[3 * q + c] = records[8 * wall_rec[q] + c];
  set_state_array(st, "wall_rec", "wall_hist", wall_hist);
  set_state_array(st, "neigh_rec", "neigh_hist", hist);
  for (const char* gone : {"records", "record_pool", "rec_state", "spectra", "liner", "impact_profile"})
    st.arrays.erase(std::remove_if(st.arrays.begin(), st.arrays.end(), [&](const auto& e) { return e.first == gone; }),
                    st.arrays.end());
  int touching = 0;
  for (int l : link) touching += l < 0;
  if (!full) return touching;
  const int n = static_cast<int>(start.size());
  // Full list of ball i: the entries of lower balls that hold i, then its own.
  std::vector<std::vector<std::pair<int, std::array<float, 3>>>> lists(n);
  for (int i = 0; i < n; ++i)
    for (int k = start[i]; k < start[i] + count[i]; ++k) {
      const bool touch = link[k] < 0;
      const int j = touch ? ~link[k] : link[k];
      std::array<float, 3> h{hist[3 * k], hist[3 * k + 1], hist[3 * k + 2]};
      if (!touch) h = {0, 0, 0};
      lists[j].push_back({touch ? ~i : i, {-h[0], -h[1], -h[2]}});
    }
  std::vector<int> f_start(n), f_count(n), f_link;
  std::vector<float> f_hist;
  for (int i = 0; i < n; ++i) {
    for (int k = start[i]; k < start[i] + count[i]; ++k) {
      const bool touch = link[k] < 0;
      const std::array<float, 3> h =
          touch ? std::array<float, 3>{hist[3 * k], hist[3 * k + 1], hist[3 * k + 2]} : std::array<float, 3>{0, 0, 0};
      lists[i].push_back({link[k], h});
    }
    f_start[i] = static_cast<int>(f_link.size());
    f_count[i] = static_cast<int>(lists[i].size());
    for (const auto& [l, h] : lists[i]) {
      f_link.push_back(plain && l < 0 ? ~l : l);
      f_hist.insert(f_hist.end(), h.begin(), h.end());
    }
  }
  set_state_array(st, "neigh_start", "neigh_start", f_start);
  set_state_array(st, "neigh_count", "neigh_count", f_count);
  set_state_array(st, "neigh_half_link", plain ? "neigh_index" : "neigh_link", f_link);
  set_state_array(st, "neigh_hist", "neigh_hist", f_hist);
  return touching;
}

}  // namespace

TEST_CASE("a state saved before the contact records, with half or full lists, resumes the same run", "[checkpoint]") {
  // Earlier checkpoints hold the springs in the list entries and wall slots
  // (no contact records); before that every pair in both balls' lists
  // ("neigh_link"), and before that without the touching flag
  // ("neigh_index", the flag read off the springs). Made here from a state
  // of today's form; loading keeps each pair's entry in the lower ball's
  // list and gives each contact a record with its spring.
  DrumSpec spec;
  spec.n_balls = 300;
  const Scene sc = make_drum(spec);
  auto a = make_solver(test::context(), sc);
  a->advance(10000);  // a bed with springs in its contacts
  const SolverState now = a->save_state();
  for (const int form : {0, 1, 2}) {
    const bool full = form > 0, plain = form > 1;
    SolverState old = now;
    REQUIRE(to_old_lists(old, full, plain) > 50);  // touching pairs
    auto b = make_solver(test::context(), sc);
    b->restore_state(old);
    auto c = make_solver(test::context(), sc);
    c->restore_state(now);
    c->advance(1000);
    b->advance(1000);
    const auto ba = c->balls(), bb = b->balls();
    REQUIRE(ba.size() == bb.size());
    int differ = 0;
    for (std::size_t i = 0; i < ba.size(); ++i)
      differ += !(ba[i].position.x == bb[i].position.x && ba[i].position.y == bb[i].position.y &&
                  ba[i].position.z == bb[i].position.z && ba[i].omega.x == bb[i].omega.x &&
                  ba[i].omega.y == bb[i].omega.y && ba[i].omega.z == bb[i].omega.z);
    INFO("full lists " << full << ", plain " << plain);
    CHECK(differ == 0);
  }
}

TEST_CASE("a state saved before the normal or the severity spectra loads: its spectra kept, the new ones from zero",
          "[checkpoint][books]") {
  DrumSpec spec;
  spec.n_balls = 200;
  const Scene sc = make_drum(spec);
  auto a = make_solver(test::context(), sc);
  a->advance(6000);
  const SolverState saved = a->save_state();
  const BookSums before = a->read_books();
  // Six fields a cell (before the normal spectrum) and eight (before the
  // severity spectra): today's cut back to them.
  for (const int kept : {6, 8}) {
    INFO(kept << " fields a cell");
    SolverState old = saved;
    for (auto& [key, bytes] : old.arrays) {
      if (key != "spectra") continue;
      const std::size_t cell_new = 2 * MC_SPECTRA_FIELDS * 4, cell_old = 2 * kept * 4, cells = bytes.size() / cell_new;
      std::vector<unsigned char> cut(cells * cell_old);
      for (std::size_t c = 0; c < cells; ++c)
        std::memcpy(cut.data() + c * cell_old, bytes.data() + c * cell_new, cell_old);
      bytes = cut;
    }
    auto b = make_solver(test::context(), sc);
    b->restore_state(old);
    const BookSums after = b->read_books();
    double count_before = 0, count_after = 0, normal_after = 0, by_normal_after = 0, by_normal_before = 0,
           severity_after = 0;
    for (int t = 0; t < before.n_types; ++t)
      for (int k = 0; k < MC_SPECTRA_BINS; ++k) {
        count_before += before.at(t, k, MC_SPECTRA_COUNT);
        count_after += after.at(t, k, MC_SPECTRA_COUNT);
        normal_after += after.at(t, k, MC_SPECTRA_NORMAL) - before.at(t, k, MC_SPECTRA_NORMAL);
        by_normal_after += after.at(t, k, MC_SPECTRA_BY_NORMAL);
        by_normal_before += before.at(t, k, MC_SPECTRA_BY_NORMAL);
        for (int f = MC_SPECTRA_IMPACT; f < MC_SPECTRA_FIELDS; ++f) severity_after += after.at(t, k, f);
      }
    CHECK(count_before > 100);
    CHECK(count_after == count_before);
    CHECK(normal_after == 0);
    CHECK(by_normal_after == (kept == 8 ? by_normal_before : 0.0));
    CHECK(severity_after == 0);
    // It runs on, and the new spectra book what closes from then on.
    b->advance(2000);
    const BookSums later = b->read_books();
    double closed = 0, by_normal = 0, impacts = 0, losses = 0;
    for (int t = 0; t < later.n_types; ++t)
      for (int k = 0; k < MC_SPECTRA_BINS; ++k) {
        closed += later.at(t, k, MC_SPECTRA_COUNT) - after.at(t, k, MC_SPECTRA_COUNT);
        by_normal += later.at(t, k, MC_SPECTRA_BY_NORMAL) - after.at(t, k, MC_SPECTRA_BY_NORMAL);
        impacts += later.at(t, k, MC_SPECTRA_IMPACT);
        losses += later.at(t, k, MC_SPECTRA_LOSS);
      }
    CHECK(closed > 10);
    CHECK(by_normal == closed);
    CHECK(impacts == closed);
    CHECK(losses == closed);
  }
}

TEST_CASE("a state saved before the impact profile was kept along the mill loads: the whole mill's kept, the bins' from zero",
          "[checkpoint][books]") {
  DrumSpec spec;
  spec.n_balls = 200;
  const Scene sc = make_drum(spec);
  auto a = make_solver(test::context(), sc);
  a->advance(6000);
  const SolverState saved = a->save_state();
  const BookSums before = a->read_books();
  double whole = 0;
  for (double v : before.impact_profile) whole += v;
  REQUIRE(whole > 0);
  REQUIRE(before.impact_axial_bins >= 1);
  SolverState old = saved;
  for (auto& [key, bytes] : old.arrays)
    if (key == "impact_profile") bytes.resize(2 * MC_IMPACT_BINS * 4);  // the whole mill's block alone
  auto b = make_solver(test::context(), sc);
  b->restore_state(old);
  const BookSums after = b->read_books();
  CHECK(after.impact_profile == before.impact_profile);
  double axial = 0;
  for (double v : after.impact_profile_axial) axial += v;
  CHECK(axial == 0);
  // It runs on, and the bins book what lands from then on: their sum is
  // the whole mill's gain.
  b->advance(3000);
  const BookSums later = b->read_books();
  double gain = 0, bins = 0;
  for (std::size_t d = 0; d < later.impact_profile.size(); ++d) gain += later.impact_profile[d] - after.impact_profile[d];
  for (double v : later.impact_profile_axial) bins += v;
  CHECK(gain > 0);
  CHECK(bins == Approx(gain).epsilon(1e-9));
  // Today's state round-trips every block.
  auto c = make_solver(test::context(), sc);
  c->restore_state(saved);
  CHECK(c->read_books().impact_profile_axial == before.impact_profile_axial);
}

TEST_CASE("a finished run extended with --resume --duration equals an unbroken run row for row", "[checkpoint]") {
  // 0.1 s of turning, then extended to 0.2 s, against 0.2 s unbroken. The
  // window (from the warm-up, less than a revolution) is the one already
  // begun, so the averages go on as well.
  const std::string common =
      " --quiet --set run.settle=0.05 --set run.warmup=0.05 --set run.checkpoint_interval=0.05"
      " --set run.snapshot_interval=0.1";
  const fs::path a = scratch("ext-unbroken"), b = scratch("ext-extended");
  REQUIRE(run_cmd("run" + common + " --set run.duration=0.2 --out '" + a.string() + "'") == 0);
  REQUIRE(run_cmd("run" + common + " --set run.duration=0.1 --out '" + b.string() + "'") == 0);
  const std::string rows_before = slurp(b / "timeseries.csv");

  std::string err;
  // Shorter than it has turned, or another key: refused by name, nothing changed.
  CHECK(run_cmd("run --quiet --resume '" + b.string() + "' --duration 0.05", &err) == 2);
  CHECK(err.find("run.duration") != std::string::npos);
  CHECK(err.find("has turned 0.1 s") != std::string::npos);
  CHECK(run_cmd("run --quiet --resume '" + b.string() + "' --duration 0.3 --set mill.speed_fraction=0.8", &err) == 2);
  CHECK(err.find("--set mill.speed_fraction") != std::string::npos);
  CHECK(slurp(b / "timeseries.csv") == rows_before);
  CHECK(slurp(b / "case.toml").find("duration = 0.1") != std::string::npos);

  REQUIRE(run_cmd("run --quiet --resume '" + b.string() + "' --duration 0.2", &err) == 0);
  INFO(err);
  CHECK(slurp(a / "timeseries.csv") == slurp(b / "timeseries.csv"));
  CHECK(slurp(a / "charge.pvd") == slurp(b / "charge.pvd"));
  CHECK(slurp(a / "case.toml") == slurp(b / "case.toml"));
  const io::Checkpoint ca = io::read_checkpoint(a / io::kCheckpointFile);
  const io::Checkpoint cb = io::read_checkpoint(b / io::kCheckpointFile);
  require_same_state(ca, cb);
  // The summary over the same window: the same sums, bit for bit.
  const auto ja = nlohmann::json::parse(slurp(a / "summary.json"));
  const auto jb = nlohmann::json::parse(slurp(b / "summary.json"));
  CHECK(ja["power_W"]["torque"].get<double>() == jb["power_W"]["torque"].get<double>());
  CHECK(ja["power_W"]["dissipation"].get<double>() == jb["power_W"]["dissipation"].get<double>());
  CHECK(ja["average"]["from_s"].get<double>() == jb["average"]["from_s"].get<double>());
  CHECK(ja["turning_s"].get<double>() == Approx(0.2).margin(1e-4));
  CHECK(jb["turning_s"].get<double>() == ja["turning_s"].get<double>());
  // Complete again: a plain resume has nothing to do, and says how to extend.
  CHECK(run_cmd("run --quiet --resume '" + b.string() + "'", &err) == 2);
  CHECK(err.find("--duration") != std::string::npos);
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST_CASE("an extension keeps the window begun where it can, else begins one after the point reached", "[checkpoint]") {
  // The lab mill's turning planned in steps: a revolution is 1.769 s.
  const auto lab = [](const std::string& duration) {
    std::vector<std::string> ov = {"run.warmup=0.5", "run.duration=" + duration};
    MillCase c = io::read_case(io::default_case(), ov);
    return std::make_pair(c, derive(c));
  };
  const auto [c3, d3] = lab("3");
  const double dt = d3.dt;
  const TurnPlan p3 = plan_turning(c3, d3, dt);
  REQUIRE(p3.revolutions == 1);  // [3 − 1.77, 3] s
  CHECK(p3.window_start == p3.turn_steps - std::lround(p3.rev_steps));
  RunState done;
  done.phase = 3;
  done.turn_step = p3.turn_steps;
  done.window_begun = 1;
  done.batches.resize(kBatchesPerRevolution);
  done.work = 1;
  done.window_profile.assign(kProfileBins, 3);

  SECTION("6 s: an unbroken run's window begins at 6 − 3 revolutions = 0.69 s, before the 3 s reached") {
    const auto [c6, d6] = lab("6");
    const RunState st = extend_run(done, c3, d3, c6, d6, dt);
    CHECK(st.phase == 2);
    CHECK(st.window_begun == 0);  // a new window, its books from zero
    CHECK(st.window_floor_step == p3.turn_steps);
    CHECK(st.batches.empty());
    CHECK(st.work == 0);
    CHECK(st.window_profile == std::vector<long>(kProfileBins, 0));
    const TurnPlan p = plan_turning(c6, d6, dt, st.window_floor_step);
    CHECK(p.revolutions == 1);  // [6 − 1.77, 6] s, after 3 s
    CHECK(p.window_start >= p3.turn_steps);
    CHECK(p.turn_steps == std::lround(6 / dt));
  }
  SECTION("0.6 s to 6 s: the unbroken run's window [0.69, 6] s begins after 0.6 s: the same window") {
    const auto [c06, d06] = lab("0.6");
    const auto [c6, d6] = lab("6");
    RunState short_run = done;
    short_run.turn_step = plan_turning(c06, d06, dt).turn_steps;
    short_run.batches.clear();
    const RunState st = extend_run(short_run, c06, d06, c6, d6, dt);
    CHECK(st.window_begun == 0);
    const TurnPlan unbroken = plan_turning(c6, d6, dt);
    CHECK(plan_turning(c6, d6, dt, st.window_floor_step).window_start == unbroken.window_start);
    CHECK(unbroken.revolutions == 3);
  }
  SECTION("a duration at or below what has turned is refused, naming the key") {
    const auto [c2, d2] = lab("3");
    REQUIRE_THROWS_WITH(extend_run(done, c3, d3, c2, d2, dt), Catch::Contains("run.duration") &&
                                                                   Catch::Contains("has turned 3 s"));
  }
  SECTION("an auto run stopped at its cap goes on with a larger cap, its window kept") {
    std::vector<std::string> ov = {"run.warmup=0.5", "run.duration=\"auto\"", "run.max_duration=2.5"};
    const MillCase ca = io::read_case(io::default_case(), ov);
    const MillDerived da = derive(ca);
    const TurnPlan pa = plan_turning(ca, da, dt);
    REQUIRE(pa.revolutions == 1);
    RunState capped = done;
    capped.turn_step = pa.turn_steps;
    ov.back() = "run.max_duration=6";
    const MillCase cb = io::read_case(io::default_case(), ov);
    const MillDerived db = derive(cb);
    const RunState st = extend_run(capped, ca, da, cb, db, dt);
    CHECK(st.window_begun == 1);
    CHECK(st.batches.size() == capped.batches.size());
    CHECK(st.work == 1);
    CHECK(plan_turning(cb, db, dt, st.window_floor_step).revolutions == 3);
  }
}
