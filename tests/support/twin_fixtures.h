// Shared helpers of the twin tests: the B1 example config (coarse demo grid) with edits.
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "config/config.h"
#include "solver/statics/gauges.h"
#include "twin/detail_model.h"
#include "twin/twin.h"

namespace peritwin::twin::testing {

inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

using Edits = std::vector<std::pair<std::string, std::string>>;

/// The B1 example text with `life_extra` (default: no remaining-life estimates) replacing its
/// `every_batches = 10` line under [detail.life], and every edit's first string replaced by its
/// second.
inline std::string b1_text(const std::string& life_extra = "every_batches = 0",
                           const Edits& edits = {}) {
  std::string text = read_text(std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml");
  // Without the example's learning ensemble ([detail.uncertainty], 64 particles): a test of the
  // ensemble adds its own (tests/twin/test_ensemble.cpp, test_learning_twin.cpp).
  if (const auto u = text.find("\n[detail.uncertainty]"); u != std::string::npos) {
    text.erase(u + 1, text.find("\n[", u + 1) - u);
  }
  const std::string anchor = "\nevery_batches = 10\n";
  text.replace(text.find(anchor), anchor.size(), "\n" + life_extra + "\n");
  for (const auto& [from, to] : edits) {
    const auto p = text.find(from);
    EXPECT_NE(p, std::string::npos) << from;
    if (p != std::string::npos) text.replace(p, from.size(), to);
  }
  return text;
}

inline config::DetailConfig b1_config(const std::string& life_extra = "every_batches = 0",
                                      const Edits& edits = {}) {
  const std::string text = b1_text(life_extra, edits);
  auto result = config::parse_config(text, "b1-test.toml");
  EXPECT_TRUE(result.ok()) << result.error_text();
  return result.config->details.at(0);
}

/// The inputs of the cross-process tests: B1 on the demo grid with a 3 mm life criterion
/// without band (synchronous estimates at states 0, 10, 20 take a few seconds) and checkpoints
/// every 4 batches; a history of 24 batches of 1000 cycles (every fourth at 4.2 kN, else 4 kN).
inline void write_cross_process_inputs(const std::string& config, const std::string& history) {
  std::ofstream(config) << b1_text(
      "every_batches = 10", {{"critical_crack_length = 0.008", "critical_crack_length = 0.003"},
                             {"band = \"a2_scatter\"", "band = \"none\""},
                             {"a2_relative_scatter = 0.2", ""},
                             {"every_batches = 100", "every_batches = 4"}});
  std::ofstream h(history);
  h << "p_max_N,r,angle_rad,count\n";
  for (int i = 0; i < 24; ++i) h << (i % 4 == 3 ? "4200" : "4000") << ",0.1,0,1000\n";
}

inline std::shared_ptr<const twin::DetailModel> b1_model(const config::DetailConfig& config) {
  auto model = twin::DetailModel::build(config);
  EXPECT_TRUE(model.ok()) << model.error().message();
  return model ? *model : nullptr;
}

inline std::unique_ptr<twin::Twin> make_twin(const std::shared_ptr<const twin::DetailModel>& model,
                                             twin::LifeMode mode = twin::LifeMode::synchronous) {
  auto twin = twin::Twin::create(model, {mode, true, true});
  EXPECT_TRUE(twin.ok()) << twin.error().message();
  return twin ? std::move(*twin) : nullptr;
}

inline messages::Batch batch(std::int64_t seq, std::vector<core::LoadBlock> blocks,
                             const std::string& source = "test") {
  return {"b1-ct", source, seq, std::move(blocks)};
}

/// A gauge observation (issue 33) of the twin's gauges: each gauge's compliance the model's at
/// α = 0 times (1 + excess[g]), measured against the model's coefficients times `used` (the
/// stream's, maybe older), σ = 0.1 % of it; detail b1-ct, source "gauges", at the twin's cycle.
inline messages::Observation gauge_observation(const twin::Twin& twin, std::int64_t seq,
                                               const std::vector<double>& excess,
                                               double used = 1.0) {
  messages::Observation o;
  o.kind = messages::ObservationKind::gauge_compliance;
  o.detail_id = "b1-ct";
  o.source_id = "gauges";
  o.seq = seq;
  o.cycle = twin.engine().total_cycles();
  const auto c = twin.gauge_influences();
  for (std::size_t g = 0; g < c.size(); ++g) {
    const double v = statics::gauge_strain(c[g], 1.0, 0.0);
    o.gauges.push_back({twin.model().gauges()[g].config.id, used * v * (1 + excess[g]),
                        1e-3 * std::abs(used * v), used * v, true});
  }
  return o;
}

}  // namespace peritwin::twin::testing
