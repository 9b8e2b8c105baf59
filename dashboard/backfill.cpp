#include "dashboard/backfill.h"

#include <algorithm>
#include <system_error>

#include "messages/channels.h"
#include "outputs/results_writer.h"

namespace peritwin::dashboard {

std::vector<ResultsFile> find_results_files(const std::filesystem::path& dir) {
  std::vector<ResultsFile> out;
  auto consider = [&out](const std::filesystem::directory_entry& e) {
    std::error_code ec;
    if (!e.is_regular_file(ec) || e.path().extension() != ".h5") return;
    const std::string id = e.path().stem().string();
    if (messages::is_valid_detail_id(id)) out.push_back({id, e.path()});
  };
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    consider(e);
    std::error_code sub_ec;
    if (!e.is_directory(sub_ec)) continue;
    for (const auto& f : std::filesystem::directory_iterator(e.path(), sub_ec)) consider(f);
  }
  std::sort(out.begin(), out.end(),
            [](const ResultsFile& a, const ResultsFile& b) { return a.path < b.path; });
  return out;
}

std::vector<HistoryPoint> read_history_points(const std::filesystem::path& h5_path) {
  std::vector<HistoryPoint> out;
  for (const auto& row : outputs::read_time_series(h5_path)) {
    out.push_back({row.state_seq, row.total_cycles, row.crack_length_m, row.remaining_cycles,
                   row.remaining_low, row.remaining_high});
  }
  return out;
}

}  // namespace peritwin::dashboard
