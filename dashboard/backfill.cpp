#include "dashboard/backfill.h"

#include <algorithm>
#include <cmath>
#include <system_error>

#include "messages/channels.h"
#include "outputs/h5_file.h"
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

ResultsContent read_results(const std::filesystem::path& h5_path) {
  ResultsContent out;
  const auto rows = outputs::read_time_series(h5_path);
  // Rows are in state order: the cycles of an estimate's state by binary search on state_seq.
  const auto cycles_of = [&rows](std::int64_t state_seq) -> std::optional<std::int64_t> {
    if (state_seq < 0) return std::nullopt;
    const auto it = std::lower_bound(
        rows.begin(), rows.end(), state_seq,
        [](const outputs::TimeSeriesRow& r, std::int64_t seq) { return r.state_seq < seq; });
    if (it == rows.end() || it->state_seq != state_seq) return std::nullopt;
    return it->total_cycles;
  };
  out.points.reserve(rows.size());
  for (const auto& row : rows) {
    HistoryPoint p{row.state_seq,        row.total_cycles,  row.crack_length_m,
                   row.remaining_cycles, row.remaining_low, row.remaining_high};
    if (const auto at = cycles_of(row.remaining_state_seq); at && !std::isnan(p.remaining)) {
      const Countdown c =
          count_down(row.remaining_cycles, row.remaining_low, row.remaining_high, *at, p.cycles);
      p.remaining = c.remaining;
      p.low = c.low;
      p.high = c.high;
    }
    out.points.push_back(p);
  }
  if (!rows.empty()) {
    const auto& r = rows.back();
    FileState f;
    f.state_seq = r.state_seq;
    f.cycles = r.total_cycles;
    f.broken_bonds = r.broken_bonds;
    f.crack_count = r.crack_count;
    f.crack_length_m = r.crack_length_m;
    f.k_i = r.k_i;
    f.k_ii = r.k_ii;
    f.tip_x = r.tip_x;
    f.tip_y = r.tip_y;
    f.remaining = r.remaining_cycles;
    f.low = r.remaining_low;
    f.high = r.remaining_high;
    f.remaining_state_seq = r.remaining_state_seq;
    f.estimate_cycles = cycles_of(r.remaining_state_seq);
    out.last = f;
  }
  const auto snapshots = outputs::read_snapshot_list(h5_path);
  if (!snapshots.empty()) {
    const auto& newest =
        *std::max_element(snapshots.begin(), snapshots.end(),
                          [](const auto& a, const auto& b) { return a.state_seq < b.state_seq; });
    const outputs::h5::File file(h5_path, outputs::h5::File::Mode::read_only, {false});
    if (file.exists("mesh/x") && file.exists("mesh/y")) {
      Field field;
      field.state_seq = newest.state_seq;
      field.damage = outputs::read_snapshot_damage(h5_path, newest);
      field.file_coordinates =
          mesh_coordinates_hash(file.read<double>("mesh/x"), file.read<double>("mesh/y"));
      // The card's max damage, when the snapshot is of the last row's state.
      if (out.last && out.last->state_seq == field.state_seq && !field.damage.empty()) {
        out.last->max_damage = *std::max_element(field.damage.begin(), field.damage.end());
      }
      out.snapshot = std::move(field);
    }
  }
  return out;
}

std::vector<HistoryPoint> read_history_points(const std::filesystem::path& h5_path) {
  return read_results(h5_path).points;
}

}  // namespace peritwin::dashboard
