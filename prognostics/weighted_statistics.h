// Statistics of a weighted sample {(x_i, w_i)}: the particles of the filter with their weights,
// or the end-of-life cycles of the particles under several future-load samples each (give every
// sample of particle i the weight w_i / K_i, K_i its number of samples; the functions normalize
// by W = sum w_i, so any common factor of the weights is irrelevant).
//
// A weighted sample is valid when values and weights have the same length, no value is NaN,
// every weight is finite and >= 0, and W > 0. Samples of weight 0 are ignored. Quantiles and
// probabilities accept infinite values (e.g. +inf: "no end of life within the simulated
// horizon"); means, variances and summaries need finite values.
//
// Quantile definition (the weighted inverse CDF with midpoint interpolation): sort the samples of
// positive weight by value, x_(1) <= ... <= x_(n) (ties kept in input order), S_k = the sum of
// the weights up to and including k, and give x_(k) the probability P_k = (S_k - w_(k)/2) / W
// (the middle of its step of the empirical CDF). Then
//   Q(p) = x_(1)                                                      for p <= P_1,
//          x_(k) + (p - P_k) / (P_(k+1) - P_k) * (x_(k+1) - x_(k))    for P_k <= p < P_(k+1),
//          x_(n)                                                      for p >= P_n.
// With equal weights P_k = (k - 1/2)/n: Hazen's plotting position, type 5 of Hyndman and Fan
// (1996). Between an infinite and another value, Q is the limit of the interpolation (the
// infinite one for 0 < t < 1; between -inf and +inf, the nearer end).
#pragma once

#include <span>
#include <vector>

#include "core/expected.h"

namespace peritwin::prognostics {

/// Whether (values, weights) is a valid weighted sample (above); `finite_values` also refuses
/// infinite values.
core::Status check_weighted_sample(std::span<const double> values, std::span<const double> weights,
                                   bool finite_values = false);

/// sum w_i x_i / W (finite values).
core::Expected<double> weighted_mean(std::span<const double> values,
                                     std::span<const double> weights);

/// sum w_i (x_i - mean)^2 / W: the variance of the weighted empirical distribution, no
/// small-sample correction (finite values).
core::Expected<double> weighted_variance(std::span<const double> values,
                                         std::span<const double> weights);

/// Q(p) for each p of `probabilities` (each in [0, 1]), by the definition above, in their order.
core::Expected<std::vector<double>> weighted_quantiles(std::span<const double> values,
                                                       std::span<const double> weights,
                                                       std::span<const double> probabilities);

/// Q(p) for one p in [0, 1].
core::Expected<double> weighted_quantile(std::span<const double> values,
                                         std::span<const double> weights, double probability);

/// Q(0.5).
core::Expected<double> weighted_median(std::span<const double> values,
                                       std::span<const double> weights);

/// P(x <= horizon) = sum over x_i <= horizon of w_i / W: e.g. the probability that the end of
/// life comes within the horizon.
core::Expected<double> probability_at_or_below(std::span<const double> values,
                                               std::span<const double> weights, double horizon);

/// The posterior summary of a parameter published by the twin.
struct ParameterSummary {
  double median = 0.0;                    ///< Q(0.5) of the parameter's values
  double coefficient_of_variation = 0.0;  ///< sqrt(weighted_variance) / weighted_mean
};

/// median and CoV of a positive parameter's weighted values (finite, mean > 0).
core::Expected<ParameterSummary> summarize(std::span<const double> values,
                                           std::span<const double> weights);

}  // namespace peritwin::prognostics
