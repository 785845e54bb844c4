#include "app/slurm.h"

#include <pwd.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace mc::app {

namespace fs = std::filesystem;

namespace {

// Runs a shell command; returns its exit status and its output (stdout and
// stderr together).
int capture(const std::string& command, std::string& output) {
  output.clear();
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) output.append(buf, n);
  const int st = ::pclose(p);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ' || s.back() == '\r')) s.pop_back();
  return s;
}

}  // namespace

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char ch : s) {
    if (ch == '\'') out += "'\\''";
    else out += ch;
  }
  return out + "'";
}

std::string array_spec(const std::vector<int>& indexes, int max_running) {
  std::string out;
  for (std::size_t i = 0; i < indexes.size();) {
    std::size_t j = i;
    while (j + 1 < indexes.size() && indexes[j + 1] == indexes[j] + 1) ++j;
    if (!out.empty()) out += ",";
    out += std::to_string(indexes[i]);
    if (j > i) out += "-" + std::to_string(indexes[j]);
    i = j + 1;
  }
  if (max_running > 0 && !out.empty()) out += "%" + std::to_string(max_running);
  return out;
}

JobScript job_script_for(const io::Sweep& s, const std::vector<io::SweepCase>& cases, const fs::path& sweep_dir,
                         const fs::path& millcharge) {
  JobScript j;
  j.name = s.name;
  j.millcharge = millcharge;
  j.sweep_dir = sweep_dir;
  j.base_case = s.base_case;
  j.device = s.device;
  j.common = s.set;
  j.command = s.command;
  j.slurm = s.slurm;
  for (const io::SweepCase& c : cases) {
    JobScript::Case jc;
    jc.index = c.index;
    jc.dir = c.dir;
    jc.label = io::case_label(s, c);
    jc.axes.assign(c.overrides.begin() + static_cast<long>(s.set.size()), c.overrides.end());
    jc.life = c.life_args;
    j.cases.push_back(std::move(jc));
  }
  return j;
}

std::string job_script_text(const JobScript& j) {
  std::ostringstream o;
  o << "#!/bin/bash\n"
    << "# millcharge sweep '" << j.name << "': " << j.cases.size() << " cases of " << j.base_case.string() << ".\n"
    << "# Written by `millcharge sweep run`. Array task N runs case N (SLURM_ARRAY_TASK_ID):\n";
  if (j.command == "life")
    o << "# a life study, `millcharge life` into cases/NAME/, which resumes the study there\n"
      << "# from its life.json. SIGTERM (scancel, the time limit) stops the stage's run\n"
      << "# with a checkpoint; submitting the case again resumes it. Without Slurm,\n";
  else
    o << "# a normal `millcharge run` into cases/NAME/, or `millcharge run --resume` when\n"
      << "# that folder holds a checkpoint. SIGTERM (scancel, the time limit) stops the\n"
      << "# run with a checkpoint; submitting the case again resumes it. Without Slurm,\n";
  o << "# `bash sweep.sh N` runs case N here. Output: cases/NAME/run.log, exit_status.\n";
  o << "#SBATCH --job-name=" << j.name << "\n";
  if (!j.array.empty()) o << "#SBATCH --array=" << array_spec(j.array, j.slurm.max_running) << "\n";
  o << "#SBATCH --output=" << (j.sweep_dir / "slurm" / "%A_%a.out").string() << "\n";
  o << "#SBATCH --ntasks=1\n";
  if (!j.slurm.partition.empty()) o << "#SBATCH --partition=" << j.slurm.partition << "\n";
  if (!j.slurm.time.empty()) o << "#SBATCH --time=" << j.slurm.time << "\n";
  if (j.slurm.gpus_per_task > 0) o << "#SBATCH --gpus-per-task=" << j.slurm.gpus_per_task << "\n";
  if (j.slurm.cpus_per_task > 0) o << "#SBATCH --cpus-per-task=" << j.slurm.cpus_per_task << "\n";
  if (j.slurm.signal_grace_s > 0) o << "#SBATCH --signal=B:TERM@" << j.slurm.signal_grace_s << "\n";
  for (const std::string& a : j.slurm.sbatch_args) o << "#SBATCH " << a << "\n";
  o << "\n";
  o << "millcharge=" << shell_quote(j.millcharge.string()) << "\n"
    << "sweep=" << shell_quote(j.sweep_dir.string()) << "\n"
    << "base=" << shell_quote(j.base_case.string()) << "\n"
    << "device=" << shell_quote(j.device) << "\n"
    << "common=(";
  for (std::size_t i = 0; i < j.common.size(); ++i) o << (i ? " " : "") << "--set " << shell_quote(j.common[i]);
  o << ")\n\n";
  o << "task=${SLURM_ARRAY_TASK_ID:-$1}\n"
    << "case \"$task\" in\n";
  for (const JobScript::Case& c : j.cases) {
    o << "  " << c.index << ")  # " << c.label << "\n"
      << "    name=" << shell_quote(c.dir) << "\n"
      << "    axes=(";
    for (std::size_t i = 0; i < c.axes.size(); ++i) o << (i ? " " : "") << "--set " << shell_quote(c.axes[i]);
    o << ")";
    if (j.command == "life") {
      o << "\n    life=(";
      for (std::size_t i = 0; i < c.life.size(); ++i) o << (i ? " " : "") << shell_quote(c.life[i]);
      o << ")";
    }
    o << " ;;\n";
  }
  o << "  *) echo \"sweep.sh: no case '$task' (the cases are 0 to " << (j.cases.empty() ? 0 : j.cases.back().index)
    << "); run it as a Slurm array task or as: bash sweep.sh N\" >&2\n"
    << "     exit 2 ;;\n"
    << "esac\n\n";
  if (j.command == "life")
    o << R"(dir=$sweep/cases/$name
# A study that ended says where in its life.json ("stopped").
if [ -f "$dir/life.json" ] && grep -q '"stopped"' "$dir/life.json"; then
  echo "case $task ($name) has finished: $dir/life.json"
  exit 0
fi)";
  else
    o << R"(dir=$sweep/cases/$name
if [ -f "$dir/summary.json" ]; then
  echo "case $task ($name) has finished: $dir/summary.json"
  exit 0
fi)";
  o << R"(
mkdir -p "$dir" || exit 1
exec >>"$dir/run.log" 2>&1
rm -f "$dir/exit_status"
echo "== case $task ($name) on $(hostname) at $(date -u +%Y-%m-%dT%H:%M:%SZ)${SLURM_JOB_ID:+, Slurm job ${SLURM_ARRAY_JOB_ID:-$SLURM_JOB_ID}_$task}"
device_opt=()
if [ -n "$device" ]; then device_opt=(--device "$device"); fi
)";
  if (j.command == "life")
    o << R"(# The study resumes from its life.json (and a stage's run from its checkpoint).
run=("$millcharge" life "$base" --out "$dir" "${common[@]}" "${axes[@]}" "${life[@]}" "${device_opt[@]}"))";
  else
    o << R"(if [ -f "$dir/checkpoint.bin" ]; then
  run=("$millcharge" run --resume "$dir" "${device_opt[@]}")
else
  run=("$millcharge" run "$base" --out "$dir" --force "${common[@]}" "${axes[@]}" "${device_opt[@]}")
fi)";
  o << R"(
echo "== ${run[*]}"
# The run gets the signal, writes its checkpoint and exits 128 + the signal.
pid=
trap 'if [ -n "$pid" ]; then kill -TERM "$pid" 2>/dev/null; fi' TERM
trap 'if [ -n "$pid" ]; then kill -INT "$pid" 2>/dev/null; fi' INT
"${run[@]}" &
pid=$!
wait "$pid"
status=$?
while kill -0 "$pid" 2>/dev/null; do  # a trapped signal ends `wait` early
  wait "$pid"
  status=$?
done
echo "$status" >"$dir/exit_status.tmp" && mv -f "$dir/exit_status.tmp" "$dir/exit_status"
echo "== exit status $status"
exit "$status"
)";
  return o.str();
}

bool on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string d;
  while (std::getline(dirs, d, ':'))
    if (!d.empty() && ::access((fs::path(d) / program).c_str(), X_OK) == 0) return true;
  return false;
}

std::string submit(const fs::path& script) {
  std::string out;
  const int st = capture("sbatch --parsable " + shell_quote(script.string()), out);
  out = trimmed(out);
  if (st != 0) throw std::runtime_error("sbatch failed (exit status " + std::to_string(st) + "): " + out);
  // The id is the last line: "123" or "123;cluster"; warnings may come first.
  const std::size_t nl = out.find_last_of('\n');
  std::string id = out.substr(nl == std::string::npos ? 0 : nl + 1);
  id = id.substr(0, id.find(';'));
  if (id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
    throw std::runtime_error("sbatch answered without a job id: " + out);
  return id;
}

std::map<std::string, std::set<int>> queued_tasks(const std::set<std::string>& job_ids) {
  std::map<std::string, std::set<int>> out;
  if (job_ids.empty()) return out;
  const passwd* pw = ::getpwuid(::getuid());
  const std::string user = pw ? pw->pw_name : std::to_string(::getuid());
  std::string text;
  // By user rather than by job id: squeue refuses ids it no longer knows.
  const int st = capture("squeue --noheader --array --format='%F %K %T' --user=" + shell_quote(user), text);
  if (st != 0)
    throw std::runtime_error("squeue failed (exit status " + std::to_string(st) + "): " + trimmed(text) +
                             "; without it the sweep cannot tell which cases are queued or running");
  std::istringstream lines(text);
  std::string job, task, state;
  while (lines >> job >> task >> state)
    if (job_ids.count(job) && task.find_first_not_of("0123456789") == std::string::npos)
      out[job].insert(std::stoi(task));
  return out;
}

}  // namespace mc::app
