// The twin service on an LCM instance: one Twin per configured detail, fed by
// PERITWIN_<DETAIL>_LOAD, publishing STATE after every applied batch (and once at start), REJECT
// for every batch not applied, FIELD (throttled, chunked) and STATUS (heartbeat, 1 s).
// Checkpoints: <state_dir>/<id>/checkpoint-<state_seq>.h5, atomically, every
// checkpoint.every_batches applied batches or checkpoint.every_seconds (wall clock; only when the
// state changed) and at stop(); start() resumes from the newest valid one. The three newest are
// kept. Results per detail: see twin/io/detail_outputs.h.
//
// Received batches go into a per-detail inbox (raw bytes + LCM receive time) and are applied in
// order by tick(); poll() first drains every message already waiting on the LCM socket, so STATUS
// can report how many batches wait (pending) and the age of the oldest one (lag_s) — LCM's own
// subscription queue is not observable through its API.
//
// The service runs on the thread that calls poll() (LCM handlers run inside it). It is the
// daemon's core and also runs in-process in tests (memq://) and in the ingest benchmark.
// Modes: deterministic (remaining life synchronously at fixed state_seq points, reproducible) or
// not (a worker thread per detail; estimates are published with the seq they belong to).
#pragma once

#include <chrono>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <vector>

#include "twin/config/config.h"
#include "twin/io/detail_outputs.h"
#include "twin/model/twin.h"
#include "twin/service/life_worker.h"

namespace peritwin::twin {

struct DaemonOptions {
  std::filesystem::path state_dir = "state";
  bool deterministic = false;
  bool results = true;  ///< HDF5/XDMF results and PNGs
  bool checkpoints = true;
  /// LCM subscription queue and the daemon's inbox per detail (messages); LCM's default is 30.
  /// A batch arriving at a full inbox is dropped (counted as an error): the producer sees the gap
  /// and resends.
  int queue_capacity = 100'000;
  double degraded_lag_s = 10.0;  ///< STATUS says "degraded" when the oldest waiting batch is older
  double status_period_s = 1.0;
  bool record_latency = false;  ///< keep receipt -> STATE publish latencies (benchmark)
};

class Daemon {
 public:
  Daemon(lcm::LCM& lcm, TwinConfig config, DaemonOptions options);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  /// Builds every detail's model and twin, resumes from checkpoints, opens results, subscribes,
  /// publishes the initial states; or why not (config-like problems such as an unsupported law
  /// are reported the same way; the caller decides the exit code).
  Status start();
  /// Handles LCM messages for up to `timeout_ms` and does the periodic chores (status, timed
  /// checkpoints, finished life estimates). Returns false after a runtime failure (see error()).
  bool poll(int timeout_ms);
  /// Applies the batches received so far, in order, and does the periodic chores; call it after
  /// lcm.handle() when someone else drives LCM.
  void tick();
  /// Final checkpoints, results and PNGs, a "stopping" status. Idempotent.
  void stop();

  [[nodiscard]] const std::string& error() const { return error_; }
  [[nodiscard]] std::size_t num_details() const { return details_.size(); }
  [[nodiscard]] const Twin& twin(std::size_t i) const;
  [[nodiscard]] const DetailOutputs* outputs(std::size_t i) const;
  /// LCM receive time -> STATE publish latencies (s) of applied batches, when record_latency.
  [[nodiscard]] const std::vector<double>& latencies() const { return latencies_; }
  [[nodiscard]] std::int64_t checkpoints_written() const { return checkpoints_written_; }

 private:
  struct Detail;
  struct Received;
  void on_load(Detail& d, const lcm::ReceiveBuffer* rbuf);
  void apply_received(Detail& d, const Received& r);
  void chores();
  void publish_state(Detail& d);
  void publish_fields(Detail& d);
  void publish_status(Detail& d, const char* health);
  void checkpoint(Detail& d, const char* why);
  void submit_life(Detail& d);
  void fail(std::string why);

  lcm::LCM& lcm_;
  TwinConfig config_;
  DaemonOptions options_;
  std::vector<std::unique_ptr<Detail>> details_;
  std::chrono::steady_clock::time_point started_;
  std::chrono::steady_clock::time_point last_status_;
  std::vector<double> latencies_;
  std::int64_t checkpoints_written_ = 0;
  std::string error_;
  bool stopped_ = false;
};

/// <state_dir>/<detail id>
std::filesystem::path detail_state_dir(const std::filesystem::path& state_dir,
                                       const std::string& detail_id);

}  // namespace peritwin::twin
