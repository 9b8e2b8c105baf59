#include "loads/cycle_blocks.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "loads/state_text.h"

namespace peritwin::loads {

namespace {
constexpr std::string_view kStateTag = "peritwin-cycle-blocks";
constexpr std::uint64_t kStateVersion = 1;

void check_rules(const BlockRules& rules) {
  if (!std::isfinite(rules.alpha_bin) || rules.alpha_bin < 0.0) {
    throw std::invalid_argument("CycleBlocks: alpha_bin must be finite and >= 0, got " +
                                std::to_string(rules.alpha_bin));
  }
}
}  // namespace

CycleBlocks::CycleBlocks(BlockRules rules) : rules_(rules) { check_rules(rules_); }

void CycleBlocks::add_pending(const Key& key) {
  if (pending_.size() >= kMaxPendingHalves) {  // drop the oldest: its whole cycle went out already
    const auto oldest = pending_by_age_.begin();
    pending_.erase(oldest->second);
    pending_by_age_.erase(oldest);
  }
  pending_.emplace(key, next_serial_);
  pending_by_age_.emplace(next_serial_, key);
  ++next_serial_;
}

void CycleBlocks::add(const CountedCycle& c, std::vector<core::LoadBlock>& out) {
  if (!std::isfinite(c.from) || !std::isfinite(c.to) || !std::isfinite(c.alpha)) {
    throw std::invalid_argument("CycleBlocks::add: non-finite cycle");
  }
  if (c.count != 1.0 && c.count != 0.5) {
    throw std::invalid_argument("CycleBlocks::add: count must be 1 or 0.5, got " +
                                std::to_string(c.count));
  }
  const bool half = c.count == 0.5;
  ++(half ? stats_.half_cycles : stats_.full_cycles);
  const double p_max = std::max(c.from, c.to);
  const double p_min = std::min(c.from, c.to);
  core::LoadBlock block{p_max, 0.0, c.alpha, 1};
  if (p_max == p_min) {
    stats_.skipped.degenerate += c.count;
    return;
  }
  if (p_max > 0.0) {
    block.r = p_min / p_max;
    if (block.r < core::kMinLoadRatio) {
      // Same range dP at R = -10: 000 Eq. (15) drives fatigue by |s(1 - R)| ~ P_max(1 - R) = dP.
      const double range = p_max - p_min;  // overflows only for |loads| near DBL_MAX
      block.p_max = std::isfinite(range)
                        ? range / (1.0 - core::kMinLoadRatio)
                        : p_max / (1.0 - core::kMinLoadRatio) - p_min / (1.0 - core::kMinLoadRatio);
      block.r = core::kMinLoadRatio;
      stats_.skipped.remapped_below_floor += c.count;
    }
  } else if (rules_.compressed_bonds_fatigue) {
    // The tensile mirror: the linear model's response to -P, every bond's |range| unchanged.
    block.p_max = -p_min;
    block.r = p_max / p_min + 0.0;  // + 0.0: -0 (P_max = 0) becomes +0
    stats_.skipped.mirrored_compressive += c.count;
  } else {
    stats_.skipped.compressive += c.count;
    return;
  }
  if (rules_.alpha_bin > 0.0) {
    const double binned = std::round(block.alpha / rules_.alpha_bin) * rules_.alpha_bin + 0.0;
    if (std::isfinite(binned)) block.alpha = binned;  // (a subnormal bin could overflow)
  }
  if (half) {
    const Key key{block.p_max, block.r, block.alpha};
    if (const auto it = pending_.find(key); it != pending_.end()) {
      // Completes the whole cycle emitted earlier for this key.
      pending_by_age_.erase(it->second);
      pending_.erase(it);
      --stats_.rounded_up_half_cycles;
      return;
    }
    add_pending(key);
    ++stats_.rounded_up_half_cycles;
  }
  out.push_back(block);
}

std::vector<core::LoadBlock> CycleBlocks::pending_halves() const {
  std::vector<core::LoadBlock> out;
  out.reserve(pending_by_age_.size());
  for (const auto& [serial, key] : pending_by_age_) {
    out.push_back({std::get<0>(key), std::get<1>(key), std::get<2>(key), 1});
  }
  return out;
}

// Text: tag version, rules (alpha_bin compressed_bonds_fatigue), stats (five counts, four skipped
// amounts), the pending keys oldest first, "end".
std::string CycleBlocks::save() const {
  std::string out(kStateTag);
  state_text::put(out, kStateVersion);
  out += "\nrules";
  state_text::put(out, rules_.alpha_bin);
  state_text::put(out, std::uint64_t{rules_.compressed_bonds_fatigue ? 1u : 0u});
  out += "\nstats";
  for (const std::size_t v : {stats_.reversals, stats_.nonfinite_samples, stats_.full_cycles,
                              stats_.half_cycles, stats_.rounded_up_half_cycles}) {
    state_text::put(out, static_cast<std::uint64_t>(v));
  }
  out += "\nskipped";
  for (const double v : {stats_.skipped.compressive, stats_.skipped.mirrored_compressive,
                         stats_.skipped.remapped_below_floor, stats_.skipped.degenerate}) {
    state_text::put(out, v);
  }
  out += "\npending";
  state_text::put(out, static_cast<std::uint64_t>(pending_by_age_.size()));
  for (const auto& [serial, key] : pending_by_age_) {
    out += '\n';
    state_text::put(out, std::get<0>(key));
    state_text::put(out, std::get<1>(key));
    state_text::put(out, std::get<2>(key));
  }
  out += "\nend\n";
  return out;
}

core::Expected<CycleBlocks, std::string> CycleBlocks::restore(std::string_view text) {
  state_text::Reader in(text, "cycle blocks state");
  std::uint64_t version = 0, compressed = 0, size = 0;
  BlockRules rules;
  in.word(kStateTag);
  if (in.count(version, "version") && version != kStateVersion) {
    in.fail("version " + std::to_string(version) + " is not " + std::to_string(kStateVersion));
  }
  in.word("rules");
  if (in.number(rules.alpha_bin, "alpha_bin") && rules.alpha_bin < 0.0) {
    in.fail("alpha_bin must be >= 0");
  }
  if (in.count(compressed, "compressed_bonds_fatigue") && compressed > 1) {
    in.fail("compressed_bonds_fatigue must be 0 or 1");
  }
  rules.compressed_bonds_fatigue = compressed == 1;
  std::uint64_t counts[5] = {};
  in.word("stats");
  for (auto& v : counts) in.count(v, "count");
  double skipped[4] = {};
  in.word("skipped");
  for (auto& v : skipped) {
    if (in.number(v, "skipped amount") && (v < 0.0 || std::fmod(2.0 * v, 1.0) != 0.0)) {
      in.fail("a skipped amount must be a whole number of half cycles >= 0");
    }
  }
  in.word("pending");
  if (in.count(size, "pending size") && size > kMaxPendingHalves) {
    in.fail("more than " + std::to_string(kMaxPendingHalves) + " pending half cycles");
  }
  std::vector<Key> keys;
  for (std::uint64_t i = 0; in.ok() && i < size; ++i) {
    double p_max = 0, r = 0, alpha = 0;
    in.number(p_max, "pending p_max");
    in.number(r, "pending r");
    in.number(alpha, "pending alpha");
    if (in.ok() && !core::check_load_block({p_max, r, alpha, 1})) {
      in.fail("pending key " + std::to_string(i) + " is no valid load block");
    }
    keys.emplace_back(p_max, r, alpha);
  }
  in.word("end");
  in.end();
  if (!in.ok()) return in.error();
  if (counts[4] < size) {
    return std::string("cycle blocks state: fewer rounded-up half cycles than pending ones");
  }
  CycleBlocks out(rules);
  out.stats_.reversals = counts[0];
  out.stats_.nonfinite_samples = counts[1];
  out.stats_.full_cycles = counts[2];
  out.stats_.half_cycles = counts[3];
  out.stats_.rounded_up_half_cycles = counts[4];
  out.stats_.skipped = {skipped[0], skipped[1], skipped[2], skipped[3]};
  for (const Key& key : keys) {
    if (out.pending_.count(key) != 0) {
      return std::string("cycle blocks state: a pending key appears twice");
    }
    out.add_pending(key);
  }
  return out;
}

}  // namespace peritwin::loads
