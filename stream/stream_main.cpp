// peritwin-stream: live load samples of one detail -> [detail.sensor] scale/offset -> rainflow ->
// load blocks -> batches -> the daemon over LCM (or the twin in-process).
//
//   peritwin-stream --config CFG [--detail ID] --input -|FILE|FIFO|tcp://127.0.0.1:PORT|lcm
//                   [--lcm-url URL] [--source ID] [--state-file F] [--json] [--batch-cycles N]
//                   [--batch-blocks N] [--batch-seconds T] [--lockstep|--window N]
//                   [--residue half|whole|keep] [--in-process] [--give-up-after S]
//                   [--key-file F [--daemon-key ID | --sign-only]]
//
// Input: lines "t,P" or "t,P,alpha" (the series format's columns; its header line and '#'
// comments accepted; t in s strictly increasing, P in the sensor's unit, alpha in rad), read as
// they arrive (stdin and FIFOs line by line, not at EOF). tcp://127.0.0.1:PORT listens there and
// takes one connection at a time (a closed connection is not the end: the next one continues the
// stream). lcm: load_samples_t on PERITWIN_<DETAIL>_SAMPLES (each (source, seq) once, gaps
// reported). A line that is no sample is skipped and counted (bad_lines), the first ones named.
// Each sample: P = scale * measured + offset, then RainflowCounter (gate) -> CycleBlocks
// (alpha_bin, compressed_bonds_fatigue) -> batches closed at --batch-cycles (1000) cycles,
// --batch-blocks (1024) blocks, or --batch-seconds of sample time (0: off).
// End of input (EOF of stdin, a FILE or a FIFO; SIGINT/SIGTERM for any input): the residue by
// --residue (default half, ASTM E1049-85, as peritwin-replay: a stream of a finished file
// applies the same cycles as its replay; whole: each residue range a whole cycle; keep: not
// applied), the last batch, then it waits for the daemon to apply everything (at most
// --give-up-after s without progress) and exits 0.
// --key-file: as peritwin-replay (replay/producer_keys.h): batches signed with the key of --source,
// every STATE and REJECT verified with the daemon's key, and the load_samples_t of --input lcm
// taken only when signed with the key of their source_id (refused and counted otherwise; not
// verified with --sign-only, which says so on stderr).
// Over LCM it first learns what the daemon has applied of --source (default "stream"); without a
// state file a stream always appends after that (a new stream is new load). --state-file F: see
// stream/stream_tool.h; a restart with it neither loses nor doubles a cycle: it resends the
// batches not acknowledged, a FILE input skips the lines already counted, and samples of a
// non-seekable input read after the last persisted state are reported as lost_samples. A state
// file that is corrupt: exit 2 naming it and why.
// Output: with --json one JSON line per STATE, then the summary (twin::summary_json) with
// "stream": {samples, nonfinite_samples, bad_lines, reversals, cycles, batches, lost_samples} and
// "skipped_cycles" as peritwin-replay. Exit codes: 0 done, 2 bad usage/config/state file,
// 3 runtime failure (LCM, no progress, a state file that cannot be written).
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <iostream>
#include <limits>
#include <map>
#include <memory>

#include "messages/auth.h"
#include "messages/channels.h"
#include "messages/transport.h"
#include "replay/producer_keys.h"
#include "replay/replay_tool.h"
#include "stream/stream_tool.h"
#include "tools/cli_checks.h"

namespace {
std::atomic<int> g_signal{0};
extern "C" void on_signal(int signal) { g_signal.store(signal); }
constexpr int kExitOk = 0, kExitUsage = 2, kExitRuntime = 3;

using namespace peritwin;

/// Lines from a descriptor as they arrive (stdin, a FILE, a FIFO, a TCP connection).
class LineInput {
 public:
  /// Reads what is available within timeout_ms; complete lines go to `lines`. False at EOF.
  bool read(int fd, int timeout_ms, std::vector<std::string>& lines) {
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, timeout_ms);
    if (ready <= 0) return true;
    char buf[65536];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0) return errno == EINTR || errno == EAGAIN;
    if (n == 0) {
      if (!partial_.empty()) lines.push_back(std::move(partial_));
      partial_.clear();
      return false;
    }
    for (ssize_t i = 0; i < n; ++i) {
      if (buf[i] == '\n') {
        lines.push_back(std::move(partial_));
        partial_.clear();
      } else {
        partial_ += buf[i];
      }
    }
    return true;
  }

 private:
  std::string partial_;
};

/// load_samples_t from the bus, each (source, seq) once; with a key ring only those signed with
/// the key of their source_id (messages/README.md, "Authentication").
class SamplesInput {
 public:
  /// `taken`: the last seq per source already taken (from the state file).
  SamplesInput(lcm::LCM& lcm, std::string detail_id, std::optional<messages::KeyRing> ring,
               std::map<std::string, std::int64_t> taken)
      : lcm_(lcm),
        detail_id_(std::move(detail_id)),
        ring_(std::move(ring)),
        last_(std::move(taken)) {
    sub_ = lcm_.subscribe(messages::channel(detail_id_, messages::Kind::kSamples),
                          &SamplesInput::on_msg, this);
    sub_->setQueueCapacity(100'000);
  }
  ~SamplesInput() { lcm_.unsubscribe(sub_); }
  SamplesInput(const SamplesInput&) = delete;
  SamplesInput& operator=(const SamplesInput&) = delete;
  std::deque<messages::Samples> inbox;
  std::uint64_t duplicates = 0, gaps = 0, refused = 0;

 private:
  void on_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto d = messages::decode_samples(rbuf->data, static_cast<std::size_t>(rbuf->data_size));
    const messages::Outcome o =
        d.samples ? messages::check_samples(*d.samples, detail_id_) : d.error;
    if (!o.applied()) {
      if (refused++ < 5) {
        std::cerr << "peritwin-stream: " << channel << ": refused: " << o.what << ": " << o.why
                  << "\n";
      }
      return;
    }
    const auto& s = *d.samples;
    if (ring_) {
      const messages::AuthKey* key = ring_->find(s.source_id);
      const Status signed_ok =
          key != nullptr
              ? messages::verify_encoded<peritwin_msgs::load_samples_t>(
                    rbuf->data, static_cast<std::size_t>(rbuf->data_size), *key)
              : Status{failure("no key for source \"" + s.source_id + "\" in the key file")};
      if (!signed_ok) {
        if (refused++ < 5) {
          std::cerr << "peritwin-stream: " << channel
                    << ": refused: auth: " << signed_ok.error().message() << "\n";
        }
        return;
      }
    }
    auto [it, fresh] = last_.try_emplace(s.source_id, 0);
    if (s.seq <= it->second) {
      ++duplicates;
      return;
    }
    if (s.seq > it->second + 1 && !(fresh && s.seq == 1)) {
      ++gaps;
      std::cerr << "peritwin-stream: " << channel << ": gap in source \"" << s.source_id
                << "\": seq " << it->second + 1 << " to " << s.seq - 1
                << " missing (their samples are not counted)\n";
    }
    it->second = s.seq;
    inbox.push_back(s);
  }
  lcm::LCM& lcm_;
  std::string detail_id_;
  std::optional<messages::KeyRing> ring_;
  std::map<std::string, std::int64_t> last_;
  lcm::Subscription* sub_ = nullptr;
};

/// The twin in this process (deterministic mode, as peritwin-replay --in-process).
class InProcessTwin {
 public:
  static Expected<std::unique_ptr<InProcessTwin>, std::string> create(
      const twin::DetailConfig& detail) {
    auto model = twin::DetailModel::build(detail);
    if (!model) return model.error().message();
    auto created = twin::Twin::create(*model, {twin::LifeMode::synchronous, true});
    if (!created) return created.error().message();
    auto t = std::make_unique<InProcessTwin>();
    t->twin_ = std::move(*created);
    t->twin_->catch_up_life();
    t->state = twin::state_message(*t->twin_, twin::now_utime());
    return t;
  }
  /// False (why set) when the batch is refused for another reason than the end of life.
  bool apply(const twin::Batch& b, std::string& why) {
    if (ended_) return true;  // the end of life was reached: the rest is not applied
    const auto outcome = twin_->apply(b);
    if (outcome.verdict == twin::Verdict::failed) {
      ended_ = true;
      return true;
    }
    if (!outcome.applied()) {
      why = "batch " + std::to_string(b.seq) + ": " + outcome.what + ": " + outcome.why;
      return false;
    }
    state = twin::state_message(*twin_, twin::now_utime());
    return true;
  }
  peritwin_msgs::damage_state_t state;

 private:
  std::unique_ptr<twin::Twin> twin_;
  bool ended_ = false;
};

int listen_on(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  const int on = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(fd, 4) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-stream: live load samples -> rainflow -> batches -> the twin"};
  std::string config_file, detail_id, input, lcm_url, source_id = "stream", state_file;
  std::string residue = "half";
  bool lockstep = false, in_process = false, json = false;
  replay::BatchingOptions batching;
  replay::ReplayOptions options;
  app.add_option("--config", config_file, "detail configuration (TOML)")->required();
  app.add_option("--detail", detail_id, "detail id (default: the config's first detail)");
  app.add_option("--input", input, "-|FILE|FIFO|tcp://127.0.0.1:PORT|lcm")->required();
  app.add_option("--lcm-url", lcm_url, "LCM URL (default: $LCM_DEFAULT_URL, then LCM's)");
  app.add_option("--source", source_id, "source id of the batches (default stream)");
  app.add_option("--state-file", state_file,
                 "keep the stream's state here (atomic, checksummed): a restart continues it");
  app.add_flag("--json", json, "JSON lines: one per state update, then a summary");
  app.add_option("--batch-cycles", batching.max_cycles,
                 "close a batch once it holds this many cycles (default 1000)")
      ->check(CLI::PositiveNumber);
  app.add_option("--batch-blocks", batching.max_blocks, "blocks per batch at most (default 1024)")
      ->check(CLI::PositiveNumber);
  app.add_option("--batch-seconds", batching.max_seconds,
                 "close a batch after this much sample time (s; default 0 = off)")
      ->check(peritwin::cli::finite_in(0.0, std::numeric_limits<double>::max()));
  auto* lockstep_opt =
      app.add_flag("--lockstep", lockstep, "wait for the daemon to apply each batch");
  app.add_option("--window", options.window, "batches in flight without --lockstep (256)")
      ->check(CLI::PositiveNumber)
      ->excludes(lockstep_opt);
  app.add_option("--residue", residue,
                 "the rainflow residue at the end of input: half (default, ASTM E1049-85, as the "
                 "replay), whole (conservative) or keep (not applied)")
      ->check(CLI::IsMember({"half", "whole", "keep"}));
  auto* in_process_opt =
      app.add_flag("--in-process", in_process, "run the twin library here (no daemon)");
  replay::ProducerKeyOptions keys;
  replay::add_key_options(app, keys)->excludes(in_process_opt);
  app.add_option("--give-up-after", options.give_up_after_s,
                 "seconds without progress from the daemon before failing (default 120)")
      ->check(peritwin::cli::finite_positive());
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? kExitOk : kExitUsage;
  }
  options.lockstep = lockstep;
  batching.merge_identical = true;
  const auto rule = residue == "whole"  ? replay::ResidueRule::whole
                    : residue == "keep" ? replay::ResidueRule::keep
                                        : replay::ResidueRule::half;
  const auto loaded =
      twin::load_config(config_file, {in_process ? 0 : std::numeric_limits<std::uint64_t>::max()});
  if (!loaded.ok()) {
    std::cerr << loaded.error_text();
    return kExitUsage;
  }
  const twin::DetailConfig* detail = twin::select_detail(*loaded.config, detail_id);
  if (detail == nullptr) {
    std::cerr << "peritwin-stream: no detail \"" << detail_id << "\" in " << config_file << "\n";
    return kExitUsage;
  }
  if (source_id.empty() || source_id.size() > twin::kMaxSourceIdLength) {
    std::cerr << "peritwin-stream: --source must have 1 to 64 characters\n";
    return kExitUsage;
  }
  if (in_process && !state_file.empty()) {
    std::cerr << "peritwin-stream: --state-file needs a daemon (the in-process twin is not "
                 "persisted)\n";
    return kExitUsage;
  }

  // The keys, before anything is read or published: a missing one is a usage error.
  auto auth = replay::load_producer_keys(keys, source_id);
  if (!auth) {
    std::cerr << "peritwin-stream: " << auth.error().message() << "\n";
    return kExitUsage;
  }
  if (keys.sign_only) {
    std::cerr << "peritwin-stream: --sign-only: the daemon's STATE and REJECT are not verified\n";
  }

  // The input.
  enum class In { fd, tcp, lcm } kind = In::fd;
  int fd = -1, listen_fd = -1, conn_fd = -1, port = 0;
  bool seekable = false;
  if (input == "-") {
    fd = STDIN_FILENO;
  } else if (input == "lcm") {
    kind = In::lcm;
  } else if (input.starts_with("tcp://")) {
    kind = In::tcp;
    const std::string rest = input.substr(6);
    const auto colon = rest.rfind(':');
    if (colon == std::string::npos || rest.substr(0, colon) != "127.0.0.1" ||
        (port = std::atoi(rest.c_str() + colon + 1)) <= 0 || port > 65535) {
      std::cerr << "peritwin-stream: --input " << input
                << ": expected tcp://127.0.0.1:PORT (loopback only)\n";
      return kExitUsage;
    }
  } else {
    fd = ::open(input.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
      std::cerr << "peritwin-stream: " << input << ": cannot open: " << std::strerror(errno)
                << "\n";
      return kExitUsage;
    }
    struct stat st {};
    seekable = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
  }

  // The state file, if any.
  std::optional<stream::Pipeline> pipeline;
  std::vector<twin::Batch> resend;
  if (!state_file.empty() && std::filesystem::exists(state_file)) {
    auto restored = stream::load_state(state_file, *detail, source_id, batching);
    if (!restored) {
      std::cerr << "peritwin-stream: corrupt state file " << restored.error() << "\n";
      return kExitUsage;
    }
    pipeline.emplace(std::move(restored->pipeline));
    resend = std::move(restored->unacknowledged);
    auto& c = pipeline->counts;
    std::uint64_t lost = 0;
    if (!seekable) {
      const auto received = stream::read_received(state_file);
      if (received && *received > c.samples) lost = *received - c.samples;
      c.lost_samples += lost;
    }
    std::cerr << "peritwin-stream: resumed from " << state_file << ": " << c.samples << " samples, "
              << c.batches << " batches (next seq " << pipeline->next_seq() << ", " << resend.size()
              << " not acknowledged); lost_samples " << lost
              << (seekable ? " (a FILE input: the lines after line " +
                                 std::to_string(c.input_lines) + " are read again)"
                           : " (read after the last persisted state, not counted)")
              << "\n";
  }

  // Where the batches go.
  if (lcm_url.empty()) {
    if (const char* env = std::getenv("LCM_DEFAULT_URL")) lcm_url = env;
  }
  std::unique_ptr<lcm::LCM> lcm;
  if (!in_process || kind == In::lcm) {
    const auto hub = messages::tcpq_hub(lcm_url);
    if (const Status up = hub ? messages::probe_hub(*hub) : Status{}; !up) {
      std::cerr << "peritwin-stream: LCM hub " << lcm_url
                << " unreachable: " << up.error().message() << "\n";
      return kExitRuntime;
    }
    lcm = std::make_unique<lcm::LCM>(lcm_url);
    if (!lcm->good() || !messages::transport_up(*lcm)) {
      std::cerr << "peritwin-stream: cannot open LCM at \"" << messages::shown_url(lcm_url)
                << "\"\n";
      return kExitRuntime;
    }
  }
  // Subscribed before anything else happens on the bus (the probe, the first state printed):
  // a sample message published once the stream has said it is up is never missed.
  std::unique_ptr<SamplesInput> samples_in;
  if (kind == In::lcm) {
    // With --key-file the samples are verified too (with the key of each message's source_id),
    // unless --sign-only (the key file then holds only this stream's key).
    std::optional<messages::KeyRing> ring;
    if (!keys.key_file.empty() && !keys.sign_only) {
      auto loaded_ring = messages::KeyRing::load(keys.key_file);
      if (!loaded_ring) {
        std::cerr << "peritwin-stream: " << loaded_ring.error().message() << "\n";
        return kExitUsage;
      }
      ring = std::move(*loaded_ring);
    } else {
      std::cerr << "peritwin-stream: the samples on the bus are not verified (no --key-file, or "
                   "--sign-only): anyone on the bus can feed this stream\n";
    }
    samples_in = std::make_unique<SamplesInput>(
        *lcm, detail->id, std::move(ring),
        pipeline ? pipeline->samples_taken : std::map<std::string, std::int64_t>{});
  }
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);

  std::int64_t last_seq = -2, last_life = -2;
  auto print = [&](const peritwin_msgs::damage_state_t& s) {
    if (s.state_seq == last_seq && s.remaining_life_seq == last_life) return;
    last_seq = s.state_seq;
    last_life = s.remaining_life_seq;
    std::cout << (json ? twin::state_json(s) : replay::describe(s)) << std::endl;
  };
  std::unique_ptr<replay::BatchSender> sender;
  std::unique_ptr<InProcessTwin> local;
  if (in_process) {
    auto created = InProcessTwin::create(*detail);
    if (!created) {
      std::cerr << "peritwin-stream: " << created.error() << "\n";
      return kExitUsage;
    }
    local = std::move(*created);
    print(local->state);
    if (!pipeline) pipeline.emplace(*detail, source_id, batching, 1);
  } else {
    sender = std::make_unique<replay::BatchSender>(*lcm, detail->id, source_id, options,
                                                   std::move(*auth));
    sender->on_state(print);
    const auto learned = sender->probe_applied([] { return g_signal.load() == 0; });
    if (!learned) {
      std::cerr << "peritwin-stream: " << learned.error().message() << "\n";
      return kExitRuntime;
    }
    const std::int64_t applied = *learned;
    if (!pipeline) {
      pipeline.emplace(*detail, source_id, batching, applied + 1);
      if (applied > 0) {
        std::cerr << "peritwin-stream: source '" << source_id << "' has batches up to seq "
                  << applied << " applied on detail " << detail->id
                  << ": this stream's batches follow from " << applied + 1 << "\n";
      }
    } else {
      const std::int64_t held = resend.empty() ? pipeline->next_seq() : resend.front().seq;
      if (applied + 1 < held) {
        std::cerr << "peritwin-stream: the daemon has applied seq " << applied << " of source '"
                  << source_id << "', but " << state_file << " holds batches from seq " << held
                  << " only (the daemon lost acknowledged batches?)\n";
        return kExitRuntime;
      }
      if (applied >= pipeline->next_seq()) {
        std::cerr << "peritwin-stream: the daemon has applied seq " << applied << " of source '"
                  << source_id << "', beyond this state file's next seq " << pipeline->next_seq()
                  << ": another producer uses this source (use another --source)\n";
        return kExitUsage;
      }
      for (auto& b : resend) {
        if (b.seq > applied) sender->add(std::move(b));
      }
    }
  }
  stream::Pipeline& pipe = *pipeline;
  if (kind == In::tcp) {
    listen_fd = listen_on(port);
    if (listen_fd < 0) {
      std::cerr << "peritwin-stream: cannot listen on 127.0.0.1:" << port << ": "
                << std::strerror(errno) << "\n";
      return kExitRuntime;
    }
    std::cerr << "peritwin-stream: listening on tcp://127.0.0.1:" << port << "\n";
  }
  // A FILE input after a restart: the lines the state has counted are skipped.
  std::uint64_t skip_lines = seekable ? pipe.counts.input_lines : 0;
  if (!seekable) pipe.counts.input_lines = 0;

  std::vector<twin::Batch> closed;
  std::string error;
  std::uint64_t bad_reported = 0;
  auto deliver = [&]() -> bool {
    if (closed.empty()) return true;
    if (!state_file.empty()) {
      std::vector<twin::Batch> pending =
          sender ? sender->unacknowledged() : std::vector<twin::Batch>{};
      pending.insert(pending.end(), closed.begin(), closed.end());
      if (const Status saved = stream::save_state(state_file, pipe, pending); !saved) {
        error = saved.error().message();
        return false;
      }
    }
    for (auto& b : closed) {
      if (sender) {
        sender->add(std::move(b));
      } else if (!local->apply(b, error)) {
        return false;
      } else {
        print(local->state);
      }
    }
    closed.clear();
    return true;
  };
  auto take = [&](double t, double p, double alpha) {
    if (pipe.last_time && !(t > *pipe.last_time)) {
      if (bad_reported++ < 5) {
        std::cerr << "peritwin-stream: sample at t = " << t << " s skipped: time not after "
                  << *pipe.last_time << " s\n";
      }
      ++pipe.counts.bad_lines;
      return;
    }
    pipe.sample(t, p, alpha, closed);
  };
  auto take_line = [&](const std::string& line) {
    ++pipe.counts.input_lines;
    const auto parsed = stream::parse_line(line);
    if (parsed.kind == stream::ParsedLine::Kind::sample) {
      take(parsed.t, parsed.p, parsed.alpha);
    } else if (parsed.kind == stream::ParsedLine::Kind::bad) {
      ++pipe.counts.bad_lines;
      if (bad_reported++ < 5) {
        std::cerr << "peritwin-stream: "
                  << (kind == In::tcp ? input
                      : input == "-"  ? "stdin"
                                      : input)
                  << ": line " << pipe.counts.input_lines << " skipped: " << parsed.why << "\n";
      }
    }
  };

  LineInput lines_in;
  bool input_open = true;
  bool lines_idle = false;  // the last pass read no line: wait for the input or the bus
  std::vector<std::string> lines;
  while (input_open && g_signal.load() == 0) {
    // Back-pressure: a FILE is read no faster than the daemon applies.
    const bool backlog =
        sender && sender->last_seq() - std::max<std::int64_t>(sender->acked_seq(), 0) >
                      static_cast<std::int64_t>(4 * std::max<std::size_t>(options.window, 1));
    // One wait over the input and the bus: a sample that closes a batch is read the moment it
    // arrives, not after an LCM wait (which cost up to 20 ms of latency per batch, issue 16).
    const int input_fd = kind == In::fd    ? fd
                         : kind == In::tcp ? (conn_fd >= 0 ? conn_fd : listen_fd)
                                           : -1;
    if (sender && lines_idle) {
      pollfd p[2] = {{input_fd, POLLIN, 0}, {lcm->getFileno(), POLLIN, 0}};
      const nfds_t n = input_fd >= 0 && !backlog ? 2 : 1;
      if (n == 1) p[0] = p[1];
      ::poll(p, n, 20);
    }
    const int wait_ms = sender ? 0 : 50;
    lines.clear();
    if (!backlog) {
      if (kind == In::fd) {
        input_open = lines_in.read(fd, wait_ms, lines);
      } else if (kind == In::tcp) {
        if (conn_fd < 0) {
          pollfd p{listen_fd, POLLIN, 0};
          if (::poll(&p, 1, wait_ms) > 0) {
            conn_fd = ::accept4(listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
            lines_in = LineInput{};
          }
        } else if (!lines_in.read(conn_fd, wait_ms, lines)) {
          ::close(conn_fd);
          conn_fd = -1;
        }
      }
    }
    for (const auto& line : lines) {
      if (skip_lines > 0) {
        --skip_lines;
        continue;
      }
      take_line(line);
    }
    if (samples_in) {
      if (!sender && twin::handle_lcm(*lcm, 50) < 0 && errno != EINTR) {
        error = "LCM failed while receiving";
        break;
      }
      while (!samples_in->inbox.empty()) {
        const auto s = std::move(samples_in->inbox.front());
        samples_in->inbox.pop_front();
        for (std::size_t i = 0; i < s.p.size(); ++i) {
          take(s.time(i), s.p[i], s.alpha.empty() ? 0.0 : s.alpha[i]);
        }
        pipe.samples_taken[s.source_id] = s.seq;
      }
    }
    if (!deliver()) break;
    if (!state_file.empty()) stream::write_received(state_file, pipe.counts.samples);
    lines_idle = lines.empty();
    if (sender && sender->pump(0) == replay::BatchSender::Progress::failed) {
      error = sender->error();
      break;
    }
  }
  if (error.empty()) {
    pipe.finish(rule, closed);
    if (!deliver()) {
      // error set
    } else if (sender) {
      if (!state_file.empty()) {
        if (const Status saved = stream::save_state(state_file, pipe, sender->unacknowledged());
            !saved) {
          error = saved.error().message();
        }
      }
      sender->finish();
      while (error.empty()) {
        const auto p = sender->pump(20);
        if (p == replay::BatchSender::Progress::done) break;
        if (p == replay::BatchSender::Progress::failed) error = sender->error();
      }
      if (error.empty() && !state_file.empty()) {
        if (const Status saved = stream::save_state(state_file, pipe, sender->unacknowledged());
            !saved) {
          error = saved.error().message();
        }
      }
    }
  }
  if (!state_file.empty()) stream::write_received(state_file, pipe.counts.samples);
  if (conn_fd >= 0) ::close(conn_fd);
  if (listen_fd >= 0) ::close(listen_fd);
  const auto& rf = pipe.rainflow();
  std::cerr << "peritwin-stream: " << pipe.counts.samples << " samples (" << rf.nonfinite_samples
            << " non-finite, " << pipe.counts.bad_lines << " bad lines), " << rf.reversals
            << " reversals, " << pipe.counts.block_cycles << " cycles in " << pipe.counts.batches
            << " batches, lost_samples " << pipe.counts.lost_samples << "\n";
  if (!error.empty()) {
    std::cerr << "peritwin-stream: " << error << "\n";
    return kExitRuntime;
  }
  std::optional<peritwin_msgs::damage_state_t> final_state;
  if (local) final_state = local->state;
  if (sender) final_state = sender->last_state();
  if (json && final_state) {
    replay::ConversionStats conversion = pipe.conversion();
    conversion.nonfinite_samples = rf.nonfinite_samples;
    conversion.reversals = rf.reversals;
    std::vector<messages::SummaryObject> extra{
        {"stream",
         {{"samples", static_cast<double>(pipe.counts.samples)},
          {"nonfinite_samples", static_cast<double>(rf.nonfinite_samples)},
          {"bad_lines", static_cast<double>(pipe.counts.bad_lines)},
          {"reversals", static_cast<double>(rf.reversals)},
          {"cycles", static_cast<double>(pipe.counts.block_cycles)},
          {"batches", static_cast<double>(pipe.counts.batches)},
          {"lost_samples", static_cast<double>(pipe.counts.lost_samples)}}},
        {"skipped_cycles", replay::skipped_cycles(conversion)}};
    std::cout << twin::summary_json(*final_state, extra) << std::endl;
  }
  return kExitOk;
}
