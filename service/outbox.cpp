#include "service/outbox.h"

#include <sys/eventfd.h>
#include <unistd.h>

#include <utility>

#include "messages/codec.h"

namespace peritwin::service {

Outbox::Outbox() : wake_fd_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {}

Outbox::~Outbox() {
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

void Outbox::push(Outgoing m) {
  {
    std::lock_guard lock(mutex_);
    queue_.push_back(std::move(m));
  }
  if (wake_fd_ >= 0) {
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto n = ::write(wake_fd_, &one, sizeof one);
  }
}

std::deque<Outgoing> Outbox::take() {
  if (wake_fd_ >= 0) {
    std::uint64_t count = 0;
    [[maybe_unused]] const auto n = ::read(wake_fd_, &count, sizeof count);
  }
  std::lock_guard lock(mutex_);
  return std::exchange(queue_, {});
}

void Outbox::flush(lcm::LCM& lcm, std::vector<double>* latencies) {
  for (auto& m : take()) {
    lcm.publish(m.channel, m.bytes.data(), static_cast<unsigned>(m.bytes.size()));
    if (latencies != nullptr && m.recv_utime > 0) {
      // From LCM's receive time (wall clock, us): includes the wait in the inbox.
      latencies->push_back(1e-6 * static_cast<double>(messages::now_utime() - m.recv_utime));
    }
  }
}

}  // namespace peritwin::service
