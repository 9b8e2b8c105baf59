// dashboard::EventFanout over socket pairs (no HTTP): the slots, every event written to every
// stream in id order (chunk-framed), a new stream caught up from the id it names, a client that
// hangs up closed and its slot given back, a client that reads nothing closed as slow once more
// than max_pending_bytes are queued for it. Every wait has a deadline of a minute; nothing is
// timed.
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "dashboard/event_fanout.h"
#include "dashboard/store.h"
#include "messages/channels.h"
#include "tests/support/http_chunks.h"
#include "tests/support/state_messages.h"

namespace peritwin::dashboard {
namespace {

using testing::dechunk;

constexpr auto kDeadline = std::chrono::seconds(60);

/// Publishes STATE `seq` of detail "fan" into `store` (one event).
void push_state(Store& store, std::int64_t seq) {
  const auto s = testing::minimal_state("fan", seq, 1000 * seq);
  std::vector<unsigned char> bytes(static_cast<std::size_t>(s.getEncodedSize()));
  s.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  store.on_message(messages::channel("fan", messages::Kind::kState), bytes.data(), bytes.size(),
                   Clock::now());
}

/// A connected pair: `server` for the fan-out, `client` read here.
struct Pair {
  Pair() {
    int fds[2];
    ok = ::socketpair(AF_UNIX, SOCK_STREAM, 0, fds) == 0;
    server = fds[0];
    client = fds[1];
  }
  ~Pair() {
    if (client >= 0) ::close(client);
  }
  Pair(const Pair&) = delete;
  Pair& operator=(const Pair&) = delete;
  bool ok = false;
  int server = -1, client = -1;
  std::string raw;  // what the client received
};

/// The "id:" of each event in an SSE body, in order.
std::vector<std::uint64_t> event_ids(const std::string& body) {
  std::vector<std::uint64_t> ids;
  for (auto p = body.find("id: "); p != std::string::npos; p = body.find("id: ", p + 4)) {
    if (p == 0 || body[p - 1] == '\n')
      ids.push_back(std::strtoull(body.c_str() + p + 4, nullptr, 10));
  }
  return ids;
}

/// Reads `p.client` until `done(p.raw)` or end of file; false at the deadline.
bool read_until(Pair& p, const std::function<bool(const std::string&)>& done, bool* eof = nullptr) {
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (!done(p.raw)) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    pollfd f{p.client, POLLIN, 0};
    if (::poll(&f, 1, 200) <= 0) continue;
    char buffer[65536];
    const ssize_t n = ::recv(p.client, buffer, sizeof buffer, 0);
    if (n <= 0) {
      if (eof != nullptr) *eof = true;
      return done(p.raw);
    }
    p.raw.append(buffer, static_cast<std::size_t>(n));
  }
  return true;
}

/// Waits until `condition` holds; false at the deadline.
bool wait_for(const std::function<bool()>& condition) {
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (!condition()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

TEST(EventFanout, SlotsAreCappedAndGivenBack) {
  Store store;
  FanoutLimits limits;
  limits.max_streams = 2;
  EventFanout fanout(store, limits);
  EXPECT_TRUE(fanout.reserve());
  EXPECT_TRUE(fanout.reserve());
  EXPECT_FALSE(fanout.reserve());
  EXPECT_EQ(fanout.stats().refused, 1u);
  EXPECT_EQ(fanout.stats().open, 2u);
  fanout.release();
  EXPECT_TRUE(fanout.reserve());
  fanout.release();
  fanout.release();
  EXPECT_EQ(fanout.stats().open, 0u);
}

TEST(EventFanout, EveryStreamGetsEveryEventInOrderFromTheIdItNames) {
  Store store;
  push_state(store, 0);  // events 1 and 2, before the fan-out starts
  push_state(store, 1);
  EventFanout fanout(store, FanoutLimits{});
  Pair from_start, from_now;
  ASSERT_TRUE(from_start.ok && from_now.ok);
  ASSERT_TRUE(fanout.reserve() && fanout.reserve());
  fanout.adopt(from_start.server, 0);  // catches up: 1, 2
  fanout.adopt(from_now.server, 2);
  for (std::int64_t seq = 2; seq < 6; ++seq) push_state(store, seq);  // events 3..6

  const auto has_six = [](const std::string& raw) {
    const auto ids = event_ids(dechunk(raw));
    return !ids.empty() && ids.back() == 6;
  };
  ASSERT_TRUE(read_until(from_start, has_six)) << from_start.raw;
  ASSERT_TRUE(read_until(from_now, has_six)) << from_now.raw;
  EXPECT_EQ(event_ids(dechunk(from_start.raw)), (std::vector<std::uint64_t>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(event_ids(dechunk(from_now.raw)), (std::vector<std::uint64_t>{3, 4, 5, 6}));
  const std::string body = dechunk(from_now.raw);
  EXPECT_EQ(body.rfind("id: 3\nevent: state\ndata: {\"kind\":\"state\",\"detail\":\"fan\",", 0), 0u)
      << body;

  // A client that hangs up: its stream closed, its slot given back; the other one stays.
  ::close(from_now.client);
  from_now.client = -1;
  ASSERT_TRUE(wait_for([&] { return fanout.stats().closed_gone == 1; }));
  EXPECT_EQ(fanout.stats().open, 1u);
  EXPECT_EQ(fanout.stats().adopted, 2u);
  push_state(store, 6);  // event 7
  ASSERT_TRUE(read_until(from_start, [](const std::string& raw) {
    const auto ids = event_ids(dechunk(raw));
    return !ids.empty() && ids.back() == 7;
  }));
  fanout.stop();  // closes the rest
  EXPECT_EQ(fanout.stats().open, 0u);
}

TEST(EventFanout, AClientThatReadsNothingIsClosedAsSlowAndTheOthersGetEverything) {
  Store store;
  FanoutLimits limits;
  limits.max_pending_bytes = 64 * 1024;
  limits.coalesce = std::chrono::milliseconds(0);
  EventFanout fanout(store, limits);
  Pair slow, reader;
  ASSERT_TRUE(slow.ok && reader.ok);
  ASSERT_TRUE(fanout.reserve() && fanout.reserve());
  fanout.adopt(slow.server, 0);
  fanout.adopt(reader.server, 0);
  // Read as the events come, on another thread; `slow` reads nothing. About 1 kB per event: 900
  // fill the slow client's socket buffer and its 64 kB queue many times over.
  constexpr std::uint64_t kEvents = 900;
  bool read_all = false;
  // The newest event id the reader has seen (from the last "id: " in what it has read: cheap,
  // and a lower bound even when a chunk boundary splits the last one).
  std::atomic<std::uint64_t> newest_read{0};
  std::thread reading([&] {
    read_all = read_until(reader, [&](const std::string& raw) {
      const auto at = raw.rfind("\nid: ");
      if (at != std::string::npos) {
        const std::uint64_t id = std::strtoull(raw.c_str() + at + 5, nullptr, 10);
        if (id > newest_read.load()) newest_read.store(id);
      }
      return newest_read.load() >= kEvents;
    });
  });
  // Fewer than the 1000 events the store keeps: however far the fan-out lags, none is lost. The
  // pushes keep at most 16 events (~16 kB) ahead of the reader, so that a loaded machine that
  // schedules the reading thread late cannot make the reader, too, a slow client; the slow one
  // reads nothing and overflows its 64 kB queue all the same.
  bool paced = true;
  for (std::uint64_t seq = 0; seq < kEvents && paced; ++seq) {
    push_state(store, static_cast<std::int64_t>(seq));
    if (seq >= 16) paced = wait_for([&] { return newest_read.load() + 16 >= seq + 1; });
  }
  reading.join();
  ASSERT_TRUE(paced) << "the reader stuck at event " << newest_read.load();
  ASSERT_TRUE(read_all) << reader.raw.size() << " bytes";
  std::vector<std::uint64_t> expected(kEvents);
  for (std::uint64_t i = 0; i < kEvents; ++i) expected[i] = i + 1;
  EXPECT_EQ(event_ids(dechunk(reader.raw)), expected);
  ASSERT_TRUE(wait_for([&] { return fanout.stats().closed_slow == 1; }));
  EXPECT_EQ(fanout.stats().open, 1u);
  // The slow client finds what was sent before, then the end of the stream.
  bool eof = false;
  EXPECT_TRUE(read_until(
                  slow, [](const std::string&) { return false; }, &eof) ||
              eof);
  EXPECT_TRUE(eof);
  EXPECT_LT(event_ids(dechunk(slow.raw)).size(), kEvents);
}

}  // namespace
}  // namespace peritwin::dashboard
