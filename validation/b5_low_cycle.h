// B5 (issue 35, docs/validation.md): paper 004's strain-controlled low-cycle fatigue of a 316L
// specimen, by 004's own scheme: elastoplastic bonds (statics/elastoplastic.h) brought through
// the turning points of each strain cycle, the kinetic theory of fracture per bond (004 Eq. 15,
// or Eq. 26 with the loop area), and a jump to the next bond break once the cycles repeat, until
// the maximum stress has dropped by 25 % (N25).
//
// The specimen (004 Sec. 3): the gauge 5 mm × 25 mm as a 2D bond-based strip (plane stress,
// thickness 5 mm), 17 points across (Δx = 5/17 mm), δ = 3.1Δx, the bottom δ layer fixed, the top
// δ layer moved in y (held in x), P = the nominal strain (the top layer's displacement over the
// distance between the two layers' mid-lines); bonds break only in the middle third (004 Fig. 7a,
// lost: a decision); E per point from N(193 GPa, 3 GPa²) with a fixed seed (004 Sec. 3).
//
// Loadings (004 Fig. 6, reconstructed from its text): symmetric ±0.18 %; POL blocks of one
// ±0.6 % cycle (up first: 004 names the order for PUL only) then 200 cycles between −0.24 % and
// −0.60 %; PUL blocks of one ∓0.6 % cycle starting in compression then 200 cycles between +0.24 %
// and +0.60 %.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/expected.h"
#include "solver/fatigue/laws/kinetic.h"
#include "solver/fatigue/laws/kinetic_calibration.h"
#include "solver/model/bond_plasticity.h"
#include "solver/statics/specimen.h"

namespace peritwin::validation {

/// A strain cycle: its two turning points in the order they are reached, repeated `count` times.
struct StrainCycle {
  double first = 0.0;
  double second = 0.0;
  std::int64_t count = 1;
};

/// 004 Fig. 6's three loadings as repeating blocks of strain cycles.
struct StrainLoading {
  std::string name;  ///< symmetric | pol | pul
  std::vector<StrainCycle> block;
  /// The cycle whose upper turning point's reaction is the "maximum stress" of N25 (the block's
  /// main cycle: the 200 small cycles of POL/PUL).
  std::size_t measured = 0;
};
StrainLoading symmetric_loading(double amplitude = 0.0018);
StrainLoading pol_loading();
StrainLoading pul_loading();

struct B5Specimen {
  double width = 0.005;
  double length = 0.025;
  double thickness = 0.005;
  int points_across = 17;
  double horizon_ratio = 3.1;
  double youngs_modulus = 193e9;
  double youngs_modulus_std = 3e9;
  std::uint64_t seed = 4;
  double failure_zone = 1.0 / 3.0;  ///< the middle fraction of the length where bonds break
};

/// The strip as a ready-to-solve specimen (P = the nominal strain on the top layer).
statics::Specimen make_b5_specimen(const B5Specimen& spec);

/// The kinetic law of 004 as B5 applies it, per bond: segment (U, γ) by σ_max (004's three S–N
/// segments) and U·k_U, γ·k_γ once an end of the bond has φ ≥ phase_switch (004 step 6), both by
/// fatigue::kt_activation; θ of Eq. (26) with the bond's loop area A_b = (A_i + A_j)/2 from the
/// model's own loops, or the extension's fixed loop_area (004's measured-area mode).
struct B5Kinetics {
  fatigue::KineticParams base;          ///< λ, n0, T, f; U, γ of a single segment
  fatigue::KineticExtension extension;  ///< segments, k_U, k_γ, ψ, A, A_σy
  double phase_switch = 0.5;            ///< φx of 004 step 6
  bool own_loop_area = false;           ///< A from the model's loops instead of loop_area
};

/// 004's S–N segments of σ_max (Pa): "σ ≤ 250, 250 < σ ≤ 290, σ > 290 MPa", each fitted on the
/// points in [from, to] (the curve saturates at 295 MPa).
struct B5Segment {
  double from, to, upper;
};
inline constexpr B5Segment kB5Segments[3] = {
    {210e6, 250e6, 250e6},
    {250e6, 290e6, 290e6},
    {290e6, 294e6, std::numeric_limits<double>::infinity()}};
/// The Masing loop area (J/m³) of the symmetric cycle with stress amplitude σ on the curve.
double loop_area_at_stress(const model::PowerLawCurve& curve, double sigma);
/// U, γ per segment fitted (fatigue::kt_calibrate_segment, R = −1) on NUREG/CR-6909 through the
/// curve, a point every 2 MPa, with θ = kT + ψ·A(segment midpoint) (ψ = 0: kT, the conventional
/// model); k_U as given. `fits` (optional) receives each segment's fit and θ.
struct B5SegmentFit {
  fatigue::KineticFit fit;
  double theta = 0.0;
  double loop_area = 0.0;
};
core::Expected<B5Kinetics> calibrate_b5_kinetics(const model::PowerLawCurve& curve, double psi,
                                                 double k_u,
                                                 std::vector<B5SegmentFit>* fits = nullptr);

/// NUREG/CR-6909 Rev. 0 (Chopra and Shack, 2007), mean air curve of austenitic stainless steel:
/// ln N = 6.891 − 1.920·ln(ε_a − 0.112), ε_a in % († docs/kinetic.md: it gives 004's 171,517
/// cycles at 0.18 %).
double nureg_6909_ss_life(double strain_amplitude);
/// The strain of the monotonic curve at stress σ (0 < σ < σ∞): the inverse of
/// model::PowerLawCurve::stress (the larger of the two branches' inverses, as g = min of them).
double curve_strain(const model::PowerLawCurve& curve, double stress);

struct B5Options {
  double kappa = 0.0;  ///< stretch per strain; 0: calibrate on the virgin strip at 0.18 %
  double critical_stretch = 8.23e-3;  ///< 004: s_c
  /// The stress of 004 Eq. (14): true, its σ_xx' = (σ_x + σ_x')/2 from the bond's two points'
  /// stresses (ElastoplasticSolver::node_stress); false, the bond's own stress on the curve.
  bool point_stress = true;
  double stress_drop = 0.25;  ///< N25
  std::int64_t max_cycles = 20'000'000;
  double newton_tolerance = 1e-10;
  /// Jump whole blocks once a block repeats the one before (004's next-break step); false: every
  /// block solved (the oracle; runs of equal cycles inside a block are still taken at once).
  bool jump = true;
  /// Called with (cycle, strains, stresses) of the specimen's loop (σ = reaction/area) whenever
  /// the count passes one of `loop_cycles` (the loop then in force, traced in 2×`loop_steps`).
  std::vector<std::int64_t> loop_cycles;
  int loop_steps = 24;
  std::function<void(std::int64_t, const std::vector<double>&, const std::vector<double>&)> loop;
};

struct B5Result {
  std::int64_t n25_cycles = -1;  ///< -1: not reached (see reason)
  std::int64_t cycles = 0;
  /// The turning-point solve failed (Newton found no equilibrium; docs/solver.md): with a crack
  /// running, the strip no longer carries the imposed strain in the model.
  bool lost_equilibrium = false;
  /// N25, else (lost equilibrium after bonds broke) the cycle it was lost in: a lower bound of N25
  /// (the stress had not dropped by 25 % at the last solve); −1 otherwise.
  std::int64_t life_cycles = -1;
  std::int64_t broken_bonds = 0;
  std::int64_t static_breaks = 0;  ///< by s ≥ s_c
  std::int64_t break_groups = 0;
  std::int64_t phase_two_breaks = 0;  ///< bonds broken with k_U, k_γ in force
  std::int64_t turning_points = 0;
  std::int64_t newton_iterations = 0;
  std::int64_t stalled_turning_points = 0;  ///< accepted at a residual <= 1e-4 (statics)
  std::int64_t substepped_turning_points = 0;
  int deepest_memory = 0;              ///< the most open Masing reversals of a bond at the end
  std::int64_t dropped_reversals = 0;  ///< Masing memory overflows (model/bond_plasticity.h)
  double peak_stress = 0.0;            ///< Pa, the largest measured σ = R/A
  double final_stress = 0.0;           ///< Pa, at the end
  double kappa = 0.0;
  double wall_s = 0.0;
  std::string reason;  ///< why it stopped
};

/// The specimen's stress σ = R/A (Pa) at the virgin strip's first loading to `strain`.
double virgin_stress(const statics::Specimen& strip, const model::PowerLawCurve& curve,
                     double kappa, double strain);
/// κ that makes the virgin strip's σ = R/A at `strain` equal to the curve's (bisection).
double calibrate_b5_kappa(const statics::Specimen& strip, const model::PowerLawCurve& curve,
                          double strain);

/// Runs one loading to N25 (or max_cycles, or a failure).
B5Result run_b5_loading(const statics::Specimen& strip, const model::PowerLawCurve& curve,
                        const StrainLoading& loading, const B5Kinetics& kinetics,
                        const B5Options& options);

}  // namespace peritwin::validation
