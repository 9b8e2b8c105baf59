// The body of a chunked HTTP response (Transfer-Encoding: chunked, RFC 9112 Sec. 7.1) as a test
// client received it: what the dashboard's event streams send.
#pragma once

#include <cstdlib>
#include <string>

namespace peritwin::testing {

/// The body from `raw` (what came after the headers): the chunks complete so far, de-framed; it
/// stops at the last chunk (size 0) or at a chunk not complete yet.
inline std::string dechunk(const std::string& raw) {
  std::string body;
  std::size_t at = 0;
  for (;;) {
    const auto eol = raw.find("\r\n", at);
    if (eol == std::string::npos) break;
    const auto size = std::strtoull(raw.substr(at, eol - at).c_str(), nullptr, 16);
    if (size == 0 || raw.size() < eol + 2 + size + 2) break;
    body.append(raw, eol + 2, size);
    at = eol + 2 + size + 2;
  }
  return body;
}

}  // namespace peritwin::testing
