// The one random stream of the prognostics: a specified generator, so that the same seed gives the
// same numbers bit for bit on every build (std::random_device is never used, and no std::
// distribution is, since their algorithms are implementation-defined).
//
//  * splitmix64 (Steele, Lea, Flood 2014; Vigna's reference splitmix64.c) turns a 64-bit seed into
//    the generator's 256-bit state;
//  * xoshiro256** 1.0 (Blackman, Vigna 2021; the reference xoshiro256starstar.c) is the generator:
//    period 2^256 - 1, jump() advances it by 2^128 draws (independent streams);
//  * uniform(): the top 53 bits of a draw, (x >> 11) * 2^-53, in [0, 1);
//  * uniform_below(n): an unbiased integer in [0, n) by rejection of the lowest 2^64 mod n draws;
//  * standard_normal(): Box-Muller (Box, Muller 1958), z = sqrt(-2 ln(1 - u1)) cos(2 pi u2), two
//    uniforms per normal (the sine's twin is not cached, so the state stays four integers);
//  * standard_normal_quantile(p): Phi^-1(p) by Wichura's AS 241 (PPND16, Applied Statistics 37
//    (1988) 477-484), relative error about 1e-16.
// The whole state is RandomState (four 64-bit integers): copy it out, store it, restore it, and
// the stream continues bit-identically.
#pragma once

#include <array>
#include <cstdint>

namespace peritwin::prognostics {

/// One step of splitmix64: advances `state` by the golden gamma 0x9e3779b97f4a7c15 and returns the
/// mixed value (the reference's next()).
std::uint64_t splitmix64(std::uint64_t& state);

/// The complete state of a Random stream (xoshiro256**'s s[0..3]); never all zero.
struct RandomState {
  std::array<std::uint64_t, 4> words{};
  friend bool operator==(const RandomState&, const RandomState&) = default;
};

/// xoshiro256** with the draws the filter needs.
class Random {
 public:
  /// s[0..3] = four successive splitmix64 outputs from `seed` (the authors' recommended seeding).
  explicit Random(std::uint64_t seed);
  /// Resumes a stream exactly where state() was taken.
  explicit Random(const RandomState& state);

  /// The next 64-bit draw: rotl(s1 * 5, 7) * 9, then the xoshiro256 state transition.
  std::uint64_t next();
  /// (next() >> 11) * 2^-53: uniform on [0, 1) with 53 random bits.
  double uniform();
  /// An integer uniform on [0, n), n >= 1, without modulo bias (draws below 2^64 mod n are
  /// rejected).
  std::uint64_t uniform_below(std::uint64_t n);
  /// A standard normal deviate by Box-Muller: sqrt(-2 ln(1 - u1)) * cos(2 pi u2).
  double standard_normal();
  /// Advances the stream by 2^128 draws (the reference jump polynomial): streams split by jumps
  /// never overlap.
  void jump();

  [[nodiscard]] const RandomState& state() const { return state_; }

 private:
  RandomState state_;
};

/// Phi^-1(p) for p in (0, 1) by AS 241 (PPND16); -inf at 0, +inf at 1, NaN outside [0, 1].
double standard_normal_quantile(double p);

}  // namespace peritwin::prognostics
