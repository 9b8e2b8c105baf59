#include "service/life_worker.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

namespace peritwin::service {

void log_life_estimate(const std::string& detail_id, const twin::LifeEstimate& e) {
  if (std::isnan(e.wall_s)) {  // set at end of life, not simulated (twin::Twin::apply)
    spdlog::info(
        "[{}] end of life at cycle {} (state_seq {}): remaining life 0 cycles, no "
        "estimate simulated",
        detail_id, e.start_cycles, e.state_seq);
    return;
  }
  // Every estimate's cost and the state it started from (issue 18 item 3).
  spdlog::info(
      "[{}] life estimate at state_seq {} (cycle {}): {:.0f} cycles [{:.0f}, {:.0f}] in {:.2f} s "
      "({})",
      detail_id, e.state_seq, e.start_cycles, e.central, e.low, e.high, e.wall_s,
      e.coarse   ? "on the coarser grid of [detail.life] dx"
      : e.forked ? "forked from the live factor"
                 : "rebuilt from the state");
}

LifePool::LifePool(int threads) {
  for (int k = 0; k < std::max(1, threads); ++k) threads_.emplace_back([this] { run(); });
}

LifePool::~LifePool() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (auto& t : threads_) t.join();
}

void LifePool::run() {
  std::unique_lock lock(mutex_);
  while (true) {
    wake_.wait(lock, [this] { return stop_ || !ready_.empty(); });
    if (stop_) return;
    LifeWorker* slot = ready_.front();
    ready_.pop_front();
    slot->queued_ = false;
    twin::LifeJob job = std::move(*slot->pending_);
    slot->pending_.reset();
    slot->running_ = true;
    lock.unlock();
    twin::LifeEstimate e = twin::estimate_life(*job.model, job.state, job.spectrum, true,
                                               &slot->cancel_, job.engine.get());
    job.engine.reset();  // its factor copy goes before the next job's
    e.state_seq = job.state_seq;
    e.seq = job.seq;
    e.source = job.source;
    const bool cancelled = slot->cancel_.load();
    if (!cancelled) log_life_estimate(job.model->config().id, e);
    lock.lock();
    slot->running_ = false;
    if (!cancelled) slot->done_ = std::move(e);
    if (slot->pending_ && !slot->cancel_) {  // submitted while it ran: to the back of the queue
      slot->queued_ = true;
      ready_.push_back(slot);
      wake_.notify_one();
    }
    finished_.notify_all();
  }
}

LifeWorker::LifeWorker(LifePool& pool) : pool_(pool) {}

LifeWorker::~LifeWorker() {
  std::unique_lock lock(pool_.mutex_);
  cancel_ = true;
  if (queued_) {
    pool_.ready_.erase(std::find(pool_.ready_.begin(), pool_.ready_.end(), this));
    queued_ = false;
  }
  pool_.finished_.wait(lock, [this] { return !running_; });
}

void LifeWorker::submit(twin::LifeJob job) {
  {
    std::lock_guard lock(pool_.mutex_);
    pending_ = std::move(job);
    if (queued_ || running_) return;  // it keeps its place; a running one re-queues itself
    queued_ = true;
    pool_.ready_.push_back(this);
  }
  pool_.wake_.notify_one();
}

bool LifeWorker::busy() const {
  std::lock_guard lock(pool_.mutex_);
  return running_ || pending_.has_value();
}

std::optional<twin::LifeEstimate> LifeWorker::take() {
  std::lock_guard lock(pool_.mutex_);
  std::optional<twin::LifeEstimate> out;
  out.swap(done_);
  return out;
}

}  // namespace peritwin::service
