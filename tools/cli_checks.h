// Command-line checks shared by the programs. CLI11's Range and PositiveNumber compare with < and
// <=, which NaN passes ("--dx nan" reached the discretization and threw length_error), so every
// floating-point option goes through one of these.
#pragma once

#include <CLI/CLI.hpp>
#include <cmath>
#include <sstream>
#include <string>

namespace peritwin::cli {

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
        if (!CLI::detail::lexical_cast(text, v)) return "not a number: " + text;
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
        if (!CLI::detail::lexical_cast(text, v)) return "not a number: " + text;
        if (!std::isfinite(v) || v <= 0.0) return "not a finite positive number: " + text;
        return {};
      },
      "POSITIVE");
}

}  // namespace peritwin::cli
