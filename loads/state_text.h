// The text of the replay side's saved states (RainflowCounter, CycleBlocks): whitespace-separated
// tokens, words and numbers; a double is written as a hexadecimal float ("-0x1.8p+3", C's %a), so
// a state read back is bit-identical. Locale-independent (std::to_chars / std::from_chars).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace peritwin::loads::state_text {

/// Appends " <v as %a>" to `out`.
void put(std::string& out, double v);
/// Appends " <v>" (decimal) to `out`.
void put(std::string& out, std::uint64_t v);

/// Reads the tokens of a saved state in order. The first failure is kept (error()); every later
/// call fails too, so a reader can check once at the end.
class Reader {
 public:
  Reader(std::string_view text, std::string_view what) : text_(text), what_(what) {}
  /// The next token (empty after a failure).
  std::string_view token(std::string_view name);
  /// The next token must be `word`.
  bool word(std::string_view word);
  /// A finite hexadecimal float written by put(double).
  bool number(double& v, std::string_view name);
  /// A decimal unsigned integer.
  bool count(std::uint64_t& v, std::string_view name);
  /// Nothing but blanks may follow.
  bool end();
  /// Fails with `reason` (if nothing failed before).
  bool fail(const std::string& reason);
  [[nodiscard]] bool ok() const { return error_.empty(); }
  /// "<what>: <reason> (token <n>)".
  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  std::string_view next();  // empty at the end of the text
  std::string_view text_;
  std::string_view what_;
  std::size_t tokens_ = 0;
  std::string error_;
};

}  // namespace peritwin::loads::state_text
