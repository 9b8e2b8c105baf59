// The DCBs of paper 003 (B6 Sec. 6.5, B7 Sec. 6.6; validation/b6_dcb.h, b7_dcb_paris.h): the
// energy release rate from the model's compliance against 003 Eq. (56), and short versions of B6.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "validation/b6_dcb.h"
#include "validation/b7_dcb_paris.h"

namespace peritwin::validation {
namespace {

double compliance_error(const DcbSpec& spec, double moment) {
  const double g = dcb_compliance_energy_release_rate(spec, moment);
  const double eq56 = dcb_energy_release_rate(spec, moment);
  std::printf("[ measured ] delta/h %.3f: G compliance %.5g J/m2, Eq. (56) %.5g (%+.2f %%)\n",
              spec.horizon / (0.5 * spec.height), g, eq56, 100 * (g / eq56 - 1));
  return g / eq56 - 1;
}

TEST(DcbCompliance, EnergyReleaseRateMatchesEq56BeforeAnyBreak) {
  // 003 Eq. (56), G = M²/(B E I) for a DCB under opposing end moments, against the intact PD
  // model's compliance: G = M²/(2B) dC/da, C = θ/M from two pre-crack lengths (a ± 2Δl). The PD
  // arms are softer in bending than Euler-Bernoulli by about 0.4·δ/h (measured: +10 % at B6's
  // δ = 0.375 mm, h = 1.45 mm, m = 3; +25 % for B7's arms at 6 rows and m = 3): within 5 % at
  // δ/h = 0.13 (B6 at 003's finest δ, 0.188 mm, m = 2), and the error must fall about as δ when δ
  // is halved (ratio 1.6-3), for B6 (plane stress) and B7 (plane strain, 6 and 12 rows per arm).
  const DcbSpec fine = b6_run(3, 2.0, 1000, 1.88e-4).spec;
  EXPECT_LT(std::abs(compliance_error(fine, 0.048)), 0.05);
  const double b6_coarse = compliance_error(b6_run(3, 3.0, 1000).spec, 0.048);
  const double b6_fine = compliance_error(b6_run(3, 3.0, 1000, 1.875e-4).spec, 0.048);
  EXPECT_GT(b6_coarse / b6_fine, 1.6);
  EXPECT_LT(b6_coarse / b6_fine, 3.0);
  const double b7_coarse = compliance_error(b7_spec(3.0, 6, 0.02), 10.0);
  const double b7_fine = compliance_error(b7_spec(3.0, 12, 0.02), 10.0);
  EXPECT_GT(b7_coarse / b7_fine, 1.6);
  EXPECT_LT(b7_coarse / b7_fine, 3.0);
  EXPECT_GT(b7_fine, 0.0);  // softer, never stiffer
}

TEST(B6Short, ThirdLawSlopeOnTheCoarseGridAsTheFullRunMeasured) {
  // B6 at m = 2 (Δl = 0.18 mm, the coarsest grid of 003 Fig. 19), third law: the slope of crack
  // length against cycles at ΔN = 10000 and 50000 as `peritwin-validate --case B6` measured them
  // (docs/validation.md, B6), within 1 % (the runs are deterministic; the tolerance is for other
  // BLAS builds). Issue 36's goal is ≤ 10 % over ΔN on the converged grids (m = 3, 4; the full
  // run); on this coarse grid the two differ by 10.5 %, asserted below 12 %.
  const DcbResult a = run_dcb(b6_run(3, 2.0, 10000));
  const DcbResult b = run_dcb(b6_run(3, 2.0, 50000));
  std::printf("[ measured ] slopes %.6g %.6g m/cycle (%.1f s, %.1f s)\n", a.slope, b.slope,
              a.wall_s, b.wall_s);
  EXPECT_NEAR(a.slope / 1.70416e-09, 1.0, 0.01);
  EXPECT_NEAR(b.slope / 1.54188e-09, 1.0, 0.01);
  EXPECT_LT(std::max(a.slope, b.slope) / std::min(a.slope, b.slope) - 1.0, 0.12);
  EXPECT_FALSE(a.failed || b.failed);
}

TEST(B6Short, SecondLawArrestsOnTheCoarseGrid) {
  // The second law (003 Eq. 23) shortens the failure stretch only of bonds beyond s0: it has a
  // threshold the other two laws lack. On B6's coarse grid (m = 2) the crack grows 0.254 mm from
  // the static ramp and early increments and then stops (the full run: 0.25441 mm after 10⁸
  // cycles at ΔN = 500, 1000, 10000), where the third law grows 1 mm in 0.58·10⁶ cycles
  // (B6Short above). Asserted: the growth at 4·10⁶ cycles is the full run's within 1 %, and it did
  // not change over the last 2·10⁶ cycles.
  DcbRun run = b6_run(2, 2.0, 10000);
  run.max_cycles = 4e6;
  const DcbResult r = run_dcb(run);
  const double growth = r.crack.back() - run.spec.crack;
  std::printf("[ measured ] second law, m = 2: growth %.6g m after %.0f cycles\n", growth,
              r.cycles.back());
  EXPECT_NEAR(growth / 0.00025441, 1.0, 0.01);
  ASSERT_EQ(r.cycles.size(), 401u);
  EXPECT_EQ(r.crack[200], r.crack.back());
  EXPECT_FALSE(std::isfinite(r.slope));
}

TEST(B6Short, FirstLawIsMoreSensitiveToTheIncrementThanTheThird) {
  // The first law (003 Eq. 19-22) on the same coarse grid: the slopes at ΔN = 10000 and 50000 as
  // the full run measured them (0.70368 and 0.905402 nm/cycle), within 1 %, and they part by
  // more than 20 % (measured 29 %) where the third law's part by 10.5 % (B6Short above): the
  // first law's implicit μ-rule (Eq. 21) with e^{λD} over an increment that breaks bonds.
  const DcbResult a = run_dcb(b6_run(1, 2.0, 10000));
  const DcbResult b = run_dcb(b6_run(1, 2.0, 50000));
  std::printf("[ measured ] first law slopes %.6g %.6g m/cycle (%.1f s, %.1f s)\n", a.slope,
              b.slope, a.wall_s, b.wall_s);
  EXPECT_NEAR(a.slope / 7.0368e-10, 1.0, 0.01);
  EXPECT_NEAR(b.slope / 9.05402e-10, 1.0, 0.01);
  EXPECT_GT(b.slope / a.slope - 1.0, 0.20);
}

}  // namespace
}  // namespace peritwin::validation
