// B3 (docs/benchmarks.md): modified CT with a hole in SAE 1020 after 002 Sec. 6-7 — the crack
// turns into the hole; with the propagation-phase fatigue limit a new crack nucleates on the far
// side, without it damage spreads along the old path.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "solver/mesh/geometry.h"

namespace peritwin::validation {

struct CrackEvent {
  /// "enters_hole"; "load_locked" (bonds break again after the load was raised, 002 Sec. 7: the
  /// load is held from here on); "new_crack" (first break on the hole's far side after entry);
  /// "old_path_crack" (first break after entry on the old crack path, away from the hole);
  /// "final_failure"; "end" (max_cycles reached).
  std::string what;
  std::int64_t cycle = -1;
  mesh::Point where;
  double p_max = 0.0;         ///< load of the block in which the event happened (N)
  double eps_inf_prop = 0.0;  ///< ε̃∞ then (002 Eq. 12; 0 without the limit)
};

/// Strain ranges (P_max(1 − R) stretch) after the crack's entry into the hole, and the cycles
/// each region needs at that load to break its first bond (000 Eq. 21 from the remaining
/// lives): the race that decides 002 Fig. 9 against Fig. 10.
struct EntryDiagnostics {
  double old_path_max_range =
      0.0;  ///< largest range of an intact phase II bond touching the old path
  double old_path_cycles = -1.0;  ///< fewest cycles to the first break there, no limit (-1: ∞)
  double old_path_cycles_limited = -1.0;  ///< the same with the limits in force (-1: never)
  double far_side_max_range = 0.0;  ///< largest range of an intact bond on the hole's far side
  double far_side_cycles = -1.0;    ///< fewest cycles to the first break there (-1: never)
  double old_path_min_life = 1.0;   ///< smallest remaining life of those old-path bonds
};

struct HoleRunResult {
  std::vector<CrackEvent> events;
  std::int64_t growth_cycles = -1;  ///< cycles to grow stop_growth (calibration runs)
  std::int64_t cycles = 0;
  std::int64_t broken_bonds = 0;
  /// Bonds broken after the entry into the hole: on the old path (within δ of its crack nodes,
  /// more than max(2δ, 2 mm) from the hole's edge), on the hole's far side (within 2δ of its edge,
  /// x past its centre), elsewhere.
  std::int64_t breaks_old_path = 0, breaks_far_side = 0, breaks_other = 0;
  double p_entry = 0.0;       ///< load when the crack entered the hole (N)
  double p_final = 0.0;       ///< load at the end of the run (N)
  double delta_k = 0.0;       ///< ΔK held while the crack grew (Pa·√m)
  double eps_bar = 0.0;       ///< ε̄ of 002 Eq. (13): mean strain range at the pre-crack tip
  double eps_inf_prop = 0.0;  ///< ε̃∞ used while the crack grew (0 without the limit)
  EntryDiagnostics entry;     ///< at the entry into the hole
  EntryDiagnostics settled;   ///< after the first window without a break (the load starts rising)
  double wall_s = 0.0;
};

/// 002 Sec. 7 loading protocol and propagation limit (reconstructed, see b3_ct_with_hole.cpp).
struct HoleProtocol {
  /// While the crack grows, P_max follows the crack so that the ASTM ΔK (000 Eq. A2) stays at its
  /// value at a0 ("loads were adjusted to maintain ΔK ≈ 20 MPa√m"); false: P_max constant.
  bool k_control = true;
  /// After the entry into the hole: every window of this many cycles without a broken bond raises
  /// P_max and ε̃∞ by `raise` (002: 0.5 % after every 300 fictitious time steps) until bonds break
  /// again; then the load is held. 0 = hold the entry load for ever. < 0 = Δx/(da/dN at ΔK): the
  /// cycles the crack took to grow one grid spacing.
  std::int64_t window = -1;
  double raise = 0.005;
  /// ε̃∞ (002 Eq. 12) while the crack grows, with the limit on. < 0: 002 Eq. (13),
  /// ε̃∞ = ε̄·ΔK_th/ΔK with ε̄ the mean strain range of the bonds of the pre-crack's tip nodes at
  /// the first block ("at the tip of the pre-crack at the first time step only", 002 Sec. 7).
  /// >= 0: this value (002 Table 2: 1e-4, for 002's own grids).
  double eps_inf_prop = -1.0;
};

/// Runs B3 from P_max at a0 (N), R = 0.1, writing damage snapshots (CSV x,y,damage) to
/// `out_prefix`_EVENT.csv at the events; `propagation_limit` switches 002 Eq. (12)-(13) on.
/// a2: the phase II coefficient per cycle (002's 7.76e6 is per fictitious time step of its own
/// solver, not per cycle: calibrate it with calibrate_b3_a2). stop_growth > 0 ends the run when the
/// crack has grown that much along x (used by the calibration), recording `growth_cycles`.
HoleRunResult run_ct_with_hole(double dx, double p_max, bool propagation_limit, double a2,
                               const std::string& out_prefix, std::int64_t max_cycles,
                               double stop_growth = 0.0, const HoleProtocol& loading = {});

/// 002 Eq. (15) in integral form: A2 such that the PD crack grows its first `growth` metres in as
/// many cycles as the Paris law da/dN = 4.5e-10 (ΔK − 11.6)^2.1 (m/cycle, MPa·√m; 002 Sec. 6)
/// under the same loading as the run (K-controlled: constant ΔK of P_max at a0, 000 Eq. A2). Two
/// iterations from a2_trial.
double calibrate_b3_a2(double dx, double p_max, double a2_trial, double growth,
                       const HoleProtocol& loading = {});

/// Paris cycles (002 Eq. 16) for the crack to grow `growth` from a0 under the loading.
double b3_paris_cycles(double p_max, double growth, const HoleProtocol& loading = {});

}  // namespace peritwin::validation
