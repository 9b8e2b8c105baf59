// A flat table of named parameters as a fatigue law (solver/fatigue/laws) reads its configuration:
// numbers with bounds, integers, booleans, each by key, and every problem reported as an
// Error{key, reason} instead of thrown, so that a reader can go on and report every error of a file
// in one pass. The solver knows no file format: twin/config implements this interface on top of
// toml++ (with file, line and key path in its messages).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "core/expected.h"

namespace peritwin::core {

/// Shortest round-trip decimal form of a double ("0.001", "6.8e+10"), as the messages print it.
std::string format_number(double value);

enum class Bound { any, positive, non_negative };

/// Whether v satisfies `bound`.
bool satisfies(double v, Bound bound);
/// "must be > 0 (got -1)" / "must be >= 0 (got -1)": the reason of a violated bound.
std::string bound_reason(double v, Bound bound);

class ParamReader {
 public:
  virtual ~ParamReader() = default;

  /// Whether the table holds `key` (does not mark it as read).
  [[nodiscard]] virtual bool has(std::string_view key) const = 0;
  /// A required real number (integers accepted), finite; nothing after reporting it missing or of
  /// the wrong type.
  virtual std::optional<double> number(std::string_view key) = 0;
  /// An optional real number: `fallback` when absent (and after reporting a wrong type).
  virtual double number(std::string_view key, double fallback) = 0;
  virtual std::int64_t integer(std::string_view key, std::int64_t fallback) = 0;
  virtual bool boolean(std::string_view key, bool fallback) = 0;
  /// Reports an impossible value: error.field is the key (at the table when the key is absent).
  virtual void report(Error error) = 0;

  /// Reports `reason` at `key` unless ok; returns ok.
  bool check(std::string_view key, bool ok, std::string_view reason);
  /// A required number within `bound` (nothing after reporting).
  std::optional<double> required(std::string_view key, Bound bound);
  /// An optional number within `bound` (reported when outside, and returned anyway).
  double optional(std::string_view key, double fallback, Bound bound);
};

}  // namespace peritwin::core
