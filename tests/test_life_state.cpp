// A life study's state read back strictly: a damaged life.json (cut, a
// value of another type, a key missing, a list cut short) is refused in one
// line naming life.json, status 2, the study's files left byte for byte; a
// study killed in stage 0 resumes; a stage's damaged summary.json and a
// --scale-from run's are refused in words, not the JSON library's; and
// life.csv's top wear rate against the stage's stations.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/life_state.h"
#include "core/mill_case.h"
#include "io/case_file.h"
#include "core/scene.h"
#include "io/csv_read.h"
#include "io/json_read.h"
#include "text_file.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Two stages (the new liner and one worn) of 0.15 s turned each.
const std::string kStudy =
    " --stages 1 --hours 2000 --quiet --set run.duration=0.15 --set run.settle=0.05 --set run.warmup=0.05"
    " --set run.checkpoint_interval=0.05 --set run.snapshot_interval=0 --hold-plates";  // the plates: test_life_plates

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("millcharge-life-state-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(p);
  return p;
}

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

// The command's exit status (-1 for a signal), its standard error.
int millcharge(const std::string& args, std::string* err = nullptr) {
  const fs::path log = scratch("stderr.txt");
  const int st = std::system((std::string(MC_BINARY) + " " + args + " >/dev/null 2>'" + log.string() + "'").c_str());
  if (err) *err = read_text(log);
  fs::remove(log);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

// Every file under a folder with its bytes.
std::map<std::string, std::string> files_under(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) out[fs::relative(e.path(), dir).string()] = read_text(e.path());
  return out;
}

// One short study, run once for this process's tests and removed at its exit.
struct SharedStudy {
  fs::path dir = scratch("study");
  SharedStudy() {
    std::string err;
    const int rc = millcharge("life" + kStudy + " --out '" + dir.string() + "'", &err);
    INFO(err);
    REQUIRE(rc == 0);
  }
  ~SharedStudy() { fs::remove_all(dir); }
};

const fs::path& study() {
  static const SharedStudy s;
  return s.dir;
}

// A copy of the study to damage.
fs::path copy_of_study(const std::string& name) {
  const fs::path d = scratch(name);
  fs::copy(study(), d, fs::copy_options::recursive);
  return d;
}

// The study's life.json damaged every way the fuzz knows, each with a label.
std::vector<std::pair<std::string, std::string>> damaged(const std::string& text) {
  std::vector<std::pair<std::string, std::string>> out;
  // Cut at every tenth byte (short of the closing brace).
  const std::size_t end = text.find_last_not_of(" \n");
  for (std::size_t n = 0; n < end; n += 10) out.push_back({"cut at " + std::to_string(n), text.substr(0, n)});
  const json doc = json::parse(text);
  const json flat = doc.flatten();
  // Every leaf of another type (a number as a string, anything else as a number).
  for (const auto& [pointer, v] : flat.items()) {
    json d = doc;
    d[json::json_pointer(pointer)] = v.is_number() || v.is_null() ? json("7") : json(7);
    out.push_back({"type of " + pointer, d.dump(1) + "\n"});
  }
  // Every object and list of another type, every key missing, every list
  // one short. Only `stopped` may be missing (the study then stops again),
  // and what a study begun before impact wear lacks: the impact
  // coefficient, and the stages' wear parts (the result's wear is then
  // sliding alone; a share of impact is then refused by name), and what a
  // study begun before the end plates wore lacks: the request's end_plates
  // (it resumes with them held, as this study holds them).
  auto may_miss = [](const std::string& p) {
    return p == "/stopped" || p == "/calibration/impact_wear_coefficient_m3_per_J" || p == "/request/end_plates" ||
           (p.rfind("/result/station_sliding_wear_m3_per_s") != std::string::npos &&
            p.rfind("/result/station_sliding_wear_m3_per_s") + 37 == p.size());
  };
  std::function<void(const json&, const std::string&)> walk = [&](const json& v, const std::string& at) {
    if (!at.empty()) {
      json d = doc;
      d[json::json_pointer(at)] = v.is_object() ? json::array() : json(3);
      out.push_back({"type of " + at, d.dump(1) + "\n"});
    }
    if (v.is_object()) {
      for (const auto& [key, member] : v.items()) {
        const std::string p = at + "/" + key;
        if (!may_miss(p)) {
          json d = doc;
          d[json::json_pointer(at)].erase(key);
          out.push_back({"missing " + p, d.dump(1) + "\n"});
        }
        if (member.is_structured()) walk(member, p);
      }
    } else {
      if (!v.empty()) {
        json d = doc;
        d[json::json_pointer(at)].erase(v.size() - 1);
        out.push_back({"one short " + at, d.dump(1) + "\n"});
      }
      for (std::size_t i = 0; i < v.size(); ++i)
        if (v[i].is_structured()) walk(v[i], at + "/" + std::to_string(i));
    }
  };
  walk(doc, "");
  return out;
}

}  // namespace

TEST_CASE("life --out naming a file is refused by name, status 2 and nothing written", "[life][cli][failures]") {
  const fs::path dir = scratch("out-file");
  fs::create_directories(dir);
  write_text(dir / "notes.txt", "mine\n");
  std::string err;
  CHECK(millcharge("life --stages 2 --hours 10 --out '" + (dir / "notes.txt").string() + "'", &err) == 2);
  CHECK(err == "millcharge: --out " + (dir / "notes.txt").string() + ": exists and is not a folder\n");
  CHECK(files_under(dir) == std::map<std::string, std::string>{{"notes.txt", "mine\n"}});
  fs::remove_all(dir);
}

TEST_CASE("life.json's state is read whole and strictly, each fault named by stage and key", "[life]") {
  const fs::path dir = scratch("state");
  fs::create_directories(dir);
  const json good = json::parse(read_text(study() / "life.json"));
  const mc::MillCase c = mc::io::read_case(study() / "cases" / "stage-00.toml");
  const mc::app::life::StateShape shape{c.lifter_pattern.size(), mc::derive(c).largest_ball_diameter};
  write_text(dir / "life.json", good.dump(1));
  const mc::app::life::LifeState st = mc::app::life::read_life_state(dir / "life.json", shape);
  REQUIRE(st.stages.size() == 2);
  CHECK(st.stages[1].case_hours == Approx(2000.0));
  CHECK(st.stopped.find("2000 hours (relative: wear coefficient not calibrated) reached") != std::string::npos);
  const std::string file = (dir / "life.json").string();
  auto refused = [&](const std::function<void(json&)>& damage, const std::string& said) {
    json d = good;
    damage(d);
    write_text(dir / "life.json", d.dump(1));
    CHECK_THROWS_WITH(mc::app::life::read_life_state(dir / "life.json", shape), file + ": " + said);
  };
  refused([](json& d) { d["stages"][1]["profiles"] = json::array(); }, "stage 1: profiles: empty list");
  refused([](json& d) { d.erase("request"); }, "request: missing");
  refused([](json& d) { d["stages"][0]["result"]["station_wear_m3_per_s"][0].erase(31); },
          "stage 0: result.station_wear_m3_per_s[0]: 31 entries, where 32 wear stations are due");
  refused([](json& d) { d["stages"][1]["profiles"][0] = {d["stages"][1]["profiles"][0][0], d["stages"][1]["profiles"][0][1]}; },
          "stage 1: profiles[0]: 2 points: a profile needs at least 3 (two feet on the shell and a top)");
  refused([](json& d) { d["stages"][0]["ran"] = "yes"; }, "stage 0: ran: expected true or false, found a string, \"yes\"");
  refused([](json& d) { d["stages"][0].erase("wear"); }, "stage 0: wear: missing, yet stage 1 follows");
  refused([](json& d) { d["stages"] = json::array(); }, "stages: empty list: the study holds no stage");
  refused([](json& d) { d["calibration"]["hours_and_wear_rates"] = "absolute"; },
          "calibration.hours_and_wear_rates: \"absolute\", not one of \"calibrated\", \"relative\", "
          "\"case_coefficient\"");
  refused([](json& d) { d["calibration"]["wear_coefficient_m3_per_N_m"] = 0; },
          "calibration.wear_coefficient_m3_per_N_m: must be > 0 where impact_wear_coefficient_m3_per_J is 0 or missing");
  CHECK(good.at("calibration").at("hours_and_wear_rates") == "relative");
  CHECK(good.at("calibration").at("case_wear_coefficient_m3_per_N_m").get<double>() == mc::kDefaultWearCoefficient);
  refused([](json& d) { d["format"] = "millcharge life 0"; },
          "format: \"millcharge life 0\", this millcharge reads \"millcharge life 2\"");
  write_text(dir / "life.json", good.dump(1).substr(0, 500));
  CHECK_THROWS_WITH(mc::app::life::read_life_state(dir / "life.json", shape),
                    file + ": cut short after 500 bytes; the file is damaged");
  fs::remove_all(dir);
}

TEST_CASE("a damaged life.json is refused before anything runs or is written (fuzz)", "[life][cli][failures]") {
  const fs::path dir = copy_of_study("fuzz");
  const std::string good = read_text(dir / "life.json");
  const std::map<std::string, std::string> before = files_under(dir);
  const auto cases = damaged(good);
  REQUIRE(cases.size() > 300);
  const auto start = std::chrono::steady_clock::now();
  int failed = 0;
  for (const auto& [label, text] : cases) {
    REQUIRE(text != good);
    write_text(dir / "life.json", text);
    std::string err;
    // A refusal takes well under a second; a stage's run would take longer.
    const int rc = millcharge("life" + kStudy + " --out '" + dir.string() + "'", &err);
    std::map<std::string, std::string> want = before;
    want["life.json"] = text;
    const bool ok = rc == 2 && std::count(err.begin(), err.end(), '\n') == 1 &&
                    err.find("life.json") != std::string::npos && err.find("json.exception") == std::string::npos &&
                    files_under(dir) == want;
    if (!ok && ++failed <= 10) {
      INFO(label << ": status " << rc << ": " << err);
      CHECK(ok);
    }
  }
  CHECK(failed == 0);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CHECK(seconds < 120);
  WARN(cases.size() << " damaged life.json files refused in " << seconds << " s");
  fs::remove_all(dir);
}

TEST_CASE("a life study killed in its first stage resumes to the same table", "[life][cli]") {
  const fs::path dir = scratch("killed-0");
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = "exec " + std::string(MC_BINARY) + " life" + kStudy + " --out '" + dir.string() +
                            "' >/dev/null 2>&1";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(300);
  while (!fs::exists(dir / "stage-00" / "checkpoint.bin") && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, SIGKILL);
  int st = 0;
  ::waitpid(pid, &st, 0);
  REQUIRE(WIFSIGNALED(st));
  CHECK_FALSE(fs::exists(dir / "stage-00" / "summary.json"));
  // Its state, written before the first run: stage 0, not yet run.
  const json j = json::parse(read_text(dir / "life.json"));
  REQUIRE(j.at("stages").size() == 1);
  CHECK(j.at("stages")[0].at("ran") == false);
  std::string err;
  const int resumed = millcharge("life" + kStudy + " --out '" + dir.string() + "'", &err);
  INFO(err);
  REQUIRE(resumed == 0);
  CHECK(read_text(dir / "life.csv") == read_text(study() / "life.csv"));
  fs::remove_all(dir);
}

TEST_CASE("a stage's damaged summary.json is refused in words, naming the file", "[life][cli][failures]") {
  const fs::path dir = copy_of_study("summary");
  // The last stage as if killed after its run and before the state was saved:
  // the resumed study reads its summary.json.
  json j = json::parse(read_text(dir / "life.json"));
  j["stages"][1]["ran"] = false;
  j["stages"][1].erase("result");
  j.erase("stopped");
  write_text(dir / "life.json", j.dump(1) + "\n");
  const std::string summary = read_text(dir / "stage-01" / "summary.json");
  json no_power = json::parse(summary);
  no_power.erase("power_W");
  const std::string sj = (dir / "stage-01" / "summary.json").string();
  const std::vector<std::pair<std::string, std::string>> bad = {
      {summary.substr(0, 900), sj + ": cut short after 900 bytes; the file is damaged"},
      {no_power.dump(2), sj + ": power_W: missing; not a millcharge run's summary"},
      {"{\"power_W\": }", sj + ": not valid JSON at line 1, column 13; the file is damaged"},
  };
  for (const auto& [text, said] : bad) {
    write_text(dir / "stage-01" / "summary.json", text);
    const std::map<std::string, std::string> before = files_under(dir);
    std::string err;
    CHECK(millcharge("life" + kStudy + " --out '" + dir.string() + "'", &err) == 2);
    CHECK(err == "millcharge: " + said + "\n");
    CHECK(files_under(dir) == before);
  }
  fs::remove_all(dir);
}

TEST_CASE("grind --scale-from a run with a damaged summary.json is refused in words", "[life][grind][failures]") {
  const fs::path lab = scratch("lab-run"), out = scratch("grind-out");
  fs::copy(study() / "stage-01", lab, fs::copy_options::recursive);
  const std::string summary = read_text(lab / "summary.json");
  json no_torque = json::parse(summary);
  no_torque["power_W"].erase("torque");
  const std::string sj = (lab / "summary.json").string();
  const std::vector<std::pair<std::string, std::string>> bad = {
      {summary.substr(0, 300), sj + ": cut short after 300 bytes; the file is damaged"},
      {no_torque.dump(2), sj + ": power_W.torque: missing; not a millcharge run's summary"},
      {"[1, 2]", sj + ": expected an object, found a list; not a millcharge run's summary"},
  };
  for (const auto& [text, said] : bad) {
    write_text(lab / "summary.json", text);
    std::string err;
    CHECK(millcharge("grind '" + (study() / "stage-00").string() + "' --ore '" + MC_ASSET_DIR +
                         "/ores/example_spectrum.toml' --time 1 --scale-from '" + lab.string() + "' --out '" +
                         out.string() + "'",
                     &err) == 2);
    // The short run's warning that it is not in steady motion, then the refusal.
    const std::size_t last = err.rfind('\n', err.size() - 2);
    CHECK(err.substr(last == std::string::npos ? 0 : last + 1) == "millcharge: " + said + "\n");
    CHECK(err.find("json.exception") == std::string::npos);
    CHECK_FALSE(fs::exists(out));
  }
  fs::remove_all(lab);
}

TEST_CASE("life.csv's top wear rate is the stations' at the lifter's top", "[life][cli]") {
  // Independently of the study's code: the stations of stage 0's run whose
  // centre is above 90 % of the new bar's 25 mm, their depth rates averaged
  // (volume rate over the station's strip of bar, length x mill length).
  const fs::path dir = study();
  const double L = mc::io::read_case(dir / "cases" / "stage-00.toml").length;
  const mc::io::CsvTable t = mc::io::read_csv_strict(dir / "stage-00" / "lifter_wear.csv");
  const int c_y = t.column("y_mm"), c_len = t.column("length_mm"), c_w = t.column("wear_m3_per_s");
  double sum = 0;
  int n = 0;
  for (std::size_t k = 0; k < t.rows.size(); ++k)
    if (t.number(k, c_y) >= 0.9 * 25.0) {
      const double m_per_s = t.number(k, c_w) / (t.number(k, c_len) * 1e-3 * L);
      sum += m_per_s * 1000 * 3600 * 1000;  // mm per 1000 h
      ++n;
    }
  REQUIRE(n >= 2);
  const mc::io::CsvTable life = mc::io::read_csv_strict(dir / "life.csv");
  const double top = life.number(0, life.column("top_wear_mm_per_1000h"));
  CHECK(top > 0);
  CHECK(top == Approx(sum / n).epsilon(2e-3));
}

TEST_CASE("an impact share sets the two wear coefficients so that the new liner wears as much, S of it by impact",
          "[life][impact_wear]") {
  using mc::app::life::StageResult;
  StageResult s0;
  s0.parts.liner_sliding_kg_h = 2.0;   // at the case's sliding coefficient
  s0.parts.liner_strike_W = 500.0;     // J/s of strike energy on the shell and lifters
  s0.parts.shell_sliding_mm_per_1000h = 10.0;
  s0.parts.shell_strike_W_m2 = 40.0;
  s0.parts.station_sliding_m3_s = {{1e-9, 2e-9}};
  s0.parts.station_strike_W = {{3.0, 0.0}};
  s0.station_m3_s = {{0, 0}};
  const double rho = 7800, k_case = 1e-11;
  const double impact_kg_h = k_case * 500.0 * rho * 3600, total = 2.0 + impact_kg_h;
  for (double share : {0.0, 0.25, 0.5, 1.0}) {
    INFO("share " << share);
    const mc::app::life::WearMix m = mc::app::life::mix_for_share(s0, share, k_case, rho);
    StageResult r = s0;
    mc::app::life::apply_mix(r, m, rho);
    // The new liner: the same kg/h as at the case's coefficients, S of it
    // by impact.
    CHECK(r.liner_kg_h == Approx(total).epsilon(1e-12));
    CHECK(m.impact * 500.0 * rho * 3600 / r.liner_kg_h == Approx(share).margin(1e-12));
    CHECK(m.sliding == Approx((1 - share) * total / 2.0).margin(1e-12));
    // 40 W/m² at m³/J is a depth rate in m/s: 1000 mm/m, 3600 s/h, 1000 h.
    const double mm_per_1000h_per_m_s = 1000.0 * 3600.0 * 1000.0;
    CHECK(r.shell_mm_per_1000h == Approx(m.sliding * 10.0 + m.impact * 40.0 * mm_per_1000h_per_m_s).epsilon(1e-12));
    CHECK(r.station_m3_s[0][0] == Approx(m.sliding * 1e-9 + m.impact * 3.0).epsilon(1e-12));
    CHECK(r.station_m3_s[0][1] == Approx(m.sliding * 2e-9).epsilon(1e-12));
  }
  // A shell whose coefficients are R times the bars': the shell wears R
  // times as deep, and the new liner still as much in all, S of it by
  // impact.
  // The shell's parts as one 10 m² shell of this density gives them: 10
  // mm per 1000 h over 10 m² is 0.78 kg/h, 40 W/m² over it 400 W.
  const double area = 10.0;
  s0.parts.shell_sliding_kg_h = 10.0 * 1e-6 * area * rho;
  s0.parts.shell_strike_W = 40.0 * area;
  for (double R : {0.5, 1.25})
    for (double share : {0.0, 0.4}) {
      INFO("ratio " << R << ", share " << share);
      const mc::app::life::WearMix m = mc::app::life::mix_for_share(s0, share, k_case, rho, R);
      StageResult r = s0;
      mc::app::life::apply_mix(r, m, rho);
      CHECK(r.liner_kg_h == Approx(total).epsilon(1e-12));
      CHECK(mc::app::life::impact_share(r, m, rho) == Approx(share).margin(1e-12));
      CHECK(r.shell_mm_per_1000h == Approx(R * (m.sliding * 10.0 + m.impact * 40.0 * 1000.0 * 3600.0 * 1000.0))
                                         .epsilon(1e-12));
      // The bars' stations keep the bars' coefficients.
      CHECK(r.station_m3_s[0][1] == Approx(m.sliding * 2e-9).epsilon(1e-12));
      // The shell's depth rate over its area is the shell's part of the
      // mixed kg/h: the depth and the mass paths agree.
      const double shell_kg_h = R * (m.sliding * s0.parts.shell_sliding_kg_h + m.impact * s0.parts.shell_strike_W * rho * 3600);
      CHECK(r.shell_mm_per_1000h * 1e-6 * area * rho == Approx(shell_kg_h).epsilon(1e-12));
    }
  // Where one wear is missing, the share that needs it is refused by name.
  StageResult no_strike = s0;
  no_strike.parts.liner_strike_W = 0;
  CHECK_THROWS_WITH(mc::app::life::mix_for_share(no_strike, 0.3, k_case, rho),
                    Catch::Contains("--impact-share 0.3: the new liner's run booked no strike energy"));
  CHECK_NOTHROW(mc::app::life::mix_for_share(no_strike, 0.0, k_case, rho));
  StageResult no_slide = s0;
  no_slide.parts.liner_sliding_kg_h = 0;
  CHECK_THROWS_WITH(mc::app::life::mix_for_share(no_slide, 0.5, k_case, rho),
                    Catch::Contains("booked no sliding wear"));
  CHECK_NOTHROW(mc::app::life::mix_for_share(no_slide, 1.0, k_case, rho));
}

TEST_CASE("the stages' standard errors add in quadrature, and a stage without halves ends them", "[life][life_state]") {
  using mc::app::life::Stage;
  std::vector<Stage> st(4);
  for (int i = 0; i < 4; ++i) {
    st[i].index = i;
    st[i].outlines = {{{0.01, 0}, {0, 0.01}, {-0.01, 0}}};
    if (i < 3) st[i].span_case_hours = 100;
  }
  st[0].se_height_mm = {3}, st[0].se_leading_deg = {1}, st[0].se_trailing_deg = {0.5};
  st[1].se_height_mm = {4}, st[1].se_leading_deg = {2}, st[1].se_trailing_deg = {0};
  const auto e = mc::app::life::cumulative_se(st);
  REQUIRE(e.size() == 4);
  CHECK(e[0].height_mm[0] == 0);
  CHECK(e[1].height_mm[0] == Approx(3));
  CHECK(e[2].height_mm[0] == Approx(5));  // sqrt(3^2 + 4^2)
  CHECK(e[2].leading_deg[0] == Approx(std::sqrt(5.0)));
  CHECK(e[2].trailing_deg[0] == Approx(0.5));
  CHECK(std::isnan(e[3].height_mm[0]));  // stage 2 had no halves
}
