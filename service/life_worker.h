// Remaining-life estimates off the ingest path (the daemon's non-deterministic mode). A LifePool
// of a few threads serves every detail of a daemon; each detail has a LifeWorker, its slot in the
// pool: the owner submits LifeJob snapshots, the newest pending job replaces an older one that
// has not started, and finished estimates are collected with take(). The slots with a job wait in
// submission order, so each detail gets its turn; at most `threads` estimates (each with its copy
// of the live engine and factor) exist at once, whatever the number of details.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "twin/twin.h"

namespace peritwin::service {

/// One log line per remaining-life estimate of detail `detail_id`: the state it belongs to, the
/// cycle it started from, the life and band, its wall time and how the simulations started.
void log_life_estimate(const std::string& detail_id, const twin::LifeEstimate& e);

class LifeWorker;

class LifePool {
 public:
  explicit LifePool(int threads);
  ~LifePool();  ///< joins; every LifeWorker of the pool must be gone first
  LifePool(const LifePool&) = delete;
  LifePool& operator=(const LifePool&) = delete;
  [[nodiscard]] int threads() const { return static_cast<int>(threads_.size()); }

 private:
  friend class LifeWorker;
  void run();

  std::mutex mutex_;                  ///< guards the pool and every slot's state
  std::condition_variable wake_;      ///< a slot was queued, or stop
  std::condition_variable finished_;  ///< a slot's estimate ended
  std::deque<LifeWorker*> ready_;     ///< slots with a pending job, oldest first
  bool stop_ = false;
  std::vector<std::thread> threads_;
};

class LifeWorker {
 public:
  explicit LifeWorker(LifePool& pool);
  ~LifeWorker();  ///< cancels its running estimate and waits for it; drops a queued one
  LifeWorker(const LifeWorker&) = delete;
  LifeWorker& operator=(const LifeWorker&) = delete;

  /// Queues a job (replacing a queued one that has not started).
  void submit(twin::LifeJob job);
  /// True while a job is queued or running.
  [[nodiscard]] bool busy() const;
  /// The newest finished estimate, if one finished since the last call.
  std::optional<twin::LifeEstimate> take();

 private:
  friend class LifePool;
  LifePool& pool_;
  // Under pool_.mutex_.
  std::optional<twin::LifeJob> pending_;
  std::optional<twin::LifeEstimate> done_;
  bool queued_ = false;   ///< on pool_.ready_
  bool running_ = false;  ///< a pool thread runs its job
  std::atomic<bool> cancel_{false};
};

}  // namespace peritwin::service
