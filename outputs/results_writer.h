// Results of one detail for people to look at: an HDF5 file with a time series appended row by
// row and damage-field snapshots, plus an XDMF file next to it so ParaView opens it directly.
// The HDF5 file is flushed after every row and snapshot; the XDMF file is rewritten atomically
// (temp file + rename) after every snapshot, so both are usable at any moment.
// Units: SI (m, rad, Pa·√m for K); cycles are counts.
//
// File layout (layout_version 3; a version-1 or -2 file is upgraded in place when opened for
// writing: version-1 rows get crack_count = -1, unknown, and no crack rows; the mesh gets
// /mesh/xyz and /mesh/vertices):
//   /                     attributes: format = "peritwin-results", layout_version = 3, detail
//   /timeseries/<column>  extendible 1-D, one element per row; attribute "units". Columns:
//                         state_seq, total_cycles, broken_bonds, crack_count,
//                         remaining_state_seq (the state the remaining-life estimate was
//                         computed on, -1 none; rows of a version-1 or -2 file: -1) (int64);
//                         crack_length_m, crack_projected_length_m, tip_x, tip_y, kink_angle_rad,
//                         k_i, k_ii (the main crack: the longest, first tip), remaining_cycles,
//                         remaining_low, remaining_high (float64)
//   /cracks/<column>      extendible 1-D, one element per crack tip per row (every crack of the
//                         state, in the STATE order); attribute "units". Columns: state_seq,
//                         crack_id, origin_kind (1 notch, 2 surface, 3 interior), k_status
//                         (crack_tip_t.K_*) (int64); length_m, projected_length_m, tip_x, tip_y,
//                         tip_angle_rad, k_i, k_ii (float64)
//   /mesh/x, /mesh/y      float64[node_count] node coordinates (m); /mesh attribute node_count
//   /mesh/xyz             float64[node_count][3] the same with z = 0: the XDMF geometry. ParaView
//                         5.11's default XDMF reader (Xdmf3ReaderS/T) crashes in
//                         vtkXdmf3DataSet::CopyShape on an X_Y geometry (two DataItems, what
//                         layouts 1-2 wrote; only the legacy XDMFReader read it) and reads XYZ.
//   /mesh/vertices        int64[node_count] 0, 1, ..., node_count − 1: the Polyvertex
//                         connectivity, given explicitly rather than left to each reader
//   /fields/step_<n>/damage  float32[node_count], n = 0, 1, 2, ... zero-padded to 6 digits;
//                         attributes state_seq, total_cycles (int64) on the dataset and its group
//   /fields/step_<n>/<field>  float64[node_count] or [node_count][components]: the snapshot's
//                         NodeFields (displacement, strain, ...); attribute "units"; the group
//                         carries the NodeFields' scalar attributes (the load they belong to)
//   /ensemble/<column>    (a detail with the learning ensemble, [detail.uncertainty]; issue 32)
//                         extendible 1-D, one element per recorded state; attribute "units".
//                         Columns: state_seq, total_cycles, estimate_cycle (the cycle count the
//                         particles' ends of life were last simulated at, -1 before any),
//                         observation_count, particles (int64); effective_sample_size,
//                         horizon_cycles, probability_within_horizon (NaN without a horizon),
//                         end_of_life_p<NN> and remaining_p<NN> for each configured percentile
//                         (p05, p50, p95 by default: the end-of-life cycle and the remaining
//                         cycles at it; +Inf beyond the simulated horizon, NaN before an
//                         estimate), <parameter>_median and <parameter>_cov for each parameter of
//                         the posterior (a2, load_scale) (float64). Group attribute
//                         "percentiles": the percentiles, comma-separated.
//   /observations/<column>  one element per observation the ensemble took in, in that order:
//                         index (0, 1, ...), state_seq (the state recorded when it was taken in),
//                         cycle (of the inspection), taken_at (the ensemble's cycle count then),
//                         kind (observation_t.KIND_*: 1 crack length, 2 no crack found,
//                         3 gauge compliance),
//                         origin_index (into the group attribute "origins", the origin names
//                         separated by newlines: "longest", a notch's name, ...), seq (the
//                         observation's seq from its source), resampled (0/1) (int64); length_m,
//                         sigma_m, pod_a50_m, pod_slope (NaN where they do not apply),
//                         predicted_median_m (the ensemble's weighted median crack at that cycle
//                         before it took it in), log_evidence, ess_before_resampling (float64).
//                         Group attribute "sources": the source ids, newline-separated, indexed
//                         by the column source_index (int64).
//   /gauges/<column>      (a detail with strain gauges, [[detail.gauge]]; issue 33,
//                         docs/gauges.md) extendible 1-D, one element per recorded state, and one
//                         more at the same state_seq after a gauge observation that changed a
//                         residual; attribute "units". Columns: state_seq, total_cycles, and per
//                         gauge <id>_in_a_row (gauge observations in a row beyond the alarm's
//                         bound, twin/gauges.h) (int64); <id>_per_constant, <id>_per_cos,
//                         <id>_per_sin (the influence coefficients of the state's bond state:
//                         strain per N of P of the constant, cos α and sin α load cases, "1/N";
//                         a gauge reads ε = P·(c0 + cos α·c1 + sin α·c2)), <id>_residual (the
//                         compliance residual of the last gauge observation, (m − m^X)/|m^X|)
//                         and <id>_sigma (its standard deviation) (NaN before an observation of
//                         the gauge) (float64). Group attributes, one element per gauge in the
//                         order of "ids" (the gauge ids, newline-separated): x_m, y_m (the
//                         centre of its measuring grid), angle_rad (its direction from +x),
//                         length_m (0: the nearest node), noise (one standard deviation of a
//                         reading, strain) (float64[n]); written when the file is opened
//                         (describe_gauges), a gauge of an earlier run kept with its columns.
//                         No /gauges for a detail without gauges.
//                         These three tables: a column that appears later (another percentile, a
//                         gauge added) has NaN (float64) or -1 (int64) in the rows before it;
//                         rewind_to drops their rows after the state like the time series'.
//   <name>.xdmf           XDMF 3: a temporal collection (Time = total_cycles) of Polyvertex grids
//                         (connectivity /mesh/vertices), Geometry XYZ from /mesh/xyz, node
//                         attributes "damage" and every NodeField (Scalar, Vector, Tensor6)
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace peritwin::outputs {

/// One crack tip of one state (the /cracks table). NaN means "not valid" (see k_status).
struct CrackRow {
  std::int64_t state_seq = 0;
  std::int64_t crack_id = 0;
  std::int64_t origin_kind = 0;  ///< 1 notch, 2 surface, 3 interior
  std::int64_t k_status = 0;     ///< crack_tip_t.K_*
  double length_m = 0.0;         ///< the crack's, along its path
  double projected_length_m = 0.0;
  double tip_x = 0.0;
  double tip_y = 0.0;
  double tip_angle_rad = 0.0;  ///< direction of growth at the tip
  double k_i = std::numeric_limits<double>::quiet_NaN();
  double k_ii = std::numeric_limits<double>::quiet_NaN();
};

/// One row of the time series. NaN means "not computed (yet)".
struct TimeSeriesRow {
  std::int64_t state_seq = 0;     ///< state sequence number the row belongs to
  std::int64_t total_cycles = 0;  ///< cycles applied since the start
  std::int64_t broken_bonds = 0;
  std::int64_t crack_count = 0;           ///< cracks found; -1 = unknown (rows of a version-1 file)
  double crack_length_m = 0.0;            ///< along the crack path
  double crack_projected_length_m = 0.0;  ///< projected, as the papers measure it
  double tip_x = std::numeric_limits<double>::quiet_NaN();  ///< crack tip (m)
  double tip_y = std::numeric_limits<double>::quiet_NaN();
  double kink_angle_rad = std::numeric_limits<double>::quiet_NaN();
  double k_i = std::numeric_limits<double>::quiet_NaN();   ///< Pa·√m
  double k_ii = std::numeric_limits<double>::quiet_NaN();  ///< Pa·√m
  double remaining_cycles = std::numeric_limits<double>::quiet_NaN();
  double remaining_low = std::numeric_limits<double>::quiet_NaN();
  double remaining_high = std::numeric_limits<double>::quiet_NaN();
  std::int64_t remaining_state_seq = -1;  ///< the state the estimate belongs to (-1: none)
  /// Every crack tip of the state (written to /cracks with this row's state_seq; not read back
  /// by read_time_series: see read_crack_rows).
  std::vector<CrackRow> cracks;
};

/// One row of a table of named columns (/ensemble, /observations): the row's int64 and float64
/// columns by name, and its string attributes' values (an index column "<name>_index" into the
/// group attribute "<name>s", a newline-separated list that grows as values appear). The
/// table's rows are kept by their "state_seq" column (rewind_to).
struct NamedRow {
  std::vector<std::pair<std::string, std::int64_t>> ints;
  std::vector<std::pair<std::string, double>> doubles;
  std::vector<std::pair<std::string, std::string>> strings;
  std::vector<std::pair<std::string, std::string>> units;  ///< column → units ("1" if absent)
};

/// A table of named columns as read back: int64 and float64 columns by name (all one length),
/// the string lists of the group's attributes ("origins", "sources") by name.
struct NamedTable {
  std::map<std::string, std::vector<std::int64_t>> ints;
  std::map<std::string, std::vector<double>> doubles;
  std::map<std::string, std::vector<std::string>> strings;
  std::map<std::string, std::string> attributes;  ///< the group's other string attributes
  /// The group's numeric attributes (e.g. /gauges' x_m), every element as double.
  std::map<std::string, std::vector<double>> numbers;
  [[nodiscard]] std::size_t rows() const;
};

/// A strain gauge as the results file describes it (the attributes of /gauges;
/// config::GaugeConfig).
struct GaugeInfo {
  std::string id;
  double x_m = 0.0, y_m = 0.0;  ///< centre of its measuring grid
  double angle_rad = 0.0;       ///< measuring direction from +x
  double length_m = 0.0;        ///< 0: the node nearest (x, y)
  double noise = 0.0;           ///< one standard deviation of a reading (strain)
  bool operator==(const GaugeInfo&) const = default;
};

/// One more per-node array of a snapshot, beside the damage.
struct NodeField {
  enum class Kind {
    scalar,   ///< 1 value per node
    vector,   ///< 3 per node: x, y, z
    tensor6,  ///< 6 per node, a symmetric tensor: xx, xy, xz, yy, yz, zz (XDMF's Tensor6 order)
  };
  std::string name;  ///< dataset and attribute name: letters, digits, '_'
  Kind kind = Kind::scalar;
  std::string units;
  std::vector<double> values;  ///< node-major: components() per node
  [[nodiscard]] std::size_t components() const;
};

/// A snapshot's fields beside the damage, and numbers that say what they are (stored as float64
/// attributes of the step group, e.g. the load P_max the displacement belongs to).
struct SnapshotFields {
  std::vector<NodeField> fields;
  std::vector<std::pair<std::string, double>> attributes;
};

struct ResultsOptions {
  std::string detail;           ///< stored as the root attribute "detail"
  int field_deflate_level = 4;  ///< damage snapshots: 0 = contiguous, 1..9 = shuffle + deflate
  /// HDF5 file locking on the results file. Off (default) lets ParaView open the file while the
  /// daemon writes it; one writer per file remains the caller's duty.
  bool file_locking = false;
};

/// Thrown for misuse (snapshot before mesh, wrong sizes, a mesh that differs from the stored one)
/// and for a file that is not a results file; HDF5 failures arrive as h5::Error.
class ResultsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SnapshotInfo {
  std::int64_t index = 0;  ///< n of /fields/step_<n>
  std::int64_t state_seq = 0;
  std::int64_t total_cycles = 0;
  /// The snapshot's NodeFields beside the damage (name and kind), in name order.
  std::vector<std::pair<std::string, NodeField::Kind>> fields;
  [[nodiscard]] std::string group() const;  ///< "/fields/step_<n>"
};

class ResultsWriter {
 public:
  /// Opens `h5_path` (…/<name>.h5) to continue it, or creates it. An existing file that HDF5
  /// cannot open is moved aside to <h5_path>.corrupt (see recovered_from()) and a new one is
  /// started; an HDF5 file that is not a results file is left alone (ResultsError). A row or
  /// snapshot half-written by a crash is dropped.
  explicit ResultsWriter(std::filesystem::path h5_path, ResultsOptions options = {});
  ~ResultsWriter();
  ResultsWriter(ResultsWriter&&) noexcept;
  ResultsWriter& operator=(ResultsWriter&&) noexcept;
  ResultsWriter(const ResultsWriter&) = delete;
  ResultsWriter& operator=(const ResultsWriter&) = delete;

  /// Node coordinates (m), written once; calling again with the same mesh is a no-op, with a
  /// different one an error.
  void write_mesh(std::span<const double> x, std::span<const double> y);
  void append(const TimeSeriesRow& row);
  /// Damage φ per node (stored as float32); needs the mesh. Rewrites the XDMF file.
  void write_snapshot(std::int64_t state_seq, std::int64_t total_cycles,
                      std::span<const float> damage, const SnapshotFields& extra = {});
  void write_snapshot(std::int64_t state_seq, std::int64_t total_cycles,
                      std::span<const double> damage, const SnapshotFields& extra = {});
  /// Appends a row to the table of named columns /<group> ("ensemble", "observations");
  /// `attributes` are set on the group (string attributes, e.g. "percentiles").
  void append_named(const std::string& group, const NamedRow& row,
                    const std::vector<std::pair<std::string, std::string>>& attributes = {});
  /// Rows of /<group> (0 when it does not exist).
  [[nodiscard]] std::uint64_t named_rows(const std::string& group) const;
  /// Describes the gauges in the attributes of /gauges (the table of named columns the gauges'
  /// rows go to): a gauge already described keeps its place and takes the new values, a new one
  /// is added after them, one described before and not in `gauges` stays (its columns hold the
  /// rows of an earlier run). Does nothing for no gauges.
  void describe_gauges(const std::vector<GaugeInfo>& gauges);
  /// Drops every row and snapshot with state_seq > `state_seq` (resume from a checkpoint).
  void rewind_to(std::int64_t state_seq);

  [[nodiscard]] std::uint64_t rows() const;
  /// The time series as written so far, with every row's crack rows (what read_time_series and
  /// read_crack_rows give, without opening the file a second time).
  [[nodiscard]] std::vector<TimeSeriesRow> read_rows() const;
  [[nodiscard]] const std::vector<SnapshotInfo>& snapshots() const;
  [[nodiscard]] std::size_t node_count() const;  ///< 0 until the mesh is written
  [[nodiscard]] const std::filesystem::path& h5_path() const;
  [[nodiscard]] const std::filesystem::path& xdmf_path() const;
  /// Where an unreadable existing file was moved to, if that happened.
  [[nodiscard]] const std::optional<std::filesystem::path>& recovered_from() const;

  /// Flushes and closes now (the destructor does it too, without throwing).
  void close();

  /// <dir>/<name>.xdmf for <dir>/<name>.h5.
  static std::filesystem::path xdmf_path_for(const std::filesystem::path& h5_path);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// --- reading a results file back (tools, tests) ------------------------------------------------

std::vector<TimeSeriesRow> read_time_series(const std::filesystem::path& h5_path);
std::vector<CrackRow> read_crack_rows(const std::filesystem::path& h5_path);
std::vector<SnapshotInfo> read_snapshot_list(const std::filesystem::path& h5_path);
std::vector<float> read_snapshot_damage(const std::filesystem::path& h5_path,
                                        const SnapshotInfo& snapshot);
/// A table of named columns (/ensemble, /observations); empty when the file has none.
NamedTable read_named_table(const std::filesystem::path& h5_path, const std::string& group);
/// The gauges /gauges describes (ResultsWriter::describe_gauges), in its order; empty without.
std::vector<GaugeInfo> read_gauges(const std::filesystem::path& h5_path);
/// A NodeField of a snapshot (`name` as written), node-major; empty when the snapshot has none.
std::vector<double> read_snapshot_field(const std::filesystem::path& h5_path,
                                        const SnapshotInfo& snapshot, const std::string& name);

}  // namespace peritwin::outputs
