// The daemon's outbox: the messages the detail workers want published (STATE, REJECT, FIELD,
// MESH), queued in order and taken out by the LCM thread, the only one that touches LCM; an
// eventfd wakes that thread's poll() when something is queued. STATUS does not go through it (the
// LCM thread publishes it from its own timer).
#pragma once

#include <cstdint>
#include <deque>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <string>
#include <vector>

namespace peritwin::service {

/// An LCM message encoded to bytes.
template <class Message>
std::vector<std::uint8_t> encode(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

struct Outgoing {
  std::string channel;
  std::vector<std::uint8_t> bytes;
  std::int64_t recv_utime = 0;  ///< of the batch this STATE answers (latency), 0 otherwise
};

/// Messages the workers want published, taken out by the LCM thread; an eventfd wakes it.
class Outbox {
 public:
  Outbox();
  ~Outbox();
  Outbox(const Outbox&) = delete;
  Outbox& operator=(const Outbox&) = delete;

  /// Any thread.
  void push(Outgoing m);
  /// LCM thread: everything queued so far, in order.
  std::deque<Outgoing> take();
  /// LCM thread: publishes everything queued so far, in order; with `latencies`, appends the LCM
  /// receive time -> publish latency (s) of each message answering a batch (recv_utime > 0).
  void flush(lcm::LCM& lcm, std::vector<double>* latencies);
  /// Readable when something was pushed since the last take() (for poll()).
  [[nodiscard]] int wake_fd() const { return wake_fd_; }

 private:
  int wake_fd_;
  std::mutex mutex_;
  std::deque<Outgoing> queue_;
};

}  // namespace peritwin::service
