#include "messages/hub_connection.h"

#include <spdlog/spdlog.h>

#include <thread>

namespace peritwin::messages {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

HubConnection::HubConnection(std::string url, std::function<bool()> keep_going)
    : url_(std::move(url)),
      shown_(messages::shown_url(url_)),
      keep_going_(std::move(keep_going)),
      hub_(messages::tcpq_hub(url_)) {}

bool HubConnection::wait(double seconds) const {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (keep_going_() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return keep_going_();
}

std::unique_ptr<lcm::LCM> HubConnection::open() {
  since_ = std::chrono::steady_clock::now();
  bool waited = false;
  while (true) {
    core::Status reachable = hub_ ? messages::probe_hub(*hub_) : core::Status{};
    if (reachable) {
      auto lcm = std::make_unique<lcm::LCM>(url_);
      if (!lcm->good()) {
        error_ = "cannot open LCM at \"" + shown_ + "\"";
        return nullptr;
      }
      if (messages::transport_up(*lcm)) {
        if (waited)
          spdlog::info("LCM hub {} reachable after {:.1f} s", shown_, seconds_since(since_));
        connected_ = true;
        backoff_.reset();
        return lcm;
      }
      reachable = core::failure("LCM could not connect");  // the hub went away meanwhile
    }
    if (!waited) {
      spdlog::warn("LCM hub {} unreachable ({}): waiting for it, retrying every {} s to {} s",
                   shown_, reachable.error().message(), backoff_.first_s(), backoff_.max_s());
      waited = true;
    }
    if (!wait(backoff_.next())) return nullptr;
  }
}

bool HubConnection::check(lcm::LCM& lcm) {
  if (connected_ && !messages::transport_up(lcm)) {
    connected_ = false;
    since_ = std::chrono::steady_clock::now();
    backoff_.reset();
    spdlog::warn(
        "LCM hub {}: connection lost; the models are kept, reconnecting every {} s to {} s", shown_,
        backoff_.first_s(), backoff_.max_s());
  }
  return connected_;
}

bool HubConnection::reconnect(lcm::LCM& lcm) {
  if (connected_) return true;
  if (!wait(backoff_.next())) return false;
  if (hub_ && !messages::probe_hub(*hub_)) return false;  // still down: leave LCM alone
  if (!messages::reconnect(lcm)) return false;            // LCM re-sends the daemon's subscriptions
  connected_ = true;
  backoff_.reset();
  spdlog::info("LCM hub {}: reconnected after {:.1f} s", shown_, seconds_since(since_));
  return true;
}

}  // namespace peritwin::messages
