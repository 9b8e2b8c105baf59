#include "loads/state_text.h"

#include <charconv>
#include <cmath>
#include <system_error>

namespace peritwin::loads::state_text {

void put(std::string& out, double v) {
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, std::abs(v), std::chars_format::hex);
  out += std::signbit(v) ? " -0x" : " 0x";
  if (ec == std::errc()) out.append(buf, end);
}

void put(std::string& out, std::uint64_t v) {
  out += ' ';
  out += std::to_string(v);
}

std::string_view Reader::next() {
  const auto blank = [](char c) { return c == ' ' || c == '\n' || c == '\t' || c == '\r'; };
  while (!text_.empty() && blank(text_.front())) text_.remove_prefix(1);
  std::size_t n = 0;
  while (n < text_.size() && !blank(text_[n])) ++n;
  const std::string_view token = text_.substr(0, n);
  text_.remove_prefix(n);
  if (!token.empty()) ++tokens_;
  return token;
}

bool Reader::fail(const std::string& reason) {
  if (error_.empty()) {
    error_ = std::string(what_) + ": " + reason + " (token " + std::to_string(tokens_) + ")";
  }
  return false;
}

std::string_view Reader::token(std::string_view name) {
  if (!ok()) return {};
  const std::string_view token = next();
  if (token.empty()) fail("truncated: expected " + std::string(name));
  return token;
}

bool Reader::word(std::string_view word) {
  if (!ok()) return false;
  const std::string_view token = next();
  if (token.empty()) return fail("truncated: expected '" + std::string(word) + "'");
  if (token != word) {
    return fail("expected '" + std::string(word) + "', got '" + std::string(token.substr(0, 40)) +
                "'");
  }
  return true;
}

bool Reader::number(double& v, std::string_view name) {
  if (!ok()) return false;
  std::string_view token = next();
  if (token.empty()) return fail("truncated: expected " + std::string(name));
  const std::string shown(token.substr(0, 40));
  const bool negative = token.front() == '-';
  if (negative) token.remove_prefix(1);
  if (token.substr(0, 2) != "0x") {
    return fail(std::string(name) + " '" + shown + "' is not a hexadecimal float");
  }
  token.remove_prefix(2);
  double x = 0.0;
  const auto [end, ec] =
      std::from_chars(token.data(), token.data() + token.size(), x, std::chars_format::hex);
  if (ec != std::errc() || end != token.data() + token.size() || token.empty() ||
      !std::isfinite(x) || token.front() == '-' || token.front() == '+') {
    return fail(std::string(name) + " '" + shown + "' is not a finite hexadecimal float");
  }
  v = negative ? -x : x;
  return true;
}

bool Reader::count(std::uint64_t& v, std::string_view name) {
  if (!ok()) return false;
  const std::string_view token = next();
  if (token.empty()) return fail("truncated: expected " + std::string(name));
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
  if (ec != std::errc() || end != token.data() + token.size()) {
    return fail(std::string(name) + " '" + std::string(token.substr(0, 40)) +
                "' is not an unsigned integer");
  }
  return true;
}

bool Reader::end() {
  if (!ok()) return false;
  const std::string_view token = next();
  if (!token.empty()) return fail("unexpected '" + std::string(token.substr(0, 40)) + "'");
  return true;
}

}  // namespace peritwin::loads::state_text
