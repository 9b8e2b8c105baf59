#include "twin/service/life_worker.h"

#include <spdlog/spdlog.h>

namespace peritwin::twin {

void log_life_estimate(const std::string& detail_id, const LifeEstimate& e) {
  // Every estimate's cost and the state it started from (issue 18 item 3).
  spdlog::info(
      "[{}] life estimate at state_seq {} (cycle {}): {:.0f} cycles [{:.0f}, {:.0f}] in {:.2f} s "
      "({})",
      detail_id, e.state_seq, e.start_cycles, e.central, e.low, e.high, e.wall_s,
      e.coarse   ? "on the coarser grid of [detail.life] dx"
      : e.forked ? "forked from the live factor"
                 : "rebuilt from the state");
}

LifeWorker::LifeWorker() : thread_([this] { run(); }) {}

LifeWorker::~LifeWorker() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    cancel_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void LifeWorker::submit(LifeJob job) {
  {
    std::lock_guard lock(mutex_);
    pending_ = std::move(job);
  }
  wake_.notify_all();
}

bool LifeWorker::busy() const {
  std::lock_guard lock(mutex_);
  return running_ || pending_.has_value();
}

std::optional<LifeEstimate> LifeWorker::take() {
  std::lock_guard lock(mutex_);
  std::optional<LifeEstimate> out;
  out.swap(done_);
  return out;
}

void LifeWorker::run() {
  while (true) {
    LifeJob job;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || pending_.has_value(); });
      if (stop_) return;
      job = std::move(*pending_);
      pending_.reset();
      running_ = true;
    }
    LifeEstimate e =
        estimate_life(*job.model, job.state, job.spectrum, true, &cancel_, job.engine.get());
    job.engine.reset();  // its factor copy goes before the next job's
    e.state_seq = job.state_seq;
    e.seq = job.seq;
    e.source = job.source;
    if (!cancel_.load()) {
      log_life_estimate(job.model->config().id, e);
    }
    std::lock_guard lock(mutex_);
    running_ = false;
    if (!stop_) done_ = std::move(e);
  }
}

}  // namespace peritwin::twin
