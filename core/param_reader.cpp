// The bounds and helpers of ParamReader (param_reader.h).
#include "core/param_reader.h"

#include <array>
#include <charconv>
#include <system_error>

namespace peritwin::core {

std::string format_number(double value) {
  std::array<char, 64> buffer{};
  const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return ec == std::errc{} ? std::string(buffer.data(), end) : std::string("?");
}

bool satisfies(double v, Bound bound) {
  return bound == Bound::any || (bound == Bound::positive ? v > 0 : v >= 0);
}

std::string bound_reason(double v, Bound bound) {
  return std::string(bound == Bound::positive ? "must be > 0" : "must be >= 0") + " (got " +
         format_number(v) + ")";
}

bool ParamReader::check(std::string_view key, bool ok, std::string_view reason) {
  if (!ok) report(Error{std::string(key), std::string(reason)});
  return ok;
}

std::optional<double> ParamReader::required(std::string_view key, Bound bound) {
  const std::optional<double> v = number(key);
  if (v && !check(key, satisfies(*v, bound), bound_reason(*v, bound))) return std::nullopt;
  return v;
}

double ParamReader::optional(std::string_view key, double fallback, Bound bound) {
  const double v = number(key, fallback);
  check(key, satisfies(v, bound), bound_reason(v, bound));
  return v;
}

}  // namespace peritwin::core
