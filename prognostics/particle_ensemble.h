// The particle filter over a detail's uncertain parameters: N particles, each a point x_i of the
// d log-parameters (x_ij = ln theta_ij) with a log-weight l_i, ln of its normalized weight
// w_i = exp(l_i), sum_i w_i = 1. The ensemble knows nothing of what a particle predicts: the
// caller (the twin, each particle a peridynamic engine) computes each particle's log-likelihood
// of an observation and hands the vector to update(); resampling returns the parent of each new
// particle so the caller can copy its state from the parent's.
//
// One observation step (bootstrap filter with regularization, Arulampalam et al. 2002 Alg. 4 with
// the kernel step of Musso, Oudjane, Le Gland 2001 and the shrinkage of Liu, West 2001):
//   1. update(log L):      l_i <- l_i + ln L_i, then l_i <- l_i - ln sum_j exp(l_j) (log-sum-exp
//                          with the maximum factored out, so no weight underflows to 0 by itself);
//   2. resample_if_needed: when ESS = 1 / sum w_i^2 < fraction * N, systematic resampling;
//   3. rejuvenate():       after a resampling, x_i <- a x_i + (1 - a) m + h L eps_i,
//                          m = sum w_i x_i, S = L L^T = sum w_i (x_i - m)(x_i - m)^T,
//                          eps_i ~ N(0, I).
// The kernel step puts back the diversity resampling took away (duplicates of a parent become
// distinct points). Its covariance h^2 S alone would inflate the ensemble's covariance to
// (1 + h^2) S at every step; shrinking each point toward the mean by a = sqrt(1 - h^2) first
// keeps the mean m and the covariance S in expectation over eps (a m + (1 - a) m = m,
// a^2 S + h^2 S = S): Liu and West's construction.
// Two choices of h (KernelBandwidth):
//   silverman: h = (4 / (N (d + 2)))^(1/(d+4)), the optimal bandwidth of a Gaussian kernel for a
//              Gaussian density (Silverman 1986 Sec. 4.3; Musso et al.'s h_opt), a = sqrt(1 - h^2).
//              The default: it shrinks with N as the Monte-Carlo error does (N = 64, d = 2:
//              h = 0.50; N = 2000: h = 0.28).
//   liu_west:  the discount factor delta of Liu and West: a = (3 delta - 1) / (2 delta),
//              h = sqrt(1 - a^2), whatever N (delta = 0.98: a = 0.990, h = 0.142). Smaller moves
//              for small N, where the moved parameter and the parent's copied state disagree less.
// There is no Metropolis acceptance (not a resample-move step): the kernel mixture is the
// regularized filter's approximation of the posterior density. It keeps the first two moments of
// any posterior and smooths its shape toward the Gaussian by O(h^2) (the price for a
// non-Gaussian posterior; not visible in the grid test of docs/prognostics.md).
//
// Random numbers: one xoshiro256** stream (prognostics/random.h) seeded by the settings' seed,
// drawn in a fixed order (documented at each function), and part of the state: state()/restore()
// and serialize()/deserialize() continue bit-identically, and the same seed, likelihoods and
// calls give the same particles and weights bit for bit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/expected.h"
#include "prognostics/random.h"
#include "prognostics/uncertain_parameter.h"
#include "prognostics/weighted_statistics.h"

namespace peritwin::prognostics {

/// How initialize() draws the particles from the prior.
enum class InitialSampling {
  /// Latin hypercube (McKay, Beckman, Conover 1979): per parameter j, a random permutation pi_j
  /// of 0..N-1 and x_ij = mu_j + sigma_j Phi^-1((pi_j(i) + U_ij) / N), U_ij uniform on (0, 1):
  /// each of the N equal-probability strata of each parameter holds exactly one particle, so the
  /// prior's marginals are matched far better than by independent draws.
  latin_hypercube,
  /// Independent draws x_ij = mu_j + sigma_j z_ij (Box-Muller), particle by particle.
  independent,
};

/// The bandwidth h of the rejuvenation kernel (header comment).
enum class KernelBandwidth { silverman, liu_west };

struct EnsembleSettings {
  std::size_t particles = 64;  ///< N >= 2
  std::uint64_t seed = 0;      ///< the random stream's seed
  InitialSampling initial_sampling = InitialSampling::latin_hypercube;
  KernelBandwidth bandwidth = KernelBandwidth::silverman;
  double liu_west_discount = 0.98;  ///< delta in (1/3, 1], used with KernelBandwidth::liu_west
};

/// What rejuvenate() did.
struct Rejuvenation {
  double bandwidth = 0.0;  ///< h
  double shrinkage = 1.0;  ///< a = sqrt(1 - h^2)
};

/// The posterior of one parameter: its name and ParameterSummary over the particles' theta.
struct ParameterPosterior {
  std::string name;
  ParameterSummary summary;
};

/// Everything that changes in an ensemble: enough to continue bit-identically.
struct EnsembleState {
  RandomState random;
  std::vector<double> log_parameters;  ///< N x d, row i = particle i
  std::vector<double> log_weights;     ///< N, normalized: ln sum exp = 0
};

class ParticleEnsemble {
 public:
  /// An ensemble over `parameters` (at least one, distinct names), initialized from the prior
  /// with settings.seed (initialize()).
  static core::Expected<ParticleEnsemble> create(std::vector<UncertainParameter> parameters,
                                                 const EnsembleSettings& settings);

  /// Re-seeds the stream with `seed` and draws N particles from the prior by the settings'
  /// InitialSampling; equal weights l_i = -ln N. Draw order: latin_hypercube: for each parameter
  /// j, the Fisher-Yates shuffle of pi_j (N - 1 uniform_below draws, i from N-1 down to 1), then
  /// U_1j..U_Nj; independent: particle by particle, parameter by parameter, one normal each.
  void initialize(std::uint64_t seed);

  [[nodiscard]] std::size_t size() const { return particles_; }
  [[nodiscard]] std::size_t dimension() const { return parameters_.size(); }
  [[nodiscard]] const std::vector<UncertainParameter>& parameters() const { return parameters_; }
  [[nodiscard]] const EnsembleSettings& settings() const { return settings_; }

  /// x_ij, the log-parameter j of particle i.
  [[nodiscard]] double log_parameter(std::size_t particle, std::size_t parameter) const {
    return log_parameters_[particle * dimension() + parameter];
  }
  /// theta_ij = exp(x_ij).
  [[nodiscard]] double parameter_value(std::size_t particle, std::size_t parameter) const;
  /// theta_i1..theta_id of one particle.
  [[nodiscard]] std::vector<double> parameter_values(std::size_t particle) const;
  /// x_1j..x_Nj: one log-parameter over the particles.
  [[nodiscard]] std::vector<double> log_parameter_column(std::size_t parameter) const;
  /// All x_ij, row-major (particle i at [i d, (i + 1) d)).
  [[nodiscard]] std::span<const double> log_parameters() const { return log_parameters_; }
  /// l_i (normalized: ln sum exp l_i = 0; -inf for a particle an observation ruled out).
  [[nodiscard]] std::span<const double> log_weights() const { return log_weights_; }
  /// w_i = exp(l_i).
  [[nodiscard]] std::vector<double> weights() const;
  /// ESS = 1 / sum w_i^2 (Kong, Liu, Wong 1994): N for equal weights, 1 for a single particle.
  [[nodiscard]] double effective_sample_size() const;
  /// sum_j ln p_j(x_ij): the prior log-density of particle i in log-parameter space.
  [[nodiscard]] double log_prior(std::size_t particle) const;

  /// Bayes' rule for one observation: l_i <- l_i + ln L_i, normalized by log-sum-exp. Returns the
  /// log marginal likelihood of the observation, ln sum_i w_i L_i (the old weights): very
  /// negative when the observation surprises the whole ensemble. Refused (weights unchanged):
  /// a length other than N, a NaN or +inf entry, or every particle of positive weight at
  /// ln L = -inf (no particle explains the observation).
  core::Expected<double> update(std::span<const double> log_likelihoods);

  /// Systematic resampling (Arulampalam et al. 2002 Alg. 2; Kitagawa 1996): one uniform u from
  /// the stream, positions (k + u) / N for k = 0..N-1, new particle k = the old particle i whose
  /// cumulative-weight interval [c_(i-1), c_i) holds position k (particles of weight 0 are never
  /// chosen). Particle i gets floor(N w_i) or ceil(N w_i) copies. Returns the parent of each new
  /// particle (non-decreasing); the weights become equal, l_i = -ln N.
  std::vector<std::size_t> resample();

  /// resample() when ESS < ess_fraction * N (e.g. 0.5); nullopt (nothing drawn) otherwise.
  std::optional<std::vector<std::size_t>> resample_if_needed(double ess_fraction);

  /// The regularization step of the header comment (weights unchanged). Draw order: particle by
  /// particle, d standard normals each. Directions of zero spread (a parameter all particles
  /// share) get no jitter.
  Rejuvenation rejuvenate();

  /// The weighted median and CoV of theta_j for each parameter, in the parameters' order.
  [[nodiscard]] std::vector<ParameterPosterior> posterior() const;

  [[nodiscard]] EnsembleState state() const;
  /// Continues from `state` (sizes N x d and N, finite log-parameters, no NaN or +inf weight,
  /// a nonzero random state).
  core::Status restore(const EnsembleState& state);

  /// The state as bytes: "PTPF", format version 1, N, d, the parameter names, the random state,
  /// the log-parameters and log-weights as IEEE-754 bit patterns, all little-endian, then the
  /// FNV-1a 64 of everything before it.
  [[nodiscard]] std::vector<std::uint8_t> serialize() const;
  /// Restores bytes from serialize(): refused (ensemble unchanged) on a wrong magic, version,
  /// size or checksum, or an N, d or parameter names other than this ensemble's.
  core::Status deserialize(std::span<const std::uint8_t> bytes);

 private:
  ParticleEnsemble(std::vector<UncertainParameter> parameters, const EnsembleSettings& settings);

  std::vector<UncertainParameter> parameters_;
  EnsembleSettings settings_;
  std::size_t particles_;
  Random random_;
  std::vector<double> log_parameters_;
  std::vector<double> log_weights_;
};

}  // namespace peritwin::prognostics
