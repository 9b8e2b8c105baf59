// peritwin-stream: live load samples of one detail -> [detail.sensor] scale/offset -> rainflow ->
// load blocks -> batches -> the daemon over LCM (or the twin in-process).
//
//   peritwin-stream --config CFG [--detail ID] --input -|FILE|FIFO|tcp://127.0.0.1:PORT|lcm
//                   [--lcm-url URL] [--source ID] [--state-file F] [--json] [--batch-cycles N]
//                   [--batch-blocks N] [--batch-seconds T] [--lockstep|--window N]
//                   [--residue half|whole|keep] [--in-process] [--give-up-after S]
//                   [--key-file F [--daemon-key ID | --sign-only]]
//                   [--format series|gauges [--identify-only] [--identify-with G,...]
//                   [--gauge-observe-cycles N]]
//
// Input: lines "t,P" or "t,P,alpha" (the series format's columns; its header line and '#'
// comments accepted; t in s strictly increasing, P in the sensor's unit, alpha in rad), read as
// they arrive (stdin and FIFOs line by line, not at EOF). tcp://127.0.0.1:PORT listens there and
// takes one connection at a time (a closed connection is not the end: the next one continues the
// stream). lcm: load_samples_t on PERITWIN_<DETAIL>_SAMPLES (each (source, seq) once, gaps
// reported). A line that is no sample is skipped and counted (bad_lines), the first ones named.
// Bounds (stream/stream_tool.h): a line longer than kMaxLineBytes (4 KiB) ends the input with an
// error; a sample whose time is not finite, beyond the clock (kMaxFutureSeconds) or not after the
// previous one, or whose load is outside sample_load_bound(), is skipped and counted (bad_lines),
// never taken, so it poisons neither later samples nor its batch (after kRebaseAfter samples in
// a row behind an outlying time the stream goes on from them).
// --format gauges (issue 33, docs/gauges.md): the input is a strain-gauge series, the header
// "time_s,<gauge id>,..." (ids of the detail's [[detail.gauge]]) then lines "t,e1,...,en"
// (strains, dimensionless); each sample's P and α are identified by least squares from the
// model's influence coefficients (stream/gauge_identification.h): the daemon's newest (every
// STATE carries them, recomputed after each re-solve) or the in-process twin's. [detail.sensor]
// scale and offset do not apply (gate and alpha_bin do). --identify-with G,...: the loads from
// these columns only (gauges away from the crack), the others compared only. A header whose gauges
// give fewer independent equations than the load's unknowns is refused (exit 2, the reason). Every
// --gauge-observe-cycles cycles (default 5000; 0 = never), and at the end of input, the gauges'
// compliance over the samples since the last one goes to the twin as an observation
// (stream/gauge_feed.h) once the batches before it are applied: its residual per gauge is in the
// STATE, a persistent one turns the daemon's health "degraded" naming the gauge, and a learning
// twin's ensemble takes it in.
// --identify-only writes the identified series "time_s,load_N,angle_rad" to stdout and exits
// (no batches; the coefficients of the daemon's current state, or with --in-process of the
// virgin model). --input lcm carries loads, not strains: refused with --format gauges.
// Each sample: P = scale * measured + offset, then RainflowCounter (gate) -> CycleBlocks
// (alpha_bin, compressed_bonds_fatigue) -> batches closed at --batch-cycles (1000) cycles,
// --batch-blocks (1024) blocks, or --batch-seconds of sample time (0: off).
// End of input (EOF of stdin, a FILE or a FIFO; SIGINT/SIGTERM for any input): the residue by
// --residue (default half, ASTM E1049-85, as peritwin-replay: a stream of a finished file
// applies the same cycles as its replay; whole: each residue range a whole cycle; keep: not
// applied), the last batch, then it waits for the daemon to apply everything (at most
// --give-up-after s without progress) and exits 0.
// --key-file: as peritwin-replay (loads/producer_keys.h): batches signed with the key of --source,
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
// "skipped_cycles" as peritwin-replay (also after an input error).
// A reject no resend can cure ends the stream at once with the daemon's reason, as in
// peritwin-replay (loads/batch_sender.h); FAILED after a batch of the stream was applied is the
// detail's end of life: the rest of the input is not read, exit 0.
// Exit codes (core/exit_codes.h): 0 done (kExitOk), 2 (kExitUsage) bad usage/config/state file or
// input that is no sample stream (a line over 4 KiB, lines without one usable sample; what came
// before is delivered first), 3 (kExitRuntime) runtime failure (LCM, no progress, a batch the
// daemon refuses for good, a state file that cannot be written).
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include "core/cli_checks.h"
#include "core/exit_codes.h"
#include "core/program.h"
#include "core/stop_signal.h"
#include "loads/producer_keys.h"
#include "messages/auth.h"
#include "messages/channels.h"
#include "messages/transport.h"
#include "replay/observation_sender.h"
#include "replay/replay_tool.h"
#include "stream/gauge_feed.h"
#include "stream/stream_tool.h"
#include "twin/in_process_twin.h"

namespace {
using namespace peritwin;
using core::kExitOk;
using core::kExitRuntime;
using core::kExitUsage;

/// Lines from a descriptor as they arrive (stdin, a FILE, a FIFO, a TCP connection), each at most
/// stream::kMaxLineBytes long: a longer one is not read on (its memory stays bounded).
class LineInput {
 public:
  enum class Read { open, eof, too_long };
  /// Reads what is available within timeout_ms; complete lines go to `lines` (those before an
  /// over-long one too).
  Read read(int fd, int timeout_ms, std::vector<std::string>& lines) {
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, timeout_ms);
    if (ready <= 0) return Read::open;
    char buf[65536];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0) return errno == EINTR || errno == EAGAIN ? Read::open : Read::eof;
    if (n == 0) {
      if (!partial_.empty()) lines.push_back(std::move(partial_));
      partial_.clear();
      return Read::eof;
    }
    for (ssize_t i = 0; i < n; ++i) {
      if (buf[i] == '\n') {
        lines.push_back(std::move(partial_));
        partial_.clear();
      } else if (partial_.size() >= stream::kMaxLineBytes) {
        partial_.clear();
        return Read::too_long;
      } else {
        partial_ += buf[i];
      }
    }
    return Read::open;
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
      const core::Status signed_ok =
          key != nullptr ? messages::verify_encoded<peritwin_msgs::load_samples_t>(
                               rbuf->data, static_cast<std::size_t>(rbuf->data_size), *key)
                         : core::Status{core::failure("no key for source \"" + s.source_id +
                                                      "\" in the key file")};
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

/// The command line.
struct Options {
  std::string config_file, detail_id, input, lcm_url, source_id = "stream", state_file;
  std::string residue = "half", format = "series";
  bool lockstep = false, in_process = false, json = false, identify_only = false;
  std::int64_t gauge_observe_cycles = 5000;
  std::vector<std::string> identify_with;
  loads::BatchingOptions batching;
  loads::ReplayOptions replay;
  loads::ProducerKeyOptions keys;
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("--config", o.config_file, "detail configuration (TOML)")->required();
  app.add_option("--detail", o.detail_id, "detail id (default: the config's first detail)");
  app.add_option("--input", o.input, "-|FILE|FIFO|tcp://127.0.0.1:PORT|lcm")->required();
  app.add_option("--lcm-url", o.lcm_url, "LCM URL (default: $LCM_DEFAULT_URL, then LCM's)");
  app.add_option("--source", o.source_id, "source id of the batches (default stream)");
  app.add_option("--state-file", o.state_file,
                 "keep the stream's state here (atomic, checksummed): a restart continues it");
  app.add_flag("--json", o.json, "JSON lines: one per state update, then a summary");
  app.add_option("--batch-cycles", o.batching.max_cycles,
                 "close a batch once it holds this many cycles (default 1000)")
      ->check(CLI::PositiveNumber);
  app.add_option("--batch-blocks", o.batching.max_blocks, "blocks per batch at most (default 1024)")
      ->check(CLI::PositiveNumber);
  app.add_option("--batch-seconds", o.batching.max_seconds,
                 "close a batch after this much sample time (s; default 0 = off)")
      ->check(peritwin::core::finite_in(0.0, std::numeric_limits<double>::max()));
  auto* lockstep_opt =
      app.add_flag("--lockstep", o.lockstep, "wait for the daemon to apply each batch");
  app.add_option("--window", o.replay.window, "batches in flight without --lockstep (256)")
      ->check(CLI::PositiveNumber)
      ->excludes(lockstep_opt);
  app.add_option("--residue", o.residue,
                 "the rainflow residue at the end of input: half (default, ASTM E1049-85, as the "
                 "replay), whole (conservative) or keep (not applied)")
      ->check(CLI::IsMember({"half", "whole", "keep"}));
  auto* in_process_opt =
      app.add_flag("--in-process", o.in_process, "run the twin library here (no daemon)");
  loads::add_key_options(app, o.keys)->excludes(in_process_opt);
  app.add_option("--format", o.format,
                 "series: t,P[,alpha] lines (default); gauges: the header time_s,<gauge id>,... "
                 "then t,<strains> lines, the loads identified from the model's gauges")
      ->check(CLI::IsMember({"series", "gauges"}));
  app.add_flag("--identify-only", o.identify_only,
               "--format gauges: write the identified time_s,load_N,angle_rad to stdout and exit");
  app.add_option("--identify-with", o.identify_with,
                 "--format gauges: identify the loads from these gauges only (comma-separated; "
                 "default all columns), the others only compared: gauges away from the crack")
      ->delimiter(',');
  app.add_option("--gauge-observe-cycles", o.gauge_observe_cycles,
                 "--format gauges: the gauges' compliance to the twin every this many cycles "
                 "(default 5000; 0 = never)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--give-up-after", o.replay.give_up_after_s,
                 "seconds without progress from the daemon before failing (default 120)")
      ->check(peritwin::core::finite_positive());
}

/// Where the samples come from (--input).
struct Input {
  enum class Kind { fd, tcp, lcm } kind = Kind::fd;
  int fd = -1, port = 0;
  bool seekable = false;  ///< a FILE: a restart skips the lines already counted
};

/// Parses --input and opens a FILE or FIFO; an exit code when it cannot.
std::optional<int> open_input(const std::string& input, Input& in) {
  if (input == "-") {
    in.fd = STDIN_FILENO;
  } else if (input == "lcm") {
    in.kind = Input::Kind::lcm;
  } else if (input.starts_with("tcp://")) {
    in.kind = Input::Kind::tcp;
    const std::string rest = input.substr(6);
    const auto colon = rest.rfind(':');
    if (colon == std::string::npos || rest.substr(0, colon) != "127.0.0.1" ||
        (in.port = std::atoi(rest.c_str() + colon + 1)) <= 0 || in.port > 65535) {
      std::cerr << "peritwin-stream: --input " << input
                << ": expected tcp://127.0.0.1:PORT (loopback only)\n";
      return core::kExitUsage;
    }
  } else {
    in.fd = ::open(input.c_str(), O_RDONLY | O_CLOEXEC);
    if (in.fd < 0) {
      std::cerr << "peritwin-stream: " << input << ": cannot open: " << std::strerror(errno)
                << "\n";
      return core::kExitUsage;
    }
    struct stat st {};
    in.seekable = ::fstat(in.fd, &st) == 0 && S_ISREG(st.st_mode);
  }
  return std::nullopt;
}

/// The checks of the options against the config; an exit code when they fail.
std::optional<int> check_options(const Options& o, const config::DetailConfig* detail) {
  if (detail == nullptr) {
    std::cerr << "peritwin-stream: no detail \"" << o.detail_id << "\" in " << o.config_file
              << "\n";
    return core::kExitUsage;
  }
  if (o.source_id.empty() || o.source_id.size() > messages::kMaxSourceIdLength) {
    std::cerr << "peritwin-stream: --source must have 1 to 64 characters\n";
    return core::kExitUsage;
  }
  if (o.format == "gauges" && o.input == "lcm") {
    std::cerr << "peritwin-stream: --format gauges reads strain lines (stdin, a FILE, a FIFO, "
                 "tcp://); --input lcm carries loads (load_samples_t)\n";
    return core::kExitUsage;
  }
  if (o.format == "gauges" && detail->gauges.empty()) {
    std::cerr << "peritwin-stream: --format gauges: detail " << detail->id
              << " has no [[detail.gauge]] in " << o.config_file << "\n";
    return core::kExitUsage;
  }
  if (o.identify_only && (o.format != "gauges" || !o.state_file.empty())) {
    std::cerr << "peritwin-stream: --identify-only needs --format gauges and no --state-file\n";
    return core::kExitUsage;
  }
  if (o.in_process && !o.state_file.empty()) {
    std::cerr << "peritwin-stream: --state-file needs a daemon (the in-process twin is not "
                 "persisted)\n";
    return core::kExitUsage;
  }
  return std::nullopt;
}

/// The pipeline and the batches not acknowledged of an existing --state-file; an exit code when
/// it is corrupt.
std::optional<int> restore_state(const Options& o, const config::DetailConfig& detail,
                                 bool seekable, std::optional<stream::Pipeline>& pipeline,
                                 std::vector<messages::Batch>& resend) {
  auto restored = stream::load_state(o.state_file, detail, o.source_id, o.batching);
  if (!restored) {
    std::cerr << "peritwin-stream: corrupt state file " << restored.error() << "\n";
    return core::kExitUsage;
  }
  pipeline.emplace(std::move(restored->pipeline));
  resend = std::move(restored->unacknowledged);
  auto& c = pipeline->counts;
  std::uint64_t lost = 0;
  if (!seekable) {
    const auto received = stream::read_received(o.state_file);
    if (received && *received > c.samples) lost = *received - c.samples;
    c.lost_samples += lost;
  }
  std::cerr << "peritwin-stream: resumed from " << o.state_file << ": " << c.samples << " samples, "
            << c.batches << " batches (next seq " << pipeline->next_seq() << ", " << resend.size()
            << " not acknowledged); lost_samples " << lost
            << (seekable ? " (a FILE input: the lines after line " + std::to_string(c.input_lines) +
                               " are read again)"
                         : " (read after the last persisted state, not counted)")
            << "\n";
  return std::nullopt;
}

/// LCM at `url` (a tcpq hub probed first); an exit code when it cannot be opened.
std::optional<int> open_lcm(const std::string& url, std::unique_ptr<lcm::LCM>& lcm) {
  const auto hub = messages::tcpq_hub(url);
  if (const core::Status up = hub ? messages::probe_hub(*hub) : core::Status{}; !up) {
    std::cerr << "peritwin-stream: LCM hub " << url << " unreachable: " << up.error().message()
              << "\n";
    return core::kExitRuntime;
  }
  lcm = std::make_unique<lcm::LCM>(url);
  if (!lcm->good() || !messages::transport_up(*lcm)) {
    std::cerr << "peritwin-stream: cannot open LCM at \"" << messages::shown_url(url) << "\"\n";
    return core::kExitRuntime;
  }
  return std::nullopt;
}

/// --input lcm: the subscription, with --key-file the samples verified too (with the key of each
/// message's source_id), unless --sign-only (the key file then holds only this stream's key).
std::optional<int> subscribe_samples(const Options& o, lcm::LCM& lcm, const std::string& detail_id,
                                     std::map<std::string, std::int64_t> taken,
                                     std::unique_ptr<SamplesInput>& samples_in) {
  std::optional<messages::KeyRing> ring;
  if (!o.keys.key_file.empty() && !o.keys.sign_only) {
    auto loaded_ring = messages::KeyRing::load(o.keys.key_file);
    if (!loaded_ring) {
      std::cerr << "peritwin-stream: " << loaded_ring.error().message() << "\n";
      return core::kExitUsage;
    }
    ring = std::move(*loaded_ring);
  } else {
    std::cerr << "peritwin-stream: the samples on the bus are not verified (no --key-file, or "
                 "--sign-only): anyone on the bus can feed this stream\n";
  }
  samples_in = std::make_unique<SamplesInput>(lcm, detail_id, std::move(ring), std::move(taken));
  return std::nullopt;
}

/// One run of the stream: set_up(), then loop() to the end of input, then finish().
class Stream {
 public:
  Stream(const Options& o, const config::DetailConfig& detail, Input in)
      : o_(o), detail_(detail), in_(in), printer_(o.json) {}
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;
  ~Stream() {
    if (conn_fd_ >= 0) ::close(conn_fd_);
    if (listen_fd_ >= 0) ::close(listen_fd_);
  }

  /// The state file, LCM, the twin or the daemon, the TCP listener; an exit code when one fails.
  std::optional<int> set_up(loads::ReplayAuth auth);
  /// Reads the input and delivers the batches until its end, a signal or an error.
  void loop();
  /// The residue and the last batch, then waits for the daemon; the report and the summary.
  int finish();

 private:
  std::optional<int> set_up_sender(loads::ReplayAuth auth, std::vector<messages::Batch> resend);
  bool deliver();
  /// --format gauges: the newest coefficients to the feed; the compliance observation when due.
  /// A STATE from the daemon (a batch's or an observation's): printed and kept as the last.
  void seen(const peritwin_msgs::damage_state_t& s) {
    printer_.print(s);
    last_seen_ = s;
  }
  void follow_gauges();
  /// `last`: the end of input: the window so far, due or not.
  void observe_gauges(bool last = false);
  void take(double t, double p, double alpha);
  void take_line(const std::string& line);
  void take_gauge_line(const std::string& line);
  void report_bad_line(const std::string& line, const std::string& why);
  [[nodiscard]] std::string input_name() const {
    return in_.kind == Input::Kind::tcp ? o_.input : o_.input == "-" ? "stdin" : o_.input;
  }
  bool read_input(bool backlog, std::vector<std::string>& lines);
  void save_state(const std::vector<messages::Batch>& pending) {
    if (const core::Status saved = stream::save_state(o_.state_file, *pipeline_, pending); !saved) {
      error_ = saved.error().message();
    }
  }

  const Options& o_;
  const config::DetailConfig& detail_;
  Input in_;
  replay::StatePrinter printer_;
  std::optional<stream::Pipeline> pipeline_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<SamplesInput> samples_in_;
  std::unique_ptr<loads::BatchSender> sender_;
  std::unique_ptr<twin::InProcessTwin> local_;
  int listen_fd_ = -1, conn_fd_ = -1;
  std::uint64_t skip_lines_ = 0, bad_reported_ = 0;
  std::vector<messages::Batch> closed_;
  std::string error_;
  /// The input is no sample stream (an over-long line, no usable line): exit kExitUsage after
  /// what was taken before is delivered.
  std::string input_error_;
  bool line_too_long_ = false;  ///< read_input() met a line beyond kMaxLineBytes
  bool stop_input_ = false;     ///< the input cannot be read on (a gauge header refused)
  std::string first_bad_;       ///< the first line skipped, for the no-usable-line error
  double load_bound_ = 0.0;     ///< sample_load_bound(), or in-process the twin's max_p
  int behind_ = 0;              ///< samples in a row refused as not after last_time ...
  double behind_last_ = 0.0;    ///< ... the last of them
  LineInput lines_in_;
  /// --format gauges: the feed, the state_seq its coefficients are from, the block cycles at
  /// which the next compliance observation is due, the last observation seq of --source.
  std::optional<stream::GaugeFeed> gauges_;
  std::int64_t coefficients_seq_ = -1;
  std::uint64_t next_observation_cycles_ = 0;
  std::int64_t observation_seq_ = 0;
  loads::ReplayAuth auth_;
  std::optional<peritwin_msgs::damage_state_t> last_seen_;
};

std::optional<int> Stream::set_up(loads::ReplayAuth auth) {
  load_bound_ = stream::sample_load_bound(detail_);
  auth_ = auth;
  if (o_.format == "gauges") {
    gauges_.emplace();
    next_observation_cycles_ = static_cast<std::uint64_t>(o_.gauge_observe_cycles);
  }
  std::vector<messages::Batch> resend;
  if (!o_.state_file.empty() && std::filesystem::exists(o_.state_file)) {
    if (auto rc = restore_state(o_, detail_, in_.seekable, pipeline_, resend)) return rc;
  }
  // Where the batches go.
  const std::string lcm_url = core::lcm_url_or_default(o_.lcm_url);
  if (!o_.in_process || in_.kind == Input::Kind::lcm) {
    if (auto rc = open_lcm(lcm_url, lcm_)) return rc;
  }
  // Subscribed before anything else happens on the bus (the probe, the first state printed):
  // a sample message published once the stream has said it is up is never missed.
  if (in_.kind == Input::Kind::lcm) {
    if (auto rc = subscribe_samples(
            o_, *lcm_, detail_.id,
            pipeline_ ? pipeline_->samples_taken : std::map<std::string, std::int64_t>{},
            samples_in_)) {
      return rc;
    }
  }
  core::install_stop_handler();
  std::signal(SIGPIPE, SIG_IGN);
  if (o_.in_process) {
    auto created = twin::InProcessTwin::create(detail_);
    if (!created) {
      std::cerr << "peritwin-stream: " << created.error() << "\n";
      return core::kExitUsage;
    }
    local_ = std::move(*created);
    printer_.print(local_->state());
    // The model is built here: its max_p (configured or derived) bounds the samples, as the
    // twin bounds the blocks.
    if (std::isfinite(local_->twin().max_p())) load_bound_ = local_->twin().max_p();
    if (!pipeline_) pipeline_.emplace(detail_, o_.source_id, o_.batching, 1);
  } else if (auto rc = set_up_sender(std::move(auth), std::move(resend))) {
    return rc;
  }
  if (in_.kind == Input::Kind::tcp) {
    listen_fd_ = listen_on(in_.port);
    if (listen_fd_ < 0) {
      std::cerr << "peritwin-stream: cannot listen on 127.0.0.1:" << in_.port << ": "
                << std::strerror(errno) << "\n";
      return core::kExitRuntime;
    }
    std::cerr << "peritwin-stream: listening on tcp://127.0.0.1:" << in_.port << "\n";
  }
  // A FILE input after a restart: the lines the state has counted are skipped.
  skip_lines_ = in_.seekable ? pipeline_->counts.input_lines : 0;
  if (!in_.seekable) pipeline_->counts.input_lines = 0;
  return std::nullopt;
}

/// The sender to the daemon: what the daemon has applied of --source decides the first seq (or,
/// with a state file, which of its batches are sent again).
std::optional<int> Stream::set_up_sender(loads::ReplayAuth auth,
                                         std::vector<messages::Batch> resend) {
  sender_ = std::make_unique<loads::BatchSender>(*lcm_, detail_.id, o_.source_id, o_.replay,
                                                 std::move(auth));
  sender_->on_state([this](const peritwin_msgs::damage_state_t& s) { seen(s); });
  const auto learned = sender_->probe_applied(core::keep_running);
  if (!learned) {
    std::cerr << "peritwin-stream: " << learned.error().message() << "\n";
    return core::kExitRuntime;
  }
  const std::int64_t applied = *learned;
  if (!pipeline_) {
    pipeline_.emplace(detail_, o_.source_id, o_.batching, applied + 1);
    if (applied > 0) {
      std::cerr << "peritwin-stream: source '" << o_.source_id << "' has batches up to seq "
                << applied << " applied on detail " << detail_.id
                << ": this stream's batches follow from " << applied + 1 << "\n";
    }
    return std::nullopt;
  }
  const std::int64_t held = resend.empty() ? pipeline_->next_seq() : resend.front().seq;
  if (applied + 1 < held) {
    std::cerr << "peritwin-stream: the daemon has applied seq " << applied << " of source '"
              << o_.source_id << "', but " << o_.state_file << " holds batches from seq " << held
              << " only (the daemon lost acknowledged batches?)\n";
    return core::kExitRuntime;
  }
  if (applied >= pipeline_->next_seq()) {
    std::cerr << "peritwin-stream: the daemon has applied seq " << applied << " of source '"
              << o_.source_id << "', beyond this state file's next seq " << pipeline_->next_seq()
              << ": another producer uses this source (use another --source)\n";
    return core::kExitUsage;
  }
  for (auto& b : resend) {
    if (b.seq > applied) sender_->add(std::move(b));
  }
  return std::nullopt;
}

/// The closed batches to the daemon or the twin (persisted first with a state file); false
/// (error_ set) when that fails.
bool Stream::deliver() {
  if (closed_.empty()) return true;
  if (!o_.state_file.empty()) {
    std::vector<messages::Batch> pending =
        sender_ ? sender_->unacknowledged() : std::vector<messages::Batch>{};
    pending.insert(pending.end(), closed_.begin(), closed_.end());
    save_state(pending);
    if (!error_.empty()) return false;
  }
  for (auto& b : closed_) {
    if (sender_) {
      sender_->add(std::move(b));
    } else if (const peritwin::core::Status applied = local_->apply(b); !applied) {
      error_ = applied.error().message();
      return false;
    } else {
      printer_.print(local_->state());
    }
  }
  closed_.clear();
  return true;
}

void Stream::take(double t, double p, double alpha) {
  stream::Pipeline& pipe = *pipeline_;
  // One bad sample is skipped and counted (bad_lines), never taken: a time beyond the clock or a
  // load beyond the detail's range would refuse every later sample or the whole batch.
  const double now_s =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  const double load = pipe.load(p);
  const double bound = load_bound_;
  const bool behind = std::isfinite(t) && pipe.last_time && !(t > *pipe.last_time);
  std::ostringstream why;
  if (!std::isfinite(t)) {
    why << "the time is not a finite number";
  } else if (t > now_s + stream::kMaxFutureSeconds) {
    why << "time " << t << " s is more than a day after the clock's now (Unix time)";
  } else if (behind) {
    why << "time not after " << *pipe.last_time << " s";
  } else if (std::isfinite(load) && (load > bound || load < -10.0 * bound)) {
    why << "load P = " << load << " N is outside [" << -10.0 * bound << ", " << bound << "] N"
        << (local_ || detail_.limits.max_p ? " (the detail's max_p)" : " (absurd for any detail)");
  }
  if (why.tellp() == 0) {
    behind_ = 0;
    pipe.sample(t, p, alpha, closed_);
    return;
  }
  ++pipe.counts.bad_lines;
  if (bad_reported_++ < 5) {
    std::cerr << "peritwin-stream: sample at t = " << t << " s skipped: " << why.str() << "\n";
  }
  if (first_bad_.empty()) {
    std::ostringstream text;
    text << "the sample at t = " << t << " s: " << why.str();
    first_bad_ = text.str();
  }
  if (!behind) return;
  // Samples that keep coming before the last time taken, in order among themselves: that time
  // was the outlier (a glitch ahead); the stream goes on from them.
  behind_ = behind_ > 0 && t > behind_last_ ? behind_ + 1 : 1;
  behind_last_ = t;
  if (behind_ >= stream::kRebaseAfter) {
    std::cerr << "peritwin-stream: " << behind_
              << " samples in a row before t = " << *pipe.last_time << " s, the last at t = " << t
              << " s: that time was out of line, the stream goes on from t = " << t << " s\n";
    pipe.last_time = t;
    behind_ = 0;
  }
}

void Stream::take_line(const std::string& line) {
  stream::Pipeline& pipe = *pipeline_;
  ++pipe.counts.input_lines;
  if (gauges_) {
    take_gauge_line(line);
    return;
  }
  const auto parsed = stream::parse_line(line);
  if (parsed.kind == stream::ParsedLine::Kind::sample) {
    take(parsed.t, parsed.p, parsed.alpha);
  } else if (parsed.kind == stream::ParsedLine::Kind::bad) {
    report_bad_line(line, parsed.why);
  }
}

void Stream::report_bad_line(const std::string& line, const std::string& why) {
  stream::Pipeline& pipe = *pipeline_;
  ++pipe.counts.bad_lines;
  if (bad_reported_++ < 5) {
    std::cerr << "peritwin-stream: " << input_name() << ": line " << pipe.counts.input_lines
              << " skipped: " << why << "\n";
  }
  if (first_bad_.empty()) {
    std::string text;
    for (const char c : line.substr(0, 60)) text += c >= 0x20 && c < 0x7f ? c : '?';
    first_bad_ = "line " + std::to_string(pipe.counts.input_lines) + " \"" + text +
                 (line.size() > 60 ? "...\"" : "\"") + ": " + why;
  }
}

/// The model's gauges as the newest state says (the daemon's last STATE, or the in-process
/// twin's); empty before one.
/// (Not a copy: follow_gauges asks at every turn of the input loop.)
const peritwin_msgs::damage_state_t* newest_state(const loads::BatchSender* sender,
                                                  const twin::InProcessTwin* local) {
  if (local != nullptr) return &local->state();
  if (sender != nullptr && sender->last_state()) return &*sender->last_state();
  return nullptr;
}

void Stream::take_gauge_line(const std::string& line) {
  if (!gauges_->has_header()) {
    const std::string_view text = line;
    if (text.find_first_not_of(" \t\r") == std::string_view::npos || text.starts_with('#')) return;
    const auto state = newest_state(sender_.get(), local_.get());
    const auto influences =
        state ? stream::influences_of(*state) : std::vector<stream::GaugeInfluence>{};
    if (influences.empty()) {
      input_error_ = "the daemon's STATE lists no gauge of detail " + detail_.id +
                     " (is its config the one with [[detail.gauge]]?)";
      stop_input_ = true;
      return;
    }
    // The identifying gauges: --identify-with, else the config's (identify = true) among the
    // columns, else every column.
    std::vector<std::string> identify_with = o_.identify_with;
    if (identify_with.empty()) {
      const auto columns = stream::parse_gauge_header(line);
      for (const auto& g : detail_.gauges) {
        if (g.identify && columns &&
            std::find(columns->begin(), columns->end(), g.id) != columns->end()) {
          identify_with.push_back(g.id);
        }
      }
    }
    if (const core::Status ok = gauges_->header(line, influences, identify_with); !ok) {
      input_error_ = input_name() + ": line " + std::to_string(pipeline_->counts.input_lines) +
                     ": " + ok.error().message();
      stop_input_ = true;
      return;
    }
    coefficients_seq_ = state->state_seq;
    const auto& id = gauges_->identifier();
    std::cerr << "peritwin-stream: " << gauges_->columns().size() << " gauges ("
              << id.columns().size() << " identifying), " << id.unknowns()
              << (id.unknowns() == 1 ? " unknown (P)" : " unknowns (P, alpha)")
              << ", coefficients of state " << coefficients_seq_ << "\n";
    if (o_.identify_only) std::cout << "time_s,load_N,angle_rad\n";
    return;
  }
  auto sample = gauges_->line(line);
  if (!sample) {
    report_bad_line(line, sample.error());
    return;
  }
  if (!*sample) return;
  const stream::IdentifiedSample& s = **sample;
  if (o_.identify_only) {
    ++pipeline_->counts.samples;
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.9g,%.9g,%.9g\n", s.t, s.load.p, s.load.alpha);
    std::cout << buf;
    return;
  }
  take(s.t, s.load.p, s.load.alpha);
}

void Stream::follow_gauges() {
  if (!gauges_ || !gauges_->has_header()) return;
  const auto state = newest_state(sender_.get(), local_.get());
  if (!state || state->state_seq == coefficients_seq_) return;
  if (const core::Status ok = gauges_->update(stream::influences_of(*state)); !ok) {
    std::cerr << "peritwin-stream: the coefficients of state " << state->state_seq
              << " are kept out: " << ok.error().message() << "\n";
  }
  coefficients_seq_ = state->state_seq;
}

void Stream::observe_gauges(bool last) {
  if (!gauges_ || o_.gauge_observe_cycles <= 0 || o_.identify_only) return;
  if (!last && pipeline_->counts.block_cycles < next_observation_cycles_) return;
  while (next_observation_cycles_ <= pipeline_->counts.block_cycles) {
    next_observation_cycles_ += static_cast<std::uint64_t>(o_.gauge_observe_cycles);
  }
  auto o = gauges_->take_observation();
  if (!o) return;
  o->detail_id = detail_.id;
  o->source_id = o_.source_id;
  if (local_) {
    o->cycle = local_->twin().engine().total_cycles();
    o->seq = ++observation_seq_;
    if (const core::Status taken = local_->observe(*o); !taken) {
      --observation_seq_;  // refused: the next one takes its seq
      std::cerr << "peritwin-stream: " << taken.error().message() << "\n";
    } else {
      printer_.print(local_->state());
    }
    return;
  }
  // Over LCM: after every batch sent so far is applied, at the daemon's cycle count then.
  while (sender_->acked_seq() < sender_->last_seq() && core::keep_running()) {
    const auto p = sender_->pump(20);
    if (p == loads::BatchSender::Progress::failed) {
      error_ = sender_->error();
      return;
    }
    if (p == loads::BatchSender::Progress::done) return;  // the end of life
  }
  const auto& state = last_seen_ ? last_seen_ : sender_->last_state();
  if (!state) return;
  o->cycle = state->total_cycles;
  // This source's observation seq as the daemon has it (all its batches applied, so this STATE
  // is current): a restarted stream follows on, and a refused observation's seq is taken again.
  observation_seq_ = 0;
  for (std::size_t k = 0; k < state->observation_source_ids.size(); ++k) {
    if (state->observation_source_ids[k] == o_.source_id) {
      observation_seq_ = state->observation_applied_seq[k];
    }
  }
  o->seq = ++observation_seq_;
  if (const core::Status sent = replay::send_observation(
          *lcm_, *o, o_.replay, auth_, [this](const auto& s) { seen(s); }, core::keep_running);
      !sent) {
    std::cerr << "peritwin-stream: gauge observation " << o->seq << ": " << sent.error().message()
              << "\n";
  }
}

/// The lines of the input available now (none with a backlog): the FILE, FIFO or stdin, or the
/// TCP connection (accepting one when there is none). False at the end of input.
bool Stream::read_input(bool backlog, std::vector<std::string>& lines) {
  const int wait_ms = sender_ ? 0 : 50;
  if (backlog) return true;
  if (in_.kind == Input::Kind::fd) {
    const LineInput::Read r = lines_in_.read(in_.fd, wait_ms, lines);
    line_too_long_ = r == LineInput::Read::too_long;
    return r == LineInput::Read::open;
  } else if (in_.kind == Input::Kind::tcp) {
    if (conn_fd_ < 0) {
      pollfd p{listen_fd_, POLLIN, 0};
      if (::poll(&p, 1, wait_ms) > 0) {
        conn_fd_ = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
        lines_in_ = LineInput{};
      }
    } else if (const LineInput::Read r = lines_in_.read(conn_fd_, wait_ms, lines);
               r != LineInput::Read::open) {
      ::close(conn_fd_);
      conn_fd_ = -1;
      line_too_long_ = r == LineInput::Read::too_long;
      return !line_too_long_;  // an over-long line ends the stream, a closed connection not
    }
  }
  return true;
}

void Stream::loop() {
  stream::Pipeline& pipe = *pipeline_;
  bool input_open = true;
  bool lines_idle = false;  // the last pass read no line: wait for the input or the bus
  std::vector<std::string> lines;
  while (input_open && core::keep_running()) {
    // Back-pressure: a FILE is read no faster than the daemon applies.
    const bool backlog =
        sender_ && sender_->last_seq() - std::max<std::int64_t>(sender_->acked_seq(), 0) >
                       static_cast<std::int64_t>(4 * std::max<std::size_t>(o_.replay.window, 1));
    // One wait over the input and the bus: a sample that closes a batch is read the moment it
    // arrives, not after an LCM wait (which cost up to 20 ms of latency per batch, issue 16).
    const int input_fd = in_.kind == Input::Kind::fd    ? in_.fd
                         : in_.kind == Input::Kind::tcp ? (conn_fd_ >= 0 ? conn_fd_ : listen_fd_)
                                                        : -1;
    if (sender_ && lines_idle) {
      pollfd p[2] = {{input_fd, POLLIN, 0}, {lcm_->getFileno(), POLLIN, 0}};
      const nfds_t n = input_fd >= 0 && !backlog ? 2 : 1;
      if (n == 1) p[0] = p[1];
      ::poll(p, n, 20);
    }
    lines.clear();
    input_open = read_input(backlog, lines);
    for (const auto& line : lines) {
      if (skip_lines_ > 0) {
        --skip_lines_;
        // A restart over a FILE skips the lines taken before, a gauge series' header included:
        // its columns are read again.
        if (gauges_ && !gauges_->has_header()) take_gauge_line(line);
        continue;
      }
      take_line(line);
      if (stop_input_) break;
    }
    if (line_too_long_) {
      input_error_ = input_name() + ": line " + std::to_string(pipe.counts.input_lines + 1) +
                     " is longer than " + std::to_string(stream::kMaxLineBytes) +
                     " bytes without an end of line: no sample stream; input ended there";
    }
    if (samples_in_) {
      if (!sender_ && messages::handle_lcm(*lcm_, 50) < 0 && errno != EINTR) {
        error_ = "LCM failed while receiving";
        break;
      }
      while (!samples_in_->inbox.empty()) {
        const auto s = std::move(samples_in_->inbox.front());
        samples_in_->inbox.pop_front();
        for (std::size_t i = 0; i < s.p.size(); ++i) {
          take(s.time(i), s.p[i], s.alpha.empty() ? 0.0 : s.alpha[i]);
        }
        pipe.samples_taken[s.source_id] = s.seq;
      }
    }
    if (!deliver()) break;
    follow_gauges();
    observe_gauges();
    if (!error_.empty() || stop_input_) break;
    if (!o_.state_file.empty()) stream::write_received(o_.state_file, pipe.counts.samples);
    lines_idle = lines.empty();
    const auto progress = sender_ ? sender_->pump(0) : loads::BatchSender::Progress::running;
    if (progress == loads::BatchSender::Progress::failed) {
      error_ = sender_->error();
      break;
    }
    if (progress == loads::BatchSender::Progress::done) break;  // the detail's end of life
  }
}

/// The "stream" and "skipped_cycles" objects of the --json summary.
std::vector<messages::SummaryObject> summary_extra(const stream::Pipeline& pipe) {
  const auto& rf = pipe.rainflow();
  loads::ConversionStats conversion = pipe.conversion();
  conversion.nonfinite_samples = rf.nonfinite_samples;
  conversion.reversals = rf.reversals;
  return {{"stream",
           {{"samples", static_cast<double>(pipe.counts.samples)},
            {"nonfinite_samples", static_cast<double>(rf.nonfinite_samples)},
            {"bad_lines", static_cast<double>(pipe.counts.bad_lines)},
            {"reversals", static_cast<double>(rf.reversals)},
            {"cycles", static_cast<double>(pipe.counts.block_cycles)},
            {"batches", static_cast<double>(pipe.counts.batches)},
            {"lost_samples", static_cast<double>(pipe.counts.lost_samples)}}},
          {"skipped_cycles", replay::skipped_cycles(conversion)}};
}

int Stream::finish() {
  stream::Pipeline& pipe = *pipeline_;
  const loads::ResidueRule rule = o_.residue == "whole"  ? loads::ResidueRule::whole
                                  : o_.residue == "keep" ? loads::ResidueRule::keep
                                                         : loads::ResidueRule::half;
  // The detail reached its end of life while the input was read: nothing more is applied.
  const bool ended = sender_ && !sender_->end_of_life().empty();
  if (error_.empty() && !ended) {
    pipe.finish(rule, closed_);
    // The gauges' window up to the end of input is observed too (after its batches are applied).
    if (deliver()) observe_gauges(true);
    if (error_.empty() && sender_) {
      if (!o_.state_file.empty()) save_state(sender_->unacknowledged());
      sender_->finish();
      while (error_.empty()) {
        const auto p = sender_->pump(20);
        if (p == loads::BatchSender::Progress::done) break;
        if (p == loads::BatchSender::Progress::failed) error_ = sender_->error();
      }
      if (error_.empty() && !o_.state_file.empty()) save_state(sender_->unacknowledged());
    }
  }
  // Before or after the end of input: the daemon's FAILED reason of the first batch not applied.
  if (sender_ && !sender_->end_of_life().empty()) {
    std::cerr << "peritwin-stream: end of life reached, the rest of the input is not applied: "
              << sender_->end_of_life() << "\n";
  }
  if (!o_.state_file.empty()) stream::write_received(o_.state_file, pipe.counts.samples);
  if (conn_fd_ >= 0) ::close(conn_fd_);
  if (listen_fd_ >= 0) ::close(listen_fd_);
  conn_fd_ = listen_fd_ = -1;
  const auto& rf = pipe.rainflow();
  std::cerr << "peritwin-stream: " << pipe.counts.samples << " samples (" << rf.nonfinite_samples
            << " non-finite, " << pipe.counts.bad_lines << " bad lines), " << rf.reversals
            << " reversals, " << pipe.counts.block_cycles << " cycles in " << pipe.counts.batches
            << " batches, lost_samples " << pipe.counts.lost_samples << "\n";
  if (!error_.empty()) {
    std::cerr << "peritwin-stream: " << error_ << "\n";
    return core::kExitRuntime;
  }
  // Lines came, none of them usable (e.g. "0;4000" or "0,5;4000,0"): the input is no sample
  // stream, which a zero exit would hide.
  if (input_error_.empty() && pipe.counts.bad_lines > 0 &&
      pipe.counts.samples <= rf.nonfinite_samples) {
    input_error_ = input_name() + ": no usable sample in " + std::to_string(pipe.counts.bad_lines) +
                   " skipped lines or samples; the first: " + first_bad_ +
                   " (expected lines t,P or t,P,alpha with '.' decimals)";
  }
  // The summary also after an input error: what was taken before it was delivered.
  std::optional<peritwin_msgs::damage_state_t> final_state;
  if (local_) final_state = local_->state();
  // The daemon's last STATE, a gauge observation's answer included (the sender keeps only
  // those of batches).
  if (sender_) final_state = last_seen_ ? last_seen_ : sender_->last_state();
  if (o_.json && final_state) {
    std::cout << messages::summary_json(*final_state, summary_extra(pipe)) << std::endl;
  }
  if (!input_error_.empty()) {
    std::cerr << "peritwin-stream: " << input_error_ << "\n";
    return core::kExitUsage;
  }
  return core::kExitOk;
}

/// The stream of `o` to its end; the exit code.
int run(Options o) {
  o.replay.lockstep = o.lockstep;
  o.batching.merge_identical = true;
  const auto loaded = replay::load_producer_config(o.config_file, o.in_process);
  if (!loaded.ok()) {
    std::cerr << loaded.error_text();
    return core::kExitUsage;
  }
  const config::DetailConfig* detail = config::select_detail(*loaded.config, o.detail_id);
  if (auto rc = check_options(o, detail)) return *rc;
  // The keys, before anything is read or published: a missing one is a usage error.
  auto auth = loads::load_producer_keys(o.keys, o.source_id);
  if (!auth) {
    std::cerr << "peritwin-stream: " << auth.error().message() << "\n";
    return core::kExitUsage;
  }
  if (o.keys.sign_only) {
    std::cerr << "peritwin-stream: --sign-only: the daemon's STATE and REJECT are not verified\n";
  }
  Input in;
  if (auto rc = open_input(o.input, in)) return *rc;
  // Gauges identify P in N: [detail.sensor] scale and offset (a load sensor's) do not apply.
  config::DetailConfig gauge_detail = *detail;
  if (o.format == "gauges") {
    gauge_detail.sensor.scale = 1.0;
    gauge_detail.sensor.offset = 0.0;
  }
  Stream stream(o, o.format == "gauges" ? gauge_detail : *detail, in);
  if (auto rc = stream.set_up(std::move(*auth))) return *rc;
  stream.loop();
  return stream.finish();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-stream: live load samples -> rainflow -> batches -> the twin"};
  Options o;
  add_options(app, o);
  if (const auto rc = core::parse_options(app, argc, argv)) return *rc;
  return run(std::move(o));
}
