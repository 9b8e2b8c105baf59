// The A2 calibration of 000 App. A on an ASTM E647 compact-tension coupon, shared by
// peritwin-validate (B1) and peritwin-calibrate (any material, grid and model): PD runs of the CT
// coupon, each compared with the Paris-law life in integral form (docs/solver.md), A2 rescaled
// until the two lives agree. Units: SI (m, N, Pa) except the Paris constants (ParisLaw).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "validation/b1_compact_tension.h"

namespace peritwin::validation {

/// The units a Paris constant C is given in (da/dN = C ΔK^M).
enum class ParisUnits {
  mm_per_cycle_mpa,  ///< mm/cycle with ΔK in MPa·√m (000 Eq. A4; ParisLaw's own units)
  m_per_cycle_pa,    ///< m/cycle with ΔK in Pa·√m (SI)
  m_per_cycle_mpa,   ///< m/cycle with ΔK in MPa·√m (002 Sec. 7)
};

/// C given in `units` as ParisLaw's C (mm/cycle, MPa·√m), for exponent m.
double paris_c_in_mm_mpa(double c, double m, ParisUnits units);

/// The PD life and the Paris life (integral form) to the crack length where K_max = K_c.
struct LifeComparison {
  double p_max = 0.0;       ///< N
  double r = 0.0;           ///< load ratio
  double a_end = 0.0;       ///< crack length from the load line at K_max = K_c (m)
  double pd_life = 0.0;     ///< cycles; NaN if the PD crack never reached a_end
  double paris_life = 0.0;  ///< cycles
  double wall_s = 0.0;      ///< wall time of the PD run
  std::int64_t broken_bonds = 0;
  [[nodiscard]] double relative_error() const { return pd_life / paris_life - 1.0; }
};

/// How the next A2 is chosen from the runs so far.
enum class A2Step {
  /// 000 Eq. (26b) after every run: A2 ← A2·C_exp/C_trial = A2·N_PD/N_Paris (B1's loop).
  eq26b,
  /// Eq. (26b) after the first run; from the second on, the two-point model N_PD = N1 + k/A2
  /// fitted to the last two runs, solved for N_PD = N_Paris. Eq. (26b) assumes the PD life scales
  /// as 1/A2, but the cycles of phase I at the notch (A1, m1) do not; they are ~30 % of B1's life
  /// at Δx = 1 mm, and Eq. (26b) then closes only ~70 % of the gap per run.
  two_point,
};

struct CalibrationSetup {
  CompactTensionSpec coupon;        ///< geometry and material
  ParisLaw paris;                   ///< the reference Paris law (mm/cycle, MPa·√m)
  double dx = 0.001;                ///< Δx (m)
  CompactTensionModel model;        ///< PD model, δ/Δx, law, φ0
  fatigue::StrainLawParams law;     ///< A1, m1, ε∞, m2 (= M, 000 Eq. 25); law.A2 = first trial
  double p_max = 4000.0;            ///< calibration load (N)
  double r = 0.1;                   ///< calibration load ratio
  std::int64_t record_every = 250;  ///< cycles between crack-length records
  A2Step step = A2Step::two_point;
  double tolerance = 0.005;  ///< stop once |N_PD/N_Paris − 1| ≤ this (0: never)
  int max_runs = 8;          ///< PD runs at most
};

struct CalibrationRun {
  double a2 = 0.0;  ///< the A2 of this run
  LifeComparison life;
  CrackHistory history;  ///< the PD crack length against cycles
};

struct CalibrationResult {
  std::vector<CalibrationRun> runs;
  /// Converged: the A2 of the last run (whose life is within tolerance). Otherwise the next A2
  /// the step rule gives after the last run (not run itself); NaN if the runs give no A2.
  double a2 = 0.0;
  bool converged = false;
  std::string failure;  ///< why there is no A2 (empty otherwise)
};

/// The PD life of the coupon at (P_max, R) with `law`, and the Paris life, both to the crack
/// length where the ASTM K_max (000 Eq. A2) reaches K_c. `history` receives the PD crack history.
LifeComparison compare_lives(const CalibrationSetup& setup, const fatigue::StrainLawParams& law,
                             double p_max, double r, CrackHistory* history = nullptr);

/// The A2 to run after `runs` (at least one, each with a finite PD life) by setup.step.
double next_a2(const CalibrationSetup& setup, const std::vector<CalibrationRun>& runs);

/// 000 App. A: PD runs from setup.law.A2, each followed by the step rule, until the PD life is
/// within tolerance of the Paris life or max_runs runs are done. `on_run` sees each run.
CalibrationResult calibrate_a2(const CalibrationSetup& setup,
                               const std::function<void(const CalibrationRun&)>& on_run = {});

/// The load putting K_max at a0 at the fraction of K_c that B1's 4 kN does (0.206): 4 kN scaled
/// by K_c/48.7 MPa·√m, B/10 mm and √(W/50 mm) (ASTM K ∝ P/(B√W) at fixed a/W).
double default_calibration_load(const CompactTensionSpec& coupon);

/// A first A2 from B1's calibration (1301 at Δx = 1 mm, δ = 3.015 mm, E = 68 GPa, C = 4.34e-7
/// mm/cycle, M = 2.6183): a bond at the tip strains by about ΔK/(E√δ), and the crack advances Δx
/// per bond life, so C_SI ≈ Δx·A2·(ΔK/(E√δ))^M/ΔK^M, i.e. A2 ∝ C_SI·(E√δ)^M/Δx (which holds 000
/// Eq. 27 at a fixed δ/Δx). A trial only: the O(1) factors differ between M, models and planes.
double a2_first_trial(const CompactTensionSpec& coupon, const ParisLaw& paris, double dx,
                      double horizon_ratio);

/// Why the coupon cannot be discretized at dx (the crack line y = 0 must fall midway between two
/// node rows: 0.6W/Δx whole; at least 8 rows over the ligament), or nothing.
std::optional<std::string> coupon_grid_problem(const CompactTensionSpec& coupon, double dx);

}  // namespace peritwin::validation
