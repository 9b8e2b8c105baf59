// The likelihood of an inspection given what a particle predicts: the log-likelihood ln L_i that
// ParticleEnsemble::update() takes, from the particle's predicted crack length a_i (m) at the
// inspection's cycle. Lengths in metres.
//
//  * a crack length measured, a_obs with standard deviation sigma (Gaussian measurement error):
//      ln L(a) = -(a_obs - a)^2 / (2 sigma^2) - ln sigma - ln(2 pi) / 2;
//  * "no crack found" by an inspection with a probability of detection POD(a): the particle's
//    crack was missed with probability 1 - POD(a), so L(a) = 1 - POD(a), and L = 1 for a <= 0
//    (no crack to find).
// POD is the log-logistic curve (hit/miss data with the logit link of MIL-HDBK-1823A on ln a):
//      POD(a) = 1 / (1 + (a / a50)^(-slope)) = 1 / (1 + exp(-slope (ln a - ln a50))),
// a50 the length found half the time, slope > 0 the steepness in ln a (the logistic scale of ln a
// is 1/slope; a90 = a50 9^(1/slope)). ln(1 - POD) = -ln(1 + exp(z)), z = slope (ln a - ln a50),
// is evaluated without overflow for any z.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "core/expected.h"

namespace peritwin::prognostics {

/// A crack length measured at an inspection.
struct CrackLengthObservation {
  double length_m = 0.0;  ///< a_obs >= 0
  double sigma_m = 0.0;   ///< the measurement's standard deviation, > 0

  /// a_obs finite and >= 0, sigma finite and > 0.
  [[nodiscard]] core::Status validate() const;
  /// ln L(a) of the header (Gaussian in a_obs - a).
  [[nodiscard]] double log_likelihood(double predicted_length_m) const;
};

/// The probability-of-detection curve of an inspection method.
struct PodCurve {
  double a50_m = 0.0;  ///< the length detected with probability 1/2, > 0
  double slope = 0.0;  ///< > 0

  /// a50 and slope finite and > 0.
  [[nodiscard]] core::Status validate() const;
  /// POD(a) = 1 / (1 + (a / a50)^(-slope)); 0 for a <= 0.
  [[nodiscard]] double probability_of_detection(double length_m) const;
};

/// An inspection that found no crack.
struct NoCrackObservation {
  PodCurve pod;

  [[nodiscard]] core::Status validate() const { return pod.validate(); }
  /// ln(1 - POD(a)); 0 for a <= 0.
  [[nodiscard]] double log_likelihood(double predicted_length_m) const;
};

/// ln L of each particle's predicted length, in order: the argument of ParticleEnsemble::update().
template <typename Observation>
std::vector<double> log_likelihoods(const Observation& observation,
                                    std::span<const double> predicted_lengths_m) {
  std::vector<double> ll(predicted_lengths_m.size());
  for (std::size_t i = 0; i < ll.size(); ++i) {
    ll[i] = observation.log_likelihood(predicted_lengths_m[i]);
  }
  return ll;
}

}  // namespace peritwin::prognostics
