// A stand-in for LCM's tcpq hub on a loopback port, in a thread of the test: it accepts one
// client, answers the handshake of LCM 1.3.1's tcpq provider (lcm/lcm_tcpq.c: the client sends
// 0x287617fb and its version, the hub 0x287617fa and its version), reads SUBSCRIBE and PUBLISH
// messages, and closes the connection after `publishes_before_close` PUBLISH messages (0: right
// after the handshake) — a hub that dies, as the client sees it. Then it stops listening, or,
// with `accept_again`, serves one more client (a restarted hub) until it is destroyed, counting
// what that client subscribes to and publishes.
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
  explicit FakeTcpqHub(int publishes_before_close, bool accept_again = false)
      : close_after_(publishes_before_close), accept_again_(accept_again) {
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
  /// The second client's SUBSCRIBE / UNSUBSCRIBE / PUBLISH messages so far (accept_again).
  [[nodiscard]] int resubscribes() const { return resubscribes_.load(); }
  [[nodiscard]] int unsubscribes() const { return unsubscribes_.load(); }
  [[nodiscard]] int republishes() const { return republishes_.load(); }

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
  /// Accepts a client and answers its handshake: the client's descriptor, or -1.
  int accept_client() {
    pollfd pfd{listener_, POLLIN, 0};
    while (!stop_ && poll(&pfd, 1, 50) == 0) {
    }
    if (stop_) return -1;
    const int client = accept(listener_, nullptr, nullptr);
    std::uint32_t magic = 0, version = 0;
    const std::uint32_t reply[2] = {htonl(0x287617fa), htonl(0x0100)};
    if (client >= 0 && read_u32(client, &magic) && read_u32(client, &version) &&
        write(client, reply, sizeof reply) == sizeof reply) {
      return client;
    }
    if (client >= 0) close(client);
    return -1;
  }
  /// Reads messages, calling count(type) after each, until it returns false (true) or the
  /// stream ends (false).
  template <typename Count>
  bool read_messages(int client, const Count& count) {
    while (true) {
      std::uint32_t type = 0, channel_len = 0, data_len = 0;
      if (!read_u32(client, &type) || !read_u32(client, &channel_len) ||
          !skip(client, channel_len)) {
        return false;
      }
      if (type == 1 && (!read_u32(client, &data_len) || !skip(client, data_len))) return false;
      if (!count(type)) return true;
    }
  }
  void serve() {
    const int client = accept_client();
    if (client >= 0 && close_after_ > 0) {
      read_messages(client, [&](std::uint32_t type) {
        if (type == 1) ++publishes_;
        return publishes_ < close_after_;
      });
    }
    if (!accept_again_) {
      close(listener_);  // no reconnection either
      listener_ = -1;
    }
    if (client >= 0) close(client);
    closed_ = true;
    if (accept_again_) {
      const int again = accept_client();
      if (again >= 0) {
        read_messages(again, [&](std::uint32_t type) {
          (type == 1 ? republishes_ : type == 2 ? resubscribes_ : unsubscribes_)++;
          return true;
        });
        close(again);
      }
      close(listener_);
      listener_ = -1;
    }
  }

  int close_after_;
  bool accept_again_;
  int listener_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false}, closed_{false};
  std::atomic<int> publishes_{0}, resubscribes_{0}, unsubscribes_{0}, republishes_{0};
  std::thread thread_;
};

}  // namespace peritwin::testing
