#include "twin/io/detail_outputs.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <system_error>

#include "twin/io/damage_png.h"

namespace peritwin::twin {

TimeSeriesRow results_row(const Twin& twin) {
  TimeSeriesRow row;
  row.state_seq = twin.state_seq();
  row.total_cycles = twin.engine().total_cycles();
  row.broken_bonds = twin.broken_bonds();
  const CrackReport& r = twin.cracks();
  if (!r.cracks.empty()) {
    const FoundCrack& c = r.cracks.front().crack;
    row.crack_length_m = c.length;
    row.crack_projected_length_m = c.projected_length;
    row.tip_x = c.tips[0].position.x;
    row.tip_y = c.tips[0].position.y;
    row.kink_angle_rad = c.kink_angle;
  }
  row.crack_count = static_cast<std::int64_t>(r.cracks.size());
  for (const auto& rc : r.cracks) {
    for (std::size_t t = 0; t < rc.crack.tips.size(); ++t) {
      const auto& tip = rc.crack.tips[t];
      CrackRow c;
      c.state_seq = row.state_seq;
      c.crack_id = rc.crack.id;
      c.origin_kind = static_cast<std::int64_t>(rc.crack.origin);
      c.k_status = static_cast<std::int64_t>(rc.k[t].status);
      c.length_m = rc.crack.length;
      c.projected_length_m = rc.crack.projected_length;
      c.tip_x = tip.position.x;
      c.tip_y = tip.position.y;
      c.tip_angle_rad = std::atan2(tip.direction.y, tip.direction.x);
      c.k_i = rc.k[t].k_i;
      c.k_ii = rc.k[t].k_ii;
      row.cracks.push_back(c);
    }
  }
  row.k_i = r.k_i;
  row.k_ii = r.k_ii;
  row.remaining_cycles = twin.life().central;
  row.remaining_low = twin.life().low;
  row.remaining_high = twin.life().high;
  return row;
}

namespace {
std::unique_ptr<ResultsWriter> open_writer(const std::filesystem::path& h5, const Twin& twin) {
  ResultsOptions options;
  options.detail = twin.detail_id();
  auto writer = std::make_unique<ResultsWriter>(h5, options);
  std::vector<double> x, y;
  for (const auto& p : twin.model().disc().position) {
    x.push_back(p.x);
    y.push_back(p.y);
  }
  writer->write_mesh(x, y);
  return writer;
}
}  // namespace

DetailOutputs::DetailOutputs(const Twin& twin) : id_(twin.detail_id()) {
  const auto& config = twin.model().config();
  dir_ = config.output.directory;
  h5_path_ = dir_ / (id_ + ".h5");
  try {
    std::filesystem::create_directories(dir_);
    try {
      writer_ = open_writer(h5_path_, twin);
    } catch (const std::exception& e) {
      // Another mesh (the config changed) or a damaged file: keep it aside, start a new one.
      writer_.reset();
      if (!std::filesystem::exists(h5_path_)) throw;
      const auto aside = std::filesystem::path(h5_path_.string() + ".old");
      spdlog::warn("[{}] {}: {}; moved to {}", id_, h5_path_.string(), e.what(), aside.string());
      std::filesystem::rename(h5_path_, aside);
      writer_ = open_writer(h5_path_, twin);
    }
    writer_->rewind_to(twin.state_seq() - 1);
    for (const auto& s : writer_->snapshots()) last_snapshot_seq_ = s.state_seq;
    writer_->append(results_row(twin));
    const auto every = config.output.field_every_batches;
    if (every > 0 && twin.state_seq() % every == 0) snapshot(twin);
    spdlog::info("[{}] results: {} ({} rows)", id_, h5_path_.string(), writer_->rows());
  } catch (const std::exception& e) {
    disable("cannot open the results file", e);
  }
}

void DetailOutputs::disable(const char* what, const std::exception& e) {
  spdlog::error("[{}] {} {}: {}; results of this detail are off from now on", id_, what,
                h5_path_.string(), e.what());
  writer_.reset();
}

void DetailOutputs::snapshot(const Twin& twin) {
  writer_->write_snapshot(twin.state_seq(), twin.engine().total_cycles(),
                          std::span<const double>(twin.engine().node_damage()));
  last_snapshot_seq_ = twin.state_seq();
}

void DetailOutputs::record(const Twin& twin) {
  if (!writer_) return;
  try {
    writer_->append(results_row(twin));
    const auto every = twin.model().config().output.field_every_batches;
    if (every > 0 && twin.state_seq() % every == 0) snapshot(twin);
  } catch (const std::exception& e) {
    disable("cannot write", e);
  }
}

std::filesystem::path DetailOutputs::damage_png() const { return dir_ / (id_ + "-damage.png"); }
std::filesystem::path DetailOutputs::crack_png() const {
  return dir_ / (id_ + "-crack-length.png");
}

void DetailOutputs::finish(const Twin& twin) {
  if (!writer_) return;
  try {
    if (last_snapshot_seq_ != twin.state_seq()) snapshot(twin);
    writer_->close();
    writer_.reset();
  } catch (const std::exception& e) {
    disable("cannot finish", e);
    return;
  }
  if (!twin.model().config().output.png) return;
  try {
    const auto& disc = twin.model().disc();
    std::vector<double> x, y;
    for (const auto& p : disc.position) {
      x.push_back(p.x);
      y.push_back(p.y);
    }
    write_damage_png(damage_png(), x, y, twin.engine().node_damage(), disc.dx);
    std::vector<double> cycles, lengths;
    for (const auto& row : read_time_series(h5_path_)) {
      cycles.push_back(static_cast<double>(row.total_cycles));
      lengths.push_back(row.crack_length_m);
    }
    write_crack_length_png(crack_png(), cycles, lengths);
    spdlog::info("[{}] pictures: {} {}", id_, damage_png().string(), crack_png().string());
  } catch (const std::exception& e) {
    spdlog::error("[{}] cannot write the PNG pictures: {}", id_, e.what());
  }
}

}  // namespace peritwin::twin
