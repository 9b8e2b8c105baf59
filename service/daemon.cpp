#include "service/daemon.h"

#include <poll.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <deque>
#include <map>
#include <optional>
#include <thread>

#include "config/config_toml.h"
#include "config/resources.h"
#include "core/blas_kernel.h"
#include "messages/channels.h"
#include "service/checkpoint_store.h"
#include "service/duplicate_twin.h"
#include "solver/linalg/sparse_cholesky.h"
#include "twin/messages_io.h"

namespace peritwin::service {

namespace {

using Clock = std::chrono::steady_clock;

/// A detail's mesh is published again at most this often, however many requests come.
constexpr double kMeshRepublishS = 1.0;
/// Window of STATUS reject_rate and of the reject log summary.
constexpr double kRejectRateWindowS = 10.0;
constexpr double kRejectLogPeriodS = 1.0;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

const char* verdict_name(messages::Verdict v) {
  switch (v) {
    case messages::Verdict::applied:
      return "applied";
    case messages::Verdict::decode:
      return "decode";
    case messages::Verdict::invalid:
      return "invalid";
    case messages::Verdict::wrong_detail:
      return "wrong detail";
    case messages::Verdict::duplicate:
      return "duplicate";
    case messages::Verdict::gap:
      return "gap";
    case messages::Verdict::failed:
      return "failed";
    case messages::Verdict::internal:
      return "internal";
    case messages::Verdict::auth:
      return "auth";
    case messages::Verdict::limit:
      return "limit";
  }
  return "?";
}

/// The process's resident memory (/proc/self/statm, bytes); 0 when unreadable.
double resident_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0.0;
  unsigned long long size = 0, resident = 0;
  const int n = std::fscanf(f, "%llu %llu", &size, &resident);
  std::fclose(f);
  return n == 2 ? static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE))
                : 0.0;
}

/// A thread count of at least 1 and at most `users` (details, or details with estimates).
int capped_threads(int wanted, std::size_t users) {
  return static_cast<int>(std::clamp<std::size_t>(static_cast<std::size_t>(std::max(1, wanted)), 1,
                                                  std::max<std::size_t>(1, users)));
}

/// DaemonOptions::worker_threads resolved: 0 = the cores (at least 2), never more than details.
int worker_thread_count(int requested, std::size_t details) {
  return capped_threads(default_worker_threads(requested), details);
}

/// DaemonOptions::life_threads resolved: 0 = half the cores (at least 1), never more than the
/// details with estimates.
int life_thread_count(int requested, std::size_t estimating) {
  return capped_threads(default_life_threads(requested), estimating);
}

}  // namespace

int default_worker_threads(int requested) {
  return requested > 0 ? requested
                       : std::max(2, static_cast<int>(std::thread::hardware_concurrency()));
}

int default_life_threads(int requested) {
  return requested > 0 ? requested
                       : std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / 2);
}

std::filesystem::path detail_state_dir(const std::filesystem::path& state_dir,
                                       const std::string& detail_id) {
  return state_dir / detail_id;
}

/// A detail's queue (scheduler.h) with everything its turns work on.
struct Daemon::Detail : DetailQueue {
  // Set up by start(); afterwards only the worker running the detail's turn touches these (one at
  // a time: Detail::scheduled) and stop(), after the workers have been joined.
  Daemon* daemon = nullptr;
  std::unique_ptr<twin::Twin> twin;
  std::unique_ptr<outputs::DetailOutputs> outputs;
  std::unique_ptr<LifeWorker> life;
  lcm::Subscription* subscription = nullptr;
  lcm::Subscription* observation_subscription = nullptr;
  lcm::Subscription* mesh_subscription = nullptr;
  std::string id, state_channel, field_channel, reject_channel, status_channel, mesh_channel;
  // The mesh (immutable): its chunks, published at start and on request by the LCM thread only.
  std::string mesh_hash;
  std::vector<peritwin_msgs::detail_mesh_t> mesh_chunks;
  Clock::time_point mesh_published{};
  std::string mesh_requester;  ///< of a request not answered yet; "" = none
  std::unique_ptr<CheckpointStore> checkpoints;
  Clock::time_point reject_log_window;  ///< start of the current 1-s reject log window
  std::int64_t rejects_unlogged = 0;    ///< rejects in the window after its first one
  std::map<std::string, std::int64_t> unlogged_by_kind;
  double max_batch_seconds = 60.0;
  double max_rejects_per_second = 10.0;
  /// The batch the STATEs answer (damage_state_t.echo_source, echo_nonce): the last one decoded
  /// and authenticated ("" / 0 before any since the start).
  std::string echo_source;
  std::uint64_t echo_nonce = 0;

  // Shared between the LCM thread and the workers, under DetailQueue::mutex.
  std::deque<Clock::time_point> reject_times;  ///< rejects of the last kRejectRateWindowS

  // Written by the worker, read by the heartbeat.
  std::atomic<std::int64_t> busy_since_ns{0};  ///< steady clock; 0 = idle
  std::atomic<std::int64_t> state_seq{0};
  /// Crack events already logged (worker thread only): the largest crack id, the merges.
  std::int32_t logged_crack_id = 0;
  std::size_t logged_merges = 0;
  std::atomic<std::int64_t> errors{0};  ///< rejected (not duplicates), undecodable, dropped
  std::atomic<std::int64_t> auth_rejects{0};
  std::atomic<std::int64_t> duplicates{0};
  std::atomic<std::int64_t> gaps{0};
  std::atomic<bool> failed{false};  ///< final failure reached
  /// A gauge in alarm (twin::GaugeResiduals::alarm): health "degraded" while set.
  std::atomic<bool> gauge_alarm{false};
};

Daemon::Daemon(lcm::LCM& lcm, config::TwinConfig config, DaemonOptions options)
    : lcm_(lcm), config_(std::move(config)), options_(std::move(options)) {}

Daemon::~Daemon() {
  scheduler_.stop();
  for (auto& d : details_) {
    if (d->subscription != nullptr) lcm_.unsubscribe(d->subscription);
    if (d->mesh_subscription != nullptr) lcm_.unsubscribe(d->mesh_subscription);
  }
}

const twin::Twin& Daemon::twin(std::size_t i) const { return *details_.at(i)->twin; }
const outputs::DetailOutputs* Daemon::outputs(std::size_t i) const {
  return details_.at(i)->outputs.get();
}

std::string Daemon::error() const {
  std::lock_guard lock(error_mutex_);
  return error_;
}

void Daemon::fail(std::string why) {
  spdlog::critical("{}", why);
  {
    std::lock_guard lock(error_mutex_);
    if (error_.empty()) error_ = std::move(why);
  }
  failed_.store(true);
  scheduler_.wake_all();
}

core::Status Daemon::start() {
  started_ = last_status_ = Clock::now();
  spdlog::info(
      "BLAS kernel: {} (states are bit-identical on the same kernel; "
      "OPENBLAS_CORETYPE pins it)",
      core::blas_kernel_name());
  if (core::Status keys = ingest_.load_keys(config_.auth); !keys) return keys;
  const std::size_t n = config_.details.size();
  const int threads = worker_thread_count(options_.worker_threads, n);
  if (!options_.deterministic) {
    const auto estimating = static_cast<std::size_t>(
        std::count_if(config_.details.begin(), config_.details.end(),
                      [](const config::DetailConfig& c) { return c.life.estimates(); }));
    if (estimating > 0) {
      life_pool_ = std::make_unique<LifePool>(life_thread_count(options_.life_threads, estimating));
      spdlog::info("remaining-life estimates: {} thread(s) shared by {} detail(s)",
                   life_pool_->threads(), estimating);
    }
  }
  // Build and factor the details `threads` at a time; the first failure in config order is the
  // one reported. With one thread the resident memory's growth over a build is that detail's.
  std::vector<std::optional<core::Expected<std::unique_ptr<Detail>>>> built(n);
  {
    const double resident_before = resident_bytes();
    const auto t0 = Clock::now();
    std::atomic<std::size_t> next{0};
    const auto build_some = [&] {
      for (std::size_t i = next++; i < n; i = next++) {
        try {
          built[i] = build_detail(config_.details[i]);
        } catch (const std::exception& e) {
          built[i] = core::failure("[" + config_.details[i].id + "] " + e.what());
        }
      }
    };
    std::vector<std::thread> builders;
    for (int k = 1; k < threads; ++k) builders.emplace_back(build_some);
    build_some();
    for (auto& b : builders) b.join();
    const double grown = std::max(0.0, resident_bytes() - resident_before);
    spdlog::info(
        "{} detail(s) built in {:.2f} s on {} thread(s): resident memory +{} ({} per detail)", n,
        seconds(Clock::now() - t0), std::min<std::size_t>(threads, n), config::format_bytes(grown),
        config::format_bytes(n > 0 ? grown / static_cast<double>(n) : 0.0));
  }
  for (auto& b : built) {
    if (!*b) return b->error();
    details_.push_back(std::move(**b));
    scheduler_.add(*details_.back());
    if (core::Status s = subscribe_detail(*details_.back()); !s) return s;
  }
  for (auto& d : details_) {
    publish_mesh(*d);
    submit_life(*d);
    publish_state(*d);
    publish_fields(*d);
  }
  flush_outbox();
  heartbeat(true);
  // Several details: the pool spreads them over the cores, so a detail's re-solve keeps to one
  // thread instead of taking the core the other details' batches run on (same arithmetic).
  linalg::SparseCholesky::allow_automatic_two_threads(n <= 1);
  scheduler_.start(threads, [this](DetailQueue& queue, const Received* batch) {
    run_turn(static_cast<Detail&>(queue), batch);
  });
  spdlog::info("{} worker thread(s) apply the batches of {} detail(s){}", threads, n,
               n > 1 ? ", each detail's re-solves on one thread" : "");
  return {};
}

void Daemon::log_crack_events(Detail& d) {
  // New cracks (ids grow in birth order) and joins, once each: what an engineer watching the log
  // wants to hear about. After a restart the ones before it are logged again, once.
  const twin::CrackReport& report = d.twin->cracks();
  // Joins of cracks this log has named; one born and joined within the same batch was never
  // reported on its own and its join is not news.
  for (; d.logged_merges < report.merges.size(); ++d.logged_merges) {
    const crack::CrackMerge& m = report.merges[d.logged_merges];
    if (m.absorbed > d.logged_crack_id) continue;
    spdlog::info("[{}] crack {} joined crack {} at {} cycles", d.id, m.absorbed, m.kept, m.cycle);
  }
  std::int32_t newest = d.logged_crack_id;
  for (const auto& rc : report.cracks) {
    if (rc.crack.id > d.logged_crack_id && rc.crack.nodes > 0) {
      spdlog::info("[{}] crack {} found at {} (started at {} cycles): {:.2f} mm", d.id, rc.crack.id,
                   rc.origin, rc.crack.birth_cycle, 1e3 * rc.crack.length);
      newest = std::max(newest, rc.crack.id);
    }
  }
  d.logged_crack_id = newest;
}

core::Expected<std::unique_ptr<Daemon::Detail>> Daemon::build_detail(
    const config::DetailConfig& config) {
  auto d = std::make_unique<Detail>();
  d->id = config.id;
  d->daemon = this;
  const auto t0 = Clock::now();
  auto built = twin::DetailModel::build(config);
  if (!built) return core::failure(built.error().message());
  const std::shared_ptr<const twin::DetailModel> model = *built;
  const twin::Twin::Options twin_options{
      options_.deterministic ? twin::LifeMode::synchronous : twin::LifeMode::external, true, true};
  auto twin = twin::Twin::create(model, twin_options);
  if (!twin) return core::failure(twin.error().message());
  d->twin = std::move(*twin);
  const linalg::SparseCholesky& factor = d->twin->engine().solver().factor();
  spdlog::info(
      "[{}] model: {} nodes, {} bonds, factor {} entries ({}{}), initial solve in {:.2f} s "
      "(estimated memory {} with its life engines, docs/limits.md)",
      config.id, model->disc().num_nodes(), model->disc().num_bonds(),
      config::config_internal::format_count(factor.factor_nonzeros()),
      config::format_bytes(factor.factor_bytes()),
      factor.has_values() ? ""
                          : ", values released until the next break: [detail.limits] "
                            "release_idle_factor",
      seconds(Clock::now() - t0), config::format_bytes(config::estimate_resources(config).bytes));
  {
    const messages::Mesh mesh = twin::detail_mesh(*model);
    d->mesh_hash = messages::mesh_hash(mesh);
    d->mesh_chunks = messages::mesh_messages(mesh, messages::now_utime());
    spdlog::info("[{}] mesh {}: {} nodes in {} chunk(s), {} line(s) of outline", config.id,
                 d->mesh_hash, mesh.x.size(), d->mesh_chunks.size(), mesh.polylines.size());
  }
  d->max_batch_seconds = config.limits.max_batch_seconds;
  d->max_rejects_per_second = config.limits.max_rejects_per_second;
  if (config.limits.max_p) {
    spdlog::info("[{}] bounds: p_max <= {:.6g} N ([detail.limits] max_p), {} sources", config.id,
                 d->twin->max_p(), config.limits.max_sources);
  } else if (std::isfinite(d->twin->max_p())) {
    spdlog::info(
        "[{}] bounds: p_max <= {:.6g} N (default: {:g} x {:.6g} N, the load at which the virgin "
        "detail's peak bond stretch reaches the critical stretch), {} sources",
        config.id, d->twin->max_p(), twin::kDefaultMaxPOverFirstBreak, d->twin->first_break_load(),
        config.limits.max_sources);
  } else {
    spdlog::warn(
        "[{}] no bound on p_max: the model knows no critical stretch (no K_c, no critical "
        "stretch); set [detail.limits] max_p",
        config.id);
  }
  d->checkpoints = std::make_unique<CheckpointStore>(
      config.id, detail_state_dir(options_.state_dir, config.id), options_.checkpoints);
  if (options_.checkpoints) {
    if (core::Status resumed = d->checkpoints->resume(*d->twin, options_.fresh_start); !resumed) {
      return resumed.error();
    }
    // Before the first STATE: a state dir we cannot write to would lose every batch applied
    // from here on at the next crash.
    if (core::Status writable = d->checkpoints->check_writable(); !writable)
      return writable.error();
  }
  d->reject_log_window = Clock::now();
  d->checkpoints->restart_period(d->reject_log_window);
  if (options_.deterministic) d->twin->catch_up_life();
  if (options_.results) d->outputs = std::make_unique<outputs::DetailOutputs>(*d->twin);
  if (!options_.deterministic && config.life.estimates()) {
    d->life = std::make_unique<LifeWorker>(*life_pool_);
  }
  d->state_channel = messages::channel(config.id, messages::Kind::kState);
  d->field_channel = messages::channel(config.id, messages::Kind::kField);
  d->reject_channel = messages::channel(config.id, messages::Kind::kReject);
  d->status_channel = messages::channel(config.id, messages::Kind::kStatus);
  d->mesh_channel = messages::channel(config.id, messages::Kind::kMesh);
  d->state_seq = d->twin->state_seq();
  d->failed = d->twin->failure() != twin::Failure::none;
  log_crack_events(*d);
  return d;
}

core::Status Daemon::subscribe_detail(Detail& d) {
  Detail* detail = &d;
  const std::string loads = messages::channel(d.id, messages::Kind::kLoad);
  d.subscription = lcm_.subscribeFunction(
      loads,
      +[](const lcm::ReceiveBuffer* rbuf, const std::string&, Detail* target) {
        target->daemon->on_load(*target, rbuf);
      },
      detail);
  if (d.subscription == nullptr) return core::failure("cannot subscribe to " + loads);
  d.subscription->setQueueCapacity(options_.queue_capacity);
  const std::string observations = messages::channel(d.id, messages::Kind::kObservation);
  d.observation_subscription = lcm_.subscribeFunction(
      observations,
      +[](const lcm::ReceiveBuffer* rbuf, const std::string&, Detail* target) {
        target->daemon->on_load(*target, rbuf, true);
      },
      detail);
  if (d.observation_subscription == nullptr) {
    return core::failure("cannot subscribe to " + observations);
  }
  d.observation_subscription->setQueueCapacity(options_.queue_capacity);
  const std::string requests = messages::channel(d.id, messages::Kind::kMeshRequest);
  d.mesh_subscription = lcm_.subscribeFunction(
      requests,
      +[](const lcm::ReceiveBuffer* rbuf, const std::string&, Detail* target) {
        target->daemon->on_mesh_request(*target, rbuf);
      },
      detail);
  if (d.mesh_subscription == nullptr) return core::failure("cannot subscribe to " + requests);
  return {};
}

void Daemon::on_load(Detail& d, const lcm::ReceiveBuffer* rbuf, bool observation) {
  if (failed()) return;
  const auto* data = static_cast<const std::uint8_t*>(rbuf->data);
  if (scheduler_.receive(d, {{data, data + rbuf->data_size}, rbuf->recv_utime, observation},
                         static_cast<std::size_t>(std::max(1, options_.queue_capacity)))) {
    return;
  }
  {
    std::lock_guard lock(d.mutex);
    d.reject_times.push_back(Clock::now());
  }
  ++d.errors;
  spdlog::warn("[{}] inbox full ({} messages): {} of {} bytes is dropped", d.id,
               options_.queue_capacity, observation ? "an observation" : "a batch",
               rbuf->data_size);
}

void Daemon::on_mesh_request(Detail& d, const lcm::ReceiveBuffer* rbuf) {
  const auto request = messages::decode_mesh_request(rbuf->data, rbuf->data_size);
  if (!request || request->detail_id != d.id) {
    spdlog::debug(
        "[{}] a mesh request of {} bytes that does not decode or names another detail "
        "is ignored",
        d.id, rbuf->data_size);
    return;
  }
  d.mesh_requester = request->requester.empty() ? "?" : request->requester;
}

void Daemon::answer_mesh_requests() {
  const auto now = Clock::now();
  for (auto& d : details_) {
    if (d->mesh_requester.empty() || seconds(now - d->mesh_published) < kMeshRepublishS) continue;
    spdlog::info("[{}] mesh requested by {}: published again", d->id, d->mesh_requester);
    d->mesh_requester.clear();
    publish_mesh(*d);
    flush_outbox();
  }
}

void Daemon::publish_mesh(Detail& d) {
  d.mesh_published = Clock::now();
  const std::int64_t utime = messages::now_utime();
  for (auto& m : d.mesh_chunks) {
    m.utime = utime;
    outbox_.push({d.mesh_channel, encode(m), 0});
  }
}

void Daemon::run_turn(Detail& d, const Received* batch) {
  if (batch != nullptr) {
    d.busy_since_ns = now_ns();
    if (options_.before_apply) options_.before_apply(d.id);
    apply_received(d, *batch);
    d.busy_since_ns = 0;
  }
  if (!failed()) worker_chores(d);
}

void Daemon::reject(Detail& d, const Ingested& ingested) {
  const std::string& source = ingested.source;
  const std::int64_t seq = ingested.seq;
  const messages::Outcome& outcome = ingested.outcome;
  if (outcome.verdict != messages::Verdict::duplicate) {
    ++d.errors;
    if (outcome.verdict == messages::Verdict::auth) ++d.auth_rejects;
    const auto now = Clock::now();
    {
      std::lock_guard lock(d.mutex);
      d.reject_times.push_back(now);
    }
    // One line per detail per second: the first reject in full, the rest as a count.
    if (seconds(now - d.reject_log_window) >= kRejectLogPeriodS) {
      log_reject_summary(d);  // of the previous window, if any
      d.reject_log_window = now;
      spdlog::warn("[{}] reject ({}) {}#{}: {}: {}", d.id, verdict_name(outcome.verdict), source,
                   seq, outcome.what, outcome.why);
    } else {
      ++d.rejects_unlogged;
      ++d.unlogged_by_kind[verdict_name(outcome.verdict)];
    }
  } else {
    spdlog::debug("[{}] duplicate: {}", d.id, outcome.why);
  }
  auto m =
      messages::reject_message(d.id, source, seq, outcome, messages::now_utime(), ingested.nonce);
  if (ingest_.daemon_key() != nullptr) messages::sign(m, *ingest_.daemon_key());
  outbox_.push({d.reject_channel, encode(m), 0});
}

void Daemon::apply_received(Detail& d, const Received& r) {
  twin::Twin& twin = *d.twin;
  const Ingested ingested = ingest_.run(twin, r);
  if (ingested.step == Ingested::Step::rejected) {
    reject(d, ingested);
    return;
  }
  // Decoded and authenticated: the STATEs from now on answer this batch's producer run.
  d.echo_source = ingested.source;
  d.echo_nonce = ingested.nonce;
  if (ingested.step == Ingested::Step::threw) {
    // The engine threw half-way through the batch: the model can no longer be trusted. Stop
    // without checkpointing it; a restart resumes from the last checkpoint.
    reject(d, ingested);
    fail("[" + d.id + "] internal error applying seq " + std::to_string(ingested.seq) + " of \"" +
         ingested.source + "\": " + ingested.outcome.why);
    return;
  }
  const messages::Outcome& outcome = ingested.outcome;
  d.duplicates = twin.counters().duplicates;
  d.gaps = twin.counters().gaps;
  if (r.observation) {
    taken_in(d, ingested, r.recv_utime);
    return;
  }
  if (!outcome.applied()) {
    reject(d, ingested);
    // Duplicates and gaps: tell the producer where to resume.
    if (outcome.verdict == messages::Verdict::duplicate ||
        outcome.verdict == messages::Verdict::gap) {
      publish_state(d);
    }
    return;
  }
  d.state_seq = twin.state_seq();
  spdlog::debug("[{}] applied {}#{}: state_seq {}, {} cycles, {} broken bonds", d.id,
                ingested.source, ingested.seq, twin.state_seq(), twin.engine().total_cycles(),
                twin.broken_bonds());
  log_crack_events(d);
  if (options_.deterministic && twin.life().state_seq == twin.state_seq()) {
    // The synchronous estimate of this state (the LifeWorker logs the asynchronous ones).
    log_life_estimate(d.id, twin.life());
  }
  if (twin.failure() != twin::Failure::none) {
    d.failed = true;
    spdlog::warn("[{}] end of life at state_seq {} ({} cycles): {}", d.id, twin.state_seq(),
                 twin.engine().total_cycles(),
                 twin.failure() == twin::Failure::singular ? "final failure (singular stiffness)"
                                                           : "end criterion met");
  }
  // Checkpoint before the STATE, so that the STATE says what is durable (checkpointed_seq).
  const auto every = twin.model().config().checkpoint.every_batches;
  if (every > 0 && twin.state_seq() % every == 0) checkpoint(d, "every_batches");
  publish_state(d, r.recv_utime);
  // FIELD every field_every_batches, and at the end of life (the last state a dashboard's damage
  // map should show: no batch comes after it).
  const auto every_field = twin.model().config().output.field_every_batches;
  if (every_field > 0 &&
      (twin.state_seq() % every_field == 0 || twin.failure() != twin::Failure::none)) {
    publish_fields(d);
  }
  if (d.outputs) d.outputs->record(twin);
  submit_life(d);
}

void Daemon::taken_in(Detail& d, const Ingested& ingested, std::int64_t recv_utime) {
  const twin::Twin& twin = *d.twin;
  if (!ingested.outcome.applied()) {
    reject(d, ingested);
    // A duplicate or a gap: the STATE says the source's last observation seq.
    if (ingested.outcome.verdict == messages::Verdict::duplicate ||
        ingested.outcome.verdict == messages::Verdict::gap) {
      publish_state(d);
    }
    return;
  }
  // Gauges (issue 33): the residual's alarm raised or cleared, named in the log.
  const std::string alarm = twin.gauge_residuals().alarm();
  if (!alarm.empty() && !d.gauge_alarm) {
    spdlog::warn(
        "[{}] health degraded: {} (the structure's compliance is not the model's: a "
        "crack the model does not have, or a gauge fault)",
        d.id, alarm);
  } else if (alarm.empty() && d.gauge_alarm) {
    spdlog::info("[{}] gauge alarm cleared", d.id);
  }
  d.gauge_alarm = !alarm.empty();
  const auto* learned = twin.ensemble();
  if (learned == nullptr || learned->observations().empty() ||
      learned->observations().back().observation.source_id != ingested.source ||
      learned->observations().back().observation.seq != ingested.seq) {
    spdlog::info("[{}] gauge observation {}#{} taken in", d.id, ingested.source, ingested.seq);
    checkpoint(d, "observation");
    publish_state(d, recv_utime);
    if (d.outputs) d.outputs->record(twin);
    return;
  }
  const auto& records = twin.ensemble()->observations();
  const twin::ObservationRecord& rec = records.back();
  const auto estimate = twin.ensemble_estimate();
  const std::size_t mid = estimate ? estimate->end_of_life.size() / 2 : 0;
  spdlog::info(
      "[{}] observation {}#{} at cycle {} taken in ({}): predicted median {:.3g} mm, "
      "log evidence {:.3g}{}; end of life p{:g} {:.0f} cycles",
      d.id, ingested.source, ingested.seq, rec.observation.cycle,
      rec.observation.kind == messages::ObservationKind::crack_length ? "crack length"
      : rec.observation.kind == messages::ObservationKind::no_crack   ? "no crack found"
                                                                      : "gauge compliance",
      rec.update.predicted_median_m * 1e3, rec.update.log_evidence,
      rec.update.resampled ? ", resampled" : "",
      estimate && mid < estimate->percentiles.size() ? estimate->percentiles[mid] : 50.0,
      estimate && mid < estimate->end_of_life.size() ? estimate->end_of_life[mid] : 0.0);
  // Observations are few and cannot be recomputed from the loads: durable before the STATE says
  // they were taken in.
  checkpoint(d, "observation");
  publish_state(d, recv_utime);
  if (d.outputs) d.outputs->record(twin);
}

void Daemon::publish_state(Detail& d, std::int64_t recv_utime) {
  auto m = twin::state_message(*d.twin, messages::now_utime(), d.checkpoints->checkpointed());
  m.echo_source = d.echo_source;
  m.echo_nonce = static_cast<std::int64_t>(d.echo_nonce);
  if (ingest_.daemon_key() != nullptr) messages::sign(m, *ingest_.daemon_key());
  outbox_.push({d.state_channel, encode(m), recv_utime});
}

void Daemon::publish_fields(Detail& d) {
  for (const auto& m : twin::field_messages(*d.twin, messages::now_utime(), d.mesh_hash)) {
    outbox_.push({d.field_channel, encode(m), 0});
  }
}

bool Daemon::publish_status(Detail& d, const char* health) {
  peritwin_msgs::status_t m{};
  m.utime = messages::now_utime();
  m.detail_id = d.id;
  m.health = health;
  m.last_seq = d.state_seq;
  const auto now = Clock::now();
  std::int64_t oldest_utime = 0;
  {
    std::lock_guard lock(d.mutex);
    m.pending = static_cast<std::int32_t>(d.inbox.size());
    if (!d.inbox.empty()) oldest_utime = d.inbox.front().recv_utime;
    while (!d.reject_times.empty() && seconds(now - d.reject_times.front()) > kRejectRateWindowS) {
      d.reject_times.pop_front();
    }
    m.reject_rate = static_cast<double>(d.reject_times.size()) / kRejectRateWindowS;
  }
  m.lag_s = oldest_utime == 0
                ? 0.0
                : std::max(0.0, 1e-6 * static_cast<double>(messages::now_utime() - oldest_utime));
  const std::int64_t busy_since = d.busy_since_ns;
  m.busy_s =
      busy_since == 0 ? 0.0 : std::max(0.0, 1e-9 * static_cast<double>(now_ns() - busy_since));
  m.uptime_s = seconds(now - started_);
  m.errors = d.errors;
  m.duplicates = d.duplicates;
  m.gaps = d.gaps;
  m.auth_rejects = d.auth_rejects;
  const DaemonIdentity& me = DaemonIdentity::self();
  m.host = me.host;
  m.pid = me.pid;
  m.started_utime = me.started_utime;
  if (m.health == "ok") {
    if (d.failed) {
      m.health = "failed";
    } else if (m.busy_s > d.max_batch_seconds || m.reject_rate > d.max_rejects_per_second ||
               m.lag_s > options_.degraded_lag_s || failed() || d.gauge_alarm) {
      m.health = "degraded";
    }
  }
  return lcm_.publish(d.status_channel, &m) == 0;
}

void Daemon::flush_outbox() {
  outbox_.flush(lcm_, options_.record_latency ? &latencies_ : nullptr);
}

void Daemon::heartbeat(bool force) {
  const auto now = Clock::now();
  if (!force && seconds(now - last_status_) < options_.status_period_s) return;
  last_status_ = now;
  for (auto& d : details_) publish_status(*d, "ok");
}

void Daemon::worker_chores(Detail& d) {
  submit_life(d);
  const auto now = Clock::now();
  if (d.checkpoints->due(d.twin->model().config().checkpoint.every_seconds, now)) {
    const std::int64_t before = d.checkpoints->seq();
    checkpoint(d, "every_seconds");
    if (d.checkpoints->seq() != before) publish_state(d);  // checkpointed_seq moved
  }
  if (seconds(now - d.reject_log_window) >= kRejectLogPeriodS) log_reject_summary(d);
}

void Daemon::log_reject_summary(Detail& d) {
  if (d.rejects_unlogged > 0) {
    std::string kinds;
    for (const auto& [kind, n] : d.unlogged_by_kind) {
      kinds += (kinds.empty() ? "" : ", ") + std::to_string(n) + " " + kind;
    }
    spdlog::warn("[{}] {} more reject(s) in the last {:.0f} s ({})", d.id, d.rejects_unlogged,
                 kRejectLogPeriodS, kinds);
    d.rejects_unlogged = 0;
    d.unlogged_by_kind.clear();
  }
}

void Daemon::checkpoint(Detail& d, const char* why) {
  const core::Expected<bool> written = d.checkpoints->write(*d.twin, why);
  if (!written) {
    fail(written.error().message());
  } else if (*written) {
    ++checkpoints_written_;
  }
}

void Daemon::submit_life(Detail& d) {
  if (!d.life) return;
  if (auto e = d.life->take()) {
    d.twin->set_life(*e);  // the LifeWorker logged it when it finished
    publish_state(d);
  }
  if (d.twin->failure() == twin::Failure::none && !d.life->busy() &&
      d.twin->life().state_seq != d.twin->state_seq()) {
    d.life->submit(d.twin->life_job());
  }
}

void Daemon::tick() {
  for (auto& d : details_) scheduler_.wait_idle(*d);
  flush_outbox();
  heartbeat(false);
  answer_mesh_requests();
}

bool Daemon::poll(int timeout_ms) {
  if (failed()) return false;
  flush_outbox();
  heartbeat(false);
  const int lcm_fd = lcm_.getFileno();
  pollfd fds[2] = {{outbox_.wake_fd(), POLLIN, 0}, {lcm_fd, POLLIN, 0}};
  const nfds_t n = lcm_fd >= 0 ? 2 : 1;
  const int ready = ::poll(fds, n, std::max(0, timeout_ms));
  if (ready > 0 && n == 2 && (fds[1].revents & (POLLIN | POLLERR | POLLHUP)) != 0) {
    errno = 0;
    int handled = messages::handle_lcm(lcm_, 0);
    // Take everything already waiting on the socket, so that STATUS can count it.
    for (int k = 0; handled > 0 && k < options_.queue_capacity; ++k)
      handled = messages::handle_lcm(lcm_, 0);
    if (handled < 0 && errno != EINTR) {  // EINTR: a signal, not a failure
      fail("LCM failed while receiving");
      return false;
    }
  }
  flush_outbox();
  heartbeat(false);
  answer_mesh_requests();
  return !failed();
}

void Daemon::stop() {
  if (stopped_) return;
  stopped_ = true;
  scheduler_.stop();  // every batch received is applied first
  for (auto& d : details_) {
    d->life.reset();  // cancels a running estimate
    if (!failed()) {
      const std::int64_t before = d->checkpoints->seq();
      checkpoint(*d, "stop");
      if (d->checkpoints->seq() != before) publish_state(*d);  // now durable
    }
    if (d->outputs) d->outputs->finish(*d->twin);
    spdlog::info(
        "[{}] stopped at state_seq {}: {} cycles, {} broken bonds, crack {:.2f} mm, "
        "state_hash {}",
        d->id, d->twin->state_seq(), d->twin->engine().total_cycles(), d->twin->broken_bonds(),
        1e3 * d->twin->cracks().main_length(), d->twin->state_hash_hex());
  }
  flush_outbox();
  for (auto& d : details_) publish_status(*d, "stopping");
}

}  // namespace peritwin::service
