#include "io/checkpoint.h"

#include <sys/stat.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <thread>

#include "io/atomic_file.h"

namespace mc::io {

namespace {

constexpr char kMagic[] = "millcharge checkpoint\n";
constexpr std::uint32_t kVersion = 1;

std::uint64_t fnv1a(const char* p, std::size_t n) {
  std::uint64_t h = 1469598103934665603ULL;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(p[i]);
    h *= 1099511628211ULL;
  }
  return h;
}

template <class T>
void put(std::string& out, T v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

void put_record(std::string& out, const std::string& name, const char* data, std::size_t n) {
  put(out, static_cast<std::uint32_t>(name.size()));
  out += name;
  put(out, static_cast<std::uint64_t>(n));
  out.append(data, n);
}

// key=value lines; doubles keep all their bits through %.17g.
class Scalars {
 public:
  void set(const std::string& k, double v) {
    char b[64];
    std::snprintf(b, sizeof b, "%.17g", v);
    text_ += k + "=" + b + "\n";
  }
  void set(const std::string& k, long v) { text_ += k + "=" + std::to_string(v) + "\n"; }
  void set(const std::string& k, int v) { set(k, static_cast<long>(v)); }
  void set(const std::string& k, bool v) { set(k, static_cast<long>(v ? 1 : 0)); }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

class ScalarReader {
 public:
  ScalarReader(const std::string& text, std::string where) : where_(std::move(where)) {
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
      const auto eq = line.find('=');
      if (eq != std::string::npos) values_[line.substr(0, eq)] = line.substr(eq + 1);
    }
  }
  double real(const std::string& k) const {
    const std::string& v = at(k);
    char* end = nullptr;
    const double d = std::strtod(v.c_str(), &end);
    if (end == v.c_str() || *end) throw CheckpointError(where_ + ": " + k + " is not a number");
    return d;
  }
  void get(const std::string& k, double& v) const { v = real(k); }
  void get(const std::string& k, long& v) const { v = integer(k); }
  void get(const std::string& k, int& v) const { v = static_cast<int>(integer(k)); }
  void get(const std::string& k, bool& v) const { v = integer(k) != 0; }
  bool has(const std::string& k) const { return values_.count(k) != 0; }
  long integer(const std::string& k) const {
    const std::string& v = at(k);
    char* end = nullptr;
    const long l = std::strtol(v.c_str(), &end, 10);
    if (end == v.c_str() || *end) throw CheckpointError(where_ + ": " + k + " is not an integer");
    return l;
  }

 private:
  const std::string& at(const std::string& k) const {
    const auto it = values_.find(k);
    if (it == values_.end()) throw CheckpointError(where_ + ": " + k + " is missing");
    return it->second;
  }
  std::string where_;
  std::map<std::string, std::string> values_;
};

// Every scalar of a RunState and of a SolverState, by name: one list that
// the writer and the reader both walk.
template <class R, class F>
void run_fields(R& r, F&& f) {
  f("phase", r.phase);
  f("settle_start_s", r.settle_start_s);
  f("settled", r.settled);
  f("settle_s", r.settle_s);
  f("settled_filling", r.settled_filling);
  f("turn_start_s", r.turn_start_s);
  f("turn_step", r.turn_step);
  f("e_window_start", r.e_window_start);
  f("open_loss_start", r.open_loss_start);
  f("e_end", r.e_end);
  f("work", r.work);
  f("diss", r.diss);
  f("torque_time", r.torque_time);
  f("arm_time", r.arm_time);
  f("span", r.span);
  f("comx", r.comx);
  f("comy", r.comy);
  f("neigh", r.neigh);
  f("rows_in_window", r.rows_in_window);
  f("rows", r.rows);
  f("snapshots", r.snapshots);
  f("wall_s", r.wall_s);
  f("stop_step", r.stop_step);
  f("settle_wall_s", r.settle_wall_s);
  f("batches_per_revolution", r.batches_per_revolution);
  f("window_floor_step", r.window_floor_step);
  f("window_begun", r.window_begun);
  f("pre_span", r.pre_span);
  f("pre_work", r.pre_work);
  f("pre_diss", r.pre_diss);
  f("pre_torque_time", r.pre_torque_time);
  f("half_window_s", r.half_window_s);
}

// Fields added after version 1 began: older files lack them, and the run
// keeps their defaults (no floor, the window's start judged from the step,
// windows that began on a row boundary).
bool optional_run_field(const std::string& key) {
  for (const char* k : {"open_loss_start", "stop_step", "settle_wall_s", "batches_per_revolution", "window_floor_step",
                        "window_begun", "pre_span", "pre_work", "pre_diss", "pre_torque_time", "half_window_s"})
    if (key == k) return true;
  return false;
}

// Doubles as raw bytes (every bit kept).
std::string doubles_bytes(const std::vector<double>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(double));
}
std::vector<double> bytes_doubles(const std::string& b) {
  std::vector<double> v(b.size() / sizeof(double));
  std::memcpy(v.data(), b.data(), v.size() * sizeof(double));
  return v;
}

template <class S, class F>
void solver_fields(S& s, F&& f) {
  f("real_bytes", s.real_bytes);
  f("n_balls", s.n_balls);
  f("time_s", s.time_s);
  f("steps", s.steps);
  f("rebuilds", s.rebuilds);
  f("mill_angle", s.mill_angle);
  f("mill_omega", s.mill_omega);
  f("observed_since", s.observed_since);
  f("pending_flags", s.pending_flags);
}

}  // namespace

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& cp) {
  std::string payload;
  put_record(payload, "case.name", cp.case_name.data(), cp.case_name.size());
  put_record(payload, "case.toml", cp.case_toml.data(), cp.case_toml.size());

  const RunState& r = cp.run;
  Scalars rs;
  run_fields(r, [&](const char* k, auto v) { rs.set(k, v); });
  put_record(payload, "run", rs.text().data(), rs.text().size());
  std::vector<std::int64_t> prof(r.window_profile.begin(), r.window_profile.end());
  put_record(payload, "run.window_profile", reinterpret_cast<const char*>(prof.data()),
             prof.size() * sizeof(std::int64_t));

  // The window's revolutions, the open one's sums and contact profile.
  std::vector<double> revs;
  for (const WindowBatch& m : r.batches)
    for (auto field : kWindowBatchFields) revs.push_back(m.*field);
  const std::string revs_bytes = doubles_bytes(revs);
  put_record(payload, "run.revolutions", revs_bytes.data(), revs_bytes.size());
  std::vector<double> tally;
  for (auto field : kTallyFields) tally.push_back(r.batch.*field);
  const std::string tally_bytes = doubles_bytes(tally);
  put_record(payload, "run.revolution", tally_bytes.data(), tally_bytes.size());
  std::vector<std::int64_t> rprof(r.batch_profile.begin(), r.batch_profile.end());
  put_record(payload, "run.batch_profile", reinterpret_cast<const char*>(rprof.data()),
             rprof.size() * sizeof(std::int64_t));
  const std::string half_bytes = doubles_bytes(r.half_books);
  put_record(payload, "run.half_books", half_bytes.data(), half_bytes.size());

  const SolverState& s = cp.solver;
  Scalars ss;
  solver_fields(s, [&](const char* k, auto v) { ss.set(k, v); });
  put_record(payload, "solver", ss.text().data(), ss.text().size());
  for (const auto& [name, bytes] : s.arrays)
    put_record(payload, "array." + name, reinterpret_cast<const char*>(bytes.data()), bytes.size());

  std::string file(kMagic);
  put(file, kVersion);
  put(file, static_cast<std::uint64_t>(payload.size()));
  file += payload;
  put(file, fnv1a(payload.data(), payload.size()));
  write_file_atomic(path, file);
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CheckpointError(where + ": cannot open the checkpoint (is this a run folder?)");
  std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t magic_len = std::strlen(kMagic);
  if (file.size() < magic_len || file.compare(0, magic_len, kMagic) != 0)
    throw CheckpointError(where + ": not a millcharge checkpoint");
  std::size_t at = magic_len;
  auto get = [&](auto& v, const char* what) {
    if (file.size() - at < sizeof v)
      throw CheckpointError(where + ": truncated (" + std::to_string(file.size()) + " bytes; ends inside the " +
                            what + ")");
    std::memcpy(&v, file.data() + at, sizeof v);
    at += sizeof v;
  };
  std::uint32_t version = 0;
  get(version, "header");
  if (version != kVersion)
    throw CheckpointError(where + ": format version " + std::to_string(version) + ", this millcharge reads " +
                          std::to_string(kVersion));
  std::uint64_t len = 0;
  get(len, "header");
  if (file.size() - at < len + sizeof(std::uint64_t))
    throw CheckpointError(where + ": truncated (" + std::to_string(file.size()) + " bytes of " +
                          std::to_string(at + len + sizeof(std::uint64_t)) + "): the write was cut short");
  const char* payload = file.data() + at;
  std::uint64_t hash = 0;
  std::memcpy(&hash, payload + len, sizeof hash);
  if (fnv1a(payload, len) != hash) throw CheckpointError(where + ": checksum mismatch: the file is damaged");
  if (file.size() != at + len + sizeof hash)
    throw CheckpointError(where + ": " + std::to_string(file.size() - (at + len + sizeof hash)) +
                          " stray bytes after the checksum");

  std::map<std::string, std::string> records;
  std::size_t p = 0;
  auto take = [&](std::size_t n) {
    if (len - p < n) throw CheckpointError(where + ": a record runs past the end of the payload");
    const std::size_t from = p;
    p += n;
    return from;
  };
  while (p < len) {
    std::uint32_t name_len = 0;
    std::memcpy(&name_len, payload + take(sizeof name_len), sizeof name_len);
    const std::string name(payload + take(name_len), name_len);
    std::uint64_t n = 0;
    std::memcpy(&n, payload + take(sizeof n), sizeof n);
    records[name] = std::string(payload + take(n), n);
  }
  auto record = [&](const std::string& name) -> const std::string& {
    const auto it = records.find(name);
    if (it == records.end()) throw CheckpointError(where + ": the record '" + name + "' is missing");
    return it->second;
  };

  Checkpoint cp;
  cp.case_name = record("case.name");
  cp.case_toml = record("case.toml");
  const ScalarReader rs(record("run"), where + ": run");
  RunState& r = cp.run;
  // Fields added after version 1 began keep their defaults in older files.
  run_fields(r, [&](const char* k, auto& v) {
    const std::string key(k);
    if (optional_run_field(key) && !rs.has(k)) return;
    rs.get(k, v);
  });
  // Older files kept one batch per whole revolution.
  if (!rs.has("batches_per_revolution")) r.batches_per_revolution = 1;
  const std::string& prof = record("run.window_profile");
  std::vector<std::int64_t> counts(prof.size() / sizeof(std::int64_t));
  std::memcpy(counts.data(), prof.data(), counts.size() * sizeof(std::int64_t));
  r.window_profile.assign(counts.begin(), counts.end());
  // Revolutions: absent from files written before the standard errors (the
  // run then goes on with the revolutions still to come).
  constexpr std::size_t kRevFields = std::size(kWindowBatchFields), kTally = std::size(kTallyFields);
  if (records.count("run.revolutions")) {
    const std::vector<double> v = bytes_doubles(records["run.revolutions"]);
    if (v.size() % kRevFields != 0) throw CheckpointError(where + ": run.revolutions has a partial revolution");
    for (std::size_t i = 0; i < v.size(); i += kRevFields) {
      WindowBatch m;
      for (std::size_t f = 0; f < kRevFields; ++f) m.*kWindowBatchFields[f] = v[i + f];
      r.batches.push_back(m);
    }
  }
  if (records.count("run.revolution")) {
    const std::vector<double> v = bytes_doubles(records["run.revolution"]);
    if (v.size() != kTally) throw CheckpointError(where + ": run.revolution has " + std::to_string(v.size()) +
                                                  " numbers, not " + std::to_string(kTally));
    for (std::size_t f = 0; f < kTally; ++f) r.batch.*kTallyFields[f] = v[f];
  }
  if (records.count("run.batch_profile")) {
    const std::string& b = records["run.batch_profile"];
    std::vector<std::int64_t> rc(b.size() / sizeof(std::int64_t));
    std::memcpy(rc.data(), b.data(), rc.size() * sizeof(std::int64_t));
    r.batch_profile.assign(rc.begin(), rc.end());
  }
  // The first half's liner books: absent from files written before them
  // (the run then has no halves).
  if (records.count("run.half_books")) r.half_books = bytes_doubles(records["run.half_books"]);

  const ScalarReader ss(record("solver"), where + ": solver");
  SolverState& s = cp.solver;
  solver_fields(s, [&](const char* k, auto& v) { ss.get(k, v); });
  for (const auto& [name, bytes] : records)
    if (name.rfind("array.", 0) == 0)
      s.arrays.emplace_back(name.substr(6), std::vector<unsigned char>(bytes.begin(), bytes.end()));
  return cp;
}

namespace {

// What changes when a file is written: its inode (a rename), size and
// modification time.
struct FileStamp {
  bool exists = false;
  ino_t inode = 0;
  off_t size = 0;
  long mtime_ns = 0;
  bool operator==(const FileStamp& o) const {
    return exists == o.exists && inode == o.inode && size == o.size && mtime_ns == o.mtime_ns;
  }
};

FileStamp stamp_of(const std::filesystem::path& path) {
  struct stat st {};
  FileStamp s;
  if (::stat(path.c_str(), &st) != 0) return s;
  s.exists = true;
  s.inode = st.st_ino;
  s.size = st.st_size;
  s.mtime_ns = static_cast<long>(st.st_mtim.tv_sec) * 1000000000L + st.st_mtim.tv_nsec;
  return s;
}

}  // namespace

Checkpoint read_complete_checkpoint(const std::filesystem::path& path, double wait_s) {
  using clock = std::chrono::steady_clock;
  const auto until = clock::now() + std::chrono::duration<double>(wait_s);
  for (;;) {
    const FileStamp before = stamp_of(path);
    try {
      return read_checkpoint(path);
    } catch (const CheckpointError&) {
      // Refused: final unless the file changed while it was read, or changes
      // still (a writer in the middle of it).
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      const FileStamp after = stamp_of(path);
      if (!before.exists || before == after || clock::now() >= until) throw;
    }
  }
}

}  // namespace mc::io
