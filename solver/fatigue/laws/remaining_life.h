// The remaining-life arithmetic shared by the fatigue laws (000 Eq. 14, 18-19, 38-39): phases,
// and λ stepped by exact repeated subtraction.
//
// Units: SI throughout. Stretches and strain ranges are dimensionless, stresses Pa, lengths m,
// volumes m^3, energies J, energy release rates J/m^2, temperatures K, frequencies Hz, activation
// volumes m^3, hysteresis loop areas as the caller's ψ expects (ψ·A must be in J). The fatigue
// constants A_i keep the units implied by their laws (A_i ε^m_i is dimensionless per cycle).
//
// Paper prefixes: 000 Nguyen et al. (energy-based PD fatigue), 002 Zhang & Bobaru
// (propagation-phase fatigue limit), 003 Bazazzadeh et al. (bilinear bond + fatigue degradation),
// 004 Vaitkunas et al. (kinetic theory of fracture).
//
// ---- Remaining-life arithmetic contract (laws 1, 2 and the KTF remaining life) ----------------
// Per cycle the remaining life is updated by ONE double subtraction, `lambda = step_life(lambda,
// d)` (i.e. `lambda -= d`), 000 Eq. (18), (19), (38), (39). This repeated-subtraction form is the
// reference ("per-cycle oracle"). `advance_life(lambda, d, k)` returns bit-for-bit the value of k
// such subtractions in O(log(lambda/d)) time, and `cycles_to_failure(lambda, d)` the exact number
// of them needed to reach lambda <= 0. Because k1 subtractions followed by k2 subtractions are
// k1+k2 subtractions, block stepping with ANY split of a constant-load stretch into blocks is
// bit-identical to per-cycle stepping; the engine may commit lambda after every block. (The
// multiplication form lambda0 - k*d was rejected: it is only identical if both modes re-anchor
// lambda0 at exactly the same cycles.) Note that the iterated count can differ from the
// real-arithmetic lambda/d by many cycles when d is tiny compared with ulp(lambda): each
// subtraction really removes d rounded to a multiple of ulp(lambda); that is why cycles_to_failure
// emulates the rounding exactly instead of correcting a closed-form estimate by a few cycles.
// Assumes IEEE-754 binary64 with round-to-nearest-even (no -ffast-math in the translation unit that
// iterates).
#pragma once

#include <cstdint>
#include <limits>

namespace peritwin::fatigue {

/// Returned by cycles_to_failure when the iteration never reaches lambda <= 0.
inline constexpr std::int64_t kNeverFails = std::numeric_limits<std::int64_t>::max();
/// 000 Sec. 4.4: damage index switching a point's bonds to phase II in 2D (δ = 3Δx); [54] used 0.5.
inline constexpr double kPhaseSwitchDamage2D = 0.398;

enum class Phase : std::uint8_t {
  kNucleation = 1,  ///< phase I, 000 Eq. (17)-(18) / (37)-(38)
  kGrowth = 2,      ///< phase II, 000 Eq. (19) / (39), optional limit 002 Eq. (12)
};

// ============================ remaining-life arithmetic (see contract above) =====================

/// One cycle of 000 Eq. (18)/(19): the canonical per-cycle update `lambda - d`.
inline double step_life(double lambda, double decrement) { return lambda - decrement; }

/// Value of `lambda` after k >= 0 applications of step_life, bit-identical to the loop, also past
/// failure (negative lambda). O(number of binades crossed) for decrement >= 0 (NaN/inf inputs are
/// fixed points after <= 2 steps); decrement < 0 (not a fatigue decrement) falls back to the loop.
double advance_life(double lambda, double decrement, std::int64_t k);

/// Smallest n >= 1 such that n applications of step_life give a value <= 0, exactly as iterating
/// (n = 1 whenever lambda - decrement <= 0, including lambda already <= 0). kNeverFails when the
/// iteration stalls or increases (decrement <= 0, NaN, or decrement < ulp(lambda)/2 somewhere) or
/// the count would exceed int64.
/// Cost: O(log2(lambda/d)) binades crossed, ~35 ns each on the build machine (~0.7 µs at 2^19).
std::int64_t cycles_to_failure(double remaining_life, double decrement_per_cycle);

/// Cheap guaranteed bracket lo <= cycles_to_failure(lambda, d) <= hi (hi may be kNeverFails), from
/// the per-step rounding error |fl(x − d) − (x − d)| <= ulp(lambda)/2. Relative width
/// ~ulp(lambda)/d: lets the engine find the next failing bond with few exact evaluations.
struct CycleBounds {
  std::int64_t lo = 1;
  std::int64_t hi = kNeverFails;
};
CycleBounds cycles_to_failure_bounds(double remaining_life, double decrement_per_cycle);

}  // namespace peritwin::fatigue
