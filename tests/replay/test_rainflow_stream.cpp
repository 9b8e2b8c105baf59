// Tests of the incremental rainflow counter (loads/rainflow.h) and the incremental cycle -> block
// conversion (loads/cycle_blocks.h). Expected numbers come from ASTM E1049-85 (Sec. 5.4.4 and its
// example), from hand traces written next to each case, or from the reference counter below,
// written here from the standard's text and sharing no code with the production one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "loads/cycle_blocks.h"
#include "loads/load_history.h"
#include "loads/rainflow.h"

namespace peritwin::replay {
namespace {

const std::vector<double> kAstmHistory = {-2, 1, -3, 5, -1, 3, -4, 4, -2};

std::vector<loads::CountedCycle> run(loads::RainflowCounter& counter,
                                     const std::vector<double>& loads,
                                     loads::ResidueRule rule = loads::ResidueRule::half) {
  std::vector<loads::CountedCycle> out;
  for (std::size_t i = 0; i < loads.size(); ++i) {
    counter.push(loads[i], static_cast<double>(i), out);
  }
  counter.finish(rule, out);
  return out;
}

// ---------------------------------------------------------------- reference counter

// A reversal of the reference: its value and the index of the sample it came from.
struct RefPoint {
  double value;
  std::size_t sample;
};

// Reversals from their definition (gate 0): skip non-finite samples, collapse runs of equal
// values to their first sample, keep the first and the last point and every point where the
// slope changes sign.
std::vector<RefPoint> reference_reversals(const std::vector<double>& x) {
  std::vector<RefPoint> d;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i])) continue;
    if (d.empty() || d.back().value != x[i]) d.push_back({x[i], i});
  }
  std::vector<RefPoint> r;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const bool end = i == 0 || i + 1 == d.size();
    if (end || (d[i].value > d[i - 1].value) != (d[i + 1].value > d[i].value)) r.push_back(d[i]);
  }
  return r;
}

using RefCycle = std::tuple<double, double, double, double>;  // from, to, count, alpha

// ASTM E1049-85 Sec. 5.4.4 as written, on the whole reversal list: a list of points whose first
// is the starting point S; read a point; while there are three or more points compare the most
// recent range X with the previous range Y; X < Y: read the next point; Y contains S: count Y as
// one-half cycle and discard its first point; otherwise count Y as one cycle and discard both its
// points. At the end, each range left is a half cycle (or a whole one for the `whole` rule).
// alpha = the sample index of Y's larger point.
std::vector<RefCycle> reference_rainflow(const std::vector<double>& x, double residue_count) {
  const std::vector<RefPoint> rev = reference_reversals(x);
  std::vector<RefPoint> pts;
  std::vector<RefCycle> out;
  auto cycle = [&](const RefPoint& a, const RefPoint& b, double n) {
    const double alpha = static_cast<double>(a.value > b.value ? a.sample : b.sample);
    out.emplace_back(a.value, b.value, n, alpha);
  };
  for (const RefPoint& p : rev) {
    pts.push_back(p);
    while (pts.size() >= 3) {
      const std::size_t n = pts.size();
      const double X = std::abs(pts[n - 1].value - pts[n - 2].value);
      const double Y = std::abs(pts[n - 2].value - pts[n - 3].value);
      if (X < Y) break;
      if (n == 3) {  // Y = (pts[0], pts[1]) contains S
        cycle(pts[0], pts[1], 0.5);
        pts.erase(pts.begin());
      } else {
        cycle(pts[n - 3], pts[n - 2], 1.0);
        pts.erase(pts.end() - 3, pts.end() - 1);
      }
    }
  }
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) cycle(pts[i], pts[i + 1], residue_count);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<RefCycle> as_sorted_tuples(const std::vector<loads::CountedCycle>& cycles) {
  std::vector<RefCycle> out;
  for (const auto& c : cycles) out.emplace_back(c.from, c.to, c.count, c.alpha);
  std::sort(out.begin(), out.end());
  return out;
}

// Random histories of four kinds: real-valued, integer levels with many ties, integer levels held
// for random plateau lengths, and real values with NaN/inf dropouts.
std::vector<double> random_series(std::mt19937_64& rng, int kind, std::size_t n) {
  std::uniform_real_distribution<double> real(-100.0, 100.0);
  std::uniform_int_distribution<int> level(-4, 4);
  std::uniform_int_distribution<int> hold(1, 4);
  std::uniform_int_distribution<int> die(0, 9);
  std::vector<double> x;
  while (x.size() < n) {
    switch (kind) {
      case 0:
        x.push_back(real(rng));
        break;
      case 1:
        x.push_back(level(rng));
        break;
      case 2: {
        const double v = level(rng);
        for (int k = hold(rng); k > 0; --k) x.push_back(v);
        break;
      }
      default: {
        const int d = die(rng);
        x.push_back(d == 0   ? std::numeric_limits<double>::quiet_NaN()
                    : d == 1 ? -std::numeric_limits<double>::infinity()
                             : std::round(real(rng) / 10.0));
      }
    }
  }
  return x;
}

// ---------------------------------------------------------------- the counter

TEST(RainflowCounter, AstmE1049ExampleRangesAndCounts) {
  // ASTM E1049-85 Fig. and Table (Sec. 5.4.4): ranges 3: 0.5, 4: 1.5, 6: 0.5, 8: 1.0, 9: 0.5.
  loads::RainflowCounter counter;
  const auto cycles = run(counter, kAstmHistory);
  std::map<double, double> by_range;
  double total = 0.0;
  for (const auto& c : cycles) {
    by_range[std::abs(c.to - c.from)] += c.count;
    total += c.count;
  }
  EXPECT_EQ(by_range, (std::map<double, double>{{3, 0.5}, {4, 1.5}, {6, 0.5}, {8, 1.0}, {9, 0.5}}));
  EXPECT_EQ(total, 4.0);
  EXPECT_EQ(counter.stats(), (loads::RainflowStats{9, 0, 9, 1, 6}));
  EXPECT_TRUE(counter.residue().empty());  // finish() starts a new history
}

TEST(RainflowCounter, MatchesTheReferenceCounterOnRandomSeries) {
  std::mt19937_64 rng(19850101);
  std::uniform_int_distribution<std::size_t> length(0, 80);
  for (int trial = 0; trial < 400; ++trial) {
    SCOPED_TRACE(trial);
    const int kind = trial % 4;
    const std::vector<double> x = random_series(rng, kind, length(rng));
    for (const loads::ResidueRule rule : {loads::ResidueRule::half, loads::ResidueRule::whole}) {
      loads::RainflowCounter counter;
      const auto got = as_sorted_tuples(run(counter, x, rule));
      EXPECT_EQ(got, reference_rainflow(x, rule == loads::ResidueRule::whole ? 1.0 : 0.5));
      std::uint64_t nonfinite = 0;
      for (const double v : x) nonfinite += std::isfinite(v) ? 0 : 1;
      EXPECT_EQ(counter.stats().nonfinite_samples, nonfinite);
      EXPECT_EQ(counter.stats().samples, x.size());
      EXPECT_EQ(counter.stats().reversals, reference_reversals(x).size());
    }
  }
}

// Chunks of a random split: split points drawn with repetition (empty chunks) and adjacent
// (single samples). At each split the counter and the converter are saved and restored.
TEST(RainflowCounter, AnySplitIntoChunksGivesTheCyclesAndBlocksOfTheWholeSeries) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> gate_draw(0.0, 3.0);
  for (int trial = 0; trial < 300; ++trial) {
    SCOPED_TRACE(trial);
    const std::vector<double> x =
        random_series(rng, trial % 4, 1 + static_cast<std::size_t>(trial));
    const double gate = trial % 3 == 0 ? 0.0 : gate_draw(rng);
    const loads::BlockRules rules{trial % 5 == 0 ? 0.25 : 0.0, trial % 2 == 0};
    const loads::ResidueRule rule =
        trial % 7 == 0 ? loads::ResidueRule::whole : loads::ResidueRule::half;
    std::vector<double> alpha(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) alpha[i] = 0.1 * static_cast<double>(i % 17);

    // Whole series.
    loads::RainflowCounter whole(gate);
    loads::CycleBlocks whole_blocks(rules);
    std::vector<loads::CountedCycle> expected_cycles;
    std::vector<core::LoadBlock> expected_blocks;
    for (std::size_t i = 0; i < x.size(); ++i) whole.push(x[i], alpha[i], expected_cycles);
    whole.finish(rule, expected_cycles);
    for (const auto& c : expected_cycles) whole_blocks.add(c, expected_blocks);

    // Chunks.
    std::uniform_int_distribution<std::size_t> at(0, x.size());
    std::vector<std::size_t> splits(static_cast<std::size_t>(trial % 9) + 1);
    for (auto& s : splits) s = at(rng);
    splits.push_back(x.size());
    std::sort(splits.begin(), splits.end());
    loads::RainflowCounter counter(gate);
    loads::CycleBlocks blocks(rules);
    std::vector<loads::CountedCycle> cycles, chunk;
    std::vector<core::LoadBlock> got_blocks;
    std::size_t begin = 0;
    for (const std::size_t end : splits) {
      for (std::size_t i = begin; i < end; ++i) counter.push(x[i], alpha[i], chunk);
      for (const auto& c : chunk) blocks.add(c, got_blocks);
      cycles.insert(cycles.end(), chunk.begin(), chunk.end());
      chunk.clear();
      begin = end;
      const std::string saved = counter.save();
      auto restored = loads::RainflowCounter::restore(saved);
      ASSERT_TRUE(restored.ok()) << restored.error() << "\n" << saved;
      EXPECT_EQ(restored->save(), saved);
      counter = std::move(restored).value();
      const std::string saved_blocks = blocks.save();
      auto restored_blocks = loads::CycleBlocks::restore(saved_blocks);
      ASSERT_TRUE(restored_blocks.ok()) << restored_blocks.error() << "\n" << saved_blocks;
      EXPECT_EQ(restored_blocks->save(), saved_blocks);
      blocks = std::move(restored_blocks).value();
    }
    counter.finish(rule, chunk);
    for (const auto& c : chunk) blocks.add(c, got_blocks);
    cycles.insert(cycles.end(), chunk.begin(), chunk.end());

    ASSERT_EQ(cycles.size(), expected_cycles.size());
    for (std::size_t i = 0; i < cycles.size(); ++i) {
      // Bit for bit (== on doubles; also their signs and exact values).
      EXPECT_EQ(cycles[i], expected_cycles[i]) << i;
    }
    EXPECT_EQ(got_blocks, expected_blocks);
    EXPECT_EQ(counter.stats(), whole.stats());
    EXPECT_EQ(blocks.stats(), whole_blocks.stats());
    EXPECT_EQ(blocks.save(), whole_blocks.save());
  }
}

TEST(RainflowCounter, RangesWithinTheGateAreNoReversals) {
  // Gate 1, angle = sample index. Trace: S = 0; 0.5 and 0.2 stay within the gate of S; 3 starts
  // a rise; 2.2 is back by 0.8 <= 1 (ignored); 3.5 is the new peak; -1 is back by 4.5: 3.5 is a
  // reversal; -0.5 is up by 0.5 (ignored); -2 the new valley; 1 is up by 3: -2 is a reversal and
  // closes the half 0-3.5 (step 5). finish reads 1 (X = 3 < Y = 5.5), residue -> halves 3.5/-2,
  // -2/1.
  const std::vector<double> x = {0, 0.5, 0.2, 3, 2.2, 3.5, -1, -0.5, -2, 1};
  loads::RainflowCounter counter(1.0);
  EXPECT_EQ(run(counter, x), (std::vector<loads::CountedCycle>{
                                 {0, 3.5, 0.5, 5}, {3.5, -2, 0.5, 5}, {-2, 1, 0.5, 9}}));
  EXPECT_EQ(counter.stats(), (loads::RainflowStats{10, 0, 4, 0, 3}));
  // A move back by exactly the gate is no reversal: 0, 2, 1, 3 with gate 1 is one rise 0-3.
  loads::RainflowCounter exact(1.0);
  EXPECT_EQ(run(exact, {0, 2, 1, 3}), (std::vector<loads::CountedCycle>{{0, 3, 0.5, 3}}));
  // Gate 0: the same series has the wiggle 2/1: finish reads 3 (X = 2 >= Y = 1, step (4)): one
  // cycle 2/1, then the residue 0/3.
  loads::RainflowCounter no_gate;
  EXPECT_EQ(run(no_gate, {0, 2, 1, 3}),
            (std::vector<loads::CountedCycle>{{2, 1, 1.0, 1}, {0, 3, 0.5, 3}}));
  EXPECT_THROW(loads::RainflowCounter(-1.0), std::invalid_argument);
  EXPECT_THROW(loads::RainflowCounter(std::numeric_limits<double>::quiet_NaN()),
               std::invalid_argument);
  EXPECT_THROW(loads::RainflowCounter(std::numeric_limits<double>::infinity()),
               std::invalid_argument);
}

TEST(RainflowCounter, NonFiniteSamplesAreCountedAndSkipped) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  loads::RainflowCounter counter;
  std::vector<loads::CountedCycle> out;
  counter.push(nan, 0, out);
  counter.push(0, 0, out);
  counter.push(inf, 0, out);
  counter.push(10, nan, out);  // a finite load with a NaN angle is skipped too
  counter.push(-inf, 0, out);
  counter.push(10, 0.5, out);
  counter.finish(loads::ResidueRule::half, out);
  EXPECT_EQ(out, (std::vector<loads::CountedCycle>{{0, 10, 0.5, 0.5}}));
  EXPECT_EQ(counter.stats(), (loads::RainflowStats{6, 4, 2, 0, 1}));
}

TEST(RainflowCounter, ResidueRuleHalfWholeKeep) {
  // 0, 10, 2, 8, 4, 6 converges: no range closes (each X < Y), the residue is the whole path:
  // ranges 10, 8, 6, 4, 2.
  const std::vector<double> x = {0, 10, 2, 8, 4, 6};
  const auto with = [](double n) {
    return std::vector<loads::CountedCycle>{
        {0, 10, n, 1}, {10, 2, n, 1}, {2, 8, n, 3}, {8, 4, n, 3}, {4, 6, n, 5}};
  };
  loads::RainflowCounter half, whole, keep;
  EXPECT_EQ(run(half, x, loads::ResidueRule::half), with(0.5));
  EXPECT_EQ(half.stats().half_cycles, 5u);
  EXPECT_EQ(run(whole, x, loads::ResidueRule::whole), with(1.0));
  EXPECT_EQ(whole.stats().full_cycles, 5u);
  EXPECT_TRUE(run(keep, x, loads::ResidueRule::keep).empty());
  EXPECT_EQ(keep.residue(), x);
  const std::string before = keep.save();
  std::vector<loads::CountedCycle> out;
  keep.finish(loads::ResidueRule::keep, out);
  EXPECT_EQ(keep.save(), before);  // keep leaves the state unchanged
  // The history continues: 20 extends the open rise 4-6 (6 was only the candidate); finish reads
  // 20: X = 16 >= Y = 4 closes 8/4, then X = 18 >= Y = 8 closes 10/2 (step (4)), residue 0/20 --
  // exactly what the unsplit series 0, 10, 2, 8, 4, 6, 20 gives.
  keep.push(20, 6, out);
  keep.finish(loads::ResidueRule::half, out);
  loads::RainflowCounter joined;
  std::vector<double> y = x;
  y.push_back(20);
  EXPECT_EQ(out, run(joined, y));
  EXPECT_EQ(out,
            (std::vector<loads::CountedCycle>{{8, 4, 1.0, 3}, {10, 2, 1.0, 1}, {0, 20, 0.5, 6}}));
}

TEST(RainflowCounter, RestoreRefusesTruncatedAndMalformedText) {
  loads::RainflowCounter counter(0.5);
  std::vector<loads::CountedCycle> out;
  for (const double v : {0.0, 10.0, 2.0, 8.0}) counter.push(v, 0.25, out);
  const std::string text = counter.save();
  ASSERT_TRUE(loads::RainflowCounter::restore(text).ok());
  // Every proper prefix without the final "end" token is truncated or malformed.
  for (std::size_t n = 0; n + 2 < text.size(); ++n) {
    SCOPED_TRACE(n);
    const auto r = loads::RainflowCounter::restore(text.substr(0, n));
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().rfind("rainflow counter state: ", 0), 0u) << r.error();
  }
  const auto expect_reason = [](const std::string& t, const std::string& reason) {
    const auto r = loads::RainflowCounter::restore(t);
    ASSERT_FALSE(r.ok()) << t;
    EXPECT_NE(r.error().find(reason), std::string::npos) << r.error();
  };
  expect_reason("", "truncated: expected 'peritwin-rainflow-counter'");
  expect_reason("garbage", "expected 'peritwin-rainflow-counter', got 'garbage'");
  expect_reason(text + " more", "unexpected 'more'");
  std::string bad_gate = text;
  bad_gate.replace(bad_gate.find("gate 0x1p-1"), 11, "gate 0.5");
  expect_reason(bad_gate, "gate '0.5' is not a hexadecimal float");
  std::string bad_version = text;
  bad_version.replace(bad_version.find(" 1\n"), 3, " 7\n");
  expect_reason(bad_version, "version 7 is not 1");
  // A stack 0, 2, -10 would have closed the half 0-2 (X = 12 >= Y = 2): not a residue.
  expect_reason(
      "peritwin-rainflow-counter 1 gate 0x0p+0 stats 4 0 3 0 0 started 1 direction up "
      "candidate 0x0p+0 0x0p+0 stack 3 0x0p+0 0x0p+0 0x1p+1 0x0p+0 -0x1.4p+3 0x0p+0 end",
      "close a cycle that was not counted");
  expect_reason(
      "peritwin-rainflow-counter 1 gate 0x0p+0 stats 4 0 3 0 0 started 1 direction sideways",
      "direction must be up, down or none");
  expect_reason(
      "peritwin-rainflow-counter 1 gate 0x0p+0 stats 4 0 3 0 0 started 1 direction up "
      "candidate 0x0p+0 0x0p+0 stack 99999999 0x0p+0 0x0p+0 end",
      "more than the text holds");
}

// ---------------------------------------------------------------- cycles -> blocks

TEST(CycleBlocks, BelowTheRFloorTheSameRangeIsAppliedAtRMinus10) {
  // 0, 100, -1100, 100, 0: reversals all five. Trace: -1100 closes the half 0/100 (step 5, S);
  // 100 closes the half 100/-1100 (X = Y = 1200, step 5); finish reads 0 (X = 100 < 1200); the
  // residue gives the halves -1100/100 and 100/0. Blocks: 0/100 -> (100, 0) pending; 100/-1100
  // has R = -11 -> (1200/11, -10) pending, counted 0.5 below the floor; -1100/100 pairs with it
  // (another 0.5); 100/0 pairs with the first.
  const loads::BlockConversion conv = loads::series_to_blocks({{}, {0, 100, -1100, 100, 0}, {}});
  const double dp = 100.0 - -1100.0;
  EXPECT_EQ(conv.blocks, (std::vector<core::LoadBlock>{{100, 0, 0, 1}, {dp / 11.0, -10.0, 0, 1}}));
  EXPECT_EQ(conv.stats.skipped.remapped_below_floor, 1.0);
  EXPECT_EQ(conv.stats.rounded_up_half_cycles, 0u);
  EXPECT_TRUE(core::check_load_blocks(conv.blocks).ok());
  // The history of the issue: 100, -1100 used to be refused (blocks[0].r = -11 < -10).
  const loads::BlockConversion two = loads::series_to_blocks({{}, {100, -1100}, {}});
  EXPECT_EQ(two.blocks, (std::vector<core::LoadBlock>{{1200.0 / 11.0, -10.0, 0, 1}}));
  EXPECT_EQ(two.stats.skipped.remapped_below_floor, 0.5);
  EXPECT_TRUE(core::check_load_blocks(two.blocks).ok());
  // R = -10 exactly is kept as it is.
  loads::CycleBlocks at_floor({});
  std::vector<core::LoadBlock> out;
  at_floor.add({100, -1000, 1.0, 0}, out);
  EXPECT_EQ(out, (std::vector<core::LoadBlock>{{100, -10, 0, 1}}));
  EXPECT_EQ(at_floor.stats().skipped.remapped_below_floor, 0.0);
}

TEST(CycleBlocks, FullyCompressiveCyclesMirroredOrSkipped) {
  // Reversals 0,-10,-2,-8,5 (angle 0.1 per sample). Trace: finish reads 5 (X = 13 >= Y = 6):
  // full -2/-8 (peak -2 at s2); then X = 15 >= Y = 10 with S: half 0/-10 (peak 0 at s0); residue
  // half -10/5 (peak 5 at s4).
  const loads::LoadSeries s{{0, 1, 2, 3, 4}, {0, -10, -2, -8, 5}, {0.0, 0.1, 0.2, 0.3, 0.4}};
  loads::SeriesRules mirror;
  const loads::BlockConversion m = loads::series_to_blocks(s, mirror);
  // Mirrors: -2/-8 -> p_max 8, r = -2/-8 = 0.25; 0/-10 -> p_max 10, r = +0.
  EXPECT_EQ(m.blocks,
            (std::vector<core::LoadBlock>{{8, 0.25, 0.2, 1}, {10, 0, 0.0, 1}, {5, -2, 0.4, 1}}));
  EXPECT_FALSE(std::signbit(m.blocks[1].r));
  EXPECT_EQ(m.stats.skipped.mirrored_compressive, 1.5);
  EXPECT_EQ(m.stats.skipped.compressive, 0.0);
  EXPECT_EQ(m.stats.rounded_up_half_cycles, 2u);
  loads::SeriesRules tension_only;
  tension_only.compressed_bonds_fatigue = false;
  const loads::BlockConversion t = loads::series_to_blocks(s, tension_only);
  EXPECT_EQ(t.blocks, (std::vector<core::LoadBlock>{{5, -2, 0.4, 1}}));
  EXPECT_EQ(t.stats.skipped.compressive, 1.5);
  EXPECT_EQ(t.stats.skipped.mirrored_compressive, 0.0);
  // Zero range is no cycle, whatever the rule.
  loads::CycleBlocks blocks({});
  std::vector<core::LoadBlock> out;
  blocks.add({3, 3, 1.0, 0}, out);
  blocks.add({0, 0, 0.5, 0}, out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(blocks.stats().skipped.degenerate, 1.5);
  EXPECT_THROW(blocks.add({0, 1, 0.25, 0}, out), std::invalid_argument);
  EXPECT_THROW(blocks.add({0, std::numeric_limits<double>::quiet_NaN(), 1, 0}, out),
               std::invalid_argument);
}

TEST(CycleBlocks, AlphaIsRoundedToItsBin) {
  loads::CycleBlocks blocks({0.1, true});
  std::vector<core::LoadBlock> out;
  blocks.add({0, 10, 1.0, 0.26}, out);   // round(2.6) = 3 -> 3 * 0.1
  blocks.add({0, 10, 1.0, -0.04}, out);  // round(-0.4) = -0 -> +0
  EXPECT_EQ(out, (std::vector<core::LoadBlock>{{10, 0, 3 * 0.1, 1}, {10, 0, 0.0, 1}}));
  EXPECT_FALSE(std::signbit(out[1].alpha));
  EXPECT_THROW(loads::CycleBlocks({-0.1, true}), std::invalid_argument);
}

TEST(CycleBlocks, PendingHalvesAreBoundedOldestDropped) {
  loads::CycleBlocks blocks({});
  std::vector<core::LoadBlock> out;
  for (std::size_t i = 0; i <= loads::kMaxPendingHalves; ++i) {
    blocks.add({0, 1.0 + static_cast<double>(i), 0.5, 0}, out);
  }
  EXPECT_EQ(out.size(), loads::kMaxPendingHalves + 1);  // every first half is a whole cycle
  const auto pending = blocks.pending_halves();
  ASSERT_EQ(pending.size(), loads::kMaxPendingHalves);
  EXPECT_EQ(pending.front().p_max, 2.0);  // key 1.0, the oldest, was dropped
  EXPECT_EQ(pending.back().p_max, 1.0 + static_cast<double>(loads::kMaxPendingHalves));
  EXPECT_EQ(blocks.stats().rounded_up_half_cycles, loads::kMaxPendingHalves + 1);
  // The dropped key's next half can no longer pair: another whole cycle.
  blocks.add({0, 1.0, 0.5, 0}, out);
  EXPECT_EQ(out.size(), loads::kMaxPendingHalves + 2);
  // A pending key's next half pairs: nothing emitted, one fewer rounded up.
  blocks.add({0, 3.0, 0.5, 0}, out);
  EXPECT_EQ(out.size(), loads::kMaxPendingHalves + 2);
  EXPECT_EQ(blocks.stats().rounded_up_half_cycles, loads::kMaxPendingHalves + 1);
  const auto restored = loads::CycleBlocks::restore(blocks.save());
  ASSERT_TRUE(restored.ok()) << restored.error();
  EXPECT_EQ(restored->pending_halves(), blocks.pending_halves());
  EXPECT_EQ(restored->stats(), blocks.stats());
}

TEST(CycleBlocks, RestoreRefusesTruncatedAndMalformedText) {
  loads::CycleBlocks blocks({0.5, false});
  std::vector<core::LoadBlock> out;
  blocks.add({0, 10, 0.5, 0}, out);
  blocks.add({2, -30, 1.0, 0}, out);
  const std::string text = blocks.save();
  const auto back = loads::CycleBlocks::restore(text);
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back->rules(), (loads::BlockRules{0.5, false}));
  for (std::size_t n = 0; n + 2 < text.size(); ++n) {
    SCOPED_TRACE(n);
    const auto r = loads::CycleBlocks::restore(text.substr(0, n));
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().rfind("cycle blocks state: ", 0), 0u) << r.error();
  }
  const auto reason = [](const std::string& t) {
    const auto r = loads::CycleBlocks::restore(t);
    return r.ok() ? std::string("(accepted)") : r.error();
  };
  EXPECT_NE(reason("%%").find("expected 'peritwin-cycle-blocks', got '%%'"), std::string::npos);
  EXPECT_NE(reason("peritwin-cycle-blocks 1 rules 0x0p+0 2").find("must be 0 or 1"),
            std::string::npos);
  EXPECT_NE(reason("peritwin-cycle-blocks 1 rules 0x0p+0 1 stats 0 0 0 1 1 skipped 0x0p+0 "
                   "0x0p+0 0x0p+0 0x0p+0 pending 1 0x1p+0 0x1p+0 0x0p+0 end")
                .find("pending key 0 is no valid load block"),
            std::string::npos);  // r = 1 is no cycle
  EXPECT_NE(reason("peritwin-cycle-blocks 1 rules 0x0p+0 1 stats 0 0 0 1 1 skipped 0x1.8p-2 "
                   "0x0p+0 0x0p+0 0x0p+0 pending 0 end")
                .find("whole number of half cycles"),
            std::string::npos);  // 0.375
}

}  // namespace
}  // namespace peritwin::replay
