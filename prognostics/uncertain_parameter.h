// An uncertain parameter of a detail (the A2 factor of the fatigue law, the load scale of the
// sensors or the spectrum, ...) with its prior: lognormal, given as the engineer states it, a
// median and a coefficient of variation (CoV = standard deviation / mean of the parameter).
//
//   theta = exp(x),  x = ln theta ~ N(mu, sigma^2),
//   sigma = sqrt(ln(1 + CoV^2)),  mu = ln(median)
// (the lognormal's mean is exp(mu + sigma^2/2), its CoV sqrt(exp(sigma^2) - 1): the two lines
// above invert that). The filter works with x, the log-parameter: a Gaussian kernel in x keeps
// theta positive, and the prior is Gaussian there.
#pragma once

#include <string>

#include "core/expected.h"
#include "prognostics/random.h"

namespace peritwin::prognostics {

class UncertainParameter {
 public:
  /// A lognormal prior from its median (> 0) and CoV (> 0), both finite; `name` non-empty (it
  /// names the parameter in summaries and checkpoints).
  static core::Expected<UncertainParameter> lognormal(std::string name, double median,
                                                      double coefficient_of_variation);

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] double median() const { return median_; }
  [[nodiscard]] double coefficient_of_variation() const { return cov_; }
  /// mu = ln(median): the mean (and median) of the log-parameter.
  [[nodiscard]] double mu_log() const { return mu_; }
  /// sigma = sqrt(ln(1 + CoV^2)): the standard deviation of the log-parameter.
  [[nodiscard]] double sigma_log() const { return sigma_; }

  /// A draw of the log-parameter: mu + sigma z, z standard normal (Box-Muller).
  double sample_log(Random& random) const;
  /// The log-parameter at probability p of its prior: mu + sigma Phi^-1(p) (AS 241).
  [[nodiscard]] double quantile_log(double p) const;
  /// ln of the prior density of the log-parameter x: -(x - mu)^2 / (2 sigma^2) - ln sigma
  /// - ln(2 pi) / 2.
  [[nodiscard]] double log_density_log(double x) const;
  /// ln of the lognormal density of theta > 0: log_density_log(ln theta) - ln theta (the Jacobian
  /// of x = ln theta); -inf for theta <= 0.
  [[nodiscard]] double log_density(double theta) const;

 private:
  UncertainParameter(std::string name, double median, double cov);
  std::string name_;
  double median_;
  double cov_;
  double mu_;
  double sigma_;
};

}  // namespace peritwin::prognostics
