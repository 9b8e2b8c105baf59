// What every TOML reader of the project (the config parser, the key file reader) does around
// toml++: the check of the text before toml::parse (Debian 12's toml++ must not read some of it),
// and one-line error messages whatever the text or toml++'s echo of it holds.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace peritwin::core {

/// Where a TOML text holds a character toml++ 3.3.0 cannot classify safely, and in what part of
/// the text ("outside a string or comment", "in a table header", "after a backslash in a string",
/// "after a line-ending backslash in a string"). Lines and columns from 1; columns count code
/// points, as toml++'s do.
struct UnsafeTomlCharacter {
  std::uint32_t line = 0;
  std::uint32_t column = 0;
  std::string where;
};

/// Debian 12's toml++ 3.3.0 classifies code points as whitespace with a lookup that reaches
/// TOML_UNREACHABLE, i.e. undefined behaviour, for most non-ASCII code points (upstream
/// marzer/tomlplusplus issues 190 and 295; found here by fuzz_config). It classifies every
/// character outside strings and comments, every character of a table header line (quoted keys
/// included), and the character after a backslash (and after a line-ending backslash's blanks) in
/// a multi-line basic string. A non-ASCII character in the first two places is invalid TOML anyway
/// and in the third exotic: the first one is found here, with its line and column, so that the
/// caller refuses the text before toml++ reads it. Strings elsewhere and comments may hold any
/// UTF-8.
std::optional<UnsafeTomlCharacter> find_unsafe_toml_character(std::string_view text);

/// Appends `s` with its control characters escaped (\n, \r, \t, \xNN): a message stays one
/// line whatever the file name, a quoted key or toml++'s echo of the input holds (found by
/// fuzz_config: "expected 'true', saw 'tr<newline>'").
void append_one_line(std::string& out, std::string_view s);

/// `s` with its control characters escaped, as append_one_line.
std::string one_line(std::string_view s);

}  // namespace peritwin::core
