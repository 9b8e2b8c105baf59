#include "prognostics/weighted_statistics.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "prognostics/text.h"

namespace peritwin::prognostics {

core::Status check_weighted_sample(std::span<const double> values, std::span<const double> weights,
                                   bool finite_values) {
  if (values.size() != weights.size()) {
    return core::Error{"weights",
                       text("has ", weights.size(), " entries for ", values.size(), " values")};
  }
  double total = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::string at = text("[", i, "]");
    if (std::isnan(values[i]) || (finite_values && !std::isfinite(values[i]))) {
      return core::Error{text("values", at), finite_values ? "must be finite" : "must not be NaN"};
    }
    if (!std::isfinite(weights[i]) || weights[i] < 0.0) {
      return core::Error{text("weights", at), "must be finite and >= 0"};
    }
    total += weights[i];
  }
  if (!(total > 0.0)) return core::Error{"weights", "their sum must be > 0"};
  return {};
}

core::Expected<double> weighted_mean(std::span<const double> values,
                                     std::span<const double> weights) {
  if (auto ok = check_weighted_sample(values, weights, true); !ok) return ok.error();
  double total = 0.0;
  double sum = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    total += weights[i];
    sum += weights[i] * values[i];
  }
  return sum / total;
}

core::Expected<double> weighted_variance(std::span<const double> values,
                                         std::span<const double> weights) {
  const auto mean = weighted_mean(values, weights);
  if (!mean) return mean.error();
  double total = 0.0;
  double sum = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double d = values[i] - *mean;
    total += weights[i];
    sum += weights[i] * d * d;
  }
  return sum / total;
}

namespace {

// x_a + t (x_b - x_a) for 0 < t < 1, with the limits of the header for infinite ends.
double interpolate(double xa, double xb, double t) {
  if (xa == xb) return xa;
  const bool inf_a = std::isinf(xa);
  const bool inf_b = std::isinf(xb);
  if (inf_a && inf_b) return t < 0.5 ? xa : xb;
  if (inf_a) return xa;
  if (inf_b) return xb;
  return xa + t * (xb - xa);
}

}  // namespace

core::Expected<std::vector<double>> weighted_quantiles(std::span<const double> values,
                                                       std::span<const double> weights,
                                                       std::span<const double> probabilities) {
  if (auto ok = check_weighted_sample(values, weights); !ok) return ok.error();
  for (std::size_t k = 0; k < probabilities.size(); ++k) {
    if (!(probabilities[k] >= 0.0 && probabilities[k] <= 1.0)) {
      return core::Error{text("probabilities[", k, "]"), "must be in [0, 1]"};
    }
  }
  // The samples of positive weight in (value, input position) order: a strict total order, so
  // the result does not depend on the sort's algorithm.
  std::vector<std::size_t> order;
  order.reserve(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (weights[i] > 0.0) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return values[a] < values[b] || (values[a] == values[b] && a < b);
  });
  const std::size_t n = order.size();
  std::vector<double> x(n);
  std::vector<double> position(n);  // P_k
  double total = 0.0;
  for (const std::size_t i : order) total += weights[i];
  double cumulative = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double w = weights[order[k]];
    cumulative += w;
    x[k] = values[order[k]];
    position[k] = (cumulative - 0.5 * w) / total;
  }
  std::vector<double> result;
  result.reserve(probabilities.size());
  for (const double p : probabilities) {
    if (p <= position.front()) {
      result.push_back(x.front());
    } else if (p >= position.back()) {
      result.push_back(x.back());
    } else {
      // The first k with P_k > p; then P_(k-1) <= p < P_k.
      const auto it = std::upper_bound(position.begin(), position.end(), p);
      const auto k = static_cast<std::size_t>(it - position.begin());
      const double t = (p - position[k - 1]) / (position[k] - position[k - 1]);
      result.push_back(t <= 0.0 ? x[k - 1] : interpolate(x[k - 1], x[k], t));
    }
  }
  return result;
}

core::Expected<double> weighted_quantile(std::span<const double> values,
                                         std::span<const double> weights, double probability) {
  const double p[] = {probability};
  auto q = weighted_quantiles(values, weights, p);
  if (!q) return q.error();
  return q->front();
}

core::Expected<double> weighted_median(std::span<const double> values,
                                       std::span<const double> weights) {
  return weighted_quantile(values, weights, 0.5);
}

core::Expected<double> probability_at_or_below(std::span<const double> values,
                                               std::span<const double> weights, double horizon) {
  if (auto ok = check_weighted_sample(values, weights); !ok) return ok.error();
  if (std::isnan(horizon)) return core::Error{"horizon", "must not be NaN"};
  double total = 0.0;
  double below = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    total += weights[i];
    if (values[i] <= horizon) below += weights[i];
  }
  return below / total;
}

core::Expected<ParameterSummary> summarize(std::span<const double> values,
                                           std::span<const double> weights) {
  const auto mean = weighted_mean(values, weights);
  if (!mean) return mean.error();
  if (!(*mean > 0.0)) return core::Error{"values", "their weighted mean must be > 0 for a CoV"};
  const auto variance = weighted_variance(values, weights);
  const auto median = weighted_median(values, weights);
  if (!variance) return variance.error();
  if (!median) return median.error();
  return ParameterSummary{*median, std::sqrt(*variance) / *mean};
}

}  // namespace peritwin::prognostics
