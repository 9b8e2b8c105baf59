// Remaining-life arithmetic (000 Eq. 18-19, 38-39); see remaining_life.h for the contract.
#include "solver/fatigue/laws/remaining_life.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace peritwin::fatigue {

namespace {

constexpr std::int64_t kTwo52 = std::int64_t{1} << 52;
constexpr std::int64_t kTwo53 = std::int64_t{1} << 53;

// ---------------------------------------------------------------------------------------------
// Exact emulation of repeated IEEE subtraction. A positive finite double x lies in a binade whose
// representable numbers are the integers a times 2^q (a < 2^53; a >= 2^52 for normal x). While the
// exact result of x - d stays in the same binade (and positive), fl(x - d) = (a - D) 2^q, where D
// is d/2^q rounded to the nearest integer, with ties (d/2^q = f + 1/2) going to the even result:
// after at most one step a is even and D is the even one of f, f + 1. So a run of such steps is one
// integer subtraction. Steps that leave the binade are done in hardware. Adding (for negative x,
// whose magnitude grows) is the mirror image.

struct Binade {
  int q = 0;             // x = a * 2^q exactly
  std::int64_t a = 0;    // integer significand
  std::int64_t low = 0;  // smallest a of the binade (2^52; 0 for subnormals)
};

Binade binade_of(double x) {  // x > 0, finite: read the IEEE fields directly (hot path)
  const auto bits = std::bit_cast<std::uint64_t>(x);
  const auto biased = static_cast<int>(bits >> 52);
  const auto fraction = static_cast<std::int64_t>(bits & ((std::uint64_t{1} << 52) - 1));
  if (biased == 0) return {-1074, fraction, 0};
  return {biased - 1075, fraction | kTwo52, kTwo52};
}

// v * 2^k, exact for the values used here (v an integer < 2^54, or d scaled by the ulp).
double scale(double v, int k) {
  if (k >= -1022 && k <= 1023) {
    return v * std::bit_cast<double>(static_cast<std::uint64_t>(k + 1023) << 52);
  }
  return std::ldexp(v, k);
}

// floor(num / den) for 0 <= num < 2^54, 0 < den < 2^54: a double division (much cheaper than an
// int64 one) corrected by at most a step or two to the exact integer quotient.
std::int64_t quotient(std::int64_t num, std::int64_t den) {
  auto q = static_cast<std::int64_t>(static_cast<double>(num) / static_cast<double>(den));
  while (q > 0 && q * den > num) --q;
  while ((q + 1) * den <= num) ++q;
  return q;
}

// Rounded step D (in units of 2^q) for t = d/2^q in [0, 2^53), or -1 when t is a tie and a is odd
// (the next step must be taken in hardware to reach an even a). Also returns floor(t), ceil(t).
struct Step {
  std::int64_t step = 0;
  std::int64_t floor = 0;
  std::int64_t ceil = 0;
};
Step rounded_step(double t, std::int64_t a) {
  Step s;
  s.floor = static_cast<std::int64_t>(t);                // truncation == floor for t >= 0
  const double frac = t - static_cast<double>(s.floor);  // exact
  s.ceil = s.floor + (frac > 0.0 ? 1 : 0);
  if (frac == 0.5) {
    s.step = a % 2 != 0 ? -1 : (s.floor % 2 == 0 ? s.floor : s.floor + 1);
  } else {
    s.step = frac < 0.5 ? s.floor : s.floor + 1;
  }
  return s;
}

// Up to `budget` steps x <- fl(x - d) for x > d > 0 that stay in x's binade and positive, taken in
// one integer subtraction. Returns the number taken (0: do the next step in hardware). Sets
// `stalled` when a step would not change x (then x never changes again).
std::int64_t bulk_subtract(double& x, double d, std::int64_t budget, bool& stalled) {
  const Binade b = binade_of(x);
  const Step s = rounded_step(scale(d, -b.q), b.a);  // t exact and < 2^53 because d < x
  if (s.step < 0) return 0;
  // The step from a_i is in-binade and positive iff a_i - t >= low and a_i - t > 0.
  const std::int64_t room = b.a - std::max(b.low + s.ceil, s.floor + 1);
  if (room < 0) return 0;
  if (s.step == 0) {
    stalled = true;
    return 0;
  }
  const std::int64_t taken = std::min(quotient(room, s.step) + 1, budget);
  x = scale(static_cast<double>(b.a - taken * s.step), b.q);
  return taken;
}

// Up to `budget` steps y <- fl(y + d) for y > 0, d > 0 that stay below the top of y's binade.
std::int64_t bulk_add(double& y, double d, std::int64_t budget, bool& stalled) {
  if (!(y > 0.0) || !std::isfinite(y)) return 0;
  const Binade b = binade_of(y);
  const double t = scale(d, -b.q);
  if (!(t < static_cast<double>(kTwo53))) return 0;  // leaves the binade at once
  const Step s = rounded_step(t, b.a);
  if (s.step < 0) return 0;
  // The step from a_i keeps ulp 2^q iff a_i + t < 2^53, i.e. a_i <= 2^53 - 1 - floor(t).
  const std::int64_t room = kTwo53 - 1 - s.floor - b.a;
  if (room < 0) return 0;
  if (s.step == 0) {
    stalled = true;
    return 0;
  }
  const std::int64_t taken = std::min(quotient(room, s.step) + 1, budget);
  y = scale(static_cast<double>(b.a + taken * s.step), b.q);
  return taken;
}

}  // namespace

// ============================ remaining-life arithmetic =========================================

double advance_life(double lambda, double decrement, std::int64_t k) {
  if (k <= 0) return lambda;
  if (decrement < 0.0) {  // increasing iterate: not a fatigue decrement, plain loop
    for (std::int64_t i = 0; i < k; ++i) lambda = step_life(lambda, decrement);
    return lambda;
  }
  if (!std::isfinite(decrement) || !std::isfinite(lambda)) {  // NaN/inf: fixed after <= 2 steps
    for (std::int64_t i = 0; i < std::min<std::int64_t>(k, 2); ++i) {
      lambda = step_life(lambda, decrement);
    }
    return lambda;
  }
  if (decrement == 0.0) return lambda;  // x - 0 == x bit for bit (also -0)
  while (k > 0) {
    bool stalled = false;
    std::int64_t taken = 0;
    if (lambda > decrement) {
      taken = bulk_subtract(lambda, decrement, k, stalled);
    } else if (lambda <= 0.0) {  // x - d == -((-x) + d) exactly (rounding is sign-symmetric)
      double magnitude = -lambda;
      taken = bulk_add(magnitude, decrement, k, stalled);
      lambda = -magnitude;
    }
    if (stalled) return lambda;
    k -= taken;
    if (k == 0) break;
    // The step after a bulk run (or when none is possible) changes binade: do it in hardware.
    const double next = step_life(lambda, decrement);
    if (next == lambda || !std::isfinite(next)) return next;  // fixed point (e.g. 1 - 2^-54 == 1)
    lambda = next;
    --k;
  }
  return lambda;
}

std::int64_t cycles_to_failure(double remaining_life, double decrement_per_cycle) {
  double x = remaining_life;
  const double d = decrement_per_cycle;
  if (step_life(x, d) <= 0.0) return 1;
  // Here x - d > 0. Without d > 0 the iterate never decreases; +inf stays +inf.
  if (!(d > 0.0) || !std::isfinite(x)) return kNeverFails;
  std::int64_t n = 0;  // steps taken; invariant x > d, so the next step keeps x > 0
  for (;;) {           // invariant: x > d
    bool stalled = false;
    const std::int64_t taken = bulk_subtract(x, d, kNeverFails, stalled);
    if (stalled) return kNeverFails;
    if (n > kNeverFails - 3 - taken) return kNeverFails;
    n += taken;
    // A bulk run keeps x > 0 but may end with x <= d in the subnormal range.
    if (step_life(x, d) <= 0.0) return n + 1;
    // The next step changes binade: do it in hardware.
    const double next = step_life(x, d);
    if (next == x) return kNeverFails;  // fixed point at the bottom of a binade
    x = next;
    n += 1;
    if (step_life(x, d) <= 0.0) return n + 1;
  }
}

CycleBounds cycles_to_failure_bounds(double remaining_life, double decrement_per_cycle) {
  const double x = remaining_life;
  const double d = decrement_per_cycle;
  if (step_life(x, d) <= 0.0) return {1, 1};
  if (!(d > 0.0) || !std::isfinite(x)) return {kNeverFails, kNeverFails};
  // Each step removes d + err, |err| <= u/2 with u the spacing of x's binade. Failing at step n
  // needs (n − 1)(d + u/2) >= x − d and (n − 2)(d − u/2) < x − d. Margins of 1e-15 cover the
  // rounding of the bound arithmetic itself.
  const double half_ulp = 0.5 * scale(1.0, binade_of(x).q);
  const double big = 9.0e18;  // below INT64_MAX
  CycleBounds b;
  const double lo = std::floor((x - d) / (d + half_ulp) * (1.0 - 1e-15)) + 1.0;
  b.lo = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::min(lo, big)));
  if (d > half_ulp) {
    const double hi = std::ceil((x - d) / (d - half_ulp) * (1.0 + 1e-15)) + 2.0;
    if (hi < big) b.hi = static_cast<std::int64_t>(hi);
  }
  return b;
}

}  // namespace peritwin::fatigue
