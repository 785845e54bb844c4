// Laboratory batch grinding test files for `millcharge grind --fit` (TOML,
// docs/grinding-fit.md documents the keys): read and validated to a
// grind::BatchTest. Every error names the file, the line and the key, e.g.
//   test.toml:14: product[3].time_min: 2 does not follow 4: times must ascend
// and unknown keys are errors. Writing one back (a synthetic test made
// from a known ore) gives a file this reader takes.
#pragma once

#include <filesystem>
#include <string>

#include "grind/fit.h"

namespace mc::io {

struct BatchTestFile {
  grind::BatchTest test;
  std::string title, mill;  // free text: what was ground, in which mill
  std::string run;          // the run of the test's mill, relative to the file ("": the RUN argument)
};

BatchTestFile read_batch_test(const std::filesystem::path& path);

// The test as TOML text (sizes in mm, passing to 8 digits).
std::string batch_test_toml(const BatchTestFile& t);

}  // namespace mc::io
