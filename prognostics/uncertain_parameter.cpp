#include "prognostics/uncertain_parameter.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "prognostics/text.h"

namespace peritwin::prognostics {

core::Expected<UncertainParameter> UncertainParameter::lognormal(std::string name, double median,
                                                                 double coefficient_of_variation) {
  if (name.empty()) return core::Error{"name", "an uncertain parameter needs a name"};
  if (!std::isfinite(median) || median <= 0.0) {
    return core::Error{text(name, ".median"), "must be finite and > 0 (a lognormal parameter)"};
  }
  if (!std::isfinite(coefficient_of_variation) || coefficient_of_variation <= 0.0) {
    return core::Error{text(name, ".cov"), "the coefficient of variation must be finite and > 0"};
  }
  return UncertainParameter(std::move(name), median, coefficient_of_variation);
}

UncertainParameter::UncertainParameter(std::string name, double median, double cov)
    : name_(std::move(name)),
      median_(median),
      cov_(cov),
      mu_(std::log(median)),
      sigma_(std::sqrt(std::log1p(cov * cov))) {}

double UncertainParameter::sample_log(Random& random) const {
  return mu_ + sigma_ * random.standard_normal();
}

double UncertainParameter::quantile_log(double p) const {
  return mu_ + sigma_ * standard_normal_quantile(p);
}

double UncertainParameter::log_density_log(double x) const {
  const double z = (x - mu_) / sigma_;
  return -0.5 * z * z - std::log(sigma_) - 0.5 * std::log(2.0 * std::numbers::pi);
}

double UncertainParameter::log_density(double theta) const {
  if (!(theta > 0.0)) return -std::numeric_limits<double>::infinity();
  const double x = std::log(theta);
  return log_density_log(x) - x;
}

}  // namespace peritwin::prognostics
