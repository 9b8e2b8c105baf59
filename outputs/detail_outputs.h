// The results of one detail for people (outputs/results_writer.h, outputs/damage_png.h):
// <output.directory>/<id>.h5 (time series: one row per applied state; node-field snapshots every
// output.field_every_batches states and at shutdown) with <id>.xdmf next to it, and, with
// output.png, <id>-damage.png (the annotated damage map) and <id>-crack-length.png (the a-N plot
// with the remaining-life estimates), rewritten at every snapshot and at shutdown. Output failures
// are logged and switch the outputs of that detail off; they never stop the twin. The daemon and
// peritwin-replay --in-process --results both write through this class.
//
// With the learning ensemble ([detail.uncertainty]), every recorded state also gets a row of
// /ensemble (its percentiles of the end of life and the remaining cycles, P(end of life within the
// horizon), the effective sample size, each parameter's posterior median and CoV) and every
// observation taken in a row of /observations (results_writer.h has the layout).
//
// With strain gauges ([[detail.gauge]], docs/gauges.md), /gauges describes them (its attributes)
// and every recorded state gets a row of it: each gauge's influence coefficients for the state's
// bond state and the compliance residual of the last gauge observation with its σ; a gauge
// observation at the same state adds a row when it changed a residual. The damage map draws
// each gauge as a short bar along its direction (at least 3 dx long) with its id beside it.
//
// A snapshot holds, per node: the damage φ; the displacement at the load of the state's last
// block (P_max, α; before any block, the largest P_max of the life reference spectrum, else 1 N:
// the step group's attributes load_p_max_n and load_alpha_rad say which), and, when the detail
// has more than the constant load basis, each loaded basis's part at P_max (displacement_cos,
// displacement_sin, displacement_constant); the Lagrange strain of that displacement (004 Eq. 6-7,
// solver/statics/pd_strain.h) as a tensor, its dilatation tr E and its larger principal value.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "outputs/damage_png.h"
#include "outputs/results_writer.h"
#include "twin/twin.h"

namespace peritwin::outputs {

/// The time-series row of the twin's current state.
TimeSeriesRow results_row(const twin::Twin& twin);

/// The load a snapshot's displacement and strain belong to (see the file comment).
core::LoadBlock snapshot_load(const twin::Twin& twin);

/// The node fields of a snapshot beside the damage (see the file comment).
SnapshotFields snapshot_fields(const twin::Twin& twin);

/// The row of /gauges of the twin's current state (results_writer.h has the columns); empty
/// columns for a detail without gauges.
NamedRow gauge_row(const twin::Twin& twin);

class DetailOutputs {
 public:
  /// Opens or creates the results file. Resuming at state_seq k drops rows and snapshots after
  /// k − 1 and records state k again (a fresh start drops everything).
  explicit DetailOutputs(const twin::Twin& twin);
  /// After every applied batch (a row of the time series; with the ensemble, a row of
  /// /ensemble and the new observations; with gauges, a row of /gauges), and after an
  /// observation or a new ensemble estimate at the same state (no new time-series row: the
  /// ensemble's, and the gauges' when their residuals changed).
  void record(const twin::Twin& twin);
  /// Last snapshot, close, pictures.
  void finish(const twin::Twin& twin);

  [[nodiscard]] std::filesystem::path h5_path() const { return h5_path_; }
  [[nodiscard]] std::filesystem::path damage_png() const;
  [[nodiscard]] std::filesystem::path crack_png() const;

 private:
  void snapshot(const twin::Twin& twin);
  /// The learning ensemble's row of /ensemble and the observations not yet in /observations.
  void record_ensemble(const twin::Twin& twin);
  /// The gauges' row of /gauges; at the state of the last one written, only when a residual
  /// changed (a gauge observation). No-op without gauges.
  void record_gauges(const twin::Twin& twin, bool same_state);
  void pictures(const twin::Twin& twin);
  /// At the initial state over a file with later states: keeps that file as <id>.run<N>.h5.
  void keep_an_earlier_history(const twin::Twin& twin);
  void disable(const char* what, const std::exception& e);

  std::filesystem::path dir_;
  std::filesystem::path h5_path_;
  std::string id_;
  std::unique_ptr<ResultsWriter> writer_;
  std::int64_t last_snapshot_seq_ = -1;
  /// The residual columns of the last row of /gauges written by this object (empty: none).
  std::vector<double> last_gauge_residuals_;
  /// What the pictures need of the rows written, kept compact (24 bytes a row, the estimates
  /// once each, a tip track point only when the tip moved): a daemon runs for years of batches.
  struct PictureHistory {
    std::vector<std::int64_t> state_seq;  ///< ascending, one per row
    std::vector<double> cycles, lengths_m;
    std::vector<LifePrediction> predictions;
    std::int64_t last_estimate_seq = -1;
    std::map<std::pair<std::int64_t, int>, std::vector<MapPoint>> tip_tracks;  ///< (crack, tip)
    void add(const TimeSeriesRow& row);
  };
  PictureHistory history_;
};

}  // namespace peritwin::outputs
