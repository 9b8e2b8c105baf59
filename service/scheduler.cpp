#include "service/scheduler.h"

#include <optional>
#include <utility>

namespace peritwin::service {

namespace {

using Clock = std::chrono::steady_clock;

/// Every detail gets a turn at least this often, for its chores (finished life estimates, timed
/// checkpoints, the reject log summary), whether batches come or not.
constexpr auto kWorkerChoresPeriod = std::chrono::milliseconds(100);

}  // namespace

void Scheduler::start(int threads, Turn turn) {
  turn_ = std::move(turn);
  next_chores_ = Clock::now() + kWorkerChoresPeriod;
  for (int k = 0; k < threads; ++k) workers_.emplace_back([this] { run_worker(); });
}

bool Scheduler::receive(DetailQueue& queue, Received batch, std::size_t capacity) {
  std::lock_guard lock(queue.mutex);
  if (queue.inbox.size() >= capacity) return false;
  queue.inbox.push_back(std::move(batch));
  if (!queue.scheduled) {
    queue.scheduled = true;
    schedule(queue);
  }
  return true;
}

void Scheduler::wait_idle(DetailQueue& queue) {
  std::unique_lock lock(queue.mutex);
  queue.idle.wait(lock, [&] { return !queue.scheduled || failed(); });
}

void Scheduler::wake_all() {
  for (DetailQueue* queue : queues_) {
    std::lock_guard lock(queue->mutex);
    queue->idle.notify_all();
  }
  std::lock_guard lock(pool_mutex_);
  pool_wake_.notify_all();
}

void Scheduler::schedule(DetailQueue& queue) {
  std::lock_guard lock(pool_mutex_);
  ready_.push_back(&queue);
  pool_wake_.notify_one();
}

void Scheduler::run_worker() {
  for (;;) {
    DetailQueue* queue = nullptr;
    bool chores_due = false;
    {
      std::unique_lock lock(pool_mutex_);
      pool_wake_.wait_until(lock, next_chores_,
                            [&] { return pool_stop_ || !ready_.empty() || failed(); });
      if (failed()) return;
      if (!ready_.empty()) {
        queue = ready_.front();
        ready_.pop_front();
      } else if (pool_stop_) {
        return;  // every detail's inbox is empty: a detail with batches is always on ready_
      } else if (Clock::now() >= next_chores_) {
        next_chores_ = Clock::now() + kWorkerChoresPeriod;
        chores_due = true;
      }
    }
    if (chores_due) schedule_chores();
    if (queue != nullptr) run_turn(*queue);
  }
}

void Scheduler::schedule_chores() {
  for (DetailQueue* queue : queues_) {
    std::lock_guard lock(queue->mutex);
    if (!queue->scheduled) {
      queue->scheduled = true;
      schedule(*queue);
    }
  }
}

void Scheduler::run_turn(DetailQueue& queue) {
  std::optional<Received> received;
  {
    std::lock_guard lock(queue.mutex);
    if (!queue.inbox.empty()) {
      received = std::move(queue.inbox.front());
      queue.inbox.pop_front();
    }
  }
  turn_(queue, received && !failed() ? &*received : nullptr);
  std::lock_guard lock(queue.mutex);
  if (!queue.inbox.empty() && !failed()) {
    schedule(queue);  // to the back of the queue: details with batches waiting take turns
  } else {
    queue.scheduled = false;
    queue.idle.notify_all();
  }
}

void Scheduler::stop() {
  {
    std::lock_guard lock(pool_mutex_);
    pool_stop_ = true;
  }
  pool_wake_.notify_all();
  for (auto& w : workers_) {
    if (w.joinable()) w.join();
  }
  workers_.clear();
}

}  // namespace peritwin::service
