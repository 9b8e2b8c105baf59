// A background thread that computes remaining-life estimates off the ingest path (the daemon's
// non-deterministic mode): the owner submits LifeJob snapshots, the newest pending job replaces
// an older one that has not started, and finished estimates are collected with take().
#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "twin/model/twin.h"

namespace peritwin::twin {

/// One log line per remaining-life estimate of detail `detail_id`: the state it belongs to, the
/// cycle it started from, the life and band, its wall time and how the simulations started.
void log_life_estimate(const std::string& detail_id, const LifeEstimate& e);

class LifeWorker {
 public:
  LifeWorker();
  ~LifeWorker();  ///< cancels a running estimate and joins
  LifeWorker(const LifeWorker&) = delete;
  LifeWorker& operator=(const LifeWorker&) = delete;

  /// Queues a job (replacing a queued one that has not started).
  void submit(LifeJob job);
  /// True while a job is queued or running.
  [[nodiscard]] bool busy() const;
  /// The newest finished estimate, if one finished since the last call.
  std::optional<LifeEstimate> take();

 private:
  void run();

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::optional<LifeJob> pending_;
  std::optional<LifeEstimate> done_;
  bool running_ = false;
  bool stop_ = false;
  std::atomic<bool> cancel_{false};
  std::thread thread_;
};

}  // namespace peritwin::twin
