// K at cracks from a hole, as the twin reports it per tip (measure_cracks: displacement
// extrapolation along the tip's own direction, 001 Eq. 62-63, with the validity checks), against
// the handbook solution for two symmetric through cracks at a central hole in a finite-width strip
// (validation/handbook_k.h: Newman-Raju's fit of Bowie's factor with their finite-width
// correction; docs/handbook-k.md, agreement between the published fits about 2 %).
//
// The detail is examples/strip-with-hole.toml (200 × 60 × 5 mm, Ø 10 mm hole, tension along x)
// on a grid of Δx = 0.5 mm (δ = 1.5 mm; 47 000 nodes, ~12 s per case) with the two cracks cut as
// notches from the hole's rim along ±y to c = 2, 4, 8 mm: the static state under P_max, no
// fatigue. Measured: c = 4 mm +5.6 %, c = 8 mm +7.0 %, the two cracks equal; K_II 3 % of K_I
// (the cuts run 0.1 mm beside the hole's axis, see below). At c = 2 mm the fit does not fit
// behind the tip on this grid (it needs 2δ = 3 mm of faces): K is flagged short. A 2 mm crack
// needs δ < 1 mm, Δx ≤ 0.33 mm: the full strip then needs more than 10 GB (the config's estimate).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/support/twin_fixtures.h"
#include "validation/handbook_k.h"

namespace peritwin::twin {
namespace {

std::string example_text() {
  std::ifstream in(std::string(PERITWIN_EXAMPLES_DIR) + "/strip-with-hole.toml");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string replaced(std::string text, const std::string& what, const std::string& with) {
  const auto at = text.find(what);
  EXPECT_NE(at, std::string::npos) << what;
  if (at != std::string::npos) text.replace(at, what.size(), with);
  return text;
}

TEST(HoleCrackK, TwoCracksAtTheHoleMatchTheHandbookWithinTenPercent) {
  const double width = 0.060, thickness = 0.005, radius = 0.005, p_max = 20000.0;
  const double sigma = p_max / (width * thickness);  // the grip force over the gross section
  for (const double c : {0.002, 0.004, 0.008}) {
    SCOPED_TRACE("c = " + std::to_string(c * 1e3) + " mm");
    std::string text = example_text();
    text = replaced(text, "dx = 0.002 ", "dx = 0.0005 ");
    // The cuts start inside the hole (0.5 mm) and end c beyond the rim, along x = 100.1 mm
    // (between two node columns). Not x = 100 mm: there the tips lie exactly on points where
    // bonds cross, and whether those bonds are cut (segments_cross counts touching) is decided by
    // the rounding of 0.035 + c against 0.025 − c. Found here: the upper and lower cracks' K then
    // differed by 4-5 %; at 100.1 mm they are equal to all printed digits.
    std::ostringstream notches;
    notches.precision(17);
    notches << "notches = [{ from = [0.1001, " << 0.030 + radius - 0.0005 << "], to = [0.1001, "
            << 0.030 + radius + c << "], name = \"upper\" }, { from = [0.1001, "
            << 0.030 - radius + 0.0005 << "], to = [0.1001, " << 0.030 - radius - c
            << "], name = \"lower\" }]\n";
    text = replaced(text, "no_fail_zones = [", notches.str() + "no_fail_zones = [");
    const config::ConfigResult parsed = config::parse_config(text, "strip-with-hole-cracks.toml");
    ASSERT_TRUE(parsed.ok()) << parsed.error_text();
    const auto model = testing::b1_model(parsed.config->details.at(0));
    ASSERT_TRUE(model);
    auto engine = model->make_engine();
    ASSERT_TRUE(engine->initialize()) << engine->failure_reason();
    const core::LoadBlock block{p_max, 0.1, 0.0, 1};
    const twin::CrackReport report = twin::measure_cracks(*model, *engine, &block);
    ASSERT_EQ(report.cracks.size(), 2u);
    const double handbook =
        validation::k_crack_at_hole(sigma, width, radius, c, /*two_cracks=*/true);
    for (const auto& rc : report.cracks) {
      SCOPED_TRACE(rc.origin);
      ASSERT_EQ(rc.k.size(), 1u);
      if (c < 2 * model->disc().horizon - 0.0005) {
        // 2 mm of crack plus the 0.5 mm cut inside the hole: less than the 2δ = 3.015 mm the
        // fit needs behind the tip. Flagged, never a number.
        EXPECT_EQ(rc.k[0].status, twin::KStatus::short_crack);
        EXPECT_TRUE(std::isnan(rc.k[0].k_i));
        continue;
      }
      ASSERT_EQ(rc.k[0].status, twin::KStatus::ok);
      EXPECT_GT(rc.k[0].k_i, 0.0);  // opening: the sign is stable
      EXPECT_NEAR(rc.k[0].k_i / handbook, 1.0, 0.10)
          << "PD " << rc.k[0].k_i * 1e-6 << " MPa√m, handbook " << handbook * 1e-6;
      // Symmetric mode I: K_II small against K_I.
      EXPECT_LT(std::abs(rc.k[0].k_ii), 0.05 * rc.k[0].k_i);
      std::cout << "c = " << c * 1e3 << " mm, " << rc.origin << ": K_I = " << rc.k[0].k_i * 1e-6
                << " MPa√m, handbook " << handbook * 1e-6 << ", K_II = " << rc.k[0].k_ii * 1e-6
                << "\n";
    }
  }
}

}  // namespace
}  // namespace peritwin::twin
