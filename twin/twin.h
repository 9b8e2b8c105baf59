// The live twin of one detail: the fatigue engine on the detail's model, exactly-once
// bookkeeping per load source, crack metrics, end-of-life state, the rolling spectrum, the latest
// remaining-life estimate, and checkpoint export/import. No LCM, no threads, no wall clock: the
// state after a batch sequence is a pure function of (config, sequence).
//
// Exactly-once (docs/design.md): every batch carries (source_id, seq). Per source the twin applies
// seq = last + 1 only: seq <= last is a DUPLICATE (ignored, counted), seq > last + 1 is a GAP
// (rejected, counted; the producer resends from applied_seq + 1, which every state publishes).
// A batch is applied as a unit, its blocks in order. A batch that is rejected for any reason
// leaves the model untouched. After final failure (end criterion met or singular stiffness)
// every new batch is rejected with FAILED.
//
// End of life: the engine checks the detail's end criterion (end_of_life_check) after every group
// of breaks and stops at the exact cycle at which it is met, inside a block or a batch. So
// end_of_life_cycle(), the broken bonds and the cracks at the end of life are those of that cycle
// for any batching of the same cycles (the engine is exact under splitting of blocks). What
// happens to the cycles after it: the twin stops. The rest of the batch that reached the end is
// not applied (the batch counts as applied: its seq is acknowledged and not resent) and every
// later batch is rejected with FAILED, naming the cycle. The state published from then on is the
// state at the end of life: the evidence an inspection needs, not a model extrapolated beyond
// its criterion (the criterion is where the calibration and the crack-length measurement stop
// being trusted; the structure's further loading is still counted by the producers). A twin for
// a repaired or re-assessed detail starts from a new config.
//
// Remaining life (LifeMode):
//  * synchronous (deterministic mode: replay in-process, the daemon with --deterministic): an
//    estimate is computed inside apply() whenever state_seq is a multiple of
//    life.every_batches, or the batch took the cycle count past a multiple of life.every_cycles
//    (catch_up_life() does it for the state the twin starts from);
//  * external (the daemon's worker thread): the owner takes life_job() snapshots, runs
//    estimate_life() elsewhere and hands the result back with set_life().
// The estimate is not part of state_hash(); it is published with the state it was computed on.
//
// Learning (issue 32, docs/prognostics.md): a detail with [detail.uncertainty] (and
// Options::learn) has an ensemble (twin/ensemble.h) beside the engine: every applied block goes to
// its particles too, observe() takes inspections in (exactly once per source and seq, like
// batches, in a sequence of their own), and its remaining-life percentiles are published with
// every state. The particles' ends of life are simulated (synchronously, in any LifeMode) at the
// start, after every observation, every [detail.uncertainty] every_batches and at the end of
// life; in between the percentiles follow the cycle count. The ensemble's state (not its
// simulated ends of life) enters state_hash(), not engine_hash().
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "messages/batch.h"
#include "solver/fatigue/fatigue_engine.h"
#include "twin/checkpoint_data.h"
#include "twin/detail_model.h"
#include "twin/ensemble.h"
#include "twin/life.h"

namespace peritwin::twin {

enum class LifeMode { synchronous, external };

/// The load P (N) at which the virgin detail's peak bond stretch reaches the critical stretch:
/// s_ref / max over intact bonds of (s_b + hypot(c_b, n_b)), the basis stretches per newton
/// (the tensile peak over the load angle α). s_ref is the bilinear law's sc (003 Eq. 44), the
/// configured critical stretch, or 000 Eq. (8) from K_c; +Inf when none is known.
double first_break_load(const DetailModel& model, const fatigue::FatigueEngine& engine);

/// [detail.limits] max_p defaults to this many times first_break_load(): a batch above it is far
/// beyond any overload the detail survives, more likely a units slip (kN for N) than a load.
inline constexpr double kDefaultMaxPOverFirstBreak = 10.0;

/// The history of a source's last applied batch (load_batch_t.history, .history_start): what
/// peritwin-replay --resume checks its own history against. Bookkeeping of the producers, not of
/// the model: no hash covers it.
struct SourceHistory {
  std::uint64_t fingerprint = 0;  ///< 0: none (a stream)
  std::int64_t start = 0;         ///< seq of that history's first batch
};
using HistoryBySource = std::map<std::string, SourceHistory>;

/// Counters since this Twin object was created (not part of the state, not checkpointed).
struct TwinCounters {
  std::int64_t applied = 0;
  std::int64_t duplicates = 0;
  std::int64_t gaps = 0;
  std::int64_t rejected = 0;  ///< everything not applied except duplicates
};

/// A snapshot for a remaining-life estimate off the ingest path.
struct LifeJob {
  std::shared_ptr<const DetailModel> model;
  fatigue::EngineState state;
  std::vector<core::LoadBlock> spectrum;
  std::int64_t state_seq = 0;
  std::int64_t seq = -1;
  std::string source;
  /// A fork of the live engine at `state` (FatigueEngine::fork), which the estimate's
  /// simulations fork again instead of rebuilding and replaying the factor; null for the bilinear
  /// law (simulate_life then imports `state`) and for the coarse estimate ([detail.life] dx). It
  /// holds a copy of the factor: one more factor in memory while the job waits or runs
  /// (docs/design.md, "Remaining life").
  std::shared_ptr<const fatigue::FatigueEngine> engine;
};

class Twin {
 public:
  struct Options {
    LifeMode life = LifeMode::synchronous;
    bool parallel_band = true;  ///< the three band simulations on three threads
    /// Run the learning ensemble when the detail has [detail.uncertainty].
    bool learn = true;
  };

  /// Builds the engine on `model` and solves the virgin state; or why it cannot.
  static core::Expected<std::unique_ptr<Twin>> create(std::shared_ptr<const DetailModel> model,
                                                      Options options);

  /// Applies a batch, or says why not: check_batch, then check_limits, then exactly-once.
  messages::Outcome apply(const messages::Batch& batch);
  /// Takes an observation in, or says why not (the model unchanged): its fields
  /// (messages::check_observation, with the field path "observation.<field>"), the detail, the
  /// source's next seq (duplicates and gaps as for batches, a sequence of its own per source), a
  /// cycle not after the twin's, an origin of the detail, a detail that learns (INVALID without
  /// [detail.uncertainty]); then the ensemble's update and a new estimate.
  messages::Outcome observe(const messages::Observation& observation);
  /// Simulates the ensemble's ends of life at the current state now (no-op without one).
  void estimate_ensemble_now() {
    if (ensemble_) catch_up_ensemble(true);
  }
  /// The learning ensemble; null without [detail.uncertainty] or Options::learn.
  [[nodiscard]] const Ensemble* ensemble() const { return ensemble_.get(); }
  /// The ensemble's remaining life at the current state (Ensemble::summary()); empty without one.
  [[nodiscard]] std::optional<EnsembleEstimate> ensemble_estimate() const;
  /// Every gauge's influence coefficients for the current bond state (twin/gauges.h).
  [[nodiscard]] std::vector<std::array<double, 3>> gauge_influences() const;
  /// The compliance residuals of the last gauge observation, per configured gauge.
  [[nodiscard]] const GaugeResiduals& gauge_residuals() const { return gauge_residuals_; }
  /// Last taken-in observation seq per source (sorted by source id).
  [[nodiscard]] const std::map<std::string, std::int64_t>& observed() const { return observed_; }
  /// The detail's bounds ([detail.limits]): every p_max <= max_p() (INVALID), at most
  /// max_sources distinct sources (LIMIT for a new one beyond it).
  [[nodiscard]] messages::Outcome check_limits(const messages::Batch& batch) const;
  /// The peak-load bound in force (N): [detail.limits] max_p, or kDefaultMaxPOverFirstBreak x
  /// first_break_load(); +Inf when neither is known.
  [[nodiscard]] double max_p() const { return max_p_; }
  [[nodiscard]] double first_break_load() const { return first_break_load_; }

  [[nodiscard]] const DetailModel& model() const { return *model_; }
  /// The same model, shared (e.g. with the learning ensemble, twin/ensemble.h).
  [[nodiscard]] std::shared_ptr<const DetailModel> shared_model() const { return model_; }
  [[nodiscard]] const std::string& detail_id() const { return model_->config().id; }
  [[nodiscard]] const Options& options() const { return options_; }
  /// Batches applied since the virgin state, all sources together (0 = virgin).
  [[nodiscard]] std::int64_t state_seq() const { return state_seq_; }
  /// Last applied seq per source (sorted by source id).
  [[nodiscard]] const std::map<std::string, std::int64_t>& applied() const { return applied_; }
  [[nodiscard]] std::int64_t applied_seq(const std::string& source) const;
  /// The history of each source's last applied batch (sorted by source id; a source whose
  /// batches carried none has {0, 0}).
  [[nodiscard]] const HistoryBySource& histories() const { return histories_; }
  /// (source, seq) of the batch that produced the current state ("" / -1 for the virgin state).
  [[nodiscard]] const std::string& last_source() const { return last_source_; }
  [[nodiscard]] std::int64_t last_seq() const { return last_seq_; }
  [[nodiscard]] const fatigue::FatigueEngine& engine() const { return *engine_; }
  [[nodiscard]] const CrackReport& cracks() const { return report_; }
  [[nodiscard]] Failure failure() const { return failure_; }
  /// The cycle at which the end of life (any Failure) was reached, -1 before it: the engine
  /// stops there (see "End of life" above).
  [[nodiscard]] std::int64_t end_of_life_cycle() const {
    return failure_ == Failure::none ? -1 : engine_->total_cycles();
  }
  /// FNV-1a 64 of the engine's state alone (FatigueEngine::state_hash: lives, doses, broken
  /// bonds, cycles, break events, bilinear damage): a function of the cycle sequence, not of how
  /// it was cut into blocks and batches, nor of the sources.
  [[nodiscard]] std::uint64_t engine_hash() const { return engine_->state_hash(); }
  [[nodiscard]] const LifeEstimate& life() const { return life_; }
  [[nodiscard]] const RollingSpectrum& spectrum() const { return spectrum_; }
  [[nodiscard]] const std::optional<core::LoadBlock>& last_block() const { return last_block_; }
  [[nodiscard]] const TwinCounters& counters() const { return counters_; }
  /// Broken bonds since the virgin state (notch-cut bonds not counted).
  [[nodiscard]] std::int64_t broken_bonds() const;
  /// Word-wise FNV-1a 64 (core/fnv1a.h) over the twin's hashed fields (for_each_field:
  /// state_seq, the applied seq per source, the last batch, the last block, the failure code, the
  /// rolling spectrum) and then the engine's state (EngineState's field table: lives, doses,
  /// intact bonds, cycles, break events, bilinear damage). Not over the life estimate.
  [[nodiscard]] std::uint64_t state_hash() const;
  [[nodiscard]] std::string state_hash_hex() const;
  struct Hashes {
    std::uint64_t state = 0;   ///< state_hash()
    std::uint64_t engine = 0;  ///< engine_hash()
  };
  /// state_hash() and engine_hash() in one pass over the engine's state (every STATE has both).
  [[nodiscard]] Hashes hashes() const;

  /// Remaining life ----------------------------------------------------------------------------
  [[nodiscard]] LifeJob life_job() const;
  /// The same without the engine fork (simulate_life then rebuilds from the state).
  [[nodiscard]] LifeJob life_job_state_only() const;
  /// Installs an estimate unless it belongs to an older state than the current estimate.
  void set_life(const LifeEstimate& estimate);
  /// True when a synchronous estimate is due for the current state and not computed yet: state 0,
  /// a state_seq that is a multiple of life.every_batches, or a state whose batch took the cycle
  /// count past a multiple of life.every_cycles.
  [[nodiscard]] bool life_due() const;
  /// Computes the estimate for the current state now (on this thread).
  void estimate_life_now();
  /// Synchronous mode: estimate_life_now() if life_due().
  void catch_up_life();

  /// Checkpoints -------------------------------------------------------------------------------
  /// 2: bilinear law state. 3: keys from the field tables (Twin::for_each_own_field,
  /// peritwin::for_each_field of EngineState) and the real FNV-1a 64 offset basis in every hash
  /// (the model signature changed with it). An older checkpoint is refused with both versions.
  static constexpr std::int64_t kCheckpointFormat = 3;
  [[nodiscard]] CheckpointData to_checkpoint() const;
  /// Whether `data` is a checkpoint this twin can restore: format version, detail id, model
  /// signature and (when given) the state_seq its file name promises. Reads no state.
  [[nodiscard]] core::Status check_checkpoint(const CheckpointData& data,
                                              std::optional<std::int64_t> state_seq) const;
  /// Restores a checkpoint of the same model (check_checkpoint first). On failure the twin must
  /// be discarded.
  core::Status restore(const CheckpointData& data);

  /// Whether a field of the twin's table enters state_hash().
  enum class Hashed : bool { no = false, yes = true };
  /// The field table of the twin's own state (the engine's is EngineState's): every field once,
  /// with its checkpoint key. `visit(key, field, hashed)`; Self is Twin or const Twin.
  template <class Self, class Visit>
  static void for_each_own_field(Self& self, Visit&& visit) {
    visit("state_seq", self.state_seq_, Hashed::yes);
    visit("source", self.applied_, Hashed::yes);
    visit("last_source", self.last_source_, Hashed::yes);
    visit("last_seq", self.last_seq_, Hashed::yes);
    visit("last_block", self.last_block_, Hashed::yes);
    visit("failure", self.failure_, Hashed::yes);
    visit("spectrum", self.spectrum_, Hashed::yes);
    visit("history", self.histories_, Hashed::no);
    visit("observed", self.observed_, Hashed::yes);
    visit("gauge", self.gauge_residuals_, Hashed::yes);
    visit("life_central", self.life_.central, Hashed::no);
    visit("life_low", self.life_.low, Hashed::no);
    visit("life_high", self.life_.high, Hashed::no);
    visit("life_state_seq", self.life_.state_seq, Hashed::no);
    visit("life_seq", self.life_.seq, Hashed::no);
    visit("life_source", self.life_.source, Hashed::no);
  }

 private:
  Twin(std::shared_ptr<const DetailModel> model, Options options);
  void refresh();  ///< crack report and failure from the engine
  /// Simulates the ensemble's ends of life when due (state 0, every_batches, the end of life).
  void catch_up_ensemble(bool force);
  [[nodiscard]] core::Fnv1a64 own_fields_hash() const;  ///< the twin's own hashed fields

  std::shared_ptr<const DetailModel> model_;
  Options options_;
  std::unique_ptr<fatigue::FatigueEngine> engine_;
  std::int64_t state_seq_ = 0;
  std::map<std::string, std::int64_t> applied_;
  std::map<std::string, std::int64_t> observed_;  ///< observations: last seq per source
  GaugeResiduals gauge_residuals_;                ///< of the last gauge observation (twin/gauges.h)
  std::unique_ptr<Ensemble> ensemble_;
  HistoryBySource histories_;
  std::string last_source_;
  std::int64_t last_seq_ = -1;
  /// Engine cycles before the batch that made the current state (life.every_cycles); not part
  /// of the state: a restored twin starts with its own cycle count.
  std::int64_t cycles_before_state_ = 0;
  std::optional<core::LoadBlock> last_block_;
  CrackReport report_;
  /// What report_ was measured from: the cracks and K change only with a break, a re-solve or
  /// the last block's P_max and α, so a batch that changes none of them keeps report_ (finding the
  /// cracks replays every break event: the largest part of a quiet batch's cost).
  struct ReportKey {
    std::size_t events = 0;
    int solves = 0, rebuilds = 0;
    std::int64_t increments = 0;
    bool failed = false, has_block = false;
    double p_max = 0.0, alpha = 0.0;
    bool operator==(const ReportKey&) const = default;
  };
  std::optional<ReportKey> report_key_;
  Failure failure_ = Failure::none;
  LifeEstimate life_;
  RollingSpectrum spectrum_;
  TwinCounters counters_;
  double first_break_load_ = 0.0;
  double max_p_ = 0.0;
  bool max_p_configured_ = false;
};

}  // namespace peritwin::twin
