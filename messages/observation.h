// An observation of a detail (issue 32): an inspection that measured a crack, or one that found
// none, at a stated cycle count. What the twin's ensemble learns from (twin/ensemble.h); read from
// a CSV file by loads/observations.h. (The bus message PERITWIN_<DETAIL>_OBSERVATION is still to
// come: docs/prognostics.md, "What is left".)
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "core/expected.h"

namespace peritwin::messages {

enum class ObservationKind {
  crack_length,  ///< a crack of length_m ± sigma_m (one standard deviation) at `origin`
  no_crack,      ///< nothing found by a method whose probability of detection is POD(a)
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
};

/// Ok, or the field that is wrong and why (the same rules as the CSV reader and the ensemble).
inline core::Status check_observation(const Observation& o) {
  if (o.cycle < 0) return core::Error{"cycle", "must be >= 0"};
  if (o.origin.empty()) return core::Error{"origin", "must be \"longest\" or a crack origin"};
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

}  // namespace peritwin::messages
