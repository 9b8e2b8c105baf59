// The results of one detail for people (twin/io/results_writer.h, twin/io/damage_png.h):
// <output.directory>/<id>.h5 (time series: one row per applied state; damage snapshots every
// output.field_every_batches states and at shutdown) with <id>.xdmf next to it, and at shutdown
// (output.png) <id>-damage.png and <id>-crack-length.png. Output failures are logged and switch
// the outputs of that detail off; they never stop the twin.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>

#include "twin/io/results_writer.h"
#include "twin/model/twin.h"

namespace peritwin::twin {

/// The time-series row of the twin's current state.
TimeSeriesRow results_row(const Twin& twin);

class DetailOutputs {
 public:
  /// Opens or creates the results file. Resuming at state_seq k drops rows and snapshots after
  /// k − 1 and records state k again (a fresh start drops everything).
  explicit DetailOutputs(const Twin& twin);
  /// After every applied batch.
  void record(const Twin& twin);
  /// Last snapshot, close, PNGs.
  void finish(const Twin& twin);

  [[nodiscard]] std::filesystem::path h5_path() const { return h5_path_; }
  [[nodiscard]] std::filesystem::path damage_png() const;
  [[nodiscard]] std::filesystem::path crack_png() const;

 private:
  void snapshot(const Twin& twin);
  void disable(const char* what, const std::exception& e);

  std::filesystem::path dir_;
  std::filesystem::path h5_path_;
  std::string id_;
  std::unique_ptr<ResultsWriter> writer_;
  std::int64_t last_snapshot_seq_ = -1;
};

}  // namespace peritwin::twin
