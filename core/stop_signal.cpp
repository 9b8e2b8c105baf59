#include "core/stop_signal.h"

#include <atomic>
#include <csignal>

namespace peritwin::core {
namespace {
std::atomic<int> g_signal{0};
extern "C" void on_stop_signal(int signal) { g_signal.store(signal); }
}  // namespace

void install_stop_handler() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
}

int stop_signal() { return g_signal.load(); }

}  // namespace peritwin::core
