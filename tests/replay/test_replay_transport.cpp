// The replay client when the tcpq hub goes away under it: the run fails, saying so, instead of
// aborting in FD_SET (issue 14, finding 5). The hub is a stand-in that closes the connection after
// a few batches (tests/support/fake_tcpq_hub.h); peritwin-replay turns this into exit 3 with the
// URL (tests/twin/test_transport.cpp runs that with LCM's own hub).
#include <gtest/gtest.h>

#include "messages/transport.h"
#include "replay/replay_tool.h"
#include "tests/support/fake_tcpq_hub.h"

namespace peritwin::replay {
namespace {

TEST(ReplayTransport, HubClosingMidRunFailsTheRun) {
  testing::FakeTcpqHub hub(3);
  lcm::LCM lcm(hub.url());
  ASSERT_TRUE(messages::transport_up(lcm));
  std::vector<core::LoadBlock> blocks(10, {4000, 0.1, 0, 1});
  loads::ReplayOptions options;
  options.window = 8;
  options.give_up_after_s = 600;
  replay::ReplayResult result;
  {
    replay::LcmReplayer replayer(lcm, loads::make_twin_batches(blocks, "b1-ct", "test", {1, 1000}),
                                 options);
    result = replayer.run({}, {});
  }
  EXPECT_FALSE(result.ok);
  EXPECT_EQ(result.error, "connection lost (no state from the daemon yet)");
  EXPECT_FALSE(result.final_state.has_value());
  EXPECT_EQ(hub.publishes(), 3);
  EXPECT_GE(result.published, 3);
  EXPECT_LE(result.published, 8);  // stops publishing once the connection is gone
  EXPECT_FALSE(messages::transport_up(lcm));
}

}  // namespace
}  // namespace peritwin::replay
