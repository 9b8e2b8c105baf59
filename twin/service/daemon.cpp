#include "twin/service/daemon.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <deque>

#include "messages/channels.h"
#include "solver/core/blas_kernel.h"
#include "twin/io/checkpoint_io.h"
#include "twin/lcm/messages_io.h"

namespace peritwin::twin {

namespace {

constexpr std::string_view kCheckpointPrefix = "checkpoint";
constexpr std::size_t kCheckpointsKept = 3;

double seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}
}  // namespace

std::filesystem::path detail_state_dir(const std::filesystem::path& state_dir,
                                       const std::string& detail_id) {
  return state_dir / detail_id;
}

struct Daemon::Received {
  std::vector<std::uint8_t> bytes;
  std::int64_t recv_utime = 0;  ///< LCM's receive time, us since the Unix epoch
};

struct Daemon::Detail {
  Daemon* daemon = nullptr;
  std::unique_ptr<Twin> twin;
  std::unique_ptr<DetailOutputs> outputs;
  std::unique_ptr<LifeWorker> worker;
  lcm::Subscription* subscription = nullptr;
  std::string state_channel, field_channel, reject_channel, status_channel;
  std::filesystem::path state_dir;
  std::int64_t checkpoint_seq = -1;  ///< state_seq of the newest checkpoint on disk
  std::chrono::steady_clock::time_point last_checkpoint;
  std::int64_t errors = 0;     ///< rejected (not duplicates), undecodable and dropped batches
  std::deque<Received> inbox;  ///< received, not yet applied, in arrival order
};

Daemon::Daemon(lcm::LCM& lcm, TwinConfig config, DaemonOptions options)
    : lcm_(lcm), config_(std::move(config)), options_(std::move(options)) {}

Daemon::~Daemon() {
  for (auto& d : details_) {
    if (d->subscription != nullptr) lcm_.unsubscribe(d->subscription);
  }
}

const Twin& Daemon::twin(std::size_t i) const { return *details_.at(i)->twin; }
const DetailOutputs* Daemon::outputs(std::size_t i) const { return details_.at(i)->outputs.get(); }

void Daemon::fail(std::string why) {
  spdlog::critical("{}", why);
  if (error_.empty()) error_ = std::move(why);
}

Status Daemon::start() {
  started_ = last_status_ = std::chrono::steady_clock::now();
  spdlog::info(
      "BLAS kernel: {} (states are bit-identical on the same kernel; "
      "OPENBLAS_CORETYPE pins it)",
      blas_kernel_name());
  const Twin::Options twin_options{
      options_.deterministic ? LifeMode::synchronous : LifeMode::external, true};
  for (const DetailConfig& config : config_.details) {
    auto d = std::make_unique<Detail>();
    const auto t0 = std::chrono::steady_clock::now();
    auto built = DetailModel::build(config);
    if (!built) {
      return failure(built.error().message());
    }
    const std::shared_ptr<const DetailModel> model = *built;
    auto twin = Twin::create(model, twin_options);
    if (!twin) {
      return failure(twin.error().message());
    }
    d->twin = std::move(*twin);
    spdlog::info("[{}] model: {} nodes, {} bonds, initial solve in {:.2f} s", config.id,
                 model->disc().num_nodes(), model->disc().num_bonds(),
                 seconds(std::chrono::steady_clock::now() - t0));
    d->state_dir = detail_state_dir(options_.state_dir, config.id);
    if (options_.checkpoints) {
      std::vector<std::string> skipped;
      auto found = newest_valid_checkpoint(d->state_dir, kCheckpointPrefix, &skipped);
      for (const auto& s : skipped) spdlog::warn("[{}] skipping checkpoint {}", config.id, s);
      if (found) {
        if (const Status restored = d->twin->restore(found->data); !restored) {
          return failure(found->file.path.string() + ": " + restored.error().message());
        }
        d->checkpoint_seq = d->twin->state_seq();
        spdlog::info("[{}] resumed from {}: state_seq {}, {} cycles, state_hash {}", config.id,
                     found->file.path.string(), d->twin->state_seq(),
                     d->twin->engine().total_cycles(), d->twin->state_hash_hex());
        const auto written = found->data.strings.find("blas_kernel");
        if (written != found->data.strings.end() && written->second != blas_kernel_name()) {
          spdlog::warn(
              "[{}] the checkpoint was written on BLAS kernel {}, this process runs {}: the run "
              "goes on correctly, but its states now agree with an uninterrupted run only to "
              "rounding, not bit for bit (set OPENBLAS_CORETYPE={} to match)",
              config.id, written->second, blas_kernel_name(), written->second);
        }
      } else {
        spdlog::info("[{}] no checkpoint in {}: starting from the virgin state", config.id,
                     d->state_dir.string());
      }
    }
    d->last_checkpoint = std::chrono::steady_clock::now();
    if (options_.deterministic) d->twin->catch_up_life();
    if (options_.results) d->outputs = std::make_unique<DetailOutputs>(*d->twin);
    if (!options_.deterministic && config.life.every_batches > 0) {
      d->worker = std::make_unique<LifeWorker>();
    }
    d->state_channel = messages::channel(config.id, messages::Kind::kState);
    d->field_channel = messages::channel(config.id, messages::Kind::kField);
    d->reject_channel = messages::channel(config.id, messages::Kind::kReject);
    d->status_channel = messages::channel(config.id, messages::Kind::kStatus);
    d->daemon = this;
    d->subscription = lcm_.subscribeFunction(
        messages::channel(config.id, messages::Kind::kLoad),
        +[](const lcm::ReceiveBuffer* rbuf, const std::string&, Detail* detail) {
          detail->daemon->on_load(*detail, rbuf);
        },
        d.get());
    if (d->subscription == nullptr) {
      return failure("cannot subscribe to " + messages::channel(config.id, messages::Kind::kLoad));
    }
    d->subscription->setQueueCapacity(options_.queue_capacity);
    details_.push_back(std::move(d));
  }
  for (auto& d : details_) {
    submit_life(*d);
    publish_state(*d);
    publish_fields(*d);
    publish_status(*d, "ok");
  }
  return {};
}

void Daemon::on_load(Detail& d, const lcm::ReceiveBuffer* rbuf) {
  if (!error_.empty()) return;
  if (d.inbox.size() >= static_cast<std::size_t>(std::max(1, options_.queue_capacity))) {
    ++d.errors;
    spdlog::warn("[{}] inbox full ({} batches): a batch of {} bytes is dropped",
                 d.twin->detail_id(), d.inbox.size(), rbuf->data_size);
    return;
  }
  const auto* data = static_cast<const std::uint8_t*>(rbuf->data);
  d.inbox.push_back({{data, data + rbuf->data_size}, rbuf->recv_utime});
}

void Daemon::apply_received(Detail& d, const Received& r) {
  Twin& twin = *d.twin;
  const Decoded decoded = decode_batch(r.bytes.data(), r.bytes.size());
  if (!decoded.batch) {
    ++d.errors;
    spdlog::warn("[{}] reject (decode): {}", twin.detail_id(), decoded.error.why);
    const auto m = reject_message(twin.detail_id(), "", -1, decoded.error, now_utime());
    lcm_.publish(d.reject_channel, &m);
    return;
  }
  const Batch& batch = *decoded.batch;
  Outcome outcome;
  try {
    outcome = twin.apply(batch);
  } catch (const std::exception& e) {
    // The engine threw half-way through the batch: the model can no longer be trusted. Stop
    // without checkpointing it; a restart resumes from the last checkpoint.
    outcome = {Verdict::internal, "message", e.what()};
    const auto m =
        reject_message(twin.detail_id(), batch.source_id, batch.seq, outcome, now_utime());
    lcm_.publish(d.reject_channel, &m);
    fail("[" + twin.detail_id() + "] internal error applying seq " + std::to_string(batch.seq) +
         " of \"" + batch.source_id + "\": " + e.what());
    return;
  }
  if (!outcome.applied()) {
    if (outcome.verdict == Verdict::duplicate) {
      spdlog::debug("[{}] duplicate: {}", twin.detail_id(), outcome.why);
    } else {
      ++d.errors;
      spdlog::warn("[{}] reject ({}): {}", twin.detail_id(), outcome.what, outcome.why);
    }
    const auto m =
        reject_message(twin.detail_id(), batch.source_id, batch.seq, outcome, now_utime());
    lcm_.publish(d.reject_channel, &m);
    // Duplicates and gaps: tell the producer where to resume.
    if (outcome.verdict == Verdict::duplicate || outcome.verdict == Verdict::gap) {
      publish_state(d);
    }
    return;
  }
  publish_state(d);
  if (options_.record_latency) {
    // From LCM's receive time (wall clock, us): includes the wait in the inbox.
    latencies_.push_back(1e-6 * static_cast<double>(now_utime() - r.recv_utime));
  }
  spdlog::debug("[{}] applied {}#{}: state_seq {}, {} cycles, {} broken bonds", twin.detail_id(),
                batch.source_id, batch.seq, twin.state_seq(), twin.engine().total_cycles(),
                twin.broken_bonds());
  if (twin.failure() != Failure::none) {
    spdlog::warn("[{}] end of life at state_seq {} ({} cycles): {}", twin.detail_id(),
                 twin.state_seq(), twin.engine().total_cycles(),
                 twin.failure() == Failure::singular ? "final failure (singular stiffness)"
                                                     : "end criterion met");
  }
  const auto every_field = twin.model().config().output.field_every_batches;
  if (every_field > 0 && twin.state_seq() % every_field == 0) publish_fields(d);
  if (d.outputs) d.outputs->record(twin);
  const auto every = twin.model().config().checkpoint.every_batches;
  if (every > 0 && twin.state_seq() % every == 0) checkpoint(d, "every_batches");
  submit_life(d);
}

void Daemon::publish_state(Detail& d) {
  const auto m = state_message(*d.twin, now_utime());
  lcm_.publish(d.state_channel, &m);
}

void Daemon::publish_fields(Detail& d) {
  for (const auto& m : field_messages(*d.twin, now_utime())) lcm_.publish(d.field_channel, &m);
}

void Daemon::publish_status(Detail& d, const char* health) {
  peritwin_msgs::status_t m{};
  m.utime = now_utime();
  m.detail_id = d.twin->detail_id();
  m.health =
      d.twin->failure() != Failure::none && std::string_view(health) == "ok" ? "failed" : health;
  m.last_seq = d.twin->state_seq();
  m.pending = static_cast<std::int32_t>(d.inbox.size());
  m.lag_s =
      d.inbox.empty()
          ? 0.0
          : std::max(0.0, 1e-6 * static_cast<double>(now_utime() - d.inbox.front().recv_utime));
  if (m.lag_s > options_.degraded_lag_s && m.health == "ok") m.health = "degraded";
  m.uptime_s = seconds(std::chrono::steady_clock::now() - started_);
  m.errors = d.errors;
  m.duplicates = d.twin->counters().duplicates;
  m.gaps = d.twin->counters().gaps;
  lcm_.publish(d.status_channel, &m);
}

void Daemon::checkpoint(Detail& d, const char* why) {
  d.last_checkpoint = std::chrono::steady_clock::now();
  if (!options_.checkpoints || d.checkpoint_seq == d.twin->state_seq()) return;
  const auto path = checkpoint_path(d.state_dir, kCheckpointPrefix,
                                    static_cast<std::uint64_t>(d.twin->state_seq()));
  try {
    const auto t0 = std::chrono::steady_clock::now();
    std::filesystem::create_directories(d.state_dir);
    write_checkpoint(path, d.twin->to_checkpoint());
    prune_checkpoints(d.state_dir, kCheckpointPrefix, kCheckpointsKept);
    d.checkpoint_seq = d.twin->state_seq();
    ++checkpoints_written_;
    spdlog::info("[{}] checkpoint ({}): {} in {:.3f} s", d.twin->detail_id(), why, path.string(),
                 seconds(std::chrono::steady_clock::now() - t0));
  } catch (const std::exception& e) {
    fail("[" + d.twin->detail_id() + "] cannot write checkpoint " + path.string() + ": " +
         e.what());
  }
}

void Daemon::submit_life(Detail& d) {
  if (!d.worker) return;
  if (auto e = d.worker->take()) {
    d.twin->set_life(*e);
    spdlog::info("[{}] remaining life at state_seq {}: {:.0f} cycles [{:.0f}, {:.0f}]",
                 d.twin->detail_id(), e->state_seq, e->central, e->low, e->high);
    publish_state(d);
  }
  if (d.twin->failure() == Failure::none && !d.worker->busy() &&
      d.twin->life().state_seq != d.twin->state_seq()) {
    d.worker->submit(d.twin->life_job());
  }
}

void Daemon::tick() {
  for (auto& d : details_) {
    while (!d->inbox.empty() && error_.empty()) {
      const Received r = std::move(d->inbox.front());
      d->inbox.pop_front();
      apply_received(*d, r);
      chores();  // a heartbeat is due even while a backlog is being worked off
    }
  }
  chores();
}

void Daemon::chores() {
  const auto now = std::chrono::steady_clock::now();
  const bool status_due = seconds(now - last_status_) >= options_.status_period_s;
  if (status_due) last_status_ = now;
  for (auto& d : details_) {
    submit_life(*d);
    const double every = d->twin->model().config().checkpoint.every_seconds;
    if (every > 0 && seconds(now - d->last_checkpoint) >= every) checkpoint(*d, "every_seconds");
    if (status_due) publish_status(*d, error_.empty() ? "ok" : "degraded");
  }
}

bool Daemon::poll(int timeout_ms) {
  if (!error_.empty()) return false;
  errno = 0;
  int handled = handle_lcm(lcm_, timeout_ms);
  // Take everything already waiting on the socket, so that STATUS can count it.
  for (int n = 0; handled > 0 && n < options_.queue_capacity; ++n) handled = handle_lcm(lcm_, 0);
  if (handled < 0 && errno != EINTR) {  // EINTR: a signal, not a failure
    fail("LCM failed while receiving");
    return false;
  }
  tick();
  return error_.empty();
}

void Daemon::stop() {
  if (stopped_) return;
  stopped_ = true;
  for (auto& d : details_) {
    d->worker.reset();  // cancels a running estimate
    if (error_.empty()) checkpoint(*d, "stop");
    if (d->outputs) d->outputs->finish(*d->twin);
    publish_status(*d, "stopping");
    spdlog::info(
        "[{}] stopped at state_seq {}: {} cycles, {} broken bonds, crack {:.2f} mm, "
        "state_hash {}",
        d->twin->detail_id(), d->twin->state_seq(), d->twin->engine().total_cycles(),
        d->twin->broken_bonds(), 1e3 * d->twin->cracks().main_length(), d->twin->state_hash_hex());
  }
}

}  // namespace peritwin::twin
