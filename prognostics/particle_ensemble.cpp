#include "prognostics/particle_ensemble.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <set>
#include <utility>

#include "core/fnv1a.h"
#include "prognostics/text.h"

namespace peritwin::prognostics {

namespace {

constexpr double kNegativeInfinity = -std::numeric_limits<double>::infinity();
constexpr std::uint32_t kFormatVersion = 1;
constexpr std::uint8_t kMagic[4] = {'P', 'T', 'P', 'F'};

// The lower-triangular Cholesky factor L (row-major d x d) of a symmetric positive semi-definite
// S: S_jj - sum_k L_jk^2 <= 1e-12 S_jj (a direction without spread, up to rounding) gives a zero
// column instead of a failure.
std::vector<double> cholesky_semidefinite(const std::vector<double>& s, std::size_t d) {
  std::vector<double> l(d * d, 0.0);
  for (std::size_t j = 0; j < d; ++j) {
    double diagonal = s[j * d + j];
    for (std::size_t k = 0; k < j; ++k) diagonal -= l[j * d + k] * l[j * d + k];
    if (!(diagonal > 1e-12 * s[j * d + j])) continue;
    const double ljj = std::sqrt(diagonal);
    l[j * d + j] = ljj;
    for (std::size_t i = j + 1; i < d; ++i) {
      double v = s[i * d + j];
      for (std::size_t k = 0; k < j; ++k) v -= l[i * d + k] * l[j * d + k];
      l[i * d + j] = v / ljj;
    }
  }
  return l;
}

// Little-endian writing and reading of the serialized state.
void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
  for (int b = 0; b < 8; ++b) out.push_back(static_cast<std::uint8_t>(v >> (8 * b)));
}
void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int b = 0; b < 4; ++b) out.push_back(static_cast<std::uint8_t>(v >> (8 * b)));
}

class ByteReader {
 public:
  explicit ByteReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  bool u64(std::uint64_t& v) {
    if (bytes_.size() - at_ < 8) return false;
    v = 0;
    for (int b = 0; b < 8; ++b) v |= std::uint64_t{bytes_[at_++]} << (8 * b);
    return true;
  }
  bool u32(std::uint32_t& v) {
    if (bytes_.size() - at_ < 4) return false;
    v = 0;
    for (int b = 0; b < 4; ++b) v |= std::uint32_t{bytes_[at_++]} << (8 * b);
    return true;
  }
  bool f64(double& v) {
    std::uint64_t bits = 0;
    if (!u64(bits)) return false;
    v = std::bit_cast<double>(bits);
    return true;
  }
  bool text(std::size_t n, std::string& v) {
    if (bytes_.size() - at_ < n) return false;
    v.assign(reinterpret_cast<const char*>(bytes_.data() + at_), n);
    at_ += n;
    return true;
  }
  [[nodiscard]] std::size_t position() const { return at_; }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = 0;
};

}  // namespace

core::Expected<ParticleEnsemble> ParticleEnsemble::create(
    std::vector<UncertainParameter> parameters, const EnsembleSettings& settings) {
  if (parameters.empty()) return core::Error{"parameters", "at least one uncertain parameter"};
  std::set<std::string> names;
  for (const auto& p : parameters) {
    if (!names.insert(p.name()).second) {
      return core::Error{"parameters", text("the name \"", p.name(), "\" is given twice")};
    }
  }
  if (settings.particles < 2) return core::Error{"particles", "must be >= 2"};
  if (!(settings.liu_west_discount > 1.0 / 3.0 && settings.liu_west_discount <= 1.0)) {
    return core::Error{"liu_west_discount", "must be in (1/3, 1]"};
  }
  return ParticleEnsemble(std::move(parameters), settings);
}

ParticleEnsemble::ParticleEnsemble(std::vector<UncertainParameter> parameters,
                                   const EnsembleSettings& settings)
    : parameters_(std::move(parameters)),
      settings_(settings),
      particles_(settings.particles),
      random_(settings.seed) {
  initialize(settings.seed);
}

void ParticleEnsemble::initialize(std::uint64_t seed) {
  random_ = Random(seed);
  const std::size_t n = particles_;
  const std::size_t d = dimension();
  log_parameters_.assign(n * d, 0.0);
  if (settings_.initial_sampling == InitialSampling::latin_hypercube) {
    // Phi^-1 of (pi(i) + U) / N, kept strictly inside (0, 1) where rounding would reach an end.
    constexpr double kLowest = std::numeric_limits<double>::min();
    const double highest = std::nextafter(1.0, 0.0);
    std::vector<std::size_t> stratum(n);
    for (std::size_t j = 0; j < d; ++j) {
      for (std::size_t i = 0; i < n; ++i) stratum[i] = i;
      for (std::size_t i = n - 1; i > 0; --i) {
        std::swap(stratum[i], stratum[random_.uniform_below(i + 1)]);
      }
      for (std::size_t i = 0; i < n; ++i) {
        const double u = 1.0 - random_.uniform();  // (0, 1]
        const double p = (static_cast<double>(stratum[i]) + u) / static_cast<double>(n);
        log_parameters_[i * d + j] = parameters_[j].quantile_log(std::clamp(p, kLowest, highest));
      }
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < d; ++j) {
        log_parameters_[i * d + j] = parameters_[j].sample_log(random_);
      }
    }
  }
  log_weights_.assign(n, -std::log(static_cast<double>(n)));
}

double ParticleEnsemble::parameter_value(std::size_t particle, std::size_t parameter) const {
  return std::exp(log_parameter(particle, parameter));
}

std::vector<double> ParticleEnsemble::parameter_values(std::size_t particle) const {
  std::vector<double> values(dimension());
  for (std::size_t j = 0; j < dimension(); ++j) values[j] = parameter_value(particle, j);
  return values;
}

std::vector<double> ParticleEnsemble::log_parameter_column(std::size_t parameter) const {
  std::vector<double> column(particles_);
  for (std::size_t i = 0; i < particles_; ++i) column[i] = log_parameter(i, parameter);
  return column;
}

std::vector<double> ParticleEnsemble::weights() const {
  std::vector<double> w(particles_);
  for (std::size_t i = 0; i < particles_; ++i) w[i] = std::exp(log_weights_[i]);
  return w;
}

double ParticleEnsemble::effective_sample_size() const {
  double sum_squares = 0.0;
  for (const double l : log_weights_) {
    const double w = std::exp(l);
    sum_squares += w * w;
  }
  return 1.0 / sum_squares;
}

double ParticleEnsemble::log_prior(std::size_t particle) const {
  double sum = 0.0;
  for (std::size_t j = 0; j < dimension(); ++j) {
    sum += parameters_[j].log_density_log(log_parameter(particle, j));
  }
  return sum;
}

core::Expected<double> ParticleEnsemble::update(std::span<const double> log_likelihoods) {
  if (log_likelihoods.size() != particles_) {
    return core::Error{"log_likelihoods", text("has ", log_likelihoods.size(), " entries for ",
                                               particles_, " particles")};
  }
  std::vector<double> updated(particles_);
  double maximum = kNegativeInfinity;
  for (std::size_t i = 0; i < particles_; ++i) {
    const double ll = log_likelihoods[i];
    if (std::isnan(ll) || ll == std::numeric_limits<double>::infinity()) {
      return core::Error{text("log_likelihoods[", i, "]"), "must not be NaN or +inf"};
    }
    updated[i] = log_weights_[i] + ll;
    maximum = std::max(maximum, updated[i]);
  }
  if (maximum == kNegativeInfinity) {
    return core::Error{"log_likelihoods",
                       "no particle explains the observation (every likelihood is 0)"};
  }
  double sum = 0.0;
  for (const double l : updated) sum += std::exp(l - maximum);
  const double log_evidence = maximum + std::log(sum);
  for (std::size_t i = 0; i < particles_; ++i) log_weights_[i] = updated[i] - log_evidence;
  return log_evidence;
}

std::vector<std::size_t> ParticleEnsemble::resample() {
  const std::size_t n = particles_;
  const std::size_t d = dimension();
  const std::vector<double> w = weights();
  std::size_t last_positive = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (w[i] > 0.0) last_positive = i;
  }
  const double u = random_.uniform();
  std::vector<std::size_t> parents(n);
  std::size_t i = 0;
  double cumulative = w[0];  // c_i
  for (std::size_t k = 0; k < n; ++k) {
    const double position = (static_cast<double>(k) + u) / static_cast<double>(n);
    while (position >= cumulative && i < last_positive) cumulative += w[++i];
    parents[k] = i;
  }
  std::vector<double> resampled(n * d);
  for (std::size_t k = 0; k < n; ++k) {
    std::copy_n(log_parameters_.begin() + static_cast<std::ptrdiff_t>(parents[k] * d), d,
                resampled.begin() + static_cast<std::ptrdiff_t>(k * d));
  }
  log_parameters_ = std::move(resampled);
  log_weights_.assign(n, -std::log(static_cast<double>(n)));
  return parents;
}

std::optional<std::vector<std::size_t>> ParticleEnsemble::resample_if_needed(double ess_fraction) {
  if (effective_sample_size() < ess_fraction * static_cast<double>(particles_)) return resample();
  return std::nullopt;
}

Rejuvenation ParticleEnsemble::rejuvenate() {
  const std::size_t n = particles_;
  const std::size_t d = dimension();
  Rejuvenation step;
  if (settings_.bandwidth == KernelBandwidth::silverman) {
    step.bandwidth = std::pow(4.0 / (static_cast<double>(n) * static_cast<double>(d + 2)),
                              1.0 / static_cast<double>(d + 4));
    step.shrinkage = std::sqrt(1.0 - step.bandwidth * step.bandwidth);
  } else {
    const double delta = settings_.liu_west_discount;
    step.shrinkage = (3.0 * delta - 1.0) / (2.0 * delta);
    step.bandwidth = std::sqrt(1.0 - step.shrinkage * step.shrinkage);
  }
  // The weighted mean m and covariance S of the log-parameters.
  const std::vector<double> w = weights();
  std::vector<double> mean(d, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < d; ++j) mean[j] += w[i] * log_parameter(i, j);
  }
  std::vector<double> covariance(d * d, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < d; ++j) {
      const double dj = log_parameter(i, j) - mean[j];
      for (std::size_t k = 0; k <= j; ++k) {
        covariance[j * d + k] += w[i] * dj * (log_parameter(i, k) - mean[k]);
      }
    }
  }
  for (std::size_t j = 0; j < d; ++j) {
    for (std::size_t k = 0; k < j; ++k) covariance[k * d + j] = covariance[j * d + k];
  }
  const std::vector<double> l = cholesky_semidefinite(covariance, d);
  std::vector<double> eps(d);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < d; ++j) eps[j] = random_.standard_normal();
    for (std::size_t j = 0; j < d; ++j) {
      double jitter = 0.0;
      for (std::size_t k = 0; k <= j; ++k) jitter += l[j * d + k] * eps[k];
      double& x = log_parameters_[i * d + j];
      x = step.shrinkage * x + (1.0 - step.shrinkage) * mean[j] + step.bandwidth * jitter;
    }
  }
  return step;
}

std::vector<ParameterPosterior> ParticleEnsemble::posterior() const {
  const std::vector<double> w = weights();
  std::vector<ParameterPosterior> result;
  result.reserve(dimension());
  for (std::size_t j = 0; j < dimension(); ++j) {
    std::vector<double> theta(particles_);
    for (std::size_t i = 0; i < particles_; ++i) theta[i] = parameter_value(i, j);
    // Valid by construction: finite positive values, normalized weights.
    const auto summary = summarize(theta, w);
    result.push_back({parameters_[j].name(), summary ? *summary : ParameterSummary{}});
  }
  return result;
}

EnsembleState ParticleEnsemble::state() const {
  return {random_.state(), log_parameters_, log_weights_};
}

core::Status ParticleEnsemble::restore(const EnsembleState& state) {
  if (state.log_parameters.size() != particles_ * dimension()) {
    return core::Error{"log_parameters",
                       text("must hold N x d = ", particles_ * dimension(), " values")};
  }
  if (state.log_weights.size() != particles_) {
    return core::Error{"log_weights", text("must hold N = ", particles_, " values")};
  }
  for (std::size_t k = 0; k < state.log_parameters.size(); ++k) {
    if (!std::isfinite(state.log_parameters[k])) {
      return core::Error{text("log_parameters[", k, "]"), "must be finite"};
    }
  }
  bool any_weight = false;
  for (std::size_t i = 0; i < particles_; ++i) {
    const double l = state.log_weights[i];
    if (std::isnan(l) || l == std::numeric_limits<double>::infinity()) {
      return core::Error{text("log_weights[", i, "]"), "must not be NaN or +inf"};
    }
    any_weight = any_weight || l != kNegativeInfinity;
  }
  if (!any_weight) return core::Error{"log_weights", "every weight is 0"};
  if (state.random == RandomState{}) return core::Error{"random", "an all-zero xoshiro state"};
  random_ = Random(state.random);
  log_parameters_ = state.log_parameters;
  log_weights_ = state.log_weights;
  return {};
}

std::vector<std::uint8_t> ParticleEnsemble::serialize() const {
  std::vector<std::uint8_t> out(std::begin(kMagic), std::end(kMagic));
  put_u32(out, kFormatVersion);
  put_u64(out, particles_);
  put_u64(out, dimension());
  for (const auto& p : parameters_) {
    put_u32(out, static_cast<std::uint32_t>(p.name().size()));
    out.insert(out.end(), p.name().begin(), p.name().end());
  }
  for (const std::uint64_t word : random_.state().words) put_u64(out, word);
  for (const double x : log_parameters_) put_u64(out, std::bit_cast<std::uint64_t>(x));
  for (const double l : log_weights_) put_u64(out, std::bit_cast<std::uint64_t>(l));
  core::Fnv1a64 checksum;
  checksum.bytes(out.data(), out.size());
  put_u64(out, checksum.get());
  return out;
}

core::Status ParticleEnsemble::deserialize(std::span<const std::uint8_t> bytes) {
  if (bytes.size() < sizeof kMagic + 8 ||
      !std::equal(std::begin(kMagic), std::end(kMagic), bytes.begin())) {
    return core::Error{"", "not a serialized particle ensemble (no \"PTPF\" header)"};
  }
  // The checksum first: every later check reads trusted bytes.
  const std::size_t body = bytes.size() - 8;
  core::Fnv1a64 checksum;
  checksum.bytes(bytes.data(), body);
  ByteReader tail(bytes.subspan(body));
  std::uint64_t stored = 0;
  if (!tail.u64(stored) || stored != checksum.get()) {
    return core::Error{"checksum", "does not match the content (truncated or corrupted)"};
  }
  ByteReader in(bytes.first(body));
  std::string magic;
  std::uint32_t version = 0;
  std::uint64_t n = 0;
  std::uint64_t d = 0;
  if (!in.text(4, magic) || !in.u32(version) || !in.u64(n) || !in.u64(d)) {
    return core::Error{"", "truncated header"};
  }
  if (version != kFormatVersion) {
    return core::Error{"version", text("format ", version, ", this build reads ", kFormatVersion)};
  }
  if (n != particles_ || d != dimension()) {
    return core::Error{"", text("holds ", n, " particles of ", d, " parameters; this ensemble has ",
                                particles_, " of ", dimension())};
  }
  for (const auto& p : parameters_) {
    std::uint32_t length = 0;
    std::string name;
    if (!in.u32(length) || !in.text(length, name)) return core::Error{"", "truncated names"};
    if (name != p.name()) {
      return core::Error{"parameters",
                         text("holds \"", name, "\" where this ensemble has \"", p.name(), "\"")};
    }
  }
  EnsembleState state;
  for (auto& word : state.random.words) {
    if (!in.u64(word)) return core::Error{"random", "truncated"};
  }
  state.log_parameters.resize(particles_ * dimension());
  for (double& x : state.log_parameters) {
    if (!in.f64(x)) return core::Error{"log_parameters", "truncated"};
  }
  state.log_weights.resize(particles_);
  for (double& l : state.log_weights) {
    if (!in.f64(l)) return core::Error{"log_weights", "truncated"};
  }
  if (in.position() != body) return core::Error{"", "trailing bytes after the state"};
  return restore(state);
}

}  // namespace peritwin::prognostics
