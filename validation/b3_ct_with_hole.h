// B3 (benchmarks/README.md): modified CT with a hole in SAE 1020 after 002 Sec. 6-7 — the crack
// turns into the hole; with the propagation-phase fatigue limit a new crack nucleates on the far
// side, without it damage spreads along the old path.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "solver/geometry.h"

namespace peritwin::validation {

struct CrackEvent {
  std::string what;  ///< "enters_hole", "new_crack", "final_failure"
  std::int64_t cycle = -1;
  Point where;
};

struct HoleRunResult {
  std::vector<CrackEvent> events;
  std::int64_t cycles = 0;
  std::int64_t broken_bonds = 0;
  double wall_s = 0.0;
};

/// Runs B3 at P_max (N), R = 0.1, writing damage snapshots (CSV x,y,damage) to `out_prefix`_N.csv
/// at the events; `propagation_limit` switches 002 Eq. (12)-(13) on.
HoleRunResult run_ct_with_hole(double dx, double p_max, bool propagation_limit,
                               const std::string& out_prefix, std::int64_t max_cycles);

}  // namespace peritwin::validation
