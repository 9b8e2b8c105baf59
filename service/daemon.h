// The twin service on an LCM instance: one Twin per configured detail, fed by
// PERITWIN_<DETAIL>_LOAD, publishing STATE after every applied batch (and once at start), REJECT
// for every batch not applied, FIELD (throttled, chunked) and STATUS (heartbeat, 1 s), and MESH
// (the discretization, chunked) at start and whenever asked on PERITWIN_<DETAIL>_MESH_REQUEST (at
// most once a second per detail; the requests in between are answered by that publication).
// Checkpoints: <state_dir>/<id>/checkpoint-<state_seq>.h5, atomically, every
// checkpoint.every_batches applied batches or checkpoint.every_seconds (wall clock; only when the
// state changed) and at stop(); start() resumes from the newest valid one whose content matches
// its name (detail, model, state_seq), and refuses to start when checkpoints exist and none is
// valid (unless fresh_start). The three newest are kept. Results per detail: see
// outputs/detail_outputs.h.
//
// Authentication ([auth] in the config; messages/README.md, "Authentication"): every batch must
// come from an allowed source with that source's HMAC-SHA256 tag, else REJECT CODE_AUTH (model
// untouched, counted in STATUS auth_rejects); STATE and REJECT are signed with [auth] daemon_key.
// Without [auth] the daemon runs unauthenticated and says so once at start.
//
// Threads (docs/design.md, "Threads of the daemon"):
//  * the LCM thread — whoever calls poll() or tick() — is the only one that touches LCM: it
//    receives batches into the per-detail inboxes (raw bytes + LCM receive time), publishes what
//    the detail workers queued in the outbox, and publishes STATUS from its own timer, whatever
//    the workers are doing;
//  * a pool of worker threads (DaemonOptions::worker_threads, default: the cores, at least two,
//    at most one per detail) applies the details' batches. A detail is on at most one worker at a
//    time and its batches are applied in arrival order (decode, authenticate, apply, STATE/REJECT,
//    results, checkpoints, remaining-life hand-over); details with batches waiting take turns,
//    one batch each, so a detail with a long backlog or a long re-solve holds one worker and the
//    other details flow on the others. STATUS says how long the current batch has been running
//    (busy_s) and turns "degraded" past [detail.limits] max_batch_seconds;
//  * start() builds and factors the details on that many threads at once.
// Each detail's state is a pure function of its config and the batches in its arrival order:
// threads change when a state is published, never what it is.
//
// The parts, each in its own file: ingest.h (decode, authenticate, apply one batch), outbox.h
// (what the workers queue for the LCM thread to publish), checkpoint_store.h (a detail's
// checkpoints: resume, write, rotation), scheduler.h (the worker threads and the per-detail
// inboxes). This class composes them per detail with the twin, its results and its life worker,
// and publishes STATUS and MESH from the LCM thread.
//
// The service is the daemon's core and also runs in-process in tests (memq://) and in the ingest
// benchmark. Modes: deterministic (remaining life synchronously at fixed state_seq points,
// reproducible) or not (a LifePool of DaemonOptions::life_threads threads shared by the details,
// one LifeWorker slot each; estimates are published with the seq they belong to).
#pragma once

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "config/config.h"
#include "outputs/detail_outputs.h"
#include "service/ingest.h"
#include "service/life_worker.h"
#include "service/outbox.h"
#include "service/scheduler.h"
#include "twin/twin.h"

namespace peritwin::service {

struct DaemonOptions {
  std::filesystem::path state_dir = "state";
  bool deterministic = false;
  bool results = true;  ///< HDF5/XDMF results and PNGs
  bool checkpoints = true;
  /// Start from the virgin state even when every checkpoint on disk is invalid (they are left
  /// where they are; the first new checkpoint prunes them by seq).
  bool fresh_start = false;
  /// LCM subscription queue and the daemon's inbox per detail (messages); LCM's default is 30.
  /// A batch arriving at a full inbox is dropped (counted as an error): the producer sees the gap
  /// and resends.
  int queue_capacity = 100'000;
  double degraded_lag_s = 10.0;  ///< STATUS says "degraded" when the oldest waiting batch is older
  double status_period_s = 1.0;
  bool record_latency = false;  ///< keep receipt -> STATE publish latencies (benchmark)
  /// Threads that apply the details' batches (and build them at start): 0 = the machine's cores,
  /// at least 2; never more than there are details. With 1, a detail's long batch delays every
  /// other detail's (the fleet benchmark's comparison).
  int worker_threads = 0;
  /// Threads that compute the remaining-life estimates of every detail (non-deterministic mode):
  /// 0 = half the machine's cores, at least 1; never more than the details with estimates. Each
  /// running estimate holds a copy of its detail's engine and factor, so this also bounds them.
  int life_threads = 0;
  /// Test hook: called on a detail's worker thread before each received batch is applied.
  std::function<void(const std::string& detail_id)> before_apply;
};

/// DaemonOptions::worker_threads and life_threads as given (0 = the default) resolved to a
/// count, before the cap by the number of details: the cores (at least 2) and half the cores
/// (at least 1).
[[nodiscard]] int default_worker_threads(int requested);
[[nodiscard]] int default_life_threads(int requested);

class Daemon {
 public:
  Daemon(lcm::LCM& lcm, config::TwinConfig config, DaemonOptions options);
  ~Daemon();  ///< stops the workers (without the final checkpoint: call stop() for that)
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  /// Builds every detail's model and twin, resumes from checkpoints, checks that the state dir is
  /// writable, opens results, subscribes, publishes the initial states and starts the workers;
  /// or why not (the caller decides the exit code).
  core::Status start();
  /// Handles LCM messages for up to `timeout_ms`, publishes what the workers queued, and the
  /// heartbeat when due. Returns quickly whatever the workers do. False after a runtime failure
  /// (see error()).
  bool poll(int timeout_ms);
  /// Waits until every batch received so far is applied and published (and the heartbeat when
  /// due); for callers that drive LCM themselves (lcm.handle(), then tick()).
  void tick();
  /// Applies what was received, then final checkpoints, results and PNGs, a "stopping" status.
  /// Idempotent.
  void stop();

  [[nodiscard]] std::string error() const;
  [[nodiscard]] std::size_t num_details() const { return details_.size(); }
  /// The twin of detail i; read it only while its worker is idle (after tick() or stop()).
  [[nodiscard]] const twin::Twin& twin(std::size_t i) const;
  [[nodiscard]] const outputs::DetailOutputs* outputs(std::size_t i) const;
  /// LCM receive time -> STATE publish latencies (s) of applied batches, when record_latency.
  [[nodiscard]] const std::vector<double>& latencies() const { return latencies_; }
  [[nodiscard]] std::int64_t checkpoints_written() const { return checkpoints_written_.load(); }

 private:
  struct Detail;
  /// The detail's model, twin, checkpoint and results (no LCM): runs on a start-up thread.
  core::Expected<std::unique_ptr<Detail>> build_detail(const config::DetailConfig& config);
  /// LCM thread: the detail's channels and subscriptions.
  core::Status subscribe_detail(Detail& d);
  void on_load(Detail& d, const lcm::ReceiveBuffer* rbuf, bool observation = false);
  /// LCM thread: a mesh_request_t for this detail marks its mesh to be published again.
  void on_mesh_request(Detail& d, const lcm::ReceiveBuffer* rbuf);
  /// LCM thread: publishes the meshes asked for, once kMeshRepublishS has passed since the last.
  void answer_mesh_requests();
  void publish_mesh(Detail& d);
  /// One turn of a detail on a worker (Scheduler::Turn): the batch if any, then its chores.
  void run_turn(Detail& d, const Received* batch);
  void apply_received(Detail& d, const Received& r);
  /// After an observation's ingest: REJECT, or log, checkpoint, STATE and results.
  void taken_in(Detail& d, const Ingested& ingested, std::int64_t recv_utime);
  /// REJECT of a batch not applied (its source, seq and nonce echoed), counted and logged.
  void reject(Detail& d, const Ingested& ingested);
  void worker_chores(Detail& d);
  void log_reject_summary(Detail& d);
  void publish_state(Detail& d, std::int64_t recv_utime = 0);
  void publish_fields(Detail& d);
  bool publish_status(Detail& d, const char* health);
  void flush_outbox();
  void heartbeat(bool force);
  void checkpoint(Detail& d, const char* why);
  void submit_life(Detail& d);
  /// Logs the cracks found and joined since the last call (one line each).
  static void log_crack_events(Detail& d);
  void fail(std::string why);
  [[nodiscard]] bool failed() const { return failed_.load(); }

  lcm::LCM& lcm_;
  config::TwinConfig config_;
  DaemonOptions options_;
  std::atomic<bool> failed_{false};
  /// Before details_: their LifeWorkers are destroyed (cancelled) before the pool.
  std::unique_ptr<LifePool> life_pool_;
  std::vector<std::unique_ptr<Detail>> details_;
  Ingest ingest_;
  Outbox outbox_;
  Scheduler scheduler_{failed_};
  std::chrono::steady_clock::time_point started_;
  std::chrono::steady_clock::time_point last_status_;
  std::vector<double> latencies_;
  std::atomic<std::int64_t> checkpoints_written_{0};
  mutable std::mutex error_mutex_;
  std::string error_;
  bool stopped_ = false;
};

/// <state_dir>/<detail id>
std::filesystem::path detail_state_dir(const std::filesystem::path& state_dir,
                                       const std::string& detail_id);

}  // namespace peritwin::service
