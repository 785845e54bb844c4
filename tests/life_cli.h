// Shared by the life study's command tests: stages of a short lab run,
// a scratch folder, `millcharge life` with its stderr, and its CSV files
// read strictly as named fields.
#pragma once

#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "io/csv_read.h"
#include "text_file.h"

namespace life_cli {

namespace fs = std::filesystem;

// Stages of 0.3 s of turning after 0.05 s of settling (about 17,500 steps).
inline const std::string kShort =
    " --quiet --set run.duration=0.3 --set run.settle=0.05 --set run.warmup=0.1"
    " --set run.checkpoint_interval=0.05 --set run.snapshot_interval=0";

inline fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("millcharge-life-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(p);
  return p;
}

inline int life(const std::string& args, std::string* err = nullptr) {
  const fs::path log = scratch("stderr.txt");
  const int st =
      std::system((std::string(MC_BINARY) + " life " + args + " >/dev/null 2>'" + log.string() + "'").c_str());
  if (err) *err = read_text(log);
  fs::remove(log);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

// A CSV file millcharge wrote (read strictly) as rows of named fields.
inline std::vector<std::map<std::string, std::string>> read_csv(const fs::path& p) {
  const mc::io::CsvTable t = mc::io::read_csv_strict(p);
  std::vector<std::map<std::string, std::string>> rows;
  for (const auto& f : t.rows) {
    std::map<std::string, std::string> r;
    for (std::size_t k = 0; k < t.header.size(); ++k) r[t.header[k]] = f[k];
    rows.push_back(r);
  }
  return rows;
}

inline double num(const std::map<std::string, std::string>& r, const std::string& key) {
  const auto it = r.find(key);
  REQUIRE(it != r.end());
  return std::stod(it->second);
}

}  // namespace life_cli
