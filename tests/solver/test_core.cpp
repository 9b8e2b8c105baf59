// The core vocabulary: the one hash (FNV-1a 64 against the reference's test vectors) and the
// Expected/Status error convention.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "core/expected.h"
#include "core/fnv1a.h"

namespace peritwin {
namespace {

TEST(Fnv1a64, ReferenceTestVectors) {
  // From the FNV reference (Fowler, Noll, Vo; the test suite of fnv-5.0.3, FNV-1a 64).
  EXPECT_EQ(core::fnv1a64(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(core::fnv1a64("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(core::fnv1a64("foobar"), 0x85944171f73967e8ULL);
  EXPECT_EQ(core::hex64(core::fnv1a64("")), "cbf29ce484222325");
  EXPECT_EQ(core::Fnv1a64::kOffsetBasis, 14695981039346656037ULL);
}

TEST(Fnv1a64, WordStepIsTheByteStepOnAWholeWord) {
  // One word w with only its low byte set hashes as FNV-1a of that byte (xor touches the same
  // bits, the multiply is the same): the word-wise variant is FNV-1a's step, not another hash.
  core::Fnv1a64 word;
  word.word(0x61);  // 'a'
  EXPECT_EQ(word.get(), core::fnv1a64("a"));
  core::Fnv1a64 packed;
  packed.packed(std::string("abc"));
  core::Fnv1a64 expected;
  expected.word(0x636261);  // "abc" little-endian in one word, then the length
  expected.word(3);
  EXPECT_EQ(packed.get(), expected.get());
}

TEST(Expected, CarriesAValueOrAnError) {
  const core::Expected<int> seven = 7;
  ASSERT_TRUE(seven.ok());
  EXPECT_EQ(*seven, 7);
  const core::Expected<int> bad = core::Error{"blocks[2].r", "r = 2 must be < 1"};
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().message(), "blocks[2].r: r = 2 must be < 1");
  const core::Status fine;
  EXPECT_TRUE(fine.ok());
  EXPECT_EQ(core::message_of(fine), "");
  const core::Status wrong = core::failure("no nodes");
  EXPECT_EQ(core::message_of(wrong), "no nodes");
  EXPECT_EQ(core::Error({"r", "why"}).within("blocks[0].").field, "blocks[0].r");
}

}  // namespace
}  // namespace peritwin
