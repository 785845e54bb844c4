// The viewer's scripted mode under Xvfb (software OpenGL from Mesa, OpenCL on
// PoCL): `millcharge view --frames N --screenshot FILE.png` on the lab mill in
// the end view. The picture must show the charge where a charge should be —
// in the lower half of the shell, displaced toward the rising side (the mill
// turns counter-clockwise, so the right side rises) — and a very different
// speed given with --set must change its shape. `view --from RUN` opens on a
// run's checkpoint, finished or still being written, and saves a state that
// `run --resume` and `bench --from` take.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

#include "core/mill_case.h"
#include "io/case_file.h"
#include "io/checkpoint.h"

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Shot {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
  double axis_x = 0, axis_y = 0, radius_px = 0;  // from the viewer's report
  std::string out, err;
};

// Runs the viewer under xvfb-run: settling (auto, about 0.26 s simulated)
// and then turning, `frames` frames of `steps` steps (dt 2.01e-5 s).
Shot shoot(const fs::path& dir, const std::string& name, int frames, const std::string& extra, int steps = 500) {
  const fs::path png = dir / (name + ".png"), out = dir / (name + ".out"), err = dir / (name + ".err");
  const std::string cmd = "xvfb-run -a -s '-screen 0 1280x800x24' " + std::string(MC_BINARY) +
                          " view --frames " + std::to_string(frames) +
                          " --steps-per-frame " + std::to_string(steps) + " --camera end --size 1280x800 --screenshot '" + png.string() + "' " +
                          extra + " > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  Shot s;
  s.out = read_text(out);
  s.err = read_text(err);
  INFO(cmd << "\nstdout: " << s.out << "\nstderr: " << s.err);
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  const auto at = s.out.find("mill axis at pixel");
  REQUIRE(at != std::string::npos);
  REQUIRE(std::sscanf(s.out.c_str() + at, "mill axis at pixel (%lf, %lf), shell radius %lf px", &s.axis_x, &s.axis_y,
                      &s.radius_px) == 3);
  int n = 0;
  unsigned char* data = stbi_load(png.string().c_str(), &s.width, &s.height, &n, 3);
  REQUIRE(data != nullptr);
  s.rgb.assign(data, data + static_cast<std::size_t>(s.width) * s.height * 3);
  stbi_image_free(data);
  return s;
}

// The balls' pixels inside the shell: strongly coloured (the speed ramp is
// saturated everywhere; background, shell, plate and lifters are grey).
struct ChargeShape {
  double covered = 0;     // fraction of the disc inside 0.95 R
  double centroid_r = 0;  // of the ball pixels, in shell radii
  double angle_deg = 0;   // of that centroid, counter-clockwise from 3 o'clock
  double upper = 0;       // fraction of ball pixels above the axis
};

ChargeShape measure(const Shot& s) {
  ChargeShape c;
  long disc = 0, balls = 0, upper = 0;
  double sx = 0, sy = 0;
  const double r_max = 0.95 * s.radius_px;
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      const double dx = x + 0.5 - s.axis_x, dy = s.axis_y - (y + 0.5);  // y up
      if (dx * dx + dy * dy > r_max * r_max) continue;
      ++disc;
      const unsigned char* p = &s.rgb[(static_cast<std::size_t>(y) * s.width + x) * 3];
      const int hi = std::max({p[0], p[1], p[2]}), lo = std::min({p[0], p[1], p[2]});
      if (hi - lo <= 40) continue;
      ++balls;
      sx += dx;
      sy += dy;
      if (dy > 0) ++upper;
    }
  if (disc == 0 || balls == 0) return c;
  c.covered = static_cast<double>(balls) / disc;
  const double mx = sx / balls, my = sy / balls;
  c.centroid_r = std::hypot(mx, my) / s.radius_px;
  c.angle_deg = std::fmod(std::atan2(my, mx) * 180 / kPi + 360, 360);
  c.upper = static_cast<double>(upper) / balls;
  return c;
}

}  // namespace

TEST_CASE("view --frames --screenshot draws the lab mill's charge where it should be, and the speed changes it",
          "[viewer]") {
  INFO("the viewer's test needs xvfb-run (Debian: xvfb and xauth; scripts/setup.sh installs them)");
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fs::temp_directory_path() / ("millcharge_view_" + std::to_string(::getpid()));
  fs::create_directories(dir);

  // 60 frames × 500 steps = 0.60 s: about 0.34 s of turning after settling.
  const Shot fast = shoot(dir, "lab75", 60, "");
  const ChargeShape a = measure(fast);
  INFO("75 %: covered " << a.covered << ", centroid " << a.centroid_r << " R at " << a.angle_deg << " deg, upper "
                        << a.upper << "\n" << fast.out << fast.err);
  CHECK(fast.width == 1280);
  CHECK(fast.height == 800);
  CHECK(fast.radius_px == Approx(320).margin(40));  // the end view frames the shell
  CHECK(fast.out.find("turning") != std::string::npos);  // settled, then turned
  // Not blank: J = 0.3 of balls seen end on covers a third or more of the disc.
  CHECK(a.covered > 0.25);
  CHECK(a.covered < 0.75);
  // The charge lies low, off the axis, lifted toward the rising (right) side.
  // At 75 % the lifters first carry the bed up as a block: its centre of mass
  // turns from 270 deg to about 357 deg after 0.6 s and settles to 315-330 deg
  // after a revolution (`millcharge run` timeseries.csv, com_angle_deg); the
  // band takes both and nothing on the falling side or above the axis.
  CHECK(a.centroid_r > 0.25);
  CHECK(a.centroid_r < 0.75);
  CHECK(a.angle_deg > 290);
  CHECK(a.angle_deg < 358);
  std::printf("75 %%: covered %.3f, centroid %.3f R at %.1f deg, upper %.3f\n", a.covered, a.centroid_r, a.angle_deg,
              a.upper);

  const Shot slow = shoot(dir, "lab30", 60, "--set mill.speed_fraction=0.3");
  const ChargeShape b = measure(slow);
  std::printf("30 %%: covered %.3f, centroid %.3f R at %.1f deg, upper %.3f\n", b.covered, b.centroid_r, b.angle_deg,
              b.upper);
  INFO("30 %: covered " << b.covered << ", centroid " << b.centroid_r << " R at " << b.angle_deg << " deg, upper "
                        << b.upper);
  CHECK(b.covered > 0.2);
  CHECK(b.angle_deg > 260);
  CHECK(b.angle_deg < 320);
  // At 30 % the bed only tilts; at 75 % the lifters carry it up the right
  // side and balls fly: the centroid turns further and rises.
  CHECK(a.angle_deg - b.angle_deg > 12);
  CHECK(a.upper - b.upper > 0.1);
  fs::remove_all(dir);
}

TEST_CASE("view --liner impact colours the liner by its impact power and marks the impact point", "[viewer]") {
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fs::temp_directory_path() / ("millcharge_view_liner_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const Shot s = shoot(dir, "liner", 60, "--liner impact");
  INFO(s.out << s.err);
  // The liner's sums of the turning mill, as the viewer reports them.
  const auto at = s.out.find("liner over the last");
  REQUIRE(at != std::string::npos);
  double window = 0, impact = 0, shear = 0;
  REQUIRE(std::sscanf(s.out.c_str() + at, "liner over the last %lf s: impact %lf W, shear %lf W", &window, &impact,
                      &shear) == 3);
  CHECK(window > 0.05);
  CHECK(impact > 1);   // the lab mill's liner takes tens of watts of impacts
  CHECK(shear > 1);
  // The impact point's magenta mark beside the shell (none without it: the
  // balls' speed ramp has no magenta).
  long magenta = 0;
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      const unsigned char* p = &s.rgb[(static_cast<std::size_t>(y) * s.width + x) * 3];
      magenta += p[0] > 220 && p[1] < 90 && p[2] > 180;
    }
  CHECK(magenta > 20);
  fs::remove_all(dir);
}

namespace {

// The line the viewer prints for a scripted edit before `frame`.
std::string edit_line(const std::string& out, int frame) {
  const std::string tag = "millcharge view: frame " + std::to_string(frame) + ": ";
  const auto at = out.find(tag);
  if (at == std::string::npos) return "";
  return out.substr(at, out.find('\n', at) - at);
}

struct Applied {
  bool ok = false;
  long balls = 0, added = 0, removed = 0, moved = 0;
};

Applied applied(const std::string& line) {
  Applied a;
  const auto at = line.find("applied: ");
  a.ok = at != std::string::npos &&
         std::sscanf(line.c_str() + at, "applied: %ld balls (%ld added, %ld removed, %ld moved", &a.balls, &a.added,
                     &a.removed, &a.moved) == 4;
  return a;
}

long balls_for(const std::vector<std::string>& overrides) {
  return mc::derive(mc::io::read_case(mc::io::default_case(), overrides)).n_balls;
}

}  // namespace

TEST_CASE("view: speed, filling and lifters change in the running window without a restart or a blow-up",
          "[viewer]") {
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fs::temp_directory_path() / ("millcharge_edit_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // 0.02 s of settling, then the mill turns; an edit every few frames of 250
  // steps, as the panel makes them (the same code path).
  const Shot s = shoot(dir, "edits", 26, "--set run.settle=0.02 --edit 3:lifters.profile.0.height=0.06 "
                                         "--edit 7:charge.filling=0.4 --edit 11:mill.speed_fraction=0.9 "
                                         "--edit 15:lifters.rows=16 --edit 19:charge.filling=0.25 "
                                         "--edit 21:mill.speed_fraction=2.5", 250);
  INFO(s.out << s.err);
  const Applied taller = applied(edit_line(s.out, 3));
  REQUIRE(taller.ok);
  CHECK(taller.balls == 2714);  // the lifters grew from 25 to 60 mm: balls in their way moved, none lost
  CHECK(taller.moved > 50);
  CHECK(taller.removed == 0);

  const Applied fuller = applied(edit_line(s.out, 7));
  REQUIRE(fuller.ok);
  const long n40 = balls_for({"lifters.profile.0.height=0.06", "charge.filling=0.4"});
  CHECK(fuller.balls == n40);
  CHECK(fuller.added == n40 - 2714);

  CHECK(edit_line(s.out, 11).find("speed 90.0 % of critical") != std::string::npos);

  const Applied rows = applied(edit_line(s.out, 15));
  REQUIRE(rows.ok);
  CHECK(rows.moved > 0);  // four more bars, some where balls were
  CHECK(rows.balls + rows.removed == n40);

  const Applied emptier = applied(edit_line(s.out, 19));
  REQUIRE(emptier.ok);
  const long n25 = balls_for({"lifters.profile.0.height=0.06", "lifters.rows=16", "charge.filling=0.25"});
  CHECK(emptier.balls == n25);
  CHECK(emptier.removed == rows.balls - n25);

  // A value the case refuses leaves the mill as it was, with the reason.
  CHECK(edit_line(s.out, 21).find("not applied") != std::string::npos);
  CHECK(edit_line(s.out, 21).find("mill.speed_fraction") != std::string::npos);

  // Still turning at 90 % after all that, with the charge in the picture.
  CHECK(s.out.find("turning") != std::string::npos);
  CHECK(s.out.find("90.0 % of critical") != std::string::npos);
  const ChargeShape c = measure(s);
  CHECK(c.covered > 0.15);
  CHECK(c.angle_deg > 270);
  CHECK(c.angle_deg < 360);
  fs::remove_all(dir);
}

namespace {

std::string capture(const std::string& cmd, int& status) {
  std::string out;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  const int st = ::pclose(p);
  status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return out;
}

// A number after `tag` in `text` (NaN when absent).
double number_after(const std::string& text, const std::string& tag) {
  const auto at = text.find(tag);
  return at == std::string::npos ? std::nan("") : std::strtod(text.c_str() + at + tag.size(), nullptr);
}

}  // namespace

TEST_CASE("view --from RUN opens on the run's turning charge, and its saved state runs on headless", "[viewer]") {
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fs::temp_directory_path() / ("millcharge_view_from_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path run = dir / "run", saved = dir / "saved";
  // The lab mill settled (auto, about 0.22 s) and turned 0.4 s.
  int status = -1;
  capture(std::string(MC_BINARY) + " run --quiet --set run.duration=0.4 --set run.warmup=0 --out '" + run.string() +
              "' > /dev/null 2>&1",
          status);
  REQUIRE(status == 0);
  const mc::io::Checkpoint cp = mc::io::read_checkpoint(run / mc::io::kCheckpointFile);
  REQUIRE(cp.run.phase == 3);
  const double turned = cp.solver.time_s - cp.run.turn_start_s;
  REQUIRE(turned == Approx(0.4).margin(1e-3));

  // 10 frames of 100 steps on from there, the lifters 40 mm tall from the
  // first (the balls in their way moved, none lost), the state saved after
  // them.
  const Shot s = shoot(dir, "from", 10,
                       "--from '" + run.string() + "' --edit 0:lifters.profile.0.height=0.04 --save-state '" +
                           saved.string() + "'",
                       100);
  INFO(s.out << s.err);
  // Where the state came from, and the window went on turning from it (no
  // settling): the turning time is the run's and the window's steps.
  CHECK(number_after(s.out, "state from " + run.string() + " at t = ") == Approx(cp.solver.time_s).margin(1e-4));
  const double dt = 0.4 / cp.run.turn_step;
  CHECK(number_after(s.out, "; turning ") == Approx(turned + 1000 * dt).margin(2e-3));
  CHECK(s.err.find("the turning mill first drawn") != std::string::npos);
  // The picture is the run's turning charge, lifted toward the rising side
  // (a fresh packing 1000 steps in would still be falling into place).
  const ChargeShape c = measure(s);
  std::printf("from a checkpoint: covered %.3f, centroid %.3f R at %.1f deg, upper %.3f\n", c.covered, c.centroid_r,
              c.angle_deg, c.upper);
  CHECK(c.covered > 0.25);
  CHECK(c.covered < 0.75);
  CHECK(c.angle_deg > 290);
  CHECK(c.angle_deg < 358);

  CHECK(s.out.find("applied: 2714 balls (0 added, 0 removed") != std::string::npos);

  // The saved state: a checkpoint 1000 steps on, the mill ready to turn on,
  // which `run --resume` continues and `bench --from` times. Its case has
  // the taller lifters, and the filling that its 2714 balls fill in the
  // smaller volume they leave (the case's 0.3 packs 2672 there).
  const mc::io::Checkpoint sv = mc::io::read_checkpoint(saved / mc::io::kCheckpointFile);
  CHECK(sv.solver.time_s == Approx(cp.solver.time_s + 1000 * dt).margin(1e-6));
  CHECK(sv.solver.steps == cp.solver.steps + 1000);
  CHECK(sv.solver.n_balls == 2714);
  CHECK(sv.run.settled);
  const mc::MillCase sc = mc::io::parse_case(sv.case_toml, "saved");
  CHECK(sv.case_toml.find("height = 0.04") != std::string::npos);
  CHECK(sc.filling > 0.3);
  CHECK(mc::derive(sc).n_balls == 2714);
  CHECK(s.out.find("run it on headless with millcharge run --resume " + saved.string()) != std::string::npos);
  const std::string resumed =
      capture(std::string(MC_BINARY) + " run --resume '" + saved.string() + "' --duration 0.02 2>&1", status);
  INFO(resumed);
  CHECK(status == 0);
  CHECK(number_after(resumed, "resuming at t = ") == Approx(sv.solver.time_s).margin(1e-4));
  CHECK(fs::exists(saved / "summary.json"));
  CHECK(fs::exists(saved / "timeseries.csv"));
  const std::string bench =
      capture(std::string(MC_BINARY) + " bench --from '" + saved.string() + "' --steps 50 --books on --quiet", status);
  INFO(bench);
  CHECK(status == 0);
  CHECK(number_after(bench, "\"n_particles\":") == 2714);
  CHECK(number_after(bench, "\"contacts_per_ball\":") > 0.2);  // a packed charge, not a fresh packing

  // A checkpoint whose state does not fit its own case (written whole, so
  // only restoring it tells): refused naming the file, status 2, no picture.
  mc::io::Checkpoint odd = cp;
  const auto at = odd.case_toml.find("filling = ");
  REQUIRE(at != std::string::npos);
  odd.case_toml.replace(at, odd.case_toml.find('\n', at) - at, "filling = 0.25");
  const fs::path odd_dir = dir / "odd", odd_png = dir / "odd.png";
  fs::create_directories(odd_dir);
  mc::io::write_checkpoint(odd_dir / mc::io::kCheckpointFile, odd);
  const std::string refused =
      capture("xvfb-run -a -s '-screen 0 1280x800x24' " + std::string(MC_BINARY) + " view --from '" + odd_dir.string() +
                  "' --frames 2 --screenshot '" + odd_png.string() + "' 2>&1",
              status);
  INFO(refused);
  CHECK(status == 2);
  CHECK(refused.find(odd_dir.string() + "/checkpoint.bin: the state holds 2714 balls") != std::string::npos);
  CHECK(refused.find("the window cannot open on it") != std::string::npos);
  CHECK(!fs::exists(odd_png));
  fs::remove_all(dir);
}

TEST_CASE("view --from a run still being written opens on its last whole checkpoint", "[viewer]") {
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fs::temp_directory_path() / ("millcharge_view_live_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path run = dir / "run";
  // A long run writing a checkpoint every 0.02 s of simulated time.
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = "exec " + std::string(MC_BINARY) + " run --quiet --set run.duration=20 --set run.warmup=0 "
                            "--set run.settle=0.02 --set run.checkpoint_interval=0.02 --out '" + run.string() +
                            "' >/dev/null 2>&1";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  REQUIRE(pid > 0);
  // Until it turns.
  double written = -1;
  for (int k = 0; k < 1200 && written < 0; ++k) {
    try {
      const mc::io::Checkpoint cp = mc::io::read_checkpoint(run / mc::io::kCheckpointFile);
      if (cp.run.phase == 2) written = cp.solver.time_s;
    } catch (const std::exception&) {
    }
    if (written < 0) ::usleep(100000);
  }
  REQUIRE(written > 0);
  // The run paused (alive, mid-run): its last whole checkpoint is the one on
  // disk now, and the window must open on that one, not an earlier one.
  ::kill(pid, SIGSTOP);
  ::usleep(200000);
  const double last = mc::io::read_checkpoint(run / mc::io::kCheckpointFile).solver.time_s;
  const Shot s = shoot(dir, "live", 3, "--from '" + run.string() + "'", 20);
  INFO(s.out << s.err);
  int st = 0;
  const bool still_running = ::waitpid(pid, &st, WNOHANG) == 0;
  ::kill(pid, SIGCONT);
  ::kill(pid, SIGTERM);
  ::waitpid(pid, &st, 0);
  CHECK(still_running);
  CHECK(last >= written);
  const double from = number_after(s.out, "state from " + run.string() + " at t = ");
  CHECK(from == Approx(last).margin(1e-4));
  CHECK(s.out.find("(turning)") != std::string::npos);
  const ChargeShape c = measure(s);
  CHECK(c.covered > 0.2);
  fs::remove_all(dir);
}
