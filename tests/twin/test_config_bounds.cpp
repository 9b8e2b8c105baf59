// twin/config, issue 14: [detail.limits], [auth], and the resource bounds — the estimate of
// nodes, bonds and factor entries against the real discretization and factor, configs refused
// before anything is built (dx = 1 µm, horizon_ratio = 1000), the memory limit and its units.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "config/config.h"
#include "config/resources.h"

namespace peritwin::twin {
namespace {

std::string examples_dir() {
#ifdef PERITWIN_EXAMPLES_DIR
  return PERITWIN_EXAMPLES_DIR;
#else
  std::string file = __FILE__;  // <repo>/tests/twin/test_config_bounds.cpp
  for (int i = 0; i < 3; ++i) file = file.substr(0, file.find_last_of('/'));
  return file + "/examples";
#endif
}

constexpr std::uint64_t kGiB = std::uint64_t{1} << 30U;

/// One [[detail]]: a plate `width` x `height` (m) with `geometry_extra` in [detail.geometry] (an
/// outline there replaces the plate's),
/// `grid` as the [detail.grid] lines, held at its left edge and pulled at its right edge; `extra`
/// is appended after the detail (more tables of it, or top-level tables such as [auth]).
std::string detail_toml(const std::string& id, double width, double height, const std::string& grid,
                        const std::string& geometry_extra = "", const std::string& extra = "") {
  const auto number = [](double v) {
    std::ostringstream out;
    out << std::setprecision(17) << v;
    return out.str();
  };
  const std::string w = number(width), h = number(height);
  return "[[detail]]\n"
         "id = \"" +
         id +
         "\"\n"
         "[detail.geometry]\n"
         "thickness = 0.005\n" +
         (geometry_extra.find("outline =") != std::string::npos
              ? std::string()
              : "outline = [{ x_min = 0.0, y_min = 0.0, x_max = " + w + ", y_max = " + h +
                    " }]\n") +
         geometry_extra + "[detail.grid]\n" + grid +
         "[detail.material]\n"
         "E = 70e9\n"
         "nu = 0.3\n"
         "[detail.fatigue]\n"
         "law = \"strain_range\"\n"
         "A1 = 100.0\n"
         "m1 = 2.0\n"
         "A2 = 1000.0\n"
         "m2 = 2.5\n"
         "[[detail.load]]\n"
         "point = [" +
         w + ", " + number(height / 2) +
         "]\n"
         "constant = [1.0, 0.0]\n"
         "[[detail.support]]\n"
         "region = { x_min = 0.0, y_min = 0.0, x_max = 0.0005, y_max = " +
         h + " }\n" + extra;
}

/// The 10 mm x 5 mm plate of test_config.cpp at dx = 0.5 mm, plus `extra`.
std::string plate(const std::string& extra = "") {
  return detail_toml("plate", 0.010, 0.005, "dx = 0.0005\n", "", extra);
}

/// 1-based line of the first line of `text` that starts with `prefix`.
std::uint32_t line_of(const std::string& text, std::string_view prefix) {
  std::uint32_t line = 1;
  std::size_t begin = 0;
  while (begin < text.size()) {
    if (std::string_view(text).substr(begin).starts_with(prefix)) return line;
    begin = text.find('\n', begin);
    if (begin == std::string::npos) break;
    ++begin;
    ++line;
  }
  ADD_FAILURE() << "no line starts with " << prefix;
  return 0;
}

/// Exactly one error, at (line, path), whose reason contains every part of `reasons`.
void expect_one_error(const config::ConfigResult& r, std::uint32_t line, std::string_view path,
                      std::initializer_list<std::string_view> reasons) {
  ASSERT_FALSE(r.ok());
  ASSERT_EQ(r.errors.size(), 1u) << r.error_text();
  const config::ConfigError& e = r.errors[0];
  EXPECT_EQ(e.line, line) << e.message();
  EXPECT_EQ(e.path, path) << e.message();
  for (const auto reason : reasons) {
    EXPECT_NE(e.reason.find(reason), std::string::npos) << e.message();
  }
}

// [detail.limits] -----------------------------------------------------------------------------

TEST(ConfigLimitsTable, DefaultsWithoutTheTable) {
  const config::ConfigResult r = config::parse_config(plate(), "plate.toml");
  ASSERT_TRUE(r.ok()) << r.error_text();
  const config::LimitsConfig& l = r.config->details[0].limits;
  EXPECT_FALSE(l.max_p.has_value());  // the daemon derives it from the model
  EXPECT_EQ(l.max_batch_seconds, 60.0);
  EXPECT_EQ(l.max_sources, 16);
  EXPECT_EQ(l.max_rejects_per_second, 10.0);
  EXPECT_FALSE(l.release_idle_factor);
}

TEST(ConfigLimitsTable, EveryKeyParsed) {
  const config::ConfigResult r =
      config::parse_config(plate("[detail.limits]\n"
                                 "max_p = 5000\n"  // an integer where a real goes
                                 "max_batch_seconds = 2.5\n"
                                 "max_sources = 3\n"
                                 "max_rejects_per_second = 0.5\n"
                                 "release_idle_factor = true\n"),
                           "plate.toml");
  ASSERT_TRUE(r.ok()) << r.error_text();
  const config::LimitsConfig& l = r.config->details[0].limits;
  ASSERT_TRUE(l.max_p.has_value());
  EXPECT_EQ(*l.max_p, 5000.0);
  EXPECT_EQ(l.max_batch_seconds, 2.5);
  EXPECT_EQ(l.max_sources, 3);
  EXPECT_EQ(l.max_rejects_per_second, 0.5);
  EXPECT_TRUE(l.release_idle_factor);
}

TEST(ConfigLimitsTable, BadValuesNamedWithTheirKeyPaths) {
  struct Case {
    std::string line;
    std::string path;
    std::string reason;
  };
  const std::vector<Case> cases = {
      {"max_p = 0.0", "detail[0].limits.max_p", "must be > 0 (got 0)"},
      {"max_p = -4000", "detail[0].limits.max_p", "must be > 0 (got -4000)"},
      {"max_p = \"4 kN\"", "detail[0].limits.max_p", "expected a number, got a string"},
      {"max_p = inf", "detail[0].limits.max_p", "must be a finite number"},
      {"max_batch_seconds = 0", "detail[0].limits.max_batch_seconds", "must be > 0"},
      {"max_sources = 0", "detail[0].limits.max_sources", "must be >= 1 (got 0)"},
      {"max_sources = 2.5", "detail[0].limits.max_sources", "expected an integer"},
      {"max_rejects_per_second = -1", "detail[0].limits.max_rejects_per_second", "must be > 0"},
      {"max_source = 4", "detail[0].limits.max_source", "unknown key \"max_source\""},
  };
  for (const Case& c : cases) {
    const std::string text = plate("[detail.limits]\n" + c.line + "\n");
    const config::ConfigResult r = config::parse_config(text, "plate.toml");
    SCOPED_TRACE(c.line);
    expect_one_error(r, line_of(text, c.line), c.path, {c.reason});
  }
}

// [detail.sensor] -----------------------------------------------------------------------------

TEST(ConfigSensorTable, DefaultsAndEveryKey) {
  const config::ConfigResult none = config::parse_config(plate(), "plate.toml");
  ASSERT_TRUE(none.ok()) << none.error_text();
  const config::SensorConfig& d = none.config->details[0].sensor;
  EXPECT_EQ(d.scale, 1.0);
  EXPECT_EQ(d.offset, 0.0);
  EXPECT_EQ(d.gate, 0.0);
  EXPECT_EQ(d.alpha_bin, 0.0);
  const config::ConfigResult r = config::parse_config(plate("[detail.sensor]\n"
                                                            "scale = -2.5e4\n"
                                                            "offset = 120\n"
                                                            "gate = 50.0\n"
                                                            "alpha_bin = 0.05\n"),
                                                      "plate.toml");
  ASSERT_TRUE(r.ok()) << r.error_text();
  const config::SensorConfig& s = r.config->details[0].sensor;
  EXPECT_EQ(s.scale, -2.5e4);
  EXPECT_EQ(s.offset, 120.0);
  EXPECT_EQ(s.gate, 50.0);
  EXPECT_EQ(s.alpha_bin, 0.05);
}

TEST(ConfigSensorTable, BadValuesNamedWithTheirKeyPaths) {
  struct Case {
    std::string line;
    std::string path;
    std::string reason;
  };
  const std::vector<Case> cases = {
      {"scale = 0.0", "detail[0].sensor.scale", "must be != 0"},
      {"scale = nan", "detail[0].sensor.scale", "must be a finite number"},
      {"offset = inf", "detail[0].sensor.offset", "must be a finite number"},
      {"gate = -1", "detail[0].sensor.gate", "must be >= 0 (got -1)"},
      {"alpha_bin = -0.1", "detail[0].sensor.alpha_bin", "must be >= 0"},
      {"alpha_bin = \"5 deg\"", "detail[0].sensor.alpha_bin", "expected a number, got a string"},
      {"gain = 2", "detail[0].sensor.gain", "unknown key \"gain\""},
  };
  for (const Case& c : cases) {
    const std::string text = plate("[detail.sensor]\n" + c.line + "\n");
    const config::ConfigResult r = config::parse_config(text, "plate.toml");
    SCOPED_TRACE(c.line);
    expect_one_error(r, line_of(text, c.line), c.path, {c.reason});
  }
}

// [auth] -----------------------------------------------------------------------------------------

TEST(ConfigAuth, AbsentMeansUnauthenticated) {
  const config::ConfigResult r = config::parse_config(plate(), "plate.toml");
  ASSERT_TRUE(r.ok()) << r.error_text();
  EXPECT_FALSE(r.config->auth.has_value());
}

TEST(ConfigAuth, RelativeKeyFileResolvedAgainstTheConfigDirectory) {
  const config::ConfigResult r = config::parse_config(
      plate("[auth]\nkey_file = \"keys/../keys/twin.keys\"\n"), "/etc/peritwin/twin.toml");
  ASSERT_TRUE(r.ok()) << r.error_text();
  ASSERT_TRUE(r.config->auth.has_value());
  EXPECT_EQ(r.config->auth->key_file, "/etc/peritwin/keys/twin.keys");
  EXPECT_TRUE(r.config->auth->sources.empty());  // every source with a key
  EXPECT_EQ(r.config->auth->daemon_key, "peritwin");
  EXPECT_EQ(r.config->auth->where.path, "auth");

  const config::ConfigResult absolute = config::parse_config(
      plate("[auth]\nkey_file = \"/var/lib/peritwin/k\"\n"), "/etc/peritwin/t.toml");
  ASSERT_TRUE(absolute.ok()) << absolute.error_text();
  EXPECT_EQ(absolute.config->auth->key_file, "/var/lib/peritwin/k");
}

TEST(ConfigAuth, LoadConfigResolvesAgainstTheFilesOwnDirectory) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(testing::TempDir()) / "peritwin_auth_config";
  fs::create_directories(dir / "conf");
  const fs::path file = dir / "conf" / "twin.toml";
  {
    std::ofstream out(file);
    out << plate(
        "[auth]\n"
        "key_file = \"producers.keys\"\n"
        "sources = [\"replay\", \"gauge-7\"]\n"
        "daemon_key = \"twin-1\"\n");
  }
  const config::ConfigResult r = config::load_config(file.string());
  ASSERT_TRUE(r.ok()) << r.error_text();
  ASSERT_TRUE(r.config->auth.has_value());
  EXPECT_EQ(r.config->auth->key_file,
            fs::absolute(dir / "conf" / "producers.keys").lexically_normal().string());
  EXPECT_EQ(r.config->auth->sources, (std::vector<std::string>{"replay", "gauge-7"}));
  EXPECT_EQ(r.config->auth->daemon_key, "twin-1");
  fs::remove_all(dir);
}

TEST(ConfigAuth, BadSourceIdsNamedOneByOne) {
  const std::string long_id(65, 'a');
  const std::string text =
      plate("[auth]\nkey_file = \"k\"\nsources = [\n\"replay\",\n\"two words\",\n\"\",\n\"" +
            long_id + "\",\n\"replay\",\n3,\n\"" + std::string(64, 'b') + "\",\n]\n");
  const config::ConfigResult r = config::parse_config(text, "twin.toml");
  ASSERT_FALSE(r.ok());
  ASSERT_EQ(r.errors.size(), 5u) << r.error_text();
  const std::uint32_t first = line_of(text, "\"replay\",");
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"auth.sources[1]", "\"two words\" is not a valid id: 1 to 64 printable ASCII"},
      {"auth.sources[2]", "\"\" is not a valid id"},
      {"auth.sources[3]", "is not a valid id"},
      {"auth.sources[4]", "\"replay\" is listed twice"},
      {"auth.sources[5]", "expected a string, got an integer"},
  };
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(r.errors[i].path, expected[i].first) << r.errors[i].message();
    EXPECT_EQ(r.errors[i].line, first + 1 + i) << r.errors[i].message();
    EXPECT_NE(r.errors[i].reason.find(expected[i].second), std::string::npos)
        << r.errors[i].message();
  }
}

TEST(ConfigAuth, MissingKeyFileBadDaemonKeyAndUnknownKey) {
  const std::string text =
      plate("[auth]\nsources = []\ndaemon_key = \"my key\"\nkeyfile = \"k\"\n");
  const config::ConfigResult r = config::parse_config(text, "twin.toml");
  ASSERT_EQ(r.errors.size(), 3u) << r.error_text();
  EXPECT_EQ(r.errors[0].path, "auth.key_file");
  EXPECT_EQ(r.errors[0].line, line_of(text, "[auth]"));
  EXPECT_NE(r.errors[0].reason.find("missing required key \"key_file\""), std::string::npos);
  EXPECT_EQ(r.errors[1].path, "auth.daemon_key");
  EXPECT_EQ(r.errors[1].line, line_of(text, "daemon_key"));
  EXPECT_NE(r.errors[1].reason.find("\"my key\" is not a valid id"), std::string::npos);
  EXPECT_EQ(r.errors[2].path, "auth.keyfile");
  EXPECT_NE(r.errors[2].reason.find("unknown key \"keyfile\""), std::string::npos);

  const std::string empty = plate("[auth]\nkey_file = \"\"\n");
  expect_one_error(config::parse_config(empty, "twin.toml"), line_of(empty, "key_file"),
                   "auth.key_file", {"must not be empty"});
  // [auth] is top level: inside a detail it is an unknown key of the detail.
  const std::string nested = plate("[detail.auth]\nkey_file = \"k\"\n");
  expect_one_error(config::parse_config(nested, "twin.toml"), line_of(nested, "[detail.auth]"),
                   "detail[0].auth", {"unknown key \"auth\""});
}

TEST(ConfigAuth, SourceIdRuleIsTheBatchRule) {
  // messages/batch.cpp: 1 to 64 characters from 0x21 to 0x7e.
  EXPECT_TRUE(config::is_valid_source_id("replay"));
  EXPECT_TRUE(config::is_valid_source_id("!~"));
  EXPECT_TRUE(config::is_valid_source_id(std::string(64, 'x')));
  EXPECT_FALSE(config::is_valid_source_id(""));
  EXPECT_FALSE(config::is_valid_source_id(std::string(65, 'x')));
  EXPECT_FALSE(config::is_valid_source_id("a b"));
  EXPECT_FALSE(config::is_valid_source_id("tab\there"));
  EXPECT_FALSE(config::is_valid_source_id("\x7f"));
  EXPECT_FALSE(config::is_valid_source_id("caf\xc3\xa9"));
}

// Resource estimate against the real discretization and factor ----------------------------------

config::DetailConfig parsed(const std::string& text) {
  const config::ConfigResult r = config::parse_config(text, "plate.toml");
  EXPECT_TRUE(r.ok()) << r.error_text();
  return r.ok() ? r.config->details[0] : config::DetailConfig{};
}

TEST(ResourceEstimate, NodesAndBondsWithinOnePercentOfTheDiscretization) {
  // A plain plate, the plate with a hole, an L of two rectangles with a hole across the inner
  // corner, at three horizons: the lattice count is exact for rectangles, the hole's area / dx²
  // and the straight-edge bond deficit (P/dx)·S are within 1 % here (measured: nodes <= 0.3 %,
  // bonds <= 0.5 %).
  struct Case {
    std::string name;
    std::string text;
  };
  const std::string hole = "holes = [{ centre = [0.005, 0.0025], radius = 0.001 }]\n";
  const std::string l_shape =
      "outline = [{ x_min = 0.0, y_min = 0.0, x_max = 0.020, y_max = 0.005 },\n"
      "           { x_min = 0.0, y_min = 0.005, x_max = 0.006, y_max = 0.016 }]\n"
      "holes = [{ centre = [0.006, 0.005], radius = 0.002 }]\n";
  std::vector<Case> cases;
  for (const char* ratio : {"2.0", "3.015", "4.0"}) {
    const std::string grid = "dx = 0.00025\nhorizon_ratio = " + std::string(ratio) + "\n";
    cases.push_back({std::string("plate ") + ratio, detail_toml("p", 0.020, 0.010, grid)});
    cases.push_back({std::string("hole ") + ratio, detail_toml("h", 0.010, 0.005, grid, hole)});
    cases.push_back({std::string("L ") + ratio, detail_toml("l", 0.020, 0.005, grid, l_shape)});
  }
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const config::DetailConfig d = parsed(c.text);
    const config::ResourceEstimate e = config::estimate_resources(d);
    const mesh::Discretization disc = discretize(d);
    ASSERT_GT(disc.num_nodes(), 0);
    EXPECT_NEAR(e.nodes, disc.num_nodes(), 0.01 * disc.num_nodes());
    EXPECT_NEAR(e.bonds, disc.num_bonds(), 0.01 * disc.num_bonds());
    if (!c.name.starts_with("L") && !c.name.starts_with("hole")) {
      EXPECT_EQ(e.nodes, disc.num_nodes());  // a rectangle: exactly discretize()'s grid
    }
  }
}

TEST(ResourceEstimate, FamilySizeIsTheLatticeCount) {
  // 000's δ = 3.015Δx: 28 neighbours (docs/solver.md, "Families"); δ = 2Δx: 12; δ = 4Δx: 48.
  const auto family = [](const char* ratio) {
    return config::estimate_resources(
               parsed(detail_toml("p", 0.010, 0.005,
                                  "dx = 0.0005\nhorizon_ratio = " + std::string(ratio) + "\n")))
        .family_size;
  };
  EXPECT_EQ(family("3.015"), 28.0);
  EXPECT_EQ(family("2.0"), 12.0);
  EXPECT_EQ(family("4.0"), 48.0);
}

TEST(ResourceEstimate, ExampleCountsAndTheFactorBoundAgainstTheRealFactor) {
  // The B1 example (3,720 nodes), state-based (mixed form, 3 unknowns per node) and bond-based:
  // the estimate's nodes are exact, its bonds, unknowns and matrix entries within 1 %, and its
  // factor entries bound CHOLMOD's supernodal factor from above by at most 2x (measured 1.78x and
  // 1.77x since the precut bonds left the pattern; 1.24-1.25x at 60k nodes, where a lower bound
  // matters; docs/limits.md).
  const config::ConfigResult r = config::load_config(examples_dir() + "/b1-ct-al6061.toml");
  ASSERT_TRUE(r.ok()) << r.error_text();
  for (const model::ModelKind kind :
       {model::ModelKind::state_based, model::ModelKind::bond_based}) {
    SCOPED_TRACE(kind == model::ModelKind::state_based ? "state_based" : "bond_based");
    config::DetailConfig d = r.config->details[0];
    d.model.kind = kind;
    const config::ResourceEstimate e = config::estimate_resources(d);
    const mesh::Discretization disc = discretize(d);
    EXPECT_EQ(e.nodes, disc.num_nodes());
    EXPECT_EQ(disc.num_nodes(), 3720);
    EXPECT_NEAR(e.bonds, disc.num_bonds(), 0.01 * disc.num_bonds());
    const config::ResolvedBoundary boundary = config::resolve(d, disc);
    ASSERT_TRUE(boundary.ok());
    const model::PdModel model =
        model::build_model(disc, d.material, d.model, d.geometry.rigid_factor);
    statics::StaticSolver solver(disc, model, boundary.supports, boundary.loads);
    ASSERT_TRUE(solver.solve().ok());
    EXPECT_EQ(solver.mixed_form(), kind == model::ModelKind::state_based);
    EXPECT_NEAR(e.unknowns, solver.num_unknowns(), 0.01 * solver.num_unknowns());
    const auto matrix = static_cast<double>(solver.stiffness_upper().nonZeros());
    EXPECT_NEAR(e.matrix_nonzeros, matrix, 0.01 * matrix);
    const double factor = solver.factor().factor_nonzeros();
    EXPECT_GE(e.factor_nonzeros, factor);
    EXPECT_LE(e.factor_nonzeros, 2.0 * factor);
    // The life band (a2_scatter) keeps three simulations besides the live engine.
    EXPECT_EQ(e.engines, 4);
    EXPECT_EQ(e.bytes, e.model_bytes + 4 * e.engine_bytes);
  }
}

TEST(ResourceEstimate, DegenerateInputsGiveNumbersNotNaN) {
  config::DetailConfig d;  // no outline, dx = 0: nothing
  EXPECT_EQ(config::estimate_resources(d).bytes, 0.0);
  d = parsed(detail_toml("p", 0.010, 0.005, "dx = 0.0005\n"));
  d.dx = 1e-300;  // 10^596 nodes: clamped, not inf - inf
  const config::ResourceEstimate e = config::estimate_resources(d);
  EXPECT_FALSE(std::isnan(e.bonds));
  EXPECT_FALSE(std::isnan(e.bytes));
  EXPECT_GT(e.bytes, 1e29);
}

// Configs refused before anything is built ------------------------------------------------------

TEST(ConfigResourceBounds, MicrometreGridRefusedAtGridDxWithoutBuilding) {
  // dx = 1 µm on a 0.1 m x 0.1 m plate: 10^10 nodes, 1.4·10^11 bonds; the engines alone would
  // need more than 10^14 bytes. That parse_config returns at all (the test process has nowhere
  // near that memory) shows nothing was discretized; the estimate says what building would take.
  const std::string text = detail_toml("huge", 0.1, 0.1, "dx = 1e-6\n");
  config::DetailConfig d = parsed(detail_toml("huge", 0.1, 0.1, "dx = 1e-3\n"));
  d.dx = 1e-6;  // what the refused config holds
  const config::ResourceEstimate e = config::estimate_resources(d);
  EXPECT_NEAR(e.nodes, 1e10, 1e-9 * 1e10);
  EXPECT_NEAR(e.bonds, 14e10, 0.01 * 14e10);
  EXPECT_GT(e.bytes, 1e14);

  for (const std::uint64_t limit : {std::uint64_t{0}, 8 * kGiB}) {  // default, 8 GiB
    SCOPED_TRACE(limit);
    const config::ConfigResult r =
        config::parse_config(text, "huge.toml", config::ConfigLimits{limit});
    expect_one_error(r, line_of(text, "dx = 1e-6"), "detail[0].grid.dx",
                     {"2.24 PiB", "1e+10 nodes", "1.4e+11 bonds", "use a larger dx"});
    const std::string named = limit > 0 ? "memory limit 8 GiB (--max-memory)"
                                        : "(the default, 75 % of physical memory; --max-memory";
    EXPECT_NE(r.errors[0].reason.find(named), std::string::npos) << r.errors[0].message();
  }
  const config::ConfigResult unlimited = config::parse_config(
      text, "huge.toml", config::ConfigLimits{std::numeric_limits<std::uint64_t>::max()});
  expect_one_error(unlimited, line_of(text, "dx = 1e-6"), "detail[0].grid.dx",
                   {"too large for the solver's 32-bit indices (at most 2.15e+09 entries)"});
}

TEST(ConfigResourceBounds, HorizonRatioAboveTenRefusedWithItsKeyPath) {
  // horizon_ratio = 1000 used to discretize a 2004 x 2004 square for the default φ0 inside
  // config checking (3.4 GB, 43 s): now it is one error, and φ0 is not computed.
  const std::string text = detail_toml("p", 0.010, 0.005, "dx = 0.0005\nhorizon_ratio = 1000\n");
  expect_one_error(config::parse_config(text, "plate.toml"), line_of(text, "horizon_ratio"),
                   "detail[0].grid.horizon_ratio",
                   {"must be <= 10", "calibrations use 3 to 4", "(got 1000)"});
  const std::string ten = detail_toml("p", 0.010, 0.005, "dx = 0.0005\nhorizon_ratio = 10\n");
  const config::ConfigResult r = config::parse_config(ten, "plate.toml");
  ASSERT_TRUE(r.ok()) << r.error_text();
  EXPECT_EQ(r.config->details[0].fatigue.phase_switch_damage,
            fatigue::phase_switch_damage_for_horizon(10.0));
}

TEST(ConfigResourceBounds, MemoryLimitNamesTheEstimateAndTheLimit) {
  // The B1 example needs an estimated ~540 MiB (4 engines with a 6.6e6-entry factor each):
  // refused under 64 MiB at detail[0].grid.dx, accepted under 4 GiB.
  const std::string file = examples_dir() + "/b1-ct-al6061.toml";
  const config::ConfigResult accepted = config::load_config(file, config::ConfigLimits{4 * kGiB});
  ASSERT_TRUE(accepted.ok()) << accepted.error_text();
  const config::ResourceEstimate e = config::estimate_resources(accepted.config->details[0]);
  EXPECT_GT(e.bytes, 64.0 * 1024 * 1024);
  EXPECT_LT(e.bytes, 4.0 * kGiB);

  const config::ConfigResult refused = config::load_config(file, config::ConfigLimits{64 << 20});
  ASSERT_EQ(refused.errors.size(), 1u) << refused.error_text();
  const config::ConfigError& err = refused.errors[0];
  EXPECT_EQ(err.file, file);
  EXPECT_EQ(err.path, "detail[0].grid.dx");
  std::ifstream in(file);
  std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(err.line, line_of(content, "dx = "));
  EXPECT_EQ(err.column, 6u);  // the value
  for (const std::string_view part :
       {std::string_view("would need an estimated "), std::string_view("MiB (3720 nodes, "),
        std::string_view("4 fatigue engines with a Cholesky factor"),
        std::string_view("more than the memory limit 64 MiB"),
        std::string_view("or raise the limit")}) {
    EXPECT_NE(err.reason.find(part), std::string::npos) << err.message();
  }
}

TEST(ConfigResourceBounds, AllDetailsTogetherRefusedAtTheLargest) {
  // Two plates, each under the limit alone, over it together: one error, at the larger one.
  const std::string grid = "dx = 0.00025\n";
  const std::string text =
      detail_toml("small", 0.010, 0.005, grid) + detail_toml("large", 0.020, 0.010, grid);
  const config::ConfigResult unlimited =
      config::parse_config(text, "two.toml", config::ConfigLimits{1024 * kGiB});
  ASSERT_TRUE(unlimited.ok()) << unlimited.error_text();
  const double small = config::estimate_resources(unlimited.config->details[0]).bytes;
  const double large = config::estimate_resources(unlimited.config->details[1]).bytes;
  ASSERT_LT(small, large);
  const auto limit = static_cast<std::uint64_t>(large + 0.5 * small);
  const config::ConfigResult r =
      config::parse_config(text, "two.toml", config::ConfigLimits{limit});
  ASSERT_EQ(r.errors.size(), 1u) << r.error_text();
  EXPECT_EQ(r.errors[0].path, "detail[1].grid.dx");
  EXPECT_NE(r.errors[0].reason.find("the 2 details would need an estimated"), std::string::npos)
      << r.errors[0].message();
}

TEST(ConfigResourceBounds, AllDetailsTogetherCountTheLifeEnginesOfTheConcurrentEstimatesOnly) {
  // Three copies of the B1 example, each with its live engine and three life engines (A2 band).
  // Every detail's life engines at once (concurrent_life_estimates 0) is over the limit; those of
  // one detail at a time (the daemon's one shared life thread) is under it, and the refusal of a
  // smaller limit says so.
  std::ifstream in(examples_dir() + "/b1-ct-al6061.toml");
  const std::string example((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string text;
  for (const std::string id : {"a", "b", "c"}) {
    std::string copy = example;
    for (const auto& [from, to] :
         {std::pair<std::string, std::string>{"id = \"b1-ct\"", "id = \"" + id + "\""},
          {"\"results/b1-ct\"", "\"results/" + id + "\""}}) {
      const auto at = copy.find(from);
      ASSERT_NE(at, std::string::npos) << from;
      copy.replace(at, from.size(), to);
    }
    text += copy + "\n";
  }
  const config::ConfigResult unlimited =
      config::parse_config(text, "three.toml", config::ConfigLimits{1024 * kGiB});
  ASSERT_TRUE(unlimited.ok()) << unlimited.error_text();
  const config::ResourceEstimate e = config::estimate_resources(unlimited.config->details[0]);
  ASSERT_EQ(e.engines, 4);
  const double one_at_a_time = 3 * (e.model_bytes + e.engine_bytes) + 3 * e.engine_bytes;
  const double all_at_once = 3 * e.bytes;
  const auto limit = static_cast<std::uint64_t>(0.5 * (one_at_a_time + all_at_once));

  const config::ConfigResult every =
      config::parse_config(text, "three.toml", config::ConfigLimits{limit, {}, 0});
  ASSERT_EQ(every.errors.size(), 1u) << every.error_text();
  EXPECT_NE(every.errors[0].reason.find("the 3 details would need an estimated"), std::string::npos)
      << every.errors[0].message();
  const config::ConfigResult one =
      config::parse_config(text, "three.toml", config::ConfigLimits{limit, {}, 1});
  EXPECT_TRUE(one.ok()) << one.error_text();
  const config::ConfigResult smaller = config::parse_config(
      text, "three.toml",
      config::ConfigLimits{static_cast<std::uint64_t>(0.9 * one_at_a_time), {}, 1});
  ASSERT_EQ(smaller.errors.size(), 1u) << smaller.error_text();
  EXPECT_NE(smaller.errors[0].reason.find(
                "together (remaining-life simulations of at most 1 detail(s) at once)"),
            std::string::npos)
      << smaller.errors[0].message();
}

TEST(ConfigServedDetails, OnlyTheServedDetailsAreReturnedAndCountedAgainstTheLimit) {
  // The daemon's --details (a fleet sharing one config): two plates over the limit together, each
  // under it alone. Serving one: accepted, that detail only; serving both: refused as before; an
  // id the file does not have: an error naming it and the file's details.
  const std::string grid = "dx = 0.00025\n";
  const std::string text =
      detail_toml("small", 0.010, 0.005, grid) + detail_toml("large", 0.020, 0.010, grid);
  const config::ConfigResult unlimited =
      config::parse_config(text, "two.toml", config::ConfigLimits{1024 * kGiB});
  ASSERT_TRUE(unlimited.ok()) << unlimited.error_text();
  const double small = config::estimate_resources(unlimited.config->details[0]).bytes;
  const double large = config::estimate_resources(unlimited.config->details[1]).bytes;
  const auto limit = static_cast<std::uint64_t>(large + 0.5 * small);

  const config::ConfigResult one =
      config::parse_config(text, "two.toml", config::ConfigLimits{limit, {"large"}});
  ASSERT_TRUE(one.ok()) << one.error_text();
  ASSERT_EQ(one.config->details.size(), 1u);
  EXPECT_EQ(one.config->details[0].id, "large");

  const config::ConfigResult both =
      config::parse_config(text, "two.toml", config::ConfigLimits{limit, {"small", "large"}});
  ASSERT_EQ(both.errors.size(), 1u) << both.error_text();
  EXPECT_EQ(both.errors[0].path, "detail[1].grid.dx");

  const config::ConfigResult unknown =
      config::parse_config(text, "two.toml", config::ConfigLimits{1024 * kGiB, {"small", "nope"}});
  ASSERT_EQ(unknown.errors.size(), 1u) << unknown.error_text();
  EXPECT_EQ(unknown.errors[0].path, "--details");
  EXPECT_EQ(unknown.errors[0].reason, "no detail \"nope\" in the file (its details: small, large)");
}

TEST(ConfigResourceBounds, HostileGeometryEndsInErrorsNotExceptions) {
  // 1500 abutting rectangles 1 m x 1 m at dx = 0.1 mm (1.5e11 nodes): swept exactly (4.5e6 steps);
  // with 20 holes besides, the sweep would take 9.5e7 steps and the bounding box stands in. Then
  // coordinates of 1e300 m at dx = 1 m. A ConfigError at grid.dx each time, never bad_alloc.
  std::string many = "outline = [\n";
  for (int i = 0; i < 1500; ++i) {
    many += "{ x_min = " + std::to_string(i) + ".0, y_min = 0.0, x_max = " + std::to_string(i + 1) +
            ".0, y_max = 1.0 },\n";
  }
  many += "]\n";
  std::string holes = "holes = [\n";
  for (int i = 0; i < 20; ++i) {
    holes += "{ centre = [" + std::to_string(10 * i + 5) + ".5, 0.5], radius = 0.25 },\n";
  }
  holes += "]\n";
  for (const std::string& geometry : {many, many + holes}) {
    const std::string text = detail_toml("many", 1500.0, 1.0, "dx = 1e-4\n", geometry);
    const config::ConfigResult r =
        config::parse_config(text, "many.toml", config::ConfigLimits{8 * kGiB});
    ASSERT_EQ(r.errors.size(), 1u) << r.error_text();
    EXPECT_EQ(r.errors[0].path, "detail[0].grid.dx");
    EXPECT_NE(r.errors[0].reason.find("(1.5e+11 nodes,"), std::string::npos)
        << r.errors[0].message();
  }

  const std::string vast = detail_toml("vast", 1e300, 1e300, "dx = 1.0\n");
  const config::ConfigResult v =
      config::parse_config(vast, "vast.toml", config::ConfigLimits{8 * kGiB});
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.errors.back().path, "detail[0].grid.dx") << v.error_text();
}

// Sizes on the command line and in messages ------------------------------------------------------

TEST(ByteSizes, ParsedWithBinarySuffixes) {
  EXPECT_EQ(config::parse_byte_size("8G"), 8 * kGiB);
  EXPECT_EQ(config::parse_byte_size("8g"), 8 * kGiB);
  EXPECT_EQ(config::parse_byte_size("8GiB"), 8 * kGiB);
  EXPECT_EQ(config::parse_byte_size("512M"), std::uint64_t{512} << 20U);
  EXPECT_EQ(config::parse_byte_size("64K"), std::uint64_t{64} << 10U);
  EXPECT_EQ(config::parse_byte_size("2T"), std::uint64_t{2} << 40U);
  EXPECT_EQ(config::parse_byte_size("1048576"), std::uint64_t{1048576});
  EXPECT_EQ(config::parse_byte_size("100B"), std::uint64_t{100});
  for (const char* bad : {"", "G", "0", "0G", "-1", "1.5G", "8X", "8 G", "8GB2", " 8G",
                          "99999999999999999999", "17179869184G"}) {
    EXPECT_FALSE(config::parse_byte_size(bad).has_value()) << bad;
  }
}

TEST(ByteSizes, FormattedInBinaryUnits) {
  EXPECT_EQ(config::format_bytes(512), "512 B");
  EXPECT_EQ(config::format_bytes(1536), "1.5 KiB");
  EXPECT_EQ(config::format_bytes(3.4e9), "3.17 GiB");
  EXPECT_EQ(config::format_bytes(2.5e15), "2.22 PiB");
  EXPECT_EQ(config::format_bytes(1e30), "8.67e+11 EiB");
}

TEST(ByteSizes, DefaultLimitIsThreeQuartersOfPhysicalMemory) {
  const std::uint64_t limit = config::default_memory_limit();
  EXPECT_GT(limit, 0u);
  const config::ConfigResult r =
      config::parse_config(plate(), "plate.toml");  // the default applies
  EXPECT_TRUE(r.ok()) << r.error_text();
}

}  // namespace
}  // namespace peritwin::twin
