// The Masing bond of 004 (issue 35): the skeleton curve against its printed formula and quadrature,
// Masing loops against their closed form and quadrature of the branch formula, memory (big–small–
// big, mean-strain cycles of 004's PUL/POL blocks, overflow), tangents by finite differences.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "solver/model/bond_plasticity.h"

namespace peritwin {
namespace {

using model::MasingState;
using model::PowerLawCurve;

const PowerLawCurve kCurve{};  // 004's 316L defaults

/// 004's printed power law, written out here by hand: σ = −0.242·ε^−0.891 + 295 MPa.
double printed_power_law(double strain) {
  return (-0.242 * std::pow(strain, -0.891) + 295.0) * 1e6;
}

/// Composite Simpson on [x0, x1] with n (even) intervals.
double simpson(const std::function<double(double)>& f, double x0, double x1, int n) {
  const double h = (x1 - x0) / n;
  double sum = f(x0) + f(x1);
  for (int i = 1; i < n; ++i) sum += (i % 2 == 1 ? 4.0 : 2.0) * f(x0 + i * h);
  return sum * h / 3.0;
}

/// ∫ f from x0 to x1 (either order), Simpson with 1e5 intervals on each piece between the kinks.
double integrate(const std::function<double(double)>& f, double x0, double x1,
                 std::vector<double> kinks) {
  const double lo = std::fmin(x0, x1);
  const double hi = std::fmax(x0, x1);
  std::vector<double> cuts{lo};
  std::sort(kinks.begin(), kinks.end());
  for (double k : kinks) {
    if (k > lo && k < hi) cuts.push_back(k);
  }
  cuts.push_back(hi);
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) sum += simpson(f, cuts[i], cuts[i + 1], 100000);
  return x1 >= x0 ? sum : -sum;
}

/// The Masing branch from (ε_r, σ_r), written here from its definition (bond_plasticity.h).
double branch(double er, double sr, double strain) {
  return sr + 2.0 * kCurve.stress(0.5 * (strain - er));
}

/// ∫σ dε along the branch from (ε_r, σ_r) between two strains, by quadrature; the branch's kinks
/// are where |ε − ε_r|/2 = ε_y.
double branch_work_quadrature(double er, double sr, double from, double to) {
  const double ey = kCurve.yield_strain();
  return integrate([&](double e) { return branch(er, sr, e); }, from, to,
                   {er - 2.0 * ey, er + 2.0 * ey});
}

::testing::AssertionResult SameBits(const MasingState& x, const MasingState& y) {
  const auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  bool same = bits(x.strain) == bits(y.strain) && bits(x.stress) == bits(y.stress) &&
              x.depth == y.depth && x.dropped_reversals == y.dropped_reversals;
  for (int i = 0; i < model::kMasingMemory; ++i) {
    same = same && bits(x.reversal_strain[i]) == bits(y.reversal_strain[i]) &&
           bits(x.reversal_stress[i]) == bits(y.reversal_stress[i]);
  }
  if (same) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "states differ: (" << x.strain << ", " << x.stress << ", depth " << int(x.depth)
         << ") vs (" << y.strain << ", " << y.stress << ", depth " << int(y.depth) << ")";
}

/// Commits the turning points in order; returns the work of each half cycle.
std::vector<double> run(MasingState& s, const std::vector<double>& turning_points) {
  std::vector<double> works;
  for (double e : turning_points) {
    works.push_back(model::masing_evaluate(kCurve, s, e).work);
    s = model::masing_commit(kCurve, s, e);
  }
  return works;
}

// ------------------------------------------------------------------ 1. the skeleton curve

TEST(PowerLawCurve, DefaultsValidAndJoinSolved) {
  ASSERT_TRUE(model::validate(kCurve)) << core::message_of(model::validate(kCurve));
  const double ey = kCurve.yield_strain();
  // 004-design.md (a) check 2: the join at 8.35e-4 (161 MPa).
  EXPECT_NEAR(ey, 8.35e-4, 0.005e-4);
  EXPECT_NEAR(kCurve.youngs_modulus * ey, 161e6, 0.5e6);
  // The root: E·ε_y equals the printed power law there (1e-12 relative).
  EXPECT_NEAR(kCurve.youngs_modulus * ey, printed_power_law(ey), 1e-12 * printed_power_law(ey));
  // The larger root: the power law is below E·ε beyond it and steeper than E at the printed 6.6e-4.
  EXPECT_LT(printed_power_law(1.1 * ey), kCurve.youngs_modulus * 1.1 * ey);
  EXPECT_GT(printed_power_law(6.6e-4), kCurve.youngs_modulus * 6.6e-4);
  // Continuity: the stress on either side of the join (adjacent doubles), 1e-12 relative.
  const double below = kCurve.stress(std::nextafter(ey, 0.0));
  const double above = kCurve.stress(std::nextafter(ey, 1.0));
  EXPECT_NEAR(below, above, 1e-12 * above);
}

TEST(PowerLawCurve, PrintedValuesAt018And060Percent) {
  // 004's curve by hand: −0.242·0.0018^−0.891 + 295 = 227.5 MPa; at 0.006: 271.9 MPa
  // (004-design.md).
  for (const auto& [strain, rounded] : {std::pair{0.0018, 227.5e6}, std::pair{0.006, 271.9e6}}) {
    EXPECT_NEAR(kCurve.stress(strain), printed_power_law(strain), 1e-14 * rounded);
    EXPECT_NEAR(kCurve.stress(strain), rounded, 0.05e6);
    EXPECT_EQ(kCurve.stress(-strain), -kCurve.stress(strain));  // odd, bit for bit
  }
  EXPECT_EQ(kCurve.stress(4e-4), kCurve.youngs_modulus * 4e-4);  // elastic below ε_y
  EXPECT_EQ(kCurve.stress(0.0), 0.0);
}

TEST(PowerLawCurve, TangentPositiveAtMostEAndNonIncreasing) {
  // On a log sweep 1e-7 … 0.5 and densely around the join: 0 < g' ≤ E, g' non-increasing (concave),
  // and g' = a·b·ε^(b−1) beyond the join (by hand: 0.242e6·0.891·ε^−1.891).
  const double ey = kCurve.yield_strain();
  std::vector<double> strains;
  for (int i = 0; i <= 6000; ++i) strains.push_back(1e-7 * std::pow(10.0, i * 6.7 / 6000.0));
  for (int i = -500; i <= 500; ++i) strains.push_back(ey * (1.0 + i * 1e-5));
  std::sort(strains.begin(), strains.end());
  double previous = kCurve.youngs_modulus;
  for (double e : strains) {
    const double t = kCurve.tangent(e);
    ASSERT_GT(t, 0.0) << e;
    ASSERT_LE(t, kCurve.youngs_modulus) << e;
    ASSERT_LE(t, previous) << e;
    ASSERT_EQ(kCurve.tangent(-e), t);
    previous = t;
  }
  EXPECT_NEAR(kCurve.tangent(0.006), 0.242e6 * 0.891 * std::pow(0.006, -1.891),
              1e-13 * kCurve.tangent(0.006));
  EXPECT_EQ(kCurve.tangent(0.0), kCurve.youngs_modulus);
}

TEST(PowerLawCurve, EnergyMatchesSimpsonQuadrature) {
  // G(ε) = ∫_0^ε g against Simpson (1e5 intervals on each side of the join): 1e-9 relative.
  const double ey = kCurve.yield_strain();
  for (double e : {5e-4, 0.0018, 0.006, 0.05}) {
    const double quad = integrate([](double x) { return kCurve.stress(x); }, 0.0, e, {ey});
    EXPECT_NEAR(kCurve.energy(e), quad, 1e-9 * quad) << e;
    EXPECT_EQ(kCurve.energy(-e), kCurve.energy(e));
  }
  EXPECT_EQ(kCurve.energy(5e-4), 0.5 * kCurve.youngs_modulus * 5e-4 * 5e-4);
}

TEST(PowerLawCurve, ValidateNamesTheField) {
  const auto field_of = [](PowerLawCurve c) {
    const core::Status s = model::validate(c);
    return s ? std::string("ok") : s.error().field;
  };
  PowerLawCurve c;
  c.youngs_modulus = 0.0;
  EXPECT_EQ(field_of(c), "youngs_modulus");
  c = {};
  c.sigma_inf = -1.0;
  EXPECT_EQ(field_of(c), "sigma_inf");
  c = {};
  c.a = 0.242e6;  // decreasing power law
  EXPECT_EQ(field_of(c), "a");
  c = {};
  c.b = -1.0;
  EXPECT_EQ(field_of(c), "b");
  c = {};
  c.b = std::nan("");
  EXPECT_EQ(field_of(c), "b");
  // No join: with σ∞ = 150 MPa, h(ε_m) = E·ε_m − σ∞ − a·ε_m^b at ε_m = (E/(a·b))^(1/(b−1))
  // = 7.13e-4 is 137.6 − 150 + 153.9 > 0 MPa (by hand): the power law stays below E·ε.
  c = {};
  c.sigma_inf = 150e6;
  EXPECT_EQ(field_of(c), "a");
  // 004's printed curve only just meets the elastic line: h(ε_m) ≈ −3.5 MPa, so σ∞ = 291 MPa
  // (h(ε_m) ≈ +0.5 MPa) has no join and σ∞ = 292 MPa (−0.5 MPa) has one.
  c.sigma_inf = 291e6;
  EXPECT_EQ(field_of(c), "a");
  c.sigma_inf = 292e6;
  EXPECT_EQ(field_of(c), "ok");
}

// ------------------------------------------------------------------ 2.–3. symmetric cycles

TEST(MasingLoop, SymmetricCyclesAreaTurningStressesAndPeriodicity) {
  for (double a : {0.0018, 0.006}) {
    SCOPED_TRACE(a);
    MasingState s;
    std::vector<MasingState> after_cycle;
    std::vector<double> works;
    for (int cycle = 1; cycle <= 3; ++cycle) {
      const std::vector<double> w = run(s, {a, -a});
      works.insert(works.end(), w.begin(), w.end());
      after_cycle.push_back(s);
    }
    // The turning stresses are ±g(a), bit for bit (the path is back on the skeleton).
    EXPECT_EQ(s.stress, -kCurve.stress(a));
    EXPECT_EQ(model::masing_commit(kCurve, s, a).stress, kCurve.stress(a));
    EXPECT_EQ(s.depth, 0);
    // Stable at once (Masing under strain control): cycles 1, 2, 3 end in the same bits.
    EXPECT_TRUE(SameBits(after_cycle[0], after_cycle[1]));
    EXPECT_TRUE(SameBits(after_cycle[1], after_cycle[2]));
    // ∮σ dε of cycle 2 (its two half cycles −a → a → −a) against 8·G(a) − 4a·g(a) by hand.
    const double area = works[2] + works[3];
    const double closed_form = 8.0 * kCurve.energy(a) - 4.0 * a * kCurve.stress(a);
    EXPECT_NEAR(area, closed_form, 1e-10 * closed_form);
    EXPECT_NEAR(model::masing_symmetric_loop_area(kCurve, a), closed_form, 1e-15 * closed_form);
    EXPECT_EQ(works[2] + works[3], works[4] + works[5]);  // periodic work
    // Virgin loading does ∫_0^a g.
    EXPECT_NEAR(works[0], kCurve.energy(a), 1e-15 * kCurve.energy(a));
  }
  // 004-design.md (a) check 3 (one-bond Python): A(±0.18 %) = 0.461, A(±0.6 %) = 4.23 MJ/m³.
  EXPECT_NEAR(model::masing_symmetric_loop_area(kCurve, 0.0018), 0.461e6, 0.0005e6);
  EXPECT_NEAR(model::masing_symmetric_loop_area(kCurve, 0.006), 4.23e6, 0.005e6);
}

TEST(MasingLoop, HalfCycleWorkMatchesQuadratureOfTheBranch) {
  // Each half cycle's closed-form work against Simpson on the branch formula written in this test,
  // 1e-8 relative; and the stress along the way against the same formula.
  for (double a : {0.0018, 0.006}) {
    SCOPED_TRACE(a);
    MasingState s;
    const double virgin = model::masing_evaluate(kCurve, s, a).work;
    EXPECT_NEAR(
        virgin,
        integrate([](double e) { return kCurve.stress(e); }, 0.0, a, {kCurve.yield_strain()}),
        1e-8 * virgin);
    s = model::masing_commit(kCurve, s, a);
    const double down = model::masing_evaluate(kCurve, s, -a).work;
    EXPECT_NEAR(down, branch_work_quadrature(a, kCurve.stress(a), a, -a), 1e-8 * std::fabs(down));
    for (double e : {0.8 * a, 0.1 * a, -0.7 * a}) {
      EXPECT_NEAR(model::masing_evaluate(kCurve, s, e).stress, branch(a, kCurve.stress(a), e),
                  1e-14 * kCurve.sigma_inf);
    }
    s = model::masing_commit(kCurve, s, -a);
    const double up = model::masing_evaluate(kCurve, s, a).work;
    EXPECT_NEAR(up, branch_work_quadrature(-a, -kCurve.stress(a), -a, a), 1e-8 * std::fabs(up));
  }
}

TEST(MasingLoop, WorkThroughAClosureMatchesQuadrature) {
  // +0.6 → −0.6 → +0.6 → +0.2 → +0.4, then one ramp to −0.3 %: the branch from R3 = (0.4 %) closes
  // at R2 = (0.2 %) and the path continues on the branch from R1 = (0.6 %, g(0.6 %)) (by hand).
  MasingState s;
  run(s, {0.006, -0.006, 0.006, 0.002, 0.004});
  ASSERT_EQ(s.depth, 2);
  const double s1 = kCurve.stress(0.006);
  const double s2 = branch(0.006, s1, 0.002);
  const double s3 = branch(0.002, s2, 0.004);
  EXPECT_EQ(s.stress, s3);
  const double expected = branch_work_quadrature(0.004, s3, 0.004, 0.002) +
                          branch_work_quadrature(0.006, s1, 0.002, -0.003);
  const model::MasingResponse r = model::masing_evaluate(kCurve, s, -0.003);
  EXPECT_NEAR(r.work, expected, 1e-8 * std::fabs(expected));
  EXPECT_EQ(r.stress, branch(0.006, s1, -0.003));
  EXPECT_EQ(model::masing_commit(kCurve, s, -0.003).depth, 1);
}

// ------------------------------------------------------------------ 4. big–small–big

TEST(MasingMemory, BigSmallBigReturnsToTheBigBranchBitForBit) {
  MasingState big;
  const std::vector<double> w_big = run(big, {0.006, -0.006, 0.006, 0.002, -0.003});
  // The same with a small cycle 0.2 → 0.4 → 0.2 % inside, closing exactly on its start ...
  MasingState small_exact;
  const std::vector<double> w_small =
      run(small_exact, {0.006, -0.006, 0.006, 0.002, 0.004, 0.002, -0.003});
  // ... and closing inside the ramp 0.4 → −0.3 %.
  MasingState small_through;
  run(small_through, {0.006, -0.006, 0.006, 0.002, 0.004, -0.003});
  EXPECT_TRUE(SameBits(big, small_exact));
  EXPECT_TRUE(SameBits(big, small_through));
  EXPECT_EQ(big.depth, 1);
  // Further loading sees nothing of the small loop either (the big loop closes on the skeleton).
  for (double e : {-0.005, -0.006, -0.007}) {
    EXPECT_EQ(model::masing_evaluate(kCurve, small_exact, e).stress,
              model::masing_evaluate(kCurve, big, e).stress);
  }
  EXPECT_EQ(model::masing_evaluate(kCurve, big, -0.007).stress, kCurve.stress(-0.007));
  // The work differs by the small loop's area: a symmetric loop of amplitude 0.1 % (Masing).
  double sum_big = 0.0;
  double sum_small = 0.0;
  for (double w : w_big) sum_big += w;
  for (double w : w_small) sum_small += w;
  const double small_area = model::masing_symmetric_loop_area(kCurve, 0.001);
  EXPECT_NEAR(sum_small - sum_big, small_area, 1e-9 * small_area);
}

TEST(MasingMemory, SmallLoopsRestoreTheirStartBitForBit) {
  // 50 small loops lo → hi → lo hung on the branch from (0.6 %, g(0.6 %)): the state after each is
  // the state before it, bit for bit. Without the snap, the branch formula at the closure point
  // (σ_hi + 2·g((lo − hi)/2)) misses σ_lo by an ulp in some of them (5 of these 50, measured), and
  // the periodic cycles of the engine would drift.
  for (int i = 1; i <= 50; ++i) {
    // lo from 0.42 to 0.57 %, where σ_lo > 0 and the up-branch adds a stress of the same sign
    // (the sum can drop low bits); hi between lo and 0.6 %, inside the big loop.
    const double lo = 0.0042 + 0.00003 * i;
    const double hi = lo + 0.5 * (0.006 - lo) * (0.3 + 0.01 * i);
    MasingState s;
    run(s, {0.006, lo});
    MasingState looped = s;
    run(looped, {hi, lo});
    EXPECT_TRUE(SameBits(looped, s)) << "loop " << i;
    run(looped, {hi, lo, hi, lo});
    EXPECT_TRUE(SameBits(looped, s)) << "loop " << i;
  }
}

TEST(MasingSkeleton, PrebuiltSkeletonGivesTheSameBits) {
  // The MasingSkeleton overloads and the PowerLawCurve ones run the same arithmetic.
  const model::MasingSkeleton sk(kCurve);
  EXPECT_EQ(sk.yield_strain(), kCurve.yield_strain());
  MasingState a;
  MasingState b;
  for (double e : {0.006, -0.006, 0.0024, 0.006, 0.001, 0.0037, -0.0071}) {
    const model::MasingResponse ra = model::masing_evaluate(kCurve, a, e);
    const model::MasingResponse rb = model::masing_evaluate(sk, b, e);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(ra.stress), std::bit_cast<std::uint64_t>(rb.stress));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(ra.tangent), std::bit_cast<std::uint64_t>(rb.tangent));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(ra.work), std::bit_cast<std::uint64_t>(rb.work));
    a = model::masing_commit(kCurve, a, e);
    b = model::masing_commit(sk, b, e);
    EXPECT_TRUE(SameBits(a, b));
    EXPECT_EQ(sk.stress(e), kCurve.stress(e));
    EXPECT_EQ(sk.energy(e), kCurve.energy(e));
  }
}

// ------------------------------------------------------------------ 5. tangent

TEST(MasingTangent, MatchesCentralDifferencesOfTheStress) {
  // Central differences of masing_evaluate's stress, h = 1e-8, away from the kinks: 1e-6 relative.
  struct Case {
    std::vector<double> history;
    std::vector<double> trials;
  };
  const std::vector<Case> cases{
      {{}, {3e-4, 0.001, 0.0018, 0.006, -0.002}},  // skeleton
      {{0.006}, {0.005, 0.003, -0.001, -0.0045}},  // branch from R1
      {{0.006, -0.006, 0.006, 0.002},
       {0.0025, 0.0032, 0.0038, 0.005, 0.0065,
        0.008}},  // nested, then through R1 onto the skeleton
      {{-0.006, 0.006, 0.0024}, {0.003, 0.0045, 0.0058}},  // 004 PUL small cycle
  };
  for (const Case& c : cases) {
    MasingState s;
    run(s, c.history);
    for (double e : c.trials) {
      const double h = 1e-8;
      const double fd = (model::masing_evaluate(kCurve, s, e + h).stress -
                         model::masing_evaluate(kCurve, s, e - h).stress) /
                        (2.0 * h);
      const double t = model::masing_evaluate(kCurve, s, e).tangent;
      EXPECT_NEAR(t, fd, 1e-6 * t) << "strain " << e << " after " << c.history.size() << " turns";
    }
  }
}

TEST(MasingTangent, TrialEqualToCommittedContinuesTheBranch) {
  MasingState s;
  model::MasingResponse r = model::masing_evaluate(kCurve, s, 0.0);
  EXPECT_EQ(r.stress, 0.0);
  EXPECT_EQ(r.work, 0.0);
  EXPECT_EQ(r.tangent, kCurve.youngs_modulus);
  s = model::masing_commit(kCurve, s, 0.006);
  r = model::masing_evaluate(kCurve, s, 0.006);
  EXPECT_EQ(r.stress, kCurve.stress(0.006));
  EXPECT_EQ(r.tangent, kCurve.tangent(0.006));
  EXPECT_EQ(r.work, 0.0);
  EXPECT_TRUE(SameBits(model::masing_commit(kCurve, s, 0.006), s));
  s = model::masing_commit(kCurve, s, 0.001);  // on the branch from (0.6 %, g(0.6 %))
  r = model::masing_evaluate(kCurve, s, 0.001);
  EXPECT_EQ(r.tangent, kCurve.tangent(0.5 * (0.001 - 0.006)));
}

// ------------------------------------------------------------------ 6. mean-strain cycles

TEST(MasingMemory, PulAndPolSmallCyclesByHand) {
  // Masing: the small loop's turning stresses are the big branch's values there, by hand:
  // PUL (004: the big cycle starts with compression): σ(+0.6 %) = g(0.6 %) = 271.9 MPa,
  // σ(+0.24 %) = g(0.6 %) − 2·g(0.18 %) = −183.1 MPa, R = −0.673 (004 quotes R = −0.7).
  // POL: the mirror image, +183.1 / −271.9 MPa, R = −1.485 (004: −1.5).
  const double g06 = printed_power_law(0.006);
  const double g018 = printed_power_law(0.0018);
  const double area = 8.0 * kCurve.energy(0.0018) - 4.0 * 0.0018 * kCurve.stress(0.0018);
  for (const int sign : {+1, -1}) {
    SCOPED_TRACE(sign > 0 ? "PUL" : "POL");
    const double up = sign * 0.006;
    const double down = sign * 0.0024;
    MasingState s;
    run(s, {-up, up});
    std::vector<MasingState> after;
    for (int cycle = 0; cycle < 3; ++cycle) {
      const std::vector<double> w = run(s, {down, up});
      after.push_back(s);
      EXPECT_NEAR(w[0] + w[1], area, 1e-10 * area);  // the ±0.18 % loop's area
    }
    EXPECT_EQ(s.depth, 0);
    EXPECT_TRUE(SameBits(after[0], after[2]));
    const double s_up = s.stress;
    const double s_down = model::masing_commit(kCurve, s, down).stress;
    EXPECT_NEAR(s_up, sign * g06, 1e-12 * g06);
    EXPECT_NEAR(s_down, sign * (g06 - 2.0 * g018), 1e-12 * g06);
    EXPECT_NEAR(sign * s_down, -183.1e6, 0.1e6);
    const double r_ratio = sign > 0 ? s_down / s_up : s_up / s_down;  // σ_min/σ_max
    EXPECT_NEAR(r_ratio, sign > 0 ? -0.673 : -1.485, 0.002);
  }
}

TEST(MasingMemory, SmallCyclesAfterAnUpDownBigCycle) {
  // The brief's order: +0.6 → −0.6, then +0.24/+0.60. The first +0.24 % lies on the ascending
  // branch from (−0.6 %, −g(0.6 %)): σ = −g(0.6 %) + 2·g(0.42 %); +0.6 % closes that branch on the
  // skeleton (the mirror of −0.6 %), and from there the loop is PUL's stable one.
  MasingState s;
  run(s, {0.006, -0.006});
  s = model::masing_commit(kCurve, s, 0.0024);
  const double g06 = printed_power_law(0.006);
  EXPECT_NEAR(s.stress, -g06 + 2.0 * printed_power_law(0.0042), 1e-12 * g06);
  s = model::masing_commit(kCurve, s, 0.006);
  EXPECT_EQ(s.depth, 0);
  EXPECT_EQ(s.stress, kCurve.stress(0.006));
  s = model::masing_commit(kCurve, s, 0.0024);
  EXPECT_NEAR(s.stress, g06 - 2.0 * printed_power_law(0.0018), 1e-12 * g06);
}

// ------------------------------------------------------------------ snapping and overflow

TEST(MasingMemory, ClosureSnapsWithinTheTolerance) {
  // A turning point 1e-14 relative short of the closure point closes the loop (snapped to the
  // stored bits); 1e-9 short does not (the path stays on the branch, one reversal open).
  MasingState start;
  run(start, {0.006, -0.006});
  const double near_miss = 0.006 * (1.0 - 1e-14);
  const MasingState snapped = model::masing_commit(kCurve, start, near_miss);
  EXPECT_EQ(snapped.depth, 0);
  EXPECT_EQ(snapped.strain, 0.006);
  EXPECT_EQ(snapped.stress, kCurve.stress(0.006));
  EXPECT_EQ(model::masing_evaluate(kCurve, start, near_miss).stress, kCurve.stress(0.006));
  // Ending exactly on an inner closure point: the stored stress, and the tangent of the branch the
  // path arrived on (from R3 = 0.4 %), not of the older one it continues on.
  MasingState nested;
  run(nested, {0.006, 0.002, 0.004});
  const double s2 = nested.reversal_stress[1];
  const model::MasingResponse at_r2 = model::masing_evaluate(kCurve, nested, 0.002);
  EXPECT_EQ(at_r2.stress, s2);
  EXPECT_EQ(at_r2.tangent, kCurve.tangent(0.5 * (0.002 - 0.004)));
  EXPECT_NE(at_r2.tangent, kCurve.tangent(0.5 * (0.002 - 0.006)));
  // The branch from R1 meets the skeleton at the mirror point with the skeleton's own slope.
  EXPECT_EQ(model::masing_evaluate(kCurve, start, 0.006).tangent, kCurve.tangent(0.006));
  const MasingState open = model::masing_commit(kCurve, start, 0.006 * (1.0 - 1e-9));
  EXPECT_EQ(open.depth, 1);
  EXPECT_LT(open.stress, kCurve.stress(0.006));
}

TEST(MasingMemory, OverflowDropsTheOldestInnerPairAndCounts) {
  // M + 2 reversals of decreasing amplitude (M = kMasingMemory): pushes 1–M fill the stack, push
  // M + 1 drops R2 and R3 (counted 2) and keeps R1 = (0.6 %, g(0.6 %)); push M + 2 fills it again.
  constexpr int m = model::kMasingMemory;
  const double step = 0.005 / (m + 2);
  std::vector<double> turns;
  for (int k = 0; k < m + 3; ++k) turns.push_back((k % 2 == 0 ? 1.0 : -1.0) * (0.006 - step * k));
  MasingState s;
  run(s, turns);
  EXPECT_EQ(s.dropped_reversals, 2u);
  EXPECT_EQ(s.depth, m);
  EXPECT_EQ(s.reversal_strain[0], 0.006);
  EXPECT_EQ(s.reversal_stress[0], kCurve.stress(0.006));
  EXPECT_EQ(s.reversal_strain[1], turns[3]);  // R4 moved down to R2
  EXPECT_EQ(s.reversal_strain[m - 1], turns[m + 1]);
  // The remembered loops still close exactly: up to just past R_{M−1} = turns[M] closes the loop
  // R_{M−1} → R_M and continues on R_{M−2}'s branch, by hand from the stored R_{M−2}.
  const double beyond = turns[m] + 0.2 * step;
  const MasingState inner = model::masing_commit(kCurve, s, beyond);
  EXPECT_EQ(inner.depth, m - 2);
  EXPECT_EQ(inner.stress, branch(s.reversal_strain[m - 3], s.reversal_stress[m - 3], beyond));
  EXPECT_EQ(inner.dropped_reversals, 2u);
  // Beyond the outer loop the path is back on the skeleton exactly (R1 was kept).
  const MasingState out = model::masing_commit(kCurve, s, 0.007);
  EXPECT_EQ(out.depth, 0);
  EXPECT_EQ(out.stress, kCurve.stress(0.007));
  EXPECT_EQ(out.dropped_reversals, 2u);
  for (int i = 0; i < m; ++i) EXPECT_EQ(out.reversal_strain[i], 0.0);
}

}  // namespace
}  // namespace peritwin
