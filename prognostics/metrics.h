// Prognostic metrics, as NASA's ProgPy defines them (github.com/nasa/progpy, src/progpy/metrics/
// and src/progpy/uncertain_data/; the same definitions as its predecessor prog_algs), extended to
// weighted samples: ProgPy's predictions are unweighted samples, and a weighted fraction with
// equal weights is ProgPy's count / n.
//
// A prediction is a set of weighted samples of the time of event (ToE: the end-of-life cycle)
// made at a prediction time t_p (the cycle the estimate was made after). The remaining life is
// RUL = ToE - t_p.
//
//  * relative accuracy (ProgPy UncertainData.relative_accuracy, after Goebel et al. 2017 p. 239):
//      RA = 1 - |r - p| / r, r the ground truth, p the MEAN of the predicted distribution.
//    ProgPy applies it to ToE (cumulative_relative_accuracy passes ToE's); Saxena et al. (2010)
//    to RUL at t_p. The two differ only in the denominator: pass RULs (ToE - t_p) for Saxena's.
//  * probability in bounds (ProgPy percentage_in_bounds of UnweightedSamples): the weighted
//    fraction with lower < x < upper, both bounds EXCLUDED.
//  * alpha-lambda (ProgPy metrics.alpha_lambda; Saxena et al. 2010): for the first prediction
//    with t_p >= lambda (ProgPy's lambda_value is a time: the cycle lambda of the way from a start
//    to the true end of life is lambda_time()), with the true ToE r,
//      bounds = [r - alpha (r - t_p), r + alpha (r - t_p)]   (RUL within +-alpha of the true RUL),
//      met <=> probability_in_bounds(bounds) >= beta.
//    The figure: alpha = 0.2 at lambda = 0.5 of life (beta is the caller's; 0.5 is the
//    usual choice in Saxena et al.).
//  * cumulative relative accuracy (ProgPy cumulative_relative_accuracy): the mean of RA over the
//    predictions of a profile (on ToE, as ProgPy).
//  * probability of success (ProgPy toe_metrics.prob_success): P(ToE > time), an infinite ToE
//    (no end of life within the simulation: ProgPy's None) counting as success.
//  * coverage: the fraction of (interval, truth) pairs with lower <= truth <= upper (closed), e.g.
//    of the 5-95 % interval of the end of life over trials; a calibrated 90 % interval covers 90 %.
#pragma once

#include <span>
#include <vector>

#include "core/expected.h"

namespace peritwin::prognostics {

/// RA = 1 - |truth - prediction| / truth; refused for truth == 0 or non-finite input.
core::Expected<double> relative_accuracy(double truth, double prediction);

/// RA with the prediction = the weighted mean of `values` (ProgPy: the distribution's mean).
core::Expected<double> relative_accuracy(std::span<const double> values,
                                         std::span<const double> weights, double truth);

/// sum of w_i over lower < x_i < upper, / W (ProgPy percentage_in_bounds: strict bounds).
core::Expected<double> probability_in_bounds(std::span<const double> values,
                                             std::span<const double> weights, double lower,
                                             double upper);

/// P(ToE > time) = sum over x_i > time of w_i / W (ProgPy prob_success).
core::Expected<double> probability_of_success(std::span<const double> times_of_event,
                                              std::span<const double> weights, double time);

struct Interval {
  double lower = 0.0;
  double upper = 0.0;
};

/// [r - alpha (r - t_p), r + alpha (r - t_p)], r the true time of event.
Interval alpha_lambda_bounds(double true_time_of_event, double prediction_time, double alpha);

/// t_lambda = start + lambda (true_time_of_event - start): Saxena's lambda (a fraction of the way
/// from `start`, e.g. the first prediction, to the end of life) as ProgPy's lambda_value.
double lambda_time(double start, double true_time_of_event, double lambda);

/// One prediction of a profile: its time and the weighted samples of the time of event.
struct TimeOfEventPrediction {
  double prediction_time = 0.0;
  std::vector<double> times_of_event;
  std::vector<double> weights;  ///< one per time of event
};

/// The verdict of alpha_lambda() and what it was made of.
struct AlphaLambda {
  bool met = false;
  double prediction_time = 0.0;        ///< the prediction evaluated
  Interval bounds;                     ///< alpha_lambda_bounds() at it
  double probability_in_bounds = 0.0;  ///< compared with beta
};

/// The alpha-lambda test of one prediction: bounds at its time, met <=> probability in bounds >=
/// beta (Saxena's alpha-lambda accuracy at every prediction from lambda on is this, called for
/// each). Refused for alpha < 0 or beta outside [0, 1].
core::Expected<AlphaLambda> alpha_lambda(const TimeOfEventPrediction& prediction,
                                         double true_time_of_event, double alpha, double beta);

/// ProgPy's alpha-lambda over a profile: the prediction with the smallest time >= lambda_time
/// (the first such in the profile's order among equal times). Refused when there is none, for
/// alpha < 0 or beta outside [0, 1].
core::Expected<AlphaLambda> alpha_lambda(std::span<const TimeOfEventPrediction> profile,
                                         double true_time_of_event, double lambda_time,
                                         double alpha, double beta);

/// The mean over the profile of relative_accuracy(prediction's samples, true ToE).
core::Expected<double> cumulative_relative_accuracy(std::span<const TimeOfEventPrediction> profile,
                                                    double true_time_of_event);

/// lower <= truth <= upper.
bool covers(const Interval& interval, double truth);

/// The fraction of i with covers(intervals[i], truths[i]); refused for unequal lengths or none.
core::Expected<double> coverage(std::span<const Interval> intervals,
                                std::span<const double> truths);

}  // namespace peritwin::prognostics
