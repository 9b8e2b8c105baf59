#include "twin/model/life.h"

#include <algorithm>
#include <cmath>
#include <future>

namespace peritwin::twin {

namespace {

bool same_key(const LoadBlock& a, const LoadBlock& b) {
  return a.p_max == b.p_max && a.r == b.r && a.alpha == b.alpha;
}

double load_range(const LoadBlock& b) { return b.p_max * (1 - b.r); }

/// The first break-event cycle (from event e0 on) after which the criterion's crack (the longest,
/// or the longest from [detail.life] crack_origin) reaches `critical`,
/// replaying the events on the bond state before the block; -1 when none does.
std::int64_t crack_length_cycle(const DetailModel& model, const FatigueEngine& engine,
                                std::vector<std::uint8_t> intact, std::size_t e0, double critical) {
  const auto& events = engine.break_events();
  std::vector<double> damage;
  std::size_t e = e0;
  while (e < events.size()) {
    const std::int64_t cycle = events[e].cycle;
    for (; e < events.size() && events[e].cycle == cycle; ++e) {
      intact[static_cast<std::size_t>(events[e].bond)] = 0;
    }
    damage_index(model.disc(), intact, damage);
    if (criterion_crack_length(model, damage, intact) >= critical) return cycle;
  }
  return -1;
}

}  // namespace

void RollingSpectrum::add(const LoadBlock& block) {
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

void RollingSpectrum::assign(std::vector<LoadBlock> blocks) {
  blocks_.assign(blocks.begin(), blocks.end());
  while (blocks_.size() > kCapacity) blocks_.pop_front();
}

std::vector<LoadBlock> RollingSpectrum::reference() const {
  std::vector<LoadBlock> levels;
  for (const auto& b : blocks_) {
    auto it = std::find_if(levels.begin(), levels.end(),
                           [&](const LoadBlock& l) { return same_key(l, b); });
    if (it == levels.end()) {
      levels.push_back(b);
    } else {
      it->count = std::min(it->count, std::numeric_limits<std::int64_t>::max() - b.count) + b.count;
    }
  }
  if (levels.size() <= kMaxLevels) return levels;
  std::stable_sort(levels.begin(), levels.end(), [](const LoadBlock& a, const LoadBlock& b) {
    return load_range(a) < load_range(b);
  });
  double total = 0;
  for (const auto& l : levels) total += static_cast<double>(l.count);
  std::vector<LoadBlock> grouped;
  double done = 0;
  LoadBlock group{};
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const LoadBlock& l = levels[i];
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
      group = LoadBlock{};
    }
  }
  return grouped;
}

std::vector<LoadBlock> reference_spectrum(const DetailModel& model,
                                          const RollingSpectrum& empirical) {
  const LifeConfig& life = model.config().life;
  if (life.empirical_spectrum()) return empirical.reference();
  return life.reference_spectrum;
}

double simulate_life(const DetailModel& model, const EngineState& state,
                     const std::vector<LoadBlock>& spectrum, double a2_factor,
                     const std::atomic<bool>* cancel) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (spectrum.empty()) return nan;
  const auto engine = model.make_engine(a2_factor);
  if (!engine->initialize() || !engine->import_state(state)) return nan;
  const LifeConfig& life = model.config().life;
  const std::int64_t start = engine->total_cycles();
  const auto elapsed = [&](std::int64_t cycle) { return static_cast<double>(cycle - start); };
  if (engine->failed()) return 0.0;
  if (end_of_life(model, *engine, measure_cracks(model, *engine, nullptr)) != Failure::none) {
    return 0.0;
  }
  constexpr std::int64_t kMaxMultiplier = std::int64_t{1} << 40;
  std::int64_t multiplier = 1;
  while (true) {
    bool broke = false;
    for (const LoadBlock& level : spectrum) {
      if (cancel != nullptr && cancel->load(std::memory_order_relaxed)) return nan;
      LoadBlock block = level;
      block.count = level.count > std::numeric_limits<std::int64_t>::max() / multiplier
                        ? std::numeric_limits<std::int64_t>::max() / 2
                        : level.count * multiplier;
      const std::size_t e0 = engine->break_events().size();
      std::vector<std::uint8_t> intact_before;
      if (life.criterion == LifeCriterion::crack_length) intact_before = engine->solver().intact();
      engine->apply(block);
      const auto& events = engine->break_events();
      if (events.size() == e0) {
        if (engine->failed()) return elapsed(engine->total_cycles());
        if (elapsed(engine->total_cycles()) > kMaxSimulatedCycles) {
          return std::numeric_limits<double>::infinity();
        }
        continue;
      }
      broke = true;
      switch (life.criterion) {
        case LifeCriterion::phase3:
          for (std::size_t e = e0; e < events.size(); ++e) {
            if (events[e].cause == BreakCause::overload) return elapsed(events[e].cycle);
          }
          break;
        case LifeCriterion::crack_length: {
          if (engine->failed() ||
              criterion_crack_length(model, engine->node_damage(), engine->solver().intact()) >=
                  life.critical_crack_length) {
            const std::int64_t cycle = crack_length_cycle(model, *engine, std::move(intact_before),
                                                          e0, life.critical_crack_length);
            if (cycle >= 0) return elapsed(cycle);
          }
          break;
        }
        case LifeCriterion::connectivity:
          break;
      }
      if (engine->failed()) return elapsed(engine->total_cycles());
      if (elapsed(engine->total_cycles()) > kMaxSimulatedCycles) {
        return std::numeric_limits<double>::infinity();
      }
    }
    multiplier = broke ? 1 : std::min(multiplier * 2, kMaxMultiplier);
  }
}

LifeEstimate estimate_life(const DetailModel& model, const EngineState& state,
                           const std::vector<LoadBlock>& spectrum, bool parallel,
                           const std::atomic<bool>* cancel) {
  LifeEstimate out;
  const LifeConfig& life = model.config().life;
  const bool band =
      life.band == BandSource::a2_scatter && model.settings().law != peritwin::FatigueLaw::kinetic;
  if (!band) {
    out.central = simulate_life(model, state, spectrum, 1.0, cancel);
    out.low = out.high = out.central;
    return out;
  }
  const double s = life.a2_relative_scatter;
  const auto policy = parallel ? std::launch::async : std::launch::deferred;
  auto low =
      std::async(policy, [&] { return simulate_life(model, state, spectrum, 1 + s, cancel); });
  auto high =
      std::async(policy, [&] { return simulate_life(model, state, spectrum, 1 - s, cancel); });
  out.central = simulate_life(model, state, spectrum, 1.0, cancel);
  const double a = low.get(), b = high.get();
  // Larger A2 damages faster: the low end. Ordered so that low <= central <= high holds even if
  // the crack path makes the relation non-monotone.
  out.low = std::min({a, b, out.central});
  out.high = std::max({a, b, out.central});
  return out;
}

}  // namespace peritwin::twin
