// The project's one error convention at every boundary: a function that can fail returns
// Expected<T> — a value or an Error carrying the reason — instead of a bool with an out-string, an
// empty-or-reason string, or an exception. Exceptions stay inside I/O code (HDF5, files, LCM logs)
// and are caught at its edge and turned into an Error. A minimal stand-in for C++23's
// std::expected (the project builds as C++20).
#pragma once

#include <string>
#include <utility>
#include <variant>

namespace peritwin::core {

/// Why something failed: the offending field or key path (e.g. "blocks[3].r", empty when the
/// whole input is at fault) and a sentence for humans.
struct Error {
  std::string field;
  std::string reason;
  /// "field: reason", or the reason alone.
  [[nodiscard]] std::string message() const {
    return field.empty() ? reason : field + ": " + reason;
  }
  /// The same error with `prefix` before the field (e.g. "blocks[3]." + "r").
  [[nodiscard]] Error within(const std::string& prefix) const { return {prefix + field, reason}; }
};

/// An error from a reason alone (for functions whose callers know the field).
inline Error failure(std::string reason) { return {{}, std::move(reason)}; }

/// Either a value or an error of type E.
template <typename T, typename E = Error>
class [[nodiscard]] Expected {
 public:
  Expected(T value)
      : data_(std::in_place_index<0>, std::move(value)) {}  // NOLINT(google-explicit-constructor)
  Expected(E error)
      : data_(std::in_place_index<1>, std::move(error)) {}  // NOLINT(google-explicit-constructor)
  [[nodiscard]] bool ok() const { return data_.index() == 0; }
  explicit operator bool() const { return ok(); }
  /// Throws std::bad_variant_access when !ok().
  [[nodiscard]] const T& value() const& { return std::get<0>(data_); }
  [[nodiscard]] T& value() & { return std::get<0>(data_); }
  [[nodiscard]] T&& value() && { return std::get<0>(std::move(data_)); }
  [[nodiscard]] const T& operator*() const& { return value(); }
  [[nodiscard]] T& operator*() & { return value(); }
  [[nodiscard]] const T* operator->() const { return &value(); }
  [[nodiscard]] T* operator->() { return &value(); }
  /// Throws std::bad_variant_access when ok().
  [[nodiscard]] const E& error() const { return std::get<1>(data_); }

 private:
  std::variant<T, E> data_;
};

/// Success or an error (Expected<void>).
template <typename E>
class [[nodiscard]] Expected<void, E> {
 public:
  Expected() = default;
  Expected(E error)
      : error_(std::move(error)), ok_(false) {}  // NOLINT(google-explicit-constructor)
  [[nodiscard]] bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  /// Meaningful only when !ok().
  [[nodiscard]] const E& error() const { return error_; }

 private:
  E error_{};
  bool ok_ = true;
};

using Status = Expected<void>;

/// The error's message, or "" when `s` is ok (for logs and test assertions).
inline std::string message_of(const Status& s) { return s ? std::string() : s.error().message(); }

}  // namespace peritwin::core
