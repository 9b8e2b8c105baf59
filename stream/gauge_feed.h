// peritwin-stream --format gauges (issue 33, docs/gauges.md): lines "t,<strain of each gauge>"
// after the header "time_s,<gauge id>,..." -> P and α per sample (stream/gauge_identification.h,
// from the model's newest influence coefficients) for the rainflow counter; and, over the samples
// since the last one, the gauges' compliance as an observation (observation_t
// KIND_GAUGE_COMPLIANCE) for the twin's residual, alarm and ensemble (twin/gauges.h).
//
// The compliance of gauge g over a window of samples: with ŷ_g = the model's strain of the
// identified load (LoadIdentifier::model_strain), the least-squares slope ρ_g = Σ ε_g ŷ_g / Σ ŷ_g²
// of the measured strain on it, reported as m_g = ρ_g · v_g(ᾱ) (strain per N at the window's
// angle ᾱ, the |P|-weighted mean of the identified angles; v_g(α) = c0 + c1 cos α + c2 sin α),
// with the standard deviation noise_g · |v_g(ᾱ)| / sqrt(Σ ŷ_g²) (the slope's, for independent
// reading errors; without a configured noise the RMS of ε_g − ŷ_g over the window stands in), and
// the model's v_g(ᾱ) it was measured against (observation_t.gauge_model).
#pragma once

#include <cstdint>
#include <optional>
#include <peritwin_msgs/damage_state_t.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "core/expected.h"
#include "messages/observation.h"
#include "stream/gauge_identification.h"

namespace peritwin::stream {

/// The influence coefficients of every gauge a STATE lists (message set version 10).
std::vector<GaugeInfluence> influences_of(const peritwin_msgs::damage_state_t& state);

/// A sample whose load was identified.
struct IdentifiedSample {
  double t = 0.0;
  IdentifiedLoad load;
};

class GaugeFeed {
 public:
  /// The header line: the columns, checked against the model's gauges; the loads are identified
  /// from the columns `identify_with` names (LoadIdentifier::create; empty: every column), the
  /// others only compared (a gauge near the crack: its coefficients are the most sensitive to
  /// the difference between the model's crack and the structure's, docs/gauges.md).
  core::Status header(std::string_view line, const std::vector<GaugeInfluence>& influence,
                      const std::vector<std::string>& identify_with = {});
  [[nodiscard]] bool has_header() const { return identifier_.has_value(); }
  /// Newer coefficients (a STATE after bonds broke); on refusal the old ones stay.
  core::Status update(const std::vector<GaugeInfluence>& influence);
  /// One data line: the identified sample (its strains taken into the window's sums), nothing
  /// (a blank or comment line), or why it is no sample.
  core::Expected<std::optional<IdentifiedSample>, std::string> line(std::string_view text);
  /// The window's compliance as an observation (detail, source, seq and cycle left to the
  /// caller); nullopt when the window saw no load. The window starts afresh.
  std::optional<messages::Observation> take_observation();
  [[nodiscard]] const LoadIdentifier& identifier() const { return *identifier_; }
  /// Every column of the header, in its order.
  [[nodiscard]] const std::vector<std::string>& columns() const { return columns_; }
  /// The model's strain of column g (any column) for the load (p, alpha).
  [[nodiscard]] double model_strain(std::size_t g, double p, double alpha) const;
  [[nodiscard]] std::uint64_t window_samples() const { return window_.samples; }

 private:
  struct Window {
    std::vector<double> strain_times_model, model_squared, residual_squared;
    double abs_p = 0.0, abs_p_alpha = 0.0;
    std::uint64_t samples = 0;
  };
  void reset_window();
  /// Every column's coefficients from `influence`, or why not (a column the model lacks).
  core::Status take_coefficients(const std::vector<GaugeInfluence>& influence);
  std::optional<LoadIdentifier> identifier_;
  std::vector<std::string> columns_;
  std::vector<std::size_t> identifying_;          ///< the identifier's columns' positions here
  std::vector<std::array<double, 3>> per_basis_;  ///< per column
  std::vector<double> noise_;                     ///< per column
  std::vector<double> subset_;                    ///< scratch: the identifying strains
  Window window_;
  std::vector<double> residuals_;  ///< scratch
};

}  // namespace peritwin::stream
