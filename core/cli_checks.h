// Command-line checks shared by the programs. CLI11's Range and PositiveNumber compare with < and
// <=, which NaN passes ("--dx nan" reached the discretization and threw length_error), so every
// floating-point option goes through one of these.
#pragma once

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>

namespace peritwin::core {

/// The option's text as a double; false unless all of it is a number (NaN and inf included).
inline bool parse_double(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size();
}

/// Shortest round-trip form: 1e-05, 0.01, 89.999.
inline std::string shortest(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

/// A finite number in [lo, hi].
inline CLI::Validator finite_in(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        double v = 0.0;
        if (!parse_double(text, v)) return "not a number: " + text;
        if (!std::isfinite(v)) return "not a finite number: " + text;
        if (v < lo || v > hi) {
          return "value " + text + " not in range " + shortest(lo) + " to " + shortest(hi);
        }
        return {};
      },
      "FLOAT in [" + shortest(lo) + " - " + shortest(hi) + "]");
}

/// A finite number > 0.
inline CLI::Validator finite_positive() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0.0;
        if (!parse_double(text, v)) return "not a number: " + text;
        if (!std::isfinite(v) || v <= 0.0) return "not a finite positive number: " + text;
        return {};
      },
      "POSITIVE");
}

}  // namespace peritwin::core
