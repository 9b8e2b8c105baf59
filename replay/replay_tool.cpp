#include "replay/replay_tool.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <set>

#include "loads/lcm_log.h"
#include "messages/channels.h"
#include "messages/transport.h"

namespace peritwin::replay {

core::Expected<HistoryBlocks> read_history(const std::filesystem::path& file, InputFormat format,
                                           const std::string& detail_id,
                                           const loads::SeriesRules& series_rules) {
  HistoryBlocks out;
  if (format != InputFormat::lcm_log) {
    const loads::HistoryFormat f = format == InputFormat::series   ? loads::HistoryFormat::series
                                   : format == InputFormat::cycles ? loads::HistoryFormat::cycles
                                                                   : loads::HistoryFormat::spectrum;
    const auto read = loads::read_blocks(file, f, series_rules);
    if (!read.ok()) return core::failure(read.error().message());
    out.blocks = read.value().blocks;
    if (format == InputFormat::series) {
      const auto& s = read.value().stats;
      out.conversion = s;
      out.note = "rainflow: " + std::to_string(s.reversals) + " reversals, " +
                 std::to_string(s.full_cycles) + " full and " + std::to_string(s.half_cycles) +
                 " half cycles, " + std::to_string(s.rounded_up_half_cycles) +
                 " unpaired halves rounded up";
    }
    return out;
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) return core::failure(file.string() + ": cannot open file");
  return read_lcm_log(in, file.string(), detail_id);
}

core::Expected<HistoryBlocks> read_lcm_log(std::istream& in, const std::string& name,
                                           const std::string& detail_id) {
  HistoryBlocks out;
  const std::string channel = messages::channel(detail_id, messages::Kind::kLoad);
  std::set<std::pair<std::string, std::int64_t>> seen;
  std::int64_t skipped = 0;
  const auto scan = loads::scan_lcm_log(
      in, name, channel, messages::kMaxBatchPayload, [&](std::span<const std::uint8_t> data) {
        const auto decoded = messages::decode_batch(data.data(), data.size());
        if (!decoded.batch || decoded.batch->detail_id != detail_id ||
            !seen.insert({decoded.batch->source_id, decoded.batch->seq}).second) {
          ++skipped;
          return;
        }
        for (const auto& b : decoded.batch->blocks) {
          out.blocks.push_back(b);
        }
      });
  if (!scan) return scan.error();
  skipped += scan.value().oversized;
  out.note = "LCM log: " + std::to_string(scan.value().on_channel) + " events on " + channel +
             ", " + std::to_string(skipped) + " skipped (undecodable, other detail or duplicate)";
  if (out.blocks.empty()) return core::failure(name + ": no load blocks on " + channel);
  return out;
}

std::vector<std::pair<std::string, double>> skipped_cycles(const loads::ConversionStats& stats) {
  return {{"compressive", stats.skipped.compressive},
          {"mirrored_compressive", stats.skipped.mirrored_compressive},
          {"remapped_below_floor", stats.skipped.remapped_below_floor},
          {"degenerate", stats.skipped.degenerate},
          {"nonfinite_samples", static_cast<double>(stats.nonfinite_samples)}};
}

std::string describe_skipped(const loads::ConversionStats& stats) {
  std::string out = "skipped cycles:";
  const char* separator = " ";
  for (const auto& [name, value] : skipped_cycles(stats)) {
    char number[32];
    std::snprintf(number, sizeof number, "%g", value);
    out += separator + name + " " + number;
    separator = ", ";
  }
  return out;
}

core::Status check_blocks(std::span<const core::LoadBlock> blocks) {
  return core::check_load_blocks(blocks, std::numeric_limits<std::int64_t>::max());
}

core::Status check_peak(std::span<const core::LoadBlock> blocks,
                        const config::LimitsConfig& limits) {
  if (!limits.max_p) return {};
  const double max_p = *limits.max_p;
  std::size_t first = blocks.size();
  double peak = 0.0;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    peak = std::max(peak, blocks[i].p_max);
    if (first == blocks.size() && blocks[i].p_max > max_p) first = i;
  }
  if (first == blocks.size()) return {};
  char text[200];
  std::snprintf(text, sizeof text,
                "p_max = %g N is above the detail's [detail.limits] max_p = %g N (the history's "
                "peak is %g N, %.3g x max_p: a load in the wrong unit?)",
                blocks[first].p_max, max_p, peak, peak / max_p);
  return core::Error{"blocks[" + std::to_string(first) + "].p_max", text};
}

LcmReplayer::LcmReplayer(lcm::LCM& lcm, std::vector<messages::Batch> batches,
                         loads::ReplayOptions options, loads::ReplayAuth auth)
    : sender_(lcm, batches.empty() ? std::string() : batches.front().detail_id,
              batches.empty() ? std::string() : batches.front().source_id, options,
              std::move(auth)) {
  for (auto& b : batches) sender_.add(std::move(b));
  sender_.finish();
}

ReplayResult LcmReplayer::run(
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
    const std::function<bool()>& idle) {
  ReplayResult result;
  sender_.on_state([&](const peritwin_msgs::damage_state_t& s) {
    result.final_state = s;
    if (on_state) on_state(s);
  });
  while (true) {
    const auto progress = sender_.pump(20);
    if (progress == loads::BatchSender::Progress::done) {
      result.ok = true;
      result.end_of_life = sender_.end_of_life();
      break;
    }
    if (progress == loads::BatchSender::Progress::failed) {
      result.error = sender_.error();
      break;
    }
    if (idle && !idle()) {
      result.error = "interrupted";
      break;
    }
  }
  sender_.on_state({});
  result.published = sender_.published();
  result.rewinds = sender_.rewinds();
  result.stale_states = sender_.stale_states();
  return result;
}

config::ConfigResult load_producer_config(const std::string& file, bool in_process) {
  return config::load_config(file, {in_process ? 0 : std::numeric_limits<std::uint64_t>::max()});
}

std::string describe(const peritwin_msgs::damage_state_t& s) { return describe(s, std::nullopt); }

std::string describe(const peritwin_msgs::damage_state_t& s,
                     std::optional<std::int64_t> estimate_cycles) {
  char buf[320];
  std::string life = "remaining life not estimated yet";
  if (s.failure != 0) {
    life = s.failure == peritwin_msgs::damage_state_t::FAILURE_SINGULAR
               ? "FINAL FAILURE (the detail came apart)"
               : "END OF LIFE (criterion met)";
  } else if (std::isfinite(s.remaining_cycles) && estimate_cycles &&
             *estimate_cycles <= s.total_cycles) {
    const double age = static_cast<double>(s.total_cycles - *estimate_cycles);
    auto left = [age](double e) { return std::max(0.0, e - age); };
    std::snprintf(buf, sizeof buf,
                  "remaining %.0f cycles [%.0f, %.0f] (estimated at cycle %lld, %.0f cycles ago)",
                  left(s.remaining_cycles), left(s.remaining_cycles_low),
                  left(s.remaining_cycles_high), static_cast<long long>(*estimate_cycles), age);
    life = buf;
  } else if (std::isfinite(s.remaining_cycles)) {
    std::snprintf(buf, sizeof buf, "remaining %.0f cycles [%.0f, %.0f] (estimated at seq %s)",
                  s.remaining_cycles, s.remaining_cycles_low, s.remaining_cycles_high,
                  s.remaining_life_seq < 0 ? "0" : std::to_string(s.remaining_life_seq).c_str());
    life = buf;
  } else if (std::isinf(s.remaining_cycles)) {
    life = "remaining life unbounded under the reference spectrum";
  }
  // A learning twin's end of life as a probability: its first, middle and last percentile.
  const std::size_t n = std::min(s.percentiles.size(), s.end_of_life_percentiles.size());
  if (s.num_particles > 0 && n > 0 && s.failure == 0) {
    const double lo = s.end_of_life_percentiles.front(), mid = s.end_of_life_percentiles[n / 2],
                 hi = s.end_of_life_percentiles[n - 1];
    if (std::isfinite(lo) && std::isfinite(mid)) {
      std::snprintf(buf, sizeof buf, "; end of life p%g %.0f, p%g %.0f, p%g %s (%d observations)",
                    s.percentiles.front(), lo, s.percentiles[n / 2], mid, s.percentiles[n - 1],
                    std::isfinite(hi) ? std::to_string(std::llround(hi)).c_str() : "beyond",
                    s.observation_count);
      life += buf;
    }
  }
  std::snprintf(buf, sizeof buf, "state %lld: %lld cycles, %lld broken bonds, crack %.2f mm, ",
                static_cast<long long>(s.state_seq), static_cast<long long>(s.total_cycles),
                static_cast<long long>(s.broken_bonds), 1e3 * messages::crack_length(s));
  return buf + life;
}

std::optional<std::int64_t> LifeCountdown::observe(const peritwin_msgs::damage_state_t& s) {
  const bool successor = last_state_seq_ && s.state_seq == *last_state_seq_ + 1;
  last_state_seq_ = s.state_seq;
  const auto n = std::min(s.source_ids.size(), s.applied_seq.size());
  for (std::size_t i = 0; i < n; ++i) {
    auto [it, fresh] = applied_.try_emplace(s.source_ids[i], s.applied_seq[i]);
    if (!fresh && it->second == s.applied_seq[i]) continue;
    it->second = s.applied_seq[i];
    if (!successor) continue;
    const auto key = std::make_pair(s.source_ids[i], s.applied_seq[i]);
    if (cycles_.insert_or_assign(key, s.total_cycles).second) order_.push_back(key);
    if (order_.size() > kMaxBatches) {
      cycles_.erase(order_.front());
      order_.pop_front();
    }
  }
  if (s.remaining_life_seq < 0) return std::int64_t{0};  // the estimate of the initial state
  const auto it = cycles_.find({s.remaining_life_source, s.remaining_life_seq});
  if (it == cycles_.end()) return std::nullopt;
  return it->second;
}

void StatePrinter::print(const peritwin_msgs::damage_state_t& s) {
  const std::optional<std::int64_t> estimate_cycles = countdown_.observe(s);
  if (s.state_seq == last_seq_ && s.remaining_life_seq == last_life_ &&
      s.observation_count == last_observations_) {
    return;
  }
  last_seq_ = s.state_seq;
  last_life_ = s.remaining_life_seq;
  last_observations_ = s.observation_count;
  std::cout << (json_ ? messages::state_json(s) : describe(s, estimate_cycles)) << std::endl;
}

}  // namespace peritwin::replay
