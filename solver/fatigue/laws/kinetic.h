// Law 4: the kinetic theory of fracture of 004 (Vaitkunas et al.), Eq. (12)-(16): a bond's damage n
// grows at the thermally activated breakage rate K_b (Eq. 14), integrated per cycle (Eq. 15).
#pragma once

#include "core/expected.h"
#include "core/param_reader.h"

namespace peritwin::fatigue {
struct FatigueSettings;
}  // namespace peritwin::fatigue

namespace peritwin::fatigue {

inline constexpr double kBoltzmann = 1.380649e-23;  ///< k (J/K), exact SI 2019
inline constexpr double kPlanck = 6.62607015e-34;   ///< h (J·s), exact SI 2019

// ============================ law 4: kinetic theory of fracture (004) ============================

struct KineticParams {
  double U = 0.0;      ///< activation energy (J), 004 Eq. (13)-(14); from the S-N curve, no default
  double gamma = 0.0;  ///< activation volume (m^3), 004 Eq. (13)-(14); no default
  double lambda = 9.0;  ///< shape parameter λ, 004 Eq. (12) (value from 004 Sec. KTF)
  double n0 = 1.771;    ///< initial constant, 004 Eq. (12); 1.771 for λ = 9 (kt_n0_for_unit_life)
  double temperature = 293.0;  ///< T (K), 004 test temperature 20 °C
  double frequency = 0.56;     ///< f (Hz), 004 test frequency
};
core::Status validate(const KineticParams& p);

/// k T (J): the thermal energy of 004 Eq. (14)-(15).
double kt_thermal_energy(double temperature);
// Not implemented: 004's self-heating, Eq. (17) (T = T* + ψσa²/Δt), and its hysteresis energy,
// Eq. (26) (θ = kT + ψA above the yield loop area A_σy). The twin's bonds are linear elastic: they
// have no hysteresis loop A, and ψ is fitted in 004 to one steel's measured temperatures. The
// law runs at the configured temperature (KineticParams::temperature) instead.
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

/// Config reader of the law kinetic: U, gamma > 0 required (004 Eq. 13-14), lambda > 0 and n0 > 1
/// (004 Eq. 12), temperature, frequency > 0 (004 Eq. 14-15).
void read_kinetic(core::ParamReader& r, FatigueSettings& f);

}  // namespace peritwin::fatigue
