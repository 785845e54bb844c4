#include "io/csv_read.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

namespace mc::io {

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> f;
  std::size_t from = 0;
  for (;;) {
    const std::size_t comma = line.find(',', from);
    f.push_back(line.substr(from, comma == std::string::npos ? std::string::npos : comma - from));
    if (comma == std::string::npos) break;
    from = comma + 1;
  }
  return f;
}

bool csv_number(const std::string& field, double& x) {
  if (field.empty()) return false;
  char* end = nullptr;
  x = std::strtod(field.c_str(), &end);
  return *end == '\0' && std::isfinite(x);
}

int CsvTable::column(const std::string& name, const std::string& why) const {
  for (std::size_t k = 0; k < header.size(); ++k)
    if (header[k] == name) return static_cast<int>(k);
  throw std::invalid_argument(path.string() + ":1: no column " + name + (why.empty() ? "" : "; " + why));
}

bool CsvTable::has(const std::string& name) const {
  for (const std::string& h : header)
    if (h == name) return true;
  return false;
}

std::string CsvTable::where(std::size_t r) const { return path.string() + ":" + std::to_string(line.at(r)); }

double CsvTable::number(std::size_t r, int c) const {
  const std::string& text = rows.at(r).at(static_cast<std::size_t>(c));
  double x = 0;
  if (!csv_number(text, x))
    throw std::invalid_argument(where(r) + ": " + header[static_cast<std::size_t>(c)] + ": \"" + text +
                                "\" is not a number; the file is damaged (run again, or resume the run)");
  return x;
}

CsvTable read_csv_strict(const std::filesystem::path& path, const std::string& missing_hint) {
  CsvTable t;
  t.path = path;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path.string() + ": missing" + (missing_hint.empty() ? "" : "; " + missing_hint));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.empty()) throw std::invalid_argument(path.string() + ": empty; the file is damaged");
  std::size_t from = 0;
  long number = 0;
  while (from < text.size()) {
    const std::size_t nl = text.find('\n', from);
    ++number;
    if (nl == std::string::npos)
      throw std::invalid_argument(path.string() + ":" + std::to_string(number) +
                                  ": the last line ends without a newline: the file was cut short");
    std::string line = text.substr(from, nl - from);
    from = nl + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (number == 1) {
      t.header = split_csv_line(line);
      continue;
    }
    std::vector<std::string> f = split_csv_line(line);
    if (f.size() != t.header.size())
      throw std::invalid_argument(path.string() + ":" + std::to_string(number) + ": " + std::to_string(f.size()) +
                                  " fields, the header has " + std::to_string(t.header.size()) +
                                  "; the file is damaged");
    t.rows.push_back(std::move(f));
    t.line.push_back(number);
  }
  return t;
}

}  // namespace mc::io
