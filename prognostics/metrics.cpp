#include "prognostics/metrics.h"

#include <cmath>
#include <string>

#include "prognostics/text.h"
#include "prognostics/weighted_statistics.h"

namespace peritwin::prognostics {

core::Expected<double> relative_accuracy(double truth, double prediction) {
  if (!std::isfinite(truth) || truth == 0.0) {
    return core::Error{"truth", "must be finite and nonzero"};
  }
  if (!std::isfinite(prediction)) return core::Error{"prediction", "must be finite"};
  return 1.0 - std::abs(truth - prediction) / truth;
}

core::Expected<double> relative_accuracy(std::span<const double> values,
                                         std::span<const double> weights, double truth) {
  const auto mean = weighted_mean(values, weights);
  if (!mean) return mean.error();
  return relative_accuracy(truth, *mean);
}

core::Expected<double> probability_in_bounds(std::span<const double> values,
                                             std::span<const double> weights, double lower,
                                             double upper) {
  if (auto ok = check_weighted_sample(values, weights); !ok) return ok.error();
  if (std::isnan(lower) || std::isnan(upper)) return core::Error{"bounds", "must not be NaN"};
  double total = 0.0;
  double inside = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    total += weights[i];
    if (values[i] > lower && values[i] < upper) inside += weights[i];
  }
  return inside / total;
}

core::Expected<double> probability_of_success(std::span<const double> times_of_event,
                                              std::span<const double> weights, double time) {
  const auto failed = probability_at_or_below(times_of_event, weights, time);
  if (!failed) return failed.error();
  return 1.0 - *failed;
}

Interval alpha_lambda_bounds(double true_time_of_event, double prediction_time, double alpha) {
  const double spread = alpha * (true_time_of_event - prediction_time);
  return {true_time_of_event - spread, true_time_of_event + spread};
}

double lambda_time(double start, double true_time_of_event, double lambda) {
  return start + lambda * (true_time_of_event - start);
}

core::Expected<AlphaLambda> alpha_lambda(const TimeOfEventPrediction& prediction,
                                         double true_time_of_event, double alpha, double beta) {
  if (!(alpha >= 0.0) || !std::isfinite(alpha)) return core::Error{"alpha", "must be >= 0"};
  if (!(beta >= 0.0 && beta <= 1.0)) return core::Error{"beta", "must be in [0, 1]"};
  AlphaLambda result;
  result.prediction_time = prediction.prediction_time;
  result.bounds = alpha_lambda_bounds(true_time_of_event, prediction.prediction_time, alpha);
  const auto inside = probability_in_bounds(prediction.times_of_event, prediction.weights,
                                            result.bounds.lower, result.bounds.upper);
  if (!inside) return inside.error();
  result.probability_in_bounds = *inside;
  result.met = *inside >= beta;
  return result;
}

core::Expected<AlphaLambda> alpha_lambda(std::span<const TimeOfEventPrediction> profile,
                                         double true_time_of_event, double lambda_time,
                                         double alpha, double beta) {
  const TimeOfEventPrediction* chosen = nullptr;
  for (const auto& prediction : profile) {
    if (prediction.prediction_time >= lambda_time &&
        (chosen == nullptr || prediction.prediction_time < chosen->prediction_time)) {
      chosen = &prediction;
    }
  }
  if (chosen == nullptr) {
    return core::Error{"profile",
                       text("no prediction at or after lambda (cycle ", lambda_time, ")")};
  }
  return alpha_lambda(*chosen, true_time_of_event, alpha, beta);
}

core::Expected<double> cumulative_relative_accuracy(std::span<const TimeOfEventPrediction> profile,
                                                    double true_time_of_event) {
  if (profile.empty()) return core::Error{"profile", "has no prediction"};
  double sum = 0.0;
  for (std::size_t k = 0; k < profile.size(); ++k) {
    const auto ra =
        relative_accuracy(profile[k].times_of_event, profile[k].weights, true_time_of_event);
    if (!ra) return ra.error().within(text("profile[", k, "]."));
    sum += *ra;
  }
  return sum / static_cast<double>(profile.size());
}

bool covers(const Interval& interval, double truth) {
  return interval.lower <= truth && truth <= interval.upper;
}

core::Expected<double> coverage(std::span<const Interval> intervals,
                                std::span<const double> truths) {
  if (intervals.size() != truths.size()) {
    return core::Error{"truths", "one per interval"};
  }
  if (intervals.empty()) return core::Error{"intervals", "none given"};
  std::size_t covered = 0;
  for (std::size_t i = 0; i < intervals.size(); ++i) {
    if (covers(intervals[i], truths[i])) ++covered;
  }
  return static_cast<double>(covered) / static_cast<double>(intervals.size());
}

}  // namespace peritwin::prognostics
