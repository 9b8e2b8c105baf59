// twin/config: the example configs parse to the benchmark numbers, every error kind names file,
// line and key path, and resolve() binds supports and loads to the expected nodes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numbers>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "config/config.h"
#include "validation/specimens.h"

namespace peritwin::twin {
namespace {

using namespace peritwin::validation;  // the benchmark specimens

std::string examples_dir() {
#ifdef PERITWIN_EXAMPLES_DIR
  return PERITWIN_EXAMPLES_DIR;
#else
  std::string file = __FILE__;  // <repo>/tests/twin/test_config.cpp
  for (int i = 0; i < 3; ++i) file = file.substr(0, file.find_last_of('/'));
  return file + "/examples";
#endif
}

/// A TOML document as lines, so that tests can edit it and find the line numbers they expect.
struct Doc {
  std::vector<std::string> lines;

  /// 1-based number of the first line starting with `prefix`.
  [[nodiscard]] std::uint32_t line_of(std::string_view prefix, std::uint32_t from = 1) const {
    for (std::size_t i = from - 1; i < lines.size(); ++i) {
      if (lines[i].starts_with(prefix)) return static_cast<std::uint32_t>(i + 1);
    }
    ADD_FAILURE() << "no line starts with " << prefix;
    return 0;
  }
  void replace(std::string_view prefix, std::string line) { lines[line_of(prefix) - 1] = line; }
  void erase(std::string_view prefix) { lines.erase(lines.begin() + line_of(prefix) - 1); }
  void insert_after(std::string_view prefix, std::string line) {
    lines.insert(lines.begin() + line_of(prefix), std::move(line));
  }
  [[nodiscard]] std::string text() const {
    std::string t;
    for (const auto& l : lines) t += l + "\n";
    return t;
  }
};

/// A 10 mm x 5 mm plate with a hole, pulled at its right edge and held at its left edge.
Doc plate() {
  return {{
      R"([[detail]])",
      R"(id = "plate")",
      R"([detail.geometry])",
      R"(thickness = 0.005)",
      R"(outline = [{ x_min = 0.0, y_min = 0.0, x_max = 0.010, y_max = 0.005 }])",
      R"(holes = [{ centre = [0.005, 0.0025], radius = 0.001 }])",
      R"([detail.grid])",
      R"(dx = 0.0005)",
      R"(horizon_ratio = 3.015)",
      R"([detail.material])",
      R"(E = 70e9)",
      R"(nu = 0.3)",
      R"([detail.fatigue])",
      R"(law = "strain_range")",
      R"(A1 = 100.0)",
      R"(m1 = 2.0)",
      R"(A2 = 1000.0)",
      R"(m2 = 2.5)",
      R"([[detail.load]])",
      R"(point = [0.010, 0.0025])",
      R"(constant = [1.0, 0.0])",
      R"([[detail.support]])",
      R"(region = { x_min = 0.0, y_min = 0.0, x_max = 0.0005, y_max = 0.005 })",
  }};
}

using XY = std::pair<double, double>;
XY xy(mesh::Point p) { return {p.x, p.y}; }

config::ConfigResult parse(const Doc& doc) {
  return config::parse_config(doc.text(), "plate.toml");
}

/// Exactly one error, at (line, path), whose reason contains `reason`.
void expect_one_error(const config::ConfigResult& r, std::uint32_t line, std::string_view path,
                      std::string_view reason) {
  ASSERT_FALSE(r.ok());
  ASSERT_EQ(r.errors.size(), 1u) << r.error_text();
  const config::ConfigError& e = r.errors[0];
  EXPECT_EQ(e.file, "plate.toml");
  EXPECT_EQ(e.line, line) << e.message();
  EXPECT_EQ(e.path, path) << e.message();
  EXPECT_NE(e.reason.find(reason), std::string::npos) << e.message();
}

TEST(Config, PlateParsesWithDefaults) {
  Doc doc = plate();
  doc.erase("horizon_ratio");
  const config::ConfigResult r = parse(doc);
  ASSERT_TRUE(r.ok()) << r.error_text();
  ASSERT_EQ(r.config->details.size(), 1u);
  const config::DetailConfig& d = r.config->details[0];
  EXPECT_EQ(d.id, "plate");
  EXPECT_EQ(d.token, "PLATE");
  EXPECT_EQ(d.horizon_ratio, 3.015);
  EXPECT_EQ(d.geometry.rigid_factor, 200.0);
  EXPECT_EQ(d.material.fracture_toughness, 0.0);
  EXPECT_EQ(d.model.kind, model::ModelKind::state_based);
  EXPECT_EQ(d.model.kernel, model::Kernel::constant);
  EXPECT_EQ(d.model.plane, model::PlaneCondition::plane_stress);
  EXPECT_TRUE(d.model.surface_correction);
  EXPECT_EQ(d.fatigue.phase_switch_damage, 0.398);
  EXPECT_EQ(d.fatigue.strain.eps_inf, 0.0);
  EXPECT_EQ(d.fatigue.strain.eps_inf_prop, 0.0);
  EXPECT_EQ(d.loads[0].per_cos.x, 0.0);
  EXPECT_EQ(d.loads[0].where.line, doc.line_of("[[detail.load]]"));
  EXPECT_EQ(d.loads[0].where.path, "detail[0].load[0]");
  EXPECT_TRUE(d.supports[0].fix_x);
  EXPECT_TRUE(d.supports[0].fix_y);
  // Relative to the config file's directory ("plate.toml": the working directory), made absolute.
  EXPECT_EQ(d.output.directory, (std::filesystem::current_path() / "results/plate").string());
  EXPECT_EQ(d.output.field_every_batches, 10);
  EXPECT_FALSE(d.output.png);
  EXPECT_EQ(d.life.criterion, config::LifeCriterion::phase3);
  EXPECT_TRUE(d.life.empirical_spectrum());
  EXPECT_EQ(d.life.band, config::BandSource::none);
  EXPECT_EQ(d.checkpoint.every_batches, 100);
  EXPECT_EQ(d.checkpoint.every_seconds, 300.0);
}

TEST(Config, PhiZeroDefaultsToTheSplitDamageOfTheHorizon) {
  // With δ = 2Δx a straight crack's faces have φ = 0.35 (hand count in test_critical_bond_energy):
  // 0.398 would keep them out of phase II, so the default follows the horizon; phi0 given wins.
  Doc doc = plate();
  doc.erase("horizon_ratio");
  doc.insert_after("dx = ", "horizon_ratio = 2.0");
  config::ConfigResult r = parse(doc);
  ASSERT_TRUE(r.ok()) << r.error_text();
  EXPECT_EQ(r.config->details[0].fatigue.phase_switch_damage, 0.35);
  doc.insert_after("law = ", "phi0 = 0.3");
  r = parse(doc);
  ASSERT_TRUE(r.ok()) << r.error_text();
  EXPECT_EQ(r.config->details[0].fatigue.phase_switch_damage, 0.3);
}

TEST(Config, B1Example) {
  const config::ConfigResult r = config::load_config(examples_dir() + "/b1-ct-al6061.toml");
  ASSERT_TRUE(r.ok()) << r.error_text();
  ASSERT_EQ(r.config->details.size(), 1u);
  const config::DetailConfig& d = r.config->details[0];
  EXPECT_EQ(d.id, "b1-ct");
  EXPECT_EQ(d.token, "B1_CT");
  const mesh::DetailGeometry& g = d.geometry;
  ASSERT_EQ(g.outline.size(), 1u);
  ASSERT_EQ(g.outline[0].shape, mesh::Region::Shape::rectangle);
  const mesh::Rectangle& o = g.outline[0].rectangle;
  EXPECT_EQ(xy({o.x_min, o.y_min}), XY(0.0, -0.030));
  EXPECT_EQ(xy({o.x_max, o.y_max}), XY(0.0625, 0.030));
  EXPECT_EQ(g.thickness, 0.010);
  EXPECT_EQ(g.rigid_factor, 200.0);
  EXPECT_TRUE(g.holes.empty());
  ASSERT_EQ(g.notches.size(), 1u);
  ASSERT_EQ(g.notches[0].path.size(), 2u);
  EXPECT_EQ(g.notches[0].name, "notch 0");
  EXPECT_EQ(xy(g.notches[0].path[0]), XY(-0.001, 0.0));
  EXPECT_EQ(xy(g.notches[0].tip()), XY(0.0275, 0.0));
  EXPECT_EQ(d.stress_intensity.method, config::StressIntensityMethod::compact_tension);
  EXPECT_EQ(d.stress_intensity.width, 0.050);
  EXPECT_EQ(xy(d.stress_intensity.load_line), XY(0.0125, 0.0));
  ASSERT_EQ(g.rigid_regions.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const mesh::Region& pin = g.rigid_regions[k];
    ASSERT_EQ(pin.shape, mesh::Region::Shape::circle);
    EXPECT_EQ(xy(pin.circle.centre), XY(0.0125, k == 0 ? 0.275 * 0.050 : -0.275 * 0.050));
    EXPECT_EQ(pin.circle.radius, 0.00625);
  }
  EXPECT_EQ(d.dx, 0.001);
  EXPECT_EQ(d.horizon_ratio, 3.015);
  EXPECT_EQ(d.material.youngs_modulus, 68e9);
  EXPECT_EQ(d.material.poisson_ratio, 0.33);
  EXPECT_EQ(d.material.fracture_toughness, 48.7e6);
  EXPECT_EQ(d.model.kind, model::ModelKind::state_based);
  EXPECT_EQ(d.fatigue.law, fatigue::FatigueLaw::strain_range);
  EXPECT_EQ(d.fatigue.phase_switch_damage, 0.398);
  EXPECT_EQ(d.fatigue.strain.A1, 103.7465);
  EXPECT_EQ(d.fatigue.strain.m1, 2.29153);
  EXPECT_EQ(d.fatigue.strain.A2, 1301.0);
  EXPECT_EQ(d.fatigue.strain.m2, 2.6183);
  ASSERT_EQ(d.loads.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const config::LoadSpec& l = d.loads[k];
    ASSERT_EQ(l.target.kind, config::NodeSelector::Kind::region);
    EXPECT_EQ(xy(l.target.region.circle.centre), xy(g.rigid_regions[k].circle.centre));
    EXPECT_EQ(l.target.region.circle.radius, 0.00625);
    EXPECT_EQ(xy(l.constant), XY(0.0, k == 0 ? 1.0 : -1.0));
    EXPECT_EQ(xy(l.per_cos), XY(0.0, 0.0));
    EXPECT_EQ(xy(l.per_sin), XY(0.0, 0.0));
  }
  EXPECT_EQ(d.loads[0].name, "upper pin");
  ASSERT_EQ(d.supports.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const config::SupportSpec& s = d.supports[k];
    ASSERT_EQ(s.target.kind, config::NodeSelector::Kind::point);
    EXPECT_EQ(xy(s.target.point), XY(0.0625, k == 0 ? 0.0005 : -0.0005));
    EXPECT_TRUE(s.fix_x && s.fix_y);
  }
  EXPECT_EQ(std::filesystem::path(d.output.directory).filename(), "b1-ct");
  EXPECT_EQ(std::filesystem::path(d.output.directory).parent_path().filename(), "results");
  EXPECT_TRUE(std::filesystem::path(d.output.directory).is_absolute());
  EXPECT_TRUE(d.output.png);
  EXPECT_EQ(d.life.criterion, config::LifeCriterion::crack_length);
  EXPECT_EQ(d.life.critical_crack_length, 0.008);
  EXPECT_EQ(d.life.every_batches, 10);
  ASSERT_EQ(d.life.reference_spectrum.size(), 1u);
  EXPECT_EQ(d.life.reference_spectrum[0], (core::LoadBlock{4000.0, 0.1, 0.0, 1000}));
  EXPECT_EQ(d.life.band, config::BandSource::a2_scatter);
  EXPECT_EQ(d.life.a2_relative_scatter, 0.2);
  EXPECT_EQ(d.checkpoint.every_batches, 100);
  EXPECT_EQ(d.checkpoint.every_seconds, 300.0);
}

TEST(Config, B1ExampleIsTheSpecimen) {
  const config::ConfigResult r = config::load_config(examples_dir() + "/b1-ct-al6061.toml");
  ASSERT_TRUE(r.ok()) << r.error_text();
  const config::DetailConfig& d = r.config->details[0];
  const statics::Specimen s =
      make_compact_tension(CompactTensionSpec{}, d.model, d.dx, d.horizon_ratio);
  EXPECT_EQ(d.material.youngs_modulus, s.material.youngs_modulus);
  EXPECT_EQ(d.material.poisson_ratio, s.material.poisson_ratio);
  EXPECT_EQ(d.material.fracture_toughness, s.material.fracture_toughness);
  EXPECT_EQ(d.geometry.thickness, s.geometry.thickness);
  EXPECT_EQ(d.geometry.rigid_factor, s.geometry.rigid_factor);

  // Same nodes, bonds, rigid nodes and pre-cut bonds (the pin boundary passes exactly through
  // lattice points, so this also checks the pin centres to the last bit).
  const mesh::Discretization disc = discretize(d);
  ASSERT_EQ(disc.num_nodes(), 62 * 60);  // no holes: node (i, j) has index 62j + i
  EXPECT_EQ(disc.num_nodes(), s.disc.num_nodes());
  EXPECT_EQ(disc.bond_i, s.disc.bond_i);
  EXPECT_EQ(disc.bond_j, s.disc.bond_j);
  EXPECT_EQ(disc.rigid, s.disc.rigid);
  EXPECT_EQ(disc.bond_precut, s.disc.bond_precut);

  const config::ResolvedBoundary b = config::resolve(d, disc);
  ASSERT_TRUE(b.ok());
  ASSERT_EQ(b.supports.size(), 2u);
  EXPECT_EQ(b.supports[0].nodes, std::vector<mesh::NodeIndex>{30 * 62 + 61});  // (61.5, 0.5) mm
  EXPECT_EQ(b.supports[1].nodes, std::vector<mesh::NodeIndex>{29 * 62 + 61});  // (61.5, -0.5) mm
  ASSERT_EQ(s.supports.size(), 2u);
  ASSERT_EQ(b.loads.size(), 2u);
  ASSERT_EQ(s.loads.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(b.supports[k].nodes, s.supports[k].nodes);
    EXPECT_EQ(b.supports[k].fix_x, s.supports[k].fix_x);
    EXPECT_EQ(b.supports[k].fix_y, s.supports[k].fix_y);
    EXPECT_EQ(b.loads[k].nodes, s.loads[k].nodes);
    EXPECT_EQ(b.loads[k].nodes.size(), 126u);
    EXPECT_EQ(b.loads[k].constant.x, s.loads[k].constant.x);
    EXPECT_EQ(b.loads[k].constant.y, s.loads[k].constant.y);
  }
}

TEST(Config, B2Example) {
  const config::ConfigResult r = config::load_config(examples_dir() + "/b2-cts-al6061.toml");
  ASSERT_TRUE(r.ok()) << r.error_text();
  const config::DetailConfig& d = r.config->details[0];
  EXPECT_EQ(d.id, "b2-cts");
  EXPECT_EQ(d.token, "B2_CTS");
  const mesh::Rectangle& o = d.geometry.outline.at(0).rectangle;
  EXPECT_EQ(xy({o.x_min, o.y_min}), XY(0.0, -0.045));
  EXPECT_EQ(xy({o.x_max, o.y_max}), XY(0.090, 0.045));
  EXPECT_EQ(d.geometry.thickness, 0.010);
  ASSERT_EQ(d.geometry.notches.size(), 1u);
  EXPECT_EQ(xy(d.geometry.notches[0].path.at(0)), XY(0.0, 0.0));
  EXPECT_EQ(xy(d.geometry.notches[0].tip()), XY(0.045, 0.0));
  const double xs[] = {0.010, 0.045, 0.080};
  ASSERT_EQ(d.geometry.rigid_regions.size(), 6u);
  for (int k = 0; k < 6; ++k) {
    const mesh::Circle& c = d.geometry.rigid_regions[k].circle;
    EXPECT_EQ(xy(c.centre), XY(xs[k % 3], k < 3 ? 0.030 : -0.030));
    EXPECT_EQ(c.radius, 0.004);  // Ø 8 mm
  }

  // 000 Eq. (51) per unit P: F1 = 0.5 cos α + (e/f) sin α (+y), F2 = −sin α (x),
  // F3 = 0.5 cos α − (e/f) sin α (+y).
  const double e_over_f = 3.0 / 7.0;
  ASSERT_EQ(d.loads.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    const config::LoadSpec& l = d.loads[k];
    EXPECT_EQ(xy(l.target.region.circle.centre), XY(xs[k], 0.030));
    EXPECT_EQ(xy(l.constant), XY(0.0, 0.0));
  }
  EXPECT_EQ(xy(d.loads[0].per_cos), XY(0.0, 0.5));
  EXPECT_EQ(xy(d.loads[0].per_sin), XY(0.0, e_over_f));
  EXPECT_EQ(xy(d.loads[1].per_cos), XY(0.0, 0.0));
  EXPECT_EQ(xy(d.loads[1].per_sin), XY(-1.0, 0.0));
  EXPECT_EQ(xy(d.loads[2].per_cos), XY(0.0, 0.5));
  EXPECT_EQ(xy(d.loads[2].per_sin), XY(0.0, -e_over_f));
  ASSERT_EQ(d.supports.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(xy(d.supports[k].target.region.circle.centre), XY(xs[k], -0.030));
    EXPECT_TRUE(d.supports[k].fix_x && d.supports[k].fix_y);
  }
  EXPECT_EQ(d.life.criterion, config::LifeCriterion::connectivity);
  EXPECT_TRUE(d.life.empirical_spectrum());
  EXPECT_EQ(d.life.band, config::BandSource::none);

  const mesh::Discretization disc = discretize(d);
  EXPECT_EQ(disc.num_nodes(), 90 * 90);
  const config::ResolvedBoundary b = config::resolve(d, disc);
  ASSERT_TRUE(b.ok());
  for (const auto& l : b.loads) EXPECT_EQ(l.nodes.size(), 52u);  // lattice points in Ø 8 mm
}

TEST(Config, ResolveSelectsNodesOnASmallGrid) {
  // 4 x 3 nodes at x = 0.5, 1.5, 2.5, 3.5 mm and y = 0.5, 1.5, 2.5 mm: node (i, j) = 4j + i.
  Doc doc = plate();
  doc.replace("outline", "outline = [{ x_min = 0.0, y_min = 0.0, x_max = 0.004, y_max = 0.003 }]");
  doc.erase("holes");
  doc.replace("dx = ", "dx = 0.001");
  doc.lines.resize(doc.line_of("[[detail.load]]") - 1);
  doc.lines.insert(
      doc.lines.end(),
      {"[[detail.load]]", "region = { x_min = 0.001, y_min = 0.001, x_max = 0.003, y_max = 0.003 }",
       "constant = [1.0, 2.0]", "per_cos = [3.0, 4.0]", "per_sin = [5.0, 6.0]", "[[detail.load]]",
       "region = { centre = [0.0015, 0.0015], radius = 0.0011 }", "constant = [0.0, 1.0]",
       "[[detail.support]]", "point = [0.0, 0.0]", "[[detail.support]]", "point = [0.004, 0.0011]",
       "fix_x = false"});
  const config::ConfigResult r = parse(doc);
  ASSERT_TRUE(r.ok()) << r.error_text();
  const config::DetailConfig& d = r.config->details[0];
  const mesh::Discretization disc = discretize(d);
  ASSERT_EQ(disc.num_nodes(), 12);
  config::ResolvedBoundary b = config::resolve(d, disc);
  ASSERT_TRUE(b.ok());
  ASSERT_EQ(b.supports.size(), 2u);
  EXPECT_EQ(b.supports[0].nodes, std::vector<mesh::NodeIndex>{0});
  EXPECT_TRUE(b.supports[0].fix_x && b.supports[0].fix_y);
  EXPECT_EQ(b.supports[1].nodes, std::vector<mesh::NodeIndex>{7});  // (3.5, 1.5) mm
  EXPECT_FALSE(b.supports[1].fix_x);
  EXPECT_TRUE(b.supports[1].fix_y);
  ASSERT_EQ(b.loads.size(), 2u);
  EXPECT_EQ(b.loads[0].nodes, (std::vector<mesh::NodeIndex>{5, 6, 9, 10}));
  EXPECT_EQ(xy(b.loads[0].constant), XY(1.0, 2.0));
  EXPECT_EQ(xy(b.loads[0].per_cos), XY(3.0, 4.0));
  EXPECT_EQ(xy(b.loads[0].per_sin), XY(5.0, 6.0));
  EXPECT_EQ(b.loads[1].nodes, (std::vector<mesh::NodeIndex>{1, 4, 5, 6, 9}));

  // A region between the nodes selects none: an error naming the load, the rest is resolved.
  doc.lines.insert(doc.lines.end(),
                   {"[[detail.load]]", "region = { centre = [0.002, 0.002], radius = 0.0001 }",
                    "constant = [0.0, 1.0]"});
  const config::ConfigResult r2 = parse(doc);
  ASSERT_TRUE(r2.ok()) << r2.error_text();
  b = config::resolve(r2.config->details[0], disc);
  ASSERT_EQ(b.errors.size(), 1u);
  EXPECT_EQ(b.errors[0].line, 31u);  // its [[detail.load]] header
  EXPECT_EQ(b.errors[0].path, "detail[0].load[2]");
  EXPECT_EQ(b.errors[0].message(),
            "plate.toml:31:1: detail[0].load[2]: the region selects no node at dx = 0.001 m");
  EXPECT_EQ(b.loads.size(), 2u);
}

TEST(Config, ModelOptionsAndSeveralDetails) {
  Doc doc = plate();
  doc.insert_after("horizon_ratio", "[detail.model]");
  doc.insert_after("[detail.model]", R"(kind = "bond_based")");
  doc.insert_after("kind = ", R"(kernel = "conical")");
  doc.insert_after("kernel = ", R"(plane = "plane_strain")");
  doc.insert_after("plane = ", "surface_correction = false");
  Doc second = plate();
  second.replace("id = ", R"(id = "Plate_2")");
  doc.lines.insert(doc.lines.end(), second.lines.begin(), second.lines.end());
  const config::ConfigResult r = parse(doc);
  ASSERT_TRUE(r.ok()) << r.error_text();
  ASSERT_EQ(r.config->details.size(), 2u);
  const model::ModelOptions& m = r.config->details[0].model;
  EXPECT_EQ(m.kind, model::ModelKind::bond_based);
  EXPECT_EQ(m.kernel, model::Kernel::conical);
  EXPECT_EQ(m.plane, model::PlaneCondition::plane_strain);
  EXPECT_FALSE(m.surface_correction);
  EXPECT_EQ(r.config->details[1].id, "Plate_2");
  EXPECT_EQ(r.config->details[1].token, "PLATE_2");
  EXPECT_EQ(r.config->details[1].where.line, 29u);
  EXPECT_EQ(r.config->details[1].where.path, "detail[1]");
  EXPECT_EQ(r.config->details[1].model.kind, model::ModelKind::state_based);
}

TEST(Config, MaterialScatterIsRead) {
  // 004's 193 ± 3 GPa: E_std and E_seed reach model::Material; absent, there is no scatter.
  const config::ConfigResult plain = parse(plate());
  ASSERT_TRUE(plain.ok()) << plain.error_text();
  EXPECT_EQ(plain.config->details[0].material.youngs_modulus_std, 0.0);
  EXPECT_EQ(plain.config->details[0].material.youngs_modulus_seed, 0u);
  Doc doc = plate();
  doc.replace("E = ", "E = 193e9");
  doc.insert_after("nu = ", "E_std = 3e9");
  doc.insert_after("E_std = ", "E_seed = 9007199254740993");  // above 2^53: an integer, exactly
  const config::ConfigResult r = parse(doc);
  ASSERT_TRUE(r.ok()) << r.error_text();
  const model::Material& m = r.config->details[0].material;
  EXPECT_EQ(m.youngs_modulus, 193e9);
  EXPECT_EQ(m.youngs_modulus_std, 3e9);
  EXPECT_EQ(m.youngs_modulus_seed, 9007199254740993u);
}

TEST(Config, FatigueLawsMapEveryField) {
  const auto fatigue = [](std::vector<std::string> keys, bool bond_based = false) {
    Doc doc = plate();
    if (bond_based) {
      doc.lines.push_back("[detail.model]");
      doc.lines.push_back(R"(kind = "bond_based")");
    }
    const std::uint32_t at = doc.line_of("[detail.fatigue]");
    doc.lines.erase(doc.lines.begin() + at, doc.lines.begin() + at + 5);  // law, A1, m1, A2, m2
    doc.lines.insert(doc.lines.begin() + at, keys.begin(), keys.end());
    const config::ConfigResult r = parse(doc);
    EXPECT_TRUE(r.ok()) << r.error_text();
    return r.ok() ? r.config->details[0].fatigue : fatigue::FatigueSettings{};
  };
  const fatigue::FatigueSettings e =
      fatigue({R"(law = "energy")", "A1 = 1.5", "m1 = 2.5", "A2 = 3.5", "m2 = 4.5",
               "eps_inf = 1e-4", "eps_inf_prop = 2e-5", "phi0 = 0.5"});
  EXPECT_EQ(e.law, fatigue::FatigueLaw::energy);
  EXPECT_EQ(e.strain.A1, 1.5);
  EXPECT_EQ(e.strain.m1, 2.5);
  EXPECT_EQ(e.strain.A2, 3.5);
  EXPECT_EQ(e.strain.m2, 4.5);
  EXPECT_EQ(e.strain.eps_inf, 1e-4);
  EXPECT_EQ(e.strain.eps_inf_prop, 2e-5);
  EXPECT_EQ(e.phase_switch_damage, 0.5);
  EXPECT_TRUE(e.compressed_bonds_fatigue);  // 000 Eq. (15)'s absolute range

  EXPECT_EQ(e.static_failure, fatigue::StaticFailure::critical_stretch);
  const fatigue::FatigueSettings g =
      fatigue({R"(law = "strain_range")", "A1 = 1.5", "m1 = 2.5", "A2 = 3.5", "m2 = 4.5",
               R"(static_failure = "critical_bond_energy")", "compressed_bonds_fatigue = false"});
  EXPECT_EQ(g.static_failure, fatigue::StaticFailure::critical_bond_energy);
  EXPECT_FALSE(g.compressed_bonds_fatigue);

  // Issue 34: the compression rule, Newman's parameters with the closure rule.
  EXPECT_EQ(e.compression, fatigue::CompressionRule::full_range);
  EXPECT_TRUE(e.mirrors_compressive_cycles());
  const fatigue::FatigueSettings c =
      fatigue({R"(law = "strain_range")", "A1 = 1.5", "m1 = 2.5", "A2 = 3.5", "m2 = 4.5",
               R"(compression = "contact")"});
  EXPECT_EQ(c.compression, fatigue::CompressionRule::contact);
  EXPECT_FALSE(c.mirrors_compressive_cycles());  // a fully compressive cycle shuts the crack
  const fatigue::FatigueSettings n =
      fatigue({R"(law = "energy")", "A1 = 1.5", "m1 = 2.5", "A2 = 3.5", "m2 = 4.5",
               R"(compression = "closure")", "closure_constraint = 2.5",
               "closure_smax_over_flow_stress = 0.4"});
  EXPECT_EQ(n.compression, fatigue::CompressionRule::closure);
  EXPECT_EQ(n.closure.constraint, 2.5);
  EXPECT_EQ(n.closure.smax_over_flow_stress, 0.4);

  const fatigue::FatigueSettings b =
      fatigue({R"(law = "bilinear")", "s0 = 1e-3", "sc = 3e-3", "A = 2e8"}, true);
  EXPECT_EQ(b.law, fatigue::FatigueLaw::bilinear);
  EXPECT_EQ(b.bilinear.s0, 1e-3);
  EXPECT_EQ(b.bilinear.sc, 3e-3);
  EXPECT_EQ(b.bilinear.A, 2e8);
  EXPECT_EQ(b.bilinear.m, 4.0);
  EXPECT_EQ(b.phase_switch_damage, 0.398);
  EXPECT_EQ(b.cycle_increment, 1000);
  const fatigue::FatigueSettings b2 = fatigue(
      {R"(law = "bilinear")", "s0 = 1e-3", "sc = 3e-3", "A = 2e8", "m = 3.0",
       "cycle_increment = 250", "softening_tolerance = 1e-8", "softening_max_iterations = 7"},
      true);
  EXPECT_EQ(b2.bilinear.m, 3.0);
  EXPECT_EQ(b2.cycle_increment, 250);
  EXPECT_EQ(b2.softening_tolerance, 1e-8);
  EXPECT_EQ(b2.softening_max_iterations, 7);

  const fatigue::FatigueSettings k0 = fatigue({R"(law = "kinetic")", "U = 2e-19", "gamma = 1e-28"});
  EXPECT_EQ(k0.law, fatigue::FatigueLaw::kinetic);
  EXPECT_EQ(k0.kinetic.U, 2e-19);
  EXPECT_EQ(k0.kinetic.gamma, 1e-28);
  EXPECT_EQ(k0.kinetic.lambda, 9.0);
  EXPECT_EQ(k0.kinetic.n0, 1.771);
  EXPECT_EQ(k0.kinetic.temperature, 293.0);
  EXPECT_EQ(k0.kinetic.frequency, 0.56);
  const fatigue::FatigueSettings k =
      fatigue({R"(law = "kinetic")", "U = 2e-19", "gamma = 1e-28", "lambda = 5", "n0 = 1.5",
               "temperature = 300", "frequency = 10"});
  EXPECT_EQ(k.kinetic.lambda, 5.0);
  EXPECT_EQ(k.kinetic.n0, 1.5);
  EXPECT_EQ(k.kinetic.temperature, 300.0);
  EXPECT_EQ(k.kinetic.frequency, 10.0);
}

TEST(ConfigErrors, UnknownKey) {
  Doc doc = plate();
  doc.insert_after("nu = ", "Nu = 0.3");
  const config::ConfigResult r = parse(doc);
  expect_one_error(r, 13, "detail[0].material.Nu", "unknown key \"Nu\"");
  EXPECT_EQ(r.errors[0].column, 1u);
  EXPECT_EQ(r.errors[0].message(),
            "plate.toml:13:1: detail[0].material.Nu: unknown key \"Nu\" (known here: E, nu, K_c, "
            "E_std, E_seed)");
}

TEST(ConfigErrors, UnknownKeyInAnInlineTable) {
  Doc doc = plate();
  doc.replace("holes", R"(holes = [{ center = [0.005, 0.0025], radius = 0.001 }])");
  const config::ConfigResult r = parse(doc);
  ASSERT_EQ(r.errors.size(), 2u) << r.error_text();
  EXPECT_EQ(r.errors[0].line, 6u);
  EXPECT_EQ(r.errors[0].path, "detail[0].geometry.holes[0].centre");
  EXPECT_EQ(r.errors[0].reason, "missing required key \"centre\"");
  EXPECT_EQ(r.errors[1].line, 6u);
  EXPECT_EQ(r.errors[1].path, "detail[0].geometry.holes[0].center");
  EXPECT_NE(r.errors[1].reason.find("unknown key"), std::string::npos);
}

TEST(ConfigErrors, WrongType) {
  Doc doc = plate();
  doc.replace("E = ", R"(E = "70e9")");
  expect_one_error(parse(doc), 11, "detail[0].material.E", "expected a number, got a string");

  doc = plate();
  doc.lines.push_back("[detail.checkpoint]");
  doc.lines.push_back("every_batches = 10.0");
  expect_one_error(parse(doc), 25, "detail[0].checkpoint.every_batches",
                   "expected an integer, got a floating-point number");

  doc = plate();
  doc.lines.push_back("[detail.life]");
  doc.lines.push_back("every_cycles = -1");
  expect_one_error(parse(doc), 25, "detail[0].life.every_cycles", "must be >= 0");

  doc = plate();
  doc.replace("point = ", "point = [0.010]");
  expect_one_error(parse(doc), 20, "detail[0].load[0].point", "expected an array [x, y]");

  doc = plate();
  doc.insert_after("m2 = ", "compressed_bonds_fatigue = 0");
  expect_one_error(parse(doc), 19, "detail[0].fatigue.compressed_bonds_fatigue",
                   "expected a boolean");

  doc = plate();  // [detail.load] instead of [[detail.load]]
  doc.replace("[[detail.load]]", "[detail.load]");
  expect_one_error(parse(doc), 19, "detail[0].load", "expected an array of tables");
}

TEST(ConfigErrors, MissingField) {
  Doc doc = plate();
  doc.erase("E = ");
  expect_one_error(parse(doc), 10, "detail[0].material.E", "missing required key \"E\"");

  doc = plate();
  doc.erase("A2 = ");
  expect_one_error(parse(doc), 13, "detail[0].fatigue.A2", "missing required key \"A2\"");

  doc = plate();  // no [detail.material] at all: reported at the [[detail]] table
  doc.erase("[detail.material]");
  doc.erase("E = ");
  doc.erase("nu = ");
  const config::ConfigResult r = parse(doc);
  expect_one_error(r, 1, "detail[0].material", "missing required key \"material\"");
}

TEST(ConfigErrors, CompressionRuleWhereTheLawCannotTakeIt) {
  // Issue 34: "contact" and "closure" are for the range laws; contact for strain_range only;
  // Newman's parameters only with the closure rule, and within their ranges.
  Doc doc = plate();
  doc.insert_after("m2 = ", R"(compression = "touching")");
  expect_one_error(parse(doc), 19, "detail[0].fatigue.compression",
                   "\"touching\" is not one of \"full_range\", \"contact\", \"closure\"");
  doc = plate();
  doc.replace("law = ", R"(law = "energy")");
  doc.insert_after("m2 = ", R"(compression = "contact")");
  expect_one_error(parse(doc), 19, "detail[0].fatigue.compression",
                   "\"contact\" needs law = \"strain_range\" (each bond's range from the contact "
                   "solution at P_min)");
  doc = plate();
  doc.insert_after("m2 = ", "closure_constraint = 2.0");
  expect_one_error(parse(doc), 19, "detail[0].fatigue.closure_constraint",
                   "only with compression = \"closure\"");
  doc = plate();
  doc.insert_after("m2 = ", R"(compression = "closure")");
  doc.insert_after("compression = ", "closure_smax_over_flow_stress = 1.2");
  expect_one_error(parse(doc), 20, "detail[0].fatigue.closure_smax_over_flow_stress",
                   "must lie in (0, 1) (got 1.2)");
}

TEST(ConfigErrors, ParameterOfAnotherLaw) {
  Doc doc = plate();
  doc.insert_after("m2 = ", "U = 2e-19");
  expect_one_error(parse(doc), 19, "detail[0].fatigue.U",
                   "unknown key \"U\" (known here: law, phi0, static_failure, A1, m1, A2, m2, "
                   "eps_inf, eps_inf_prop, compressed_bonds_fatigue, compression, "
                   "closure_constraint, closure_smax_over_flow_stress)");
  doc = plate();
  doc.replace("law = ", R"(law = "bilinear")");
  const config::ConfigResult r = parse(doc);
  // s0, sc, A missing; A1, m1, A2, m2 unknown; the plate is state-based
  ASSERT_EQ(r.errors.size(), 8u) << r.error_text();
  const auto law = std::find_if(r.errors.begin(), r.errors.end(),
                                [](const auto& e) { return e.path == "detail[0].fatigue.law"; });
  ASSERT_NE(law, r.errors.end());
  EXPECT_EQ(law->line, 14u);
  EXPECT_NE(law->reason.find("bond_based"), std::string::npos);
}

TEST(ConfigErrors, HorizonRatioBelowOne) {
  Doc doc = plate();
  doc.replace("horizon_ratio", "horizon_ratio = 0.9");
  expect_one_error(parse(doc), 9, "detail[0].grid.horizon_ratio", "must be >= 1");
}

TEST(ConfigErrors, HoleOutsideTheBody) {
  Doc doc = plate();
  doc.replace("holes", R"(holes = [{ centre = [0.005, 0.0025], radius = 0.001 },)");
  doc.insert_after("holes", R"(  { centre = [0.050, 0.0025], radius = 0.001 }])");
  expect_one_error(parse(doc), 7, "detail[0].geometry.holes[1]", "the hole lies outside the body");
}

TEST(ConfigErrors, NonPositiveYoungsModulus) {
  for (const char* line : {"E = 0.0", "E = -70e9", "E = 0"}) {
    Doc doc = plate();
    doc.replace("E = ", line);
    expect_one_error(parse(doc), 11, "detail[0].material.E", "must be > 0");
  }
}

TEST(ConfigErrors, MaterialScatterOutOfBounds) {
  // E = 70e9 in the plate: E_std must be >= 0 and < E/5 = 14e9 (each node's E is clamped to
  // E ± 4·E_std, which must stay > 0); the seed is an integer >= 0.
  struct Case {
    const char* line;
    const char* path;
    const char* reason;
  };
  const Case cases[] = {
      {"E_std = -1e9", "detail[0].material.E_std", "must be >= 0 (got -1e+09)"},
      {"E_std = 14e9", "detail[0].material.E_std", "must be < E/5 = 1.4e+10 Pa"},
      {"E_std = 70e9", "detail[0].material.E_std", "must be < E/5"},
      {"E_std = nan", "detail[0].material.E_std", "must be a finite number"},
      {"E_std = \"3e9\"", "detail[0].material.E_std", "expected a number"},
      {"E_seed = -1", "detail[0].material.E_seed", "must be >= 0"},
      {"E_seed = 1.5", "detail[0].material.E_seed", "expected an integer"},
  };
  for (const Case& c : cases) {
    Doc doc = plate();
    doc.insert_after("nu = ", c.line);
    SCOPED_TRACE(c.line);
    expect_one_error(parse(doc), doc.line_of(c.line), c.path, c.reason);
  }
  Doc ok = plate();
  ok.insert_after("nu = ", "E_std = 13.9e9");
  EXPECT_TRUE(parse(ok).ok()) << parse(ok).error_text();
}

TEST(ConfigErrors, OtherImpossibleValues) {
  struct Case {
    const char* prefix;  ///< the line to replace
    const char* line;
    const char* at;  ///< the line the error is reported at
    const char* path;
    const char* reason;
  };
  const Case cases[] = {
      {"nu = ", "nu = 0.5", "nu", "detail[0].material.nu", "must lie in (-1, 0.5)"},
      {"nu = ", "nu = -1", "nu", "detail[0].material.nu", "must lie in (-1, 0.5)"},
      {"dx = ", "dx = 0.0", "dx", "detail[0].grid.dx", "must be > 0"},
      {"dx = ", "dx = 0.006", "dx", "detail[0].grid.dx",
       "must not exceed the body's smaller side 0.005 m"},
      {"thickness", "thickness = -1", "thickness", "detail[0].geometry.thickness", "must be > 0"},
      {"holes", "holes = [{ centre = [0.005, 0.0025], radius = 0.0 }]", "holes",
       "detail[0].geometry.holes[0].radius", "must be > 0"},
      {"outline", "outline = [{ x_min = 0.0, y_min = 0.0, x_max = 0.0, y_max = 0.005 }]", "outline",
       "detail[0].geometry.outline[0].x_max", "must be > x_min"},
      {"point = ", "point = [0.011, 0.0025]", "point", "detail[0].load[0].point",
       "lies outside the body"},
      {"constant = ", "constant = [0.0, 0.0]", "[[detail.load]]", "detail[0].load[0]",
       "every force component is zero"},
      {"point = ", "point = [0.010, nan]", "point", "detail[0].load[0].point[1]",
       "must be a finite number"},
      {"law = ", R"(law = "paris")", "law", "detail[0].fatigue.law", "is not one of"},
      {"A1 = ", "A1 = -100.0", "A1", "detail[0].fatigue.A1", "must be > 0 (got -100)"},
      {"id = ", R"(id = "b1.ct")", "id", "detail[0].id", "is not 1 to 32 characters"},
      {"region = ", "region = { x_min = 0.0, y_min = 0.0, x_max = 0.0005 }", "region",
       "detail[0].support[0].region.y_max", "missing required key"},
      {"region = ", "region = { radius = 0.001 }", "region", "detail[0].support[0].region.centre",
       "missing required key"},
      {"region = ", "region = {}", "region", "detail[0].support[0].region", "expected a rectangle"},
  };
  for (const Case& c : cases) {
    Doc doc = plate();
    doc.replace(c.prefix, c.line);
    const std::uint32_t line = doc.line_of(c.at);
    SCOPED_TRACE(c.line);
    expect_one_error(parse(doc), line, c.path, c.reason);
  }
}

TEST(ConfigErrors, StateBasedModelTakesTheConstantKernelOnly) {
  Doc doc = plate();
  doc.insert_after("horizon_ratio", "[detail.model]");
  doc.insert_after("[detail.model]", R"(kernel = "gaussian")");
  expect_one_error(parse(doc), 11, "detail[0].model.kernel", "constant kernel only");
  doc.insert_after("[detail.model]", R"(kind = "bond_based")");
  EXPECT_TRUE(parse(doc).ok());
}

TEST(ConfigErrors, DuplicateDetailIds) {
  Doc doc = plate();
  Doc second = plate();
  second.replace("id = ", R"(id = "PLATE")");
  second.lines.push_back("[detail.output]");
  second.lines.push_back(R"(directory = "results/plate-2")");
  doc.lines.insert(doc.lines.end(), second.lines.begin(), second.lines.end());
  const config::ConfigResult r = parse(doc);
  expect_one_error(r, 25, "detail[1].id", "same channel token PLATE as detail[0]");
  EXPECT_EQ(r.errors[0].message(),
            "plate.toml:25:6: detail[1].id: \"PLATE\" has the same channel token PLATE as "
            "detail[0] (\"plate\", line 1)");
}

TEST(ConfigErrors, DuplicateOutputDirectories) {
  Doc doc = plate();
  Doc second = plate();
  second.replace("id = ", R"(id = "plate-2")");
  second.lines.push_back("[detail.output]");
  second.lines.push_back(R"(directory = "results/plate")");
  doc.lines.insert(doc.lines.end(), second.lines.begin(), second.lines.end());
  expect_one_error(parse(doc), 48, "detail[1].output.directory", "also the output directory");
}

TEST(ConfigErrors, TomlSyntaxError) {
  Doc doc = plate();
  doc.replace("nu = ", "nu = = 0.3");
  const config::ConfigResult r = parse(doc);
  ASSERT_EQ(r.errors.size(), 1u);
  const config::ConfigError& e = r.errors[0];
  EXPECT_EQ(e.line, 12u);
  EXPECT_EQ(e.column, 6u);
  EXPECT_EQ(e.path, "");
  EXPECT_TRUE(e.message().starts_with("plate.toml:12:6: TOML syntax error: ")) << e.message();
}

// Found by fuzz_config: toml++ 3.3.0 reaches TOML_UNREACHABLE (undefined behaviour) when it
// classifies most non-ASCII characters as whitespace or not, e.g. in a table header. Such
// characters are refused before toml++ reads the text, with line and column; strings and
// comments keep any UTF-8.
TEST(ConfigErrors, NonAsciiWhereTomlppCannotClassifyIt) {
  const std::vector<std::tuple<std::string, std::uint32_t, std::uint32_t, std::string>> cases = {
      // the fuzzer's input, cut short: U+0213 in a table header
      {"[[detail\xC8\x93oad]]\n", 1, 9, "in a table header"},
      {"[detail]\n[detail.\"g\xC3\xA9ometry\"]\n", 2, 11, "in a table header"},
      {"a = 1\nb\xC3\xA9 = 2\n", 2, 2, "outside a string or comment"},
      {"a = \"x\"\xC2\xA7\n", 1, 8, "outside a string or comment"},
      {"a = [\n  1,\n  \xC2\xA7\n]\n", 3, 3, "outside a string or comment"},
      // upstream issue 190: a line-ending backslash in a multi-line string, then U+00A7
      {"s = \"\"\"\\\n\xC2\xA7\"\"\"\n", 2, 1, "after a line-ending backslash in a string"},
      {"s = \"\"\"a\\  \n   \n \xC2\xA7\"\"\"\n", 3, 2,
       "after a line-ending backslash in a string"},
      {"s = \"\\\xC2\xA7\"\n", 1, 7, "after a backslash in a string"},
      {"\xFF", 1, 1, "outside a string or comment"},
      // found by fuzz_key_file: a quote where no string can start opens none for toml++, which
      // reads on through a bare value
      {"a = 0\"\xD1\xB7\"\n", 1, 7, "outside a string or comment"},
      {"a = [1 \"\xC2\xA7\"]\n", 1, 9, "outside a string or comment"},
      // found by fuzz_key_file: an '=' inside a bare value is no key's, so the quote after it
      // opens no string either (the fuzzer's input, cut short: U+FEF7)
      {"a = -\"01=\"\xEF\xBB\xB7\n", 1, 11, "outside a string or comment"},
      {"a = -1=\"\xC2\xA7\"\n", 1, 9, "outside a string or comment"},
      {"a = { b = -\"x=\"\xC2\xA7\" }\n", 1, 16, "outside a string or comment"},
  };
  for (const auto& [text, line, column, where] : cases) {
    SCOPED_TRACE(text);
    const config::ConfigResult r = config::parse_config(text, "u.toml");
    ASSERT_EQ(r.errors.size(), 1u) << r.error_text();
    EXPECT_EQ(r.errors[0].message(), "u.toml:" + std::to_string(line) + ":" +
                                         std::to_string(column) +
                                         ": TOML syntax error: non-ASCII character " + where);
  }
  // Any UTF-8 in comments, strings (quoted keys too) and multi-line strings; a leading BOM.
  Doc doc = plate();
  doc.lines.insert(doc.lines.begin(), "\xEF\xBB\xBF# Größe δ/Δx");
  doc.insert_after("id = ", R"(description = """Platte mit Loch, Ø 2 mm \u00e9 é""" # ü)");
  doc.insert_after("id = ", R"('δ' = 1)");
  doc.insert_after("id = ", R"("ключ" = 'ü' # [x])");
  doc.insert_after("id = ", R"(notes = { "ä" = "ö", b = ["ü", 'é'] })");
  const config::ConfigResult ok = parse(doc);
  ASSERT_EQ(ok.errors.size(), 3u) << ok.error_text();  // three unknown keys, none refused
  EXPECT_EQ(ok.errors[0].path, "detail[0].notes");
  EXPECT_EQ(ok.errors[1].path, "detail[0].ключ");
  EXPECT_EQ(ok.errors[2].path, "detail[0].δ");
}

// Found by fuzz_config: toml++ echoes the input in its errors ("saw 'tr<newline>'"), and a quoted
// key may hold any character; every message is one line all the same.
TEST(ConfigErrors, MessagesAreOneLine) {
  const config::ConfigResult echo = config::parse_config("[[detail]]\nid = tr\n", "e.toml");
  ASSERT_EQ(echo.errors.size(), 1u);
  EXPECT_EQ(echo.errors[0].message(),
            "e.toml:2:8: TOML syntax error: Error while parsing boolean: expected 'true', saw "
            "'tr\\n'");
  Doc doc = plate();
  doc.insert_after("id = ", R"("a\nb\u0001" = 1)");
  const config::ConfigResult key = parse(doc);
  ASSERT_EQ(key.errors.size(), 1u) << key.error_text();
  EXPECT_EQ(key.errors[0].path, "detail[0].a\nb\x01");
  EXPECT_TRUE(key.errors[0].message().starts_with(
      "plate.toml:3:1: detail[0].a\\nb\\x01: unknown key \"a\\nb\\x01\" (known here: "))
      << key.errors[0].message();
}

TEST(ConfigErrors, AllErrorsAreReportedInLineOrder) {
  Doc doc = plate();
  doc.replace("thickness", "thickness = 0.0");
  doc.replace("horizon_ratio", "horizon_ratio = 0.5");
  doc.replace("E = ", "E = -1.0");
  doc.replace("nu = ", "nu = true");
  doc.insert_after("m2 = ", "bogus = 1");
  const config::ConfigResult r = parse(doc);
  ASSERT_EQ(r.errors.size(), 5u) << r.error_text();
  const std::vector<std::pair<std::uint32_t, std::string>> expected = {
      {4, "detail[0].geometry.thickness"},
      {9, "detail[0].grid.horizon_ratio"},
      {11, "detail[0].material.E"},
      {12, "detail[0].material.nu"},
      {19, "detail[0].fatigue.bogus"}};
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_EQ(r.errors[k].line, expected[k].first) << r.errors[k].message();
    EXPECT_EQ(r.errors[k].path, expected[k].second) << r.errors[k].message();
  }
}

TEST(ConfigErrors, LifeSettings) {
  Doc doc = plate();
  doc.lines.push_back("[detail.life]");                 // 24
  doc.lines.push_back(R"(criterion = "phase3")");       // 25
  doc.lines.push_back("critical_crack_length = 0.01");  // 26
  doc.lines.push_back(  // 27: each block breaks one rule of check_load_block
      R"(reference_spectrum = [{ p_max = 4000.0, r = 1.0, count = 1 }, { p_max = 4000.0, r = 0.1, count = 0 }])");
  doc.lines.push_back(R"(band = "a2_scatter")");  // 28
  const config::ConfigResult r = parse(doc);
  ASSERT_EQ(r.errors.size(), 4u) << r.error_text();
  EXPECT_EQ(r.errors[0].path, "detail[0].life.a2_relative_scatter");  // missing: table line
  EXPECT_EQ(r.errors[0].line, 24u);
  EXPECT_EQ(r.errors[1].path, "detail[0].life.critical_crack_length");
  EXPECT_EQ(r.errors[1].line, 26u);
  EXPECT_EQ(r.errors[2].path, "detail[0].life.reference_spectrum[0].r");
  EXPECT_EQ(r.errors[3].path, "detail[0].life.reference_spectrum[1].count");
  EXPECT_EQ(r.errors[3].line, 27u);
}

TEST(ConfigErrors, LifeCoarseGridSpacing) {
  // [detail.life] dx: the coarser estimate model's spacing, larger than the grid's (0.5 mm here),
  // for the laws with an A2 to calibrate; each error at its line and field.
  Doc doc = plate();
  doc.lines.push_back("[detail.life]");  // 24
  doc.lines.push_back("dx = 0.001");     // 25
  config::ConfigResult ok = parse(doc);
  ASSERT_TRUE(ok.ok()) << ok.error_text();
  EXPECT_EQ(ok.config->details[0].life.dx, 0.001);
  EXPECT_EQ(parse(plate()).config->details[0].life.dx, 0.0);  // default: none

  doc = plate();
  doc.lines.push_back("[detail.life]");
  doc.lines.push_back("dx = 0.0005");
  expect_one_error(parse(doc), 25, "detail[0].life.dx",
                   "must be larger than [detail.grid] dx = 5e-04 m");
  doc = plate();
  doc.lines.push_back("[detail.life]");
  doc.lines.push_back("dx = -0.001");
  expect_one_error(parse(doc), 25, "detail[0].life.dx", "must be > 0");
  doc = plate();
  doc.replace("law = ", R"(law = "kinetic")");
  doc.replace("A1 = ", "U = 2e-19");
  doc.replace("m1 = ", "gamma = 1e-28");
  doc.erase("A2 = ");
  doc.erase("m2 = ");
  doc.lines.push_back("[detail.life]");
  doc.lines.push_back("dx = 0.001");
  const config::ConfigResult kinetic = parse(doc);
  ASSERT_FALSE(kinetic.ok());
  ASSERT_EQ(kinetic.errors.size(), 1u) << kinetic.error_text();
  EXPECT_EQ(kinetic.errors[0].path, "detail[0].life.dx");
  EXPECT_NE(kinetic.errors[0].reason.find("only with fatigue law"), std::string::npos);
}

TEST(ConfigErrors, StressIntensitySettings) {
  Doc doc = plate();
  doc.lines.push_back("[detail.stress_intensity]");      // 24
  doc.lines.push_back(R"(method = "compact_tension")");  // 25
  doc.lines.push_back("load_line = [0.0, 0.0]");         // 26
  config::ConfigResult r = parse(doc);
  ASSERT_EQ(r.errors.size(), 1u) << r.error_text();
  EXPECT_EQ(r.errors[0].path, "detail[0].stress_intensity.width");  // missing: table line
  EXPECT_EQ(r.errors[0].line, 24u);
  doc.lines[doc.lines.size() - 2] = R"(method = "extrapolation")";
  r = parse(doc);
  ASSERT_EQ(r.errors.size(), 1u) << r.error_text();
  EXPECT_EQ(r.errors[0].path, "detail[0].stress_intensity.load_line");
  EXPECT_EQ(r.errors[0].line, 26u);
}

TEST(ConfigErrors, FileAndDocumentLevel) {
  const config::ConfigResult missing = config::load_config("/nonexistent/peritwin.toml");
  ASSERT_EQ(missing.errors.size(), 1u);
  EXPECT_EQ(missing.errors[0].message(),
            "/nonexistent/peritwin.toml: cannot read the file: No such file or directory");
  const config::ConfigResult directory = config::load_config(examples_dir());
  ASSERT_EQ(directory.errors.size(), 1u);
  EXPECT_EQ(directory.errors[0].reason, "cannot read the file: it is a directory");

  const config::ConfigResult empty = config::parse_config("", "empty.toml");
  ASSERT_EQ(empty.errors.size(), 1u);
  EXPECT_EQ(empty.errors[0].path, "detail");

  const config::ConfigResult stray = config::parse_config("title = \"x\"\n", "stray.toml");
  ASSERT_EQ(stray.errors.size(), 2u) << stray.error_text();

  const config::ConfigResult binary =
      config::parse_config(std::string("\0\xff\xfe[[", 5), "bin.toml");
  EXPECT_FALSE(binary.ok());
  EXPECT_EQ(binary.errors.size(), 1u);
}

}  // namespace
}  // namespace peritwin::twin

namespace peritwin::twin {
namespace {

TEST(ConfigGeometry, PolygonOutlineWithArcAndFilletAndNotchPolyline) {
  Doc doc = plate();
  // A 10 x 5 mm plate drawn as a polygon: the right end a semicircle of radius 2.5 mm about
  // (10, 2.5) mm, the lower left corner rounded with r = 1 mm.
  doc.replace("outline", R"(outline = [{ polygon = [{ at = [0.0, 0.0], fillet = 0.001 }, )"
                         R"([0.010, 0.0], { to = [0.010, 0.005], arc_centre = [0.010, 0.0025], )"
                         R"(direction = "ccw" }, [0.0, 0.005]] }])");
  doc.insert_after("holes", R"(notches = [{ path = [[0.0, 0.001], [0.001, 0.001], )"
                            R"([0.002, 0.0015]], name = "weld toe" }, )"
                            R"({ from = [0.0, 0.004], to = [0.001, 0.004] }])");
  const config::ConfigResult r = parse(doc);
  ASSERT_TRUE(r.ok()) << r.error_text();
  const mesh::DetailGeometry& g = r.config->details[0].geometry;
  ASSERT_EQ(g.outline.size(), 1u);
  ASSERT_EQ(g.outline[0].shape, mesh::Region::Shape::polygon);
  // 50 mm² + the half disc π·2.5²/2 − the fillet's (1 − π/4)·1² = 59.6029 mm².
  EXPECT_NEAR(g.outline[0].area(),
              50e-6 + std::numbers::pi * 6.25e-6 / 2 - (1 - std::numbers::pi / 4) * 1e-6, 1e-18);
  EXPECT_DOUBLE_EQ(g.bounding_box().x_max, 0.0125);
  ASSERT_EQ(g.notches.size(), 2u);
  EXPECT_EQ(g.notches[0].name, "weld toe");
  ASSERT_EQ(g.notches[0].path.size(), 3u);
  EXPECT_EQ(xy(g.notches[0].tip()), XY(0.002, 0.0015));
  const mesh::Point d = g.notches[0].direction();  // (1, 0.5)/√1.25
  EXPECT_NEAR(d.x, 1 / std::sqrt(1.25), 1e-15);
  EXPECT_NEAR(d.y, 0.5 / std::sqrt(1.25), 1e-15);
  EXPECT_EQ(g.notches[1].name, "notch 1");
  // A node on the arc's far end (12.5, 2.5) mm would be material; one beyond it is not.
  EXPECT_TRUE(g.is_material({0.0125, 0.0025}));
  EXPECT_FALSE(g.is_material({0.01251, 0.0025}));
}

TEST(ConfigGeometry, PolygonErrorsNameTheVertex) {
  Doc doc = plate();
  // A bow tie: the edge to vertex [3] crosses the edge to vertex [1].
  doc.replace("outline",
              R"(outline = [{ x_min = 0.0, y_min = 0.0, x_max = 0.010, y_max = 0.005 },)");
  doc.insert_after("outline",
                   R"(  { polygon = [[0.0, 0.0], [0.01, 0.005], [0.01, 0.0], [0.0, 0.005]] }])");
  expect_one_error(parse(doc), 6, "detail[0].geometry.outline[1].polygon[3]",
                   "the boundary crosses itself");
  doc = plate();
  doc.replace("outline", R"(outline = [{ polygon = [[0.0, 0.0], [0.010, 0.0], )"
                         R"({ at = [0.010, 0.005], fillet = 0.006 }, [0.0, 0.005]] }])");
  expect_one_error(parse(doc), 5, "detail[0].geometry.outline[0].polygon[2]", "the fillets need");
  doc = plate();
  doc.replace("outline",
              R"(outline = [{ polygon = [[0.0, 0.0], [0.010, 0.0], )"
              R"({ to = [0.010, 0.005], arc_centre = [0.011, 0.0025] }, [0.0, 0.005]] }])");
  expect_one_error(parse(doc), 5, "detail[0].geometry.outline[0].polygon[2].direction",
                   "missing required key");
  doc = plate();
  doc.replace("outline", R"(outline = [{ polygon = [[0.0, 0.0], [0.010, 0.0]] }])");
  expect_one_error(parse(doc), 5, "detail[0].geometry.outline[0].polygon", "at least 3 vertices");
  doc = plate();
  doc.insert_after("holes", R"(notches = [{ path = [[0.0, 0.001]] }])");
  expect_one_error(parse(doc), 7, "detail[0].geometry.notches[0].path", "at least 2 points");
}

}  // namespace
}  // namespace peritwin::twin
