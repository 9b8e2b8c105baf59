// Issue 33: strain gauges on the model. Their influence coefficients against closed forms (the far
// field of a strip, P/(W·h·E) and −ν times it across; Kirsch's field beside a hole, with the
// nonlocal gradient's smoothing stated), the PD strain of an affine field exact at any node,
// the coefficients following the model after bonds break (against a solver built afresh on the
// same bonds), and the compliance residual's alarm on synthetic gauge observations.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include "solver/statics/gauges.h"
#include "tests/support/twin_fixtures.h"
#include "twin/gauges.h"
#include "twin/messages_io.h"

namespace peritwin::twin {
namespace {

/// A plain Al strip W = 60 mm wide, 240 mm long, h = 5 mm, pulled along x by P on its right end
/// column, held in x on its left end column (one node in y too), on a dx grid; `extra` appended
/// inside the [[detail]] (holes, gauges).
std::string strip_text(double length, double width, double dx, const std::string& geometry_extra,
                       const std::string& gauges) {
  const auto num = [](double v) { return std::to_string(v); };
  return "[[detail]]\nid = \"strip\"\n[detail.geometry]\nthickness = 0.005\n"
         "outline = [{ x_min = 0.0, y_min = 0.0, x_max = " +
         num(length) + ", y_max = " + num(width) + " }]\n" + geometry_extra +
         "\n[detail.grid]\ndx = " + num(dx) +
         "\nhorizon_ratio = 3.015\n[detail.model]\nkind = \"state_based\"\n"
         "plane = \"plane_stress\"\n[detail.material]\nE = 68e9\nnu = 0.33\nK_c = 48.7e6\n"
         "[detail.fatigue]\nlaw = \"strain_range\"\nphi0 = 0.398\nA1 = 103.7465\nm1 = 2.29153\n"
         "A2 = 1301.0\nm2 = 2.6183\n[[detail.load]]\nregion = { x_min = " +
         num(length - dx) + ", y_min = 0.0, x_max = " + num(length) + ", y_max = " + num(width) +
         " }\nconstant = [1.0, 0.0]\n[[detail.support]]\nregion = { x_min = 0.0, y_min = 0.0, "
         "x_max = " +
         num(dx) + ", y_max = " + num(width) +
         " }\nfix_x = true\nfix_y = false\n[[detail.support]]\npoint = [" + num(0.5 * dx) + ", " +
         num(0.5 * width) + "]\n[detail.life]\nevery_batches = 0\n" + gauges;
}

std::shared_ptr<const DetailModel> build(const std::string& text) {
  auto parsed = config::parse_config(text, "gauges-test.toml");
  EXPECT_TRUE(parsed.ok()) << parsed.error_text();
  if (!parsed.ok()) return nullptr;
  return testing::b1_model(parsed.config->details.at(0));
}

std::vector<std::array<double, 3>> virgin_influences(const DetailModel& model) {
  auto engine = model.make_engine();
  EXPECT_TRUE(engine->initialize());
  return gauge_influences(model.gauges(), engine->solver());
}

TEST(Gauges, StripFarFieldIsPOverWhE) {
  // Gauges 80 mm from either end (> 2 W: Saint-Venant), 10 mm long, along and across the load.
  const double pi = std::numbers::pi;
  const auto model = build(strip_text(
      0.240, 0.060, 0.002, "",
      "[[detail.gauge]]\nid = \"axial\"\nat = [0.12, 0.03]\nlength = 0.01\nnoise = 1e-6\n"
      "[[detail.gauge]]\nid = \"lateral\"\nat = [0.12, 0.03]\nangle = " +
          std::to_string(pi / 2) + "\nlength = 0.01\n"));
  ASSERT_TRUE(model);
  ASSERT_EQ(model->gauges().size(), 2u);
  // 10 mm of a 2 mm grid: 6 columns; y = 30 mm lies between two rows, dx/2 from each: both.
  EXPECT_EQ(model->gauges()[0].nodes.size(), 12u);
  const auto c = virgin_influences(*model);
  const double expected = 1.0 / (0.060 * 0.005 * 68e9);  // P/(W·h·E), P = 1 N
  EXPECT_NEAR(c[0][0] / expected, 1.0, 0.005);
  EXPECT_NEAR(c[1][0] / expected, -0.33, 0.005);  // −ν: plane stress
  // The pattern has no angle dependence: the cos α and sin α cases load nothing.
  EXPECT_EQ(c[0][1], 0.0);
  EXPECT_EQ(c[0][2], 0.0);
}

TEST(Gauges, NormalStrainOfAnAffineFieldIsExactAtEveryNode) {
  const auto model = build(strip_text(0.04, 0.02, 0.002, "", ""));
  ASSERT_TRUE(model);
  const auto& disc = model->disc();
  // u = H·x with H = [[2, 3], [−1, 5]]·1e-4: n·sym(H)·n at 30° is exact at boundary nodes too.
  const double hxx = 2e-4, hxy = 3e-4, hyx = -1e-4, hyy = 5e-4, angle = std::numbers::pi / 6;
  std::vector<double> u(2 * static_cast<std::size_t>(disc.num_nodes()));
  for (std::size_t k = 0; k < disc.position.size(); ++k) {
    u[2 * k] = hxx * disc.position[k].x + hxy * disc.position[k].y;
    u[2 * k + 1] = hyx * disc.position[k].x + hyy * disc.position[k].y;
  }
  const double c = std::cos(angle), s = std::sin(angle);
  const double expected = hxx * c * c + (hxy + hyx) * c * s + hyy * s * s;
  for (mesh::NodeIndex k = 0; k < disc.num_nodes(); ++k) {
    EXPECT_NEAR(statics::pd_normal_strain(disc, {}, u, k, angle), expected, 1e-15) << k;
  }
}

/// Kirsch's plane-stress strain along `angle` at (x, y) from the centre of a hole of radius a in
/// an infinite plate under a remote stress S along x.
double kirsch_strain(double x, double y, double a, double s, double e, double nu, double angle) {
  const double r = std::hypot(x, y), t = std::atan2(y, x);
  const double q = a * a / (r * r);
  const double srr = s / 2 * (1 - q) + s / 2 * (1 - 4 * q + 3 * q * q) * std::cos(2 * t);
  const double stt = s / 2 * (1 + q) - s / 2 * (1 + 3 * q * q) * std::cos(2 * t);
  const double srt = -s / 2 * (1 + 2 * q - 3 * q * q) * std::sin(2 * t);
  const double c = std::cos(t), n = std::sin(t);
  const double sxx = srr * c * c + stt * n * n - 2 * srt * n * c;
  const double syy = srr * n * n + stt * c * c + 2 * srt * n * c;
  const double sxy = (srr - stt) * n * c + srt * (c * c - n * n);
  const double exx = (sxx - nu * syy) / e, eyy = (syy - nu * sxx) / e, exy = (1 + nu) / e * sxy;
  const double gc = std::cos(angle), gs = std::sin(angle);
  return exx * gc * gc + eyy * gs * gs + 2 * exy * gc * gs;
}

TEST(Gauges, BesideAHoleKirschWithinTheNonlocalSmoothing) {
  // A 160 x 120 mm plate with a hole of a = 6 mm at (80, 60) mm (d/W = 0.1), dx = 1 mm, δ = 3 mm.
  // Point gauges along x at 2a and 3a from the centre, beside the hole (θ = 90°).
  const double a = 0.006, cx = 0.080, cy = 0.060, dx = 0.001;
  const auto model =
      build(strip_text(0.160, 0.120, dx, "holes = [{ centre = [0.080, 0.060], radius = 0.006 }]\n",
                       "[[detail.gauge]]\nid = \"r2a\"\nat = [0.0805, 0.0725]\n"
                       "[[detail.gauge]]\nid = \"r3a\"\nat = [0.0805, 0.0785]\n"));
  ASSERT_TRUE(model);
  const auto c = virgin_influences(*model);
  const double s = 1.0 / (0.120 * 0.005), e = 68e9, nu = 0.33;  // remote stress of P = 1 N
  const double delta = model->disc().horizon;
  for (std::size_t g = 0; g < 2; ++g) {
    const mesh::Point p =
        model->disc().position[static_cast<std::size_t>(model->gauges()[g].nodes[0])];
    const double x = p.x - cx, y = p.y - cy;
    const double local = kirsch_strain(x, y, a, s, e, nu, 0.0);
    // The PD gradient (004 Eq. 6, ω = 1) is the least-squares linear fit of u over the horizon's
    // disc: exact for quadratic u, its error for a smooth field is (δ²/12)·∇²ε to leading order
    // (a disc's moments: ⟨x⁴⟩/⟨x²⟩ = δ²/2, ⟨x²y²⟩/⟨x²⟩ = δ²/6). ∇² of Kirsch's strain by central
    // differences.
    const double h = 1e-4;
    const double laplacian =
        (kirsch_strain(x + h, y, a, s, e, nu, 0) + kirsch_strain(x - h, y, a, s, e, nu, 0) +
         kirsch_strain(x, y + h, a, s, e, nu, 0) + kirsch_strain(x, y - h, a, s, e, nu, 0) -
         4 * local) /
        (h * h);
    const double smoothed = local + delta * delta / 12 * laplacian;
    // Left to the finite width (Howland: ~1 % at d/W = 0.1 this far from the rim) and the grid's
    // staircase rim: 2 % of the local strain (measured: 0.2 % and 0.8 %).
    EXPECT_NEAR(c[g][0] / smoothed, 1.0, 0.02)
        << model->gauges()[g].config.id << ": Kirsch " << local << ", smoothed " << smoothed
        << ", model " << c[g][0] << ", far field " << s / e;
    // And beyond the far field (Kirsch: 1.17 and 1.03 of it): the gauge sees the concentration.
    EXPECT_GT(c[g][0], (g == 0 ? 1.1 : 1.01) * s / e);
    std::cout << model->gauges()[g].config.id << ": model/Kirsch " << c[g][0] / local
              << ", model/smoothed " << c[g][0] / smoothed << "\n";
  }
}

TEST(GaugeObservations, ResidualsAlarmAndCheckpoint) {
  const auto model = testing::b1_model(testing::b1_config());
  ASSERT_TRUE(model);
  ASSERT_EQ(model->gauges().size(), 3u);  // the example's tip, arm, back
  auto twin = testing::make_twin(model);
  ASSERT_TRUE(twin->apply(testing::batch(1, {{4000.0, 0.1, 0.0, 2000}})).applied());
  const std::string before = twin::state_message(*twin, 0, {}).state_hash;
  // No gauge observation yet: the residuals are NaN and out of the hash (a detail without gauges
  // hashes as before them).
  EXPECT_TRUE(std::isnan(twin->gauge_residuals().residual[0]));

  // What the model predicts: residual 0 (to round-off) for every gauge, no alarm.
  ASSERT_TRUE(twin->observe(testing::gauge_observation(*twin, 1, {0, 0, 0})).applied());
  for (std::size_t g = 0; g < 3; ++g) {
    EXPECT_NEAR(twin->gauge_residuals().residual[g], 0.0, 1e-12);
    EXPECT_NEAR(twin->gauge_residuals().sigma[g], 1e-3, 1e-12);
    EXPECT_EQ(twin->gauge_residuals().in_a_row[g], 0);
  }
  EXPECT_NE(twin::state_message(*twin, 0, {}).state_hash, before);
  // Coefficients 10 % high in the stream (P̂ = P/1.1 then): k_X = 1/1.1, m^X = 1.1·v: residual 0.
  ASSERT_TRUE(twin->observe(testing::gauge_observation(*twin, 2, {0, 0, 0}, 1.1)).applied());
  EXPECT_NEAR(twin->gauge_residuals().residual[1], 0.0, 1e-12);

  // The tip gauge 8 % more compliant than the model, 80 σ: in alarm after kGaugeAlarmAfter.
  for (std::int64_t k = 0; k < kGaugeAlarmAfter; ++k) {
    EXPECT_EQ(twin->gauge_residuals().alarm(), "");
    ASSERT_TRUE(twin->observe(testing::gauge_observation(*twin, 3 + k, {0.08, 0, 0})).applied());
    EXPECT_NEAR(twin->gauge_residuals().residual[0], 0.08, 1e-12);
    EXPECT_EQ(twin->gauge_residuals().in_a_row[0], k + 1);
    EXPECT_EQ(twin->gauge_residuals().in_a_row[1], 0);
  }
  const std::string alarm = twin->gauge_residuals().alarm();
  EXPECT_NE(alarm.find("gauge tip: compliance residual +8.0 %"), std::string::npos) << alarm;
  EXPECT_EQ(alarm.find("arm"), std::string::npos) << alarm;
  const auto state = twin::state_message(*twin, 0, {});
  ASSERT_EQ(state.num_gauges, 3);
  EXPECT_EQ(state.gauge_ids[0], "tip");
  EXPECT_EQ(state.gauge_alarm_counts[0], kGaugeAlarmAfter);
  EXPECT_NEAR(state.gauge_residuals[0], 0.08, 1e-12);
  // Beyond 4 σ but within the 5 % floor: no count (a twin tracking the structure leaves that).
  ASSERT_TRUE(twin->observe(testing::gauge_observation(*twin, 3 + kGaugeAlarmAfter, {0.04, 0, 0}))
                  .applied());
  EXPECT_EQ(twin->gauge_residuals().in_a_row[0], 0);
  ASSERT_TRUE(twin->observe(testing::gauge_observation(*twin, 4 + kGaugeAlarmAfter, {0.08, 0, 0}))
                  .applied());
  ASSERT_TRUE(twin->observe(testing::gauge_observation(*twin, 5 + kGaugeAlarmAfter, {0.08, 0, 0}))
                  .applied());
  const auto again = twin::state_message(*twin, 0, {});

  // Refused, the state unchanged: a gauge the detail does not have, a cycle in the future.
  auto unknown = testing::gauge_observation(*twin, 6 + kGaugeAlarmAfter, {0, 0, 0});
  unknown.gauges[1].id = "nowhere";
  const auto refused = twin->observe(unknown);
  EXPECT_EQ(refused.what, "observation.gauges[1].id");
  auto future = testing::gauge_observation(*twin, 6 + kGaugeAlarmAfter, {0, 0, 0});
  future.cycle += 1;
  EXPECT_EQ(twin->observe(future).what, "observation.cycle");
  EXPECT_EQ(twin::state_message(*twin, 0, {}).state_hash, again.state_hash);

  // A checkpoint restores the residuals and their counts, bit for bit.
  auto restored = testing::make_twin(model);
  ASSERT_TRUE(restored->restore(twin->to_checkpoint()).ok());
  EXPECT_EQ(twin::state_message(*restored, 0, {}).state_hash, again.state_hash);
  EXPECT_EQ(restored->gauge_residuals().alarm(), alarm);
}

TEST(GaugeObservations, CoefficientsFollowTheBrokenBonds) {
  // After bonds break the STATE's coefficients are those of a solver built afresh on the same
  // intact bonds (the independent path), and the tip gauge's have moved.
  const auto model = testing::b1_model(testing::b1_config());
  ASSERT_TRUE(model);
  auto twin = testing::make_twin(model);
  const auto virgin = twin->gauge_influences();
  ASSERT_TRUE(twin->apply(testing::batch(1, {{4000.0, 0.1, 0.0, 20000}})).applied());
  ASSERT_GT(twin->engine().broken_bonds(), 0);
  const auto now = twin->gauge_influences();
  const auto& sp = model->specimen();
  statics::StaticSolver fresh(sp.disc, sp.model, sp.supports, sp.loads, sp.ties);
  std::vector<mesh::BondIndex> broken;
  for (mesh::BondIndex b = 0; b < sp.disc.num_bonds(); ++b) {
    if (twin->engine().solver().intact()[static_cast<std::size_t>(b)] == 0) broken.push_back(b);
  }
  fresh.set_incremental(false);
  ASSERT_TRUE(fresh.solve().ok());
  ASSERT_TRUE(fresh.break_bonds(broken).ok());
  const auto expected = gauge_influences(model->gauges(), fresh);
  for (std::size_t g = 0; g < 3; ++g) {
    EXPECT_NEAR(now[g][0], expected[g][0], 1e-9 * std::abs(expected[g][0])) << g;
  }
  EXPECT_GT(std::abs(now[0][0] / virgin[0][0] - 1), 1e-3);  // the tip gauge saw the crack
  const auto state = twin::state_message(*twin, 0, {});
  EXPECT_EQ(state.gauge_per_constant[0], now[0][0]);
}

}  // namespace
}  // namespace peritwin::twin
