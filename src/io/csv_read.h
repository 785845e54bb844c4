// A CSV file that millcharge wrote, read back strictly: the header, then
// rows of the header's width, every row ended by a newline (a file cut
// short is refused), numbers parsed whole. Every refusal names the file and
// the line: "RUN/spectra.csv:43: normal_spectrum_W: "abc" is not a number".
// For the files millcharge writes itself (spectra.csv, timeseries.csv):
// no quoting, no commas inside fields.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace mc::io {

struct CsvTable {
  std::filesystem::path path;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<long> line;  // each row's line in the file (the header is line 1)

  // The column's index; throws std::invalid_argument naming the file and
  // the column when the header lacks it (and `why`, when given).
  int column(const std::string& name, const std::string& why = "") const;
  bool has(const std::string& name) const;
  // Row r's field in column c as a finite number, else std::invalid_argument
  // naming path:line and the column.
  double number(std::size_t r, int c) const;
  // "path:line" of row r, for a caller's own message.
  std::string where(std::size_t r) const;
};

// A line's fields, split at every comma (no quoting).
std::vector<std::string> split_csv_line(const std::string& line);
// Whether `field` is a finite number written whole; its value in `x`.
bool csv_number(const std::string& field, double& x);

// Throws std::invalid_argument: a file that is missing (`missing_hint` is
// added), empty, cut (its last line has no newline), or holds a row whose
// width is not the header's.
CsvTable read_csv_strict(const std::filesystem::path& path, const std::string& missing_hint = "");

}  // namespace mc::io
