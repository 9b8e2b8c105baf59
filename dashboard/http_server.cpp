#include "dashboard/http_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <mutex>
#include <string_view>
#include <thread>
#include <vector>

namespace peritwin::dashboard {
namespace {

using SteadyClock = std::chrono::steady_clock;

/// The largest request body read (no route takes one).
constexpr std::size_t kMaxPayload = 64 * 1024;

/// The connection a worker is answering, and whether a route took it (take_connection).
struct Answering {
  socket_t sock = INVALID_SOCKET;
  bool taken = false;
};
thread_local Answering answering;

void close_connection(socket_t sock) {
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
}

/// poll() one socket for `events` up to `timeout`; its revents, 0 on timeout, -1 on error.
int poll_one(socket_t sock, short events, std::chrono::milliseconds timeout) {
  pollfd p{sock, events, 0};
  int n;
  do {
    n = ::poll(&p, 1, static_cast<int>(timeout.count()));
  } while (n < 0 && errno == EINTR);
  return n <= 0 ? n : p.revents;
}

/// A connected socket as httplib's Stream, unbuffered: the gate peeks what is left for the next
/// request, so nothing may be read ahead of the one being answered.
class SocketStream final : public httplib::Stream {
 public:
  SocketStream(socket_t sock, const ServerLimits& limits)
      : sock_(sock),
        read_deadline_(SteadyClock::now() + limits.read_timeout),
        write_timeout_(limits.write_timeout) {}

  /// Everything of one request is read by `read_deadline_`, the read timeout after the worker
  /// took it: its headers are already there (the gate waited for them), and a body dribbled in
  /// slowly (a byte every few seconds) must not hold the worker longer than that.
  bool is_readable() const override {
    const auto left =
        std::chrono::ceil<std::chrono::milliseconds>(read_deadline_ - SteadyClock::now());
    return left.count() > 0 && poll_one(sock_, POLLIN, left) > 0;
  }
  /// False once the client is gone (it hung up or reset), or takes nothing for the write timeout
  /// (DataSink::is_writable of a content provider).
  bool is_writable() const override {
    const int r = poll_one(sock_, POLLOUT | POLLRDHUP, write_timeout_);
    return r > 0 && (r & (POLLRDHUP | POLLHUP | POLLERR | POLLNVAL)) == 0;
  }
  ssize_t read(char* ptr, size_t size) override {
    if (!is_readable()) return -1;
    ssize_t n;
    do {
      n = ::recv(sock_, ptr, size, 0);
    } while (n < 0 && errno == EINTR);
    return n;
  }
  ssize_t write(const char* ptr, size_t size) override {
    if (poll_one(sock_, POLLOUT, write_timeout_) <= 0) return -1;
    ssize_t n;
    do {
      n = ::send(sock_, ptr, size, MSG_NOSIGNAL);
    } while (n < 0 && errno == EINTR);
    return n;
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    address(&::getpeername, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    address(&::getsockname, ip, port);
  }
  socket_t socket() const override { return sock_; }

 private:
  void address(int (*get)(int, sockaddr*, socklen_t*), std::string& ip, int& port) const {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    if (get(sock_, reinterpret_cast<sockaddr*>(&a), &len) != 0) return;
    char text[INET6_ADDRSTRLEN] = {};
    if (a.ss_family == AF_INET) {
      const auto* in = reinterpret_cast<const sockaddr_in*>(&a);
      ::inet_ntop(AF_INET, &in->sin_addr, text, sizeof text);
      port = ntohs(in->sin_port);
    } else if (a.ss_family == AF_INET6) {
      const auto* in6 = reinterpret_cast<const sockaddr_in6*>(&a);
      ::inet_ntop(AF_INET6, &in6->sin6_addr, text, sizeof text);
      port = ntohs(in6->sin6_port);
    }
    ip = text;
  }

  socket_t sock_;
  SteadyClock::time_point read_deadline_;
  std::chrono::milliseconds write_timeout_;
};

}  // namespace

int take_connection() {
  if (answering.sock == INVALID_SOCKET || answering.taken) return -1;
  answering.taken = true;
  return answering.sock;
}

/// The server's task queue: httplib's accept loop "enqueues" each new connection, which is handed
/// to the gate at once on the accept thread (never waiting for a worker); the gate gives a
/// connection to the workers once its request headers are all there.
class BoundedServer::Pool final : public httplib::TaskQueue {
 public:
  explicit Pool(BoundedServer& server)
      : server_(server), workers_(server.limits_.workers), wake_(::eventfd(0, EFD_NONBLOCK)) {
    gate_ = std::thread([this] { run_gate(); });
    server_.pool_ = this;
  }
  ~Pool() override {
    server_.pool_ = nullptr;
    if (wake_ >= 0) ::close(wake_);
  }

  /// Only the accept loop calls this, with process_and_close_socket(sock): quick, see there.
  void enqueue(std::function<void()> fn) override { fn(); }

  void shutdown() override {
    {
      const std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    wake();
    gate_.join();
    workers_.shutdown();  // runs what is queued; those connections are closed, not handed back
    const std::lock_guard lock(mutex_);
    for (const auto& w : arrivals_) close_connection(w.sock);
    arrivals_.clear();
  }

  /// `sock` waits in the gate for its next request's headers until `deadline`.
  void wait_for_request(socket_t sock, SteadyClock::time_point deadline, std::size_t served) {
    {
      const std::lock_guard lock(mutex_);
      if (!stopping_) {
        arrivals_.push_back({sock, deadline, served});
        sock = -1;
      }
    }
    if (sock >= 0) return close_connection(sock);
    wake();
  }

 private:
  struct Waiting {
    socket_t sock;
    SteadyClock::time_point deadline;
    std::size_t served;    // requests answered on this connection so far
    bool partial = false;  // some of the headers are there: peeked again every tick
  };
  /// How often a connection with part of its headers is looked at again (poll would report it
  /// readable at once, over and over).
  static constexpr std::chrono::milliseconds kPartialTick{50};

  void wake() {
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto n = ::write(wake_, &one, sizeof one);
  }

  /// "complete" (the headers are there, or too many to wait for: httplib answers it), "partial",
  /// "nothing" yet, or "gone" (closed or failed).
  enum class Peek { kNothing, kPartial, kComplete, kGone };
  static Peek peek(socket_t sock) {
    static thread_local std::vector<char> buffer(CPPHTTPLIB_HEADER_MAX_LENGTH);
    ssize_t n;
    do {
      n = ::recv(sock, buffer.data(), buffer.size(), MSG_PEEK | MSG_DONTWAIT);
    } while (n < 0 && errno == EINTR);
    if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK ? Peek::kNothing : Peek::kGone;
    if (n == 0) return Peek::kGone;
    const std::string_view seen(buffer.data(), static_cast<std::size_t>(n));
    if (static_cast<std::size_t>(n) == buffer.size() || seen.find("\r\n\r\n") != seen.npos ||
        seen.find("\n\n") != seen.npos)
      return Peek::kComplete;
    return Peek::kPartial;
  }

  void run_gate() {
    std::vector<Waiting> waiting;
    std::vector<pollfd> fds;
    for (;;) {
      {
        const std::lock_guard lock(mutex_);
        if (stopping_) break;
        waiting.insert(waiting.end(), arrivals_.begin(), arrivals_.end());
        arrivals_.clear();
      }
      // Too many waiting: the oldest are closed (a flood of idle connections cannot keep a new
      // request, whose headers usually come with it, from being answered).
      if (waiting.size() > server_.limits_.max_waiting) {
        const auto excess = waiting.size() - server_.limits_.max_waiting;
        for (std::size_t i = 0; i < excess; ++i) close_connection(waiting[i].sock);
        waiting.erase(waiting.begin(), waiting.begin() + static_cast<std::ptrdiff_t>(excess));
      }
      // Poll the eventfd and the connections with nothing yet, up to the nearest deadline (or
      // the next tick for the partial ones).
      fds.assign(1, pollfd{wake_, POLLIN, 0});
      auto until = SteadyClock::now() + std::chrono::seconds(60);
      bool any_partial = false;
      for (const auto& w : waiting) {
        fds.push_back(pollfd{w.sock, static_cast<short>(w.partial ? 0 : POLLIN), 0});
        until = std::min(until, w.deadline);
        any_partial = any_partial || w.partial;
      }
      if (any_partial) until = std::min(until, SteadyClock::now() + kPartialTick);
      const auto wait = std::chrono::ceil<std::chrono::milliseconds>(until - SteadyClock::now());
      const int n =
          ::poll(fds.data(), fds.size(), static_cast<int>(std::max<long>(0, wait.count())));
      if (n < 0 && errno != EINTR) {
        std::this_thread::sleep_for(kPartialTick);  // e.g. ENOMEM: try again, do not spin
        continue;
      }
      if (fds[0].revents != 0) {
        std::uint64_t count;
        [[maybe_unused]] const auto r = ::read(wake_, &count, sizeof count);
      }
      const auto now = SteadyClock::now();
      std::size_t kept = 0;
      for (std::size_t i = 0; i < waiting.size(); ++i) {
        Waiting w = waiting[i];
        const short revents = fds[i + 1].revents;
        if (revents != 0 || w.partial) {
          switch (peek(w.sock)) {
            case Peek::kComplete:
              server_.dispatch(*this, w.sock, w.served);
              continue;
            case Peek::kGone:
              close_connection(w.sock);
              continue;
            case Peek::kPartial:
              w.partial = true;
              break;
            case Peek::kNothing:
              break;
          }
        }
        if (now >= w.deadline) {  // idle, or its headers too slow: closed, its fd returns
          close_connection(w.sock);
          continue;
        }
        waiting[kept++] = w;
      }
      waiting.resize(kept);
    }
    for (const auto& w : waiting) close_connection(w.sock);
  }

  friend class BoundedServer;
  BoundedServer& server_;
  httplib::ThreadPool workers_;
  int wake_;
  std::thread gate_;
  std::mutex mutex_;
  bool stopping_ = false;
  std::vector<Waiting> arrivals_;
};

BoundedServer::BoundedServer(const ServerLimits& limits) : limits_(limits) {
  // httplib's own keep-alive loop is not used (serve below), but these go out in the
  // "Keep-Alive: timeout=, max=" header and bound its timeouts.
  set_keep_alive_timeout(
      std::chrono::duration_cast<std::chrono::seconds>(limits_.keep_alive_timeout).count());
  set_keep_alive_max_count(limits_.keep_alive_max_count);
  set_read_timeout(limits_.read_timeout);
  set_write_timeout(limits_.write_timeout);
  // No route takes a body: a request announcing more than this is refused (413), not read.
  set_payload_max_length(kMaxPayload);
  new_task_queue = [this] { return new Pool(*this); };
}

bool BoundedServer::set_backlog(int backlog) {
  const socket_t sock = svr_sock_;
  return sock != INVALID_SOCKET && ::listen(sock, backlog) == 0;  // again: updates the backlog
}

bool BoundedServer::process_and_close_socket(socket_t sock) {
  Pool* pool = pool_.load();
  if (pool == nullptr) {
    close_connection(sock);
    return false;
  }
  pool->wait_for_request(sock, SteadyClock::now() + limits_.header_timeout, 0);
  return true;
}

void BoundedServer::dispatch(Pool& pool, socket_t sock, std::size_t served) {
  pool.workers_.enqueue([this, sock, served] { serve(sock, served); });
}

void BoundedServer::serve(socket_t sock, std::size_t served) {
  SocketStream stream(sock, limits_);
  const bool last = served + 1 >= limits_.keep_alive_max_count;
  bool closed = false;
  answering = {sock, false};
  const bool ok = process_request(stream, last, closed, nullptr);
  const bool taken = answering.taken;
  answering = {};
  if (taken) return;  // an event stream: the fan-out thread owns it now
  Pool* pool = pool_.load();
  if (ok && !closed && !last && pool != nullptr && svr_sock_ != INVALID_SOCKET) {
    return pool->wait_for_request(sock, SteadyClock::now() + limits_.keep_alive_timeout,
                                  served + 1);
  }
  close_connection(sock);
}

}  // namespace peritwin::dashboard
