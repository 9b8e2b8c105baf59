#include "outputs/results_writer.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <sstream>

#include "outputs/checkpoint_io.h"
#include "outputs/h5_file.h"

namespace peritwin::outputs {

namespace {

constexpr const char* kFormat = "peritwin-results";
constexpr std::int64_t kLayoutVersion = 3;

template <class Row>
struct IntColumn {
  const char* name;
  std::int64_t Row::*member;
  const char* units;
  std::int64_t fill = 0;  ///< the value of rows written before the column existed
};
template <class Row>
struct DoubleColumn {
  const char* name;
  double Row::*member;
  const char* units;
};

constexpr std::array<IntColumn<TimeSeriesRow>, 5> kIntColumns{{
    {"state_seq", &TimeSeriesRow::state_seq, "1"},
    {"total_cycles", &TimeSeriesRow::total_cycles, "cycles"},
    {"broken_bonds", &TimeSeriesRow::broken_bonds, "1"},
    {"crack_count", &TimeSeriesRow::crack_count, "1", -1},
    {"remaining_state_seq", &TimeSeriesRow::remaining_state_seq, "1", -1},
}};
constexpr std::array<IntColumn<CrackRow>, 4> kCrackIntColumns{{
    {"state_seq", &CrackRow::state_seq, "1"},
    {"crack_id", &CrackRow::crack_id, "1"},
    {"origin_kind", &CrackRow::origin_kind, "1"},
    {"k_status", &CrackRow::k_status, "1"},
}};
constexpr std::array<DoubleColumn<CrackRow>, 7> kCrackDoubleColumns{{
    {"length_m", &CrackRow::length_m, "m"},
    {"projected_length_m", &CrackRow::projected_length_m, "m"},
    {"tip_x", &CrackRow::tip_x, "m"},
    {"tip_y", &CrackRow::tip_y, "m"},
    {"tip_angle_rad", &CrackRow::tip_angle_rad, "rad"},
    {"k_i", &CrackRow::k_i, "Pa*m^0.5"},
    {"k_ii", &CrackRow::k_ii, "Pa*m^0.5"},
}};
constexpr std::array<DoubleColumn<TimeSeriesRow>, 10> kDoubleColumns{{
    {"crack_length_m", &TimeSeriesRow::crack_length_m, "m"},
    {"crack_projected_length_m", &TimeSeriesRow::crack_projected_length_m, "m"},
    {"tip_x", &TimeSeriesRow::tip_x, "m"},
    {"tip_y", &TimeSeriesRow::tip_y, "m"},
    {"kink_angle_rad", &TimeSeriesRow::kink_angle_rad, "rad"},
    {"k_i", &TimeSeriesRow::k_i, "Pa*m^0.5"},
    {"k_ii", &TimeSeriesRow::k_ii, "Pa*m^0.5"},
    {"remaining_cycles", &TimeSeriesRow::remaining_cycles, "cycles"},
    {"remaining_low", &TimeSeriesRow::remaining_low, "cycles"},
    {"remaining_high", &TimeSeriesRow::remaining_high, "cycles"},
}};

/// A column table's open datasets: its int columns, then its double columns.
struct TableColumns {
  std::vector<h5::Dataset> ints;
  std::vector<h5::Dataset> doubles;
  /// Rows every column holds (a crash between the appends of one row leaves some longer).
  [[nodiscard]] std::uint64_t shortest() const {
    std::uint64_t n = std::numeric_limits<std::uint64_t>::max();
    for (const auto& ds : ints) n = std::min(n, ds.size());
    for (const auto& ds : doubles) n = std::min(n, ds.size());
    return n;
  }
  /// Cuts every column to n rows.
  void resize(std::uint64_t n) {
    for (auto& ds : ints) {
      if (ds.size() != n) ds.resize(n);
    }
    for (auto& ds : doubles) {
      if (ds.size() != n) ds.resize(n);
    }
  }
  template <class Row, std::size_t NI, std::size_t ND>
  void append(const Row& row, const std::array<IntColumn<Row>, NI>& int_columns,
              const std::array<DoubleColumn<Row>, ND>& double_columns) {
    for (std::size_t i = 0; i < NI; ++i) ints[i].append(row.*(int_columns[i].member));
    for (std::size_t i = 0; i < ND; ++i) doubles[i].append(row.*(double_columns[i].member));
  }
  void clear() {
    ints.clear();
    doubles.clear();
  }
};

std::string step_name(std::int64_t index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "step_%06lld", static_cast<long long>(index));
  return buf;
}

/// index of "step_<digits>", or -1.
std::int64_t parse_step(const std::string& name) {
  if (name.rfind("step_", 0) != 0 || name.size() == 5) return -1;
  std::int64_t v = 0;
  for (std::size_t i = 5; i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9') return -1;
    v = v * 10 + (name[i] - '0');
  }
  return v;
}

std::string xml_escape(std::string_view s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

/// XDMF AttributeType of a NodeField kind, also stored as the dataset's "kind" attribute.
const char* kind_name(NodeField::Kind kind) {
  switch (kind) {
    case NodeField::Kind::vector:
      return "Vector";
    case NodeField::Kind::tensor6:
      return "Tensor6";
    case NodeField::Kind::scalar:
      break;
  }
  return "Scalar";
}

std::optional<NodeField::Kind> kind_from_name(const std::string& name) {
  for (const auto kind :
       {NodeField::Kind::scalar, NodeField::Kind::vector, NodeField::Kind::tensor6}) {
    if (name == kind_name(kind)) return kind;
  }
  return std::nullopt;
}

std::size_t components_of(NodeField::Kind kind) {
  switch (kind) {
    case NodeField::Kind::vector:
      return 3;
    case NodeField::Kind::tensor6:
      return 6;
    case NodeField::Kind::scalar:
      break;
  }
  return 1;
}

bool valid_field_name(const std::string& name) {
  return !name.empty() && name != "damage" && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

void check_format(const h5::File& file) {
  if (!file.has_attribute("format") || file.attribute_string("format") != kFormat) {
    throw ResultsError("'" + file.file_name() + "' is not a peritwin results file");
  }
  const std::int64_t layout = file.attribute_int64("layout_version");
  if (layout < 1 || layout > kLayoutVersion) {
    throw ResultsError("'" + file.file_name() + "' has results layout_version " +
                       std::to_string(layout) + "; this build reads " +
                       std::to_string(kLayoutVersion));
  }
}

/// Snapshots whose dataset and attributes are complete, by index; with `drop_partial`, removes
/// the step groups a crash left incomplete.
std::vector<SnapshotInfo> scan_snapshots(h5::Group& root, bool drop_partial) {
  std::vector<SnapshotInfo> out;
  if (!root.exists("fields")) return out;
  h5::Group fields = root.open_group("fields");
  for (const auto& name : fields.children()) {
    const std::int64_t index = parse_step(name);
    if (index < 0) continue;
    bool complete = fields.exists(name + "/damage");
    if (complete) {
      const h5::Dataset ds = fields.open_dataset(name + "/damage");
      complete = ds.has_attribute("state_seq") && ds.has_attribute("total_cycles");
      if (complete) {
        SnapshotInfo info{
            index, ds.attribute_int64("state_seq"), ds.attribute_int64("total_cycles"), {}};
        const h5::Group step = fields.open_group(name);
        for (const auto& field : step.children()) {
          if (field == "damage") continue;
          const h5::Dataset f = step.open_dataset(field);
          if (!f.has_attribute("kind")) continue;
          const auto kind = kind_from_name(f.attribute_string("kind"));
          if (kind) info.fields.emplace_back(field, *kind);
        }
        out.push_back(std::move(info));
      }
    }
    if (!complete && drop_partial) fields.remove(name);
  }
  std::sort(out.begin(), out.end(),
            [](const SnapshotInfo& a, const SnapshotInfo& b) { return a.index < b.index; });
  return out;
}

}  // namespace

namespace {
/// /mesh/xyz and /mesh/vertices from the node coordinates (see the layout in the header).
void write_mesh_geometry(h5::File& file, std::span<const double> x, std::span<const double> y) {
  std::vector<double> xyz(3 * x.size(), 0.0);
  std::vector<std::int64_t> vertices(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    xyz[3 * i] = x[i];
    xyz[3 * i + 1] = y[i];
    vertices[i] = static_cast<std::int64_t>(i);
  }
  h5::Group mesh = file.require_group("mesh");
  mesh.write<double>("xyz", std::span<const double>(xyz), {.columns = 3});
  mesh.write<std::int64_t>("vertices", std::span<const std::int64_t>(vertices));
}
}  // namespace

std::string SnapshotInfo::group() const { return "/fields/" + step_name(index); }

std::size_t NodeField::components() const { return components_of(kind); }

/// The named-column tables (/ensemble, /observations, /gauges).
constexpr std::array<const char*, 3> kNamedTables{"ensemble", "observations", "gauges"};

/// The numeric attributes of /gauges, one element per id of its attribute "ids".
constexpr std::array<std::pair<const char*, double GaugeInfo::*>, 5> kGaugeAttributes{{
    {"x_m", &GaugeInfo::x_m},
    {"y_m", &GaugeInfo::y_m},
    {"angle_rad", &GaugeInfo::angle_rad},
    {"length_m", &GaugeInfo::length_m},
    {"noise", &GaugeInfo::noise},
}};

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> out;
  if (text.empty()) return out;
  std::size_t start = 0;
  for (;;) {
    const auto end = text.find('\n', start);
    out.push_back(text.substr(start, end - start));
    if (end == std::string::npos) return out;
    start = end + 1;
  }
}

bool has_attribute(const h5::Object& o, const std::string& name) {
  const auto names = o.attribute_names();
  return std::find(names.begin(), names.end(), name) != names.end();
}

/// The gauges a /gauges group describes (its attributes), in the order of "ids".
std::vector<GaugeInfo> described_gauges(const h5::Group& g) {
  std::vector<GaugeInfo> out;
  if (!has_attribute(g, "ids")) return out;
  for (auto& id : split_lines(g.attribute_string("ids"))) {
    GaugeInfo info;
    info.id = std::move(id);
    out.push_back(std::move(info));
  }
  for (const auto& [name, member] : kGaugeAttributes) {
    if (!has_attribute(g, name)) continue;
    const auto values = g.attribute_doubles(name);
    for (std::size_t k = 0; k < std::min(values.size(), out.size()); ++k)
      out[k].*member = values[k];
  }
  return out;
}

/// Rows of a named-column table: its shortest column (a crash between the appends of one row
/// leaves some longer).
std::uint64_t named_table_rows(const h5::Group& g) {
  std::uint64_t n = std::numeric_limits<std::uint64_t>::max();
  for (const auto& name : g.children()) n = std::min(n, g.open_dataset(name).size());
  return n == std::numeric_limits<std::uint64_t>::max() ? 0 : n;
}

/// Appends the fill of its type (-1 or NaN) to `ds` until it holds n elements.
void fill_to(h5::Dataset& ds, std::uint64_t n) {
  while (ds.size() < n) {
    if (ds.element_type() == h5::ElementType::i64) {
      ds.append(std::int64_t{-1});
    } else {
      ds.append(std::numeric_limits<double>::quiet_NaN());
    }
  }
}

struct ResultsWriter::Impl {
  std::filesystem::path h5_path;
  std::filesystem::path xdmf_path;
  ResultsOptions options;
  std::optional<std::filesystem::path> recovered_from;
  h5::File file;
  TableColumns series;  ///< /timeseries
  TableColumns cracks;  ///< /cracks
  std::uint64_t rows = 0;
  std::size_t nodes = 0;
  std::vector<SnapshotInfo> snapshots;

  void open_or_create();
  void require_open(const char* what) const {
    if (!file.is_open()) throw ResultsError(std::string(what) + " after close()");
  }
  void open_columns();
  /// Drops the crack rows after the first `limit` and those of states after `state_seq`.
  void trim_cracks_after(std::int64_t state_seq, std::uint64_t limit);
  void write_xdmf() const;
  [[nodiscard]] std::string xdmf_grid(std::string_view name, const SnapshotInfo* snapshot) const;
};

void ResultsWriter::Impl::open_or_create() {
  const h5::File::Options fopts{options.file_locking};
  if (std::filesystem::exists(h5_path)) {
    try {
      file = h5::File(h5_path, h5::File::Mode::read_write, fopts);
    } catch (const h5::Error& e) {
      // Not ours to move aside: something that is not a file, no permission, or a lock held
      // by another writer. Anything else is a file a crash left unreadable.
      const std::string why = e.what();
      if (!std::filesystem::is_regular_file(h5_path) ||
          ::access(h5_path.c_str(), R_OK | W_OK) != 0 || why.find("to lock") != std::string::npos) {
        throw;
      }
      std::filesystem::path aside = h5_path;
      aside += ".corrupt";
      std::filesystem::rename(h5_path, aside);
      recovered_from = aside;
    }
  }
  if (file.is_open()) {
    check_format(file);
  } else {
    file = h5::File(h5_path, h5::File::Mode::create_exclusive, fopts);
    file.set_attribute("format", std::string_view(kFormat));
    file.set_attribute("layout_version", kLayoutVersion);
    file.set_attribute("detail", options.detail);
  }
  open_columns();
  if (file.attribute_int64("layout_version") != kLayoutVersion) {
    file.set_attribute("layout_version", kLayoutVersion);  // upgraded by open_columns
  }
  if (file.exists("mesh/x")) {
    nodes = static_cast<std::size_t>(file.open_dataset("mesh/x").size());
    if (!file.exists("mesh/xyz")) {  // a layout 1 or 2 file
      write_mesh_geometry(file, file.read<double>("mesh/x"), file.read<double>("mesh/y"));
    }
  }
  snapshots = scan_snapshots(file, true);
  file.flush();
  if (nodes > 0) write_xdmf();
}

void ResultsWriter::Impl::open_columns() {
  auto open = [](h5::Group& g, const char* name, const char* units, auto tag) {
    using T = decltype(tag);
    if (g.exists(name)) return g.open_dataset(name);
    h5::Dataset ds = g.create_extendible<T>(name, 1024);
    ds.set_attribute("units", std::string_view(units));
    return ds;
  };
  h5::Group ts = file.require_group("timeseries");
  series.clear();
  for (const auto& c : kIntColumns) {
    const bool existed = ts.exists(c.name);
    series.ints.push_back(open(ts, c.name, c.units, std::int64_t{}));
    if (!existed && c.fill != 0) {  // a column new in this layout: the old rows get `fill`
      const std::uint64_t old_rows = ts.open_dataset(kIntColumns[0].name).size();
      for (std::uint64_t i = 0; i < old_rows; ++i) series.ints.back().append(c.fill);
    }
  }
  for (const auto& c : kDoubleColumns)
    series.doubles.push_back(open(ts, c.name, c.units, double{}));
  // A crash between the appends of one row leaves columns of different lengths: drop the tail.
  rows = series.shortest();
  series.resize(rows);
  // The crack rows: equal lengths, and none of a row the time series does not hold (a crash
  // after a row's crack rows and before the row).
  h5::Group cr = file.require_group("cracks");
  cracks.clear();
  for (const auto& c : kCrackIntColumns) {
    cracks.ints.push_back(open(cr, c.name, c.units, std::int64_t{}));
  }
  for (const auto& c : kCrackDoubleColumns) {
    cracks.doubles.push_back(open(cr, c.name, c.units, double{}));
  }
  const std::int64_t last_seq =
      rows == 0 ? -1
                : series.ints.front().read<std::int64_t>().at(static_cast<std::size_t>(rows - 1));
  trim_cracks_after(last_seq, cracks.shortest());
}

void ResultsWriter::Impl::trim_cracks_after(std::int64_t state_seq, std::uint64_t limit) {
  const auto seqs = cracks.ints.front().read<std::int64_t>();
  std::uint64_t keep = std::min<std::uint64_t>(limit, seqs.size());
  while (keep > 0 && seqs[static_cast<std::size_t>(keep - 1)] > state_seq) --keep;
  cracks.resize(keep);
}

std::string ResultsWriter::Impl::xdmf_grid(std::string_view name,
                                           const SnapshotInfo* snapshot) const {
  const std::string h5 = xml_escape(h5_path.filename().string());
  const std::string n = std::to_string(nodes);
  std::ostringstream g;
  g << "      <Grid Name=\"" << name << "\" GridType=\"Uniform\">\n";
  if (snapshot != nullptr) g << "        <Time Value=\"" << snapshot->total_cycles << "\"/>\n";
  // Geometry XYZ, not X_Y: ParaView 5.11's Xdmf3 reader crashes on X_Y (see the header).
  g << "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n
    << "\" NodesPerElement=\"1\">\n"
    << "          <DataItem Dimensions=\"" << n
    << "\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">" << h5
    << ":/mesh/vertices</DataItem>\n"
    << "        </Topology>\n"
    << "        <Geometry GeometryType=\"XYZ\">\n"
    << "          <DataItem Dimensions=\"" << n
    << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5
    << ":/mesh/xyz</DataItem>\n"
    << "        </Geometry>\n";
  if (snapshot != nullptr) {
    auto attribute = [&](const std::string& field, const char* type, std::size_t components,
                         int precision) {
      g << "        <Attribute Name=\"" << field << "\" AttributeType=\"" << type
        << "\" Center=\"Node\">\n"
        << "          <DataItem Dimensions=\"" << n;
      if (components > 1) g << " " << components;
      g << "\" NumberType=\"Float\" Precision=\"" << precision << "\" Format=\"HDF\">" << h5 << ":"
        << snapshot->group() << "/" << field << "</DataItem>\n"
        << "        </Attribute>\n";
    };
    attribute("damage", "Scalar", 1, 4);
    for (const auto& [field, kind] : snapshot->fields) {
      attribute(field, kind_name(kind), components_of(kind), 8);
    }
  }
  g << "      </Grid>\n";
  return g.str();
}

void ResultsWriter::Impl::write_xdmf() const {
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n"
    << "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    << "<Xdmf Version=\"3.0\">\n"
    << "  <Domain>\n";
  const std::string detail = xml_escape(options.detail.empty() ? "detail" : options.detail);
  if (snapshots.empty()) {
    x << xdmf_grid(detail + " mesh", nullptr);
  } else {
    x << "    <Grid Name=\"" << detail
      << " damage\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (const auto& s : snapshots) x << xdmf_grid(step_name(s.index), &s);
    x << "    </Grid>\n";
  }
  x << "  </Domain>\n"
    << "</Xdmf>\n";
  write_file_atomically(xdmf_path, x.str());
}

ResultsWriter::ResultsWriter(std::filesystem::path h5_path, ResultsOptions options)
    : impl_(std::make_unique<Impl>()) {
  impl_->xdmf_path = xdmf_path_for(h5_path);
  impl_->h5_path = std::move(h5_path);
  impl_->options = std::move(options);
  impl_->open_or_create();
}

ResultsWriter::~ResultsWriter() {
  if (!impl_) return;
  try {
    close();
  } catch (...) {  // NOLINT(bugprone-empty-catch): a destructor must not throw
  }
}

ResultsWriter::ResultsWriter(ResultsWriter&&) noexcept = default;
ResultsWriter& ResultsWriter::operator=(ResultsWriter&&) noexcept = default;

void ResultsWriter::write_mesh(std::span<const double> x, std::span<const double> y) {
  impl_->require_open("write_mesh");
  if (x.size() != y.size() || x.empty()) {
    throw ResultsError("write_mesh: x and y must be non-empty and of equal size (got " +
                       std::to_string(x.size()) + " and " + std::to_string(y.size()) + ")");
  }
  h5::File& f = impl_->file;
  if (f.exists("mesh/x")) {
    const auto sx = f.read<double>("mesh/x");
    const auto sy = f.read<double>("mesh/y");
    if (!std::equal(x.begin(), x.end(), sx.begin(), sx.end()) ||
        !std::equal(y.begin(), y.end(), sy.begin(), sy.end())) {
      throw ResultsError("'" + impl_->h5_path.string() +
                         "' already holds a different mesh; start a new results file");
    }
    return;
  }
  {
    h5::Group mesh = f.require_group("mesh");
    mesh.write<double>("x", x);
    mesh.write<double>("y", y);
    mesh.set_attribute("node_count", static_cast<std::int64_t>(x.size()));
  }
  write_mesh_geometry(f, x, y);
  f.flush();
  impl_->nodes = x.size();
  impl_->write_xdmf();
}

void ResultsWriter::append(const TimeSeriesRow& row) {
  impl_->require_open("append");
  // The crack rows first: a crash before the row is appended leaves crack rows that the next
  // open drops (open_columns).
  for (CrackRow c : row.cracks) {
    c.state_seq = row.state_seq;
    impl_->cracks.append(c, kCrackIntColumns, kCrackDoubleColumns);
  }
  impl_->series.append(row, kIntColumns, kDoubleColumns);
  impl_->file.flush();
  ++impl_->rows;
}

void ResultsWriter::write_snapshot(std::int64_t state_seq, std::int64_t total_cycles,
                                   std::span<const double> damage, const SnapshotFields& extra) {
  std::vector<float> f(damage.size());
  std::transform(damage.begin(), damage.end(), f.begin(),
                 [](double d) { return static_cast<float>(d); });
  write_snapshot(state_seq, total_cycles, std::span<const float>(f), extra);
}

void ResultsWriter::write_snapshot(std::int64_t state_seq, std::int64_t total_cycles,
                                   std::span<const float> damage, const SnapshotFields& extra) {
  Impl& im = *impl_;
  im.require_open("write_snapshot");
  if (im.nodes == 0) throw ResultsError("write_snapshot before write_mesh");
  if (damage.size() != im.nodes) {
    throw ResultsError("write_snapshot: " + std::to_string(damage.size()) + " damage values for " +
                       std::to_string(im.nodes) + " nodes");
  }
  SnapshotInfo info{
      im.snapshots.empty() ? 0 : im.snapshots.back().index + 1, state_seq, total_cycles, {}};
  for (const auto& field : extra.fields) {
    if (!valid_field_name(field.name)) {
      throw ResultsError("write_snapshot: bad field name '" + field.name + "'");
    }
    if (field.values.size() != im.nodes * field.components()) {
      throw ResultsError("write_snapshot: field '" + field.name + "' has " +
                         std::to_string(field.values.size()) + " values for " +
                         std::to_string(im.nodes) + " nodes of " +
                         std::to_string(field.components()) + " components");
    }
    if (std::any_of(info.fields.begin(), info.fields.end(),
                    [&](const auto& f) { return f.first == field.name; })) {
      throw ResultsError("write_snapshot: field '" + field.name + "' given twice");
    }
    info.fields.emplace_back(field.name, field.kind);
  }
  std::sort(info.fields.begin(), info.fields.end());
  {
    h5::Group step = im.file.create_group("fields/" + step_name(info.index));
    for (const auto& field : extra.fields) {
      h5::Dataset ds = step.write<double>(
          field.name, std::span<const double>(field.values),
          {.deflate_level = im.options.field_deflate_level, .columns = field.components()});
      ds.set_attribute("units", std::string_view(field.units));
      ds.set_attribute("kind", std::string_view(kind_name(field.kind)));
    }
    for (const auto& [name, value] : extra.attributes) step.set_attribute(name, value);
    // The damage last: a step is complete (scan_snapshots) once its damage has its attributes.
    h5::Dataset ds = step.write<float>("damage", damage, {im.options.field_deflate_level});
    for (h5::Object* o : {static_cast<h5::Object*>(&step), static_cast<h5::Object*>(&ds)}) {
      o->set_attribute("state_seq", state_seq);
      o->set_attribute("total_cycles", total_cycles);
    }
  }
  im.file.flush();
  im.snapshots.push_back(std::move(info));
  im.write_xdmf();
}

void ResultsWriter::rewind_to(std::int64_t state_seq) {
  impl_->require_open("rewind_to");
  Impl& im = *impl_;
  const auto seqs = im.series.ints.front().read<std::int64_t>();
  const auto keep = static_cast<std::uint64_t>(
      std::find_if(seqs.begin(), seqs.end(), [&](std::int64_t s) { return s > state_seq; }) -
      seqs.begin());
  if (keep != im.rows) {
    im.series.resize(keep);
    im.rows = keep;
  }
  im.trim_cracks_after(state_seq, std::numeric_limits<std::uint64_t>::max());
  for (const char* table : kNamedTables) {
    if (!im.file.exists(std::string(table) + "/state_seq")) continue;
    h5::Group g = im.file.open_group(table);
    const auto named_seqs = g.open_dataset("state_seq").read<std::int64_t>();
    std::uint64_t named_keep = std::min<std::uint64_t>(named_table_rows(g), named_seqs.size());
    for (std::uint64_t i = 0; i < named_keep; ++i) {
      if (named_seqs[static_cast<std::size_t>(i)] > state_seq) {
        named_keep = i;
        break;
      }
    }
    for (const auto& name : g.children()) {
      auto ds = g.open_dataset(name);
      if (ds.size() != named_keep) ds.resize(named_keep);
    }
  }
  const auto before = im.snapshots.size();
  std::erase_if(im.snapshots, [&](const SnapshotInfo& s) {
    if (s.state_seq <= state_seq) return false;
    im.file.remove(s.group());
    return true;
  });
  im.file.flush();
  if (im.snapshots.size() != before && im.nodes > 0) im.write_xdmf();
}

void ResultsWriter::append_named(
    const std::string& group, const NamedRow& row,
    const std::vector<std::pair<std::string, std::string>>& attributes) {
  impl_->require_open("append_named");
  h5::Group g = impl_->file.require_group(group);
  const std::uint64_t n = named_table_rows(g);
  for (const auto& name : g.children()) {  // drop a half-written row's tail
    auto ds = g.open_dataset(name);
    if (ds.size() != n) ds.resize(n);
  }
  const auto units = [&row](const std::string& name) {
    for (const auto& [column, u] : row.units) {
      if (column == name) return u;
    }
    return std::string("1");
  };
  const auto column = [&](const std::string& name, auto tag) {
    using T = decltype(tag);
    if (g.exists(name)) return g.open_dataset(name);
    h5::Dataset ds = g.create_extendible<T>(name, 1024);
    ds.set_attribute("units", std::string_view(units(name)));
    fill_to(ds, n);  // a column new in this row: the rows before it hold the fill
    return ds;
  };
  for (const auto& [name, value] : row.ints) column(name, std::int64_t{}).append(value);
  for (const auto& [name, value] : row.doubles) column(name, double{}).append(value);
  for (const auto& [name, value] : row.strings) {
    // The value's index in the group's list "<name>s" (added to it when new).
    const std::string list_name = name + "s";
    auto list = has_attribute(g, list_name) ? split_lines(g.attribute_string(list_name))
                                            : std::vector<std::string>{};
    auto it = std::find(list.begin(), list.end(), value);
    const auto index = static_cast<std::int64_t>(it - list.begin());
    if (it == list.end()) {
      list.push_back(value);
      std::string text;
      for (std::size_t i = 0; i < list.size(); ++i) text += (i ? "\n" : "") + list[i];
      g.set_attribute(list_name, text);
    }
    column(name + "_index", std::int64_t{}).append(index);
  }
  for (const auto& name : g.children()) {  // columns this row does not have
    auto ds = g.open_dataset(name);
    fill_to(ds, n + 1);
  }
  for (const auto& [name, value] : attributes) g.set_attribute(name, value);
  impl_->file.flush();
}

void ResultsWriter::describe_gauges(const std::vector<GaugeInfo>& gauges) {
  impl_->require_open("describe_gauges");
  for (const auto& g : gauges) {
    if (g.id.empty() || g.id.find('\n') != std::string::npos) {
      throw ResultsError("describe_gauges: bad gauge id '" + g.id + "'");
    }
  }
  h5::File& f = impl_->file;
  if (gauges.empty()) return;  // nothing new to say (gauges described before stay)
  h5::Group g = f.require_group("gauges");
  std::vector<GaugeInfo> all = described_gauges(g);
  for (const auto& gauge : gauges) {
    const auto it =
        std::find_if(all.begin(), all.end(), [&](const GaugeInfo& a) { return a.id == gauge.id; });
    if (it == all.end()) {
      all.push_back(gauge);
    } else {
      *it = gauge;
    }
  }
  std::string ids;
  for (std::size_t k = 0; k < all.size(); ++k) ids += (k ? "\n" : "") + all[k].id;
  g.set_attribute("ids", ids);
  for (const auto& [name, member] : kGaugeAttributes) {
    std::vector<double> values;
    for (const auto& a : all) values.push_back(a.*member);
    g.set_attribute_array(name, values);
  }
  f.flush();
}

std::uint64_t ResultsWriter::named_rows(const std::string& group) const {
  impl_->require_open("named_rows");
  if (!impl_->file.exists(group)) return 0;
  return named_table_rows(impl_->file.open_group(group));
}

std::uint64_t ResultsWriter::rows() const { return impl_->rows; }
const std::vector<SnapshotInfo>& ResultsWriter::snapshots() const { return impl_->snapshots; }
std::size_t ResultsWriter::node_count() const { return impl_->nodes; }
const std::filesystem::path& ResultsWriter::h5_path() const { return impl_->h5_path; }
const std::filesystem::path& ResultsWriter::xdmf_path() const { return impl_->xdmf_path; }
const std::optional<std::filesystem::path>& ResultsWriter::recovered_from() const {
  return impl_->recovered_from;
}

void ResultsWriter::close() {
  if (!impl_ || !impl_->file.is_open()) return;
  impl_->series.clear();
  impl_->cracks.clear();
  impl_->file.flush();
  impl_->file.close();
}

std::filesystem::path ResultsWriter::xdmf_path_for(const std::filesystem::path& h5_path) {
  std::filesystem::path p = h5_path;
  p.replace_extension(".xdmf");
  return p;
}

// --- reading -----------------------------------------------------------------------------------

namespace {

/// The rows of one column table (/timeseries or /cracks), as long as its shortest column. A
/// missing int column (a version-1 file has no crack_count) reads as its `fill`.
template <class Row, std::size_t NI, std::size_t ND>
std::vector<Row> read_table(const h5::File& file, const std::string& group,
                            const std::array<IntColumn<Row>, NI>& int_columns,
                            const std::array<DoubleColumn<Row>, ND>& double_columns) {
  std::vector<std::vector<std::int64_t>> ints;
  std::vector<std::vector<double>> doubles;
  std::size_t n = std::numeric_limits<std::size_t>::max();
  for (const auto& c : int_columns) {
    const std::string path = group + "/" + c.name;
    ints.push_back(file.exists(path) ? file.read<std::int64_t>(path)
                                     : std::vector<std::int64_t>(ints.front().size(), c.fill));
    n = std::min(n, ints.back().size());
  }
  for (const auto& c : double_columns) {
    doubles.push_back(file.read<double>(group + "/" + c.name));
    n = std::min(n, doubles.back().size());
  }
  std::vector<Row> rows(n);
  for (std::size_t r = 0; r < n; ++r) {
    for (std::size_t i = 0; i < NI; ++i) rows[r].*(int_columns[i].member) = ints[i][r];
    for (std::size_t i = 0; i < ND; ++i) rows[r].*(double_columns[i].member) = doubles[i][r];
  }
  return rows;
}

}  // namespace

std::vector<TimeSeriesRow> ResultsWriter::read_rows() const {
  impl_->require_open("read_rows");
  auto rows = read_table(impl_->file, "timeseries", kIntColumns, kDoubleColumns);
  const auto cracks = read_table(impl_->file, "cracks", kCrackIntColumns, kCrackDoubleColumns);
  std::size_t c = 0;
  for (auto& row : rows) {
    while (c < cracks.size() && cracks[c].state_seq < row.state_seq) ++c;
    for (; c < cracks.size() && cracks[c].state_seq == row.state_seq; ++c) {
      row.cracks.push_back(cracks[c]);
    }
  }
  return rows;
}

std::vector<TimeSeriesRow> read_time_series(const std::filesystem::path& h5_path) {
  const h5::File file(h5_path, h5::File::Mode::read_only, {false});
  check_format(file);
  return read_table(file, "timeseries", kIntColumns, kDoubleColumns);
}

std::vector<CrackRow> read_crack_rows(const std::filesystem::path& h5_path) {
  const h5::File file(h5_path, h5::File::Mode::read_only, {false});
  check_format(file);
  if (!file.exists("cracks/state_seq")) return {};  // a version-1 file
  return read_table(file, "cracks", kCrackIntColumns, kCrackDoubleColumns);
}

std::size_t NamedTable::rows() const {
  if (!ints.empty()) return ints.begin()->second.size();
  if (!doubles.empty()) return doubles.begin()->second.size();
  return 0;
}

NamedTable read_named_table(const std::filesystem::path& h5_path, const std::string& group) {
  const h5::File file(h5_path, h5::File::Mode::read_only, {false});
  check_format(file);
  NamedTable t;
  if (!file.exists(group)) return t;
  const h5::Group g = file.open_group(group);
  const std::uint64_t n = named_table_rows(g);
  for (const auto& name : g.children()) {
    const auto ds = g.open_dataset(name);
    if (ds.element_type() == h5::ElementType::i64) {
      auto v = ds.read<std::int64_t>();
      v.resize(static_cast<std::size_t>(n));
      t.ints[name] = std::move(v);
    } else {
      auto v = ds.read<double>();
      v.resize(static_cast<std::size_t>(n));
      t.doubles[name] = std::move(v);
    }
  }
  for (const auto& name : g.attribute_names()) {
    if (!g.attribute_is_string(name)) {
      t.numbers[name] = g.attribute_doubles(name);
      continue;
    }
    const std::string value = g.attribute_string(name);
    // "<x>s" listing the values of the index column "<x>_index".
    if (name.size() > 1 && name.back() == 's' &&
        t.ints.contains(name.substr(0, name.size() - 1) + "_index")) {
      t.strings[name] = split_lines(value);
    } else {
      t.attributes[name] = value;
    }
  }
  return t;
}

std::vector<GaugeInfo> read_gauges(const std::filesystem::path& h5_path) {
  const h5::File file(h5_path, h5::File::Mode::read_only, {false});
  check_format(file);
  if (!file.exists("gauges")) return {};
  return described_gauges(file.open_group("gauges"));
}

std::vector<SnapshotInfo> read_snapshot_list(const std::filesystem::path& h5_path) {
  h5::File file(h5_path, h5::File::Mode::read_only, {false});
  check_format(file);
  return scan_snapshots(file, false);
}

std::vector<float> read_snapshot_damage(const std::filesystem::path& h5_path,
                                        const SnapshotInfo& snapshot) {
  const h5::File file(h5_path, h5::File::Mode::read_only, {false});
  check_format(file);
  return file.read<float>(snapshot.group() + "/damage");
}

std::vector<double> read_snapshot_field(const std::filesystem::path& h5_path,
                                        const SnapshotInfo& snapshot, const std::string& name) {
  const h5::File file(h5_path, h5::File::Mode::read_only, {false});
  check_format(file);
  const std::string path = snapshot.group() + "/" + name;
  if (!valid_field_name(name) || !file.exists(path)) return {};
  return file.read<double>(path);
}

}  // namespace peritwin::outputs
