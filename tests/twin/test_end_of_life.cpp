// End of life at the exact cycle, whatever the batching (twin/twin.h, "End of life").
//
// The reference is the 1-cycle batching: the twin then looks at the criterion after every cycle,
// which is the definition of "the first cycle at which the criterion is met". Every other batching
// of the same cycle sequence (blocks of 100, 700, 1000, 5000 cycles, several blocks per batch, one
// block for the whole history) must stop at that cycle with the same broken bonds and the same
// engine state (bit-identical: Twin::engine_hash).
#include <algorithm>
#include <cstdint>
#include <vector>

#include "tests/support/twin_fixtures.h"

namespace peritwin::twin {
namespace {

using testing::b1_config;
using testing::b1_model;
using testing::batch;
using testing::make_twin;

// The load: 4 kN, R = 0.1 on the demo's B1 model. The criterion is 8 mm of growth in the
// example; 1 mm here keeps the 1-cycle run to ~12 000 batches. The first `kCommonPrefix` cycles
// (no bond breaks before ~10 000) come as one batch in every run except the single-block one, so
// that the 1-cycle reference does not spend its time where nothing happens.
constexpr double kPMax = 4000.0;
constexpr double kR = 0.1;
constexpr std::int64_t kCommonPrefix = 9000;
constexpr std::int64_t kHistory = 64000;

struct EndOfLife {
  std::int64_t cycle = -1;
  std::int64_t total_cycles = 0;
  std::uint64_t engine_hash = 0;
  std::vector<std::uint8_t> intact;
  double crack_length = 0.0;
  std::size_t batches = 0;
};

/// Feeds the history in batches of `blocks_per_batch` blocks of `cycles_per_block` cycles (after
/// the common prefix unless `one_block`) until the twin reports its end of life.
EndOfLife run(const std::shared_ptr<const twin::DetailModel>& model, std::int64_t cycles_per_block,
              std::int64_t blocks_per_batch = 1, bool one_block = false) {
  auto twin = make_twin(model);
  EndOfLife out;
  std::int64_t seq = 1;
  std::int64_t fed = 0;
  if (one_block) {
    EXPECT_TRUE(twin->apply(batch(seq++, {{kPMax, kR, 0, kHistory}})).applied());
    fed = kHistory;
  } else {
    EXPECT_TRUE(twin->apply(batch(seq++, {{kPMax, kR, 0, kCommonPrefix}})).applied());
    fed = kCommonPrefix;
  }
  while (twin->failure() == twin::Failure::none && fed < kHistory) {
    std::vector<core::LoadBlock> blocks;
    for (std::int64_t b = 0; b < blocks_per_batch && fed < kHistory; ++b) {
      const std::int64_t n = std::min(cycles_per_block, kHistory - fed);
      blocks.push_back({kPMax, kR, 0, n});
      fed += n;
    }
    const messages::Outcome o = twin->apply(batch(seq++, blocks));
    EXPECT_TRUE(o.applied()) << o.what << ": " << o.why;
    if (!o.applied()) break;
  }
  out.cycle = twin->end_of_life_cycle();
  out.total_cycles = twin->engine().total_cycles();
  out.engine_hash = twin->engine_hash();
  out.intact = twin->engine().solver().intact();
  out.crack_length = twin::criterion_crack_length(*model, twin->engine().node_damage(), out.intact);
  out.batches = static_cast<std::size_t>(seq - 1);
  // A batch after the end of life is refused and changes nothing.
  const messages::Outcome after = twin->apply(batch(seq, {{kPMax, kR, 0, 1000}}));
  EXPECT_EQ(after.verdict, messages::Verdict::failed);
  EXPECT_EQ(twin->engine_hash(), out.engine_hash);
  return out;
}

TEST(EndOfLife, TheSameCycleBondsAndEngineStateForEveryBatching) {
  const double critical = 0.001;
  auto model = b1_model(b1_config(
      "every_batches = 0", {{"critical_crack_length = 0.008", "critical_crack_length = 0.001"}}));
  ASSERT_TRUE(model);

  const EndOfLife reference = run(model, 1);
  ASSERT_GT(reference.cycle, kCommonPrefix) << "the criterion must be met after the prefix";
  ASSERT_LT(reference.cycle, kHistory);
  EXPECT_EQ(reference.total_cycles, reference.cycle) << "the twin stops at the end of life";
  EXPECT_GE(reference.crack_length, critical);
  // The 1-cycle run looked after every cycle: one cycle earlier the criterion was not met.
  {
    auto twin = make_twin(model);
    ASSERT_TRUE(twin->apply(batch(1, {{kPMax, kR, 0, reference.cycle - 1}})).applied());
    EXPECT_EQ(twin->failure(), twin::Failure::none);
    EXPECT_LT(twin::criterion_crack_length(*model, twin->engine().node_damage(),
                                           twin->engine().solver().intact()),
              critical);
    // ... and one more cycle reaches it.
    ASSERT_TRUE(twin->apply(batch(2, {{kPMax, kR, 0, 1}})).applied());
    EXPECT_EQ(twin->end_of_life_cycle(), reference.cycle);
    EXPECT_EQ(twin->engine_hash(), reference.engine_hash);
  }

  struct Case {
    std::int64_t cycles_per_block, blocks_per_batch;
    bool one_block;
  };
  for (const Case c : {Case{100, 1, false}, Case{700, 1, false}, Case{1000, 1, false},
                       Case{5000, 1, false}, Case{143, 7, false}, Case{0, 1, true}}) {
    SCOPED_TRACE(c.one_block ? std::string("one block")
                             : std::to_string(c.blocks_per_batch) + " x " +
                                   std::to_string(c.cycles_per_block) + " cycles per batch");
    const EndOfLife e = run(model, c.cycles_per_block, c.blocks_per_batch, c.one_block);
    EXPECT_EQ(e.cycle, reference.cycle);
    EXPECT_EQ(e.total_cycles, reference.total_cycles);
    EXPECT_EQ(e.intact, reference.intact);
    EXPECT_EQ(e.engine_hash, reference.engine_hash);
    EXPECT_EQ(e.crack_length, reference.crack_length);
  }
}

}  // namespace
}  // namespace peritwin::twin
