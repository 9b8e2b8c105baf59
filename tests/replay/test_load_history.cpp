// Tests of loads/rainflow.h, loads/cycle_blocks.h and loads/load_history.h (the incremental
// counter's own properties: tests/replay/test_rainflow_stream.cpp). Expected numbers come from ASTM
// E1049-85 (Sec. 5.4.4 example), from hand traces written next to each case, or from an independent
// brute-force four-point rainflow written here.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "loads/load_history.h"
#include "loads/rainflow.h"

namespace peritwin::replay {
namespace {

namespace fs = std::filesystem;

const std::vector<double> kAstmHistory = {-2, 1, -3, 5, -1, 3, -4, 4, -2};

std::map<double, double> counts_by_range(const std::vector<loads::CountedCycle>& cycles) {
  std::map<double, double> out;
  for (const auto& c : cycles) out[std::abs(c.to - c.from)] += c.count;
  return out;
}

// ---------------------------------------------------------------- independent reference code

// Reversals the plain way: drop repeats, then keep the ends and every slope sign change.
std::vector<double> naive_reversals(const std::vector<double>& x) {
  std::vector<double> d;
  for (double v : x) {
    if (d.empty() || d.back() != v) d.push_back(v);
  }
  std::vector<double> r;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (i == 0 || i + 1 == d.size() || (d[i] - d[i - 1] > 0) != (d[i + 1] - d[i] > 0)) {
      r.push_back(d[i]);
    }
  }
  return r;
}

struct RefCycle {
  double range;
  double mean;
  double count;
  auto operator<=>(const RefCycle&) const = default;
};

// Brute-force four-point rainflow: rescan from the start for points a,b,c,d with
// |c-b| <= |b-a| and |c-b| <= |d-c|, count b-c as one cycle and remove b, c; the residue left when
// no such quadruple exists is counted as half cycles. O(n^3), fine for short histories.
std::vector<RefCycle> four_point_rainflow(std::vector<double> r) {
  std::vector<RefCycle> out;
  for (bool found = true; found;) {
    found = false;
    for (std::size_t i = 0; i + 3 < r.size(); ++i) {
      const double inner = std::abs(r[i + 2] - r[i + 1]);
      if (inner <= std::abs(r[i + 1] - r[i]) && inner <= std::abs(r[i + 3] - r[i + 2])) {
        out.push_back({inner, 0.5 * (r[i + 1] + r[i + 2]), 1.0});
        r.erase(r.begin() + static_cast<std::ptrdiff_t>(i + 1),
                r.begin() + static_cast<std::ptrdiff_t>(i + 3));
        found = true;
        break;
      }
    }
  }
  for (std::size_t i = 0; i + 1 < r.size(); ++i) {
    out.push_back({std::abs(r[i + 1] - r[i]), 0.5 * (r[i] + r[i + 1]), 0.5});
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<double> random_history(std::mt19937_64& rng, std::size_t n, bool integer_levels) {
  std::uniform_real_distribution<double> real(-100.0, 100.0);
  std::uniform_int_distribution<int> level(-5, 5);
  std::vector<double> x(n);
  for (auto& v : x) v = integer_levels ? level(rng) : real(rng);
  return x;
}

// ---------------------------------------------------------------- rainflow

TEST(Rainflow, AstmE1049ExampleAggregateCounts) {
  const auto cycles = loads::count_cycles(kAstmHistory);
  const std::map<double, double> expected = {{3, 0.5}, {4, 1.5}, {6, 0.5}, {8, 1.0}, {9, 0.5}};
  EXPECT_EQ(counts_by_range(cycles), expected);
}

TEST(Rainflow, AstmE1049ExampleCycleByCycle) {
  // Hand trace of Sec. 5.4.4 on the reversals -2, 1, -3, 5, -1, 3, -4, 4, -2, in counting order.
  const std::vector<loads::CountedCycle> expected = {
      {-2, 1, 0.5, 0}, {1, -3, 0.5, 0}, {-1, 3, 1.0, 0}, {-3, 5, 0.5, 0},
      {5, -4, 0.5, 0}, {-4, 4, 0.5, 0}, {4, -2, 0.5, 0}};
  EXPECT_EQ(loads::count_cycles(kAstmHistory), expected);
}

TEST(Rainflow, MonotonePointsAndPlateausAreNoReversals) {
  // Reversals 0 (s0), 2 (s2, first of its plateau), -1 (s5), 3 (s8). Trace: reading -1 closes
  // the half 0-2 (step 5); finish reads 3, which closes the half 2-(-1) (step 5), residue -1-3.
  // The angle is the sample index: each cycle's alpha is at its peak's first sample.
  const std::vector<double> x = {0, 1, 2, 2, 1, -1, -1, -1, 3, 3};
  std::vector<double> angle(x.size());
  std::iota(angle.begin(), angle.end(), 0.0);
  const std::vector<loads::CountedCycle> expected = {
      {0, 2, 0.5, 2}, {2, -1, 0.5, 2}, {-1, 3, 0.5, 8}};
  EXPECT_EQ(loads::count_cycles(x, angle), expected);
  EXPECT_TRUE(loads::count_cycles(std::vector<double>{}).empty());
  EXPECT_TRUE(loads::count_cycles(std::vector<double>{4, 4, 4}).empty());
  EXPECT_TRUE(loads::count_cycles(std::vector<double>{NAN, 4, INFINITY}).empty());
  EXPECT_THROW((void)loads::count_cycles(x, std::vector<double>{1.0}), std::invalid_argument);
}

// Against the brute-force four-point method on random histories. Both compute range and mean from
// the same two reversal values, so they are compared exactly: the total count per (range, mean)
// must agree; with real-valued levels (no ties) even the cycle lists agree one to one (with ties,
// e.g. 5,-4,5 later closed, ASTM may count two equal half cycles where the four-point method counts
// one full cycle; the total per range is the same). Damage sum(count * range^3) agrees to 1e-12
// relative, and sum(2 * count * range) equals the path length sum |r[i+1] - r[i]| to 1e-12
// relative.
TEST(Rainflow, MatchesBruteForceFourPointOnRandomHistories) {
  std::mt19937_64 rng(20240601);
  for (int trial = 0; trial < 400; ++trial) {
    SCOPED_TRACE(trial);
    const bool integer_levels = trial % 2 == 1;
    const auto x = random_history(rng, 5 + static_cast<std::size_t>(trial % 60), integer_levels);
    const std::vector<double> rev = naive_reversals(x);
    std::vector<RefCycle> got;
    for (const auto& c : loads::count_cycles(x)) {
      got.push_back({std::abs(c.to - c.from), 0.5 * (c.from + c.to), c.count});
    }
    std::sort(got.begin(), got.end());
    const auto ref = four_point_rainflow(rev);
    if (!integer_levels) {
      EXPECT_EQ(got, ref);
    }
    std::map<std::pair<double, double>, double> got_total, ref_total;
    double d_got = 0, d_ref = 0, path = 0, counted = 0;
    for (const auto& c : got) {
      got_total[{c.range, c.mean}] += c.count;
      d_got += c.count * std::pow(c.range, 3);
      counted += 2.0 * c.count * c.range;
    }
    for (const auto& c : ref) {
      ref_total[{c.range, c.mean}] += c.count;
      d_ref += c.count * std::pow(c.range, 3);
    }
    EXPECT_EQ(got_total, ref_total);
    for (std::size_t i = 0; i + 1 < rev.size(); ++i) path += std::abs(rev[i + 1] - rev[i]);
    EXPECT_NEAR(d_got, d_ref, 1e-12 * d_ref);
    EXPECT_NEAR(counted, path, 1e-12 * path);
  }
}

// ---------------------------------------------------------------- cycles -> blocks

TEST(CyclesToBlocks, AstmExampleGivesOneBlockPerCycleWithHalvesRoundedUp) {
  const loads::BlockConversion conv = loads::series_to_blocks({{}, kAstmHistory, {}});
  // Counting order of the hand trace above; every half cycle has its own key -> rounded up.
  const std::vector<core::LoadBlock> expected = {
      {1, -2.0, 0, 1},       {1, -3.0, 0, 1}, {3, -1.0 / 3.0, 0, 1}, {5, -3.0 / 5.0, 0, 1},
      {5, -4.0 / 5.0, 0, 1}, {4, -1.0, 0, 1}, {4, -2.0 / 4.0, 0, 1}};
  EXPECT_EQ(conv.blocks, expected);
  EXPECT_EQ(conv.stats.reversals, 9u);
  EXPECT_EQ(conv.stats.full_cycles, 1u);
  EXPECT_EQ(conv.stats.half_cycles, 6u);
  EXPECT_EQ(conv.stats.skipped, loads::ConversionStats::SkippedCycles{});
  EXPECT_EQ(conv.stats.rounded_up_half_cycles, 6u);
}

TEST(CyclesToBlocks, HalfCyclesOfTheSameKeyPairIntoWholeCycles) {
  // 0,10,0,10,0: ASTM step (5) gives three halves 0-10 and the residue a fourth -> 2 cycles.
  loads::LoadSeries even{{0, 1, 2, 3, 4}, {0, 10, 0, 10, 0}, {}};
  loads::BlockConversion conv = loads::series_to_blocks(even);
  EXPECT_EQ(conv.blocks, (std::vector<core::LoadBlock>{{10, 0, 0, 2}}));
  EXPECT_EQ(conv.stats.half_cycles, 4u);
  EXPECT_EQ(conv.stats.rounded_up_half_cycles, 0u);
  // 0,10,0,10: three halves -> one pair + one rounded up = 2 cycles.
  loads::LoadSeries odd{{0, 1, 2, 3}, {0, 10, 0, 10}, {}};
  conv = loads::series_to_blocks(odd);
  EXPECT_EQ(conv.blocks, (std::vector<core::LoadBlock>{{10, 0, 0, 2}}));
  EXPECT_EQ(conv.stats.half_cycles, 3u);
  EXPECT_EQ(conv.stats.rounded_up_half_cycles, 1u);
}

TEST(CyclesToBlocks, CompressiveCyclesAreSkippedWhenCompressedBondsDoNotFatigue) {
  // Reversals 0,-10,-2,-8,5 (trace): full -2/-8 (P_max -2), half 0/-10 (P_max 0), residue half
  // -10/5 -> only the last one drives fatigue: P_max 5, R -2, alpha at the sample of 5.
  loads::LoadSeries s{{0, 1, 2, 3, 4}, {0, -10, -2, -8, 5}, {0.0, 0.1, 0.2, 0.3, 0.4}};
  loads::SeriesRules rules;
  rules.compressed_bonds_fatigue = false;
  const loads::BlockConversion conv = loads::series_to_blocks(s, rules);
  EXPECT_EQ(conv.blocks, (std::vector<core::LoadBlock>{{5, -2, 0.4, 1}}));
  EXPECT_EQ(conv.stats.skipped.compressive, 1.5);
  EXPECT_EQ(conv.stats.skipped.mirrored_compressive, 0.0);
  EXPECT_EQ(conv.stats.full_cycles, 1u);
  EXPECT_EQ(conv.stats.half_cycles, 2u);
  EXPECT_EQ(conv.stats.rounded_up_half_cycles, 1u);
}

TEST(CyclesToBlocks, AngleIsTakenAtTheMaximumReversal) {
  // Loads 0,4,10,10,2,5,8,0 -> reversals 0(s0),10(s2),2(s4),8(s6),0(s7). Trace: full 2/8
  // (P_max 8 at s6), half 0/10 (max at s2), residue half 10/0 (max at s2, same key -> paired).
  loads::LoadSeries s{{0, 1, 2, 3, 4, 5, 6, 7},
                      {0, 4, 10, 10, 2, 5, 8, 0},
                      {0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7}};
  const loads::BlockConversion conv = loads::series_to_blocks(s);
  EXPECT_EQ(conv.blocks, (std::vector<core::LoadBlock>{{8, 0.25, 0.6, 1}, {10, 0, 0.2, 1}}));
  EXPECT_EQ(conv.stats.rounded_up_half_cycles, 0u);
}

// No damage lost: for random tensile histories, sum(count * dP^3) of the blocks is at least the
// rainflow damage (1e-12 relative) and the cycle total is exactly full + (halves + rounded up) / 2.
TEST(CyclesToBlocks, HalfCycleRuleNeverLosesDamage) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    SCOPED_TRACE(trial);
    auto x = random_history(rng, 40, trial % 2 == 1);
    for (auto& v : x) v += 200.0;  // all tensile
    const auto cycles = loads::count_cycles(x);
    loads::BlockConversion conv;
    loads::CycleBlocks converter({});
    for (const auto& c : cycles) converter.add(c, conv.blocks);
    conv.stats = converter.stats();
    double d_rf = 0, d_blocks = 0;
    for (const auto& c : cycles) d_rf += c.count * std::pow(std::abs(c.to - c.from), 3);
    std::int64_t total = 0;
    for (const auto& b : loads::merge_consecutive(conv.blocks)) {
      d_blocks += static_cast<double>(b.count) * std::pow(b.p_max * (1.0 - b.r), 3);
      total += b.count;
    }
    EXPECT_GE(d_blocks, d_rf * (1.0 - 1e-12));
    const std::size_t s = conv.stats.half_cycles + conv.stats.rounded_up_half_cycles;
    EXPECT_EQ(s % 2, 0u);
    EXPECT_EQ(total, static_cast<std::int64_t>(conv.stats.full_cycles + s / 2));
  }
}

TEST(CyclesToBlocks, MergeConsecutiveSumsRunsOnly) {
  const std::vector<core::LoadBlock> in = {{1, 0, 0, 2}, {1, 0, 0, 3}, {2, 0, 0, 1}, {1, 0, 0, 4}};
  EXPECT_EQ(loads::merge_consecutive(in),
            (std::vector<core::LoadBlock>{{1, 0, 0, 5}, {2, 0, 0, 1}, {1, 0, 0, 4}}));
  const std::int64_t big = std::numeric_limits<std::int64_t>::max() - 1;
  const std::vector<core::LoadBlock> overflow = {{1, 0, 0, big}, {1, 0, 0, 5}};
  EXPECT_EQ(loads::merge_consecutive(overflow), overflow);  // never overflows the count
}

// ---------------------------------------------------------------- readers

class LoadHistoryFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("peritwin_replay_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  fs::path dir_;
};

TEST_F(LoadHistoryFiles, SeriesWithAngleCommentsBlanksAndCrlf) {
  const auto p = write("s.csv",
                       "# recorded 2024-06-01\r\n\r\n time_s , load_N , angle_rad \r\n"
                       "0,0,0.0\r\n# mid comment\r\n1,4,0.1\n2,10,0.2\n3,10,0.3\n4,2,0.4\n"
                       "5,5,0.5\n6,8,0.6\n7,0,0.7\n\n");
  const auto series = loads::read_series_csv(p);
  ASSERT_TRUE(series.ok()) << series.error().message();
  EXPECT_EQ(series.value().time_s, (std::vector<double>{0, 1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(series.value().load_n, (std::vector<double>{0, 4, 10, 10, 2, 5, 8, 0}));
  EXPECT_EQ(series.value().angle_rad.size(), 8u);
  EXPECT_EQ(series.value().angle_rad[6], 0.6);
  const auto blocks = loads::read_blocks(p, loads::HistoryFormat::series);
  ASSERT_TRUE(blocks.ok());
  EXPECT_EQ(blocks.value().blocks,
            (std::vector<core::LoadBlock>{{8, 0.25, 0.6, 1}, {10, 0, 0.2, 1}}));
}

TEST_F(LoadHistoryFiles, SeriesWithoutAngleIsTheAstmExample) {
  std::string text = "time_s,load_N\n";
  for (std::size_t i = 0; i < kAstmHistory.size(); ++i) {
    text += std::to_string(0.5 * static_cast<double>(i)) + "," +
            std::to_string(static_cast<int>(kAstmHistory[i])) + "\n";
  }
  const auto series = loads::read_series_csv(write("s.csv", text));
  ASSERT_TRUE(series.ok()) << series.error().message();
  EXPECT_TRUE(series.value().angle_rad.empty());
  EXPECT_EQ(series.value().load_n, kAstmHistory);
  EXPECT_EQ(loads::series_to_blocks(series.value()).blocks.size(), 7u);
}

TEST_F(LoadHistoryFiles, CyclesListKeptAsGiven) {
  const auto p = write("c.csv",
                       "p_max_N,r,angle_rad,count\n1e4,0.1,0,1000\n1e4,0.1,0,5\n"
                       "2.5e4,-1,1.5707963267948966,7\n");
  const auto blocks = loads::read_cycles_csv(p);
  ASSERT_TRUE(blocks.ok()) << blocks.error().message();
  EXPECT_EQ(blocks.value(),
            (std::vector<core::LoadBlock>{
                {1e4, 0.1, 0, 1000}, {1e4, 0.1, 0, 5}, {2.5e4, -1, 1.5707963267948966, 7}}));
}

TEST_F(LoadHistoryFiles, SpectrumRepeatDirective) {
  const auto p = write("sp.csv",
                       "# repeat 3\n# two-level spectrum\np_max_N,r,angle_rad,count\n"
                       "100,0.1,0,10\n200,0.5,0.2,1\n");
  const auto spectrum = loads::read_spectrum_csv(p);
  ASSERT_TRUE(spectrum.ok()) << spectrum.error().message();
  EXPECT_EQ(spectrum.value().repeat, 3);
  const std::vector<core::LoadBlock> one = {{100, 0.1, 0, 10}, {200, 0.5, 0.2, 1}};
  EXPECT_EQ(spectrum.value().blocks, one);
  std::vector<core::LoadBlock> three;
  for (int k = 0; k < 3; ++k) three.insert(three.end(), one.begin(), one.end());
  EXPECT_EQ(loads::expand(spectrum.value()), three);
  const auto blocks = loads::read_blocks(p, loads::HistoryFormat::spectrum);
  ASSERT_TRUE(blocks.ok());
  EXPECT_EQ(blocks.value().blocks, three);

  // At the cap exactly: 2 blocks x 500 000.
  const auto at_cap = loads::read_blocks(
      write("cap.csv", "# repeat 500000\np_max_N,r,angle_rad,count\n100,0.1,0,10\n200,0.5,0.2,1\n"),
      loads::HistoryFormat::spectrum);
  ASSERT_TRUE(at_cap.ok()) << at_cap.error().message();
  ASSERT_EQ(at_cap.value().blocks.size(), loads::kMaxSpectrumBlocks);
  EXPECT_EQ(at_cap.value().blocks.back(), one.back());
  EXPECT_THROW((void)loads::expand({one, 500'001}), std::length_error);

  const auto plain =
      loads::read_spectrum_csv(write("p.csv", "p_max_N,r,angle_rad,count\n100,0,0,1\n"));
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(plain.value().repeat, 1);
  // "# repeated ..." is an ordinary comment, not the directive.
  const auto comment = loads::read_cycles_csv(
      write("k.csv", "# repeated test\np_max_N,r,angle_rad,count\n1,0,0,1\n"));
  EXPECT_TRUE(comment.ok());
}

struct BadCase {
  loads::HistoryFormat format;
  std::string text;
  std::size_t line;
  std::string reason;  // substring of the message
};

TEST_F(LoadHistoryFiles, EveryErrorNamesFileLineAndReason) {
  const std::string series = "time_s,load_N,angle_rad\n";
  const std::string blocks = "p_max_N,r,angle_rad,count\n";
  const std::vector<BadCase> cases = {
      {loads::HistoryFormat::series, "time,load\n0,1\n", 1, "expected header"},
      {loads::HistoryFormat::series, "# c\n\n" + series + "0,1,0\n1,2,0,9\n", 5,
       "expected 3 fields, got 4"},
      {loads::HistoryFormat::series, series + "nan,1,0\n", 2, "non-finite value 'nan' in 'time_s'"},
      {loads::HistoryFormat::series, series + "0,1,0\ninf,1,0\n", 3, "non-finite value 'inf'"},
      {loads::HistoryFormat::series, series + "0,1,0\n1,2x,0\n", 3, "malformed number '2x'"},
      {loads::HistoryFormat::series, series + "0,,0\n", 2, "empty field 'load_N'"},
      {loads::HistoryFormat::series, series + "0,1e999,0\n", 2, "out of range"},
      {loads::HistoryFormat::series, series + "0,1,0\n\n0,2,0\n", 4, "strictly increasing"},
      {loads::HistoryFormat::series, "# repeat 2\n" + series + "0,1,0\n", 1,
       "only valid in a spectrum"},
      {loads::HistoryFormat::cycles, blocks + "1,0,0,0\n", 2,
       "'count' must be an integer >= 1, got '0'"},
      {loads::HistoryFormat::cycles, blocks + "1,0,0,1.5\n", 2, "'count' must be an integer >= 1"},
      {loads::HistoryFormat::cycles, blocks + "1,0,0,-3\n", 2, "'count' must be an integer >= 1"},
      {loads::HistoryFormat::cycles, blocks + "1,0,0,99999999999999999999\n", 2, "out of range"},
      {loads::HistoryFormat::cycles, blocks + "1,0,nan,1\n", 2,
       "non-finite value 'nan' in 'angle_rad'"},
      // The rows follow check_load_block, the daemon's own rule (R = 1 is no cycle, R >= -10).
      {loads::HistoryFormat::cycles, blocks + "0,0,0,1\n", 2, "p_max = 0 must be > 0"},
      {loads::HistoryFormat::cycles, blocks + "1,1.5,0,1\n", 2, "r = 1.5 must be < 1"},
      {loads::HistoryFormat::cycles, blocks + "1,1,0,1\n", 2, "r = 1 must be < 1"},
      {loads::HistoryFormat::cycles, blocks + "1,-11,0,1\n", 2, "r = -11 must be >= -10"},
      {loads::HistoryFormat::cycles, blocks + "1,0,0\n", 2, "expected 4 fields, got 3"},
      {loads::HistoryFormat::spectrum, blocks + "# repeat 2\n1,0,0,1\n", 2,
       "must be the first line"},
      {loads::HistoryFormat::spectrum, "# repeat 0\n" + blocks + "1,0,0,1\n", 1,
       "'repeat' must be"},
      {loads::HistoryFormat::spectrum, "# repeat x\n" + blocks + "1,0,0,1\n", 1,
       "'repeat' must be"},
      // Found by fuzz_spectrum: the repeat used to be expanded unchecked (std::bad_alloc, the
      // replay tool aborted; 10^8 x 2 blocks took 6 GB and a minute).
      {loads::HistoryFormat::spectrum, "# repeat 100000000000000000\n" + blocks + "1,0,0,1\n", 1,
       "'# repeat 100000000000000000' of 1 blocks expands to more than 1000000 blocks"},
      {loads::HistoryFormat::spectrum, "# repeat 500001\n" + blocks + "1,0,0,1\n2,0,0,1\n", 1,
       "'# repeat 500001' of 2 blocks expands to more than 1000000 blocks"},
      {loads::HistoryFormat::spectrum, "# only comments\n\n", 0, "no header line"},
      {loads::HistoryFormat::spectrum, blocks + "# nothing\n", 0, "no data rows"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(i);
    const fs::path p = write("bad" + std::to_string(i) + ".csv", cases[i].text);
    const auto r = loads::read_blocks(p, cases[i].format);
    ASSERT_FALSE(r.ok());
    const loads::ParseError& e = r.error();
    EXPECT_EQ(e.file, p.string());
    EXPECT_EQ(e.line, cases[i].line);
    const std::string prefix =
        p.string() + (cases[i].line == 0 ? "" : ":" + std::to_string(cases[i].line)) + ": ";
    EXPECT_EQ(e.message().rfind(prefix, 0), 0u) << e.message();
    EXPECT_NE(e.message().find(cases[i].reason), std::string::npos) << e.message();
  }
  const auto missing = loads::read_cycles_csv(dir_ / "missing.csv");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().message(), (dir_ / "missing.csv").string() + ": cannot open file");
}

// ---------------------------------------------------------------- batching

TEST(Batching, SplitsIntoBatchesOfAtMostMaxBlocks) {
  std::vector<core::LoadBlock> blocks;
  for (int i = 0; i < 7; ++i) blocks.push_back({100.0 + i, 0.1, 0, i + 1});
  const auto batches = loads::make_batches(blocks, 3);
  ASSERT_EQ(batches.size(), 3u);
  EXPECT_EQ(batches[0].size(), 3u);
  EXPECT_EQ(batches[1].size(), 3u);
  EXPECT_EQ(batches[2].size(), 1u);
  std::vector<core::LoadBlock> joined;
  for (const auto& b : batches) joined.insert(joined.end(), b.begin(), b.end());
  EXPECT_EQ(joined, blocks);
  EXPECT_EQ(loads::make_batches(blocks, 7).size(), 1u);
  EXPECT_EQ(loads::make_batches(blocks, 100).size(), 1u);
  EXPECT_EQ(loads::make_batches(blocks, 1).size(), 7u);
  EXPECT_TRUE(loads::make_batches({}, 4).empty());
  EXPECT_THROW((void)loads::make_batches(blocks, 0), std::invalid_argument);
}

}  // namespace
}  // namespace peritwin::replay
