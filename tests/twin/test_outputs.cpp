// Outputs people look at and checkpoints: HDF5 results + XDMF, atomic verified checkpoints, PNGs.
// Every expected number here is one the test itself wrote; the HDF5 and PNG files are read back
// with the plain C APIs (hdf5.h, png.h), not with the code under test.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <numbers>
#include <sstream>

#include "outputs/checkpoint_io.h"
#include "outputs/damage_png.h"
#include "outputs/h5_file.h"
#include "outputs/results_writer.h"

namespace peritwin::twin {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

class OutputsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("peritwin-outputs-" + std::to_string(::getpid()) + "-" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    // RAII: nothing the code under test (or the test) opened is still open.
    EXPECT_EQ(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL), 0);
    fs::remove_all(dir_);
  }
  fs::path dir_;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void spit(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

// --- raw HDF5 C API readers (independent of h5_file.h) ---------------------------------------

template <class T>
std::vector<T> raw_read(hid_t file, const char* path, hid_t memtype) {
  const hid_t ds = H5Dopen2(file, path, H5P_DEFAULT);
  EXPECT_GE(ds, 0) << path;
  const hid_t space = H5Dget_space(ds);
  std::vector<T> out(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
  if (!out.empty()) {
    EXPECT_GE(H5Dread(ds, memtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), 0);
  }
  H5Sclose(space);
  H5Dclose(ds);
  return out;
}

std::int64_t raw_int_attribute(hid_t file, const char* object, const char* name) {
  std::int64_t v = -1;
  const hid_t a = H5Aopen_by_name(file, object, name, H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(a, 0) << object << " @" << name;
  EXPECT_GE(H5Aread(a, H5T_NATIVE_INT64, &v), 0);
  H5Aclose(a);
  return v;
}

/// Stored type class and size of a dataset.
std::pair<H5T_class_t, std::size_t> raw_type(hid_t file, const char* path) {
  const hid_t ds = H5Dopen2(file, path, H5P_DEFAULT);
  const hid_t t = H5Dget_type(ds);
  std::pair<H5T_class_t, std::size_t> out{H5Tget_class(t), H5Tget_size(t)};
  H5Tclose(t);
  H5Dclose(ds);
  return out;
}

std::vector<outputs::TimeSeriesRow> sample_rows() {
  outputs::TimeSeriesRow a;  // default NaNs for what is not computed yet
  a.state_seq = 1;
  a.total_cycles = 1000;
  outputs::TimeSeriesRow b{2,   250000, 17,     2,     1.25e-3, 1.125e-3, 0.0315, -0.0021,
                           0.1, 12.5e6, -0.3e6, 4.5e6, 3.9e6,   5.1e6,    1,      {}};
  // Two cracks: a notch crack and an interior one with two tips (three crack rows).
  b.cracks = {{0, 1, 1, 0, 1.25e-3, 1.125e-3, 0.0315, -0.0021, 0.1, 12.5e6, -0.3e6},
              {0, 2, 3, 2, 2e-3, 1.9e-3, 0.01, 0.02, 3.0, kNaN, kNaN},
              {0, 2, 3, 0, 2e-3, 1.9e-3, 0.008, 0.02, -0.1, 1e6, 2e5}};
  outputs::TimeSeriesRow c{3,
                           9007199254740993LL,
                           123456789,
                           1,
                           0.1 + 0.2,
                           1.0 / 3.0,
                           -0.0,
                           1e-300,
                           -3.14159,
                           kNaN,
                           std::numeric_limits<double>::infinity(),
                           0.0,
                           -1.0,
                           2.5,
                           3,
                           {}};
  return {a, b, c};
}

void expect_rows_equal(const std::vector<outputs::TimeSeriesRow>& got,
                       const std::vector<outputs::TimeSeriesRow>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t r = 0; r < want.size(); ++r) {
    EXPECT_EQ(got[r].state_seq, want[r].state_seq);
    EXPECT_EQ(got[r].total_cycles, want[r].total_cycles);
    EXPECT_EQ(got[r].broken_bonds, want[r].broken_bonds);
    EXPECT_EQ(got[r].crack_count, want[r].crack_count);
    EXPECT_EQ(got[r].remaining_state_seq, want[r].remaining_state_seq);
    const double outputs::TimeSeriesRow::*members[] = {
        &outputs::TimeSeriesRow::crack_length_m, &outputs::TimeSeriesRow::crack_projected_length_m,
        &outputs::TimeSeriesRow::tip_x,          &outputs::TimeSeriesRow::tip_y,
        &outputs::TimeSeriesRow::kink_angle_rad, &outputs::TimeSeriesRow::k_i,
        &outputs::TimeSeriesRow::k_ii,           &outputs::TimeSeriesRow::remaining_cycles,
        &outputs::TimeSeriesRow::remaining_low,  &outputs::TimeSeriesRow::remaining_high};
    for (auto m : members) EXPECT_TRUE(same_bits(got[r].*m, want[r].*m)) << "row " << r;
  }
}

struct Mesh {
  std::vector<double> x, y;
};
Mesh sample_mesh() {
  Mesh m;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 4; ++i) {
      m.x.push_back((i + 0.5) * 1e-3);
      m.y.push_back((j + 0.5) * 1e-3 - 0.1);
    }
  }
  return m;
}

TEST_F(OutputsTest, ResultsFileHoldsEveryNumberWritten) {
  const fs::path h5 = dir_ / "ct-1.h5";
  const Mesh mesh = sample_mesh();
  const auto rows = sample_rows();
  const std::vector<float> d0(12, 0.0f);
  std::vector<float> d1(12, 0.25f);
  d1[5] = 1.0f;
  d1[6] = 0.123456789f;
  {
    outputs::ResultsWriter w(h5, {.detail = "ct-1"});
    w.write_mesh(mesh.x, mesh.y);
    w.append(rows[0]);
    w.write_snapshot(1, 1000, std::span<const float>(d0));
    w.append(rows[1]);
    w.append(rows[2]);
    w.write_snapshot(3, 9007199254740993LL, std::span<const float>(d1));
    EXPECT_EQ(w.rows(), 3u);
    EXPECT_EQ(w.snapshots().size(), 2u);
  }
  const hid_t f = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const auto seq = raw_read<std::int64_t>(f, "/timeseries/state_seq", H5T_NATIVE_INT64);
  const auto cyc = raw_read<std::int64_t>(f, "/timeseries/total_cycles", H5T_NATIVE_INT64);
  const auto bb = raw_read<std::int64_t>(f, "/timeseries/broken_bonds", H5T_NATIVE_INT64);
  const auto cc = raw_read<std::int64_t>(f, "/timeseries/crack_count", H5T_NATIVE_INT64);
  const auto rs = raw_read<std::int64_t>(f, "/timeseries/remaining_state_seq", H5T_NATIVE_INT64);
  ASSERT_EQ(seq.size(), 3u);
  std::vector<outputs::TimeSeriesRow> got(3);
  for (std::size_t r = 0; r < 3; ++r) {
    got[r].state_seq = seq[r];
    got[r].total_cycles = cyc[r];
    got[r].broken_bonds = bb[r];
    got[r].crack_count = cc[r];
    got[r].remaining_state_seq = rs[r];
  }
  const std::pair<const char*, double outputs::TimeSeriesRow::*> cols[] = {
      {"crack_length_m", &outputs::TimeSeriesRow::crack_length_m},
      {"crack_projected_length_m", &outputs::TimeSeriesRow::crack_projected_length_m},
      {"tip_x", &outputs::TimeSeriesRow::tip_x},
      {"tip_y", &outputs::TimeSeriesRow::tip_y},
      {"kink_angle_rad", &outputs::TimeSeriesRow::kink_angle_rad},
      {"k_i", &outputs::TimeSeriesRow::k_i},
      {"k_ii", &outputs::TimeSeriesRow::k_ii},
      {"remaining_cycles", &outputs::TimeSeriesRow::remaining_cycles},
      {"remaining_low", &outputs::TimeSeriesRow::remaining_low},
      {"remaining_high", &outputs::TimeSeriesRow::remaining_high}};
  for (const auto& [name, member] : cols) {
    const auto v =
        raw_read<double>(f, ("/timeseries/" + std::string(name)).c_str(), H5T_NATIVE_DOUBLE);
    ASSERT_EQ(v.size(), 3u) << name;
    for (std::size_t r = 0; r < 3; ++r) got[r].*member = v[r];
  }
  expect_rows_equal(got, rows);

  EXPECT_EQ(raw_read<double>(f, "/mesh/x", H5T_NATIVE_DOUBLE), mesh.x);
  EXPECT_EQ(raw_read<double>(f, "/mesh/y", H5T_NATIVE_DOUBLE), mesh.y);
  EXPECT_EQ(raw_int_attribute(f, "/mesh", "node_count"), 12);
  EXPECT_EQ(raw_type(f, "/mesh/x"), std::make_pair(H5T_FLOAT, std::size_t{8}));
  EXPECT_EQ(raw_type(f, "/fields/step_000000/damage"), std::make_pair(H5T_FLOAT, std::size_t{4}));
  EXPECT_EQ(raw_read<float>(f, "/fields/step_000000/damage", H5T_NATIVE_FLOAT), d0);
  EXPECT_EQ(raw_read<float>(f, "/fields/step_000001/damage", H5T_NATIVE_FLOAT), d1);
  EXPECT_EQ(raw_int_attribute(f, "/fields/step_000000/damage", "state_seq"), 1);
  EXPECT_EQ(raw_int_attribute(f, "/fields/step_000000/damage", "total_cycles"), 1000);
  EXPECT_EQ(raw_int_attribute(f, "/fields/step_000001/damage", "state_seq"), 3);
  EXPECT_EQ(raw_int_attribute(f, "/fields/step_000001", "total_cycles"), 9007199254740993LL);
  H5Fclose(f);

  // The library's own reader agrees.
  expect_rows_equal(outputs::read_time_series(h5), rows);
  // The crack rows of every row, with its state_seq, bit for bit.
  const auto cracks = outputs::read_crack_rows(h5);
  ASSERT_EQ(cracks.size(), rows[1].cracks.size());
  for (std::size_t i = 0; i < cracks.size(); ++i) {
    const outputs::CrackRow& want = rows[1].cracks[i];
    EXPECT_EQ(cracks[i].state_seq, 2);
    EXPECT_EQ(cracks[i].crack_id, want.crack_id);
    EXPECT_EQ(cracks[i].origin_kind, want.origin_kind);
    EXPECT_EQ(cracks[i].k_status, want.k_status);
    for (auto m :
         {&outputs::CrackRow::length_m, &outputs::CrackRow::projected_length_m,
          &outputs::CrackRow::tip_x, &outputs::CrackRow::tip_y, &outputs::CrackRow::tip_angle_rad,
          &outputs::CrackRow::k_i, &outputs::CrackRow::k_ii}) {
      EXPECT_TRUE(same_bits(cracks[i].*m, want.*m)) << i;
    }
  }
  const auto snaps = outputs::read_snapshot_list(h5);
  ASSERT_EQ(snaps.size(), 2u);
  EXPECT_EQ(outputs::read_snapshot_damage(h5, snaps[1]), d1);

  // XDMF: both steps, their times, the dataset paths, and no temp file left behind.
  const std::string xdmf = slurp(dir_ / "ct-1.xdmf");
  for (const char* s :
       {"<Xdmf Version=\"3.0\">", "CollectionType=\"Temporal\"", "Name=\"step_000000\"",
        "Name=\"step_000001\"", "<Time Value=\"1000\"/>", "<Time Value=\"9007199254740993\"/>",
        "TopologyType=\"Polyvertex\" NumberOfElements=\"12\"", "GeometryType=\"XYZ\"",
        "ct-1.h5:/mesh/vertices", "ct-1.h5:/mesh/xyz", "ct-1.h5:/fields/step_000000/damage",
        "ct-1.h5:/fields/step_000001/damage", "</Xdmf>"}) {
    EXPECT_NE(xdmf.find(s), std::string::npos) << s;
  }
  auto count = [&](std::string_view needle) {
    std::size_t n = 0;
    for (auto p = xdmf.find(needle); p != std::string::npos; p = xdmf.find(needle, p + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("<Grid "), 3u);
  EXPECT_EQ(count("</Grid>"), 3u);
  EXPECT_FALSE(fs::exists(dir_ / "ct-1.xdmf.tmp"));
}

TEST_F(OutputsTest, ResultsFileContinuesDropsHalfRowsAndRewinds) {
  const fs::path h5 = dir_ / "d.h5";
  const Mesh mesh = sample_mesh();
  const auto rows = sample_rows();
  {
    outputs::ResultsWriter w(h5, {.detail = "d"});
    w.write_mesh(mesh.x, mesh.y);
    for (const auto& r : rows) w.append(r);
    w.write_snapshot(1, 10, std::vector<double>(12, 0.5));
    w.write_snapshot(3, 30, std::vector<double>(12, 0.75));
  }
  {  // A crash between the column appends of a row: one column one element longer.
    outputs::h5::File f(h5, outputs::h5::File::Mode::read_write);
    f.open_dataset("timeseries/state_seq").append<std::int64_t>(99);
  }
  outputs::ResultsWriter w(h5, {.detail = "d"});
  EXPECT_FALSE(w.recovered_from().has_value());
  EXPECT_EQ(w.rows(), 3u);
  ASSERT_EQ(w.snapshots().size(), 2u);
  EXPECT_EQ(w.node_count(), 12u);
  w.write_mesh(mesh.x, mesh.y);  // same mesh: no-op
  std::vector<double> other = mesh.x;
  other[0] += 1e-9;
  EXPECT_THROW(w.write_mesh(other, mesh.y), outputs::ResultsError);
  EXPECT_THROW(w.write_snapshot(4, 40, std::vector<double>(11, 0.0)), outputs::ResultsError);

  w.rewind_to(1);  // resume from a checkpoint at state 1: the crack rows of state 2 go too
  EXPECT_EQ(w.rows(), 1u);
  EXPECT_EQ(outputs::read_crack_rows(h5).size(), 0u);
  w.append(rows[1]);
  EXPECT_EQ(outputs::read_crack_rows(h5).size(), 3u);
  w.rewind_to(2);  // resume from a checkpoint at state 2
  EXPECT_EQ(w.rows(), 2u);
  ASSERT_EQ(w.snapshots().size(), 1u);
  EXPECT_EQ(w.snapshots()[0].state_seq, 1);
  w.write_snapshot(3, 31, std::vector<double>(12, 1.0));
  EXPECT_EQ(w.snapshots().back().index, 1);
  w.close();
  const auto back = outputs::read_time_series(h5);
  expect_rows_equal(back, {rows[0], rows[1]});
  const auto snaps = outputs::read_snapshot_list(h5);
  ASSERT_EQ(snaps.size(), 2u);
  EXPECT_EQ(snaps[1].total_cycles, 31);
  EXPECT_EQ(outputs::read_snapshot_damage(h5, snaps[1]), std::vector<float>(12, 1.0f));
  const std::string xdmf = slurp(dir_ / "d.xdmf");
  EXPECT_NE(xdmf.find("<Time Value=\"31\"/>"), std::string::npos);
  EXPECT_EQ(xdmf.find("<Time Value=\"30\"/>"), std::string::npos);
}

/// A float64 attribute of any shape, read with the C API.
std::vector<double> raw_double_attribute(hid_t file, const char* object, const char* name) {
  const hid_t a = H5Aopen_by_name(file, object, name, H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(a, 0) << object << " @" << name;
  const hid_t space = H5Aget_space(a);
  std::vector<double> out(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
  EXPECT_GE(H5Aread(a, H5T_NATIVE_DOUBLE, out.data()), 0);
  H5Sclose(space);
  H5Aclose(a);
  return out;
}

TEST_F(OutputsTest, GaugeTableIsDescribedOnceAndRewoundLikeTheTimeSeries) {
  const fs::path h5 = dir_ / "g.h5";
  const std::vector<outputs::GaugeInfo> first{
      {"g1", 0.030, 0.0205, 0.0, 0.004, 2e-6},
      {"tip-2", 0.035, 0.002, 1.5707963267948966, 0.0, 0.0}};
  auto row = [](std::int64_t seq, const std::vector<std::string>& ids) {
    outputs::NamedRow r;
    r.ints = {{"state_seq", seq}, {"total_cycles", 1000 * seq}};
    r.units = {{"total_cycles", "cycles"}};
    for (std::size_t g = 0; g < ids.size(); ++g) {
      const auto v = static_cast<double>(10 * seq) + static_cast<double>(g + 1);  // exact
      r.doubles.emplace_back(ids[g] + "_per_constant", v);
      r.doubles.emplace_back(ids[g] + "_residual", seq == 3 ? 0.01 : kNaN);
      r.ints.emplace_back(ids[g] + "_in_a_row", seq == 3 ? 1 : 0);
      r.units.emplace_back(ids[g] + "_per_constant", "1/N");
    }
    return r;
  };
  {
    outputs::ResultsWriter w(h5, {.detail = "d"});
    w.describe_gauges({});  // no gauges: no group
    EXPECT_EQ(w.named_rows("gauges"), 0u);
    w.describe_gauges(first);
    EXPECT_EQ(w.named_rows("gauges"), 0u);  // described, no rows yet
    for (std::int64_t seq = 0; seq <= 4; ++seq) w.append_named("gauges", row(seq, {"g1", "tip-2"}));
    EXPECT_EQ(w.named_rows("gauges"), 5u);
    w.rewind_to(2);  // a resume from the checkpoint of state 3: rows after state 2 go
    EXPECT_EQ(w.named_rows("gauges"), 3u);
    EXPECT_THROW(w.describe_gauges({{"a\nb", 0, 0, 0, 0, 0}}), outputs::ResultsError);
  }
  EXPECT_EQ(outputs::read_gauges(h5), first);
  {
    // The next run: tip-2 moved, g3 added, g1 gone from the config (its columns stay).
    outputs::ResultsWriter w(h5, {.detail = "d"});
    w.describe_gauges(
        {{"tip-2", 0.036, 0.003, 1.0, 0.002, 1e-6}, {"g3", 0.01, 0.02, 0.5, 0.0, 0.0}});
    w.append_named("gauges", row(3, {"tip-2", "g3"}));
  }
  const std::vector<outputs::GaugeInfo> all{
      first[0], {"tip-2", 0.036, 0.003, 1.0, 0.002, 1e-6}, {"g3", 0.01, 0.02, 0.5, 0.0, 0.0}};
  EXPECT_EQ(outputs::read_gauges(h5), all);
  const auto t = outputs::read_named_table(h5, "gauges");
  ASSERT_EQ(t.rows(), 4u);
  EXPECT_EQ(t.ints.at("state_seq"), (std::vector<std::int64_t>{0, 1, 2, 3}));
  EXPECT_EQ(t.ints.at("total_cycles"), (std::vector<std::int64_t>{0, 1000, 2000, 3000}));
  EXPECT_EQ(t.doubles.at("g1_per_constant")[2], 21.0);
  EXPECT_TRUE(std::isnan(t.doubles.at("g1_per_constant")[3]));  // not in the last run's row
  EXPECT_EQ(t.doubles.at("tip-2_per_constant")[1], 12.0);
  EXPECT_EQ(t.doubles.at("tip-2_per_constant")[3], 31.0);
  EXPECT_EQ(t.doubles.at("g3_per_constant")[3], 32.0);
  EXPECT_TRUE(std::isnan(t.doubles.at("g3_per_constant")[0]));  // before g3 existed
  EXPECT_EQ(t.ints.at("g3_in_a_row"), (std::vector<std::int64_t>{-1, -1, -1, 1}));
  EXPECT_EQ(t.doubles.at("tip-2_residual")[3], 0.01);
  EXPECT_EQ(t.attributes.at("ids"), "g1\ntip-2\ng3");
  EXPECT_EQ(t.numbers.at("x_m"), (std::vector<double>{0.030, 0.036, 0.01}));
  EXPECT_EQ(t.numbers.at("noise"), (std::vector<double>{2e-6, 1e-6, 0.0}));
  // The same with the plain C API: float64 array attributes, a string of ids, units per column.
  const hid_t f = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  EXPECT_EQ(raw_double_attribute(f, "/gauges", "y_m"), (std::vector<double>{0.0205, 0.003, 0.02}));
  EXPECT_EQ(raw_double_attribute(f, "/gauges", "angle_rad"), (std::vector<double>{0.0, 1.0, 0.5}));
  EXPECT_EQ(raw_double_attribute(f, "/gauges", "length_m"),
            (std::vector<double>{0.004, 0.002, 0.0}));
  const auto ids = H5Aopen_by_name(f, "/gauges", "ids", H5P_DEFAULT, H5P_DEFAULT);
  const hid_t ids_type = H5Aget_type(ids);
  EXPECT_EQ(H5Tget_class(ids_type), H5T_STRING);
  H5Tclose(ids_type);
  H5Aclose(ids);
  EXPECT_EQ(raw_type(f, "/gauges/g3_per_constant"), std::make_pair(H5T_FLOAT, std::size_t{8}));
  EXPECT_EQ(raw_read<double>(f, "/gauges/g1_per_constant", H5T_NATIVE_DOUBLE).size(), 4u);
  H5Fclose(f);
}

TEST_F(OutputsTest, LayoutVersionOneFileIsUpgradedInPlace) {
  // A results file of layout 1 (before the crack table): no /timeseries/crack_count, no /cracks.
  const fs::path h5 = dir_ / "old.h5";
  const auto rows = sample_rows();
  {
    outputs::ResultsWriter w(h5, {.detail = "old"});
    w.append(rows[0]);
  }
  {
    outputs::h5::File f(h5, outputs::h5::File::Mode::read_write);
    f.remove("timeseries/crack_count");
    f.remove("cracks");
    f.set_attribute("layout_version", std::int64_t{1});
  }
  // Readable as it is: its rows' crack_count reads -1 (unknown), no crack rows.
  const auto before = outputs::read_time_series(h5);
  ASSERT_EQ(before.size(), 1u);
  EXPECT_EQ(before[0].crack_count, -1);
  EXPECT_TRUE(outputs::read_crack_rows(h5).empty());
  // Continued by a writer: upgraded to layout 3, the old row kept (crack_count -1), new rows whole.
  {
    outputs::ResultsWriter w(h5, {.detail = "old"});
    EXPECT_EQ(w.rows(), 1u);
    w.append(rows[1]);
  }
  const auto after = outputs::read_time_series(h5);
  ASSERT_EQ(after.size(), 2u);
  EXPECT_EQ(after[0].crack_count, -1);
  EXPECT_EQ(after[0].total_cycles, rows[0].total_cycles);
  EXPECT_EQ(after[1].crack_count, rows[1].crack_count);
  EXPECT_EQ(outputs::read_crack_rows(h5).size(), rows[1].cracks.size());
  EXPECT_EQ(
      outputs::h5::File(h5, outputs::h5::File::Mode::read_only).attribute_int64("layout_version"),
      3);
}

TEST_F(OutputsTest, LayoutVersionTwoFileGetsTheXdmf3MeshAndEstimateColumn) {
  // Layout 2: no /mesh/xyz, /mesh/vertices (its X_Y geometry crashed ParaView's Xdmf3 reader), no
  // /timeseries/remaining_state_seq.
  const fs::path h5 = dir_ / "v2.h5";
  const Mesh mesh = sample_mesh();
  const auto rows = sample_rows();
  {
    outputs::ResultsWriter w(h5, {.detail = "v2"});
    w.write_mesh(mesh.x, mesh.y);
    w.append(rows[1]);
  }
  {
    outputs::h5::File f(h5, outputs::h5::File::Mode::read_write);
    f.remove("mesh/xyz");
    f.remove("mesh/vertices");
    f.remove("timeseries/remaining_state_seq");
    f.set_attribute("layout_version", std::int64_t{2});
  }
  EXPECT_EQ(outputs::read_time_series(h5).at(0).remaining_state_seq, -1);
  {
    outputs::ResultsWriter w(h5, {.detail = "v2"});
    w.append(rows[2]);
  }
  const auto after = outputs::read_time_series(h5);
  ASSERT_EQ(after.size(), 2u);
  EXPECT_EQ(after[0].remaining_state_seq, -1);
  EXPECT_EQ(after[1].remaining_state_seq, rows[2].remaining_state_seq);
  const hid_t f = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const auto xyz = raw_read<double>(f, "/mesh/xyz", H5T_NATIVE_DOUBLE);
  const auto vertices = raw_read<std::int64_t>(f, "/mesh/vertices", H5T_NATIVE_INT64);
  H5Fclose(f);
  ASSERT_EQ(xyz.size(), 36u);
  ASSERT_EQ(vertices.size(), 12u);
  for (std::size_t k = 0; k < 12; ++k) {
    EXPECT_EQ(xyz[3 * k], mesh.x[k]);
    EXPECT_EQ(xyz[3 * k + 1], mesh.y[k]);
    EXPECT_EQ(xyz[3 * k + 2], 0.0);
    EXPECT_EQ(vertices[k], static_cast<std::int64_t>(k));
  }
  EXPECT_EQ(
      outputs::h5::File(h5, outputs::h5::File::Mode::read_only).attribute_int64("layout_version"),
      3);
}

TEST_F(OutputsTest, SnapshotNodeFieldsAreStoredWithTheirShapes) {
  const fs::path h5 = dir_ / "fields.h5";
  const Mesh mesh = sample_mesh();
  outputs::SnapshotFields extra;
  outputs::NodeField disp{"displacement", outputs::NodeField::Kind::vector, "m", {}};
  outputs::NodeField strain{"strain", outputs::NodeField::Kind::tensor6, "1", {}};
  outputs::NodeField dil{"dilatation", outputs::NodeField::Kind::scalar, "1", {}};
  for (std::size_t k = 0; k < 12; ++k) {
    for (int c = 0; c < 3; ++c) disp.values.push_back(1e-6 * static_cast<double>(10 * k + c));
    for (int c = 0; c < 6; ++c) strain.values.push_back(1e-4 * static_cast<double>(10 * k + c));
    dil.values.push_back(-1e-3 * static_cast<double>(k));
  }
  extra.fields = {disp, strain, dil};
  extra.attributes = {{"load_p_max_n", 4000.0}};
  {
    outputs::ResultsWriter w(h5, {.detail = "f"});
    w.write_mesh(mesh.x, mesh.y);
    w.write_snapshot(1, 10, std::vector<double>(12, 0.5), extra);
    // Sizes that do not match the nodes, a name twice or a bad name are refused.
    outputs::SnapshotFields bad;
    bad.fields = {{"displacement", outputs::NodeField::Kind::vector, "m", std::vector<double>(12)}};
    EXPECT_THROW(w.write_snapshot(2, 20, std::vector<double>(12, 0.5), bad), outputs::ResultsError);
    bad.fields = {dil, dil};
    EXPECT_THROW(w.write_snapshot(2, 20, std::vector<double>(12, 0.5), bad), outputs::ResultsError);
    bad.fields = {{"a b", outputs::NodeField::Kind::scalar, "1", std::vector<double>(12)}};
    EXPECT_THROW(w.write_snapshot(2, 20, std::vector<double>(12, 0.5), bad), outputs::ResultsError);
    EXPECT_EQ(w.snapshots().size(), 1u);
  }
  const auto snaps = outputs::read_snapshot_list(h5);
  ASSERT_EQ(snaps.size(), 1u);
  EXPECT_EQ(snaps[0].fields.size(), 3u);  // found again on reading, with their kinds
  EXPECT_EQ(outputs::read_snapshot_field(h5, snaps[0], "displacement"), disp.values);
  EXPECT_EQ(outputs::read_snapshot_field(h5, snaps[0], "strain"), strain.values);
  EXPECT_EQ(outputs::read_snapshot_field(h5, snaps[0], "dilatation"), dil.values);
  EXPECT_TRUE(outputs::read_snapshot_field(h5, snaps[0], "nothing").empty());
  const std::string xdmf = slurp(dir_ / "fields.xdmf");
  for (const char* s :
       {"<Attribute Name=\"displacement\" AttributeType=\"Vector\" Center=\"Node\">",
        "<DataItem Dimensions=\"12 3\" NumberType=\"Float\" Precision=\"8\" "
        "Format=\"HDF\">fields.h5:/fields/step_000000/displacement</DataItem>",
        "<Attribute Name=\"strain\" AttributeType=\"Tensor6\" Center=\"Node\">",
        "<DataItem Dimensions=\"12 6\"",
        "<Attribute Name=\"dilatation\" AttributeType=\"Scalar\" Center=\"Node\">"}) {
    EXPECT_NE(xdmf.find(s), std::string::npos) << s;
  }
  const hid_t f = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hid_t ds = H5Dopen2(f, "/fields/step_000000/strain", H5P_DEFAULT);
  const hid_t space = H5Dget_space(ds);
  hsize_t dims[2] = {0, 0};
  EXPECT_EQ(H5Sget_simple_extent_ndims(space), 2);
  H5Sget_simple_extent_dims(space, dims, nullptr);
  EXPECT_EQ(dims[0], 12u);
  EXPECT_EQ(dims[1], 6u);
  H5Sclose(space);
  H5Dclose(ds);
  double p = 0.0;
  const hid_t a =
      H5Aopen_by_name(f, "/fields/step_000000", "load_p_max_n", H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(H5Aread(a, H5T_NATIVE_DOUBLE, &p), 0);
  H5Aclose(a);
  EXPECT_EQ(p, 4000.0);
  H5Fclose(f);
}

TEST_F(OutputsTest, UnreadableResultsFileIsMovedAside) {
  const fs::path h5 = dir_ / "x.h5";
  spit(h5, "not an HDF5 file at all");
  outputs::ResultsWriter w(h5, {.detail = "x"});
  ASSERT_TRUE(w.recovered_from().has_value());
  EXPECT_EQ(slurp(*w.recovered_from()), "not an HDF5 file at all");
  EXPECT_EQ(w.rows(), 0u);
}

TEST_F(OutputsTest, H5ErrorsNameFileAndObject) {
  const fs::path missing = dir_ / "missing.h5";
  try {
    outputs::h5::File f(missing, outputs::h5::File::Mode::read_only);
    FAIL() << "opened a missing file";
  } catch (const outputs::h5::Error& e) {
    EXPECT_EQ(e.file(), missing.string());
    EXPECT_NE(std::string(e.what()).find("missing.h5"), std::string::npos) << e.what();
  }
  outputs::h5::File f(dir_ / "a.h5", outputs::h5::File::Mode::create_exclusive);
  f.write<double>("g/values", std::vector<double>{1.0, 2.0});
  try {
    (void)f.read<double>("g/nothing");
    FAIL() << "read a missing dataset";
  } catch (const outputs::h5::Error& e) {
    EXPECT_EQ(e.object(), "/g/nothing");
    EXPECT_NE(std::string(e.what()).find("a.h5"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)f.read_string("g/values"), outputs::h5::Error);
  EXPECT_THROW(outputs::h5::File(dir_ / "a.h5", outputs::h5::File::Mode::create_exclusive),
               outputs::h5::Error);
}

// --- checkpoints -------------------------------------------------------------------------------

twin::CheckpointData sample_checkpoint(std::int64_t salt) {
  twin::CheckpointData d;
  d.format_version = 7;
  d.f64_arrays["remaining_life"] = {1.0,    -0.0,
                                    kNaN,   std::numeric_limits<double>::infinity(),
                                    5e-324, 0.1 * static_cast<double>(salt)};
  d.f64_arrays["empty"] = {};
  std::vector<double> big(5000);
  for (std::size_t i = 0; i < big.size(); ++i)
    big[i] = std::sin(static_cast<double>(i) + static_cast<double>(salt));
  d.f64_arrays["big"] = big;
  d.i64_arrays["seq"] = {std::numeric_limits<std::int64_t>::min(), -1,  0, 1,
                         std::numeric_limits<std::int64_t>::max(), salt};
  d.u8_arrays["broken"] = {0, 1, 255, 7};
  d.i64_scalars["applied_seq"] = 42 + salt;
  d.i64_scalars["min"] = std::numeric_limits<std::int64_t>::min();
  d.f64_scalars["total_cycles"] = 1.5e9;
  d.f64_scalars["nan"] = kNaN;
  d.strings["source"] = "replay \xc3\xa9t\xc3\xa9 \"quoted\"";
  d.strings["empty"] = "";
  d.strings["config"] = std::string(100000, 'c');  // larger than an attribute may be
  return d;
}

template <class T>
void expect_arrays_equal(const std::map<std::string, std::vector<T>>& got,
                         const std::map<std::string, std::vector<T>>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (const auto& [name, values] : want) {
    ASSERT_TRUE(got.contains(name)) << name;
    const auto& g = got.at(name);
    ASSERT_EQ(g.size(), values.size()) << name;
    // memcmp of an empty array would pass null pointers (undefined; UBSan's nonnull check).
    if (values.empty()) continue;
    EXPECT_EQ(std::memcmp(g.data(), values.data(), values.size() * sizeof(T)), 0) << name;
  }
}

void expect_checkpoints_equal(const twin::CheckpointData& got, const twin::CheckpointData& want) {
  EXPECT_EQ(got.format_version, want.format_version);
  expect_arrays_equal(got.f64_arrays, want.f64_arrays);
  expect_arrays_equal(got.i64_arrays, want.i64_arrays);
  expect_arrays_equal(got.u8_arrays, want.u8_arrays);
  EXPECT_EQ(got.i64_scalars, want.i64_scalars);
  ASSERT_EQ(got.f64_scalars.size(), want.f64_scalars.size());
  for (const auto& [name, v] : want.f64_scalars) {
    ASSERT_TRUE(got.f64_scalars.contains(name)) << name;
    EXPECT_TRUE(same_bits(got.f64_scalars.at(name), v)) << name;
  }
  EXPECT_EQ(got.strings, want.strings);
  EXPECT_EQ(outputs::checkpoint_checksum(got), outputs::checkpoint_checksum(want));
}

/// File offset of a contiguous dataset's first byte (raw HDF5).
haddr_t data_offset(const fs::path& file, const char* dataset) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t ds = H5Dopen2(f, dataset, H5P_DEFAULT);
  const haddr_t off = H5Dget_offset(ds);
  H5Dclose(ds);
  H5Fclose(f);
  return off;
}

void flip_byte(const fs::path& file, std::size_t offset) {
  std::string bytes = slurp(file);
  ASSERT_LT(offset, bytes.size());
  bytes[offset] = static_cast<char>(bytes[offset] ^ 0x5A);
  spit(file, bytes);
}

void truncate_by(const fs::path& file, std::size_t cut) {
  const std::string bytes = slurp(file);
  spit(file, bytes.substr(0, bytes.size() - cut));
}

TEST_F(OutputsTest, CheckpointRoundTripIsExact) {
  const fs::path p = dir_ / "cp-000000000001.h5";
  const twin::CheckpointData d = sample_checkpoint(1);
  outputs::write_checkpoint(p, d);
  EXPECT_FALSE(fs::exists(dir_ / "cp-000000000001.h5.tmp"));
  expect_checkpoints_equal(outputs::read_checkpoint(p), d);
  // Rewriting the same path replaces it atomically.
  const twin::CheckpointData d2 = sample_checkpoint(2);
  outputs::write_checkpoint(p, d2);
  expect_checkpoints_equal(outputs::read_checkpoint(p), d2);
  EXPECT_NE(outputs::checkpoint_checksum(d), outputs::checkpoint_checksum(d2));

  twin::CheckpointData bad;
  bad.f64_arrays["a/b"] = {1.0};
  EXPECT_THROW(outputs::write_checkpoint(dir_ / "bad.h5", bad), std::invalid_argument);
}

TEST_F(OutputsTest, TruncatedAndCorruptedCheckpointsAreRejected) {
  const twin::CheckpointData d = sample_checkpoint(3);
  const fs::path good = dir_ / "good.h5";
  outputs::write_checkpoint(good, d);
  const std::size_t size = fs::file_size(good);

  for (const std::size_t cut : {std::size_t{1}, std::size_t{100}, size / 2, size - 8}) {
    const fs::path t = dir_ / ("truncated-" + std::to_string(cut) + ".h5");
    fs::copy_file(good, t);
    truncate_by(t, cut);
    EXPECT_THROW((void)outputs::read_checkpoint(t), outputs::CheckpointError) << "cut " << cut;
  }

  const fs::path c = dir_ / "corrupt.h5";
  fs::copy_file(good, c);
  const haddr_t off = data_offset(c, "/arrays/f64/big");
  ASSERT_NE(off, HADDR_UNDEF);
  flip_byte(c, static_cast<std::size_t>(off) + 8 * 1234 + 3);
  try {
    (void)outputs::read_checkpoint(c);
    FAIL() << "a flipped byte went unnoticed";
  } catch (const outputs::CheckpointError& e) {
    EXPECT_EQ(e.path(), c);
    EXPECT_NE(std::string(e.what()).find("checksum mismatch"), std::string::npos) << e.what();
  }

  const fs::path u = dir_ / "corrupt-u8.h5";
  fs::copy_file(good, u);
  flip_byte(u, static_cast<std::size_t>(data_offset(u, "/arrays/u8/broken")) + 2);
  EXPECT_THROW((void)outputs::read_checkpoint(u), outputs::CheckpointError);
  EXPECT_THROW((void)outputs::read_checkpoint(dir_ / "nope.h5"), outputs::CheckpointError);
}

// A corrupt checkpoint may declare arrays and strings far larger than the file (HDF5 reads storage
// that was never written as fill values): refused before anything is allocated, naming the entry.
// Before, 2^40 doubles went to std::vector (bad_alloc; an ASan build aborted) and a 2 GB string to
// std::string.
TEST_F(OutputsTest, CheckpointEntriesLargerThanTheFileAreRefused) {
  const fs::path good = dir_ / "good.h5";
  outputs::write_checkpoint(good, sample_checkpoint(4));
  auto expect_refused = [](const fs::path& p, const std::string& what) {
    try {
      (void)outputs::read_checkpoint(p);
      FAIL() << "read " << p;
    } catch (const outputs::CheckpointError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };

  // An extendible array of 2^40 doubles with no chunk written: the file grows by ~1 kB.
  const fs::path huge = dir_ / "huge-array.h5";
  fs::copy_file(good, huge);
  {
    const hid_t f = H5Fopen(huge.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hsize_t dims[1] = {0}, maxdims[1] = {H5S_UNLIMITED}, chunk[1] = {1024};
    const hid_t space = H5Screate_simple(1, dims, maxdims);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 1, chunk);
    const hid_t ds =
        H5Dcreate2(f, "/arrays/f64/huge", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    ASSERT_GE(ds, 0);
    const hsize_t extent[1] = {hsize_t{1} << 40};
    ASSERT_GE(H5Dset_extent(ds, extent), 0);
    H5Dclose(ds);
    H5Pclose(dcpl);
    H5Sclose(space);
    H5Fclose(f);
  }
  ASSERT_LT(fs::file_size(huge), fs::file_size(good) + 16'384);
  expect_refused(huge,
                 "array '/arrays/f64/huge' claims 1099511627776 elements of 8 bytes, more "
                 "than the ");

  // A fixed-length string of 2^31 bytes whose storage is never allocated.
  const fs::path text = dir_ / "huge-string.h5";
  fs::copy_file(good, text);
  {
    const hid_t f = H5Fopen(text.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, std::size_t{1} << 31);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_alloc_time(dcpl, H5D_ALLOC_TIME_LATE);
    const hid_t ds = H5Dcreate2(f, "/strings/huge", type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    ASSERT_GE(ds, 0);
    H5Dclose(ds);
    H5Pclose(dcpl);
    H5Sclose(space);
    H5Tclose(type);
    H5Fclose(f);
  }
  ASSERT_LT(fs::file_size(text), fs::file_size(good) + 16'384);
  expect_refused(text, "is a string of 2147483648 bytes, more than the ");
}

TEST_F(OutputsTest, NewestValidCheckpointSkipsBrokenOnes) {
  for (std::uint64_t seq : {1u, 2u, 3u, 10u}) {
    outputs::write_checkpoint(outputs::checkpoint_path(dir_, "ct", seq),
                              sample_checkpoint(static_cast<std::int64_t>(seq)));
  }
  EXPECT_EQ(outputs::checkpoint_path(dir_, "ct", 10).filename(), "ct-000000000010.h5");
  spit(dir_ / "ct-2-000000000099.h5", "other detail");  // prefix "ct-2", not ours
  spit(dir_ / "ct-abc.h5", "not a checkpoint name");
  spit(dir_ / "ct-000000000011.h5.tmp", "in flight");
  truncate_by(outputs::checkpoint_path(dir_, "ct", 10), 200);
  const fs::path three = outputs::checkpoint_path(dir_, "ct", 3);
  flip_byte(three, static_cast<std::size_t>(data_offset(three, "/arrays/i64/seq")) + 1);

  const auto listed = outputs::list_checkpoints(dir_, "ct");
  ASSERT_EQ(listed.size(), 4u);
  EXPECT_EQ(listed[0].seq, 10u);
  EXPECT_EQ(listed[3].seq, 1u);

  std::vector<std::string> skipped;
  const auto found = outputs::newest_valid_checkpoint(dir_, "ct", &skipped);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(found->file.seq, 2u);
  expect_checkpoints_equal(found->data, sample_checkpoint(2));
  ASSERT_EQ(skipped.size(), 2u);
  EXPECT_NE(skipped[0].find("ct-000000000010.h5"), std::string::npos) << skipped[0];
  EXPECT_NE(skipped[1].find("checksum"), std::string::npos) << skipped[1];

  EXPECT_FALSE(outputs::newest_valid_checkpoint(dir_, "nothing").has_value());
  EXPECT_FALSE(outputs::newest_valid_checkpoint(dir_ / "no-such-dir", "ct").has_value());
}

TEST_F(OutputsTest, PruneKeepsTheNewestK) {
  for (std::uint64_t seq = 1; seq <= 5; ++seq) {
    outputs::write_checkpoint(outputs::checkpoint_path(dir_, "ct", seq), sample_checkpoint(1));
  }
  spit(dir_ / "ct-000000000002.h5.tmp", "stale");
  spit(dir_ / "ct-000000000009.h5.tmp", "in flight");
  spit(dir_ / "ctx-000000000001.h5", "another prefix");
  const auto removed = outputs::prune_checkpoints(dir_, "ct", 2);
  EXPECT_EQ(removed.size(), 4u);  // seq 3, 2, 1 and the stale tmp of 2
  const auto left = outputs::list_checkpoints(dir_, "ct");
  ASSERT_EQ(left.size(), 2u);
  EXPECT_EQ(left[0].seq, 5u);
  EXPECT_EQ(left[1].seq, 4u);
  EXPECT_FALSE(fs::exists(dir_ / "ct-000000000002.h5.tmp"));
  EXPECT_TRUE(fs::exists(dir_ / "ct-000000000009.h5.tmp"));
  EXPECT_TRUE(fs::exists(dir_ / "ctx-000000000001.h5"));
  EXPECT_TRUE(outputs::prune_checkpoints(dir_, "ct", 2).empty());
  EXPECT_THROW(outputs::prune_checkpoints(dir_, "ct", 0), std::invalid_argument);
}

// --- PNG ---------------------------------------------------------------------------------------

std::uint32_t be32(const std::string& b, std::size_t at) {
  return (std::uint32_t(std::uint8_t(b[at])) << 24) |
         (std::uint32_t(std::uint8_t(b[at + 1])) << 16) |
         (std::uint32_t(std::uint8_t(b[at + 2])) << 8) | std::uint32_t(std::uint8_t(b[at + 3]));
}

/// Signature, then the IHDR chunk first: returns {width, height}, checks 8-bit RGB.
std::pair<std::uint32_t, std::uint32_t> png_header(const fs::path& p) {
  const std::string b = slurp(p);
  EXPECT_GE(b.size(), 33u);
  const std::string signature("\x89PNG\r\n\x1a\n", 8);
  EXPECT_EQ(b.substr(0, 8), signature);
  EXPECT_EQ(be32(b, 8), 13u);  // IHDR length
  EXPECT_EQ(b.substr(12, 4), "IHDR");
  EXPECT_EQ(std::uint8_t(b[24]), 8);  // bit depth
  EXPECT_EQ(std::uint8_t(b[25]), 2);  // colour type: RGB
  return {be32(b, 16), be32(b, 20)};
}

/// Decoded RGB pixels with libpng (simplified read API).
std::vector<std::uint8_t> png_pixels(const fs::path& p, std::uint32_t& w, std::uint32_t& h) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  EXPECT_NE(png_image_begin_read_from_file(&img, p.c_str()), 0) << img.message;
  img.format = PNG_FORMAT_RGB;
  std::vector<std::uint8_t> px(PNG_IMAGE_SIZE(img));
  EXPECT_NE(png_image_finish_read(&img, nullptr, px.data(), 0, nullptr), 0) << img.message;
  w = img.width;
  h = img.height;
  return px;
}

/// A PNG read back with libpng: its size and pixels, and counts of pixels inside a box.
struct Picture {
  std::uint32_t width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  explicit Picture(const fs::path& p) : rgb(png_pixels(p, width, height)) {}
  [[nodiscard]] outputs::Rgb at(int x, int y) const {
    const std::size_t i = 3 * (std::size_t(y) * width + std::size_t(x));
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
  /// The pixels of the box (clipped to the picture) whose colour satisfies pred.
  template <class Pred>
  [[nodiscard]] std::size_t count(const outputs::Box& b, Pred pred) const {
    std::size_t n = 0;
    for (int y = std::max(0, b.top); y < std::min<int>(b.bottom(), int(height)); ++y) {
      for (int x = std::max(0, b.left); x < std::min<int>(b.right(), int(width)); ++x) {
        n += pred(at(x, y));
      }
    }
    return n;
  }
  [[nodiscard]] std::size_t count(const outputs::Box& b, outputs::Rgb c) const {
    return count(b, [c](outputs::Rgb p) { return p == c; });
  }
  /// Pixels of text: dark grey to black.
  [[nodiscard]] std::size_t dark(const outputs::Box& b) const {
    return count(b, [](outputs::Rgb p) { return p.r < 110 && p.g < 110 && p.b < 110; });
  }
  [[nodiscard]] outputs::Box all() const { return {0, 0, int(width), int(height)}; }
};

/// The named boxes lie inside the picture and no two share a pixel.
void expect_apart(const std::vector<std::pair<std::string, outputs::Box>>& boxes,
                  const outputs::Box& picture) {
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const auto& [name, b] = boxes[i];
    if (b.width == 0 && b.height == 0) continue;  // nothing there (an empty title)
    EXPECT_GT(b.width, 0) << name;
    EXPECT_GT(b.height, 0) << name;
    EXPECT_TRUE(picture.contains(b)) << name << " at " << b.left << "," << b.top << " size "
                                     << b.width << "x" << b.height << " is outside the picture";
    for (std::size_t j = 0; j < i; ++j) {
      EXPECT_FALSE(b.overlaps(boxes[j].second)) << name << " overlaps " << boxes[j].first;
    }
  }
}

/// Every box of a picture's text and legend, named, for expect_apart.
std::vector<std::pair<std::string, outputs::Box>> text_boxes(const outputs::PictureText& t) {
  std::vector<std::pair<std::string, outputs::Box>> out{
      {"title", t.title}, {"x title", t.x_title}, {"y title", t.y_title}};
  for (std::size_t i = 0; i < t.x_tick_labels.size(); ++i) {
    out.emplace_back("x tick label " + std::to_string(i), t.x_tick_labels[i]);
  }
  for (std::size_t i = 0; i < t.y_tick_labels.size(); ++i) {
    out.emplace_back("y tick label " + std::to_string(i), t.y_tick_labels[i]);
  }
  for (const auto& e : t.legend) out.emplace_back("legend " + e.label, e.box);
  return out;
}

/// Text was drawn where the layout says: dark pixels in every text box, more in longer ones, and
/// letters at least as tall as the old 14-pixel bitmap font; each legend entry holds its sample
/// and its text side by side.
void expect_text_drawn(const Picture& pic, const outputs::PictureText& t) {
  EXPECT_GT(pic.dark(t.title), 150u);
  EXPECT_GE(t.title.height, 16);
  EXPECT_GT(pic.dark(t.x_title), 40u);
  EXPECT_GT(pic.dark(t.y_title), 40u);
  EXPECT_GT(t.y_title.height, t.y_title.width);  // reads upwards
  for (const auto& b : t.x_tick_labels) {
    EXPECT_GT(pic.dark(b), 10u);
    EXPECT_GE(b.height, 14);
  }
  for (const auto& b : t.y_tick_labels) EXPECT_GT(pic.dark(b), 10u);
  ASSERT_FALSE(t.x_tick_labels.empty());
  ASSERT_FALSE(t.y_tick_labels.empty());
  for (const auto& e : t.legend) {
    EXPECT_GT(pic.dark(e.text), 5u * e.label.size()) << e.label;
    EXPECT_TRUE(e.box.contains(e.sample)) << e.label;
    EXPECT_TRUE(e.box.contains(e.text)) << e.label;
    EXPECT_LE(e.sample.right(), e.text.left) << e.label;
  }
}

TEST_F(OutputsTest, DamagePngHasExpectedSizeAndColours) {
  // 20 x 10 nodes at cell centres (dx = 1 mm), a 4 x 4 hole, one fully damaged node at (5, 2).
  const double dx = 1e-3;
  std::vector<double> x, y, d;
  for (int j = 0; j < 10; ++j) {
    for (int i = 0; i < 20; ++i) {
      if (i >= 12 && i < 16 && j >= 3 && j < 7) continue;
      x.push_back((i + 0.5) * dx);
      y.push_back((j + 0.5) * dx);
      d.push_back(i == 5 && j == 2 ? 1.0 : 0.0);
    }
  }
  const fs::path p = dir_ / "damage.png";
  const outputs::DamageImageLayout layout = outputs::write_damage_png(p, x, y, d, dx);
  // 800 / max(20, 10) = 40 pixels per node.
  EXPECT_EQ(layout.node_pixels, 40);
  EXPECT_EQ(png_header(p), std::make_pair(800u, 400u));

  const Picture pic(p);
  ASSERT_EQ(pic.width, 800u);
  auto at = [&](int col, int row) {  // centre pixel of grid cell (col, row from the top)
    return pic.at(col * 40 + 20, row * 40 + 20);
  };
  const outputs::Rgb red = at(5, 9 - 2);
  EXPECT_EQ(red, outputs::damage_color(1.0));
  EXPECT_GT(red.r, 150);
  EXPECT_LT(red.g, 80);
  EXPECT_LT(red.b, 80);
  EXPECT_EQ(at(0, 0), outputs::damage_color(0.0));
  EXPECT_GT(outputs::damage_color(0.0).b, outputs::damage_color(0.0).r);
  EXPECT_EQ(at(13, 9 - 4), (outputs::Rgb{255, 255, 255}));  // inside the hole: no material
  EXPECT_EQ(outputs::damage_color(0.5), (outputs::Rgb{250, 220, 40}));
  // A node is its colour to the edge of its square: 40 x 40 pixels exactly.
  EXPECT_EQ(pic.count({5 * 40, 7 * 40, 40, 40}, red), 1600u);
  EXPECT_EQ(pic.count(pic.all(), red), 1600u);

  EXPECT_THROW(outputs::write_damage_png(p, x, y, std::vector<double>(3, 0.0), dx),
               outputs::PngError);
  EXPECT_THROW(outputs::write_damage_png(p, x, y, d, 1e-9), outputs::PngError);
}

TEST_F(OutputsTest, DamageMapTellsTheNotchFromTheCrack) {
  // 20 x 10 nodes (dx = 1 mm); node (5, 4) holds notch damage only (φ = 0.42 = its notch φ), node
  // (6, 4) the same notch damage plus a broken fatigue bond (φ = 0.48): grey and colour.
  const double dx = 1e-3;
  std::vector<double> x, y, d;
  outputs::DamageMap map;
  map.title = "ct-1   N = 12000 cycles";
  for (int j = 0; j < 10; ++j) {
    for (int i = 0; i < 20; ++i) {
      x.push_back((i + 0.5) * dx);
      y.push_back((j + 0.5) * dx);
      const bool notch = j == 4 && (i == 5 || i == 6);
      d.push_back(notch ? (i == 5 ? 0.42 : 0.48) : 0.0);
      map.notch_damage.push_back(notch ? 0.42 : 0.0);
    }
  }
  map.notches = {{{0.0, 4.5e-3}, {5.5e-3, 4.5e-3}}};
  map.crack_paths = {{{6.5e-3, 4.5e-3}, {12.5e-3, 2.5e-3}}};
  const fs::path p = dir_ / "map.png";
  const outputs::DamageMapLayout layout = outputs::write_damage_map_png(p, x, y, d, dx, map);
  EXPECT_EQ(layout.grid.node_pixels, 40);
  EXPECT_GT(layout.left, 0);  // room for the y axis, its ticks and labels
  EXPECT_GT(layout.top, 0);   // and the title
  EXPECT_GT(layout.width, layout.left + layout.grid.width);  // and the colour bar
  const Picture pic(p);
  ASSERT_EQ(pic.width, static_cast<std::uint32_t>(layout.width));
  ASSERT_EQ(pic.height, static_cast<std::uint32_t>(layout.height));
  auto at = [&](int col, int row_from_top, int dy = 20) {
    return pic.at(layout.left + col * 40 + 20, layout.top + row_from_top * 40 + dy);
  };
  EXPECT_EQ(at(5, 9 - 4, 5),
            outputs::notch_color(0.42));  // off the notch line drawn through the row
  EXPECT_EQ(outputs::notch_color(0.42).r, outputs::notch_color(0.42).b);  // a grey
  EXPECT_EQ(at(6, 9 - 4, 5), outputs::damage_color(0.48));
  EXPECT_EQ(at(15, 0), outputs::damage_color(0.0));
  const outputs::Rgb magenta{200, 0, 200}, black{0, 0, 0};
  const outputs::Box raster{layout.left, layout.top, layout.grid.width, layout.grid.height};
  // The crack path, 6.3 mm at 40 px/mm and 3 px wide (antialiased: pixels near its colour), and
  // its tip; the notch line, 5.5 mm at 3 px (two of its rows wholly black).
  EXPECT_GT(pic.count(raster, [](outputs::Rgb c) { return c.r > 150 && c.g < 80 && c.b > 150; }),
            600u);
  EXPECT_GT(pic.count(raster, black), 400u);

  // The layout: nothing shares a pixel with anything else; the text is there.
  auto boxes = text_boxes(layout.text);
  boxes.emplace_back("raster", raster);
  boxes.emplace_back("colour bar", layout.colour_bar);
  boxes.emplace_back("colour bar title", layout.colour_bar_title);
  for (std::size_t i = 0; i < layout.colour_bar_labels.size(); ++i) {
    boxes.emplace_back("colour bar label " + std::to_string(i), layout.colour_bar_labels[i]);
  }
  expect_apart(boxes, pic.all());
  expect_text_drawn(pic, layout.text);
  EXPECT_LE(layout.text.title.bottom(), raster.top);
  EXPECT_GT(pic.dark(layout.colour_bar_title), 40u);
  ASSERT_EQ(layout.colour_bar_labels.size(), 5u);  // 0.00, 0.25, 0.50, 0.75, 1.00
  for (const auto& b : layout.colour_bar_labels) EXPECT_GT(pic.dark(b), 20u);
  EXPECT_GT(layout.colour_bar_labels.front().top, layout.colour_bar_labels.back().top);  // 0 below
  // The bar is the colour scale: φ = 1 on top, 0 at the bottom, 0.5 half way.
  const outputs::Box& bar = layout.colour_bar;
  const int mid = bar.left + bar.width / 2;
  EXPECT_EQ(pic.at(mid, bar.top), outputs::damage_color(1.0));
  EXPECT_EQ(pic.at(mid, bar.bottom() - 1), outputs::damage_color(0.0));
  EXPECT_EQ(pic.count({bar.left, bar.top, bar.width, 1}, outputs::damage_color(1.0)),
            static_cast<std::size_t>(bar.width));
  const int half = (bar.height - 1) / 2;
  EXPECT_EQ(pic.at(mid, bar.top + half),
            outputs::damage_color(1.0 - static_cast<double>(half) / (bar.height - 1)));
  // The legend: the grey swatch of notch-only nodes, then the crack path.
  ASSERT_EQ(layout.text.legend.size(), 2u);
  EXPECT_EQ(layout.text.legend[0].label, "notch");
  EXPECT_EQ(layout.text.legend[1].label, "crack");
  const outputs::Box swatch = layout.text.legend[0].sample;
  EXPECT_EQ(pic.at(swatch.left, swatch.top + swatch.height / 2), outputs::notch_color(0.0));
  EXPECT_GT(pic.count(layout.text.legend[1].sample, magenta), 40u);

  // A detail without notches: no notch entry.
  map.notch_damage.assign(d.size(), 0.0);
  const auto plain = outputs::write_damage_map_png(p, x, y, d, dx, map);
  ASSERT_EQ(plain.text.legend.size(), 1u);
  EXPECT_EQ(plain.text.legend[0].label, "crack");
  map.notch_damage = {0.1};  // not one per node
  EXPECT_THROW(outputs::write_damage_map_png(p, x, y, d, dx, map), outputs::PngError);
}

TEST_F(OutputsTest, DamageMapDrawsTheGaugesWithTheirIds) {
  // 20 x 10 nodes (dx = 1 mm, 40 pixels a node), a red node under the horizontal gauge "h1", a
  // crack path right of it (where its label would go first), a point gauge "v0" along y (drawn
  // 3 dx long) and a gauge at 45 degrees.
  const double dx = 1e-3;
  std::vector<double> x, y, d;
  for (int j = 0; j < 10; ++j) {
    for (int i = 0; i < 20; ++i) {
      x.push_back((i + 0.5) * dx);
      y.push_back((j + 0.5) * dx);
      d.push_back(i == 10 && j == 7 ? 1.0 : 0.1 * (i % 5));
    }
  }
  outputs::DamageMap map;
  map.title = "ct-1   N = 12000 cycles";
  map.notch_damage.assign(d.size(), 0.0);
  map.crack_paths = {{{13.0e-3, 7.5e-3}, {19.5e-3, 7.5e-3}}};
  const fs::path plain_png = dir_ / "plain.png";
  const auto plain = outputs::write_damage_map_png(plain_png, x, y, d, dx, map);
  map.gauges = {{"h1", {10.5e-3, 7.5e-3}, 0.0, 4e-3},
                {"v0", {3.5e-3, 2.5e-3}, 0.5 * std::numbers::pi, 0.0},
                {"d45", {15.5e-3, 4.5e-3}, 0.25 * std::numbers::pi, 2e-3}};
  const fs::path p = dir_ / "gauges.png";
  const outputs::DamageMapLayout layout = outputs::write_damage_map_png(p, x, y, d, dx, map);
  const Picture pic(p), before(plain_png);
  ASSERT_EQ(layout.grid.node_pixels, 40);
  const outputs::Box raster{layout.left, layout.top, layout.grid.width, layout.grid.height};
  // The pixel of a model point (m): node (x, y)'s square starts at column (x - x_min)/dx·40, row
  // (y_max - y)/dx·40 (DamageImageLayout), its centre 20 pixels further.
  auto px = [&](double xm) { return layout.left + (xm - 0.5e-3) / dx * 40 + 20; };
  auto py = [&](double ym) { return layout.top + (9.5e-3 - ym) / dx * 40 + 20; };
  const outputs::Rgb green = outputs::kGaugeColor, black{0, 0, 0};

  // Nothing else moved: the text, the raster and the colour bar where they were without gauges;
  // the legend gains the gauge after the crack.
  EXPECT_EQ(layout.left, plain.left);
  EXPECT_EQ(layout.top, plain.top);
  EXPECT_GE(layout.width, plain.width);  // the legend's column may widen for "gauge"
  auto same_box = [](const outputs::Box& a, const outputs::Box& b) {
    return a.left == b.left && a.top == b.top && a.width == b.width && a.height == b.height;
  };
  const auto now = text_boxes(layout.text), was = text_boxes(plain.text);
  ASSERT_EQ(now.size(), was.size() + 1);
  for (std::size_t i = 0; i < was.size(); ++i) {
    EXPECT_EQ(now[i].first, was[i].first);
    EXPECT_TRUE(same_box(now[i].second, was[i].second)) << was[i].first;
  }
  EXPECT_TRUE(same_box(layout.colour_bar, plain.colour_bar));
  EXPECT_TRUE(same_box(layout.colour_bar_title, plain.colour_bar_title));
  ASSERT_EQ(layout.text.legend.size(), 2u);
  EXPECT_EQ(layout.text.legend[1].label, "gauge");
  EXPECT_GT(pic.count(layout.text.legend[1].sample, green), 60u);
  expect_text_drawn(pic, layout.text);

  ASSERT_EQ(layout.gauges.size(), 3u);
  // h1: 4 mm along x = 160 pixels, centred on its node; the core is 5 pixels across with a black
  // rim: its middle three rows are wholly green from end to end (less a pixel at each end).
  const double hx = px(10.5e-3), hy = py(7.5e-3);
  EXPECT_EQ(layout.gauges[0].id, "h1");
  EXPECT_NEAR(layout.gauges[0].x0, hx - 80, 1e-9);
  EXPECT_NEAR(layout.gauges[0].x1, hx + 80, 1e-9);
  EXPECT_NEAR(layout.gauges[0].y0, hy, 1e-9);
  const outputs::Box core{static_cast<int>(hx) - 79, static_cast<int>(hy) - 1, 158, 3};
  EXPECT_EQ(pic.count(core, green), 158u * 3u);
  EXPECT_EQ(pic.at(static_cast<int>(hx), static_cast<int>(hy) - 3), black);  // the rim
  EXPECT_EQ(pic.at(static_cast<int>(hx), static_cast<int>(hy) + 3), black);
  EXPECT_EQ(pic.at(static_cast<int>(hx), static_cast<int>(hy) - 8),
            before.at(static_cast<int>(hx), static_cast<int>(hy) - 8));       // the map beyond it
  EXPECT_NE(pic.at(static_cast<int>(hx) + 85, static_cast<int>(hy)), green);  // its end
  // v0: a point gauge drawn 3 dx = 120 pixels along y.
  const double vx = px(3.5e-3), vy = py(2.5e-3);
  EXPECT_EQ(pic.count({static_cast<int>(vx) - 1, static_cast<int>(vy) - 58, 3, 116}, green),
            3u * 116u);
  EXPECT_NE(pic.at(static_cast<int>(vx), static_cast<int>(vy) - 64), green);
  EXPECT_NE(pic.at(static_cast<int>(vx), static_cast<int>(vy) + 64), green);
  // d45: 3 dx at 45 degrees (up and right): green along the line through its centre.
  const double cx = px(15.5e-3), cy = py(4.5e-3);
  for (int t = -55; t <= 55; t += 5) {
    const double u = t / std::numbers::sqrt2;
    EXPECT_EQ(pic.at(static_cast<int>(std::floor(cx + u)), static_cast<int>(std::floor(cy - u))),
              green)
        << t;
  }
  // Green pixels only on the bars and the label plates' rims; elsewhere the raster is the map
  // without gauges.
  std::size_t changed_outside = 0, green_outside = 0;
  for (int r = raster.top; r < raster.bottom(); ++r) {
    for (int c = raster.left; c < raster.right(); ++c) {
      bool marked = false;
      for (const auto& m : layout.gauges) {
        marked = marked || m.bar.overlaps({c, r, 1, 1}) || m.label.overlaps({c, r, 1, 1});
      }
      if (marked) continue;
      changed_outside += !(pic.at(c, r) == before.at(c, r));
      green_outside += pic.at(c, r) == green;
    }
  }
  EXPECT_EQ(changed_outside, 0u);
  EXPECT_EQ(green_outside, 0u);
  // The labels: inside the map (so clear of the title, axes, colour bar and legend), on no bar
  // and no other label, beside their own bar, the id drawn in dark pixels on white.
  for (std::size_t i = 0; i < layout.gauges.size(); ++i) {
    const auto& m = layout.gauges[i];
    EXPECT_TRUE(raster.contains(m.label)) << m.id;
    for (std::size_t j = 0; j < layout.gauges.size(); ++j) {
      EXPECT_FALSE(m.label.overlaps(layout.gauges[j].bar)) << m.id << " on " << layout.gauges[j].id;
      if (j != i) {
        EXPECT_FALSE(m.label.overlaps(layout.gauges[j].label)) << m.id;
      }
    }
    const outputs::Box near{m.bar.left - 4, m.bar.top - 4, m.bar.width + 8, m.bar.height + 8};
    EXPECT_TRUE(near.overlaps(m.label)) << m.id << " is not beside its bar";
    EXPECT_GT(pic.dark(m.label), 8u * m.id.size()) << m.id;
    EXPECT_GT(pic.count(m.label, outputs::Rgb{255, 255, 255}), 40u) << m.id;
    EXPECT_GE(m.label.height, 12) << m.id;
    EXPECT_LT(m.label.height - 4, layout.text.x_tick_labels.at(0).height) << m.id << ": small";
  }
  // h1's label is not on the crack path right of it: it went left of the bar.
  EXPECT_LE(layout.gauges[0].label.right(), layout.gauges[0].bar.left);
  // The crack path is still drawn where no label covers it.
  const outputs::Rgb magenta{200, 0, 200};
  EXPECT_GT(pic.count(raster, magenta), 300u);

  // The gauges' colour is none of the map's: at least 200 (sum of |ΔR|, |ΔG|, |ΔB|) from every
  // damage colour and every notch grey.
  auto distance = [](outputs::Rgb a, outputs::Rgb b) {
    return std::abs(a.r - b.r) + std::abs(a.g - b.g) + std::abs(a.b - b.b);
  };
  for (int k = 0; k <= 1000; ++k) {
    EXPECT_GE(distance(outputs::damage_color(k / 1000.0), green), 200) << k;
    EXPECT_GE(distance(outputs::notch_color(k / 1000.0), green), 200) << k;
  }
}

TEST_F(OutputsTest, CrackGrowthPlotShowsTheEstimates) {
  outputs::CrackGrowthPlot plot;
  plot.title = "ct-1   crack length and predicted end of life";
  for (int k = 0; k <= 20; ++k) {
    plot.cycles.push_back(1e3 * k);
    plot.lengths_m.push_back(1e-4 * k);
  }
  plot.predictions = {{5e3, 5e-4, 2e4, 1.5e4, 2.5e4}, {1e4, 1e-3, 1.6e4, kNaN, kNaN}};
  plot.critical_length_m = 3e-3;
  plot.end_of_life_cycle = 20000;
  const fs::path p = dir_ / "an.png";
  const outputs::PlotLayout layout = outputs::write_crack_growth_png(p, plot);
  const Picture pic(p);
  ASSERT_EQ(pic.width, 800u);
  ASSERT_EQ(pic.height, 500u);
  EXPECT_EQ(layout.width, 800);
  EXPECT_EQ(layout.height, 500);
  const outputs::Rgb orange{230, 110, 0}, blue{31, 90, 180}, grey{120, 120, 120},
      magenta{200, 0, 200};
  // Diamonds, the band bar, the dashed latest prediction (2 px over the frame's height).
  EXPECT_GT(pic.count(layout.frame, orange), 300u);
  EXPECT_GT(pic.count(layout.frame, blue), 500u);  // the curve, 3 px wide
  // The legend: its four entries in order, each with its sample in its colour, none overlapping
  // another or anything else of the picture.
  const auto& legend = layout.text.legend;
  ASSERT_EQ(legend.size(), 4u);
  EXPECT_EQ(legend[0].label, "crack length");
  EXPECT_EQ(legend[1].label, "predicted end (band)");
  EXPECT_EQ(legend[2].label, "critical");
  EXPECT_EQ(legend[3].label, "end of life");
  EXPECT_GT(pic.count(legend[0].sample, blue), 40u);
  EXPECT_GT(pic.count(legend[1].sample, orange), 30u);
  EXPECT_GT(pic.count(legend[2].sample, grey), 10u);
  EXPECT_GT(pic.count(legend[3].sample, magenta), 40u);
  auto boxes = text_boxes(layout.text);
  boxes.emplace_back("frame", layout.frame);
  expect_apart(boxes, pic.all());
  expect_text_drawn(pic, layout.text);
  for (const auto& e : legend) EXPECT_LE(e.box.right(), layout.frame.right()) << e.label;

  // A narrow picture: the same legend no longer fits one row and takes two, still apart.
  const outputs::PlotLayout narrow = outputs::write_crack_growth_png(p, plot, {.width = 420});
  const Picture small(p);
  ASSERT_EQ(small.width, 420u);
  ASSERT_EQ(narrow.text.legend.size(), 4u);
  EXPECT_GT(narrow.text.legend.back().box.top, narrow.text.legend.front().box.top);
  auto narrow_boxes = text_boxes(narrow.text);
  narrow_boxes.emplace_back("frame", narrow.frame);
  expect_apart(narrow_boxes, small.all());
  expect_text_drawn(small, narrow.text);

  plot.lengths_m.pop_back();
  EXPECT_THROW(outputs::write_crack_growth_png(p, plot), outputs::PngError);
}

TEST_F(OutputsTest, LinePlotDrawsEverySeries) {
  // Two curves in their own colours (a solid sine, a dashed line), the image the size asked for;
  // a horizontal line at y = 0 over a fixed range [-1, 1] lands on the frame's middle row.
  outputs::LinePlot plot;
  plot.title = "k(t)";
  plot.x_title = "t";
  plot.y_title = "k";
  plot.y_lo = -1.0;
  plot.y_hi = 1.0;
  outputs::PlotSeries sine{"sine", {}, {}, outputs::Rgb{200, 40, 40}, false};
  outputs::PlotSeries zero{"zero", {}, {}, outputs::Rgb{30, 150, 60}, true};
  for (int k = 0; k <= 200; ++k) {
    sine.x.push_back(0.05 * k);
    sine.y.push_back(std::sin(0.05 * k));
    zero.x.push_back(0.05 * k);
    zero.y.push_back(0.0);
  }
  plot.series = {sine, zero};
  const fs::path p = dir_ / "lines.png";
  const outputs::PlotLayout layout =
      outputs::write_line_plot_png(p, plot, outputs::PlotOptions{640, 400});
  const Picture pic(p);
  ASSERT_EQ(pic.width, 640u);
  ASSERT_EQ(pic.height, 400u);
  const outputs::Rgb red{200, 40, 40}, green{30, 150, 60};
  // The sine over 10 units at 2 px (antialiased: pixels near its colour).
  EXPECT_GT(
      pic.count(layout.frame, [](outputs::Rgb c) { return c.r > 150 && c.g < 130 && c.b < 130; }),
      700u);
  // Dashed: about half of a 2 px line across the frame.
  EXPECT_GT(
      pic.count(layout.frame, [](outputs::Rgb c) { return c.g > 110 && c.r < 130 && c.b < 130; }),
      350u);
  // The zero line: its green pixels sit in the frame's middle rows.
  const outputs::Box& f = layout.frame;
  std::size_t best = 0;
  int best_row = -1;
  for (int row = f.top; row < f.bottom(); ++row) {
    const std::size_t n = pic.count({f.left, row, f.width, 1}, green);
    if (n > best) {
      best = n;
      best_row = row;
    }
  }
  EXPECT_NEAR(best_row, f.top + f.height / 2, 2);
  EXPECT_GT(best, static_cast<std::size_t>(f.width) / 3);
  ASSERT_EQ(layout.text.legend.size(), 2u);
  EXPECT_EQ(layout.text.legend[0].label, "sine");
  EXPECT_GT(pic.count(layout.text.legend[0].sample, red), 40u);
  EXPECT_GT(pic.count(layout.text.legend[1].sample, green), 20u);
  auto boxes = text_boxes(layout.text);
  boxes.emplace_back("frame", layout.frame);
  expect_apart(boxes, pic.all());
  // One-letter titles: fewer dark pixels than expect_text_drawn asks of a title.
  EXPECT_GT(pic.dark(layout.text.title), 40u);
  for (const auto& b : layout.text.x_tick_labels) EXPECT_GT(pic.dark(b), 10u);
  plot.series[0].y.pop_back();
  EXPECT_THROW(outputs::write_line_plot_png(p, plot), outputs::PngError);
}

TEST_F(OutputsTest, CrackLengthPlotIsAPng) {
  std::vector<double> n, a;
  for (int k = 0; k <= 50; ++k) {
    n.push_back(2e4 * k);
    a.push_back(1e-3 * (1.0 + 0.002 * k * k));
  }
  a[20] = kNaN;  // breaks the line, must not break the plot
  const fs::path p = dir_ / "crack.png";
  const outputs::PlotLayout layout = outputs::write_crack_length_png(p, n, a);
  EXPECT_EQ(png_header(p), std::make_pair(800u, 500u));
  const Picture pic(p);
  // The blue curve is there, in two pieces: between the columns it covers, one gap (the missing
  // point, 4e4 cycles wide: about 4 % of the frame) with none of it.
  auto blue = [](outputs::Rgb c) { return c.r < 100 && c.b > 150; };
  EXPECT_GT(pic.count(layout.frame, blue), 500u);
  const outputs::Box& f = layout.frame;
  std::vector<int> gaps;  // widths of the runs of columns without blue between columns with it
  int last = -1;
  for (int col = f.left; col < f.right(); ++col) {
    if (pic.count({col, f.top, 1, f.height}, blue) == 0) continue;
    if (last >= 0 && col - last > 1) gaps.push_back(col - last - 1);
    last = col;
  }
  ASSERT_EQ(gaps.size(), 1u);
  EXPECT_GT(gaps[0], f.width / 50);
  EXPECT_LT(gaps[0], f.width / 20);
  // No estimates, no critical length, no end of life: the curve's legend entry alone.
  ASSERT_EQ(layout.text.legend.size(), 1u);
  EXPECT_EQ(layout.text.legend[0].label, "crack length");
  // The x axis: 0 to 1e6 cycles; its tick labels ("2e5" style) are apart.
  ASSERT_GE(layout.text.x_tick_labels.size(), 3u);
  auto boxes = text_boxes(layout.text);
  boxes.emplace_back("frame", layout.frame);
  expect_apart(boxes, pic.all());
  outputs::write_crack_length_png(dir_ / "empty.png", {}, {}, {.width = 400, .height = 300});
  EXPECT_EQ(png_header(dir_ / "empty.png"), std::make_pair(400u, 300u));
}

}  // namespace
}  // namespace peritwin::twin
