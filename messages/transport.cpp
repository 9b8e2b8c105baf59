#include "messages/transport.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string_view>

namespace peritwin::messages {

std::optional<TcpqHub> tcpq_hub(const std::string& url) {
  std::string u = url;
  if (u.empty()) {
    if (const char* env = std::getenv("LCM_DEFAULT_URL")) u = env;
  }
  constexpr std::string_view kScheme = "tcpq://";
  if (u.compare(0, kScheme.size(), kScheme) != 0) return std::nullopt;
  std::string network = u.substr(kScheme.size());
  network = network.substr(0, network.find('?'));
  if (network.empty()) network = "127.0.0.1:7700";  // lcm_tcpq_create's default
  TcpqHub hub;
  const auto colon = network.find(':');
  hub.host = network.substr(0, colon);
  in_addr addr{};
  if (inet_aton(hub.host.c_str(), &addr) != 0) hub.address = addr.s_addr;
  if (colon != std::string::npos) {
    const std::string port = network.substr(colon + 1);
    char* end = nullptr;
    const long p = std::strtol(port.c_str(), &end, 0);  // base 0, as the provider parses it
    if (end == port.c_str() || p < 0 || p > 65535) return std::nullopt;
    hub.port = static_cast<std::uint16_t>(p);
  }
  return hub;
}

core::Status probe_hub(const TcpqHub& hub, double timeout_s) {
  const int s = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (s < 0) return core::failure(std::string("cannot create a socket: ") + std::strerror(errno));
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(hub.port);
  sa.sin_addr.s_addr = hub.address;
  int err = 0;
  if (connect(s, reinterpret_cast<const sockaddr*>(&sa), sizeof sa) != 0) {
    err = errno;
    if (err == EINPROGRESS) {
      pollfd p{s, POLLOUT, 0};
      const int ready = poll(&p, 1, static_cast<int>(std::lround(1e3 * timeout_s)));
      if (ready == 0) {
        close(s);
        char buf[64];
        std::snprintf(buf, sizeof buf, "no answer within %g s", timeout_s);
        return core::failure(buf);
      }
      socklen_t len = sizeof err;
      if (ready < 0) {
        err = errno;
      } else if (getsockopt(s, SOL_SOCKET, SO_ERROR, &err, &len) != 0) {
        err = errno;
      }
    }
  }
  close(s);
  if (err != 0) return core::failure(std::strerror(err));
  return {};
}

bool transport_up(lcm::LCM& lcm) { return lcm.getFileno() >= 0; }

core::Status reconnect(lcm::LCM& lcm) {
  if (transport_up(lcm)) return {};
  lcm::Subscription* probe = lcm.subscribeFunction(
      "PERITWIN_RECONNECT_PROBE", +[](const lcm::ReceiveBuffer*, const std::string&, void*) {},
      static_cast<void*>(nullptr));
  if (probe != nullptr) lcm.unsubscribe(probe);
  if (!transport_up(lcm)) return core::failure("LCM could not connect");
  return {};
}

std::string shown_url(const std::string& url) { return url.empty() ? "(LCM default)" : url; }

}  // namespace peritwin::messages
