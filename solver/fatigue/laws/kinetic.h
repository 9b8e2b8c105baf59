// Law 4: the kinetic theory of fracture of 004 (Vaitkunas et al.), Eq. (12)-(16): a bond's damage n
// grows at the thermally activated breakage rate K_b (Eq. 14), integrated per cycle (Eq. 15).
#pragma once

#include <array>
#include <limits>

#include "core/expected.h"
#include "core/param_reader.h"

namespace peritwin::fatigue {
struct FatigueSettings;
}  // namespace peritwin::fatigue

namespace peritwin::fatigue {

inline constexpr double kBoltzmann = 1.380649e-23;  ///< k (J/K), exact SI 2019
inline constexpr double kPlanck = 6.62607015e-34;   ///< h (J·s), exact SI 2019

// ============================ law 4: kinetic theory of fracture (004) ============================

/// One stress segment of 004's S-N calibration ("σ ≤ 250, 250 < σ ≤ 290, σ > 290 MPa", Sec. KTF
/// symmetric model, Fig. 4a, 8b): U and γ of the bonds whose σ_max lies in (previous upper, upper].
struct KineticSegment {
  double sigma_upper = std::numeric_limits<double>::infinity();  ///< Pa; +inf for the last one
  double U = 0.0;                                                ///< J
  double gamma = 0.0;                                            ///< m^3
};

inline constexpr int kMaxKineticSegments = 3;

struct KineticParams {
  double U = 0.0;      ///< activation energy (J), 004 Eq. (13)-(14); from the S-N curve, no default
  double gamma = 0.0;  ///< activation volume (m^3), 004 Eq. (13)-(14); no default
  double lambda = 9.0;  ///< shape parameter λ, 004 Eq. (12) (value from 004 Sec. KTF)
  double n0 = 1.771;    ///< initial constant, 004 Eq. (12); 1.771 for λ = 9 (kt_n0_for_unit_life)
  double temperature = 293.0;  ///< T (K), 004 test temperature 20 °C
  double frequency = 0.56;     ///< f (Hz), 004 test frequency
};
core::Status validate(const KineticParams& p);

/// 004's parts beyond Eq. (15): the stress segments, the phase II factors and Eq. (26)'s loop
/// energy. Kept out of KineticParams on purpose: twin/detail_model.cpp hashes KineticParams'
/// bytes into every detail's signature (checkpoints resume only on an equal signature), so a
/// larger KineticParams would change the signature of every existing detail. Default: all off,
/// and the law is Eq. (15) bit for bit. (The signature should include this struct when it is not
/// the default; that line belongs to twin/.)
struct KineticExtension {
  /// 004's stress segments (Fig. 4a, 8b): 0 = KineticParams' single U, gamma for every σ; 2 or 3
  /// = segments[0..count), ascending sigma_upper, the last +inf; the reader sets segments[0] to
  /// {sigma_upper1, U, gamma}.
  int segment_count = 0;
  std::array<KineticSegment, kMaxKineticSegments> segments{};
  /// Phase II (crack growth) factors of 004 step 6 and Fig. 4b: U ← k_U·U, γ ← k_γ·γ for the bonds
  /// in phase II (FatigueSettings::phase_switch_damage; 004 uses φx ≥ 0.5). 004: k_U = 1.2,
  /// k_γ = 1. Default 1: off.
  double kU = 1.0;
  double kgamma = 1.0;
  /// 004 Eq. (26): θ = kT + ψA when A ≥ A_σy, else kT. ψ in m^3 (θ in J, A in J/m^3; 004 prints
  /// "ψ = 50" without a unit, which in SI makes θ ≈ 10^7 J: docs/kinetic.md). Default 0: off.
  double psi = 0.0;
  /// A: the hysteresis loop area per cycle (J/m^3) applied to every loaded bond, 004's "measured
  /// areas" mode (e.g. 0.78·A230 for POL, Fig. 12b). Default 0.
  double loop_area = 0.0;
  /// A_σy: the loop area at the yield limit (J/m^3), below which Eq. (26) falls back to kT.
  double loop_area_yield = 0.0;
};
core::Status validate(const KineticExtension& e);

/// k T (J): the thermal energy of 004 Eq. (14)-(15).
double kt_thermal_energy(double temperature);
/// 004 Eq. (26): θ = kT + ψ·A if A ≥ A_σy, else kT (J), with ψ in m^3 and A, A_σy in J/m^3. It
/// returns kt_thermal_energy(temperature) bit for bit when ψ·A = 0 or A < A_σy.
double kt_thermal_energy(double temperature, double psi, double loop_area, double loop_area_yield);
/// Not implemented: 004's self-heating, Eq. (17) (T = T* + ψσa²/Δt, Fertig's version for
/// composites, which 004 does not use for steel), and a loop area computed per bond (the twin's
/// bonds are linear elastic and have no loop: Eq. 26 takes the configured
/// KineticExtension::loop_area).

/// U and γ (J, m^3) of a bond at σ_max in phase 1 or 2: its stress segment (the first with
/// σ_max ≤ sigma_upper), then k_U, k_γ in phase 2 (004 step 6).
struct KineticActivation {
  double U = 0.0;
  double gamma = 0.0;
};
KineticActivation kt_activation(const KineticParams& p, const KineticExtension& e, double sigma_max,
                                int phase);
/// 004 Eq. (14): K_b = (θ/h) exp(−(U − γσ)/θ), θ = kT (or the Eq. 26 thermal energy).
double kt_breakage_rate(double sigma, double U, double gamma, double thermal_energy);
/// Per-cycle dose Φ = ∫ K_b dt over one cycle in which σ ramps linearly between Rσ_max and σ_max in
/// 1/f (the assumption behind 004 Eq. 15): Φ = θ²/(h γ f σ_max(1 − R)) e^(−U/θ) [e^(γσ_max/θ) −
/// e^(γRσ_max/θ)], evaluated overflow-safely; for R → 1 its limit (θ/(h f)) e^((γσ_max − U)/θ).
double kt_cycle_dose(double sigma_max, double load_ratio, double frequency, double U, double gamma,
                     double thermal_energy);
/// 004 Eq. (15): damage after N cycles from n_I, n = n0 − {(n0 − n_I)^(1−λ) − (1 − λ) N
/// Φ}^(1/(1−λ)); λ = 1 (not covered by the paper) uses the exact limit n0 − (n0 − n_I) e^(−NΦ).
/// Capped at n0.
double kt_damage_after_cycles(double n_initial, double cycles, double dose_per_cycle, double lambda,
                              double n0);
/// Damage increment of one cycle, Eq. (15) with N = 1 from n.
double kt_damage_increment(double n, double dose_per_cycle, double lambda, double n0);
/// n0 with ∫_0^1 dn/(n0 − n)^λ = 1 (004 Sec. KTF; 1.771 for λ = 9), by bisection. λ > 0.
double kt_n0_for_unit_life(double lambda);
/// Consumed life z(n) = ∫_0^n dn'/(n0 − n')^λ; Eq. (12) integrates to dz/dN = Φ exactly.
double kt_consumed_life(double n, double lambda, double n0);
/// Remaining life r = z(1) − z(n) (> 0 intact, <= 0 failed, n >= 1). Unlike q = 1 − n (004 Eq. 16)
/// r falls by exactly Φ per cycle at constant σ_max, R: use it with step_life/advance_life/
/// cycles_to_failure and decrement Φ. z(1) = 1 when n0 = kt_n0_for_unit_life(λ).
double kt_remaining_life(double n, double lambda, double n0);
/// Inverse of kt_remaining_life: damage n for a remaining life r (r <= 0 gives n >= 1).
double kt_damage_from_remaining_life(double remaining, double lambda, double n0);

/// Per-cycle dose of a bond of the law kinetic: kt_cycle_dose with kt_activation(p, e, σ_max,
/// phase) and θ of Eq. (26) from e (004 Eq. 14, 15, 26). 0 for σ_max <= 0.
double kt_bond_dose(const KineticParams& p, const KineticExtension& e, double sigma_max,
                    double load_ratio, int phase);

/// Config reader of the law kinetic: U, gamma > 0 required (004 Eq. 13-14), lambda > 0 and n0 > 1
/// (004 Eq. 12), temperature, frequency > 0 (004 Eq. 14-15). Segments: U2, gamma2 (and U3,
/// gamma3) > 0 with sigma_upper1 (and sigma_upper2) in Pa, ascending; kU, kgamma > 0; psi (m^3),
/// loop_area, loop_area_yield (J/m^3) >= 0. docs/kinetic.md lists them.
void read_kinetic(core::ParamReader& r, FatigueSettings& f);

}  // namespace peritwin::fatigue
