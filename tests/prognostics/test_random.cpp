// The random stream and the priors: splitmix64 and xoshiro256** against their reference
// algorithms, the normal quantile against AS 241 as Python's statistics.NormalDist implements
// it, the Box-Muller moments, and the lognormal prior's parameters and density.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include "prognostics/random.h"
#include "prognostics/uncertain_parameter.h"

namespace peritwin {
namespace {

using prognostics::Random;

TEST(Random, Splitmix64MatchesTheReference) {
  // The first outputs of Vigna's splitmix64.c from the state 1234567.
  std::uint64_t state = 1234567;
  EXPECT_EQ(prognostics::splitmix64(state), 6457827717110365317ULL);
  EXPECT_EQ(prognostics::splitmix64(state), 3203168211198807973ULL);
  EXPECT_EQ(prognostics::splitmix64(state), 9817491932198370423ULL);
}

TEST(Random, Xoshiro256StarStarMatchesTheReference) {
  // Seeded by four splitmix64 outputs from 42; the values from an independent Python transcription
  // of xoshiro256starstar.c (next() and jump()).
  Random random(42);
  EXPECT_EQ(random.state().words[0], 0xbdd732262feb6e95ULL);
  EXPECT_EQ(random.state().words[3], 0x581ce1ff0e4ae394ULL);
  EXPECT_EQ(random.next(), 1546998764402558742ULL);
  EXPECT_EQ(random.next(), 6990951692964543102ULL);
  EXPECT_EQ(random.next(), 12544586762248559009ULL);
  EXPECT_EQ(random.next(), 17057574109182124193ULL);
  random.jump();
  EXPECT_EQ(random.next(), 8590228844810902155ULL);
  EXPECT_EQ(random.next(), 2210021617906878354ULL);
  // uniform() = (next() >> 11) 2^-53.
  Random fresh(42);
  EXPECT_EQ(fresh.uniform(), 0.08386297105988216);
}

TEST(Random, StateRoundTripContinuesTheStream) {
  Random a(7);
  for (int i = 0; i < 5; ++i) a.next();
  Random b(a.state());
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.next(), b.next());
}

TEST(Random, UniformBelowIsUniform) {
  // 60,000 draws in [0, 3): each count within 4 binomial standard deviations (sqrt(n p (1-p)) =
  // 115.5) of 20,000.
  Random random(3);
  std::vector<int> count(3, 0);
  for (int i = 0; i < 60000; ++i) ++count[random.uniform_below(3)];
  for (const int c : count) EXPECT_NEAR(c, 20000, 4 * 115.5);
  EXPECT_EQ(random.uniform_below(1), 0U);
}

TEST(Random, BoxMullerMoments) {
  // 200,000 normals: mean within 4/sqrt(n) = 0.0089, variance within 4 sqrt(2/n) = 0.0126, the
  // fraction below -1.96 within 4 sqrt(p(1-p)/n) = 0.0019 of 0.025.
  Random random(11);
  const int n = 200000;
  double sum = 0.0;
  double sum_squares = 0.0;
  int below = 0;
  for (int i = 0; i < n; ++i) {
    const double z = random.standard_normal();
    sum += z;
    sum_squares += z * z;
    if (z < -1.959963984540054) ++below;
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 0.0, 0.0089);
  EXPECT_NEAR(sum_squares / n - mean * mean, 1.0, 0.0126);
  EXPECT_NEAR(static_cast<double>(below) / n, 0.025, 0.0019);
}

TEST(Random, NormalQuantileIsAs241) {
  // Python 3.11 statistics.NormalDist().inv_cdf (AS 241 too), to 1e-15 relative.
  EXPECT_NEAR(prognostics::standard_normal_quantile(0.975), 1.9599639845400536, 2e-15);
  EXPECT_NEAR(prognostics::standard_normal_quantile(0.3), -0.5244005127080407, 1e-15);
  EXPECT_NEAR(prognostics::standard_normal_quantile(1e-10), -6.361340902404056, 7e-15);
  EXPECT_EQ(prognostics::standard_normal_quantile(0.5), 0.0);
  EXPECT_TRUE(std::isinf(prognostics::standard_normal_quantile(0.0)));
  EXPECT_TRUE(std::isnan(prognostics::standard_normal_quantile(1.5)));
  // Phi(Phi^-1(p)) = p with Phi(x) = erfc(-x / sqrt 2) / 2, over the three branches.
  for (const double p : {1e-300, 1e-20, 0.01, 0.07, 0.2, 0.5, 0.74, 0.93, 0.999}) {
    const double x = prognostics::standard_normal_quantile(p);
    EXPECT_NEAR(0.5 * std::erfc(-x / std::numbers::sqrt2) / p, 1.0, 1e-13) << p;
  }
}

TEST(UncertainParameter, LognormalFromMedianAndCov) {
  const auto a2 = prognostics::UncertainParameter::lognormal("A2", 2.0, 0.3);
  ASSERT_TRUE(a2.ok());
  EXPECT_DOUBLE_EQ(a2->mu_log(), std::log(2.0));
  EXPECT_DOUBLE_EQ(a2->sigma_log(), std::sqrt(std::log(1.09)));  // 0.29356...
  // The lognormal density at theta = 3 by hand.
  const double s = a2->sigma_log();
  const double z = (std::log(3.0) - std::log(2.0)) / s;
  EXPECT_NEAR(a2->log_density(3.0),
              -0.5 * z * z - std::log(3.0 * s * std::sqrt(2.0 * std::numbers::pi)), 1e-14);
  EXPECT_EQ(a2->log_density(0.0), -std::numeric_limits<double>::infinity());
  // The density of ln theta integrates to 1 (midpoint rule over mu +- 10 sigma, 20,000 cells).
  double integral = 0.0;
  const double lo = a2->mu_log() - 10 * s;
  const double dx = 20 * s / 20000;
  for (int k = 0; k < 20000; ++k) integral += std::exp(a2->log_density_log(lo + (k + 0.5) * dx));
  EXPECT_NEAR(integral * dx, 1.0, 1e-12);
  // Draws: E theta = median exp(sigma^2 / 2) = 2 sqrt(1.09), CoV 0.3. 200,000 draws: the mean's
  // standard error is 0.3 E/sqrt(n) = 0.0014, the CoV's about 0.3/sqrt(2n) (1+...) ~ 0.0006.
  Random random(5);
  double sum = 0.0;
  double sum_squares = 0.0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double theta = std::exp(a2->sample_log(random));
    sum += theta;
    sum_squares += theta * theta;
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 2.0 * std::sqrt(1.09), 4 * 0.0014);
  EXPECT_NEAR(std::sqrt(sum_squares / n - mean * mean) / mean, 0.3, 0.004);
}

TEST(UncertainParameter, RefusesWhatIsNoLognormal) {
  EXPECT_FALSE(prognostics::UncertainParameter::lognormal("", 1.0, 0.3).ok());
  EXPECT_FALSE(prognostics::UncertainParameter::lognormal("A2", 0.0, 0.3).ok());
  EXPECT_FALSE(prognostics::UncertainParameter::lognormal("A2", -1.0, 0.3).ok());
  EXPECT_FALSE(prognostics::UncertainParameter::lognormal("A2", 1.0, 0.0).ok());
  EXPECT_FALSE(prognostics::UncertainParameter::lognormal("A2", 1.0, NAN).ok());
  const auto e = prognostics::UncertainParameter::lognormal("A2", 1.0, -0.1);
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.error().field, "A2.cov");
}

}  // namespace
}  // namespace peritwin
