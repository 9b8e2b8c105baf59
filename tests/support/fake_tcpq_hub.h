// A stand-in for LCM's tcpq hub on a loopback port, in a thread of the test: it accepts one
// client, answers the handshake of LCM 1.3.1's tcpq provider (lcm/lcm_tcpq.c: the client sends
// 0x287617fb and its version, the hub 0x287617fa and its version), reads SUBSCRIBE and PUBLISH
// messages, and closes the connection and its listening socket after `publishes_before_close`
// PUBLISH messages (0: right after the handshake) — a hub that dies, as the client sees it.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

namespace peritwin::testing {

class FakeTcpqHub {
 public:
  explicit FakeTcpqHub(int publishes_before_close) : close_after_(publishes_before_close) {
    listener_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = 0;
    bind(listener_, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    listen(listener_, 4);
    socklen_t len = sizeof addr;
    getsockname(listener_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    thread_ = std::thread([this] { serve(); });
  }
  ~FakeTcpqHub() {
    stop_ = true;
    thread_.join();
    if (listener_ >= 0) close(listener_);
  }
  FakeTcpqHub(const FakeTcpqHub&) = delete;
  FakeTcpqHub& operator=(const FakeTcpqHub&) = delete;

  [[nodiscard]] int port() const { return port_; }
  [[nodiscard]] std::string url() const { return "tcpq://127.0.0.1:" + std::to_string(port_); }
  /// PUBLISH messages read before the close.
  [[nodiscard]] int publishes() const { return publishes_.load(); }
  /// True once the client's connection was closed.
  [[nodiscard]] bool closed() const { return closed_.load(); }

 private:
  /// Reads n bytes (false at end of stream, on error or once stop_ is set).
  bool read_exactly(int fd, void* buf, std::size_t n) {
    auto* p = static_cast<unsigned char*>(buf);
    while (n > 0) {
      pollfd pfd{fd, POLLIN, 0};
      if (poll(&pfd, 1, 50) == 0) {
        if (stop_) return false;
        continue;
      }
      const ssize_t got = read(fd, p, n);
      if (got <= 0) return false;
      p += got;
      n -= static_cast<std::size_t>(got);
    }
    return true;
  }
  bool read_u32(int fd, std::uint32_t* v) {
    std::uint32_t n = 0;
    if (!read_exactly(fd, &n, 4)) return false;
    *v = ntohl(n);
    return true;
  }
  bool skip(int fd, std::uint32_t n) {
    std::vector<unsigned char> buf(n);
    return n == 0 || read_exactly(fd, buf.data(), n);
  }
  void serve() {
    pollfd pfd{listener_, POLLIN, 0};
    while (!stop_ && poll(&pfd, 1, 50) == 0) {
    }
    if (stop_) return;
    const int client = accept(listener_, nullptr, nullptr);
    std::uint32_t magic = 0, version = 0;
    if (client >= 0 && read_u32(client, &magic) && read_u32(client, &version)) {
      const std::uint32_t reply[2] = {htonl(0x287617fa), htonl(0x0100)};
      bool ok = write(client, reply, sizeof reply) == sizeof reply;
      while (ok && publishes_ < close_after_) {
        std::uint32_t type = 0, channel_len = 0, data_len = 0;
        ok = read_u32(client, &type) && read_u32(client, &channel_len) && skip(client, channel_len);
        if (ok && type == 1) {  // PUBLISH: then the payload
          ok = read_u32(client, &data_len) && skip(client, data_len);
          if (ok) ++publishes_;
        }
      }
    }
    close(listener_);  // no reconnection either
    listener_ = -1;
    if (client >= 0) close(client);
    closed_ = true;
  }

  int close_after_;
  int listener_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false}, closed_{false};
  std::atomic<int> publishes_{0};
  std::thread thread_;
};

}  // namespace peritwin::testing
