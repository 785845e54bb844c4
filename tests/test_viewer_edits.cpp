// The window's numbers across a live edit (`millcharge view --edit`), under
// Xvfb: after a speed, lifter or filling edit the averages (torque power,
// toe, shoulder) restart and, once the settle-in has passed, agree with a
// window that ran the edited case from the start and restarted its averages
// at the same frame; revolutions add up across a speed change; a saved
// state reopens turning; the window settles with run.settle_damping as
// `run` does; an --edit past --frames is refused.
#include <catch2/catch.hpp>

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

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

#include "core/mill_case.h"
#include "io/case_file.h"
#include "text_file.h"

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Out {
  int status = -1;
  std::string out, err;
};

// millcharge with `args`, under xvfb-run for `view`.
Out millcharge(const fs::path& dir, const std::string& name, const std::string& args, bool window = true) {
  const fs::path out = dir / (name + ".out"), err = dir / (name + ".err");
  // The scripted window reports its numbers with the picture.
  const std::string picture =
      window && args.find("--screenshot") == std::string::npos ? " --screenshot '" + (dir / (name + ".png")).string() + "'" : "";
  const std::string cmd = std::string(window ? "xvfb-run -a -s '-screen 0 1280x800x24' " : "") + MC_BINARY + " " +
                          args + picture + " > '" + out.string() + "' 2> '" + err.string() + "'";
  const int st = std::system(cmd.c_str());
  Out o;
  o.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  o.out = read_text(out);
  o.err = read_text(err);
  return o;
}

double number_after(const std::string& text, const std::string& tag) {
  const auto at = text.find(tag);
  return at == std::string::npos ? std::nan("") : std::strtod(text.c_str() + at + tag.size(), nullptr);
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("millcharge_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// What the scripted window reports about its averages.
struct Averages {
  double power = NAN, power_se = NAN, span_s = NAN, toe = NAN, shoulder = NAN, edit_t = NAN;
  double rev = NAN, turn_from = NAN, turn_to = NAN;
  double toe_se = NAN, shoulder_se = NAN;  // from the 0.5 s batches
};

Averages averages(const Out& o) {
  Averages a;
  a.power = number_after(o.out, "torque power ");
  const auto power = o.out.find("torque power ");
  if (power != std::string::npos) a.power_se = number_after(o.out.substr(power), " +- ");
  const auto over = o.out.find(" W over the ", o.out.find("torque power "));
  if (over != std::string::npos) a.span_s = std::strtod(o.out.c_str() + over + 12, nullptr);
  a.toe = number_after(o.out, "view: toe ");
  a.shoulder = number_after(o.out, " deg, shoulder ");
  const auto batches = o.out.find("batches of ", o.out.find("view: toe "));
  double batch_s = 0, toe = 0, shoulder = 0;
  if (batches != std::string::npos)
    std::sscanf(o.out.c_str() + batches, "batches of %lf s: toe %lf +- %lf, shoulder %lf +- %lf", &batch_s, &toe,
                &a.toe_se, &shoulder, &a.shoulder_se);
  a.edit_t = number_after(o.out, "(t = ");
  a.rev = number_after(o.out, "turned ");
  a.turn_from = number_after(o.out, " rev from t = ");
  a.turn_to = number_after(o.out, " s to ");
  return a;
}

// The lab mill 50 mm long (905 balls), 1000 steps (0.0201 s) a frame for
// 140 frames, the edit before frame 30 (0.6 s in, about 0.4 s after the mill
// started). The reference window runs the edited case from the start and
// gives the edited value again at frame 30, which restarts its averages
// at the same time with the same settle-in.
constexpr const char* kMill = "view --set mill.length=0.05 --frames 140 --steps-per-frame 1000";

// Each mean within twice the combined standard error of the two (batch
// means: power of 0.2 s, 9 batches each; toe and shoulder of 0.5 s, three
// batches each, their contact profiles of 1.7 s summed for the value), and
// the angles at least within 3 deg: three batches give a rough error, and
// their scatter on this mill measured 0.5 to 6.6 deg.
void check_agree(const Averages& edited, const Averages& fresh, double settle_in_s) {
  REQUIRE(std::isfinite(edited.power));
  REQUIRE(std::isfinite(fresh.power));
  REQUIRE(edited.power_se > 0);
  REQUIRE(fresh.power_se > 0);
  // The averages began after the edit and its settle-in, not before: they
  // span the turning after them, to within a frame.
  const double frame_s = 1000 * 2.01e-5;
  CHECK(edited.span_s == Approx(edited.turn_to - edited.edit_t - settle_in_s).margin(1.5 * frame_s));
  CHECK(fresh.span_s == Approx(fresh.turn_to - fresh.edit_t - settle_in_s).margin(1.5 * frame_s));
  CHECK(std::fabs(edited.power - fresh.power) <= 2 * std::hypot(edited.power_se, fresh.power_se));
  REQUIRE(edited.toe_se >= 0);
  REQUIRE(fresh.toe_se >= 0);
  CHECK(edited.toe == Approx(fresh.toe).margin(std::max(3.0, 2 * std::hypot(edited.toe_se, fresh.toe_se))));
  CHECK(edited.shoulder ==
        Approx(fresh.shoulder).margin(std::max(3.0, 2 * std::hypot(edited.shoulder_se, fresh.shoulder_se))));
}

mc::MillDerived lab(const std::vector<std::string>& set) {
  return mc::derive(mc::io::read_case(mc::io::default_case(), set));
}

}  // namespace

TEST_CASE("view --edit speed: averages restart after a quarter revolution, agree with the edited case, revolutions add up",
          "[viewer]") {
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fresh_dir("view_edit_speed");
  const Out e = millcharge(dir, "edited", std::string(kMill) + " --set mill.speed_fraction=0.5 --edit 30:mill.speed_fraction=0.8");
  const Out f = millcharge(dir, "fresh", std::string(kMill) + " --set mill.speed_fraction=0.8 --edit 30:mill.speed_fraction=0.8");
  INFO("edited:\n" << e.out << e.err << "\nfresh:\n" << f.out << f.err);
  REQUIRE(e.status == 0);
  REQUIRE(f.status == 0);
  const Averages a = averages(e), b = averages(f);
  std::printf("speed edit 50 -> 80 %%: power %.1f +- %.1f W, toe %.2f, shoulder %.2f deg; fresh at 80 %%: %.1f +- %.1f W, "
              "%.2f, %.2f deg\n",
              a.power, a.power_se, a.toe, a.shoulder, b.power, b.power_se, b.toe, b.shoulder);
  const mc::MillDerived slow = lab({"mill.length=0.05", "mill.speed_fraction=0.5"});
  const mc::MillDerived fast = lab({"mill.length=0.05", "mill.speed_fraction=0.8"});
  check_agree(a, b, 0.25 * fast.revolution_s);
  // Revolutions: the time at each speed over its own period, by hand.
  const double by_hand = (a.edit_t - a.turn_from) / slow.revolution_s + (a.turn_to - a.edit_t) / fast.revolution_s;
  CHECK(a.rev == Approx(by_hand).epsilon(1e-3));
  // Not the whole time over the new period (what it was).
  CHECK(std::fabs(a.rev - (a.turn_to - a.turn_from) / fast.revolution_s) > 0.05);
  fs::remove_all(dir);
}

// The edit before frame 30, and the reference window with the edited case
// from the start, restarting its averages at frame 30 by giving its speed again.
static void check_edit(const std::string& name, const std::string& key) {
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fresh_dir("view_edit_" + name);
  const double settle_in = 0.25 * lab({"mill.length=0.05"}).revolution_s;
  // The edited window keeps its balls; the reference packs as many: the
  // filling they fill in the edited mill, as the saved case gives it.
  const Out e = millcharge(dir, "edited", std::string(kMill) + " --edit 30:" + key + " --save-state '" +
                                              (dir / "saved").string() + "'");
  REQUIRE(e.status == 0);
  const mc::MillCase saved = mc::io::read_case(dir / "saved" / "case.toml");
  char filling[64];
  std::snprintf(filling, sizeof filling, " --set charge.filling=%.9g", saved.filling);
  const Out f = millcharge(dir, "fresh", std::string(kMill) + " --set " + key + filling +
                                             " --edit 30:mill.speed_fraction=0.75");
  INFO(name << " edited:\n" << e.out << e.err << "\nfresh:\n" << f.out << f.err);
  auto balls = [](const Out& o) { return number_after(o.out.substr(std::min(o.out.size(), o.out.find("mill axis"))), "% of critical, "); };
  CHECK(balls(e) == balls(f));  // as many balls
  REQUIRE(f.status == 0);
  const Averages a = averages(e), b = averages(f);
  std::printf("%s edit: power %.1f +- %.1f W, toe %.2f, shoulder %.2f deg; fresh: %.1f +- %.1f W, %.2f, %.2f deg\n",
              name.c_str(), a.power, a.power_se, a.toe, a.shoulder, b.power, b.power_se, b.toe, b.shoulder);
  check_agree(a, b, settle_in);
  fs::remove_all(dir);
}

TEST_CASE("view --edit lifters: averages restart and agree with the edited case from the start", "[viewer]") {
  check_edit("lifters", "lifters.profile.0.height=0.05");
}

TEST_CASE("view --edit filling: averages restart and agree with the edited case from the start", "[viewer]") {
  check_edit("filling", "charge.filling=0.38");
}

TEST_CASE("view: a state saved by the window reopens turning, its clock going on", "[viewer]") {
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fresh_dir("view_reopen");
  const fs::path saved = dir / "saved";
  const Out s = millcharge(dir, "save", "view --set mill.length=0.05 --frames 30 --steps-per-frame 500 --screenshot '" + (dir / "s.png").string() + "' --save-state '" +
                                            saved.string() + "'");
  INFO(s.out << s.err);
  REQUIRE(s.status == 0);
  const Averages a = averages(s);
  REQUIRE(std::isfinite(a.turn_from));
  // 0.1 s into the turning the liner has too few impacts for an impact
  // point: said so, not printed as nan.
  CHECK(s.out.find("impact point not yet") != std::string::npos);
  CHECK(s.out.find("nan") == std::string::npos);
  const Out r = millcharge(dir, "reopen", "view --from '" + saved.string() + "' --frames 3 --steps-per-frame 500 --screenshot '" +
                                              (dir / "r.png").string() + "'");
  INFO(r.out << r.err);
  REQUIRE(r.status == 0);
  const Averages b = averages(r);
  CHECK(r.out.find("(turning)") != std::string::npos);
  CHECK(r.err.find("the turning mill first drawn") != std::string::npos);
  // The turning clock goes on from where it was; the mill turned in the
  // first frame too: three frames at the case's speed.
  const mc::MillDerived d = lab({"mill.length=0.05"});
  CHECK(b.turn_from == Approx(a.turn_from).margin(1e-4));
  CHECK(b.turn_to == Approx(a.turn_to + 1500 * d.dt).margin(1e-4));
  CHECK(b.rev - a.rev == Approx(1500 * d.dt / d.revolution_s).margin(1.5e-4));  // printed to 1e-4
  fs::remove_all(dir);
}

TEST_CASE("view settles with run.settle_damping as run does", "[viewer]") {
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fresh_dir("view_settle_damping");
  // Damped hard, the charge comes to rest sooner; a frame of 995 steps is
  // run's settling chunk (0.02 s), so both test for rest at the same steps.
  const std::string set = " --set mill.length=0.05 --set run.settle_damping=60";
  const Out run = millcharge(dir, "run", "run --quiet --set run.duration=0.02 --set run.warmup=0 --out '" +
                                             (dir / "run").string() + "'" + set, false);
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  const double run_settle = number_after(read_text(dir / "run" / "summary.json"), "\"settle_s\": ");
  const Out v = millcharge(dir, "view", "view --frames 40 --steps-per-frame 995 --screenshot '" + (dir / "v.png").string() +
                                            "'" + set);
  INFO(v.out << v.err);
  REQUIRE(v.status == 0);
  const double view_settle = averages(v).turn_from;
  std::printf("settling with damping 60 1/s: run %.4f s, view %.4f s\n", run_settle, view_settle);
  CHECK(view_settle == Approx(run_settle).margin(0.021));
  fs::remove_all(dir);
}

TEST_CASE("view --edit past --frames is refused by name, status 2", "[viewer]") {
  const fs::path dir = fresh_dir("view_edit_past");
  const Out o = millcharge(dir, "past", "view --frames 10 --edit 10:mill.speed_fraction=0.5", false);
  CHECK(o.status == 2);
  CHECK(o.err.find("--edit 10:mill.speed_fraction=0.5") != std::string::npos);
  CHECK(o.err.find("--frames 10") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("view: a blow-up after an edit goes back to the state before it, and the session goes on", "[viewer]") {
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fresh_dir("view_blow_up");
  // A restitution of 1e-30 damps the contacts past what the explicit step
  // holds (damping ratio 0.999 at the same dt): balls go through the shell
  // within steps of the edit.
  const Out o = millcharge(dir, "blow", "view --set mill.length=0.05 --frames 40 --steps-per-frame 500 "
                                        "--edit 25:contact.restitution=1e-30 --save-state '" +
                                            (dir / "saved").string() + "'");
  INFO(o.out << o.err);
  REQUIRE(o.status == 0);
  CHECK(o.err.find("the solver blew up after the edit") != std::string::npos);
  CHECK(o.err.find("the edit is undone") != std::string::npos);
  // The state saved after it is the case before the edit, turned on: the
  // revolutions those frames make at 75 %, the frame that blew up not counted.
  const mc::MillCase saved = mc::io::read_case(dir / "saved" / "case.toml");
  CHECK(saved.contact.restitution == Approx(0.4));
  const Averages a = averages(o);
  const mc::MillDerived d = lab({"mill.length=0.05"});
  CHECK(a.rev == Approx((a.turn_to - a.turn_from) / d.revolution_s).margin(1.5e-4));
  CHECK(a.turn_to == Approx(39 * 500 * d.dt).margin(1e-4));  // 40 frames, one of them thrown away
  fs::remove_all(dir);
}

TEST_CASE("view: the speed colours follow a speed edit", "[viewer]") {
  REQUIRE(std::system("command -v xvfb-run > /dev/null 2>&1") == 0);
  const fs::path dir = fresh_dir("view_colour_range");
  // From 50 % to 150 % of critical: the balls on the shell move at about
  // the new tip speed (3.2 m/s), past the old range's top (twice the tip
  // speed at 50 %, 2.1 m/s), well inside the new one (6.4 m/s).
  const Out o = millcharge(dir, "fast", "view --set mill.length=0.05 --set mill.speed_fraction=0.5 --frames 60 "
                                        "--steps-per-frame 500 --edit 20:mill.speed_fraction=1.5 --no-panel");
  INFO(o.out << o.err);
  REQUIRE(o.status == 0);
  int w = 0, h = 0, n = 0;
  unsigned char* rgb = stbi_load((dir / "fast.png").string().c_str(), &w, &h, &n, 3);
  REQUIRE(rgb != nullptr);
  // Ball pixels are saturated (grey mill and background are not); the hot
  // end of the ramp is red (0.90, 0.15, 0.10) shaded.
  long balls = 0, hot = 0;
  for (long k = 0; k < static_cast<long>(w) * h; ++k) {
    const int r = rgb[3 * k], g = rgb[3 * k + 1], b = rgb[3 * k + 2];
    if (std::max({r, g, b}) - std::min({r, g, b}) <= 40) continue;
    ++balls;
    if (r > 2 * g && r > 2 * b) ++hot;
  }
  stbi_image_free(rgb);
  REQUIRE(balls > 10000);
  const double share = static_cast<double>(hot) / balls;
  std::printf("speed colours after 50 -> 150 %%: %.3f of the ball pixels at the hot end\n", share);
  CHECK(share < 0.1);
  fs::remove_all(dir);
}
