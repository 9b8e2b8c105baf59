// The twin's strain gauges (issue 33, docs/gauges.md): each [[detail.gauge]] bound to the nodes
// of a model's grid, its influence coefficients for an engine's bond state (published in every
// STATE), and the compliance residual a gauge observation (observation_t KIND_GAUGE_COMPLIANCE,
// sent by peritwin-stream --format gauges) leaves against the model, with its alarm.
//
// A gauge observation holds, per gauge g, the compliance m_g its readings showed against the
// loads the stream identified from the gauges with the model's strain per N v^t_g (at the
// observation's angle), i.e. m_g = v^t_g · (Σ ε_g ŷ_g / Σ ŷ_g²), ŷ_g = P̂·v^t_g. If the structure
// behaves as a model X with strain per N v^X, the identification gives P̂ = k_X·P with
// k_X = Σ_h w_h v^t_h v^X_h / Σ_h w_h (v^t_h)² over the gauges h the loads were identified from
// (weighted least squares, w_h = 1/noise_h² when every one has a noise, else 1), so the observation
// predicted by X is m^X_g = v^X_g / k_X: exact for a load pattern without an angle dependence (one
// unknown P); for the two-unknown patterns (P, α) the angle is taken as identified (the
// observation's), which is the same to first order. The residual of gauge g is (m_g −
// m^X_g)/|m^X_g| with the standard deviation σ_g/|m^X_g|.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "config/config.h"
#include "core/expected.h"
#include "messages/observation.h"
#include "solver/mesh/discretization.h"
#include "solver/statics/static_solver.h"

namespace peritwin::twin {

/// A gauge is in alarm once its residual has been beyond kGaugeAlarmSigmas standard deviations
/// in kGaugeAlarmAfter gauge observations in a row (a single outlier, e.g. a block with an
/// unusual load mix, does not raise it; a crack the model does not have keeps it there).
inline constexpr double kGaugeAlarmSigmas = 4.0;
inline constexpr std::int64_t kGaugeAlarmAfter = 2;
/// ... and beyond this fraction of the model's compliance: a twin that tracks the structure still
/// leaves the crack's growth within a window and the coefficients' lag behind it (the stream
/// identifies with the last STATE's) in the residual, which the reading noise's σ (10⁻⁴ of the
/// compliance over a window of 10⁴ samples) does not cover: measured up to 1.6 % (loads from
/// every gauge) and 3.4 % (the gauge near the crack only compared) on the B1 record of its own
/// model, 12-60 % once a truth's crack leads by 0.7-1.5 mm (docs/gauges.md).
inline constexpr double kGaugeAlarmFloor = 0.05;
/// The likelihood of a gauge observation for a model's prediction m^X adds this fraction of m^X
/// to its standard deviation: the same window and lag effects, which a learning ensemble would
/// otherwise read as evidence (3 %: what a twin that tracks the structure leaves, up to 3.4 %
/// measured; at 1 % the ensemble's band collapsed and missed the truth, docs/gauges.md).
inline constexpr double kGaugeModelFraction = 0.03;

/// A configured gauge on a model's grid.
struct ModelGauge {
  config::GaugeConfig config;
  std::vector<mesh::NodeIndex> nodes;  ///< statics::gauge_nodes on that grid
};
std::vector<ModelGauge> model_gauges(const std::vector<config::GaugeConfig>& gauges,
                                     const mesh::Discretization& disc);

/// Every gauge's influence coefficients (statics::gauge_influence) for the solver's state.
std::vector<std::array<double, 3>> gauge_influences(const std::vector<ModelGauge>& gauges,
                                                    const statics::StaticSolver& solver);

/// The residuals of the last gauge observation, per configured gauge (ids as configured when it
/// was taken in; a restored checkpoint maps them by id).
struct GaugeResiduals {
  std::vector<std::string> ids;
  std::vector<double> residual;        ///< (m − m^X)/|m^X|; NaN before an observation of it
  std::vector<double> sigma;           ///< its standard deviation; NaN likewise
  std::vector<std::int64_t> in_a_row;  ///< observations in a row beyond kGaugeAlarmSigmas
  /// Empty residuals for `gauges` (NaN, 0 in a row).
  static GaugeResiduals none(const std::vector<ModelGauge>& gauges);
  /// These residuals re-keyed to `gauges` (by id; a gauge not held gets NaN and 0).
  [[nodiscard]] GaugeResiduals for_gauges(const std::vector<ModelGauge>& gauges) const;
  /// "" when no gauge is in alarm, else e.g. "gauge g1: compliance residual +6.2 % (5.1 σ) in
  /// 3 gauge observations in a row" (every gauge in alarm, in the config's order).
  [[nodiscard]] std::string alarm() const;
};

/// Per gauge of the observation, the index of the configured gauge; or which one is none
/// (Error field "gauges[i].id").
core::Expected<std::vector<std::size_t>> observed_gauge_indices(
    const messages::Observation& o, const std::vector<ModelGauge>& gauges);

/// m^X of every gauge of the observation for a model with influence coefficients `influences`
/// (indexed as the configured gauges; `indices` from observed_gauge_indices) at the observation's
/// angle. NaN where the model's gauge reads nothing (its nodes lost every bond).
std::vector<double> predicted_compliance(const messages::Observation& o,
                                         const std::vector<std::size_t>& indices,
                                         const std::vector<ModelGauge>& gauges,
                                         const std::vector<std::array<double, 3>>& influences);

/// log L of the observation given the prediction m^X: −½ Σ_g ((m_g − m^X_g)²/v_g + ln v_g) with
/// v_g = σ_g² + model_sigma_g² + (kGaugeModelFraction·m^X_g)² (Gaussian reading errors, the
/// prediction's own, the window's; the 2π constant left out; model_sigma may be empty). −∞ when a
/// prediction is NaN.
double gauge_log_likelihood(const messages::Observation& o, const std::vector<double>& predicted,
                            const std::vector<double>& model_sigma = {});

/// Updates `residuals` with the observation against the prediction (gauges not in it keep
/// their residual and their count).
void take_in(GaugeResiduals& residuals, const messages::Observation& o,
             const std::vector<std::size_t>& indices, const std::vector<double>& predicted);

}  // namespace peritwin::twin
