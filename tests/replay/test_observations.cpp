// Issue 32's inputs: the observations file (loads/load_history.h read_observations_csv) and the
// batches split at the observations' cycles (replay/learning.h).
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "loads/load_history.h"
#include "replay/learning.h"

namespace peritwin {
namespace {

constexpr const char* kHeader = "cycle,kind,origin,length_m,sigma_m,pod_a50_m,pod_slope\n";

loads::ReadResult<std::vector<messages::Observation>> read(const std::string& rows) {
  std::istringstream in(std::string(kHeader) + rows);
  return loads::read_observations_csv(in, "obs.csv");
}

TEST(Observations, BothKindsAreReadWithTheirFields) {
  const auto r = read(
      "# an eddy-current inspection, then a measured crack\n"
      "5000,no_crack,,,,0.001,3\n"
      "20000,crack_length,notch 0,0.0031,0.0003,,\n");
  ASSERT_TRUE(r.ok()) << r.error().message();
  ASSERT_EQ(r->size(), 2u);
  EXPECT_EQ((*r)[0].cycle, 5000);
  EXPECT_EQ((*r)[0].kind, messages::ObservationKind::no_crack);
  EXPECT_EQ((*r)[0].origin, "longest");
  EXPECT_DOUBLE_EQ((*r)[0].pod_a50_m, 0.001);
  EXPECT_DOUBLE_EQ((*r)[0].pod_slope, 3.0);
  EXPECT_EQ((*r)[1].kind, messages::ObservationKind::crack_length);
  EXPECT_EQ((*r)[1].origin, "notch 0");
  EXPECT_DOUBLE_EQ((*r)[1].length_m, 0.0031);
  EXPECT_DOUBLE_EQ((*r)[1].sigma_m, 0.0003);
}

TEST(Observations, EveryBadRowIsRefusedWithItsLineAndField) {
  struct Case {
    std::string rows, expected;
  };
  for (const Case& c : {
           Case{"-1,crack_length,longest,0.001,0.0001,,\n", "obs.csv:2: 'cycle' must be"},
           Case{"10,crack,longest,0.001,0.0001,,\n", "'kind' must be crack_length or no_crack"},
           Case{"10,crack_length,longest,-0.001,0.0001,,\n", "'length_m' must be a finite"},
           Case{"10,crack_length,longest,0.001,0,,\n", "'sigma_m' must be a finite"},
           Case{"10,crack_length,longest,0.001,0.0001,0.001,\n", "'pod_a50_m' must be empty"},
           Case{"10,no_crack,longest,,,0.001,-2\n", "'pod_slope' must be finite and > 0"},
           Case{"10,no_crack,longest,0.002,,0.001,2\n", "'length_m' must be empty"},
           Case{"20,no_crack,,,,0.001,2\n10,no_crack,,,,0.001,2\n",
                "obs.csv:3: 'cycle' 10 is before"},
           Case{"10,no_crack,,,,nan,2\n", "non-finite value 'nan'"},
       }) {
    const auto r = read(c.rows);
    ASSERT_FALSE(r.ok()) << c.rows;
    EXPECT_NE(r.error().message().find(c.expected), std::string::npos)
        << r.error().message() << " (expected: " << c.expected << ")";
  }
  std::istringstream wrong("cycle,kind,length_m\n1,no_crack,0\n");
  const auto header = loads::read_observations_csv(wrong, "obs.csv");
  ASSERT_FALSE(header.ok());
  EXPECT_NE(header.error().message().find("expected header"), std::string::npos);
}

// Batches of 1000 cycles split at 2500 and 3000 (a boundary already) and 3200: every cycle kept
// in order, a batch ends at each observation's cycle, seqs numbered again from the first.
TEST(Observations, BatchesAreSplitAtTheObservationsCycles) {
  std::vector<messages::Batch> batches;
  for (int k = 0; k < 4; ++k) {
    batches.push_back({"b1-ct", "replay", 10 + k, {{4000, 0.1, 0.0, 600}, {4200, 0.1, 0.0, 400}}});
  }
  const auto split = replay::split_batches_at(batches, {2500, 3000, 3000, 3200});
  std::int64_t total = 0;
  std::vector<std::int64_t> ends;
  for (std::size_t i = 0; i < split.size(); ++i) {
    EXPECT_EQ(split[i].seq, 10 + static_cast<std::int64_t>(i));
    for (const auto& b : split[i].blocks) total += b.count;
    ends.push_back(total);
  }
  EXPECT_EQ(total, 4000);
  EXPECT_EQ(ends, (std::vector<std::int64_t>{1000, 2000, 2500, 3000, 3200, 4000}));
  // The block around 2500 (the third batch's first, 4000 N, cycles 2000-2600) split in two.
  ASSERT_EQ(split[2].blocks.size(), 1u);
  EXPECT_EQ(split[2].blocks[0].count, 500);
  EXPECT_EQ(split[3].blocks[0].count, 100);
  EXPECT_DOUBLE_EQ(split[3].blocks[0].p_max, 4000);
  // No observation: the batches as they were.
  const auto same = replay::split_batches_at(batches, {});
  ASSERT_EQ(same.size(), batches.size());
  for (std::size_t i = 0; i < same.size(); ++i) EXPECT_EQ(same[i].blocks.size(), 2u);
}

}  // namespace
}  // namespace peritwin
