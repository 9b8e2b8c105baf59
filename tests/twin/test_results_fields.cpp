// Results people can use: the PD strain of 004 Eq. (6)-(7) against closed forms, the node fields
// of a snapshot against the model's own solution, and a twin's results directory as the daemon
// and peritwin-replay --results write it (the XDMF structure ParaView's default reader needs,
// the HDF5 shapes it names, the pictures written at every snapshot). Expected numbers come from
// the closed forms in the test or from the solver's own accessors; files are read back with the
// plain HDF5 and libpng C APIs.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>

#include "config/config.h"
#include "outputs/detail_outputs.h"
#include "solver/statics/pd_strain.h"
#include "tests/support/twin_fixtures.h"

namespace peritwin::twin {
namespace {

namespace fs = std::filesystem;
using testing::b1_config;
using testing::b1_model;
using testing::batch;
using testing::make_twin;

/// E = ½(H + Hᵀ + HᵀH) of a constant displacement gradient H (the closed form of 004 Eq. 7 for
/// u = H·x, whose F = I + H by 004 Eq. 6 whatever the family).
statics::PlaneStrain lagrange_of(const std::array<std::array<double, 2>, 2>& h) {
  statics::PlaneStrain e;
  e.xx = h[0][0] + 0.5 * (h[0][0] * h[0][0] + h[1][0] * h[1][0]);
  e.yy = h[1][1] + 0.5 * (h[0][1] * h[0][1] + h[1][1] * h[1][1]);
  e.xy = 0.5 * (h[0][1] + h[1][0]) + 0.5 * (h[0][0] * h[0][1] + h[1][0] * h[1][1]);
  return e;
}

std::vector<double> affine_field(const mesh::Discretization& disc,
                                 const std::array<std::array<double, 2>, 2>& h) {
  std::vector<double> u(2 * disc.position.size());
  for (std::size_t k = 0; k < disc.position.size(); ++k) {
    const mesh::Point p = disc.position[k];
    u[2 * k] = h[0][0] * p.x + h[0][1] * p.y + 1e-5;  // plus a rigid translation
    u[2 * k + 1] = h[1][0] * p.x + h[1][1] * p.y - 2e-5;
  }
  return u;
}

class ResultsFieldsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { model_ = b1_model(b1_config()); }
  static void TearDownTestSuite() { model_.reset(); }
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("peritwin-results-fields-" + std::to_string(::getpid()) + "-" + info->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::shared_ptr<const twin::DetailModel> model_;
  fs::path dir_;
};
std::shared_ptr<const twin::DetailModel> ResultsFieldsTest::model_;

TEST_F(ResultsFieldsTest, AffineDisplacementGivesItsLagrangeStrainAtEveryNode) {
  // B1's grid: free edges, a notch (cut bonds) and partial volumes; 004 Eq. (6) is exact for an
  // affine field on any family that spans the plane, so every node must give the closed form.
  const mesh::Discretization& disc = model_->disc();
  std::vector<std::uint8_t> intact(disc.bond_precut.size());
  for (std::size_t b = 0; b < intact.size(); ++b) intact[b] = disc.bond_precut[b] == 0;
  const std::array<std::array<double, 2>, 2> h{{{2e-3, 5e-4}, {-3e-4, -1e-3}}};
  const statics::PlaneStrain want = lagrange_of(h);
  const auto got = statics::pd_lagrange_strain(disc, intact, affine_field(disc, h));
  ASSERT_EQ(got.size(), disc.position.size());
  for (std::size_t k = 0; k < got.size(); ++k) {
    // Round-off of sums of ~30 bonds of length ~δ: 1e-12 absolute on strains of 1e-3.
    ASSERT_NEAR(got[k].xx, want.xx, 1e-12) << "node " << k;
    ASSERT_NEAR(got[k].yy, want.yy, 1e-12) << "node " << k;
    ASSERT_NEAR(got[k].xy, want.xy, 1e-12) << "node " << k;
  }
  // A uniform stretch ε: E_xx = E_yy = ε + ε²/2, dilatation 2ε + ε², principal ε + ε²/2.
  const double eps = 1e-3;
  const auto stretch =
      statics::pd_lagrange_strain(disc, intact, affine_field(disc, {{{eps, 0}, {0, eps}}}));
  EXPECT_NEAR(stretch[100].dilatation(), 2 * eps + eps * eps, 1e-12);
  EXPECT_NEAR(stretch[100].max_principal(), eps + 0.5 * eps * eps, 1e-12);
  EXPECT_NEAR(stretch[100].xy, 0.0, 1e-12);
  // A rigid rotation strains nothing: the HᵀH term of Eq. (7) cancels the linear one.
  const double c = std::cos(0.02) - 1.0, s = std::sin(0.02);
  for (const auto& e :
       statics::pd_lagrange_strain(disc, intact, affine_field(disc, {{{c, -s}, {s, c}}}))) {
    ASSERT_NEAR(e.xx, 0.0, 1e-12);
    ASSERT_NEAR(e.yy, 0.0, 1e-12);
    ASSERT_NEAR(e.xy, 0.0, 1e-12);
  }
}

TEST_F(ResultsFieldsTest, ANodeWithoutBondsAcrossTheLineHasNoStrain) {
  const mesh::Discretization& disc = model_->disc();
  // Keep only node 0's bonds along x: K of Eq. (6) is singular, the strain is NaN, not a guess.
  std::vector<std::uint8_t> intact(disc.bond_precut.size(), 1);
  for (auto f = disc.family_offset[0]; f < disc.family_offset[1]; ++f) {
    const auto b = static_cast<std::size_t>(disc.family_bonds[static_cast<std::size_t>(f)]);
    if (std::abs(disc.bond_sin[b]) > 1e-12) intact[b] = 0;
  }
  const auto e =
      statics::pd_lagrange_strain(disc, intact, std::vector<double>(2 * disc.position.size()));
  EXPECT_TRUE(std::isnan(e[0].xx));
  EXPECT_TRUE(std::isfinite(e[1].xx));
  EXPECT_THROW(statics::pd_lagrange_strain(disc, intact, std::vector<double>(3)),
               std::invalid_argument);
}

TEST_F(ResultsFieldsTest, SnapshotFieldsAreTheModelsSolutionAtTheLastLoad) {
  auto twin = make_twin(model_);
  // Before any block: the largest P_max of the life reference spectrum (per newton without one).
  double reference = 1.0;
  for (const auto& b : model_->config().life.reference_spectrum) {
    reference = b.p_max > reference ? b.p_max : reference;
  }
  EXPECT_EQ(outputs::snapshot_load(*twin).p_max, reference);
  ASSERT_EQ(twin->apply(batch(1, {{4000.0, 0.1, 0.0, 1000}})).verdict, messages::Verdict::applied);
  const outputs::SnapshotFields fields = outputs::snapshot_fields(*twin);
  ASSERT_EQ(fields.attributes.size(), 2u);
  EXPECT_EQ(fields.attributes[0], std::make_pair(std::string("load_p_max_n"), 4000.0));
  EXPECT_EQ(fields.attributes[1], std::make_pair(std::string("load_alpha_rad"), 0.0));
  // B1 has one load basis (constant): displacement, strain, dilatation, max_principal_strain.
  std::vector<std::string> names;
  for (const auto& f : fields.fields) names.push_back(f.name);
  EXPECT_EQ(names, (std::vector<std::string>{"displacement", "strain", "dilatation",
                                             "max_principal_strain"}));
  std::vector<double> u;
  twin->engine().solver().displacement(4000.0, 0.0, u);
  const auto& disp = fields.fields[0];
  ASSERT_EQ(disp.kind, outputs::NodeField::Kind::vector);
  ASSERT_EQ(disp.values.size(), 3 * model_->disc().position.size());
  const auto& u_const = twin->engine().solver().basis_displacement(statics::basis_constant);
  for (std::size_t k = 0; k < model_->disc().position.size(); ++k) {
    ASSERT_EQ(disp.values[3 * k], u[2 * k]) << k;
    ASSERT_EQ(disp.values[3 * k + 1], u[2 * k + 1]) << k;
    ASSERT_EQ(disp.values[3 * k + 2], 0.0);
    ASSERT_DOUBLE_EQ(disp.values[3 * k + 1], 4000.0 * u_const[2 * k + 1]);  // P·U_const, α = 0
  }
  const auto strain =
      statics::pd_lagrange_strain(model_->disc(), twin->engine().solver().intact(), u);
  const auto& tensor = fields.fields[1];
  ASSERT_EQ(tensor.kind, outputs::NodeField::Kind::tensor6);
  double largest_principal = 0.0;
  std::size_t at = 0;
  for (std::size_t k = 0; k < strain.size(); ++k) {
    ASSERT_EQ(tensor.values[6 * k], strain[k].xx);
    ASSERT_EQ(tensor.values[6 * k + 1], strain[k].xy);
    ASSERT_EQ(tensor.values[6 * k + 3], strain[k].yy);
    ASSERT_EQ(fields.fields[2].values[k], strain[k].dilatation());
    const double p = fields.fields[3].values[k];
    if (std::isfinite(p) && p > largest_principal) {
      largest_principal = p;
      at = k;
    }
  }
  // The strain concentrates at the notch tip ((28 mm, 0) in B1's frame): the largest principal
  // strain sits within a horizon of it.
  const mesh::Point tip = model_->config().geometry.notches.at(0).tip();
  const mesh::Point p = model_->disc().position[at];
  EXPECT_LT(std::hypot(p.x - tip.x, p.y - tip.y), 2.0 * model_->disc().horizon)
      << "largest principal strain " << largest_principal << " at (" << p.x << ", " << p.y << ")";
}

TEST(ResultsFieldsStrip, FarFieldStrainIsTheUniaxialOneAndPeaksAtTheHoleRim) {
  // examples/strip-with-hole.toml at P = 20 kN along x: W = 60 mm, h = 5 mm, E = 68 GPa, so away
  // from the hole and the grips E_xx = P/(W·h·E) = 9.804e-4 (plane stress, small strain).
  auto parsed = config::load_config(std::string(PERITWIN_EXAMPLES_DIR) + "/strip-with-hole.toml");
  ASSERT_TRUE(parsed.ok()) << parsed.error_text();
  const auto model = b1_model(parsed.config->details.at(0));
  auto twin = make_twin(model);
  const double p = 20000.0;
  ASSERT_EQ(twin->apply({"strip-hole", "test", 1, {{p, 0.1, 0.0, 1}}}).verdict,
            messages::Verdict::applied);
  const outputs::SnapshotFields fields = outputs::snapshot_fields(*twin);
  const auto& strain = fields.fields.at(1);
  const auto& principal = fields.fields.at(3);
  ASSERT_EQ(strain.name, "strain");
  ASSERT_EQ(principal.name, "max_principal_strain");
  const mesh::Discretization& disc = model->disc();
  std::vector<double> far;
  std::size_t peak = 0;
  for (std::size_t k = 0; k < disc.position.size(); ++k) {
    const double x = disc.position[k].x;
    if ((x > 0.03 && x < 0.07) || (x > 0.13 && x < 0.17)) far.push_back(strain.values[6 * k]);
    if (principal.values[k] > principal.values[peak]) peak = k;
  }
  std::sort(far.begin(), far.end());
  const double want = p / (0.060 * 0.005 * 68e9);
  EXPECT_NEAR(far[far.size() / 2], want, 0.01 * want);  // measured 9.799e-4: 0.05 % off
  // The concentration: at the rim of the hole (r = 5 mm), at its top or bottom (x ≈ 0.1).
  const mesh::Point at = disc.position[peak];
  EXPECT_NEAR(std::hypot(at.x - 0.100, at.y - 0.030), 0.005, disc.dx);
  EXPECT_NEAR(at.x, 0.100, disc.dx);
  EXPECT_GT(principal.values[peak], 1.4 * want);  // measured 1.64 on the 1 mm grid (δ = 3 mm)
}

// --- the results directory -----------------------------------------------------------------

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Shape of an HDF5 dataset, read with the C API.
std::vector<hsize_t> dataset_dims(const fs::path& h5, const std::string& path) {
  const hid_t f = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(f, 0);
  const hid_t ds = H5Dopen2(f, path.c_str(), H5P_DEFAULT);
  EXPECT_GE(ds, 0) << path;
  std::vector<hsize_t> dims;
  if (ds >= 0) {
    const hid_t space = H5Dget_space(ds);
    dims.resize(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
    H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    H5Sclose(space);
    H5Dclose(ds);
  }
  H5Fclose(f);
  return dims;
}

std::vector<double> dataset_doubles(const fs::path& h5, const std::string& path) {
  const hid_t f = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t ds = H5Dopen2(f, path.c_str(), H5P_DEFAULT);
  const hid_t space = H5Dget_space(ds);
  std::vector<double> out(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
  EXPECT_GE(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), 0);
  H5Sclose(space);
  H5Dclose(ds);
  H5Fclose(f);
  return out;
}

std::vector<hsize_t> parse_dims(const std::string& text) {
  std::vector<hsize_t> dims;
  std::istringstream in(text);
  for (hsize_t d = 0; in >> d;) dims.push_back(d);
  return dims;
}

/// Checks every DataItem of the XDMF against the HDF5 dataset it names, and the structure the
/// Xdmf3 reader needs: the geometry of every Uniform grid is XYZ of n x 3 (ParaView 5.11's Xdmf3
/// reader crashed on the X_Y geometry of layout 2), its Polyvertex topology carries its
/// connectivity, every attribute's components match its AttributeType.
void expect_xdmf_readable(const fs::path& dir, const std::string& xdmf_text, std::size_t nodes,
                          std::size_t& grids, std::vector<std::string>& attributes) {
  const std::regex topology(
      R"re(<Topology TopologyType="Polyvertex" NumberOfElements="(\d+)" NodesPerElement="1">\s*<DataItem Dimensions="(\d+)" NumberType="Int" Precision="8" Format="HDF">([^:<]+):/mesh/vertices</DataItem>\s*</Topology>)re");
  const std::regex geometry(
      R"re(<Geometry GeometryType="XYZ">\s*<DataItem Dimensions="(\d+) 3" NumberType="Float" Precision="8" Format="HDF">[^:<]+:/mesh/xyz</DataItem>\s*</Geometry>)re");
  const std::regex attribute(
      R"re(<Attribute Name="(\w+)" AttributeType="(\w+)" Center="Node">\s*<DataItem Dimensions="([\d ]+)" NumberType="Float" Precision="(\d)" Format="HDF">([^:<]+):([^<]+)</DataItem>)re");
  grids = 0;
  for (auto it = std::sregex_iterator(xdmf_text.begin(), xdmf_text.end(), topology);
       it != std::sregex_iterator(); ++it) {
    EXPECT_EQ(std::stoul((*it)[1]), nodes);
    EXPECT_EQ(std::stoul((*it)[2]), nodes);
    EXPECT_TRUE(fs::exists(dir / (*it)[3].str()));
    ++grids;
  }
  std::size_t geometries = 0;
  for (auto it = std::sregex_iterator(xdmf_text.begin(), xdmf_text.end(), geometry);
       it != std::sregex_iterator(); ++it) {
    EXPECT_EQ(std::stoul((*it)[1]), nodes);
    ++geometries;
  }
  std::size_t uniform = 0;
  for (auto p = xdmf_text.find("GridType=\"Uniform\""); p != std::string::npos;
       p = xdmf_text.find("GridType=\"Uniform\"", p + 1)) {
    ++uniform;
  }
  EXPECT_EQ(grids, uniform) << "a Uniform grid without the Polyvertex connectivity";
  EXPECT_EQ(xdmf_text.find("X_Y"), std::string::npos) << "Xdmf3 crashes on an X_Y geometry";
  EXPECT_EQ(geometries, uniform);
  attributes.clear();
  for (auto it = std::sregex_iterator(xdmf_text.begin(), xdmf_text.end(), attribute);
       it != std::sregex_iterator(); ++it) {
    const std::string name = (*it)[1], type = (*it)[2];
    const auto dims = parse_dims((*it)[3]);
    const fs::path h5 = dir / (*it)[5].str();
    const std::size_t components = type == "Scalar" ? 1 : type == "Vector" ? 3 : 6;
    EXPECT_TRUE(type == "Scalar" || type == "Vector" || type == "Tensor6") << type;
    EXPECT_EQ(dims.front(), nodes) << name;
    EXPECT_EQ(components == 1 ? dims.size() : dims.at(1), components == 1 ? 1u : components)
        << name;
    EXPECT_EQ(dataset_dims(h5, (*it)[6]), dims) << name << " " << (*it)[6];
    attributes.push_back(name);
  }
}

std::pair<png_uint_32, png_uint_32> png_size(const fs::path& p) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  EXPECT_NE(png_image_begin_read_from_file(&img, p.c_str()), 0) << p;
  const std::pair<png_uint_32, png_uint_32> out{img.width, img.height};
  png_image_free(&img);
  return out;
}

TEST_F(ResultsFieldsTest, AFreshStartKeepsAnEarlierRunsHistoryUnderANewName) {
  // A run of 3 states, then a new run from the initial state (no checkpoint) in the same
  // directory: the old file is kept whole as b1-ct.run1.h5 (4 rows, states 0-3), the new one
  // holds the new run's row only; a third start over a file of the initial state alone has
  // nothing to keep.
  config::DetailConfig config = b1_config("every_batches = 0");
  config.output.directory = dir_.string();
  config.output.png = false;
  const auto model = b1_model(config);
  {
    auto twin = make_twin(model);
    outputs::DetailOutputs outputs(*twin);
    for (std::int64_t seq = 1; seq <= 3; ++seq) {
      ASSERT_TRUE(twin->apply(batch(seq, {{4000.0, 0.1, 0.0, 1000}})).applied());
      outputs.record(*twin);
    }
    outputs.finish(*twin);
  }
  auto seqs = [](const fs::path& h5) {
    std::vector<std::int64_t> out;
    for (const auto& row : outputs::read_time_series(h5)) out.push_back(row.state_seq);
    return out;
  };
  ASSERT_EQ(seqs(dir_ / "b1-ct.h5"), (std::vector<std::int64_t>{0, 1, 2, 3}));
  for (int run = 1; run <= 2; ++run) {
    auto twin = make_twin(model);
    outputs::DetailOutputs outputs(*twin);
    outputs.finish(*twin);
  }
  EXPECT_EQ(seqs(dir_ / "b1-ct.run1.h5"), (std::vector<std::int64_t>{0, 1, 2, 3}));
  EXPECT_FALSE(fs::exists(dir_ / "b1-ct.run2.h5"));
  EXPECT_EQ(seqs(dir_ / "b1-ct.h5"), (std::vector<std::int64_t>{0}));
}

TEST_F(ResultsFieldsTest, ResultsDirectoryIsWhatParaViewAndPeopleRead) {
  config::DetailConfig config = b1_config("every_batches = 2");
  config.output.directory = dir_.string();
  config.output.field_every_batches = 2;
  config.output.png = true;
  auto twin = make_twin(b1_model(config));
  twin->catch_up_life();  // the estimate of state 0, as the daemon and the replay tool make it
  outputs::DetailOutputs outputs(*twin);
  const fs::path damage_png = dir_ / "b1-ct-damage.png";
  EXPECT_TRUE(fs::exists(damage_png)) << "state 0 is a snapshot: its picture is written";
  fs::remove(damage_png);
  ASSERT_EQ(twin->apply(batch(1, {{4000.0, 0.1, 0.0, 6000}})).verdict, messages::Verdict::applied);
  outputs.record(*twin);
  EXPECT_FALSE(fs::exists(damage_png)) << "state 1 is not a snapshot";
  ASSERT_EQ(twin->apply(batch(2, {{4000.0, 0.1, 0.0, 6000}})).verdict, messages::Verdict::applied);
  outputs.record(*twin);
  // field_every_batches = 2: the pictures of state 2 are there before the twin stops.
  ASSERT_TRUE(fs::exists(damage_png));
  ASSERT_TRUE(fs::exists(dir_ / "b1-ct-crack-length.png"));
  const auto [w, h] = png_size(damage_png);
  EXPECT_GT(w, 800u);  // the raster plus axes and the colour bar
  EXPECT_GT(h, 600u);
  std::vector<double> u;
  twin->engine().solver().displacement(4000.0, 0.0, u);
  outputs.finish(*twin);  // closes the file (HDF5 opens a file once per process)

  const fs::path h5 = dir_ / "b1-ct.h5";
  const std::size_t nodes = model_->disc().position.size();
  std::size_t grids = 0;
  std::vector<std::string> attributes;
  expect_xdmf_readable(dir_, slurp(dir_ / "b1-ct.xdmf"), nodes, grids, attributes);
  EXPECT_EQ(grids, 2u);  // states 0 and 2 (finish() adds none: state 2 has its snapshot)
  EXPECT_EQ(std::count(attributes.begin(), attributes.end(), "displacement"), 2);
  EXPECT_EQ(std::count(attributes.begin(), attributes.end(), "strain"), 2);
  EXPECT_EQ(std::count(attributes.begin(), attributes.end(), "damage"), 2);
  // The mesh ParaView sees: the nodes with z = 0, connectivity 0..n-1.
  const auto xyz = dataset_doubles(h5, "/mesh/xyz");
  ASSERT_EQ(xyz.size(), 3 * nodes);
  const auto vertices = dataset_doubles(h5, "/mesh/vertices");
  for (std::size_t k = 0; k < nodes; ++k) {
    ASSERT_EQ(xyz[3 * k], model_->disc().position[k].x);
    ASSERT_EQ(xyz[3 * k + 1], model_->disc().position[k].y);
    ASSERT_EQ(xyz[3 * k + 2], 0.0);
    ASSERT_EQ(vertices[k], static_cast<double>(k));
  }
  // The last snapshot's displacement is the model's solution at 4 kN, node by node.
  const auto disp = dataset_doubles(h5, "/fields/step_000001/displacement");
  ASSERT_EQ(disp.size(), 3 * nodes);
  for (std::size_t k = 0; k < nodes; ++k) {
    ASSERT_EQ(disp[3 * k], u[2 * k]);
    ASSERT_EQ(disp[3 * k + 1], u[2 * k + 1]);
  }
  const auto rows = outputs::read_time_series(h5);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[2].remaining_state_seq, 2);  // estimated at states 0 and 2 (every_batches = 2)
  EXPECT_EQ(rows[1].remaining_state_seq, 0);
  EXPECT_EQ(rows[0].remaining_state_seq, 0);
}

}  // namespace
}  // namespace peritwin::twin
