// A bounded history of one detail for the dashboard: rows of N numbers (one row per STATE), at most
// `capacity` rows however many are pushed. When a push goes over the bound, every second interior
// row is dropped except the protected ones: the first, the last, and per column the row holding
// its smallest and its largest value (NaN ignored). So the first and the last rows pushed and every
// column's all-time extremes are always kept (an all-time extreme is the column's extreme at every
// decimation after its push), monotone input keeps its ends, and the rows kept stay in push order.
// Pure: no clock, no I/O, no locking (the caller's mutex guards it).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

namespace peritwin::dashboard {

template <std::size_t N>
class BoundedHistory {
 public:
  using Row = std::array<double, N>;

  /// capacity >= 2 + 2 N (room for the protected rows); smaller values are raised to that.
  explicit BoundedHistory(std::size_t capacity = 10000)
      : capacity_(capacity < 2 + 2 * N + 2 ? 2 + 2 * N + 2 : capacity) {}

  void push(const Row& row) {
    rows_.push_back(row);
    ++pushed_;
    if (rows_.size() > capacity_) decimate();
  }

  [[nodiscard]] const std::vector<Row>& rows() const { return rows_; }
  [[nodiscard]] std::size_t size() const { return rows_.size(); }
  [[nodiscard]] std::size_t capacity() const { return capacity_; }
  /// Rows pushed since construction (kept or not).
  [[nodiscard]] std::size_t pushed() const { return pushed_; }
  [[nodiscard]] bool empty() const { return rows_.empty(); }

 private:
  void decimate() {
    const std::size_t n = rows_.size();
    std::vector<bool> keep(n, false);
    keep.front() = keep.back() = true;
    for (std::size_t c = 0; c < N; ++c) {
      std::size_t lo = n, hi = n;
      for (std::size_t i = 0; i < n; ++i) {
        const double v = rows_[i][c];
        if (std::isnan(v)) continue;
        if (lo == n || v < rows_[lo][c]) lo = i;
        if (hi == n || v > rows_[hi][c]) hi = i;
      }
      if (lo < n) keep[lo] = true;
      if (hi < n) keep[hi] = true;
    }
    // Every second unprotected interior row goes: about half of them.
    bool drop = false;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      if (keep[i]) continue;
      keep[i] = !drop;
      drop = !drop;
    }
    std::vector<Row> kept;
    kept.reserve(capacity_);
    for (std::size_t i = 0; i < n; ++i) {
      if (keep[i]) kept.push_back(rows_[i]);
    }
    rows_ = std::move(kept);
  }

  std::size_t capacity_;
  std::size_t pushed_ = 0;
  std::vector<Row> rows_;
};

}  // namespace peritwin::dashboard
