#include "loads/rainflow.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include "loads/state_text.h"

namespace peritwin::loads {

namespace {
constexpr std::string_view kStateTag = "peritwin-rainflow-counter";
constexpr std::uint64_t kStateVersion = 1;
}  // namespace

RainflowCounter::RainflowCounter(double gate) : gate_(gate) {
  if (!std::isfinite(gate) || gate < 0.0) {
    throw std::invalid_argument("RainflowCounter: the gate must be finite and >= 0, got " +
                                std::to_string(gate));
  }
}

void RainflowCounter::read_reversal(Reversal reversal, std::vector<CountedCycle>& out) {
  ++stats_.reversals;
  stack_.push_back(reversal);  // ASTM E1049-85 Sec. 5.4.4 step (1)
  // A cycle between two stack points, with the angle of its peak.
  const auto count = [&](const Reversal& first, const Reversal& second, double n) {
    out.push_back(
        {first.load, second.load, n, first.load > second.load ? first.alpha : second.alpha});
  };
  while (stack_.size() >= 3) {  // step (2)
    const std::size_t k = stack_.size();
    const double x = std::abs(stack_[k - 1].load - stack_[k - 2].load);
    const double y = std::abs(stack_[k - 2].load - stack_[k - 3].load);
    if (x < y) break;  // step (3)
    if (k == 3) {
      // Step (5): Y contains S -> one-half cycle, S moves to Y's second point (the stack holds
      // three points here, so erasing the front is O(1)).
      count(stack_[0], stack_[1], 0.5);
      ++stats_.half_cycles;
      stack_.erase(stack_.begin());
    } else {
      // Step (4): one cycle, both points of Y discarded.
      count(stack_[k - 3], stack_[k - 2], 1.0);
      ++stats_.full_cycles;
      stack_[k - 3] = stack_[k - 1];
      stack_.resize(k - 2);
    }
  }
}

void RainflowCounter::push(double load, double alpha, std::vector<CountedCycle>& out) {
  ++stats_.samples;
  if (!std::isfinite(load) || !std::isfinite(alpha)) {
    ++stats_.nonfinite_samples;
    return;
  }
  if (direction_ > 0) {
    if (load > candidate_.load) {
      candidate_ = {load, alpha};  // still rising (a plateau keeps its first sample)
    } else if (candidate_.load - load > gate_) {
      read_reversal(candidate_, out);  // moved back by more than the gate: a peak
      candidate_ = {load, alpha};
      direction_ = -1;
    }
    return;
  }
  if (direction_ < 0) {
    if (load < candidate_.load) {
      candidate_ = {load, alpha};
    } else if (load - candidate_.load > gate_) {
      read_reversal(candidate_, out);  // a valley
      candidate_ = {load, alpha};
      direction_ = 1;
    }
    return;
  }
  if (!started_) {
    started_ = true;
    read_reversal({load, alpha}, out);  // the starting point S
    return;
  }
  // Only S so far: the first candidate is the first sample beyond the gate from S.
  const double s = stack_.back().load;
  if (load - s > gate_ || s - load > gate_) {
    direction_ = load > s ? 1 : -1;
    candidate_ = {load, alpha};
  }
}

void RainflowCounter::finish(ResidueRule rule, std::vector<CountedCycle>& out) {
  if (rule == ResidueRule::keep) return;
  if (direction_ != 0) read_reversal(candidate_, out);  // the last point of the history
  // Step (6): the residue.
  const double n = rule == ResidueRule::whole ? 1.0 : 0.5;
  for (std::size_t i = 0; i + 1 < stack_.size(); ++i) {
    const Reversal& a = stack_[i];
    const Reversal& b = stack_[i + 1];
    out.push_back({a.load, b.load, n, a.load > b.load ? a.alpha : b.alpha});
    ++(rule == ResidueRule::whole ? stats_.full_cycles : stats_.half_cycles);
  }
  stack_.clear();
  started_ = false;
  direction_ = 0;
  candidate_ = {};
}

std::vector<double> RainflowCounter::residue() const {
  std::vector<double> out;
  out.reserve(stack_.size() + 1);
  for (const Reversal& r : stack_) out.push_back(r.load);
  if (direction_ != 0) out.push_back(candidate_.load);
  return out;
}

// Text: tag version, gate, the five stats, started direction, candidate (load alpha), the stack
// size and its points (load alpha), "end".
std::string RainflowCounter::save() const {
  std::string out(kStateTag);
  state_text::put(out, kStateVersion);
  out += "\ngate";
  state_text::put(out, gate_);
  out += "\nstats";
  for (const std::uint64_t v : {stats_.samples, stats_.nonfinite_samples, stats_.reversals,
                                stats_.full_cycles, stats_.half_cycles}) {
    state_text::put(out, v);
  }
  out += "\nstarted";
  state_text::put(out, std::uint64_t{started_ ? 1u : 0u});
  out += "\ndirection ";
  out += direction_ > 0 ? "up" : direction_ < 0 ? "down" : "none";
  out += "\ncandidate";
  state_text::put(out, candidate_.load);
  state_text::put(out, candidate_.alpha);
  out += "\nstack";
  state_text::put(out, static_cast<std::uint64_t>(stack_.size()));
  for (const Reversal& r : stack_) {
    out += '\n';
    state_text::put(out, r.load);
    state_text::put(out, r.alpha);
  }
  out += "\nend\n";
  return out;
}

core::Expected<RainflowCounter, std::string> RainflowCounter::restore(std::string_view text) {
  state_text::Reader in(text, "rainflow counter state");
  std::uint64_t version = 0, started = 0, size = 0;
  double gate = 0.0;
  RainflowStats stats;
  in.word(kStateTag);
  if (in.count(version, "version") && version != kStateVersion) {
    in.fail("version " + std::to_string(version) + " is not " + std::to_string(kStateVersion));
  }
  in.word("gate");
  if (in.number(gate, "gate") && gate < 0.0) in.fail("the gate must be >= 0");
  in.word("stats");
  in.count(stats.samples, "samples");
  in.count(stats.nonfinite_samples, "nonfinite_samples");
  in.count(stats.reversals, "reversals");
  in.count(stats.full_cycles, "full_cycles");
  in.count(stats.half_cycles, "half_cycles");
  in.word("started");
  if (in.count(started, "started") && started > 1) in.fail("started must be 0 or 1");
  in.word("direction");
  int direction = 0;
  if (const std::string_view word = in.token("direction"); word == "up") {
    direction = 1;
  } else if (word == "down") {
    direction = -1;
  } else if (word != "none") {
    in.fail("direction must be up, down or none");
  }
  Reversal candidate;
  in.word("candidate");
  in.number(candidate.load, "candidate load");
  in.number(candidate.alpha, "candidate alpha");
  in.word("stack");
  in.count(size, "stack size");
  // Each point takes at least two tokens of 4 characters: a size beyond that is a lie.
  if (in.ok() && size > text.size() / 8)
    in.fail("stack size " + std::to_string(size) + " is more than the text holds");
  std::vector<Reversal> stack;
  for (std::uint64_t i = 0; in.ok() && i < size; ++i) {
    Reversal r;
    in.number(r.load, "stack load");
    in.number(r.alpha, "stack alpha");
    stack.push_back(r);
  }
  in.word("end");
  in.end();
  if (!in.ok()) return in.error();

  // The state must be one that push() could have left.
  const std::string what = "rainflow counter state: ";
  if (stats.nonfinite_samples > stats.samples) return what + "more non-finite samples than samples";
  if ((started == 0) != stack.empty())
    return what + "started must be 1 exactly when the stack holds S";
  if (started == 0 && direction != 0) return what + "a direction before the starting point";
  if (direction == 0 && stack.size() > 1)
    return what + "a stack of several points without a candidate";
  if (direction == 0 && (candidate.load != 0.0 || candidate.alpha != 0.0)) {
    return what + "a candidate without a direction";
  }
  for (std::size_t i = 1; i < stack.size(); ++i) {
    const double range = std::abs(stack[i].load - stack[i - 1].load);
    if (!(range > gate))
      return what + "stack point " + std::to_string(i) + " is within the gate of its predecessor";
    if (i >= 2) {
      const double before = std::abs(stack[i - 1].load - stack[i - 2].load);
      if ((stack[i].load - stack[i - 1].load) * (stack[i - 1].load - stack[i - 2].load) >= 0.0) {
        return what + "stack point " + std::to_string(i - 1) + " is no reversal";
      }
      if (!(range < before)) {
        return what + "stack points " + std::to_string(i - 2) + ".." + std::to_string(i) +
               " close a cycle that was not counted (ASTM E1049-85 Sec. 5.4.4 step (3))";
      }
    }
  }
  if (direction != 0) {
    const Reversal& top = stack.back();
    const double away = direction > 0 ? candidate.load - top.load : top.load - candidate.load;
    if (!(away > gate)) return what + "the candidate is not beyond the gate from the last reversal";
    if (stack.size() >= 2 && (top.load - stack[stack.size() - 2].load) * direction > 0.0) {
      return what + "the candidate continues the last range instead of reversing it";
    }
  }
  RainflowCounter counter(gate);
  counter.stats_ = stats;
  counter.started_ = started == 1;
  counter.direction_ = direction;
  if (direction != 0) counter.candidate_ = candidate;
  counter.stack_ = std::move(stack);
  return counter;
}

std::vector<CountedCycle> count_cycles(std::span<const double> loads,
                                       std::span<const double> angles, ResidueRule rule,
                                       double gate) {
  if (!angles.empty() && angles.size() != loads.size()) {
    throw std::invalid_argument("count_cycles: " + std::to_string(angles.size()) + " angles for " +
                                std::to_string(loads.size()) + " loads");
  }
  RainflowCounter counter(gate);
  std::vector<CountedCycle> out;
  for (std::size_t i = 0; i < loads.size(); ++i) {
    counter.push(loads[i], angles.empty() ? 0.0 : angles[i], out);
  }
  counter.finish(rule, out);
  return out;
}

}  // namespace peritwin::loads
