// peritwin-dashboard --results DIR: each detail's history from before the dashboard started, read
// from the daemon's results files (outputs/results_writer.h, /timeseries: one row per state) so a
// dashboard started late shows the whole curve.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "dashboard/store.h"

namespace peritwin::dashboard {

/// A results file of one detail: <DIR>/<id>.h5 or <DIR>/<anything>/<id>.h5 (the daemon's
/// `output.directory` per detail, "results/<id>" by default), the detail id its file name's stem.
struct ResultsFile {
  std::string detail_id;
  std::filesystem::path path;
};

/// The results files under `dir` (itself and one level of sub-directories), sorted by path;
/// names whose stem is no valid detail id are skipped.
std::vector<ResultsFile> find_results_files(const std::filesystem::path& dir);

/// What a late dashboard takes from a results file: the history, the last state (the last
/// /timeseries row) and the newest damage snapshot with the file's grid.
struct ResultsContent {
  std::vector<HistoryPoint> points;  ///< one per row, in file order
  std::optional<FileState> last;     ///< none in a file without rows
  std::optional<Field> snapshot;     ///< none in a file without snapshots (or mesh)
};

/// Reads all of the above. Remaining life is counted down from each row's estimate state
/// (remaining_state_seq, whose row gives its cycles) as the live store does; a row whose
/// estimate state has no row (or is -1: a layout-1 or -2 file) keeps the estimate as written.
/// Throws (outputs::ResultsError, outputs::h5::Error) when the file cannot be read.
ResultsContent read_results(const std::filesystem::path& h5_path);

/// read_results(h5_path).points.
std::vector<HistoryPoint> read_history_points(const std::filesystem::path& h5_path);

}  // namespace peritwin::dashboard
