// B5 (issue 35): paper 004's low-cycle fatigue scheme (validation/b5_low_cycle.h) on a coarse
// strip, 7 points across the 5 mm gauge (245 nodes): the calibrations against the curve they
// come from, the N25 stepping against solving every block, and the full runs' orderings.
#include <gtest/gtest.h>

#include <cmath>

#include "validation/b5_low_cycle.h"

namespace peritwin {
namespace {

using namespace peritwin::validation;

const model::PowerLawCurve kCurve;  // 004's 316L curve

statics::Specimen coarse_strip() {
  B5Specimen spec;
  spec.points_across = 7;
  return make_b5_specimen(spec);
}

TEST(B5, KappaMakesTheStripCarryTheCurvesStressAtTheSymmetricAmplitude) {
  const auto strip = coarse_strip();
  const double kappa = calibrate_b5_kappa(strip, kCurve, 0.0018);
  B5Options o;
  o.kappa = kappa;
  o.max_cycles = 1;  // one cycle: its upper turning point is the virgin loading
  const auto k = calibrate_b5_kinetics(kCurve, 0.0, 1.2);
  ASSERT_TRUE(k.ok()) << k.error().reason;
  const B5Result r = run_b5_loading(strip, kCurve, symmetric_loading(), *k, o);
  EXPECT_NEAR(r.peak_stress / kCurve.stress(0.0018), 1.0, 1e-6);  // bisection to 2e-12 in κ
  EXPECT_GT(kappa, 0.2);
  EXPECT_LT(kappa, 2.0);
}

TEST(B5, TheSegmentsReproduceTheSnCurveTheyWereFittedOn) {
  // Independent: the single-bond life of each fitted segment at its points against NUREG's
  // through the curve, within the fit's own reported max |Δ ln N| (segment 1: 0.19, 004-design).
  std::vector<B5SegmentFit> fits;
  const auto k = calibrate_b5_kinetics(kCurve, 0.0, 1.2, &fits);
  ASSERT_TRUE(k.ok());
  ASSERT_EQ(fits.size(), 3u);
  const double kt = fatigue::kt_thermal_energy(k->base.temperature);
  for (double sa : {212e6, 230e6, 248e6}) {
    const double n =
        fatigue::kt_sn_life(sa, -1.0, k->base.frequency, k->extension.segments[0].U,
                            k->extension.segments[0].gamma, k->base.lambda, k->base.n0, kt);
    const double nureg = nureg_6909_ss_life(curve_strain(kCurve, sa));
    EXPECT_LE(std::abs(std::log(n / nureg)), fits[0].fit.max_abs_log_error + 1e-12) << sa;
  }
  EXPECT_LT(fits[0].fit.max_abs_log_error, 0.2);
  // NUREG Rev. 0 at 0.18 % is 004's S–N life, 171,517 cycles.
  EXPECT_NEAR(nureg_6909_ss_life(0.0018), 171517.0, 0.5);
}

TEST(B5, JumpingBlocksGivesTheLifeOfSolvingEveryBlock) {
  // Symmetric ±0.35 % (a short life), conventional: the jump to the cycle of the next break
  // against solving every cycle.
  const auto strip = coarse_strip();
  const auto k = calibrate_b5_kinetics(kCurve, 0.0, 1.2);
  ASSERT_TRUE(k.ok());
  B5Options o;
  o.kappa = calibrate_b5_kappa(strip, kCurve, 0.0018);
  const StrainLoading loading = symmetric_loading(0.0035);
  const B5Result jumped = run_b5_loading(strip, kCurve, loading, *k, o);
  o.jump = false;
  const B5Result solved = run_b5_loading(strip, kCurve, loading, *k, o);
  RecordProperty("life", std::to_string(solved.life_cycles));
  ASSERT_GT(solved.life_cycles, 0) << solved.reason;
  EXPECT_EQ(jumped.life_cycles, solved.life_cycles);
  EXPECT_EQ(jumped.broken_bonds, solved.broken_bonds);
  EXPECT_LT(jumped.turning_points, solved.turning_points);
}

TEST(B5, PulIsFarShorterThanSymmetricAndTheModifiedModelLengthensIt) {
  // 004's orderings on the coarse strip: PUL conventional below half of the modified PUL life
  // (004: 3,185 against 74,675), the modified model (measured-area mode, 0.45·A270) longer.
  const auto strip = coarse_strip();
  const auto conventional = calibrate_b5_kinetics(kCurve, 0.0, 1.2);
  auto modified = calibrate_b5_kinetics(kCurve, 1.85e-28, 1.2);
  ASSERT_TRUE(conventional.ok() && modified.ok());
  modified->extension.loop_area = 0.45 * loop_area_at_stress(kCurve, 270e6);
  B5Options o;
  o.kappa = calibrate_b5_kappa(strip, kCurve, 0.0018);
  const B5Result c = run_b5_loading(strip, kCurve, pul_loading(), *conventional, o);
  const B5Result m = run_b5_loading(strip, kCurve, pul_loading(), *modified, o);
  ASSERT_GT(c.life_cycles, 0) << c.reason;
  ASSERT_GT(m.life_cycles, 0) << m.reason;
  EXPECT_LT(2 * c.life_cycles, m.life_cycles);
}

}  // namespace
}  // namespace peritwin
