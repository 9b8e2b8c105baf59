#pragma once
// The JSON lines the command-line tools print (peritwin-bench, peritwin-bench-ingest,
// peritwin-validate), built with nlohmann-json (issue 13): ordered_json keeps the keys in the
// order they are set, strings are escaped by the library and non-finite numbers print as null.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>

namespace peritwin::core {

using JsonLine = nlohmann::ordered_json;

/// `v` rounded to `decimals` digits after the point (printf's %.Nf), as the nearest double: the
/// library prints it with those digits (its shortest round-trip form, trailing zeros dropped).
/// Non-finite values stay non-finite (printed as null).
inline double fixed(double v, int decimals) {
  if (!std::isfinite(v)) return v;
  char text[400];  // %.Nf of 1e308 has 309 digits before the point
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return std::strtod(text, nullptr);
}

/// `v` rounded to `digits` significant digits (printf's %.Ng, or %.(N-1)e), as fixed() does.
inline double significant(double v, int digits) {
  if (!std::isfinite(v)) return v;
  char text[64];
  std::snprintf(text, sizeof text, "%.*e", digits - 1, v);
  return std::strtod(text, nullptr);
}

/// A count held in a double (printf's %.0f): an integer, or null when not finite.
inline JsonLine whole(double v) {
  if (!std::isfinite(v)) return nullptr;
  return static_cast<std::int64_t>(std::llround(v));
}

/// One line on stdout. Invalid UTF-8 in strings (a path, say) is replaced, not thrown on.
inline void print_line(const JsonLine& line) {
  const std::string text = line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::printf("%s\n", text.c_str());
}

}  // namespace peritwin::core
