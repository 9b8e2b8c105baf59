// The particle ensemble's steps one by one: Latin-hypercube initialization, the Bayes update in
// log space, the effective sample size, systematic resampling (its copy counts and its
// unbiasedness), the rejuvenation kernel, and determinism: the same seed gives the same bits, and
// serialize -> deserialize -> continue gives the bits of never serializing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

#include "prognostics/particle_ensemble.h"
#include "prognostics/weighted_statistics.h"

namespace peritwin {
namespace {

using prognostics::EnsembleSettings;
using prognostics::ParticleEnsemble;
using prognostics::UncertainParameter;

// The demo's prior: A2 with CoV 0.3 around a calibrated value, the load scale with 0.05.
std::vector<UncertainParameter> demo_prior() {
  return {*UncertainParameter::lognormal("A2", 3.2e-3, 0.3),
          *UncertainParameter::lognormal("load_scale", 1.0, 0.05)};
}

ParticleEnsemble make(
    std::size_t n, std::uint64_t seed,
    prognostics::InitialSampling sampling = prognostics::InitialSampling::latin_hypercube) {
  EnsembleSettings settings;
  settings.particles = n;
  settings.seed = seed;
  settings.initial_sampling = sampling;
  return *ParticleEnsemble::create(demo_prior(), settings);
}

double phi(double z) { return 0.5 * std::erfc(-z / std::numbers::sqrt2); }

bool same_bits(std::span<const double> a, std::span<const double> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// A likelihood that depends on both parameters: Gaussian in ln A2 + 3 ln S around `y`.
std::vector<double> likelihood(const ParticleEnsemble& e, double y, double sigma) {
  std::vector<double> ll(e.size());
  for (std::size_t i = 0; i < e.size(); ++i) {
    const double r = (y - e.log_parameter(i, 0) - 3.0 * e.log_parameter(i, 1)) / sigma;
    ll[i] = -0.5 * r * r;
  }
  return ll;
}

TEST(ParticleEnsemble, CreateRefusesBadSettings) {
  EnsembleSettings one;
  one.particles = 1;
  EXPECT_FALSE(ParticleEnsemble::create(demo_prior(), one).ok());
  EXPECT_FALSE(ParticleEnsemble::create({}, EnsembleSettings{}).ok());
  auto twice = demo_prior();
  twice.push_back(*UncertainParameter::lognormal("A2", 1.0, 0.1));
  EXPECT_FALSE(ParticleEnsemble::create(twice, EnsembleSettings{}).ok());
  EnsembleSettings discount;
  discount.liu_west_discount = 0.3;
  EXPECT_FALSE(ParticleEnsemble::create(demo_prior(), discount).ok());
}

TEST(ParticleEnsemble, LatinHypercubeFillsEveryStratumOnce) {
  const std::size_t n = 500;
  const auto e = make(n, 17);
  for (std::size_t j = 0; j < e.dimension(); ++j) {
    const auto& prior = e.parameters()[j];
    std::vector<int> hits(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const double p = phi((e.log_parameter(i, j) - prior.mu_log()) / prior.sigma_log());
      ++hits[static_cast<std::size_t>(std::floor(p * static_cast<double>(n)))];
    }
    EXPECT_TRUE(std::all_of(hits.begin(), hits.end(), [](int h) { return h == 1; })) << j;
  }
  // Equal weights -ln N, ESS = N.
  for (const double l : e.log_weights()) EXPECT_DOUBLE_EQ(l, -std::log(500.0));
  EXPECT_NEAR(e.effective_sample_size(), 500.0, 1e-9);
}

TEST(ParticleEnsemble, PriorMomentsFromBothSamplings) {
  // N = 2000. Latin hypercube: the mean of ln A2 within 0.01 sigma (stratified: its error is far
  // below the 1/sqrt(N) = 0.022 sigma of independent draws). Independent: within 4/sqrt(N) sigma.
  for (const auto sampling :
       {prognostics::InitialSampling::latin_hypercube, prognostics::InitialSampling::independent}) {
    const auto e = make(2000, 5, sampling);
    const auto& prior = e.parameters()[0];
    const auto x = e.log_parameter_column(0);
    const auto w = e.weights();
    const double mean = *prognostics::weighted_mean(x, w);
    const double sd = std::sqrt(*prognostics::weighted_variance(x, w));
    const bool lhs = sampling == prognostics::InitialSampling::latin_hypercube;
    EXPECT_NEAR(mean, prior.mu_log(), (lhs ? 0.01 : 4 / std::sqrt(2000.0)) * prior.sigma_log());
    EXPECT_NEAR(sd / prior.sigma_log(), 1.0, lhs ? 0.01 : 4 / std::sqrt(4000.0));
  }
}

TEST(ParticleEnsemble, UpdateIsBayesInLogSpace) {
  auto e = make(4, 1);
  const double minus_inf = -std::numeric_limits<double>::infinity();
  const std::vector<double> ll = {0.0, std::log(2.0), std::log(3.0), minus_inf};
  const auto evidence = e.update(ll);
  ASSERT_TRUE(evidence.ok());
  // w = (1, 2, 3, 0) / 6; evidence = sum (1/4) L_i = 6/4.
  EXPECT_NEAR(*evidence, std::log(1.5), 1e-15);
  const auto w = e.weights();
  EXPECT_NEAR(w[0], 1.0 / 6, 1e-15);
  EXPECT_NEAR(w[1], 2.0 / 6, 1e-15);
  EXPECT_NEAR(w[2], 3.0 / 6, 1e-15);
  EXPECT_EQ(w[3], 0.0);
  EXPECT_NEAR(e.effective_sample_size(), 36.0 / 14.0, 1e-13);
  // Log-likelihoods far below exp's range change nothing: only differences matter (to the
  // rounding of l_i = -ln 4 - 5000 + ln L_i, 5000 x 2^-52 ~ 1e-12).
  auto shifted = make(4, 1);
  std::vector<double> low = ll;
  for (double& l : low) l -= 5000.0;
  ASSERT_TRUE(shifted.update(low).ok());
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(shifted.weights()[i], w[i], 1e-12);
}

TEST(ParticleEnsemble, UpdateRefusesAndKeepsTheWeights) {
  auto e = make(4, 1);
  const std::vector<double> before(e.log_weights().begin(), e.log_weights().end());
  const double minus_inf = -std::numeric_limits<double>::infinity();
  EXPECT_FALSE(e.update(std::vector<double>{0.0, 0.0, 0.0}).ok());
  EXPECT_FALSE(e.update(std::vector<double>{0.0, NAN, 0.0, 0.0}).ok());
  EXPECT_FALSE(e.update(std::vector<double>(4, std::numeric_limits<double>::infinity())).ok());
  const auto none = e.update(std::vector<double>(4, minus_inf));
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().reason.find("no particle"), std::string::npos);
  EXPECT_TRUE(same_bits(before, e.log_weights()));
}

TEST(ParticleEnsemble, SystematicResamplingCopyCounts) {
  // Particle i gets floor(N w_i) or ceil(N w_i) copies; weight-0 particles none; parents sorted.
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    auto e = make(200, seed);
    auto ll = likelihood(e, std::log(3.2e-3) + 0.3, 0.15);
    ll[7] = -std::numeric_limits<double>::infinity();
    ASSERT_TRUE(e.update(ll).ok());
    const auto w = e.weights();
    const auto parents = e.resample();
    ASSERT_TRUE(std::is_sorted(parents.begin(), parents.end()));
    std::vector<int> copies(200, 0);
    for (const auto p : parents) ++copies[p];
    for (std::size_t i = 0; i < 200; ++i) {
      const double expected = 200.0 * w[i];
      EXPECT_GE(copies[i], std::floor(expected - 1e-9)) << seed << " " << i;
      EXPECT_LE(copies[i], std::ceil(expected + 1e-9)) << seed << " " << i;
    }
    EXPECT_EQ(copies[7], 0);
    for (const double l : e.log_weights()) EXPECT_DOUBLE_EQ(l, -std::log(200.0));
  }
}

TEST(ParticleEnsemble, SystematicResamplingKeepsTheWeightedMean) {
  // The unweighted mean of ln A2 after resampling against the weighted mean before, 20 seeds,
  // N = 2000, an observation that leaves ESS ~ 0.28 N. Tolerance: 3 Monte-Carlo standard errors of
  // multinomial resampling, 3 sqrt(Var_w / N) (systematic resampling's error is smaller).
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    auto e = make(2000, seed);
    ASSERT_TRUE(e.update(likelihood(e, std::log(3.2e-3) + 0.3, 0.1)).ok());
    const auto x = e.log_parameter_column(0);
    const auto w = e.weights();
    const double mean = *prognostics::weighted_mean(x, w);
    const double variance = *prognostics::weighted_variance(x, w);
    e.resample();
    const auto y = e.log_parameter_column(0);
    const double resampled = *prognostics::weighted_mean(y, e.weights());
    EXPECT_NEAR(resampled, mean, 3.0 * std::sqrt(variance / 2000.0)) << seed;
  }
}

TEST(ParticleEnsemble, ResampleIfNeededOnlyBelowTheThreshold) {
  auto e = make(100, 2);
  const auto random_before = e.state().random;
  EXPECT_FALSE(e.resample_if_needed(0.5).has_value());  // ESS = N
  EXPECT_EQ(e.state().random, random_before);           // nothing drawn
  std::vector<double> ll(100, 0.0);
  ll[0] = 10.0;  // ESS ~ 1
  ASSERT_TRUE(e.update(ll).ok());
  EXPECT_LT(e.effective_sample_size(), 2.0);
  const auto parents = e.resample_if_needed(0.5);
  ASSERT_TRUE(parents.has_value());
  EXPECT_EQ(parents->size(), 100U);
}

TEST(ParticleEnsemble, RejuvenationBandwidths) {
  auto e = make(2000, 3);
  const auto silverman = e.rejuvenate();
  EXPECT_NEAR(silverman.bandwidth, std::pow(4.0 / (2000.0 * 4.0), 1.0 / 6.0), 1e-15);  // 0.2817
  EXPECT_NEAR(silverman.shrinkage * silverman.shrinkage + silverman.bandwidth * silverman.bandwidth,
              1.0, 1e-15);
  EnsembleSettings lw;
  lw.particles = 64;
  lw.bandwidth = prognostics::KernelBandwidth::liu_west;
  lw.liu_west_discount = 0.98;
  auto f = *ParticleEnsemble::create(demo_prior(), lw);
  const auto step = f.rejuvenate();
  EXPECT_NEAR(step.shrinkage, (3 * 0.98 - 1) / (2 * 0.98), 1e-15);                     // 0.98980
  EXPECT_NEAR(step.bandwidth, std::sqrt(1 - step.shrinkage * step.shrinkage), 1e-15);  // 0.1425
}

TEST(ParticleEnsemble, RejuvenationKeepsMeanAndCovariance) {
  // Correlated particles (after an observation of ln A2 + 3 ln S), resampled, then rejuvenated:
  // mean and covariance of the log-parameters are kept in expectation. N = 2000: the means within
  // 3 standard errors of the kernel noise h sqrt(S_jj / N), the standard deviations within 5 %.
  auto e = make(2000, 9);
  ASSERT_TRUE(e.update(likelihood(e, std::log(3.2e-3) + 0.2, 0.1)).ok());
  e.resample();
  std::vector<double> mean(2);
  std::vector<double> sd(2);
  for (std::size_t j = 0; j < 2; ++j) {
    const auto x = e.log_parameter_column(j);
    mean[j] = *prognostics::weighted_mean(x, e.weights());
    sd[j] = std::sqrt(*prognostics::weighted_variance(x, e.weights()));
  }
  const auto step = e.rejuvenate();
  for (std::size_t j = 0; j < 2; ++j) {
    const auto x = e.log_parameter_column(j);
    EXPECT_NEAR(*prognostics::weighted_mean(x, e.weights()), mean[j],
                3 * step.bandwidth * sd[j] / std::sqrt(2000.0));
    EXPECT_NEAR(std::sqrt(*prognostics::weighted_variance(x, e.weights())) / sd[j], 1.0, 0.05);
  }
  // Resampling duplicated particles; the kernel made them distinct again.
  auto x = e.log_parameter_column(0);
  std::sort(x.begin(), x.end());
  EXPECT_EQ(std::adjacent_find(x.begin(), x.end()), x.end());
}

TEST(ParticleEnsemble, RejuvenationLeavesACollapsedEnsembleInPlace) {
  // All weight on one particle: after resampling every particle is that one, S = 0, and the
  // kernel has no direction to move in (the semi-definite Cholesky gives L = 0): the particles
  // stay where they are, up to the rounding of a x + (1 - a) m with m = x.
  auto e = make(50, 4);
  std::vector<double> ll(50, -std::numeric_limits<double>::infinity());
  ll[13] = 0.0;
  ASSERT_TRUE(e.update(ll).ok());
  const double a2 = e.log_parameter(13, 0);
  const auto parents = e.resample();
  EXPECT_TRUE(std::all_of(parents.begin(), parents.end(), [](std::size_t p) { return p == 13; }));
  e.rejuvenate();
  for (std::size_t i = 0; i < 50; ++i) EXPECT_NEAR(e.log_parameter(i, 0), a2, 1e-14 * std::abs(a2));
}

// One cycle of the filter's calls, with an observation that moves with `step`.
void run_steps(ParticleEnsemble& e, int from, int to) {
  for (int step = from; step < to; ++step) {
    ASSERT_TRUE(e.update(likelihood(e, std::log(3.2e-3) + 0.05 * step, 0.2)).ok());
    e.resample_if_needed(0.9);
    e.rejuvenate();
  }
}

TEST(ParticleEnsemble, SameSeedSameBits) {
  auto a = make(300, 77);
  auto b = make(300, 77);
  run_steps(a, 0, 4);
  run_steps(b, 0, 4);
  EXPECT_TRUE(same_bits(a.log_parameters(), b.log_parameters()));
  EXPECT_TRUE(same_bits(a.log_weights(), b.log_weights()));
  EXPECT_EQ(a.state().random, b.state().random);
  auto c = make(300, 78);
  run_steps(c, 0, 4);
  EXPECT_FALSE(same_bits(a.log_parameters(), c.log_parameters()));
  // initialize(seed) restarts exactly as create with that seed.
  c.initialize(77);
  run_steps(c, 0, 4);
  EXPECT_TRUE(same_bits(a.log_parameters(), c.log_parameters()));
}

TEST(ParticleEnsemble, SerializeDeserializeContinuesBitIdentically) {
  auto never = make(300, 123);
  run_steps(never, 0, 6);

  auto interrupted = make(300, 123);
  run_steps(interrupted, 0, 3);
  const auto bytes = interrupted.serialize();
  auto restored = make(300, 999);  // another seed: everything must come from the bytes
  ASSERT_TRUE(restored.deserialize(bytes).ok()) << core::message_of(restored.deserialize(bytes));
  run_steps(restored, 3, 6);
  EXPECT_TRUE(same_bits(never.log_parameters(), restored.log_parameters()));
  EXPECT_TRUE(same_bits(never.log_weights(), restored.log_weights()));
  EXPECT_EQ(never.state().random, restored.state().random);

  // The plain struct does the same.
  auto via_state = make(300, 5);
  ASSERT_TRUE(via_state.restore(interrupted.state()).ok());
  run_steps(via_state, 3, 6);
  EXPECT_TRUE(same_bits(never.log_parameters(), via_state.log_parameters()));
}

TEST(ParticleEnsemble, DeserializeRefusesForeignOrDamagedBytes) {
  auto e = make(100, 1);
  const auto bytes = e.serialize();
  // 4 magic + 4 version + 8 N + 8 d + (4 + 2) + (4 + 10) names + 32 random + 8 (200 + 100) + 8.
  EXPECT_EQ(bytes.size(), 4U + 4 + 8 + 8 + 6 + 14 + 32 + 8 * 300 + 8);
  auto target = make(100, 2);
  const auto before = target.state();
  auto truncated = bytes;
  truncated.resize(bytes.size() - 9);
  EXPECT_FALSE(target.deserialize(truncated).ok());
  auto flipped = bytes;
  flipped[200] ^= 0x01;
  const auto damaged = target.deserialize(flipped);
  ASSERT_FALSE(damaged.ok());
  EXPECT_EQ(damaged.error().field, "checksum");
  EXPECT_FALSE(target.deserialize(std::vector<std::uint8_t>{'X', 'Y'}).ok());
  auto other_size = make(101, 1);
  EXPECT_FALSE(other_size.deserialize(bytes).ok());
  EnsembleSettings settings;
  settings.particles = 100;
  auto other_names =
      *ParticleEnsemble::create({*UncertainParameter::lognormal("A2", 1.0, 0.3),
                                 *UncertainParameter::lognormal("initial_flaw", 1.0, 0.3)},
                                settings);
  EXPECT_FALSE(other_names.deserialize(bytes).ok());
  EXPECT_TRUE(same_bits(before.log_parameters, target.log_parameters()));
  EXPECT_EQ(before.random, target.state().random);
}

TEST(ParticleEnsemble, PosteriorSummaryOfThePrior) {
  // N = 2000 by Latin hypercube: the median of theta within 1 % of the prior median, the CoV
  // within 0.01 of the prior's.
  const auto e = make(2000, 8);
  const auto posterior = e.posterior();
  ASSERT_EQ(posterior.size(), 2U);
  EXPECT_EQ(posterior[0].name, "A2");
  EXPECT_NEAR(posterior[0].summary.median / 3.2e-3, 1.0, 0.01);
  EXPECT_NEAR(posterior[0].summary.coefficient_of_variation, 0.3, 0.01);
  EXPECT_EQ(posterior[1].name, "load_scale");
  EXPECT_NEAR(posterior[1].summary.median, 1.0, 0.01);
  EXPECT_NEAR(posterior[1].summary.coefficient_of_variation, 0.05, 0.002);
}

}  // namespace
}  // namespace peritwin
