// Remaining life: rolling spectrum, forward simulation, band, synchronous estimates.
#include <cmath>

#include "tests/support/twin_fixtures.h"
#include "twin/model/life.h"

namespace peritwin::twin {
namespace {

using testing::b1_config;
using testing::b1_model;
using testing::batch;
using testing::make_twin;

TEST(RollingSpectrum, MergesConsecutiveAndRolls) {
  RollingSpectrum s;
  s.add({4000, 0.1, 0, 10});
  s.add({4000, 0.1, 0, 5});
  s.add({3000, 0.1, 0, 1});
  s.add({4000, 0.1, 0, 2});
  ASSERT_EQ(s.blocks().size(), 3u);
  EXPECT_EQ(s.blocks()[0].count, 15);
  const auto ref = s.reference();
  ASSERT_EQ(ref.size(), 2u);
  EXPECT_EQ(ref[0].p_max, 4000);
  EXPECT_EQ(ref[0].count, 17);
  EXPECT_EQ(ref[1].count, 1);
  for (int i = 0; i < 5000; ++i) s.add({1000.0 + i, 0.1, 0, 1});
  EXPECT_EQ(s.blocks().size(), RollingSpectrum::kCapacity);
  EXPECT_EQ(s.blocks().front().p_max, 1000.0 + 5000 - RollingSpectrum::kCapacity);
}

TEST(RollingSpectrum, ManyLevelsAreGroupedConservatively) {
  RollingSpectrum s;
  for (int i = 0; i < 100; ++i) s.add({1000.0 + 10 * i, 0.0, 0, 3});
  const auto ref = s.reference();
  EXPECT_LE(ref.size(), RollingSpectrum::kMaxLevels);
  std::int64_t total = 0;
  for (const auto& b : ref) total += b.count;
  EXPECT_EQ(total, 300);
  EXPECT_EQ(ref.back().p_max, 1990.0);  // the largest range represents the top group
  for (std::size_t i = 1; i < ref.size(); ++i) EXPECT_GT(ref[i].p_max, ref[i - 1].p_max);
}

class LifeTest : public ::testing::Test {
 public:
  static std::shared_ptr<const DetailModel> no_band_model() {
    return b1_model(b1_config("every_batches = 2",
                              {{"critical_crack_length = 0.008", "critical_crack_length = 0.002"},
                               {"band = \"a2_scatter\"", "band = \"none\""},
                               {"a2_relative_scatter = 0.2", ""}}));
  }

 protected:
  // A short critical crack length keeps the forward simulations to a few dozen re-solves.
  static void SetUpTestSuite() {
    model_ = b1_model(b1_config(
        "every_batches = 2", {{"critical_crack_length = 0.008", "critical_crack_length = 0.002"}}));
  }
  static void TearDownTestSuite() { model_.reset(); }
  static std::shared_ptr<const DetailModel> model_;
};
std::shared_ptr<const DetailModel> LifeTest::model_;

TEST_F(LifeTest, ForwardSimulationIsExactAndDeterministic) {
  auto twin = make_twin(model_, LifeMode::external);
  const LifeJob job = twin->life_job();
  ASSERT_EQ(job.spectrum.size(), 1u);  // the configured reference spectrum
  const double a = simulate_life(*model_, job.state, job.spectrum, 1.0);
  const double b = simulate_life(*model_, job.state, job.spectrum, 1.0);
  ASSERT_TRUE(std::isfinite(a));
  EXPECT_GT(a, 0.0);
  EXPECT_EQ(a, b);
  // Applying exactly that many cycles of the reference reaches the criterion; one fewer does not.
  const auto& ref = job.spectrum.front();
  const auto n = static_cast<std::int64_t>(a);
  auto before = make_twin(model_, LifeMode::external);
  ASSERT_TRUE(before->apply(batch(1, {{ref.p_max, ref.r, ref.alpha, n - 1}})).applied());
  EXPECT_EQ(before->failure(), Failure::none);
  ASSERT_TRUE(before->apply(batch(2, {{ref.p_max, ref.r, ref.alpha, 1}})).applied());
  EXPECT_EQ(before->failure(), Failure::end_criterion);
  EXPECT_EQ(simulate_life(*model_, before->engine().export_state(), job.spectrum, 1.0), 0.0);
  // An empty spectrum gives no estimate.
  EXPECT_TRUE(std::isnan(simulate_life(*model_, job.state, {}, 1.0)));
}

TEST_F(LifeTest, BandFromA2Scatter) {
  auto twin = make_twin(model_, LifeMode::external);
  const LifeJob job = twin->life_job();
  const LifeEstimate e = estimate_life(*model_, job.state, job.spectrum, true);
  EXPECT_LE(e.low, e.central);
  EXPECT_LE(e.central, e.high);
  EXPECT_LT(e.low, e.high);
  // The band is the range of the runs with A2·(1 ± 0.2) and A2 itself. At a 2 mm crack on the
  // 1 mm grid the order of the three need not follow A2 (which bonds break first may change).
  const double plus = simulate_life(*model_, job.state, job.spectrum, 1.2);
  const double minus = simulate_life(*model_, job.state, job.spectrum, 0.8);
  EXPECT_EQ(e.low, std::min({plus, minus, e.central}));
  EXPECT_EQ(e.high, std::max({plus, minus, e.central}));
}

TEST_F(LifeTest, SynchronousEstimatesAtFixedPointsFall) {
  auto twin = make_twin(no_band_model(), LifeMode::synchronous);
  twin->catch_up_life();  // state 0 is a fixed point
  EXPECT_EQ(twin->life().state_seq, 0);
  EXPECT_EQ(twin->life().seq, -1);
  const double at0 = twin->life().central;
  ASSERT_TRUE(std::isfinite(at0));
  ASSERT_TRUE(twin->apply(batch(1, {{4000, 0.1, 0, 2000}})).applied());
  EXPECT_EQ(twin->life().state_seq, 0);  // not a fixed point: the estimate lags
  ASSERT_TRUE(twin->apply(batch(2, {{4000, 0.1, 0, 2000}})).applied());
  EXPECT_EQ(twin->life().state_seq, 2);
  EXPECT_EQ(twin->life().seq, 2);
  EXPECT_EQ(twin->life().source, "test");
  // Under the reference load itself the estimate falls by the cycles applied (exactly, unless a
  // bond broke differently, which the same load cannot cause).
  EXPECT_EQ(twin->life().central, at0 - 4000);
}

TEST_F(LifeTest, EveryCyclesEstimatesWhereABatchPassesAMultipleOfItsCycles) {
  // every_cycles = 5000 alone, batches of 700 cycles: estimates at state 0 and at the states
  // whose batch took the count past 5000, 10000, ... (700 k crosses 5000 m at k = 8, 15, 22).
  auto model =
      b1_model(b1_config("every_batches = 0\nevery_cycles = 5000",
                         {{"critical_crack_length = 0.008", "critical_crack_length = 0.002"},
                          {"band = \"a2_scatter\"", "band = \"none\""},
                          {"a2_relative_scatter = 0.2", ""}}));
  ASSERT_TRUE(model);
  ASSERT_EQ(model->config().life.every_cycles, 5000);
  auto twin = make_twin(model, LifeMode::synchronous);
  twin->catch_up_life();
  EXPECT_EQ(twin->life().state_seq, 0);
  std::vector<std::int64_t> estimated_at;
  for (std::int64_t s = 1; s <= 22; ++s) {
    ASSERT_TRUE(twin->apply(batch(s, {{4000, 0.1, 0, 700}})).applied());
    if (twin->life().state_seq == s) estimated_at.push_back(s);
  }
  EXPECT_EQ(estimated_at, (std::vector<std::int64_t>{8, 15, 22}));
}

}  // namespace
}  // namespace peritwin::twin
