#include "dashboard/event_fanout.h"

#include <fcntl.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <deque>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>

namespace peritwin::dashboard {
namespace {

using SteadyClock = std::chrono::steady_clock;
using Piece = std::shared_ptr<const std::string>;

/// `text` as one chunk of the chunked transfer coding httplib started the response with.
Piece chunk(const std::string& text) {
  char size[24];
  std::snprintf(size, sizeof size, "%zx\r\n", text.size());
  auto framed = std::make_shared<std::string>(size);
  framed->reserve(framed->size() + text.size() + 2);
  *framed += text;
  *framed += "\r\n";
  return framed;
}

/// The events of `events` with an id in (after, upto], as one SSE text; their number added to
/// `count`.
std::string format(const std::deque<Event>& events, std::uint64_t after, std::uint64_t upto,
                   std::uint64_t& count) {
  std::string out;
  for (const auto& e : events) {
    if (e.id <= after || e.id > upto) continue;
    out += "id: " + std::to_string(e.id) + "\nevent: " + e.kind + "\ndata: " + e.data + "\n\n";
    ++count;
  }
  return out;
}

/// How often the streams are looked at for keep-alives and stalls.
constexpr std::chrono::milliseconds kTick{250};

}  // namespace

struct EventFanout::Client {
  int sock = -1;
  std::uint64_t cursor = 0;  // the newest event queued for it
  std::deque<Piece> queue;   // to send, in order
  std::size_t offset = 0;    // bytes of queue.front() sent
  std::size_t pending = 0;   // bytes queued, not sent
  SteadyClock::time_point last_queued{};
  SteadyClock::time_point progress{};  // last time queued bytes went out (or were first queued)
  bool want_out = false;               // EPOLLOUT registered
};

EventFanout::EventFanout(Store& store, const FanoutLimits& limits)
    : store_(store),
      limits_(limits),
      epoll_(::epoll_create1(EPOLL_CLOEXEC)),
      wake_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  epoll_event e{};
  e.events = EPOLLIN;
  e.data.fd = wake_;
  ::epoll_ctl(epoll_, EPOLL_CTL_ADD, wake_, &e);
  store_.set_event_listener([this] {
    if (armed_.exchange(false)) wake();
  });
  thread_ = std::thread([this] { run(); });
}

EventFanout::~EventFanout() {
  stop();
  store_.set_event_listener(nullptr);
  if (wake_ >= 0) ::close(wake_);
  if (epoll_ >= 0) ::close(epoll_);
}

bool EventFanout::reserve() {
  if (slots_.fetch_add(1) >= limits_.max_streams) {
    slots_.fetch_sub(1);
    refused_.fetch_add(1);
    return false;
  }
  return true;
}

void EventFanout::release() { slots_.fetch_sub(1); }

void EventFanout::adopt(int sock, std::uint64_t after) {
  {
    const std::lock_guard lock(mutex_);
    if (!stopping_) {
      arrivals_.push_back({sock, after});
      sock = -1;
    }
  }
  if (sock >= 0) {
    ::shutdown(sock, SHUT_RDWR);
    ::close(sock);
    release();
    return;
  }
  wake();
}

void EventFanout::stop() {
  {
    const std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  wake();
  if (thread_.joinable()) thread_.join();
}

FanoutStats EventFanout::stats() const {
  FanoutStats s;
  s.open = slots_.load();
  s.adopted = adopted_.load();
  s.refused = refused_.load();
  s.closed_gone = closed_gone_.load();
  s.closed_slow = closed_slow_.load();
  s.events_sent = events_sent_.load();
  s.writes = writes_.load();
  return s;
}

void EventFanout::wake() {
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto n = ::write(wake_, &one, sizeof one);
}

void EventFanout::run() {
  std::unordered_map<int, Client> clients;
  const Piece keep_alive = chunk(": keep-alive\n\n");
  std::uint64_t cursor = store_.last_event_id();  // the newest event written to every stream
  auto next_write = SteadyClock::now();           // coalescing: no write of events before this
  auto next_tick = SteadyClock::now() + kTick;
  std::vector<epoll_event> ready(256);
  std::vector<std::pair<int, bool>> doomed;  // {sock, slow}: closed after a loop over `clients`

  const auto close_client = [&](int sock, bool slow) {
    const auto it = clients.find(sock);
    if (it == clients.end()) return;
    ::epoll_ctl(epoll_, EPOLL_CTL_DEL, sock, nullptr);
    ::shutdown(sock, SHUT_RDWR);
    ::close(sock);
    clients.erase(it);
    (slow ? closed_slow_ : closed_gone_).fetch_add(1);
    release();
  };
  const auto close_doomed = [&] {
    for (const auto& [sock, slow] : doomed) close_client(sock, slow);
    doomed.clear();
  };
  const auto doom = [&](int sock, bool slow) { doomed.emplace_back(sock, slow); };
  // Sends what is queued until the socket takes no more; false when the client is gone.
  const auto flush = [&](Client& c, SteadyClock::time_point now) {
    while (!c.queue.empty()) {
      const std::string& piece = *c.queue.front();
      ssize_t n;
      do {
        n = ::send(c.sock, piece.data() + c.offset, piece.size() - c.offset,
                   MSG_NOSIGNAL | MSG_DONTWAIT);
      } while (n < 0 && errno == EINTR);
      if (n < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK) return false;
        break;
      }
      c.offset += static_cast<std::size_t>(n);
      c.pending -= static_cast<std::size_t>(n);
      c.progress = now;
      if (c.offset == piece.size()) {
        c.queue.pop_front();
        c.offset = 0;
      }
    }
    const bool want_out = !c.queue.empty();
    if (want_out != c.want_out) {
      epoll_event e{};
      e.events = EPOLLIN | EPOLLRDHUP | (want_out ? EPOLLOUT : 0u);
      e.data.fd = c.sock;
      ::epoll_ctl(epoll_, EPOLL_CTL_MOD, c.sock, &e);
      c.want_out = want_out;
    }
    return true;
  };
  // Queues `piece` for `c` and sends what its socket takes; the stream is closed when its client
  // is gone, or as slow when more than max_pending_bytes wait behind the piece being sent (one
  // piece alone, e.g. a new stream's catch-up of up to 1000 events, may be larger: the stall
  // timeout bounds how long it waits).
  const auto deliver = [&](Client& c, const Piece& piece, SteadyClock::time_point now) {
    if (c.queue.empty()) c.progress = now;
    c.queue.push_back(piece);
    c.pending += piece->size();
    c.last_queued = now;
    if (!flush(c, now)) return doom(c.sock, false);
    const std::size_t in_progress = c.queue.empty() ? 0 : c.queue.front()->size() - c.offset;
    if (c.pending - in_progress > limits_.max_pending_bytes) doom(c.sock, true);
  };

  for (;;) {
    std::vector<Arrival> arrivals;
    {
      const std::lock_guard lock(mutex_);
      if (stopping_) break;
      arrivals.swap(arrivals_);
    }
    auto now = SteadyClock::now();
    // New streams: the events kept after the one each names, up to those every stream has.
    for (const auto& a : arrivals) {
      const int flags = ::fcntl(a.sock, F_GETFL);
      epoll_event interest{};
      interest.events = EPOLLIN | EPOLLRDHUP;
      interest.data.fd = a.sock;
      if (flags < 0 || ::fcntl(a.sock, F_SETFL, flags | O_NONBLOCK) != 0 ||
          ::epoll_ctl(epoll_, EPOLL_CTL_ADD, a.sock, &interest) != 0) {
        ::shutdown(a.sock, SHUT_RDWR);
        ::close(a.sock);
        release();
        continue;
      }
      adopted_.fetch_add(1);
      Client& c = clients[a.sock];
      c.sock = a.sock;
      c.cursor = std::max(a.after, cursor);
      c.last_queued = now;
      if (a.after < cursor) {
        const auto events = store_.events_after(a.after, std::chrono::milliseconds(0));
        std::uint64_t count = 0;
        const std::string text = format(events, a.after, cursor, count);
        if (!text.empty()) deliver(c, chunk(text), now);
        events_sent_.fetch_add(count);
      }
    }
    close_doomed();

    // New events, written to every stream at most once per `coalesce`.
    if (now >= next_write) {
      armed_.store(true);  // before looking: an event pushed after the look wakes the thread
      const auto events = store_.events_after(cursor, std::chrono::milliseconds(0));
      if (!events.empty()) {
        armed_.store(false);
        const std::uint64_t last = events.back().id;
        std::uint64_t all_count = 0, sent = 0;
        const Piece all = chunk(format(events, cursor, last, all_count));
        for (auto& [sock, c] : clients) {
          if (c.cursor >= last) continue;
          // A stream that named an event newer than `cursor` gets the ones after it only.
          Piece piece = all;
          if (c.cursor > cursor) {
            piece = chunk(format(events, c.cursor, last, sent));
          } else {
            sent += all_count;
          }
          c.cursor = last;
          deliver(c, piece, now);
        }
        close_doomed();
        events_sent_.fetch_add(sent);
        writes_.fetch_add(1);
        cursor = last;
        next_write = now + limits_.coalesce;
      }
    }

    // Keep-alives to the quiet streams; the slow ones closed.
    if (now >= next_tick) {
      next_tick = now + kTick;
      for (auto& [sock, c] : clients) {
        if (!c.queue.empty() && now - c.progress >= limits_.stall_timeout) {
          doom(sock, true);
        } else if (now - c.last_queued >= limits_.keep_alive) {
          deliver(c, keep_alive, now);
        }
      }
      close_doomed();
    }

    // Wait for a socket, a new stream or event (when armed), the next write (when not), or the
    // next tick.
    auto until = next_tick;
    if (!armed_.load()) until = std::min(until, next_write);
    const auto wait = std::chrono::ceil<std::chrono::milliseconds>(until - SteadyClock::now());
    const int n = ::epoll_wait(epoll_, ready.data(), static_cast<int>(ready.size()),
                               static_cast<int>(std::max<long>(0, wait.count())));
    if (n < 0) {
      if (errno != EINTR) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    now = SteadyClock::now();
    for (int i = 0; i < n; ++i) {
      const int fd = ready[static_cast<std::size_t>(i)].data.fd;
      const auto events = ready[static_cast<std::size_t>(i)].events;
      if (fd == wake_) {
        std::uint64_t count;
        [[maybe_unused]] const auto r = ::read(wake_, &count, sizeof count);
        continue;
      }
      const auto it = clients.find(fd);
      if (it == clients.end()) continue;
      Client& c = it->second;
      bool gone = (events & (EPOLLERR | EPOLLHUP)) != 0;
      if (!gone && (events & (EPOLLIN | EPOLLRDHUP)) != 0) {
        // A client sends nothing on an event stream: what comes is read and dropped; end of
        // file (or a reset) is the client gone.
        char scratch[4096];
        for (;;) {
          const ssize_t r = ::recv(fd, scratch, sizeof scratch, MSG_DONTWAIT);
          if (r > 0) continue;
          if (r == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) gone = true;
          if (r < 0 && errno == EINTR) continue;
          break;
        }
      }
      if (!gone && (events & EPOLLOUT) != 0 && !flush(c, now)) gone = true;
      if (gone) doom(fd, false);
    }
    close_doomed();
  }
  // Stopping: every stream closed, and whatever was handed over meanwhile.
  std::vector<Arrival> arrivals;
  {
    const std::lock_guard lock(mutex_);
    arrivals.swap(arrivals_);
  }
  for (const auto& a : arrivals) {
    ::shutdown(a.sock, SHUT_RDWR);
    ::close(a.sock);
    release();
  }
  for (auto& [sock, c] : clients) {
    ::epoll_ctl(epoll_, EPOLL_CTL_DEL, sock, nullptr);
    ::shutdown(sock, SHUT_RDWR);
    ::close(sock);
    release();
  }
  clients.clear();
}

}  // namespace peritwin::dashboard
