#include "twin/twin.h"

#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>

namespace peritwin::twin {

namespace {

std::string number(double v) {
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc{} ? std::string(buf, end) : std::string("?");
}

Outcome invalid(std::string what, std::string why) {
  return {Verdict::invalid, std::move(what), std::move(why)};
}

bool printable_ascii(std::string_view s) {
  for (const char c : s) {
    if (c < 0x21 || c > 0x7e) return false;
  }
  return true;
}

}  // namespace

std::string hex64(std::uint64_t value) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out(16, '0');
  for (int i = 15; i >= 0; --i) {
    out[static_cast<std::size_t>(i)] = kDigits[value & 0xF];
    value >>= 4;
  }
  return out;
}

Outcome check_block(const LoadBlock& b, std::size_t index) {
  const std::string at = "blocks[" + std::to_string(index) + "].";
  if (!std::isfinite(b.p_max))
    return invalid(at + "p_max", "p_max = " + number(b.p_max) + " is not finite");
  if (!(b.p_max > 0)) return invalid(at + "p_max", "p_max = " + number(b.p_max) + " must be > 0");
  if (!std::isfinite(b.r)) return invalid(at + "r", "r = " + number(b.r) + " is not finite");
  if (!(b.r < 1.0)) return invalid(at + "r", "r = " + number(b.r) + " must be < 1");
  if (!(b.r >= kMinLoadRatio)) {
    return invalid(at + "r", "r = " + number(b.r) + " must be >= " + number(kMinLoadRatio));
  }
  if (!std::isfinite(b.alpha))
    return invalid(at + "alpha", "alpha = " + number(b.alpha) + " is not finite");
  if (b.count < 1)
    return invalid(at + "count", "count = " + std::to_string(b.count) + " must be >= 1");
  if (!validate(b).empty()) return invalid(at + "block", validate(b));  // the engine's own check
  return {};
}

Outcome check_batch(const Batch& batch, std::string_view detail_id) {
  if (batch.detail_id != detail_id) {
    return {Verdict::wrong_detail, "detail_id",
            "detail_id \"" + batch.detail_id + "\" does not match the channel's detail \"" +
                std::string(detail_id) + "\""};
  }
  if (batch.source_id.empty() || batch.source_id.size() > kMaxSourceIdLength ||
      !printable_ascii(batch.source_id)) {
    return invalid("source_id", "source_id must be 1 to " + std::to_string(kMaxSourceIdLength) +
                                    " printable ASCII characters without blanks");
  }
  if (batch.seq < 1) return invalid("seq", "seq = " + std::to_string(batch.seq) + " must be >= 1");
  if (batch.blocks.empty()) return invalid("num_blocks", "num_blocks = 0 must be >= 1");
  if (batch.blocks.size() > kMaxBlocksPerBatch) {
    return invalid("num_blocks", "num_blocks = " + std::to_string(batch.blocks.size()) +
                                     " must be <= " + std::to_string(kMaxBlocksPerBatch));
  }
  std::int64_t cycles = 0;
  for (std::size_t i = 0; i < batch.blocks.size(); ++i) {
    Outcome o = check_block(batch.blocks[i], i);
    if (!o.applied()) return o;
    cycles += std::min(batch.blocks[i].count, kMaxBatchCycles);
    if (cycles > kMaxBatchCycles) {
      return invalid("blocks[" + std::to_string(i) + "].count",
                     "the batch's cycle count exceeds " + std::to_string(kMaxBatchCycles));
    }
  }
  return {};
}

Twin::Twin(std::shared_ptr<const DetailModel> model, Options options)
    : model_(std::move(model)), options_(options) {}

std::unique_ptr<Twin> Twin::create(std::shared_ptr<const DetailModel> model, Options options,
                                   std::string* error) {
  std::unique_ptr<Twin> twin(new Twin(std::move(model), options));
  twin->engine_ = twin->model_->make_engine();
  if (!twin->engine_->initialize()) {
    if (error != nullptr) {
      *error = "detail " + twin->detail_id() +
               ": the virgin model cannot be solved: " + twin->engine_->failure_reason();
    }
    return nullptr;
  }
  twin->refresh();
  return twin;
}

std::int64_t Twin::applied_seq(const std::string& source) const {
  const auto it = applied_.find(source);
  return it == applied_.end() ? 0 : it->second;
}

std::int64_t Twin::broken_bonds() const { return engine_->broken_bonds() - model_->precut_bonds(); }

void Twin::refresh() {
  report_ = measure_cracks(*model_, *engine_, last_block_ ? &*last_block_ : nullptr);
  failure_ = end_of_life(*model_, *engine_, report_);
}

Outcome Twin::apply(const Batch& batch) {
  Outcome o = check_batch(batch, detail_id());
  if (!o.applied()) {
    ++counters_.rejected;
    return o;
  }
  const std::int64_t last = applied_seq(batch.source_id);
  if (batch.seq <= last) {
    ++counters_.duplicates;
    return {Verdict::duplicate, "seq",
            "seq " + std::to_string(batch.seq) + " of source \"" + batch.source_id +
                "\" is already applied (last applied " + std::to_string(last) + ")"};
  }
  if (batch.seq > last + 1) {
    ++counters_.gaps;
    ++counters_.rejected;
    return {Verdict::gap, "seq",
            "seq " + std::to_string(batch.seq) + " of source \"" + batch.source_id +
                "\" skips ahead: expected " + std::to_string(last + 1) + ", missing " +
                std::to_string(batch.seq - last - 1) + " batch(es); resend from " +
                std::to_string(last + 1)};
  }
  if (failure_ != Failure::none) {
    ++counters_.rejected;
    return {Verdict::failed, "message",
            failure_ == Failure::singular
                ? "the detail has reached final failure: " + engine_->failure_reason()
                : std::string("the detail has reached its end-of-life criterion")};
  }
  for (const LoadBlock& block : batch.blocks) {
    if (engine_->failed()) break;
    engine_->apply(block);
    spectrum_.add(block);
    last_block_ = block;
  }
  applied_[batch.source_id] = batch.seq;
  ++state_seq_;
  last_source_ = batch.source_id;
  last_seq_ = batch.seq;
  ++counters_.applied;
  refresh();
  if (failure_ != Failure::none) {
    set_life({0.0, 0.0, 0.0, state_seq_, last_seq_, last_source_});
  } else if (options_.life == LifeMode::synchronous) {
    catch_up_life();
  }
  return {};
}

namespace {

/// FNV-1a 64 over 64-bit words (one xor-multiply per word, not per byte): the state hash runs
/// after every batch over every bond, byte-wise FNV cost a quarter of the ingest time.
class WordHash {
 public:
  void word(std::uint64_t w) {
    h_ ^= w;
    h_ *= 1099511628211ULL;
  }
  void real(double v) { word(std::bit_cast<std::uint64_t>(v)); }
  void integer(std::int64_t v) { word(static_cast<std::uint64_t>(v)); }
  /// Bytes packed little-endian 8 to a word, then the length.
  void bytes(const std::uint8_t* p, std::size_t n) {
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
      std::uint64_t w;
      std::memcpy(&w, p + i, 8);
      word(w);
    }
    std::uint64_t tail = 0;
    for (std::size_t k = 0; i + k < n; ++k) tail |= std::uint64_t{p[i + k]} << (8 * k);
    word(tail);
    word(n);
  }
  void text(const std::string& s) {
    bytes(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
  }
  void block(const LoadBlock& b) {
    real(b.p_max);
    real(b.r);
    real(b.alpha);
    integer(b.count);
  }
  [[nodiscard]] std::uint64_t get() const { return h_; }

 private:
  std::uint64_t h_ = 1469598103934665603ULL;
};

}  // namespace

std::uint64_t Twin::state_hash() const {
  // The model: every bond's remaining life (bits), intact flag and phase, the cycle count; then
  // the bookkeeping. Equal hashes <=> bit-identical states (up to 64-bit collisions).
  WordHash h;
  for (const double life : engine_->remaining_life()) h.real(life);
  const auto& intact = engine_->solver().intact();
  h.bytes(intact.data(), intact.size());
  const auto& phase = engine_->bond_phase();
  h.bytes(phase.data(), phase.size());
  h.integer(engine_->total_cycles());
  h.integer(state_seq_);
  for (const auto& [source, seq] : applied_) {
    h.text(source);
    h.integer(seq);
  }
  h.integer(static_cast<std::int64_t>(failure_));
  h.integer(last_block_ ? 1 : 0);
  if (last_block_) h.block(*last_block_);
  h.integer(static_cast<std::int64_t>(spectrum_.blocks().size()));
  for (const auto& b : spectrum_.blocks()) h.block(b);
  return h.get();
}

std::string Twin::state_hash_hex() const { return hex64(state_hash()); }

LifeJob Twin::life_job() const {
  return {model_,
          engine_->export_state(),
          reference_spectrum(*model_, spectrum_),
          state_seq_,
          last_seq_,
          last_source_};
}

void Twin::set_life(const LifeEstimate& estimate) {
  if (estimate.state_seq < life_.state_seq) return;
  life_ = estimate;
}

bool Twin::life_due() const {
  const std::int64_t every = model_->config().life.every_batches;
  return failure_ == Failure::none && every > 0 && state_seq_ % every == 0 &&
         life_.state_seq != state_seq_;
}

void Twin::estimate_life_now() {
  const LifeJob job = life_job();
  LifeEstimate e = estimate_life(*model_, job.state, job.spectrum, options_.parallel_band);
  e.state_seq = job.state_seq;
  e.seq = job.seq;
  e.source = job.source;
  set_life(e);
}

void Twin::catch_up_life() {
  if (options_.life == LifeMode::synchronous && life_due()) estimate_life_now();
}

}  // namespace peritwin::twin
