// B1 (docs/benchmarks.md): mode-I compact tension in Al 6061-T6 after 000 Sec. 6.1 — the PD
// fatigue crack growth, the Paris-law reference life and the A2 calibration of 000 App. A.
#pragma once

#include <string>
#include <vector>

#include "solver/fatigue/fatigue_engine.h"
#include "solver/fatigue/laws/strain_range.h"
#include "validation/specimens.h"

namespace peritwin::validation {

/// Experimental Paris law of 000 Eq. (A4): da/dN = C ΔK^M in mm/cycle with ΔK in MPa·√m.
struct ParisLaw {
  double c = 4.34e-7;
  double m = 2.6183;
};

/// Crack length from the load line (m) against cycles.
struct CrackHistory {
  std::vector<double> cycles;
  std::vector<double> crack_length;
  bool final_failure = false;
  double wall_s = 0.0;
  std::int64_t broken_bonds = 0;
  int solves = 0;
  std::string failure;  ///< why the first static solve failed (the run is empty), or empty
};

/// Composite Simpson rule of f over [a, b] with an even number of panels.
template <class F>
double integrate_simpson(F&& f, double a, double b, int panels) {
  const double h = (b - a) / panels;
  double sum = f(a) + f(b);
  for (int i = 1; i < panels; ++i) sum += (i % 2 ? 4 : 2) * f(a + i * h);
  return sum * h / 3;
}

/// Crack length at which K_max = K_c with the ASTM E647 K (000 Eq. A2).
double critical_crack_length(const CompactTensionSpec& spec, double p_max);

/// Cycles for the Paris law to grow the crack from a0 to a_end (Simpson on dN/da, 2000 panels).
double paris_life(const CompactTensionSpec& spec, const ParisLaw& paris, double p_max, double r,
                  double a_end);

/// The PD model a CT run uses; the defaults are B1's (000 Sec. 6.1: state-based, plane stress,
/// δ = 3.015Δx, the strain-range law, φ0 = 0.398).
struct CompactTensionModel {
  model::ModelOptions options;
  double horizon_ratio = 3.015;  ///< δ/Δx
  fatigue::FatigueLaw law =
      fatigue::FatigueLaw::strain_range;  ///< strain_range or energy (A1, m1, A2, m2)
  double phase_switch_damage = fatigue::kPhaseSwitchDamage2D;  ///< φ0, 000 Sec. 4.4
};

/// Runs the PD fatigue model of the CT coupon at (P_max, R) with the given strain-law parameters
/// until final failure or a crack length (from the load line) ≥ a_stop, recording the crack length
/// after every `record_every` cycles.
CrackHistory run_compact_tension(const CompactTensionSpec& spec, double dx,
                                 const fatigue::StrainLawParams& law, double p_max, double r,
                                 double a_stop, std::int64_t record_every, bool incremental,
                                 const CompactTensionModel& model = {});

/// First cycle count at which the history reaches crack length a (linear interpolation), or -1.
double cycles_at_length(const CrackHistory& history, double a);

/// Least-squares Paris constant C (with M fixed) of a PD crack history over [a_from, a_to]:
/// da/dN by central differences of the recorded history, ΔK by 000 Eq. (A2) (000 App. A, Eq.
/// A1-A3).
double fitted_paris_constant(const CompactTensionSpec& spec, const CrackHistory& history,
                             double p_max, double r, double m, double a_from, double a_to);

}  // namespace peritwin::validation
