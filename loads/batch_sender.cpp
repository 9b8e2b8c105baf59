#include "loads/batch_sender.h"

#include <algorithm>
#include <cerrno>
#include <limits>
#include <utility>

#include "messages/channels.h"
#include "messages/transport.h"

namespace peritwin::loads {

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

/// The seq of probe_applied()'s batch: never applied (it skips ahead of any source).
constexpr std::int64_t kProbeSeq = std::numeric_limits<std::int64_t>::max();
/// A STATE that answers no batch of this run and disagrees with it prompts a probe at most this
/// often (a flood of old STATEs costs one small batch a second).
constexpr double kReprobeAfterS = 1.0;

/// A reject no resend can cure: the batch itself (INVALID), the daemon's keys (AUTH), its limits
/// (LIMIT) or the detail's end (FAILED) refuse it, and would refuse it again. DUPLICATE and GAP
/// are the protocol at work (the STATE tells where to resend from); DECODE, WRONG_DETAIL and
/// INTERNAL are left to the no-progress timeout as before.
bool incurable(std::int8_t code) {
  using R = peritwin_msgs::reject_t;
  return code == R::CODE_INVALID || code == R::CODE_AUTH || code == R::CODE_LIMIT ||
         code == R::CODE_FAILED;
}

/// reject_t's name of a code, for the error line.
std::string code_name(std::int8_t code) {
  using R = peritwin_msgs::reject_t;
  switch (code) {
    case R::CODE_INVALID:
      return "CODE_INVALID";
    case R::CODE_AUTH:
      return "CODE_AUTH";
    case R::CODE_LIMIT:
      return "CODE_LIMIT";
    case R::CODE_FAILED:
      return "CODE_FAILED";
    default:
      return "code " + std::to_string(code);
  }
}

std::int64_t checkpointed_seq(const peritwin_msgs::damage_state_t& s, const std::string& source) {
  for (std::size_t i = 0; i < s.source_ids.size() && i < s.checkpointed_seq.size(); ++i) {
    if (s.source_ids[i] == source) return s.checkpointed_seq[i];
  }
  return 0;
}
}  // namespace

BatchSender::BatchSender(lcm::LCM& lcm, std::string detail_id, std::string source_id,
                         ReplayOptions options, ReplayAuth auth)
    : lcm_(lcm),
      detail_id_(std::move(detail_id)),
      source_id_(std::move(source_id)),
      options_(options),
      auth_(std::move(auth)),
      nonce_(messages::random_nonce()),
      last_progress_(std::chrono::steady_clock::now()),
      last_send_(last_progress_),
      resend_after_(options.resend_after_s) {
  if (options_.lockstep) options_.window = 1;
  options_.window = std::max<std::size_t>(1, options_.window);
  load_channel_ = messages::channel(detail_id_, messages::Kind::kLoad);
  state_sub_ = lcm_.subscribe(messages::channel(detail_id_, messages::Kind::kState),
                              &BatchSender::on_state_msg, this);
  reject_sub_ = lcm_.subscribe(messages::channel(detail_id_, messages::Kind::kReject),
                               &BatchSender::on_reject_msg, this);
  state_sub_->setQueueCapacity(100'000);
  reject_sub_->setQueueCapacity(100'000);
}

BatchSender::~BatchSender() {
  lcm_.unsubscribe(state_sub_);
  lcm_.unsubscribe(reject_sub_);
}

void BatchSender::on_state_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!fatal_.empty()) return;  // the run ends with the first failure
  const auto size = static_cast<std::size_t>(rbuf->data_size);
  if (auth_.daemon_key) {
    const core::Status v = messages::verify_encoded<peritwin_msgs::damage_state_t>(
        rbuf->data, size, *auth_.daemon_key);
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
  if (!state || state->detail_id != detail_id_) return;
  if (messages::answers(*state, source_id_, nonce_)) {
    inbox_.push_back(*state);
    return;
  }
  // Not an answer to this run (published before it started, again, or to another run): not
  // progress. When it disagrees with what this run knows (e.g. a restarted daemon's start-up
  // STATE), a probe asks for a STATE that answers this run.
  ++stale_states_;
  if (applied_ >= 0 && messages::applied_seq(*state, source_id_) != applied_) reprobe_ = true;
}

void BatchSender::on_reject_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!fatal_.empty()) return;
  const auto size = static_cast<std::size_t>(rbuf->data_size);
  if (auth_.daemon_key) {
    const core::Status v =
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
  // Only the rejects of this run's batches: their nonce is this run's.
  if (!reject || reject->source_id != source_id_ ||
      static_cast<std::uint64_t>(reject->nonce) != nonce_) {
    return;
  }
  // Only a reject of one of this run's batches (or of the probe) says something about this run:
  // another producer on the same source id gets its own.
  const bool ours = reject->seq == kProbeSeq ||
                    (first_seq_ > 0 && reject->seq >= first_seq_ && reject->seq <= last_seq_);
  if (!ours || !incurable(reject->code)) return;
  const std::string refused = "the daemon refused " +
                              (reject->seq == kProbeSeq ? std::string("the probe batch")
                                                        : "batch " + std::to_string(reject->seq)) +
                              " of source \"" + source_id_ + "\" (" + code_name(reject->code) +
                              "): " + printable(reject->what) + ": " + printable(reject->why);
  if (reject->code == peritwin_msgs::reject_t::CODE_FAILED) {
    // The daemon checks duplicates and gaps first: FAILED for seq s means it had applied s - 1.
    // pump() decides whether this run brought the detail to its end of life (done) or found it
    // ended (failed).
    if (failed_seq_ == 0 || reject->seq < failed_seq_) {
      failed_seq_ = reject->seq;
      failed_why_ = refused;
    }
    return;
  }
  if (reject->code == peritwin_msgs::reject_t::CODE_AUTH) {
    fatal_ = refused + (auth_.batch_key ? "" : " (this run signs nothing: give it --key-file)");
  } else {
    fatal_ = refused + " (not sent again: no resend can change that)";
  }
}

void BatchSender::publish(const messages::Batch& batch) {
  auto m = messages::batch_message(batch, messages::now_utime());
  m.nonce = static_cast<std::int64_t>(nonce_);
  if (auth_.batch_key) messages::sign(m, *auth_.batch_key);
  lcm_.publish(load_channel_, &m);
  ++published_;
  last_send_ = std::chrono::steady_clock::now();
}

bool BatchSender::receive(int timeout_ms) {
  errno = 0;
  if (messages::transport_up(lcm_) && messages::handle_lcm(lcm_, timeout_ms) < 0 &&
      errno != EINTR) {
    error_ = "LCM failed while receiving";
    return false;
  }
  if (!fatal_.empty()) {
    error_ = fatal_;
    return false;
  }
  if (!messages::transport_up(lcm_)) {  // a tcpq hub closed the connection: no retry here
    error_ = "connection lost (" +
             (applied_ < 0 ? std::string("no state from the daemon yet")
                           : "the daemon had applied seq " + std::to_string(applied_) + " of " +
                                 std::to_string(last_seq_)) +
             ")";
    return false;
  }
  return true;
}

void BatchSender::take_states() {
  for (const auto& s : inbox_) {
    const std::int64_t a = messages::applied_seq(s, source_id_);
    if (a != applied_) {
      last_progress_ = std::chrono::steady_clock::now();
      resend_after_ = options_.resend_after_s;
    }
    if (applied_ >= 0 && a < applied_) {  // the daemon went back (restart from a checkpoint)
      next_ = a + 1;
      ++rewinds_;
    }
    applied_ = a;
    durable_ = checkpointed_seq(s, source_id_);
    next_ = std::max(next_, applied_ + 1);
    last_state_ = s;
    if (on_state_) on_state_(s);
  }
  inbox_.clear();
  // Forget what the daemon holds durably, and the oldest applied beyond kMaxRetained.
  while (!batches_.empty() && batches_.front().seq <= applied_ &&
         (batches_.front().seq <= durable_ ||
          applied_ - batches_.front().seq >= static_cast<std::int64_t>(kMaxRetained))) {
    batches_.pop_front();
  }
}

void BatchSender::publish_probe() {
  const messages::Batch probe{
      detail_id_, source_id_, kProbeSeq, {core::LoadBlock{1.0, 0.0, 0.0, 1}}};
  publish(probe);
  --published_;  // not a batch of the run
  last_probe_ = std::chrono::steady_clock::now();
}

core::Expected<std::int64_t> BatchSender::probe_applied(const std::function<bool()>& idle) {
  const auto start = std::chrono::steady_clock::now();
  std::optional<std::chrono::steady_clock::time_point> sent;
  double resend_after = options_.resend_after_s;
  while (applied_ < 0) {
    if ((!sent || since(*sent) > resend_after) && messages::transport_up(lcm_)) {
      if (sent) resend_after = std::min(2 * resend_after, 30.0);
      publish_probe();
      sent = std::chrono::steady_clock::now();
    }
    if (!receive(20)) return core::failure(error_);
    take_states();
    if (applied_ >= 0) break;
    if (since(start) > options_.give_up_after_s) {
      return core::failure("no state from the daemon of detail \"" + detail_id_ + "\" for " +
                           std::to_string(options_.give_up_after_s) + " s (is it running?)");
    }
    if (idle && !idle()) return core::failure("interrupted");
  }
  last_progress_ = std::chrono::steady_clock::now();
  return applied_;
}

void BatchSender::add(messages::Batch batch) {
  if (!outstanding()) {  // idle until now: the no-progress clock starts here
    last_progress_ = std::chrono::steady_clock::now();
    resend_after_ = options_.resend_after_s;
  }
  if (last_seq_ == 0) {
    next_ = std::max(next_, batch.seq);
    first_seq_ = batch.seq;
  }
  last_seq_ = batch.seq;
  batches_.push_back(std::move(batch));
}

void BatchSender::finish() { finished_ = true; }

std::vector<messages::Batch> BatchSender::unacknowledged() const {
  std::vector<messages::Batch> out;
  for (const auto& b : batches_) {
    if (b.seq > applied_) out.push_back(b);
  }
  return out;
}

BatchSender::Progress BatchSender::pump(int timeout_ms) {
  if (!error_.empty()) return Progress::failed;
  const std::int64_t first = batches_.empty() ? last_seq_ + 1 : batches_.front().seq;
  const std::int64_t base = applied_ >= 0 ? applied_ : first - 1;
  const std::int64_t limit =
      std::min<std::int64_t>(last_seq_, base + static_cast<std::int64_t>(options_.window));
  while (next_ <= limit && messages::transport_up(lcm_)) {
    if (batches_.empty() || next_ < batches_.front().seq) {
      error_ = "the daemon went back to seq " + std::to_string(next_ - 1) + " of source \"" +
               source_id_ + "\", but batches before " +
               std::to_string(batches_.empty() ? last_seq_ + 1 : batches_.front().seq) +
               " are no longer held (it reported them durable, or more than " +
               std::to_string(kMaxRetained) + " were applied since)";
      return Progress::failed;
    }
    publish(batches_[static_cast<std::size_t>(next_ - batches_.front().seq)]);
    ++next_;
  }
  if (!receive(timeout_ms)) return Progress::failed;
  take_states();
  if (reprobe_ && since(last_probe_) > kReprobeAfterS && messages::transport_up(lcm_)) {
    reprobe_ = false;
    publish_probe();
  }
  if (finished_ && applied_ >= 0 && applied_ >= last_seq_) return Progress::done;
  if (failed_seq_ > 0) {
    if (failed_seq_ - 1 >= first_seq_) {  // this run's batches reached the end of life: done
      end_of_life_ = failed_why_;
      return Progress::done;
    }
    error_ = failed_why_ + "; none of this run's batches was applied";
    return Progress::failed;
  }
  if (!outstanding() && applied_ >= 0) {
    last_progress_ = std::chrono::steady_clock::now();
    return Progress::running;
  }
  if (since(last_progress_) > options_.give_up_after_s) {
    error_ = "no progress from the daemon for " + std::to_string(options_.give_up_after_s) +
             " s (applied seq " + std::to_string(applied_) + " of " + std::to_string(last_seq_) +
             ")";
    return Progress::failed;
  }
  if (since(last_progress_) > resend_after_ && since(last_send_) > resend_after_) {
    next_ = std::max<std::int64_t>(applied_, first - 1) + 1;  // go back: resend what is not applied
    ++rewinds_;
    resend_after_ = std::min(2 * resend_after_, 30.0);
  }
  return Progress::running;
}

}  // namespace peritwin::loads
