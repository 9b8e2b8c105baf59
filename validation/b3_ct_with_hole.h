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
  std::int64_t growth_cycles = -1;  ///< cycles to grow stop_growth (calibration runs)
  std::int64_t cycles = 0;
  std::int64_t broken_bonds = 0;
  double wall_s = 0.0;
};

/// Runs B3 at P_max (N), R = 0.1, writing damage snapshots (CSV x,y,damage) to `out_prefix`_N.csv
/// at the events; `propagation_limit` switches 002 Eq. (12)-(13) on.
/// a2: the phase II coefficient per cycle (002's 7.76e6 is per fictitious time step of its own
/// solver, not per cycle: calibrate it with calibrate_b3_a2). stop_growth > 0 ends the run when the
/// crack has grown that much along x (used by the calibration), recording `growth_cycles`.
HoleRunResult run_ct_with_hole(double dx, double p_max, bool propagation_limit, double a2,
                               const std::string& out_prefix, std::int64_t max_cycles,
                               double stop_growth = 0.0);

/// 002 Eq. (15) in integral form: A2 such that the PD crack grows its first `growth` metres in as
/// many cycles as the Paris law da/dN = 4.5e-10 (ΔK − 11.6)^2.1 (m/cycle, MPa·√m; 002 Sec. 6)
/// with the ASTM CT ΔK (000 Eq. A2). Two iterations from a2_trial.
double calibrate_b3_a2(double dx, double p_max, double a2_trial, double growth);

}  // namespace peritwin::validation
