// A JSON file that millcharge wrote (a run's summary.json, a life study's
// life.json, a sweep's jobs.json), read back strictly. Every refusal is one
// line that names the file, the place in it and the cause, in words rather
// than the JSON library's: "RUN/summary.json: cut short after 1,204 bytes",
// "STUDY/life.json: stage 1: profiles: empty list".
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace mc::io {

// What is wrong with a JSON text, in words; "" when it parses.
std::string json_text_fault(const std::string& text);

// The file parsed. Throws std::invalid_argument naming the file: missing
// (`missing_hint` added), a folder, unreadable, empty, cut short, or not
// JSON (with the line and column where it stops being JSON).
nlohmann::json read_json_file(const std::filesystem::path& path, const std::string& missing_hint = "");

// A value in a JSON file with where it is, so that a check that fails says
// so in one line: "FILE: [part: ]key.key[i]: cause". Every accessor checks
// the value's type and throws std::invalid_argument on a wrong one.
class JsonAt {
 public:
  JsonAt(const nlohmann::json& value, const std::string& file) : v_(&value), head_(file) {}

  // A named part of the file ("stage 1"): later keys are counted from here.
  JsonAt part(const std::string& label) const;
  // The member `key` of an object (refused when missing), or whether it is there.
  JsonAt operator[](const std::string& key) const;
  bool has(const std::string& key) const;
  // Element i of an array.
  JsonAt operator[](std::size_t i) const;

  const nlohmann::json& value() const { return *v_; }
  void object() const;                // must be an object
  std::size_t size() const;           // must be an array: its length
  std::size_t size(std::size_t want, const std::string& of) const;  // an array of exactly `want` (`of`: what they count)
  double number() const;              // a finite number
  double number_at_least(double lo) const;
  double number_or_nan() const;       // a finite number, or null (NaN)
  long whole() const;                 // an integer
  bool boolean() const;
  std::string text() const;           // a string
  std::vector<double> numbers(std::size_t want, const std::string& of) const;  // finite, exactly `want`

  std::string where() const { return path_.empty() ? head_ : head_ + ": " + path_; }
  [[noreturn]] void fail(const std::string& cause) const;

 private:
  JsonAt(const nlohmann::json* v, std::string head, std::string path) : v_(v), head_(std::move(head)), path_(std::move(path)) {}
  [[noreturn]] void wrong_type(const char* want) const;
  const nlohmann::json* v_;
  std::string head_, path_;
};

}  // namespace mc::io
