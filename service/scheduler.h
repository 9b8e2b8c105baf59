// The daemon's worker pool (docs/design.md, "Threads of the daemon"). Each detail has a queue: the
// batches received for it by the LCM thread (raw bytes and LCM receive time), in arrival order. A
// detail is on at most one worker at a time, so its batches are applied one after another in that
// order; details with batches waiting take turns, one batch each, so a detail with a long backlog
// or a long re-solve holds one worker and the other details flow on the others. Every
// kWorkerChoresPeriod each idle detail also gets a turn without a batch, for its chores.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace peritwin::service {

/// A batch (or an observation, message set version 9) as LCM delivered it.
struct Received {
  std::vector<std::uint8_t> bytes;
  std::int64_t recv_utime = 0;  ///< LCM's receive time, us since the Unix epoch
  /// From the detail's OBSERVATION channel (observation_t), not its LOAD channel: observations
  /// and batches share the inbox, so the twin takes them in the order they arrived.
  bool observation = false;
};

/// A detail's place in the scheduler, shared between the LCM thread and the workers under `mutex`.
struct DetailQueue {
  std::mutex mutex;
  std::condition_variable idle;  ///< tick(): no longer scheduled
  std::deque<Received> inbox;    ///< received, not yet applied, in arrival order
  /// On the pool's ready queue or in a turn on a worker: never on two workers at once, so its
  /// batches are applied one after another in arrival order.
  bool scheduled = false;
};

class Scheduler {
 public:
  /// One turn of a detail on a worker: the batch to apply (nullptr for a chores-only turn, or
  /// when the daemon has failed), then the detail's chores.
  using Turn = std::function<void(DetailQueue& queue, const Received* batch)>;

  /// `failed`: the daemon's failure flag; once set, workers stop taking turns.
  explicit Scheduler(const std::atomic<bool>& failed) : failed_(failed) {}
  ~Scheduler() { stop(); }
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  /// Before start(): a detail's queue (it must outlive the scheduler's workers).
  void add(DetailQueue& queue) { queues_.push_back(&queue); }
  /// Starts `threads` workers that run `turn` for the details with something to do.
  void start(int threads, Turn turn);
  /// LCM thread: appends a received batch to the detail's inbox and schedules the detail; false
  /// (the batch dropped) when the inbox already holds `capacity` batches.
  bool receive(DetailQueue& queue, Received batch, std::size_t capacity);
  /// Waits until the detail is neither queued nor in a turn (or the daemon failed).
  void wait_idle(DetailQueue& queue);
  /// After a failure: wakes whoever waits on a detail or for work.
  void wake_all();
  /// Lets the workers finish every batch received, then joins them. Idempotent.
  void stop();

 private:
  /// Puts a detail on the ready queue (caller holds queue.mutex and has set queue.scheduled).
  void schedule(DetailQueue& queue);
  void run_worker();
  /// One turn of a detail on a worker: at most one batch, then its chores.
  void run_turn(DetailQueue& queue);
  /// Every kWorkerChoresPeriod: a chores-only turn for each detail that is not scheduled.
  void schedule_chores();
  [[nodiscard]] bool failed() const { return failed_.load(); }

  const std::atomic<bool>& failed_;
  std::vector<DetailQueue*> queues_;
  Turn turn_;
  std::mutex pool_mutex_;  ///< taken after a DetailQueue::mutex, never before
  std::condition_variable pool_wake_;
  std::deque<DetailQueue*> ready_;  ///< details with something to do, each at most once
  std::chrono::steady_clock::time_point next_chores_;
  bool pool_stop_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace peritwin::service
