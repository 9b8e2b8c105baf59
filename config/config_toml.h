// Internal to twin/config*.cpp: reading toml++ tables with error collection. Every getter records
// its key as known (so finish() can report the unknown ones), reports a wrong type or a missing
// required key with file, line, column and key path, and returns nothing in that case; the caller
// goes on reading so that every error of the file is found in one pass.
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "config/config.h"
#include "core/param_reader.h"

namespace peritwin::config::config_internal {

/// A count for people: exact below 10^6 ("49902"), else 3 digits ("1.41e+11").
std::string format_count(double value);

struct Context {
  std::string file;
  std::vector<ConfigError> errors;
  /// The most memory all details together may need (bytes, ConfigLimits resolved); 0 = unbounded.
  std::uint64_t max_memory_bytes = 0;
  bool default_memory_limit = false;  ///< max_memory_bytes is default_memory_limit()
  /// ConfigLimits::served_details (empty: every detail is served).
  std::vector<std::string> served_details{};
  int concurrent_life_estimates = 0;  ///< ConfigLimits::concurrent_life_estimates
  void error(const toml::source_region& where, std::string path, std::string reason);
  [[nodiscard]] SourceRef ref(const toml::node& node, std::string path) const;
};

/// [x, y] of two real numbers at `path` (errors reported).
std::optional<mesh::Point> point_of(Context& ctx, const toml::node& n, const std::string& path);

class TableReader {
 public:
  TableReader(Context& ctx, const toml::table& table, std::string path);

  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] std::string path_of(std::string_view key) const;
  [[nodiscard]] const toml::table& table() const { return table_; }
  [[nodiscard]] bool has(std::string_view key) const { return table_.contains(key); }
  [[nodiscard]] Context& context() const { return ctx_; }

  /// Any node (marks the key known; reports it missing when required).
  const toml::node* node(std::string_view key, bool required);
  /// A real number (integers accepted), finite.
  std::optional<double> number(std::string_view key);                 // required
  double number(std::string_view key, double fallback);               // optional
  std::optional<std::int64_t> integer(std::string_view key);          // required
  std::int64_t integer(std::string_view key, std::int64_t fallback);  // optional
  bool boolean(std::string_view key, bool fallback);
  std::optional<std::string> string(std::string_view key);  // required
  std::string string(std::string_view key, std::string fallback);
  /// [x, y] of two real numbers.
  std::optional<mesh::Point> point(std::string_view key);  // required
  mesh::Point point(std::string_view key, mesh::Point fallback);
  const toml::table* table(std::string_view key, bool required);
  const toml::array* array(std::string_view key, bool required);

  /// One of the named choices; nothing (after reporting) when the string is not one of them.
  template <typename E>
  std::optional<E> choice(std::string_view key,
                          std::initializer_list<std::pair<std::string_view, E>> choices,
                          std::optional<E> fallback) {
    return choice(key,
                  std::span<const std::pair<std::string_view, E>>(choices.begin(), choices.size()),
                  fallback);
  }
  template <typename E>
  std::optional<E> choice(std::string_view key,
                          std::span<const std::pair<std::string_view, E>> choices,
                          std::optional<E> fallback) {
    if (fallback && !has(key)) {
      node(key, false);  // marks the key known
      return fallback;
    }
    const std::optional<std::string> text = string(key);
    if (!text) return std::nullopt;
    std::string names;
    for (const auto& [name, value] : choices) {
      if (name == *text) return value;
      names += (names.empty() ? "\"" : ", \"") + std::string(name) + "\"";
    }
    invalid(key, "\"" + *text + "\" is not one of " + names);
    return std::nullopt;
  }

  /// Reports an impossible value at the key's node (at the table when the key is absent).
  void invalid(std::string_view key, std::string reason);
  /// Reports `reason` unless ok; returns ok.
  bool check(std::string_view key, bool ok, std::string_view reason);
  /// Reports an error about the table itself.
  void error(std::string reason);
  /// Reports every key of the table that no getter asked for.
  void finish();

 private:
  Context& ctx_;
  const toml::table& table_;
  std::string path_;
  std::vector<std::string> known_;
};

/// The ParamReader of a TableReader (core/param_reader.h): what a fatigue law's reader
/// (solver/fatigue/laws/) reports lands in the context with file, line and key path.
class TomlParamReader final : public core::ParamReader {
 public:
  explicit TomlParamReader(TableReader& r) : r_(r) {}
  [[nodiscard]] bool has(std::string_view key) const override { return r_.has(key); }
  std::optional<double> number(std::string_view key) override { return r_.number(key); }
  double number(std::string_view key, double fallback) override { return r_.number(key, fallback); }
  std::int64_t integer(std::string_view key, std::int64_t fallback) override {
    return r_.integer(key, fallback);
  }
  bool boolean(std::string_view key, bool fallback) override { return r_.boolean(key, fallback); }
  void report(core::Error error) override { r_.invalid(error.field, std::move(error.reason)); }

 private:
  TableReader& r_;
};

/// Human name of a TOML node type ("string", "integer", "table", ...).
std::string_view type_name(toml::node_type type);

/// The whole document (defined in config_parse.cpp).
TwinConfig parse_document(Context& ctx, const toml::table& root);

}  // namespace peritwin::config::config_internal
