#include "twin/life.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>

#include "solver/fatigue/law_registry.h"
#include "twin/coarse_life.h"

namespace peritwin::twin {

namespace {

bool same_key(const core::LoadBlock& a, const core::LoadBlock& b) {
  return a.p_max == b.p_max && a.r == b.r && a.alpha == b.alpha;
}

double load_range(const core::LoadBlock& b) { return b.p_max * (1 - b.r); }

}  // namespace

void RollingSpectrum::add(const core::LoadBlock& block) {
  if (!blocks_.empty() && same_key(blocks_.back(), block)) {
    auto& last = blocks_.back();
    last.count = block.count > std::numeric_limits<std::int64_t>::max() - last.count
                     ? std::numeric_limits<std::int64_t>::max()
                     : last.count + block.count;
    return;
  }
  blocks_.push_back(block);
  while (blocks_.size() > kCapacity) blocks_.pop_front();
}

void RollingSpectrum::assign(std::vector<core::LoadBlock> blocks) {
  blocks_.assign(blocks.begin(), blocks.end());
  while (blocks_.size() > kCapacity) blocks_.pop_front();
}

std::vector<core::LoadBlock> RollingSpectrum::reference() const {
  std::vector<core::LoadBlock> levels;
  for (const auto& b : blocks_) {
    auto it = std::find_if(levels.begin(), levels.end(),
                           [&](const core::LoadBlock& l) { return same_key(l, b); });
    if (it == levels.end()) {
      levels.push_back(b);
    } else {
      it->count = std::min(it->count, std::numeric_limits<std::int64_t>::max() - b.count) + b.count;
    }
  }
  if (levels.size() <= kMaxLevels) return levels;
  std::stable_sort(levels.begin(), levels.end(),
                   [](const core::LoadBlock& a, const core::LoadBlock& b) {
                     return load_range(a) < load_range(b);
                   });
  double total = 0;
  for (const auto& l : levels) total += static_cast<double>(l.count);
  std::vector<core::LoadBlock> grouped;
  double done = 0;
  core::LoadBlock group{};
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const core::LoadBlock& l = levels[i];
    if (group.count == 0) {
      group = l;
    } else {
      const std::int64_t count = group.count + l.count;
      group = l;  // sorted by range: the newest member has the largest range
      group.count = count;
    }
    done += static_cast<double>(l.count);
    const double boundary =
        total * static_cast<double>(grouped.size() + 1) / static_cast<double>(kMaxLevels);
    if (done >= boundary || i + 1 == levels.size()) {
      grouped.push_back(group);
      group = core::LoadBlock{};
    }
  }
  return grouped;
}

std::vector<core::LoadBlock> reference_spectrum(const DetailModel& model,
                                                const RollingSpectrum& empirical) {
  const config::LifeConfig& life = model.config().life;
  if (life.empirical_spectrum()) return empirical.reference();
  return life.reference_spectrum;
}

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

bool can_fork(const DetailModel& model) {
  return !peritwin::fatigue::law_entry(model.settings().law).damage_based;
}

double run_to_end(fatigue::FatigueEngine& engine, const std::vector<core::LoadBlock>& spectrum,
                  const fatigue::FatigueEngine::StopCheck& stop, const std::atomic<bool>* cancel,
                  SimulationStats* stats) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (spectrum.empty()) return nan;
  SimulationStats local;
  SimulationStats& st = stats != nullptr ? *stats : local;
  struct Stepping {  // the stepping phase, whichever way it returns
    SimulationStats& st;
    const fatigue::FatigueEngine& engine;
    std::size_t events0;
    int updates0;
    std::chrono::steady_clock::time_point t0;
    ~Stepping() {
      st.stepping_s += seconds_since(t0);
      st.breaks += static_cast<std::int64_t>(engine.break_events().size() - events0);
      st.updates += engine.updates() - updates0;
    }
  } stepping{st, engine, engine.break_events().size(), engine.updates(),
             std::chrono::steady_clock::now()};
  const std::int64_t start = engine.total_cycles();
  const auto elapsed = [&](std::int64_t cycle) { return static_cast<double>(cycle - start); };
  constexpr std::int64_t kMaxMultiplier = std::int64_t{1} << 40;
  std::int64_t multiplier = 1;
  while (true) {
    bool broke = false;
    for (const core::LoadBlock& level : spectrum) {
      if (cancel != nullptr && cancel->load(std::memory_order_relaxed)) return nan;
      core::LoadBlock block = level;
      block.count = level.count > std::numeric_limits<std::int64_t>::max() / multiplier
                        ? std::numeric_limits<std::int64_t>::max() / 2
                        : level.count * multiplier;
      const std::size_t e0 = engine.break_events().size();
      if (engine.apply(block, stop) != fatigue::EngineStatus::ok)
        return elapsed(engine.total_cycles());
      broke = broke || engine.break_events().size() != e0;
      if (elapsed(engine.total_cycles()) > kMaxSimulatedCycles) {
        return std::numeric_limits<double>::infinity();
      }
    }
    multiplier = broke ? 1 : std::min(multiplier * 2, kMaxMultiplier);
  }
}

double simulate_life(const DetailModel& model, const fatigue::EngineState& state,
                     const std::vector<core::LoadBlock>& spectrum, double a2_factor,
                     const std::atomic<bool>* cancel, const fatigue::FatigueEngine* live,
                     SimulationStats* stats) {
  const auto t_start = std::chrono::steady_clock::now();
  SimulationStats local;
  SimulationStats& st = stats != nullptr ? *stats : local;
  st = SimulationStats{};
  struct WallTime {  // the whole call, whichever way it returns
    SimulationStats& st;
    std::chrono::steady_clock::time_point t0;
    ~WallTime() { st.wall_s = seconds_since(t0); }
  } wall{st, t_start};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (spectrum.empty()) return nan;
  std::unique_ptr<fatigue::FatigueEngine> engine;
  if (live != nullptr && can_fork(model)) {
    // Decision (issue 18 item 3): the copy of the live factor replaces a fresh engine's first
    // factorization, periodic rebuild and replay of up to refactor_every_resolves rank updates;
    // fork() reproduces import_state's result bit for bit (tests/twin/test_life.cpp).
    const auto t0 = std::chrono::steady_clock::now();
    engine = live->fork(model.engine_settings(a2_factor));
    st.fork_s = seconds_since(t0);
  } else {
    engine = model.make_engine(a2_factor);
    auto t0 = std::chrono::steady_clock::now();
    const bool ok = engine->initialize();
    st.build_s = seconds_since(t0);
    if (!ok) return nan;
    t0 = std::chrono::steady_clock::now();
    const bool imported = engine->import_state(state);
    st.import_s = seconds_since(t0);
    if (!imported) return nan;
  }
  if (end_of_life(model, *engine) != Failure::none) return 0.0;
  // The engine stops at the exact cycle of the criterion (end_of_life_check); connectivity (and
  // every criterion's singular stiffness) ends in the engine's final failure.
  return run_to_end(*engine, spectrum, end_of_life_check(model), cancel, &st);
}

LifeEstimate estimate_life(const DetailModel& model, const fatigue::EngineState& state,
                           const std::vector<core::LoadBlock>& spectrum, bool parallel,
                           const std::atomic<bool>* cancel, const fatigue::FatigueEngine* live,
                           std::vector<SimulationStats>* stats) {
  if (model.config().life.dx > 0) {
    if (stats != nullptr) stats->clear();
    return estimate_life_coarse(model, model.config().life.dx, state, spectrum, parallel, cancel);
  }
  const auto t0 = std::chrono::steady_clock::now();
  LifeEstimate out;
  out.start_cycles = state.total_cycles;
  out.forked = live != nullptr && can_fork(model);
  const config::LifeConfig& life = model.config().life;
  const bool band = life.band == config::BandSource::a2_scatter &&
                    peritwin::fatigue::law_entry(model.settings().law).scatter_band;
  std::vector<SimulationStats> local(3);
  std::vector<SimulationStats>& st = stats != nullptr ? *stats : local;
  st.assign(band ? 3 : 1, SimulationStats{});
  if (!band) {
    out.central = simulate_life(model, state, spectrum, 1.0, cancel, live, &st[0]);
    out.low = out.high = out.central;
    out.wall_s = seconds_since(t0);
    return out;
  }
  const double s = life.a2_relative_scatter;
  const auto policy = parallel ? std::launch::async : std::launch::deferred;
  auto low = std::async(
      policy, [&] { return simulate_life(model, state, spectrum, 1 + s, cancel, live, &st[1]); });
  auto high = std::async(
      policy, [&] { return simulate_life(model, state, spectrum, 1 - s, cancel, live, &st[2]); });
  out.central = simulate_life(model, state, spectrum, 1.0, cancel, live, &st[0]);
  const double a = low.get(), b = high.get();
  // Larger A2 damages faster: the low end. Ordered so that low <= central <= high holds even if
  // the crack path makes the relation non-monotone.
  out.low = std::min({a, b, out.central});
  out.high = std::max({a, b, out.central});
  out.wall_s = seconds_since(t0);
  return out;
}

}  // namespace peritwin::twin
