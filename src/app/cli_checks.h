// Checks of numeric command-line options whose messages say what is
// wanted, in the option's unit: "--feed-rate: must be > 0 t/h, got 0".
// (CLI11's own range checks print their bounds' numeric limits in full.)
// CLI11 runs a check on the option's text before converting it, so these
// also refuse what is not a number, or not a whole one where a count is
// wanted, by the same words.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

namespace mc::app::cli {

namespace detail {

inline std::string with_unit(const std::string& unit) { return unit.empty() ? "" : " " + unit; }

// The text as a finite number, or false.
inline bool number(const std::string& text, double& x) {
  if (text.empty()) return false;
  char* end = nullptr;
  x = std::strtod(text.c_str(), &end);
  return end && *end == '\0' && std::isfinite(x);
}

inline std::string quoted(const std::string& text) { return "\"" + text + "\""; }

inline std::string shown(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

}  // namespace detail

// A number > 0 (a rate, a size, a time).
inline CLI::Validator positive(const std::string& unit = "") {
  return CLI::Validator(
      [unit](std::string& text) -> std::string {
        double x = 0;
        if (!detail::number(text, x)) return "must be a number > 0" + detail::with_unit(unit) + ", got " + detail::quoted(text);
        if (!(x > 0)) return "must be > 0" + detail::with_unit(unit) + ", got " + text;
        return "";
      },
      "> 0" + detail::with_unit(unit));
}

// A number >= 0.
inline CLI::Validator non_negative(const std::string& unit = "") {
  return CLI::Validator(
      [unit](std::string& text) -> std::string {
        double x = 0;
        if (!detail::number(text, x)) return "must be a number >= 0" + detail::with_unit(unit) + ", got " + detail::quoted(text);
        if (!(x >= 0)) return "must be >= 0" + detail::with_unit(unit) + ", got " + text;
        return "";
      },
      ">= 0" + detail::with_unit(unit));
}

// A number from lo to hi, both included.
inline CLI::Validator between(double lo, double hi, const std::string& unit = "") {
  const std::string range = "from " + detail::shown(lo) + " to " + detail::shown(hi) + detail::with_unit(unit);
  return CLI::Validator(
      [range, lo, hi](std::string& text) -> std::string {
        double x = 0;
        if (!detail::number(text, x)) return "must be a number " + range + ", got " + detail::quoted(text);
        if (!(x >= lo && x <= hi)) return "must be " + range + ", got " + text;
        return "";
      },
      range);
}

// A whole number from lo to hi, both included (a count).
inline CLI::Validator count(long lo, long hi, const std::string& unit = "") {
  const std::string range = "a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) + detail::with_unit(unit);
  return CLI::Validator(
      [range, lo, hi](std::string& text) -> std::string {
        double x = 0;
        if (!detail::number(text, x) || x != std::floor(x)) return "must be " + range + ", got " + detail::quoted(text);
        if (!(x >= lo && x <= hi)) return "must be " + range + ", got " + text;
        return "";
      },
      range);
}

// A whole number >= lo, with no upper bound but the type's (a count).
inline CLI::Validator count_from(long lo, const std::string& unit = "") {
  const std::string range = "a whole number >= " + std::to_string(lo) + detail::with_unit(unit);
  return CLI::Validator(
      [range, lo](std::string& text) -> std::string {
        double x = 0;
        if (!detail::number(text, x) || x != std::floor(x) || x > 9.2e18) return "must be " + range + ", got " + detail::quoted(text);
        if (!(x >= lo)) return "must be " + range + ", got " + text;
        return "";
      },
      range);
}

}  // namespace mc::app::cli
