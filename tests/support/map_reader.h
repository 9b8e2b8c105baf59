// A core::ParamReader over a map of numbers that collects its errors as Error{key, reason}: the
// fatigue laws' read_* functions tested without toml++ (the config implements the same interface).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/param_reader.h"

namespace peritwin::testing {

/// A ParamReader over a map of numbers that collects its errors as Error{key, reason}.
class MapReader final : public core::ParamReader {
 public:
  explicit MapReader(std::map<std::string, double> values) : values_(std::move(values)) {}
  [[nodiscard]] bool has(std::string_view key) const override {
    return values_.contains(std::string(key));
  }
  std::optional<double> number(std::string_view key) override {
    if (has(key)) return values_.at(std::string(key));
    errors.push_back({std::string(key), "missing"});
    return std::nullopt;
  }
  double number(std::string_view key, double fallback) override {
    return has(key) ? values_.at(std::string(key)) : fallback;
  }
  std::int64_t integer(std::string_view key, std::int64_t fallback) override {
    return has(key) ? static_cast<std::int64_t>(values_.at(std::string(key))) : fallback;
  }
  bool boolean(std::string_view key, bool fallback) override {
    return has(key) ? values_.at(std::string(key)) != 0.0 : fallback;
  }
  void report(core::Error error) override { errors.push_back(std::move(error)); }
  std::vector<core::Error> errors;

 private:
  std::map<std::string, double> values_;
};

}  // namespace peritwin::testing
