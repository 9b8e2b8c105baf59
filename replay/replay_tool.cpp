#include "replay/replay_tool.h"

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <set>

#include "messages/channels.h"
#include "messages/transport.h"
#include "replay/lcm_log.h"

namespace peritwin::replay {

namespace {
double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

/// Reads the leading fields of an encoded message that could not be verified, for the error
/// (bounded; a field it cannot read reads as empty / -1).
class Peek {
 public:
  Peek(const void* data, std::size_t size)
      : p_(static_cast<const unsigned char*>(data)), size_(size), pos_(8 + 8) {}
  std::int64_t int64() {
    if (size_ < pos_ + 8) return fail<std::int64_t>(-1);
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v = (v << 8) | p_[pos_++];
    return static_cast<std::int64_t>(v);
  }
  std::string string() {
    if (size_ < pos_ + 4) return fail<std::string>({});
    std::uint32_t len = 0;
    for (int i = 0; i < 4; ++i) len = (len << 8) | p_[pos_++];
    if (len < 1 || len > 256 || size_ - pos_ < len) return fail<std::string>({});
    std::string s;
    for (std::uint32_t i = 0; i + 1 < len; ++i) {
      const unsigned char c = p_[pos_ + i];
      s += c >= 0x20 && c < 0x7f ? static_cast<char>(c) : '?';
    }
    pos_ += len;
    return s;
  }

 private:
  template <typename T>
  T fail(T value) {
    pos_ = size_ + 1;
    return value;
  }
  const unsigned char* p_;
  std::size_t size_, pos_;
};
/// Text from the bus for a log line: printable ASCII only, at most 300 characters (an unverified
/// reject's reason must not reach the terminal as control sequences).
std::string printable(const std::string& text) {
  std::string out;
  for (const char c : text.substr(0, 300)) out += c >= 0x20 && c < 0x7f ? c : '?';
  return out;
}
}  // namespace

Expected<HistoryBlocks> read_history(const std::filesystem::path& file, InputFormat format,
                                     const std::string& detail_id,
                                     const SeriesRules& series_rules) {
  HistoryBlocks out;
  if (format != InputFormat::lcm_log) {
    const HistoryFormat f = format == InputFormat::series   ? HistoryFormat::series
                            : format == InputFormat::cycles ? HistoryFormat::cycles
                                                            : HistoryFormat::spectrum;
    const auto read = read_blocks(file, f, series_rules);
    if (!read.ok()) return failure(read.error().message());
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
  if (!in) return failure(file.string() + ": cannot open file");
  return read_lcm_log(in, file.string(), detail_id);
}

Expected<HistoryBlocks> read_lcm_log(std::istream& in, const std::string& name,
                                     const std::string& detail_id) {
  HistoryBlocks out;
  const std::string channel = messages::channel(detail_id, messages::Kind::kLoad);
  std::set<std::pair<std::string, std::int64_t>> seen;
  std::int64_t skipped = 0;
  const auto scan = scan_lcm_log(
      in, name, channel, messages::kMaxBatchPayload, [&](std::span<const std::uint8_t> data) {
        const auto decoded = twin::decode_batch(data.data(), data.size());
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
  if (out.blocks.empty()) return failure(name + ": no load blocks on " + channel);
  return out;
}

std::vector<std::pair<std::string, double>> skipped_cycles(const ConversionStats& stats) {
  return {{"compressive", stats.skipped.compressive},
          {"mirrored_compressive", stats.skipped.mirrored_compressive},
          {"remapped_below_floor", stats.skipped.remapped_below_floor},
          {"degenerate", stats.skipped.degenerate},
          {"nonfinite_samples", static_cast<double>(stats.nonfinite_samples)}};
}

std::string describe_skipped(const ConversionStats& stats) {
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

std::vector<twin::Batch> make_twin_batches(const std::vector<LoadBlock>& blocks,
                                           const std::string& detail_id,
                                           const std::string& source_id,
                                           const BatchingOptions& options) {
  std::vector<twin::Batch> out;
  twin::Batch current{detail_id, source_id, 1, {}};
  std::int64_t cycles = 0;
  for (const auto& b : blocks) {
    current.blocks.push_back(b);
    cycles += b.count;
    if (current.blocks.size() >= std::max<std::size_t>(1, options.max_blocks) ||
        cycles >= options.max_cycles) {
      out.push_back(std::move(current));
      current = {detail_id, source_id, static_cast<std::int64_t>(out.size()) + 1, {}};
      cycles = 0;
    }
  }
  if (!current.blocks.empty()) out.push_back(std::move(current));
  return out;
}

Status check_blocks(std::span<const LoadBlock> blocks) {
  return check_load_blocks(blocks, std::numeric_limits<std::int64_t>::max());
}

LcmReplayer::LcmReplayer(lcm::LCM& lcm, std::vector<twin::Batch> batches, ReplayOptions options,
                         ReplayAuth auth)
    : lcm_(lcm), batches_(std::move(batches)), options_(options), auth_(std::move(auth)) {
  if (!batches_.empty()) {
    detail_id_ = batches_.front().detail_id;
    source_id_ = batches_.front().source_id;
  }
  if (options_.lockstep) options_.window = 1;
  options_.window = std::max<std::size_t>(1, options_.window);
  load_channel_ = messages::channel(detail_id_, messages::Kind::kLoad);
  state_sub_ = lcm_.subscribe(messages::channel(detail_id_, messages::Kind::kState),
                              &LcmReplayer::on_state_msg, this);
  reject_sub_ = lcm_.subscribe(messages::channel(detail_id_, messages::Kind::kReject),
                               &LcmReplayer::on_reject_msg, this);
  state_sub_->setQueueCapacity(100'000);
  reject_sub_->setQueueCapacity(100'000);
}

LcmReplayer::~LcmReplayer() {
  lcm_.unsubscribe(state_sub_);
  lcm_.unsubscribe(reject_sub_);
}

void LcmReplayer::on_state_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!fatal_.empty()) return;  // the run ends with the first failure
  const auto size = static_cast<std::size_t>(rbuf->data_size);
  if (auth_.daemon_key) {
    const Status v = messages::verify_encoded<peritwin_msgs::damage_state_t>(rbuf->data, size,
                                                                             *auth_.daemon_key);
    if (!v) {
      Peek peek(rbuf->data, size);
      const std::string detail = peek.string();
      const std::int64_t state_seq = peek.int64();
      fatal_ = channel + ": " +
               (v.error().field == "auth_tag"
                    ? "state_seq " + std::to_string(state_seq) + " of detail \"" + detail +
                          "\": " + v.error().reason + " (not from the holder of daemon key \"" +
                          auth_.daemon_key_id + "\")"
                    : v.error().reason);
      return;
    }
  }
  // Unverified (no key) or verified: decoded only after its layout is checked.
  const auto state = messages::decode_state(rbuf->data, size);
  if (state && state->detail_id == detail_id_) inbox_.push_back(*state);
}

void LcmReplayer::on_reject_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!fatal_.empty()) return;
  const auto size = static_cast<std::size_t>(rbuf->data_size);
  if (auth_.daemon_key) {
    const Status v =
        messages::verify_encoded<peritwin_msgs::reject_t>(rbuf->data, size, *auth_.daemon_key);
    if (!v) {
      Peek peek(rbuf->data, size);
      peek.string();  // detail_id
      const std::string source = peek.string();
      const std::int64_t seq = peek.int64();
      fatal_ = channel + ": " +
               (v.error().field == "auth_tag"
                    ? "reject of source \"" + source + "\" seq " + std::to_string(seq) + ": " +
                          v.error().reason + " (not from the holder of daemon key \"" +
                          auth_.daemon_key_id + "\")"
                    : v.error().reason);
      return;
    }
  }
  const auto reject = messages::decode_reject(rbuf->data, size);
  if (!reject || reject->source_id != source_id_) return;
  if (reject->code == peritwin_msgs::reject_t::CODE_FAILED) ++rejected_failed_;
  if (reject->code == peritwin_msgs::reject_t::CODE_AUTH) {
    fatal_ = "the daemon refused batch " + std::to_string(reject->seq) + " of source \"" +
             source_id_ + "\" (CODE_AUTH): " + printable(reject->what) + ": " +
             printable(reject->why) +
             (auth_.batch_key ? "" : " (this run signs nothing: give it --key-file)");
  }
}

void LcmReplayer::publish(std::int64_t seq) {
  auto m = twin::batch_message(batches_[static_cast<std::size_t>(seq - 1)], twin::now_utime());
  if (auth_.batch_key) messages::sign(m, *auth_.batch_key);
  lcm_.publish(load_channel_, &m);
  ++published_;
}

ReplayResult LcmReplayer::run(
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
    const std::function<bool()>& idle) {
  ReplayResult result;
  const auto n = static_cast<std::int64_t>(batches_.size());
  std::int64_t applied = -1;  // unknown until the first STATE
  std::int64_t next = 1;      // next seq to publish
  auto last_progress = std::chrono::steady_clock::now();
  auto last_send = last_progress;
  double resend_after = options_.resend_after_s;  // doubles while the daemon stays silent
  while (true) {
    const std::int64_t base = std::max<std::int64_t>(applied, 0);
    const std::int64_t limit =
        std::min<std::int64_t>(n, base + static_cast<std::int64_t>(options_.window));
    while (next <= limit && messages::transport_up(lcm_)) {
      publish(next++);
      last_send = std::chrono::steady_clock::now();
    }
    errno = 0;
    if (messages::transport_up(lcm_) && twin::handle_lcm(lcm_, 20) < 0 && errno != EINTR) {
      result.error = "LCM failed while receiving";
      break;
    }
    if (!fatal_.empty()) {
      result.error = fatal_;
      break;
    }
    if (!messages::transport_up(lcm_)) {  // a tcpq hub closed the connection: no retry here
      result.error = "connection lost (" +
                     (applied < 0 ? std::string("no state from the daemon yet")
                                  : "the daemon had applied seq " + std::to_string(applied) +
                                        " of " + std::to_string(n)) +
                     ")";
      break;
    }
    for (const auto& s : inbox_) {
      const std::int64_t a = twin::applied_seq(s, source_id_);
      if (a != applied) {
        last_progress = std::chrono::steady_clock::now();
        resend_after = options_.resend_after_s;
      }
      if (applied >= 0 && a < applied) {  // the daemon went back (restart from a checkpoint)
        next = a + 1;
        ++result.rewinds;
      }
      applied = a;
      next = std::max(next, applied + 1);
      result.final_state = s;
      if (on_state) on_state(s);
    }
    inbox_.clear();
    if (applied >= n) {
      result.ok = true;
      break;
    }
    if (result.final_state && result.final_state->failure != 0 && rejected_failed_ > 0) {
      result.ok = true;  // the detail reached its end of life: the rest is refused
      break;
    }
    if (since(last_progress) > options_.give_up_after_s) {
      result.error = "no progress from the daemon for " + std::to_string(options_.give_up_after_s) +
                     " s (applied seq " + std::to_string(applied) + " of " + std::to_string(n) +
                     ")";
      break;
    }
    if (since(last_progress) > resend_after && since(last_send) > resend_after) {
      next = std::max<std::int64_t>(applied, 0) + 1;  // go back: resend what is not applied
      ++result.rewinds;
      resend_after = std::min(2 * resend_after, 30.0);
    }
    if (idle && !idle()) {
      result.error = "interrupted";
      break;
    }
  }
  result.published = published_;
  return result;
}

InProcessResult run_in_process(
    const twin::DetailConfig& detail, const std::vector<twin::Batch>& batches,
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state) {
  InProcessResult result;
  auto model = twin::DetailModel::build(detail);
  if (!model) {
    result.error = model.error().message();
    return result;
  }
  auto created = twin::Twin::create(*model, {twin::LifeMode::synchronous, true});
  if (!created) {
    result.error = created.error().message();
    return result;
  }
  auto t = std::move(*created);
  t->catch_up_life();
  auto state = twin::state_message(*t, twin::now_utime());
  if (on_state) on_state(state);
  for (const auto& b : batches) {
    const auto outcome = t->apply(b);
    if (outcome.verdict == twin::Verdict::failed) break;
    if (!outcome.applied()) {
      result.error = "batch " + std::to_string(b.seq) + ": " + outcome.what + ": " + outcome.why;
      return result;
    }
    state = twin::state_message(*t, twin::now_utime());
    if (on_state) on_state(state);
  }
  result.final_state = state;
  return result;
}

std::string describe(const peritwin_msgs::damage_state_t& s) {
  char buf[320];
  std::string life = "remaining life not estimated yet";
  if (s.failure != 0) {
    life = s.failure == peritwin_msgs::damage_state_t::FAILURE_SINGULAR
               ? "FINAL FAILURE (the detail came apart)"
               : "END OF LIFE (criterion met)";
  } else if (std::isfinite(s.remaining_cycles)) {
    std::snprintf(buf, sizeof buf, "remaining %.0f cycles [%.0f, %.0f] (estimated at seq %s)",
                  s.remaining_cycles, s.remaining_cycles_low, s.remaining_cycles_high,
                  s.remaining_life_seq < 0 ? "0" : std::to_string(s.remaining_life_seq).c_str());
    life = buf;
  } else if (std::isinf(s.remaining_cycles)) {
    life = "remaining life unbounded under the reference spectrum";
  }
  std::snprintf(buf, sizeof buf, "state %lld: %lld cycles, %lld broken bonds, crack %.2f mm, ",
                static_cast<long long>(s.state_seq), static_cast<long long>(s.total_cycles),
                static_cast<long long>(s.broken_bonds), 1e3 * twin::crack_length(s));
  return buf + life;
}

}  // namespace peritwin::replay
