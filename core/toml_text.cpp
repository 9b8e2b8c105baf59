// Around toml++ 3.3.0's parser: the check of the text, one-line messages (toml_text.h).
#include "core/toml_text.h"

namespace peritwin::core {

std::optional<UnsafeTomlCharacter> find_unsafe_toml_character(std::string_view t) {
  std::uint32_t line = 1, column = 1;
  std::size_t i = t.starts_with("\xEF\xBB\xBF") ? 3 : 0;  // toml++ skips a UTF-8 BOM
  auto at = [&](std::size_t k) -> unsigned char {
    return k < t.size() ? static_cast<unsigned char>(t[k]) : 0;
  };
  auto next = [&] {  // columns count code points, as toml++'s do
    if (t[i] == '\n') {
      ++line;
      column = 1;
    } else if ((at(i) & 0xC0) != 0x80) {
      ++column;
    }
    ++i;
  };
  auto refuse = [&](std::string_view where) {
    return UnsafeTomlCharacter{line, column, std::string(where)};
  };
  int depth = 0;           // arrays open (a value may span lines)
  bool line_start = true;  // only blanks so far on this line
  bool header = false;     // on a [table] or [[array]] header line
  unsigned char last = 0;  // the last non-blank character outside strings on this line
  // Where a value may be: after a key's '=' (until the line ends outside brackets), in an array,
  // after an inline table's '='. There a run of characters that starts unquoted is one bare token
  // up to a blank or the line's end (inside brackets also ',', ']' or '}'), and toml++ reads a
  // quote, '=', ',', '.' or '[' in it as part of the token, not as a string's start or structure:
  // `x = -"0=" <U+FEF7>` (found by fuzz_key_file) must be checked as outside a string.
  std::string open;  // the arrays ('[') and inline tables ('{') open, innermost last
  bool in_value = false;
  bool bare = false;
  while (i < t.size()) {
    const unsigned char c = at(i);
    if (c == '#') {
      while (i < t.size() && t[i] != '\n') next();
      continue;
    }
    // A quote opens a string only where TOML lets one start (a key or a value): elsewhere, as in
    // `x = 0"...`, toml++ classifies the characters after it as part of a bare value (found by
    // fuzz_key_file), so they are checked as outside a string.
    const bool string_may_start =
        line_start || last == '=' || last == '[' || last == ',' || last == '{' || last == '.';
    if ((c == '"' || c == '\'') && string_may_start && !bare) {
      const bool basic = c == '"';
      const bool multi = at(i + 1) == c && at(i + 2) == c;
      for (int k = 0; k < (multi ? 3 : 1); ++k) next();
      while (i < t.size()) {
        const unsigned char s = at(i);
        if (!multi && s == '\n') break;  // unterminated: toml++ says so
        if (s == c && (!multi || (at(i + 1) == c && at(i + 2) == c))) {
          for (int k = 0; k < (multi ? 3 : 1); ++k) next();
          for (int k = 0; multi && k < 2 && at(i) == c; ++k) next();  // """a"""" ends with a quote
          break;
        }
        if (basic && s == '\\') {
          next();
          if (multi && (at(i) == ' ' || at(i) == '\t' || at(i) == '\r' || at(i) == '\n')) {
            while (at(i) == ' ' || at(i) == '\t' || at(i) == '\r' || at(i) == '\n') next();
            if (at(i) >= 0x80) return refuse("after a line-ending backslash in a string");
            continue;
          }
          if (at(i) >= 0x80) return refuse("after a backslash in a string");
          if (i < t.size()) next();
          continue;
        }
        if (s >= 0x80 && header) return refuse("in a table header");
        next();
      }
      line_start = false;
      last = c;
      continue;
    }
    if (c >= 0x80) return refuse(header ? "in a table header" : "outside a string or comment");
    const bool blank = c == ' ' || c == '\t' || c == '\r' || c == '\n';
    if (bare && !blank && !(!open.empty() && (c == ',' || c == ']' || c == '}'))) {
      line_start = false;
      last = 'v';  // inside a bare token: nothing here opens a string or a bracket
      next();
      continue;
    }
    bare = false;
    if (c == '\n') {
      line_start = true;
      header = false;
      last = 0;
      if (open.empty()) in_value = false;
    } else if (c == '[') {
      if (line_start && depth == 0) {
        header = true;
      } else if (!header) {
        ++depth;
        open.push_back('[');
        in_value = true;
      }
    } else if (c == ']' && !header && depth > 0) {
      --depth;
      if (!open.empty() && open.back() == '[') open.pop_back();
    } else if (c == '{' && !header) {
      open.push_back('{');
      in_value = false;  // a key comes first
    } else if (c == '}' && !header) {
      if (!open.empty() && open.back() == '{') open.pop_back();
      in_value = true;
    } else if (c == ',' && !open.empty() && open.back() == '{') {
      in_value = false;  // the next key of the inline table
    } else if (c == '=' && !header) {
      if (in_value) {
        bare = true;  // an '=' where a value is: part of a bare token
        line_start = false;
        last = 'v';
        next();
        continue;
      }
      in_value = true;
    } else if (!blank && !header && in_value && c != ',' && c != '\'' && c != '"') {
      bare = true;
      line_start = false;
      last = 'v';
      next();
      continue;
    } else if (!blank && !header && in_value && (c == '\'' || c == '"')) {
      bare = true;  // a quote where no string may start (e.g. after a bare token's blank)
      line_start = false;
      last = 'v';
      next();
      continue;
    }
    if (!blank) {
      line_start = false;
      last = c;
    }
    next();
  }
  return std::nullopt;
}

void append_one_line(std::string& out, std::string_view s) {
  static constexpr char kHex[] = "0123456789abcdef";
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else if (u < 0x20 || u == 0x7f) {
      out += "\\x";
      out += kHex[u >> 4];
      out += kHex[u & 0xf];
    } else {
      out += c;
    }
  }
}

std::string one_line(std::string_view s) {
  std::string out;
  append_one_line(out, s);
  return out;
}

}  // namespace peritwin::core
