#include "service/duplicate_twin.h"

#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>

#include "messages/channels.h"
#include "messages/codec.h"
#include "messages/transport.h"

namespace peritwin::service {

const DaemonIdentity& DaemonIdentity::self() {
  static const DaemonIdentity me = [] {
    DaemonIdentity id;
    std::array<char, 256> host{};
    if (::gethostname(host.data(), host.size() - 1) == 0) id.host = host.data();
    id.pid = static_cast<std::int32_t>(::getpid());
    id.started_utime = messages::now_utime();
    return id;
  }();
  return me;
}

std::string OtherTwin::describe() const {
  return "detail \"" + detail_id + "\" already has a twin: peritwin pid " +
         std::to_string(daemon.pid) + " on host \"" + daemon.host + "\" (up " +
         std::to_string(static_cast<long long>(uptime_s)) + " s, health " + health + ")";
}

namespace {

class StatusWatch {
 public:
  StatusWatch(lcm::LCM& lcm, const std::vector<std::string>& detail_ids) : lcm_(lcm) {
    for (const auto& id : detail_ids) {
      subs_.push_back(lcm_.subscribe(messages::channel(id, messages::Kind::kStatus),
                                     &StatusWatch::on_status, this));
    }
  }
  ~StatusWatch() {
    for (auto* s : subs_) lcm_.unsubscribe(s);
  }
  StatusWatch(const StatusWatch&) = delete;
  StatusWatch& operator=(const StatusWatch&) = delete;
  std::optional<OtherTwin> found;

 private:
  void on_status(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (found) return;
    const auto s = messages::decode_status(rbuf->data, static_cast<std::size_t>(rbuf->data_size));
    if (!s) return;
    const DaemonIdentity& me = DaemonIdentity::self();
    if (s->host == me.host && s->pid == me.pid && s->started_utime == me.started_utime) return;
    // A daemon that says it is stopping (its last STATUS after SIGTERM) is going away: a restart
    // that follows it at once is no second twin.
    if (s->health == "stopping") return;
    found = OtherTwin{s->detail_id, {s->host, s->pid, s->started_utime}, s->health, s->uptime_s};
  }
  lcm::LCM& lcm_;
  std::vector<lcm::Subscription*> subs_;
};

}  // namespace

std::optional<OtherTwin> find_other_twin(lcm::LCM& lcm, const std::vector<std::string>& detail_ids,
                                         double window_s) {
  StatusWatch watch(lcm, detail_ids);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(window_s);
  while (!watch.found && std::chrono::steady_clock::now() < until) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        until - std::chrono::steady_clock::now());
    if (messages::handle_lcm(lcm, static_cast<int>(std::max<std::int64_t>(left.count(), 1))) < 0 &&
        errno != EINTR) {
      break;
    }
  }
  return watch.found;
}

}  // namespace peritwin::service
