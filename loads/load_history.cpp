#include "loads/load_history.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <system_error>

namespace peritwin::loads {

namespace {

namespace fs = std::filesystem;

constexpr std::string_view kSeriesHeader = "time_s,load_N";
constexpr std::string_view kSeriesAngleHeader = "time_s,load_N,angle_rad";
constexpr std::string_view kBlockHeader = "p_max_N,r,angle_rad,count";

std::string_view trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

// Concatenation by appending (avoids GCC 12's false -Wrestrict on "literal" + std::string).
std::string cat(std::initializer_list<std::string_view> parts) {
  std::string out;
  for (std::string_view part : parts) out += part;
  return out;
}

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  while (true) {
    const std::size_t comma = line.find(',');
    fields.push_back(trim(line.substr(0, comma)));
    if (comma == std::string_view::npos) break;
    line.remove_prefix(comma + 1);
  }
  return fields;
}

std::string join(const std::vector<std::string_view>& fields) {
  std::string out;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i > 0) out += ',';
    out += fields[i];
  }
  return out;
}

// A double spanning the whole field, finite unless `allow_nonfinite` ("nan", "inf", "-inf",
// "infinity"), or the reason why not.
std::variant<double, std::string> parse_number(std::string_view field, std::string_view name,
                                               bool allow_nonfinite = false) {
  if (field.empty()) return cat({"empty field '", name, "'"});
  double value = 0.0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (ec == std::errc::result_out_of_range) {
    return cat({"value '", field, "' of '", name, "' is out of range"});
  }
  if (ec != std::errc() || end != field.data() + field.size()) {
    return cat({"malformed number '", field, "' in '", name, "'"});
  }
  if (!std::isfinite(value) && !allow_nonfinite) {
    return cat({"non-finite value '", field, "' in '", name, "'"});
  }
  return value;
}

// An integer >= 1 written with digits only, or the reason why not.
std::variant<std::int64_t, std::string> parse_count(std::string_view field, std::string_view name) {
  const std::string why = cat({"'", name, "' must be an integer >= 1, got '", field, "'"});
  if (field.empty() || field.find_first_not_of("0123456789") != std::string_view::npos) return why;
  std::int64_t value = 0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (ec == std::errc::result_out_of_range) return cat({"'", name, "' is out of range"});
  if (ec != std::errc() || end != field.data() + field.size() || value < 1) return why;
  return value;
}

// "# repeat ..." (the word followed by a blank or the end of the line) -> the text after "repeat".
std::optional<std::string_view> repeat_directive(std::string_view line) {
  line = trim(line);
  if (line.empty() || line.front() != '#') return std::nullopt;
  line = trim(line.substr(1));
  constexpr std::string_view kWord = "repeat";
  if (line.substr(0, kWord.size()) != kWord) return std::nullopt;
  const std::string_view rest = line.substr(kWord.size());
  if (!rest.empty() && rest.front() != ' ' && rest.front() != '\t') return std::nullopt;
  return trim(rest);
}

// Reads `in` (errors name `name`) line by line: comments, the optional repeat directive (only
// when `repeat` is not null), the header (one of `headers`; its index goes to `header_index`),
// then on_row(line, fields) for each data row, which returns an error reason or nothing.
template <typename RowFn>
std::optional<ParseError> scan_csv(std::istream& in, const std::string& name,
                                   std::span<const std::string_view> headers, std::int64_t* repeat,
                                   std::size_t& header_index, RowFn&& on_row) {
  auto fail = [&](std::size_t line, std::string reason) {
    return std::optional<ParseError>(ParseError{name, line, std::move(reason)});
  };
  std::string text;
  std::size_t line_no = 0;
  bool have_header = false;
  std::size_t rows = 0;
  while (std::getline(in, text)) {
    ++line_no;
    std::string_view line = trim(text);
    if (line_no == 1 && line.substr(0, 3) == "\xEF\xBB\xBF") line = trim(line.substr(3));  // BOM
    if (const auto directive = repeat_directive(line)) {
      if (repeat == nullptr) return fail(line_no, "'# repeat' is only valid in a spectrum file");
      if (line_no != 1) return fail(line_no, "'# repeat' must be the first line of the file");
      auto n = parse_count(*directive, "repeat");
      if (n.index() != 0) return fail(line_no, std::get<1>(std::move(n)));
      *repeat = std::get<0>(n);
      continue;
    }
    if (line.empty() || line.front() == '#') continue;
    const std::vector<std::string_view> fields = split_fields(line);
    if (!have_header) {
      const std::string got = join(fields);
      for (header_index = 0; header_index < headers.size(); ++header_index) {
        if (got == headers[header_index]) break;
      }
      if (header_index == headers.size()) {
        std::string expected;
        for (std::size_t i = 0; i < headers.size(); ++i) {
          expected += cat({i > 0 ? "' or '" : "", headers[i]});
        }
        return fail(line_no, cat({"expected header '", expected, "', got '", line, "'"}));
      }
      have_header = true;
      continue;
    }
    const std::size_t expected = split_fields(headers[header_index]).size();
    if (fields.size() != expected) {
      return fail(line_no, "expected " + std::to_string(expected) + " fields, got " +
                               std::to_string(fields.size()));
    }
    if (auto reason = on_row(line_no, fields)) return fail(line_no, std::move(*reason));
    ++rows;
  }
  if (in.bad()) return fail(line_no, "read error");
  if (!have_header) return fail(0, "no header line");
  if (rows == 0) return fail(0, "no data rows");
  return std::nullopt;
}

// The block rows of a cycles or spectrum file.
std::optional<ParseError> scan_blocks(std::istream& in, const std::string& name,
                                      std::int64_t* repeat, std::vector<core::LoadBlock>& blocks) {
  constexpr std::string_view kNames[] = {"p_max_N", "r", "angle_rad", "count"};
  const std::string_view headers[] = {kBlockHeader};
  std::size_t header_index = 0;
  return scan_csv(
      in, name, headers, repeat, header_index,
      [&](std::size_t, const std::vector<std::string_view>& f) -> std::optional<std::string> {
        double v[3] = {};
        for (std::size_t i = 0; i < 3; ++i) {
          auto x = parse_number(f[i], kNames[i]);
          if (x.index() != 0) return std::get<1>(std::move(x));
          v[i] = std::get<0>(x);
        }
        auto count = parse_count(f[3], kNames[3]);
        if (count.index() != 0) return std::get<1>(std::move(count));
        const core::LoadBlock block{v[0], v[1], v[2], std::get<0>(count)};
        if (const core::Status valid = core::check_load_block(block); !valid)
          return valid.error().reason;
        blocks.push_back(block);
        return std::nullopt;
      });
}

// Opens `file` for one of the stream readers; "cannot open file" when it cannot.
template <typename T, typename ReadFn>
ReadResult<T> read_file(const fs::path& file, ReadFn&& read) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return ParseError{file.string(), 0, "cannot open file"};
  return read(in, file.string());
}

}  // namespace

std::string ParseError::message() const {
  if (line == 0) return file + ": " + reason;
  return file + ":" + std::to_string(line) + ": " + reason;
}

std::vector<core::LoadBlock> merge_consecutive(std::span<const core::LoadBlock> blocks) {
  std::vector<core::LoadBlock> out;
  for (const core::LoadBlock& b : blocks) {
    if (!out.empty()) {
      core::LoadBlock& last = out.back();
      if (last.p_max == b.p_max && last.r == b.r && last.alpha == b.alpha &&
          b.count <= std::numeric_limits<std::int64_t>::max() - last.count) {
        last.count += b.count;
        continue;
      }
    }
    out.push_back(b);
  }
  return out;
}

BlockConversion series_to_blocks(const LoadSeries& series, const SeriesRules& rules) {
  const std::size_t n = series.load_n.size();
  if (!series.angle_rad.empty() && series.angle_rad.size() != n) {
    throw std::invalid_argument("series_to_blocks: " + std::to_string(series.angle_rad.size()) +
                                " angles for " + std::to_string(n) + " loads");
  }
  RainflowCounter counter(rules.gate);
  CycleBlocks converter({rules.alpha_bin, rules.compressed_bonds_fatigue});
  std::vector<CountedCycle> cycles;
  std::vector<core::LoadBlock> blocks;
  const auto convert = [&] {
    for (const CountedCycle& c : cycles) converter.add(c, blocks);
    cycles.clear();
  };
  for (std::size_t i = 0; i < n; ++i) {
    counter.push(series.load_n[i], series.angle_rad.empty() ? 0.0 : series.angle_rad[i], cycles);
    convert();
  }
  counter.finish(rules.residue, cycles);
  convert();
  BlockConversion out{merge_consecutive(blocks), converter.stats()};
  out.stats.reversals = counter.stats().reversals;
  out.stats.nonfinite_samples = counter.stats().nonfinite_samples;
  return out;
}

std::vector<core::LoadBlock> expand(const Spectrum& spectrum) {
  const std::size_t n = spectrum.blocks.size();
  const auto repeat = static_cast<std::size_t>(spectrum.repeat < 0 ? 0 : spectrum.repeat);
  std::vector<core::LoadBlock> out;
  if (n == 0 || repeat == 0) return out;
  if (repeat > kMaxSpectrumBlocks / n) {
    throw std::length_error("expand: " + std::to_string(n) + " blocks x " + std::to_string(repeat) +
                            " are more than " + std::to_string(kMaxSpectrumBlocks) + " blocks");
  }
  out.reserve(n * repeat);
  for (std::size_t k = 0; k < repeat; ++k) {
    out.insert(out.end(), spectrum.blocks.begin(), spectrum.blocks.end());
  }
  return out;
}

ReadResult<LoadSeries> read_series_csv(std::istream& in, const std::string& name) {
  const std::string_view headers[] = {kSeriesHeader, kSeriesAngleHeader};
  constexpr std::string_view kNames[] = {"time_s", "load_N", "angle_rad"};
  LoadSeries series;
  std::size_t header_index = 0;
  std::size_t previous_line = 0;
  auto error = scan_csv(
      in, name, headers, nullptr, header_index,
      [&](std::size_t line, const std::vector<std::string_view>& f) -> std::optional<std::string> {
        double v[3] = {};
        for (std::size_t i = 0; i < f.size(); ++i) {
          auto x = parse_number(f[i], kNames[i], i > 0);  // load, angle: a dropout is skipped
          if (x.index() != 0) return std::get<1>(std::move(x));
          v[i] = std::get<0>(x);
        }
        if (!series.time_s.empty() && !(v[0] > series.time_s.back())) {
          return cat({"time_s must be strictly increasing (", f[0], " after line ",
                      std::to_string(previous_line), ")"});
        }
        previous_line = line;
        series.time_s.push_back(v[0]);
        series.load_n.push_back(v[1]);
        if (f.size() == 3) series.angle_rad.push_back(v[2]);
        return std::nullopt;
      });
  if (error) return std::move(*error);
  return series;
}

ReadResult<std::vector<core::LoadBlock>> read_cycles_csv(std::istream& in,
                                                         const std::string& name) {
  std::vector<core::LoadBlock> blocks;
  if (auto error = scan_blocks(in, name, nullptr, blocks)) return std::move(*error);
  return blocks;
}

ReadResult<std::vector<messages::Observation>> read_observations_csv(std::istream& in,
                                                                     const std::string& name) {
  constexpr std::string_view kHeaders[] = {
      "cycle,kind,origin,length_m,sigma_m,pod_a50_m,pod_slope"};
  constexpr std::string_view kNames[] = {"cycle",   "kind",      "origin",   "length_m",
                                         "sigma_m", "pod_a50_m", "pod_slope"};
  std::vector<messages::Observation> out;
  std::size_t header = 0;
  auto error = scan_csv(
      in, name, kHeaders, nullptr, header,
      [&](std::size_t, const std::vector<std::string_view>& f) -> std::optional<std::string> {
        messages::Observation o;
        std::int64_t cycle = 0;
        const auto [end, ec] = std::from_chars(f[0].data(), f[0].data() + f[0].size(), cycle);
        if (f[0].empty() || ec != std::errc() || end != f[0].data() + f[0].size() || cycle < 0) {
          return cat({"'cycle' must be an integer >= 0, got '", f[0], "'"});
        }
        o.cycle = cycle;
        if (!out.empty() && cycle < out.back().cycle) {
          return cat({"'cycle' ", f[0], " is before the previous row's: rows in cycle order"});
        }
        if (f[1] == "crack_length") {
          o.kind = messages::ObservationKind::crack_length;
        } else if (f[1] == "no_crack") {
          o.kind = messages::ObservationKind::no_crack;
        } else {
          return cat({"'kind' must be crack_length or no_crack, got '", f[1], "'"});
        }
        o.origin = f[2].empty() ? "longest" : std::string(f[2]);
        const bool crack = o.kind == messages::ObservationKind::crack_length;
        double* targets[] = {&o.length_m, &o.sigma_m, &o.pod_a50_m, &o.pod_slope};
        for (std::size_t k = 3; k < 7; ++k) {
          const bool used = crack == (k < 5);
          if (!used) {
            if (!f[k].empty()) {
              return cat({"'", kNames[k], "' must be empty for kind ", f[1]});
            }
            continue;
          }
          auto v = parse_number(f[k], kNames[k]);
          if (v.index() != 0) return std::get<1>(std::move(v));
          *targets[k - 3] = std::get<0>(v);
        }
        if (const core::Status st = messages::check_observation(o); !st) {
          return "'" + st.error().field + "' " + st.error().reason;
        }
        out.push_back(std::move(o));
        return std::nullopt;
      });
  if (error) return std::move(*error);
  return out;
}

ReadResult<std::vector<messages::Observation>> read_observations_csv(
    const std::filesystem::path& file) {
  return read_file<std::vector<messages::Observation>>(
      file,
      [](std::istream& in, const std::string& name) { return read_observations_csv(in, name); });
}

ReadResult<Spectrum> read_spectrum_csv(std::istream& in, const std::string& name) {
  Spectrum spectrum;
  if (auto error = scan_blocks(in, name, &spectrum.repeat, spectrum.blocks)) {
    return std::move(*error);
  }
  // The directive is line 1; a list longer than the cap on its own is refused here too.
  const std::size_t n = spectrum.blocks.size();
  if (n > kMaxSpectrumBlocks ||
      static_cast<std::uint64_t>(spectrum.repeat) > kMaxSpectrumBlocks / n) {
    return ParseError{name, spectrum.repeat > 1 ? std::size_t{1} : std::size_t{0},
                      "'# repeat " + std::to_string(spectrum.repeat) + "' of " + std::to_string(n) +
                          " blocks expands to more than " + std::to_string(kMaxSpectrumBlocks) +
                          " blocks"};
  }
  return spectrum;
}

ReadResult<BlockConversion> read_blocks(std::istream& in, const std::string& name,
                                        HistoryFormat format, const SeriesRules& rules) {
  switch (format) {
    case HistoryFormat::series: {
      auto series = read_series_csv(in, name);
      if (!series) return series.error();
      return series_to_blocks(series.value(), rules);
    }
    case HistoryFormat::cycles: {
      auto blocks = read_cycles_csv(in, name);
      if (!blocks) return blocks.error();
      return BlockConversion{std::move(blocks).value(), {}};
    }
    case HistoryFormat::spectrum: {
      auto spectrum = read_spectrum_csv(in, name);
      if (!spectrum) return spectrum.error();
      return BlockConversion{expand(spectrum.value()), {}};
    }
  }
  return ParseError{name, 0, "unknown history format"};
}

ReadResult<LoadSeries> read_series_csv(const std::filesystem::path& file) {
  return read_file<LoadSeries>(
      file, [](std::istream& in, const std::string& name) { return read_series_csv(in, name); });
}

ReadResult<std::vector<core::LoadBlock>> read_cycles_csv(const std::filesystem::path& file) {
  return read_file<std::vector<core::LoadBlock>>(
      file, [](std::istream& in, const std::string& name) { return read_cycles_csv(in, name); });
}

ReadResult<Spectrum> read_spectrum_csv(const std::filesystem::path& file) {
  return read_file<Spectrum>(
      file, [](std::istream& in, const std::string& name) { return read_spectrum_csv(in, name); });
}

ReadResult<BlockConversion> read_blocks(const std::filesystem::path& file, HistoryFormat format,
                                        const SeriesRules& rules) {
  return read_file<BlockConversion>(file, [&](std::istream& in, const std::string& name) {
    return read_blocks(in, name, format, rules);
  });
}

std::vector<std::span<const core::LoadBlock>> make_batches(std::span<const core::LoadBlock> blocks,
                                                           std::size_t max_blocks) {
  if (max_blocks == 0) throw std::invalid_argument("make_batches: max_blocks must be >= 1");
  std::vector<std::span<const core::LoadBlock>> batches;
  for (std::size_t i = 0; i < blocks.size(); i += max_blocks) {
    batches.push_back(blocks.subspan(i, std::min(max_blocks, blocks.size() - i)));
  }
  return batches;
}

}  // namespace peritwin::loads
