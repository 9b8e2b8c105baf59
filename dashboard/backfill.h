// peritwin-dashboard --results DIR: each detail's history from before the dashboard started, read
// from the daemon's results files (outputs/results_writer.h, /timeseries: one row per state) so a
// dashboard started late shows the whole curve.
#pragma once

#include <filesystem>
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

/// The history points of a results file, one per /timeseries row, in file order. Throws
/// (twin::ResultsError, h5::Error) when the file cannot be read.
std::vector<HistoryPoint> read_history_points(const std::filesystem::path& h5_path);

}  // namespace peritwin::dashboard
