// Weighted percentiles and summaries, the inspection likelihoods and the prognostic metrics,
// against numbers computed by hand (each test says how).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "prognostics/metrics.h"
#include "prognostics/observation_likelihood.h"
#include "prognostics/weighted_statistics.h"

namespace peritwin {
namespace {

namespace pg = prognostics;
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(WeightedQuantiles, EqualWeightsAreHazen) {
  // {4, 1, 3, 2} (unsorted): P_k = (k - 1/2)/4 = 0.125, 0.375, 0.625, 0.875 for 1, 2, 3, 4.
  const std::vector<double> x = {4, 1, 3, 2};
  const std::vector<double> w(4, 1.0);
  const std::vector<double> p = {0.0, 0.1, 0.125, 0.25, 0.5, 0.8, 0.875, 1.0};
  const auto q = pg::weighted_quantiles(x, w, p);
  ASSERT_TRUE(q.ok());
  // 0.25: halfway from P_1 = 0.125 to P_2 = 0.375 -> 1.5; 0.8: (0.8 - 0.625)/0.25 = 0.7 -> 3.7.
  const std::vector<double> expected = {1, 1, 1, 1.5, 2.5, 3.7, 4, 4};
  for (std::size_t k = 0; k < p.size(); ++k) EXPECT_NEAR((*q)[k], expected[k], 1e-14) << p[k];
}

TEST(WeightedQuantiles, WeightsByHand) {
  // {30, 10, 20} with weights {0.3, 0.2, 0.5}: sorted 10, 20, 30; S = 0.2, 0.7, 1.0;
  // P = 0.1, 0.45, 0.85.
  const std::vector<double> x = {30, 10, 20};
  const std::vector<double> w = {0.3, 0.2, 0.5};
  // 0.5: 20 + 10 (0.5 - 0.45)/(0.85 - 0.45) = 21.25; 0.3: 10 + 10 (0.2 / 0.35) = 15.714285...
  EXPECT_NEAR(*pg::weighted_quantile(x, w, 0.5), 21.25, 1e-13);
  EXPECT_NEAR(*pg::weighted_median(x, w), 21.25, 1e-13);
  EXPECT_NEAR(*pg::weighted_quantile(x, w, 0.3), 10 + 10 * 0.2 / 0.35, 1e-13);
  EXPECT_EQ(*pg::weighted_quantile(x, w, 0.05), 10);
  EXPECT_EQ(*pg::weighted_quantile(x, w, 0.95), 30);
  // Scaling the weights changes nothing; a weight-0 sample is ignored.
  const std::vector<double> w10 = {3, 2, 5};
  EXPECT_NEAR(*pg::weighted_quantile(x, w10, 0.3), 10 + 10 * 0.2 / 0.35, 1e-13);
  const std::vector<double> x0 = {30, 10, 20, 1000};
  const std::vector<double> w0 = {0.3, 0.2, 0.5, 0.0};
  EXPECT_NEAR(*pg::weighted_quantile(x0, w0, 0.95), 30, 1e-13);
  // P(x <= 20) = 0.7; mean 21, variance 0.2*121 + 0.5*1 + 0.3*81 = 49: CoV 7/21.
  EXPECT_NEAR(*pg::probability_at_or_below(x, w, 20.0), 0.7, 1e-15);
  EXPECT_NEAR(*pg::probability_at_or_below(x, w, 19.99), 0.2, 1e-15);
  EXPECT_NEAR(*pg::weighted_mean(x, w), 21.0, 1e-13);
  EXPECT_NEAR(*pg::weighted_variance(x, w), 49.0, 1e-12);
  const auto summary = pg::summarize(x, w);
  ASSERT_TRUE(summary.ok());
  EXPECT_NEAR(summary->median, 21.25, 1e-13);
  EXPECT_NEAR(summary->coefficient_of_variation, 1.0 / 3.0, 1e-14);
}

TEST(WeightedQuantiles, SeveralFutureLoadSamplesPerParticle) {
  // Particle A (w 0.75) ends at 100 or 300 under two load samples, B (w 0.25) at 200 (one sample):
  // samples 100, 300 of weight 0.375 each and 200 of 0.25. Sorted 100, 200, 300; S = 0.375,
  // 0.625, 1; P = 0.1875, 0.5, 0.8125: the median is 200, P(<= 250) = 0.625.
  const std::vector<double> x = {100, 300, 200};
  const std::vector<double> w = {0.75 / 2, 0.75 / 2, 0.25};
  EXPECT_NEAR(*pg::weighted_median(x, w), 200, 1e-12);
  EXPECT_NEAR(*pg::probability_at_or_below(x, w, 250), 0.625, 1e-15);
}

TEST(WeightedQuantiles, InfiniteEndOfLife) {
  // {1, 2, +inf}, equal weights: P = 1/6, 1/2, 5/6. Q(0.5) = 2, Q(0.6) = +inf (between 2 and
  // +inf), Q(0.1) = 1; P(x <= 2) = 2/3.
  const std::vector<double> x = {kInf, 2, 1};
  const std::vector<double> w(3, 1.0);
  EXPECT_EQ(*pg::weighted_quantile(x, w, 0.5), 2.0);
  EXPECT_EQ(*pg::weighted_quantile(x, w, 0.6), kInf);
  EXPECT_EQ(*pg::weighted_quantile(x, w, 0.1), 1.0);
  EXPECT_NEAR(*pg::probability_at_or_below(x, w, 2.0), 2.0 / 3.0, 1e-15);
  EXPECT_FALSE(pg::weighted_mean(x, w).ok());  // means need finite values
}

TEST(WeightedQuantiles, RefusesInvalidSamples) {
  const std::vector<double> x = {1, 2};
  EXPECT_FALSE(pg::weighted_median(x, std::vector<double>{1.0}).ok());
  EXPECT_FALSE(pg::weighted_median(x, std::vector<double>{1.0, -1.0}).ok());
  EXPECT_FALSE(pg::weighted_median(x, std::vector<double>{0.0, 0.0}).ok());
  EXPECT_FALSE(pg::weighted_median(std::vector<double>{1, NAN}, std::vector<double>{1, 1}).ok());
  EXPECT_FALSE(pg::weighted_quantile(x, std::vector<double>{1, 1}, 1.5).ok());
  EXPECT_FALSE(pg::weighted_median(std::vector<double>{}, std::vector<double>{}).ok());
}

TEST(ObservationLikelihood, CrackLengthIsGaussian) {
  const pg::CrackLengthObservation obs{12e-3, 0.3e-3};
  ASSERT_TRUE(obs.validate().ok());
  const double peak = -std::log(0.3e-3) - 0.5 * std::log(2 * std::numbers::pi);
  EXPECT_NEAR(obs.log_likelihood(12e-3), peak, 1e-12);
  EXPECT_NEAR(obs.log_likelihood(12.3e-3) - peak, -0.5, 1e-9);  // one sigma
  EXPECT_NEAR(obs.log_likelihood(11.4e-3) - peak, -2.0, 1e-9);  // two sigma
  EXPECT_FALSE((pg::CrackLengthObservation{-1e-3, 0.3e-3}).validate().ok());
  EXPECT_FALSE((pg::CrackLengthObservation{1e-3, 0.0}).validate().ok());
}

TEST(ObservationLikelihood, NoCrackWithLogLogisticPod) {
  // a50 = 2 mm, slope 3: POD(a50) = 1/2; a90 = a50 9^(1/3) -> 0.9; POD(a50/2) = 1/(1 + 2^3) = 1/9.
  const pg::NoCrackObservation obs{{2e-3, 3.0}};
  ASSERT_TRUE(obs.validate().ok());
  const double a90 = 2e-3 * std::cbrt(9.0);
  EXPECT_NEAR(obs.pod.probability_of_detection(2e-3), 0.5, 1e-15);
  EXPECT_NEAR(obs.pod.probability_of_detection(a90), 0.9, 1e-14);
  EXPECT_NEAR(obs.pod.probability_of_detection(1e-3), 1.0 / 9.0, 1e-15);
  EXPECT_EQ(obs.pod.probability_of_detection(0.0), 0.0);
  EXPECT_NEAR(obs.log_likelihood(2e-3), std::log(0.5), 1e-15);
  EXPECT_NEAR(obs.log_likelihood(a90), std::log(0.1), 1e-13);
  EXPECT_NEAR(obs.log_likelihood(1e-3), std::log(8.0 / 9.0), 1e-15);
  EXPECT_EQ(obs.log_likelihood(0.0), 0.0);  // no crack predicted: likelihood 1
  // Far beyond a50 the likelihood is tiny but its log finite: z = 3 ln(1000) = 20.72.
  EXPECT_NEAR(obs.log_likelihood(2.0), -(3 * std::log(1000.0) + std::log1p(1e-9)), 1e-9);
  // Far below, 1 - POD -> 1: ln(1 - POD) = -ln(1 + 1e-9) for a = a50 / 1000.
  EXPECT_NEAR(obs.log_likelihood(2e-6), -std::log1p(1e-9), 1e-18);
  EXPECT_FALSE((pg::PodCurve{0.0, 3.0}).validate().ok());
  EXPECT_FALSE((pg::PodCurve{1e-3, -1.0}).validate().ok());
  const std::vector<double> predicted = {0.0, 2e-3};
  const auto ll = pg::log_likelihoods(obs, predicted);
  ASSERT_EQ(ll.size(), 2U);
  EXPECT_EQ(ll[0], 0.0);
  EXPECT_NEAR(ll[1], std::log(0.5), 1e-15);
}

TEST(Metrics, RelativeAccuracy) {
  EXPECT_NEAR(*pg::relative_accuracy(100.0, 90.0), 0.9, 1e-15);
  EXPECT_NEAR(*pg::relative_accuracy(100.0, 115.0), 0.85, 1e-15);
  EXPECT_FALSE(pg::relative_accuracy(0.0, 1.0).ok());
  // Of samples: the weighted mean. {80, 100, 120, 140} with {3, 1, 0, 0}: mean 85 -> 0.85;
  // equal weights: mean 110 -> 0.9.
  const std::vector<double> x = {80, 100, 120, 140};
  EXPECT_NEAR(*pg::relative_accuracy(x, std::vector<double>{3, 1, 0, 0}, 100.0), 0.85, 1e-15);
  EXPECT_NEAR(*pg::relative_accuracy(x, std::vector<double>(4, 1.0), 100.0), 0.9, 1e-15);
}

TEST(Metrics, ProbabilityInBoundsExcludesTheBounds) {
  // ProgPy: lower < x < upper. {900, 950, 1000, 1100} in (900, 1100): 950 and 1000 -> 0.5.
  const std::vector<double> x = {900, 950, 1000, 1100};
  EXPECT_NEAR(*pg::probability_in_bounds(x, std::vector<double>(4, 1.0), 900, 1100), 0.5, 1e-15);
  // Weighted: weights {1, 2, 3, 4} -> (2 + 3) / 10.
  EXPECT_NEAR(*pg::probability_in_bounds(x, std::vector<double>{1, 2, 3, 4}, 900, 1100), 0.5,
              1e-15);
  EXPECT_NEAR(*pg::probability_in_bounds(x, std::vector<double>{1, 2, 2, 4}, 900, 1100), 4.0 / 9.0,
              1e-15);
}

TEST(Metrics, AlphaLambdaAsProgPy) {
  // True end of life 1000 cycles, predictions from cycle 0: lambda = 0.5 -> t_lambda = 500.
  const double t_lambda = pg::lambda_time(0.0, 1000.0, 0.5);
  EXPECT_EQ(t_lambda, 500.0);
  // The first prediction at or after 500 is the one at 520: bounds 1000 -+ 0.2 (1000 - 520) =
  // [904, 1096]. Its samples 850, 910, 1000, 1090, 1100, 1200: three inside -> 0.5.
  const std::vector<double> w6(6, 1.0);
  const std::vector<pg::TimeOfEventPrediction> profile = {
      {200, {5000, 5000, 5000, 5000, 5000, 5000}, w6},
      {700, {1000, 1000, 1000, 1000, 1000, 1000}, w6},
      {520, {850, 910, 1000, 1090, 1100, 1200}, w6},
      {480, {1000, 1000, 1000, 1000, 1000, 1000}, w6},
  };
  const auto met = pg::alpha_lambda(profile, 1000.0, t_lambda, 0.2, 0.5);
  ASSERT_TRUE(met.ok());
  EXPECT_EQ(met->prediction_time, 520.0);
  EXPECT_NEAR(met->bounds.lower, 904.0, 1e-12);
  EXPECT_NEAR(met->bounds.upper, 1096.0, 1e-12);
  EXPECT_NEAR(met->probability_in_bounds, 0.5, 1e-15);
  EXPECT_TRUE(met->met);
  EXPECT_FALSE(pg::alpha_lambda(profile, 1000.0, t_lambda, 0.2, 0.6)->met);
  // No prediction at or after lambda: refused.
  EXPECT_FALSE(pg::alpha_lambda(profile, 1000.0, 800.0, 0.2, 0.5).ok());
  // The cumulative relative accuracy over the profile (on ToE, as ProgPy): means 5000, 1000,
  // 1025, 1000 -> RA -3, 1, 0.975, 1 -> mean -0.00625.
  EXPECT_NEAR(*pg::cumulative_relative_accuracy(profile, 1000.0), (-3 + 1 + 0.975 + 1) / 4, 1e-14);
}

TEST(Metrics, ProbabilityOfSuccessAndCoverage) {
  // ProgPy prob_success: P(ToE > time), an unreached end of life (+inf) a success.
  // {100, 200, +inf, 300} at 200: 2 of 4.
  const std::vector<double> toe = {100, 200, kInf, 300};
  EXPECT_NEAR(*pg::probability_of_success(toe, std::vector<double>(4, 1.0), 200), 0.5, 1e-15);
  // Coverage of closed intervals: [0, 10] covers 5 and 10, not 11 -> 2/3.
  const std::vector<pg::Interval> intervals = {{0, 10}, {0, 10}, {0, 10}};
  EXPECT_NEAR(*pg::coverage(intervals, std::vector<double>{5, 10, 11}), 2.0 / 3.0, 1e-15);
  EXPECT_FALSE(pg::coverage(intervals, std::vector<double>{5}).ok());
}

}  // namespace
}  // namespace peritwin
