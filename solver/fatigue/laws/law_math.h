// Internal to solver/fatigue/laws/*.cpp: small helpers of the laws' arithmetic and validation.
#pragma once

#include <cmath>
#include <limits>
#include <string>

namespace peritwin::fatigue::detail {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// base^exponent for base > 0, else 0 (a decrement of a bond without range, 000 Eq. 17-19).
inline double pow_pos(double base, double exponent) {
  return base > 0.0 ? std::pow(base, exponent) : 0.0;
}

/// Appends `text` to `msg` ("; "-separated) unless ok: the validate() messages.
inline void require(std::string& msg, bool ok, const char* text) {
  if (ok) return;
  if (!msg.empty()) msg += "; ";
  msg += text;
}

inline bool positive(double v) { return std::isfinite(v) && v > 0.0; }
inline bool non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace peritwin::fatigue::detail
