// Error texts of the prognostics, built by appending: GCC 12's -Wrestrict misfires on
// "literal" + std::to_string(...) (the same workaround as loads/load_history.cpp).
#pragma once

#include <string>
#include <string_view>
#include <type_traits>

namespace peritwin::prognostics {

/// The parts one after the other: numbers by std::to_string, anything else as text.
template <typename... Parts>
std::string text(const Parts&... parts) {
  std::string s;
  const auto append = [&s](const auto& part) {
    if constexpr (std::is_arithmetic_v<std::decay_t<decltype(part)>>) {
      s += std::to_string(part);
    } else {
      s += std::string_view(part);
    }
  };
  (append(parts), ...);
  return s;
}

}  // namespace peritwin::prognostics
