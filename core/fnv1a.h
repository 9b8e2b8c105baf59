// The project's one hash: FNV-1a 64 (Fowler, Noll, Vo; offset basis 14695981039346656037, prime
// 1099511628211). It fingerprints a detail's model (the checkpoint signature), the state of a
// twin or an engine (state_hash: equal hashes <=> bit-identical states, up to 64-bit collisions)
// and the content of a checkpoint (its checksum).
//
// bytes() is FNV-1a proper, one xor-multiply per byte (reference test vectors: "" ->
// cbf29ce484222325, "a" -> af63dc4c8601ec8c). word() applies the same step to a whole 64-bit word
// at once: the state hash runs after every batch over every bond, and byte-wise FNV cost a quarter
// of the ingest time. A hash names which of the two it uses; both start from the offset basis.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>

namespace peritwin::core {

class Fnv1a64 {
 public:
  static constexpr std::uint64_t kOffsetBasis = 14695981039346656037ULL;
  static constexpr std::uint64_t kPrime = 1099511628211ULL;

  /// FNV-1a over bytes.
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      h_ ^= p[i];
      h_ *= kPrime;
    }
  }
  void bytes(std::string_view s) { bytes(s.data(), s.size()); }

  /// The FNV-1a step over one 64-bit word.
  void word(std::uint64_t w) {
    h_ ^= w;
    h_ *= kPrime;
  }
  void real(double v) { word(std::bit_cast<std::uint64_t>(v)); }
  void integer(std::int64_t v) { word(static_cast<std::uint64_t>(v)); }
  /// Word-wise: bytes packed little-endian 8 to a word, then the length.
  void packed(const std::uint8_t* p, std::size_t n) {
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
      std::uint64_t w;
      std::memcpy(&w, p + i, 8);
      word(w);
    }
    std::uint64_t tail = 0;
    for (std::size_t k = 0; i + k < n; ++k) tail |= std::uint64_t{p[i + k]} << (8 * k);
    word(tail);
    word(n);
  }
  void packed(std::string_view s) {
    packed(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
  }

  /// word() over each value's bits, in a register: the state hash's bulk (per-bond lives).
  void reals(const double* p, std::size_t n) {
    std::uint64_t h = h_;
    for (std::size_t i = 0; i < n; ++i) h = (h ^ std::bit_cast<std::uint64_t>(p[i])) * kPrime;
    h_ = h;
  }

  [[nodiscard]] std::uint64_t get() const { return h_; }
  /// A hash that continues from `state` (a get() of one that stopped there).
  static Fnv1a64 from(std::uint64_t state) {
    Fnv1a64 h;
    h.h_ = state;
    return h;
  }

 private:
  std::uint64_t h_ = kOffsetBasis;
};

/// Two FNV-1a 64 hashes fed the same words, `first` usually after some words of its own: a
/// twin's state hash and its engine's hash in one pass over the engine's state. The two
/// multiply chains are independent, so the pass costs about what one hash costs.
struct Fnv1a64Pair {
  Fnv1a64 first, second;
  void word(std::uint64_t w) {
    first.word(w);
    second.word(w);
  }
  void real(double v) { word(std::bit_cast<std::uint64_t>(v)); }
  void integer(std::int64_t v) { word(static_cast<std::uint64_t>(v)); }
  void packed(const std::uint8_t* p, std::size_t n) {
    first.packed(p, n);
    second.packed(p, n);
  }
  void packed(std::string_view s) {
    first.packed(s);
    second.packed(s);
  }
  void reals(const double* p, std::size_t n) {
    std::uint64_t a = first.get(), b = second.get();
    for (std::size_t i = 0; i < n; ++i) {
      const auto w = std::bit_cast<std::uint64_t>(p[i]);
      a = (a ^ w) * Fnv1a64::kPrime;
      b = (b ^ w) * Fnv1a64::kPrime;
    }
    first = Fnv1a64::from(a);
    second = Fnv1a64::from(b);
  }
};

/// FNV-1a 64 of a byte string.
inline std::uint64_t fnv1a64(std::string_view s) {
  Fnv1a64 h;
  h.bytes(s);
  return h.get();
}

/// 16 lower-case hex digits.
inline std::string hex64(std::uint64_t value) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out(16, '0');
  for (int i = 15; i >= 0; --i) {
    out[static_cast<std::size_t>(i)] = kDigits[value & 0xF];
    value >>= 4;
  }
  return out;
}

}  // namespace peritwin::core
