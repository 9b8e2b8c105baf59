// B6 (issue 36): the double cantilever beam of 003 Sec. 6.5 under opposing end moments, with the
// bilinear bond and each of 003's three fatigue degradation laws (Eq. 47, 49, 50); the slope of
// crack length against cycles over the grid ratio m = δ/Δl and the cycle increment ΔN. The DCB
// builder and the run are shared with B7 (003 Sec. 6.6, validation/b7_dcb_paris.h).
// Units: SI (m, N, Pa, N·m).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "solver/fatigue/laws/bilinear.h"
#include "solver/model/pd_model.h"
#include "solver/statics/specimen.h"

namespace peritwin::validation {

/// A DCB: the rectangle [0, L] × [−H/2, H/2] (two arms of height H/2 each), thickness B, a
/// pre-crack along y = 0 from x = 0 to x = a. The arms' free ends (the first column of nodes)
/// carry opposing moments ±M as a linear distribution of x-forces over the end nodes (per unit P
/// = 1 N·m: F_i = ±(y_i − y_c)/Σ(y_j − y_c)², which opens the crack); the last column x = L is
/// clamped. Only bonds with both ends in the band |y| < δ (the bonds that can cross the
/// crack plane) and beyond x = a − δ may soften and break: the arms are no-fail zones. 003's DCB
/// is a homogeneous PD body, but its figures are lost; with pure-moment loading the arms carry
/// the bending strain 6M/(B h² E) over their whole length, which would fatigue the arms' fibres
/// at a rate comparable to the tip's (the third law has no threshold), so the crack is confined
/// to its plane as a delamination is.
struct DcbSpec {
  double length = 0.0161;      ///< L (003 Sec. 6.5)
  double height = 0.0029;      ///< H = 2h, both arms (003's "W")
  double thickness = 0.001;    ///< B: not given by 003 Sec. 6.5 (chosen; G scales as 1/B²)
  double crack = 0.005;        ///< a, pre-crack length from the loaded end
  double youngs = 70e9;        ///< E
  double poisson = 1.0 / 3.0;  ///< bond-based: 1/3 in plane stress, 1/4 in plane strain (fixed)
  model::PlaneCondition plane = model::PlaneCondition::plane_stress;
  double gc = 0.0;             ///< G_c of the bilinear bond (J/m²)
  double kr = 20.0;            ///< k_r = G_c/G_0 = s_c/s_0, 003 Eq. (44)
  double horizon = 3.75e-4;    ///< δ_H
  double horizon_ratio = 3.0;  ///< m = δ/Δl (Δl rounded so that y = 0 lies between node rows)
};

/// Δl: the nearest spacing to δ/m with an even number of node rows over H (y = 0 between rows).
double dcb_spacing(const DcbSpec& spec);
/// The model's bending modulus of an arm: E (plane stress) or E/(1 − ν²) with ν = 1/4 (plane
/// strain, bond-based).
double dcb_bending_modulus(const DcbSpec& spec);
/// 003 Eq. (56): G = M²/(B E I), I = B h³/12 of one arm (h = H/2), E the bending modulus.
double dcb_energy_release_rate(const DcbSpec& spec, double moment);
/// The moment at which Eq. (56) gives G.
double dcb_moment_for(const DcbSpec& spec, double g);

statics::Specimen make_dcb(const DcbSpec& spec);

/// The bilinear bond's s0, sc (003 Eq. 43-44) for the spec's G_c, k_r, E, δ and plane condition;
/// the law's coefficients are left as given.
fatigue::BilinearParams dcb_bond(const DcbSpec& spec, fatigue::BilinearParams law);

/// G of the intact DCB from its compliance: the generalized rotation θ = Σ F_i·u_i / M (work
/// conjugate of M, both arms) at pre-crack lengths a ± k·Δl; G = M²/(2B)·dC/da, C = θ/M.
double dcb_compliance_energy_release_rate(const DcbSpec& spec, double moment, int k = 2);

struct DcbRun {
  DcbSpec spec;
  fatigue::BilinearParams law;  ///< law and its coefficients; s0, sc from dcb_bond
  double moment = 0.048;        ///< M_a (N·m)
  std::int64_t delta_n = 1000;  ///< ΔN
  double max_cycles = 1e8;
  double stop_growth = 0.001;  ///< stop when the crack has grown this much (m)
  /// The slope is the least-squares fit of crack length against cycles over growth in
  /// [fit_from, fit_to] (m), past the start-up of the fatigue zone.
  double fit_from = 0.0003, fit_to = 0.001;
  bool progress = false;  ///< a line on stderr every 20 increments
};

struct DcbResult {
  std::vector<double> cycles, crack;  ///< effective crack length (m, from the loaded end)
  double slope = 0.0;                 ///< m/cycle; NaN when the window was not reached
  /// max/min − 1 of the local rate (secant over quarters of the window's middle half)
  double rate_variation = 0.0;
  double dx = 0.0, horizon = 0.0;
  std::int64_t broken = 0, increments = 0, unconverged = 0;
  bool failed = false;
  std::string failure;
  double wall_s = 0.0;
};

/// Runs the DCB at constant moment (the load held at its peak, 003 Sec. 4) in increments of ΔN
/// until the crack has grown `stop_growth`, failure, or max_cycles. Crack length: a0 plus the
/// number of broken bonds that cross y = 0 beyond a0 over the number of crossing bonds per unit
/// length of the plane (an effective length: the farthest break jumps by whole bond rows).
DcbResult run_dcb(const DcbRun& run);

/// Least-squares slope of y against x over the points with y in [lo, hi]; NaN with < 3 points.
double fitted_slope(const std::vector<double>& x, const std::vector<double>& y, double lo,
                    double hi);

/// B6's reconstructed inputs (003 Sec. 6.5 gives neither G_c nor the laws' Table 2): G_c with
/// G(M_a)/G_c = 0.25 by Eq. (56) (M_a = 0.048 N·m, B = 1 mm: G = 130 J/m², G = 5 G_0 with k_r = 20,
/// so the static ramp damages the bonds at the tip, as 003 says), and each law's coefficients
/// (b6_dcb.cpp: law 3's A fixed, laws 1 and 2 calibrated to law 3's slope).
double b6_critical_energy_release_rate(const DcbSpec& spec);
fatigue::BilinearParams b6_law(int law);
DcbRun b6_run(int law, double horizon_ratio, std::int64_t delta_n, double horizon = 3.75e-4);

/// One B6 configuration, printed as its JSON line (peritwin-validate --case B6 --law L ...);
/// `coefficient` > 0 replaces the law's A, C or B.
int run_b6_single(int law, double horizon_ratio, std::int64_t delta_n, double horizon,
                  double coefficient, double max_cycles);

/// B6 as peritwin-validate --case B6: JSON lines and docs/figures-style PNGs into out_dir.
/// The three laws side by side: slope against ΔN per (law, m) from B6 JSON lines (any mix of
/// study and single lines; horizon-study lines left out) into a PNG.
int plot_b6_slopes(const std::string& jsonl, const std::string& png);

/// `only_law` > 0: that law alone (its slopes and crack PNGs, its δ-convergence).
int run_b6(const std::string& out_dir, bool quick, int only_law = 0);

}  // namespace peritwin::validation
