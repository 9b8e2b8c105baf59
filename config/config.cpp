// The public entry points of config/config.h and the table reader of
// config/config_toml.h; the sections of the schema are read in config_parse.cpp.
#include "config/config.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <system_error>

#include "config/config_toml.h"
#include "core/toml_text.h"
#include "messages/batch.h"

namespace peritwin::config {

namespace config_internal {

std::string format_count(double value) {
  if (!std::isfinite(value)) return "unbounded";
  if (value < 1e6) return std::to_string(static_cast<long long>(std::llround(value)));
  std::array<char, 32> buffer{};
  std::snprintf(buffer.data(), buffer.size(), "%.3g", value);
  return buffer.data();
}

std::string_view type_name(toml::node_type type) {
  switch (type) {
    case toml::node_type::none:
      return "nothing";
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a floating-point number";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
  }
  return "an unknown type";
}

void Context::error(const toml::source_region& where, std::string path, std::string reason) {
  errors.push_back(
      {file, where.begin.line, where.begin.column, std::move(path), std::move(reason)});
}

SourceRef Context::ref(const toml::node& node, std::string path) const {
  return {file, node.source().begin.line, node.source().begin.column, std::move(path)};
}

TableReader::TableReader(Context& ctx, const toml::table& table, std::string path)
    : ctx_(ctx), table_(table), path_(std::move(path)) {}

std::string TableReader::path_of(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

const toml::node* TableReader::node(std::string_view key, bool required) {
  if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.emplace_back(key);
  const toml::node* n = table_.get(key);
  if (n == nullptr && required) {
    ctx_.error(table_.source(), path_of(key), "missing required key \"" + std::string(key) + "\"");
  }
  return n;
}

namespace {
void wrong_type(Context& ctx, const toml::node& n, std::string path, std::string_view expected) {
  ctx.error(n.source(), std::move(path),
            "expected " + std::string(expected) + ", got " + std::string(type_name(n.type())));
}

std::optional<double> as_number(Context& ctx, const toml::node& n, const std::string& path) {
  if (const auto* i = n.as_integer()) return static_cast<double>(i->get());
  if (const auto* f = n.as_floating_point()) {
    if (std::isfinite(f->get())) return f->get();
    ctx.error(n.source(), path, "must be a finite number");
    return std::nullopt;
  }
  wrong_type(ctx, n, path, "a number");
  return std::nullopt;
}
}  // namespace

std::optional<double> TableReader::number(std::string_view key) {
  const toml::node* n = node(key, true);
  return n == nullptr ? std::nullopt : as_number(ctx_, *n, path_of(key));
}

double TableReader::number(std::string_view key, double fallback) {
  const toml::node* n = node(key, false);
  return n == nullptr ? fallback : as_number(ctx_, *n, path_of(key)).value_or(fallback);
}

std::optional<std::int64_t> TableReader::integer(std::string_view key) {
  const toml::node* n = node(key, true);
  if (n == nullptr) return std::nullopt;
  if (const auto* i = n->as_integer()) return i->get();
  wrong_type(ctx_, *n, path_of(key), "an integer");
  return std::nullopt;
}

std::int64_t TableReader::integer(std::string_view key, std::int64_t fallback) {
  return has(key) ? integer(key).value_or(fallback) : (node(key, false), fallback);
}

bool TableReader::boolean(std::string_view key, bool fallback) {
  const toml::node* n = node(key, false);
  if (n == nullptr) return fallback;
  if (const auto* b = n->as_boolean()) return b->get();
  wrong_type(ctx_, *n, path_of(key), "a boolean (true or false)");
  return fallback;
}

std::optional<std::string> TableReader::string(std::string_view key) {
  const toml::node* n = node(key, true);
  if (n == nullptr) return std::nullopt;
  if (const auto* s = n->as_string()) return s->get();
  wrong_type(ctx_, *n, path_of(key), "a string");
  return std::nullopt;
}

std::string TableReader::string(std::string_view key, std::string fallback) {
  return has(key) ? string(key).value_or(std::move(fallback)) : (node(key, false), fallback);
}

std::optional<mesh::Point> point_of(Context& ctx, const toml::node& n, const std::string& path) {
  const toml::array* a = n.as_array();
  if (a == nullptr) {
    wrong_type(ctx, n, path, "an array [x, y]");
    return std::nullopt;
  }
  if (a->size() != 2) {
    ctx.error(
        n.source(), path,
        "expected an array [x, y] of 2 numbers, got " + std::to_string(a->size()) + " elements");
    return std::nullopt;
  }
  const auto x = as_number(ctx, (*a)[0], path + "[0]");
  const auto y = as_number(ctx, (*a)[1], path + "[1]");
  if (!x || !y) return std::nullopt;
  return mesh::Point{*x, *y};
}

std::optional<mesh::Point> TableReader::point(std::string_view key) {
  const toml::node* n = node(key, true);
  if (n == nullptr) return std::nullopt;
  return point_of(ctx_, *n, path_of(key));
}

mesh::Point TableReader::point(std::string_view key, mesh::Point fallback) {
  return has(key) ? point(key).value_or(fallback) : (node(key, false), fallback);
}

const toml::table* TableReader::table(std::string_view key, bool required) {
  const toml::node* n = node(key, required);
  if (n == nullptr) return nullptr;
  if (const auto* t = n->as_table()) return t;
  wrong_type(ctx_, *n, path_of(key), "a table");
  return nullptr;
}

const toml::array* TableReader::array(std::string_view key, bool required) {
  const toml::node* n = node(key, required);
  if (n == nullptr) return nullptr;
  if (const auto* a = n->as_array()) return a;
  wrong_type(ctx_, *n, path_of(key), "an array");
  return nullptr;
}

void TableReader::invalid(std::string_view key, std::string reason) {
  const toml::node* n = table_.get(key);
  ctx_.error(n != nullptr ? n->source() : table_.source(), path_of(key), std::move(reason));
}

bool TableReader::check(std::string_view key, bool ok, std::string_view reason) {
  if (!ok) invalid(key, std::string(reason));
  return ok;
}

void TableReader::error(std::string reason) {
  ctx_.error(table_.source(), path_, std::move(reason));
}

void TableReader::finish() {
  std::string names;
  for (const auto& k : known_) names += (names.empty() ? "" : ", ") + k;
  for (const auto& [key, value] : table_) {
    if (std::find(known_.begin(), known_.end(), key.str()) != known_.end()) continue;
    ctx_.error(key.source(), path_of(key.str()),
               "unknown key \"" + std::string(key.str()) + "\" (known here: " + names + ")");
  }
}

}  // namespace config_internal

namespace {}  // namespace

std::string ConfigError::message() const {
  std::string m;
  core::append_one_line(m, file);
  if (line > 0) {
    m += ':';
    m += std::to_string(line);
    if (column > 0) {
      m += ':';
      m += std::to_string(column);
    }
  }
  if (!path.empty()) {
    m += ": ";
    core::append_one_line(m, path);
  }
  m += ": ";
  core::append_one_line(m, reason);
  return m;
}

std::string ConfigResult::error_text() const {
  std::string text;
  for (const auto& e : errors) text += e.message() + "\n";
  return text;
}

bool is_valid_source_id(std::string_view id) {
  // messages/batch.cpp's rule for load_batch_t.source_id (check_batch).
  if (id.empty() || id.size() > messages::kMaxSourceIdLength) return false;
  return std::all_of(id.begin(), id.end(), [](char c) { return c >= 0x21 && c <= 0x7e; });
}

std::uint64_t default_memory_limit() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page_size = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page_size <= 0) return std::uint64_t{8} << 30U;
  const auto physical = static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size);
  return physical / 4 * 3;
}

std::optional<std::uint64_t> parse_byte_size(std::string_view text) {
  std::uint64_t value = 0;
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  const auto [stop, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc{} || stop == begin) return std::nullopt;
  std::string suffix(stop, end);
  std::transform(suffix.begin(), suffix.end(), suffix.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  unsigned shift = 0;
  if (!suffix.empty() && suffix != "B") {
    const std::string_view units = "KMGT";
    const auto unit = units.find(suffix.front());
    const std::string_view rest = std::string_view(suffix).substr(1);
    if (unit == std::string_view::npos || !(rest.empty() || rest == "B" || rest == "IB")) {
      return std::nullopt;
    }
    shift = 10U * static_cast<unsigned>(unit + 1);
  }
  if (value == 0 || value > (std::numeric_limits<std::uint64_t>::max() >> shift)) {
    return std::nullopt;
  }
  return value << shift;
}

std::string format_bytes(double bytes) {
  if (!std::isfinite(bytes)) return "an unbounded amount";
  if (bytes < 1024.0) return std::to_string(static_cast<long long>(std::llround(bytes))) + " B";
  const char* units[] = {"KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double v = bytes / 1024.0;
  std::size_t u = 0;
  while (v >= 1024.0 && u + 1 < std::size(units)) {
    v /= 1024.0;
    ++u;
  }
  std::array<char, 48> buffer{};
  std::snprintf(buffer.data(), buffer.size(), "%.3g %s", v, units[u]);
  return buffer.data();
}

ConfigResult parse_config(std::string_view text, std::string_view file_name,
                          const ConfigLimits& limits) {
  ConfigResult result;
  const std::string file(file_name);
  if (const auto bad = core::find_unsafe_toml_character(text)) {
    result.errors.push_back(
        {file, bad->line, bad->column, "", "TOML syntax error: non-ASCII character " + bad->where});
    return result;
  }
  try {
    const toml::table root = toml::parse(text, file_name);
    config_internal::Context ctx{file, {}};
    ctx.default_memory_limit = limits.max_memory_bytes == 0;
    ctx.max_memory_bytes =
        ctx.default_memory_limit ? default_memory_limit() : limits.max_memory_bytes;
    ctx.served_details = limits.served_details;
    ctx.concurrent_life_estimates = limits.concurrent_life_estimates;
    TwinConfig config = config_internal::parse_document(ctx, root);
    std::stable_sort(ctx.errors.begin(), ctx.errors.end(), [](const auto& a, const auto& b) {
      return a.line != b.line ? a.line < b.line : a.column < b.column;
    });
    if (ctx.errors.empty()) {
      result.config = std::move(config);
    } else {
      result.errors = std::move(ctx.errors);
    }
  } catch (const toml::parse_error& e) {
    result.errors.push_back({file, e.source().begin.line, e.source().begin.column, "",
                             "TOML syntax error: " + std::string(e.description())});
  } catch (const std::exception& e) {
    result.errors.push_back({file, 0, 0, "", std::string("internal error: ") + e.what()});
  } catch (...) {
    result.errors.push_back({file, 0, 0, "", "internal error"});
  }
  return result;
}

const DetailConfig* select_detail(const TwinConfig& config, std::string_view id) {
  if (id.empty()) return config.details.empty() ? nullptr : &config.details.front();
  for (const auto& d : config.details) {
    if (d.id == id) return &d;
  }
  return nullptr;
}

ConfigResult load_config(const std::string& file, const ConfigLimits& limits) {
  const auto failure = [&file](std::string reason) {
    ConfigResult result;
    result.errors.push_back({file, 0, 0, "", "cannot read the file: " + reason});
    return result;
  };
  try {
    std::error_code ec;
    if (std::filesystem::is_directory(file, ec)) return failure("it is a directory");
    errno = 0;
    std::ifstream in(file, std::ios::binary);
    if (!in) return failure(std::error_code(errno, std::generic_category()).message());
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) return failure("read error");
    return parse_config(text.str(), file, limits);
  } catch (...) {
    return failure("unexpected error");
  }
}

namespace {
std::vector<mesh::NodeIndex> select_nodes(const NodeSelector& target,
                                          const mesh::Discretization& disc) {
  if (target.kind == NodeSelector::Kind::region) return disc.nodes_in(target.region);
  const mesh::NodeIndex k = disc.nearest_node(target.point);
  return k < 0 ? std::vector<mesh::NodeIndex>{} : std::vector<mesh::NodeIndex>{k};
}

ConfigError no_nodes(const SourceRef& where, const NodeSelector& target, double dx) {
  const char* what = target.kind == NodeSelector::Kind::region ? "region" : "point";
  return {
      where.file, where.line, where.column, where.path,
      std::string("the ") + what + " selects no node at dx = " + core::format_number(dx) + " m"};
}
}  // namespace

ResolvedBoundary resolve(const DetailConfig& detail, const mesh::Discretization& disc) {
  ResolvedBoundary out;
  for (const auto& s : detail.supports) {
    std::vector<mesh::NodeIndex> nodes = select_nodes(s.target, disc);
    if (nodes.empty()) {
      out.errors.push_back(no_nodes(s.where, s.target, disc.dx));
      continue;
    }
    out.supports.push_back({std::move(nodes), s.fix_x, s.fix_y});
  }
  for (const auto& l : detail.loads) {
    std::vector<mesh::NodeIndex> nodes = select_nodes(l.target, disc);
    if (nodes.empty()) {
      out.errors.push_back(no_nodes(l.where, l.target, disc.dx));
      continue;
    }
    out.loads.push_back({std::move(nodes), l.constant, l.per_cos, l.per_sin});
  }
  return out;
}

mesh::Discretization discretize(const DetailConfig& detail) {
  return mesh::discretize(detail.geometry, detail.dx, detail.horizon());
}

}  // namespace peritwin::config
