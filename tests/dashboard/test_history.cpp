// dashboard::BoundedHistory: the size bound, and what decimation keeps (first, last, extremes).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "dashboard/history.h"

namespace peritwin::dashboard {
namespace {

TEST(BoundedHistory, KeepsEverythingBelowTheBound) {
  dashboard::BoundedHistory<2> h(100);
  for (int i = 0; i < 100; ++i) h.push({double(i), double(-i)});
  ASSERT_EQ(h.size(), 100u);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(h.rows()[std::size_t(i)][0], double(i));
}

TEST(BoundedHistory, BoundHoldsAndEndsAndExtremesStayAfterManyPushes) {
  dashboard::BoundedHistory<2> h(10000);
  const int n = 1'000'003;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int i = 0; i < n; ++i) {
    // A wiggle with one deep dip and one tall peak in the middle of the run.
    double v = std::sin(i * 0.001);
    if (i == 123'457) v = -50.0;
    if (i == 654'321) v = 75.0;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    h.push({double(i), v});
    ASSERT_LE(h.size(), 10000u) << i;
  }
  EXPECT_EQ(h.pushed(), std::size_t(n));
  EXPECT_GT(h.size(), 4000u);  // decimation halves, it does not empty
  EXPECT_EQ(h.rows().front()[0], 0.0);
  EXPECT_EQ(h.rows().back()[0], double(n - 1));
  double kept_lo = std::numeric_limits<double>::infinity(), kept_hi = -kept_lo;
  for (const auto& r : h.rows()) {
    kept_lo = std::min(kept_lo, r[1]);
    kept_hi = std::max(kept_hi, r[1]);
  }
  EXPECT_EQ(kept_lo, lo);
  EXPECT_EQ(kept_hi, hi);
  EXPECT_EQ(kept_lo, -50.0);
  EXPECT_EQ(kept_hi, 75.0);
  // Push order is kept.
  EXPECT_TRUE(std::is_sorted(h.rows().begin(), h.rows().end(),
                             [](const auto& a, const auto& b) { return a[0] < b[0]; }));
}

TEST(BoundedHistory, MonotoneInputKeepsItsEnds) {
  dashboard::BoundedHistory<1> h(1000);
  for (int i = 0; i < 250'000; ++i) h.push({1.0 + i * 0.5});
  ASSERT_LE(h.size(), 1000u);
  EXPECT_EQ(h.rows().front()[0], 1.0);
  EXPECT_EQ(h.rows().back()[0], 1.0 + 249'999 * 0.5);
  EXPECT_TRUE(std::is_sorted(h.rows().begin(), h.rows().end()));
}

TEST(BoundedHistory, NanIsNoExtremeAndIsKeptAsData) {
  dashboard::BoundedHistory<2> h(50);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < 5000; ++i) h.push({double(i), i % 7 == 0 ? nan : double(i % 13)});
  ASSERT_LE(h.size(), 50u);
  double hi = -1;
  for (const auto& r : h.rows()) {
    if (!std::isnan(r[1])) hi = std::max(hi, r[1]);
  }
  EXPECT_EQ(hi, 12.0);
}

}  // namespace
}  // namespace peritwin::dashboard
