// Reads back the JSON files millcharge wrote (json_read.h).
#include "io/json_read.h"

#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

namespace mc::io {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string thousands(std::size_t v) {
  std::string s = std::to_string(v);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3) s.insert(i, ",");
  return s;
}

// A value as a short text for a message: its type, and the value itself
// where it is a short scalar.
std::string shown(const json& v) {
  if (v.is_object()) return "an object";
  if (v.is_array()) return "a list";
  if (v.is_null()) return "null";
  std::string s = v.dump();
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  const char* kind = v.is_string() ? "a string" : v.is_boolean() ? "a boolean" : "a number";
  return std::string(kind) + ", " + s;
}

}  // namespace

std::string json_text_fault(const std::string& text) {
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) return "empty";
  try {
    const json parsed = json::parse(text);
    (void)parsed;
    return "";
  } catch (const json::parse_error& e) {
    // e.byte counts from 1; one past the last byte is the end of the text.
    if (e.byte > text.size()) return "cut short after " + thousands(text.size()) + " bytes";
    const std::size_t at = e.byte > 0 ? e.byte - 1 : 0;
    long line = 1, column = 1;
    for (std::size_t k = 0; k < at; ++k) text[k] == '\n' ? (++line, column = 1) : ++column;
    return "not valid JSON at line " + std::to_string(line) + ", column " + std::to_string(column);
  } catch (const json::exception&) {
    return "not valid JSON";
  }
}

json read_json_file(const fs::path& path, const std::string& missing_hint) {
  std::error_code ec;
  const std::string name = path.string();
  if (!fs::exists(path, ec))
    throw std::invalid_argument(name + ": missing" + (missing_hint.empty() ? "" : "; " + missing_hint));
  if (fs::is_directory(path, ec)) throw std::invalid_argument(name + ": is a folder, not a file");
  std::ifstream in(path, std::ios::binary);
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (!in && !in.eof()) throw std::invalid_argument(name + ": cannot be read");
  const std::string fault = json_text_fault(text);
  if (!fault.empty()) throw std::invalid_argument(name + ": " + fault + "; the file is damaged");
  return json::parse(text);
}

void JsonAt::fail(const std::string& cause) const { throw std::invalid_argument(where() + ": " + cause); }

void JsonAt::wrong_type(const char* want) const { fail(std::string("expected ") + want + ", found " + shown(*v_)); }

JsonAt JsonAt::part(const std::string& label) const { return JsonAt(v_, where() + ": " + label, ""); }

JsonAt JsonAt::operator[](const std::string& key) const {
  object();
  const std::string path = path_.empty() ? key : path_ + "." + key;
  const auto it = v_->find(key);
  if (it == v_->end()) JsonAt(v_, head_, path).fail("missing");
  return JsonAt(&*it, head_, path);
}

bool JsonAt::has(const std::string& key) const {
  object();
  return v_->contains(key);
}

JsonAt JsonAt::operator[](std::size_t i) const {
  const std::size_t n = size();
  const std::string path = path_ + "[" + std::to_string(i) + "]";
  if (i >= n) JsonAt(v_, head_, path).fail("missing (the list has " + std::to_string(n) + ")");
  return JsonAt(&(*v_)[i], head_, path);
}

void JsonAt::object() const {
  if (!v_->is_object()) wrong_type("an object");
}

std::size_t JsonAt::size() const {
  if (!v_->is_array()) wrong_type("a list");
  return v_->size();
}

std::size_t JsonAt::size(std::size_t want, const std::string& of) const {
  const std::size_t n = size();
  if (n == 0 && want > 0) fail("empty list");
  if (n != want) fail(std::to_string(n) + " entries, where " + std::to_string(want) + " " + of + " are due");
  return n;
}

double JsonAt::number() const {
  if (!v_->is_number()) wrong_type("a number");
  const double x = v_->get<double>();
  if (!std::isfinite(x)) fail("not a finite number");
  return x;
}

double JsonAt::number_at_least(double lo) const {
  const double x = number();
  if (!(x >= lo)) {
    std::ostringstream s;
    s << "must be >= " << lo << ", found " << x;
    fail(s.str());
  }
  return x;
}

double JsonAt::number_or_nan() const { return v_->is_null() ? NAN : number(); }

long JsonAt::whole() const {
  if (!v_->is_number_integer()) wrong_type("a whole number");
  return v_->get<long>();
}

bool JsonAt::boolean() const {
  if (!v_->is_boolean()) wrong_type("true or false");
  return v_->get<bool>();
}

std::string JsonAt::text() const {
  if (!v_->is_string()) wrong_type("a string");
  return v_->get<std::string>();
}

std::vector<double> JsonAt::numbers(std::size_t want, const std::string& of) const {
  const std::size_t n = size(want, of);
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = (*this)[i].number();
  return out;
}

}  // namespace mc::io
