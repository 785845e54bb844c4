#include "app/sweep_runs.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>

#include "io/json_read.h"

namespace mc::app {

namespace fs = std::filesystem;

const char* status_name(CaseStatus s) {
  switch (s) {
    case CaseStatus::not_started: return "not started";
    case CaseStatus::incomplete: return "incomplete";
    case CaseStatus::stopped: return "stopped";
    case CaseStatus::failed: return "failed";
    case CaseStatus::done: return "done";
  }
  return "?";
}

std::string last_log_line(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line)) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    // A terminal's progress line is rewritten in place: its last state counts.
    if (const std::size_t cr = line.find_last_of('\r'); cr != std::string::npos) line = line.substr(cr + 1);
    if (line.empty() || line.rfind("== ", 0) == 0) continue;
    last = line;
  }
  return last;
}

std::string file_not_of_a_sweep(const fs::path& dir) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) return "";
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name != "run.log" && name != "exit_status" && name != "exit_status.tmp") return name;
  }
  return ec ? "what cannot be listed (" + ec.message() + ")" : "";
}

nlohmann::json life_study_state(const fs::path& case_dir) {
  std::ifstream in(case_dir / "life.json", std::ios::binary);
  if (!in) return nlohmann::json::object();
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (!io::json_text_fault(text).empty()) return nlohmann::json::object();
  nlohmann::json j = nlohmann::json::parse(text);
  return j.is_object() ? j : nlohmann::json::object();
}

std::string life_study_stopped(const nlohmann::json& state) {
  return state.contains("stopped") && state["stopped"].is_string() ? state["stopped"].get<std::string>() : "";
}

CaseState case_state(const fs::path& dir, bool life) {
  CaseState st;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return st;
  st.checkpoint = fs::exists(dir / (life ? "life.json" : "checkpoint.bin"), ec);
  if (std::ifstream in(dir / "exit_status"); in) {
    int code = -1;
    if (in >> code) st.exit_status = code;
  }
  st.last_line = last_log_line(dir / "run.log");
  if (life ? !life_study_stopped(life_study_state(dir)).empty() : fs::exists(dir / "summary.json", ec))
    st.status = CaseStatus::done;
  else if (st.exit_status >= 128) st.status = CaseStatus::stopped;
  else if (st.exit_status >= 0) st.status = CaseStatus::failed;
  else st.status = CaseStatus::incomplete;
  if (st.status == CaseStatus::failed && st.exit_status == 0)
    st.last_line = std::string("exit status 0 but no ") + (life ? "ended study in life.json" : "summary.json") + "; " +
                   st.last_line;
  return st;
}

fs::path case_path(const fs::path& sweep_dir, const std::string& dir) { return sweep_dir / "cases" / dir; }

nlohmann::ordered_json cases_json(const io::Sweep& s, const std::vector<io::SweepCase>& cases) {
  auto value = [](const io::SweepValue& v) { return v.numeric ? nlohmann::ordered_json(v.number) : nlohmann::ordered_json(v.text); };
  nlohmann::ordered_json j;
  j["sweep"] = s.name;
  j["file"] = s.file.string();
  j["case"] = s.base_case.string();
  j["set"] = s.set;
  j["combine"] = s.zipped ? "zip" : "cross";
  j["command"] = s.command;
  if (s.is_life()) {
    nlohmann::ordered_json life;
    for (const io::SweepLifeOption& o : s.life) life[o.key] = value(o.value);
    j["life"] = life;
  }
  const std::vector<std::string> names = io::short_axis_names(s);
  j["axes"] = nlohmann::json::array();
  for (std::size_t i = 0; i < s.axes.size(); ++i) {
    nlohmann::ordered_json a;
    a["key"] = s.axes[i].key;
    a["name"] = names[i];
    a["group"] = s.axes[i].group;
    a["values"] = nlohmann::json::array();
    for (const io::SweepValue& v : s.axes[i].values) a["values"].push_back(value(v));
    j["axes"].push_back(a);
  }
  j["cases"] = nlohmann::json::array();
  for (const io::SweepCase& c : cases) {
    nlohmann::ordered_json e;
    e["index"] = c.index;
    e["dir"] = c.dir;
    nlohmann::ordered_json values;
    for (std::size_t i = 0; i < s.axes.size(); ++i) values[s.axes[i].key] = value(s.axes[i].values[c.value_index[i]]);
    e["values"] = values;
    e["overrides"] = c.overrides;
    if (s.is_life()) e["life_args"] = c.life_args;
    j["cases"].push_back(e);
  }
  return j;
}

namespace {

volatile sig_atomic_t g_stop = 0;
extern "C" void on_sweep_signal(int sig) { g_stop = sig; }

std::string wall_text(double s) {
  char buf[32];
  if (s < 60) std::snprintf(buf, sizeof buf, "%.0fs", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  else std::snprintf(buf, sizeof buf, "%dh%02dm", static_cast<int>(s) / 3600, static_cast<int>(s) / 60 % 60);
  return buf;
}

}  // namespace

int run_local(const fs::path& script, const fs::path& sweep_dir, const std::vector<io::SweepCase>& cases,
              const std::vector<int>& indexes, int parallel, const io::Sweep& s) {
  using clock = std::chrono::steady_clock;
  // SIGINT (Ctrl-C, which the runs get too) and SIGTERM: no new cases, the
  // running ones stop with a checkpoint. No SA_RESTART: waitpid returns.
  g_stop = 0;
  struct sigaction sa {}, old_int {}, old_term {};
  sa.sa_handler = on_sweep_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &old_int);
  sigaction(SIGTERM, &sa, &old_term);

  struct Running {
    int index;
    clock::time_point start;
  };
  std::map<pid_t, Running> running;
  std::size_t next = 0;
  int n_done = 0, n_failed = 0, n_stopped = 0;
  bool forwarded = false;
  const int total = static_cast<int>(indexes.size());
  while (next < indexes.size() || !running.empty()) {
    while (!g_stop && next < indexes.size() && static_cast<int>(running.size()) < parallel) {
      const int index = indexes[next++];
      std::fflush(stdout);
      const pid_t pid = ::fork();
      if (pid < 0) {
        std::perror("millcharge: fork");
        g_stop = SIGTERM;
        break;
      }
      if (pid == 0) {
        const std::string arg = std::to_string(index);
        ::execl("/bin/bash", "bash", script.c_str(), arg.c_str(), static_cast<char*>(nullptr));
        std::perror("millcharge: /bin/bash");
        ::_exit(127);
      }
      running[pid] = {index, clock::now()};
      std::printf("case %d (%s): started\n", index, io::case_label(s, cases[index]).c_str());
      std::fflush(stdout);
    }
    if (g_stop && !forwarded) {
      for (auto& [pid, r] : running) ::kill(pid, SIGTERM);  // sweep.sh hands it to the run
      forwarded = true;
    }
    if (running.empty()) break;
    int st = 0;
    const pid_t pid = ::waitpid(-1, &st, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;
    }
    auto it = running.find(pid);
    if (it == running.end()) continue;
    const int index = it->second.index;
    const double wall = std::chrono::duration<double>(clock::now() - it->second.start).count();
    running.erase(it);
    const CaseState cs = case_state(case_path(sweep_dir, cases[index].dir), s.is_life());
    const std::string label = io::case_label(s, cases[index]);
    if (cs.status == CaseStatus::done) {
      ++n_done;
      std::printf("case %d (%s): done in %s\n", index, label.c_str(), wall_text(wall).c_str());
    } else if (cs.status == CaseStatus::stopped) {
      ++n_stopped;
      std::printf("case %d (%s): stopped (exit status %d), %s kept\n", index, label.c_str(), cs.exit_status,
                  s.is_life() ? "the study (life.json) and its stage's checkpoint" : "checkpoint");
    } else {
      ++n_failed;
      const int code = cs.exit_status >= 0 ? cs.exit_status : WIFEXITED(st) ? WEXITSTATUS(st) : -1;
      std::printf("case %d (%s): failed (exit status %d): %s\n", index, label.c_str(), code, cs.last_line.c_str());
    }
    std::fflush(stdout);
  }
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  const int not_run = total - n_done - n_failed - n_stopped;
  std::printf("sweep %s: %d of %d cases run here finished, %d failed, %d stopped%s\n", s.name.c_str(), n_done, total,
              n_failed, n_stopped, not_run > 0 ? (", " + std::to_string(not_run) + " not started").c_str() : "");
  if (g_stop) return 128 + g_stop;
  return n_failed > 0 || n_stopped > 0 ? 1 : 0;
}

}  // namespace mc::app
