// The LCM transport helpers (messages/transport.h) and handle_lcm without a hub: LCM 1.3.1's
// tcpq provider leaves its socket at -1 when the hub is down or has closed the connection, and
// lcm.handleTimeout() then aborted in FD_SET (issue 14, finding 5).
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/loopback_port.h"
#include "messages/codec.h"
#include "messages/transport.h"
#include "tests/support/fake_tcpq_hub.h"

namespace peritwin::messages {
namespace {

std::uint32_t ipv4(const char* text) {
  in_addr a{};
  inet_aton(text, &a);
  return a.s_addr;
}

TEST(TcpqHub, AsLcmReadsTheUrl) {
  const auto hub = messages::tcpq_hub("tcpq://127.0.0.1:7701");
  ASSERT_TRUE(hub.has_value());
  EXPECT_EQ(hub->host, "127.0.0.1");
  EXPECT_EQ(hub->address, ipv4("127.0.0.1"));
  EXPECT_EQ(hub->port, 7701);
  const auto with_options = messages::tcpq_hub("tcpq://10.1.2.3:0x1e15?foo=bar");  // strtol base 0
  ASSERT_TRUE(with_options.has_value());
  EXPECT_EQ(with_options->address, ipv4("10.1.2.3"));
  EXPECT_EQ(with_options->port, 7701);
  const auto defaults = messages::tcpq_hub("tcpq://");  // lcm_tcpq_create's 127.0.0.1:7700
  ASSERT_TRUE(defaults.has_value());
  EXPECT_EQ(defaults->address, ipv4("127.0.0.1"));
  EXPECT_EQ(defaults->port, 7700);
  const auto name =
      messages::tcpq_hub("tcpq://localhost:7000");  // never resolved by LCM 1.3.1: 0.0.0.0
  ASSERT_TRUE(name.has_value());
  EXPECT_EQ(name->address, 0u);
  EXPECT_EQ(name->port, 7000);
  EXPECT_FALSE(messages::tcpq_hub("tcpq://127.0.0.1:65536").has_value());
  EXPECT_FALSE(messages::tcpq_hub("udpm://239.255.76.67:7667?ttl=0").has_value());
  EXPECT_FALSE(messages::tcpq_hub("memq://").has_value());
}

TEST(TcpqHub, ProbeTellsListeningFromRefused) {
  testing::FakeTcpqHub listening(0);
  const auto up = messages::tcpq_hub(listening.url());
  ASSERT_TRUE(up.has_value());
  EXPECT_TRUE(messages::probe_hub(*up).ok());
  const auto down =
      messages::tcpq_hub("tcpq://127.0.0.1:" + std::to_string(core::free_loopback_port()));
  ASSERT_TRUE(down.has_value());
  const core::Status refused = messages::probe_hub(*down);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().message(), "Connection refused");
}

TEST(Backoff, DoublesFromATenthToFiveSeconds) {
  messages::Backoff backoff;
  const std::vector<double> expected{0.1, 0.2, 0.4, 0.8, 1.6, 3.2, 5.0, 5.0};
  for (const double e : expected) EXPECT_DOUBLE_EQ(backoff.next(), e);
  backoff.reset();
  EXPECT_DOUBLE_EQ(backoff.next(), 0.1);
}

TEST(HandleLcm, WithoutHubWaitsAndReturnsZero) {
  lcm::LCM lcm("tcpq://127.0.0.1:" + std::to_string(core::free_loopback_port()));
  ASSERT_TRUE(lcm.good());         // LCM 1.3.1 says good without a connection ...
  EXPECT_EQ(lcm.getFileno(), -1);  // ... and its descriptor is -1
  EXPECT_FALSE(messages::transport_up(lcm));
  EXPECT_EQ(messages::handle_lcm(lcm, 10), 0);  // lcm.handleTimeout() aborted here
  EXPECT_EQ(messages::handle_lcm(lcm, 0), 0);
  lcm::LCM memq("memq://");  // no connection to lose
  EXPECT_TRUE(messages::transport_up(memq));
}

TEST(HandleLcm, HubClosingTheConnectionIsNoFailure) {
  testing::FakeTcpqHub hub(0);  // closes right after the handshake
  lcm::LCM lcm(hub.url());
  ASSERT_TRUE(messages::transport_up(lcm));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  int calls = 0;
  while (messages::transport_up(lcm) && std::chrono::steady_clock::now() < deadline) {
    EXPECT_EQ(messages::handle_lcm(lcm, 100),
              0);  // the end of the stream is handled, not a message
    ++calls;
  }
  EXPECT_FALSE(messages::transport_up(lcm));
  EXPECT_GE(calls, 1);
  EXPECT_EQ(messages::handle_lcm(lcm, 10), 0);  // and after it, no FD_SET(-1)
}

TEST(Reconnect, SameInstanceResubscribesAndPublishesNothing) {
  testing::FakeTcpqHub hub(0, /*accept_again=*/true);  // closes the first connection at once
  lcm::LCM lcm(hub.url());
  auto* sub = lcm.subscribeFunction(
      "PERITWIN_B1_CT_LOAD", +[](const lcm::ReceiveBuffer*, const std::string&, void*) {},
      static_cast<void*>(nullptr));
  ASSERT_NE(sub, nullptr);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (messages::transport_up(lcm) && std::chrono::steady_clock::now() < deadline)
    messages::handle_lcm(lcm, 100);
  ASSERT_FALSE(messages::transport_up(lcm));
  ASSERT_TRUE(messages::reconnect(lcm).ok());
  EXPECT_TRUE(messages::transport_up(lcm));
  // The hub saw the daemon's subscription again and the probe's come and go, and no message.
  while ((hub.resubscribes() < 2 || hub.unsubscribes() < 1) &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(hub.resubscribes(), 2);  // PERITWIN_B1_CT_LOAD and the probe
  EXPECT_EQ(hub.unsubscribes(), 1);  // the probe
  EXPECT_EQ(hub.republishes(), 0);
  EXPECT_TRUE(messages::reconnect(lcm).ok());  // connected: nothing to do
  lcm.unsubscribe(sub);
}

TEST(Reconnect, WithoutHubFails) {
  lcm::LCM lcm("tcpq://127.0.0.1:" + std::to_string(core::free_loopback_port()));
  const core::Status again = messages::reconnect(lcm);
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(again.error().message(), "LCM could not connect");
  lcm::LCM memq("memq://");
  EXPECT_TRUE(messages::reconnect(memq).ok());
}

}  // namespace
}  // namespace peritwin::messages
