// An observation of a detail (issue 32): an inspection that measured a crack, or one that found
// none, at a stated cycle count. What the twin's ensemble learns from (twin/ensemble.h); read from
// a CSV file by loads::read_observations_csv, carried on PERITWIN_<DETAIL>_OBSERVATION as
// observation_t (signed like a batch; messages/codec.h decode_observation).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/expected.h"
#include "messages/batch.h"

namespace peritwin::messages {

enum class ObservationKind {
  crack_length,  ///< a crack of length_m ± sigma_m (one standard deviation) at `origin`
  no_crack,      ///< nothing found by a method whose probability of detection is POD(a)
  /// strain gauges' compliance measured against the loads identified from them (issue 33)
  gauge_compliance,
};

/// Most gauges one gauge observation holds.
inline constexpr std::size_t kMaxObservedGauges = 64;

/// One gauge of a gauge_compliance observation (observation_t's gauge_* fields): the compliance
/// its readings showed (1/N: strain per N of P at the observation's angle), its standard
/// deviation (1/N, > 0), and the model's at that angle the loads were identified with (1/N).
struct GaugeCompliance {
  std::string id;
  double compliance = 0.0;
  double sigma = 0.0;
  double model = 0.0;
  bool identifies = true;  ///< one of the gauges the loads were identified from
};

struct Observation {
  std::int64_t cycle = 0;  ///< the detail's total cycle count at the inspection
  ObservationKind kind = ObservationKind::crack_length;
  /// "longest" (the longest crack of the detail), or a crack origin as STATE reports it (a
  /// notch's name, "hole <index>", "outline").
  std::string origin = "longest";
  double length_m = std::numeric_limits<double>::quiet_NaN();   ///< crack_length: a (m, >= 0)
  double sigma_m = std::numeric_limits<double>::quiet_NaN();    ///< crack_length: σ (m, > 0)
  double pod_a50_m = std::numeric_limits<double>::quiet_NaN();  ///< no_crack: a50 (m, > 0)
  double pod_slope = std::numeric_limits<double>::quiet_NaN();  ///< no_crack: slope (> 0)
  // Who sent it (observation_t): exactly once per (source_id, seq), seq 1, 2, … per source in a
  // sequence of its own (not the batches'); the producer run's nonce (0 = none).
  std::string detail_id;
  std::string source_id;
  std::int64_t seq = 0;
  std::uint64_t nonce = 0;
  /// gauge_compliance: the gauges (ids of the detail's [[detail.gauge]], each once) and the
  /// load angle of the cycles they were measured over (rad).
  std::vector<GaugeCompliance> gauges;
  double gauge_angle_rad = 0.0;
};

/// Ok, or the field that is wrong and why (the same rules as the CSV reader and the ensemble).
inline core::Status check_observation(const Observation& o) {
  if (o.cycle < 0) return core::Error{"cycle", "must be >= 0"};
  if (o.origin.empty() || o.origin.size() > 64 ||
      o.origin.find_first_of("\n\r\t") != std::string::npos) {
    return core::Error{"origin", "must be \"longest\" or a crack origin (1 to 64 characters)"};
  }
  if (o.kind == ObservationKind::gauge_compliance) {
    if (o.gauges.empty() || o.gauges.size() > kMaxObservedGauges) {
      return core::Error{"gauges",
                         "must hold 1 to " + std::to_string(kMaxObservedGauges) + " gauges"};
    }
    if (!std::isfinite(o.gauge_angle_rad)) {
      return core::Error{"gauge_angle_rad", "must be a finite angle"};
    }
    for (std::size_t g = 0; g < o.gauges.size(); ++g) {
      const GaugeCompliance& c = o.gauges[g];
      const std::string at = "gauges[" + std::to_string(g) + "]";
      if (c.id.empty() || c.id.size() > 32)
        return core::Error{at + ".id", "must be 1 to 32 characters"};
      for (std::size_t h = 0; h < g; ++h) {
        if (o.gauges[h].id == c.id) return core::Error{at + ".id", "gauge \"" + c.id + "\" twice"};
      }
      if (!std::isfinite(c.compliance)) return core::Error{at + ".compliance", "must be finite"};
      if (!(std::isfinite(c.sigma) && c.sigma > 0)) {
        return core::Error{at + ".sigma", "must be a finite standard deviation > 0"};
      }
      if (!std::isfinite(c.model)) return core::Error{at + ".model", "must be finite"};
    }
    if (std::none_of(o.gauges.begin(), o.gauges.end(),
                     [](const GaugeCompliance& g) { return g.identifies; })) {
      return core::Error{"gauges", "no gauge identified the loads (gauge_identifies all 0)"};
    }
    return {};
  }
  if (!o.gauges.empty())
    return core::Error{"gauges", "only a gauge_compliance observation has gauges"};
  if (o.kind == ObservationKind::crack_length) {
    if (!(std::isfinite(o.length_m) && o.length_m >= 0)) {
      return core::Error{"length_m", "must be a finite length >= 0"};
    }
    if (!(std::isfinite(o.sigma_m) && o.sigma_m > 0)) {
      return core::Error{"sigma_m", "must be a finite standard deviation > 0"};
    }
  } else {
    if (!(std::isfinite(o.pod_a50_m) && o.pod_a50_m > 0)) {
      return core::Error{"pod_a50_m", "must be a finite length > 0"};
    }
    if (!(std::isfinite(o.pod_slope) && o.pod_slope > 0)) {
      return core::Error{"pod_slope", "must be finite and > 0"};
    }
  }
  return {};
}

/// Everything about an observation message that needs no bookkeeping, as check_batch: WRONG_DETAIL
/// or INVALID with the field path "observation.<field>", else applied.
inline Outcome check_observation_message(const Observation& o, std::string_view detail_id) {
  if (o.detail_id != detail_id) {
    return {Verdict::wrong_detail, "observation.detail_id",
            "detail_id \"" + o.detail_id + "\" does not match the channel's detail \"" +
                std::string(detail_id) + "\""};
  }
  if (!is_valid_source_id(o.source_id)) {
    return {Verdict::invalid, "observation.source_id",
            "source_id must be 1 to " + std::to_string(kMaxSourceIdLength) +
                " printable ASCII characters without blanks"};
  }
  if (o.seq < 1) {
    return {Verdict::invalid, "observation.seq",
            "seq = " + std::to_string(o.seq) + " must be >= 1"};
  }
  if (const core::Status st = check_observation(o); !st) {
    return {Verdict::invalid, "observation." + st.error().field, st.error().reason};
  }
  return {};
}

}  // namespace peritwin::messages
