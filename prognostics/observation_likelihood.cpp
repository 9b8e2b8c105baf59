#include "prognostics/observation_likelihood.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace peritwin::prognostics {

core::Status CrackLengthObservation::validate() const {
  if (!std::isfinite(length_m) || length_m < 0.0) {
    return core::Error{"length_m", "must be finite and >= 0"};
  }
  if (!std::isfinite(sigma_m) || sigma_m <= 0.0) {
    return core::Error{"sigma_m", "must be finite and > 0"};
  }
  return {};
}

double CrackLengthObservation::log_likelihood(double predicted_length_m) const {
  const double z = (length_m - predicted_length_m) / sigma_m;
  return -0.5 * z * z - std::log(sigma_m) - 0.5 * std::log(2.0 * std::numbers::pi);
}

core::Status PodCurve::validate() const {
  if (!std::isfinite(a50_m) || a50_m <= 0.0) return core::Error{"pod_a50_m", "must be > 0"};
  if (!std::isfinite(slope) || slope <= 0.0) return core::Error{"pod_slope", "must be > 0"};
  return {};
}

double PodCurve::probability_of_detection(double length_m) const {
  if (!(length_m > 0.0)) return 0.0;
  const double z = slope * (std::log(length_m) - std::log(a50_m));
  // 1 / (1 + e^-z), written for both signs of z without overflow.
  if (z >= 0.0) return 1.0 / (1.0 + std::exp(-z));
  const double e = std::exp(z);
  return e / (1.0 + e);
}

double NoCrackObservation::log_likelihood(double predicted_length_m) const {
  if (!(predicted_length_m > 0.0)) return 0.0;
  const double z = pod.slope * (std::log(predicted_length_m) - std::log(pod.a50_m));
  // ln(1 - POD) = -ln(1 + e^z) = -(max(z, 0) + ln(1 + e^-|z|)).
  return -(std::max(z, 0.0) + std::log1p(std::exp(-std::abs(z))));
}

}  // namespace peritwin::prognostics
