// Issue 34: the compressive part of reversed cycles. Newman's opening function (laws/
// crack_closure.h), crack faces in contact (statics/crack_contact.h) and the engine's rules
// (FatigueSettings::compression).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "solver/fatigue/fatigue_engine.h"
#include "solver/fatigue/laws/crack_closure.h"
#include "solver/statics/crack_contact.h"
#include "tests/support/plates.h"

namespace peritwin {
namespace {

using testing::make_notched_plate;

// ------------------------------------------------------------------ Newman's opening function

TEST(NewmanClosure, CoefficientsOfTheOpeningFunctionAsNewman1984WritesThem) {
  // Newman (1984), plane stress (α = 1) at S_max/σ0 = 0.3, the coefficients by hand:
  // A0 = (0.825 − 0.34 + 0.05)·cos(0.15π) = 0.535·0.891007 = 0.476689, A1 = 0.344·0.3 = 0.1032.
  const fatigue::NewmanClosure c{1.0, 0.3};
  const double a0 = 0.535 * std::cos(0.15 * std::numbers::pi);
  EXPECT_NEAR(a0, 0.476689, 1e-6);
  EXPECT_NEAR(fatigue::newman_opening_ratio(0.0, c), a0, 1e-15);
  EXPECT_NEAR(fatigue::newman_opening_ratio(-1.0, c), a0 - 0.1032, 1e-15);
  EXPECT_NEAR(fatigue::newman_opening_ratio(-2.0, c), a0 - 0.2064, 1e-15);
  EXPECT_NEAR(fatigue::newman_opening_ratio(-5.0, c), a0 - 0.2064, 1e-15);  // held below −2
  // Plane strain (α = 3): A0 = (0.825 − 1.02 + 0.45)·cos(0.15π)^(1/3), A1 = (0.415 − 0.213)·0.3.
  const fatigue::NewmanClosure strain{3.0, 0.3};
  const double a0s = 0.255 * std::cbrt(std::cos(0.15 * std::numbers::pi));
  EXPECT_NEAR(fatigue::newman_opening_ratio(0.0, strain), a0s, 1e-15);
  EXPECT_NEAR(fatigue::newman_opening_ratio(-1.0, strain), a0s - 0.0606, 1e-15);
}

TEST(NewmanClosure, TheCubicMeetsROneWithSlopeOneAndNeverFallsBelowR) {
  // A2, A3 are chosen so that f(1) = 1 and f'(1) = 1 (the crack is open through a cycle that
  // never unloads), and f = max(R, cubic) for R >= 0.
  for (const double alpha : {1.0, 1.5, 2.0, 2.5, 3.0}) {
    for (const double s : {0.1, 0.3, 0.5, 0.8}) {
      const fatigue::NewmanClosure c{alpha, s};
      EXPECT_NEAR(fatigue::newman_opening_ratio(1.0, c), 1.0, 1e-14);
      const double h = 1e-6;
      const double slope =
          (fatigue::newman_opening_ratio(1.0, c) - fatigue::newman_opening_ratio(1.0 - h, c)) / h;
      EXPECT_NEAR(slope, 1.0, 1e-5) << alpha << " " << s;
      // Continuous at R = 0 (both branches give A0).
      EXPECT_NEAR(fatigue::newman_opening_ratio(1e-12, c), fatigue::newman_opening_ratio(-1e-12, c),
                  1e-11);
      for (double r = -2.0; r < 1.0; r += 0.05) {
        EXPECT_GE(fatigue::newman_opening_ratio(r, c), r - 1e-15);
        const double u = fatigue::newman_effective_range_fraction(r, c);
        EXPECT_GT(u, 0.0);
        EXPECT_LE(u, 1.0 + 1e-12);
      }
    }
  }
  EXPECT_FALSE(fatigue::validate(fatigue::NewmanClosure{0.5, 0.3}).ok());
  EXPECT_FALSE(fatigue::validate(fatigue::NewmanClosure{2.0, 1.0}).ok());
  EXPECT_TRUE(fatigue::validate(fatigue::NewmanClosure{}).ok());
}

// ------------------------------------------------------------------ crack faces in contact

/// A plate under load along y with a cut ACROSS the load (along x) through its middle third: in
/// compression the cut's faces press together. `confined`: the side edges held in x (a patch in a
/// die), so that no bond across the cut is stretched by the Poisson expansion.
statics::Specimen cut_plate(model::ModelKind kind, bool confined) {
  statics::Specimen p;
  const double dx = 0.001;
  const int columns = 18, rows = 14;
  const double h = 0.5 * rows * dx;
  p.geometry.thickness = 0.004;
  p.geometry.outline = {mesh::Rectangle{0.0, -h, columns * dx, h}};
  p.geometry.notches = {{"cut", {{6 * dx, 0.0}, {12 * dx, 0.0}}}};
  p.disc = discretize(p.geometry, dx, 3.015 * dx);
  model::ModelOptions o;
  o.kind = kind;
  p.model = model::build_model(p.disc, model::Material{68e9, 0.33, 0.0}, o, 200.0);
  p.supports.push_back(
      {p.disc.nodes_in(mesh::Region::of(mesh::Rectangle{-1, -h, 1, -h + dx})), true, true});
  if (confined) {
    p.supports.push_back(
        {p.disc.nodes_in(mesh::Region::of(mesh::Rectangle{-1, -h, dx, h})), true, false});
    p.supports.push_back(
        {p.disc.nodes_in(mesh::Region::of(mesh::Rectangle{(columns - 1) * dx, -h, 1, h})), true,
         false});
  }
  p.loads.push_back(
      {p.disc.nodes_in(mesh::Region::of(mesh::Rectangle{-1, h - dx, 1, h})), {0, 1}, {}, {}});
  return p;
}

class CrackFaceContactTest : public ::testing::TestWithParam<model::ModelKind> {};

struct Compared {
  double scale = 0.0;    ///< the largest |stretch| of the uncut body
  double worst = 0.0;    ///< the largest |contact − uncut| over all bonds
  double through = 0.0;  ///< the most negative cut-bond stretch without contact
  std::vector<mesh::BondIndex> open;
};

/// The contact stretches at P = −1 against the uncut body's (the same plate, every bond intact).
Compared compare_with_uncut(const statics::Specimen& p) {
  mesh::Discretization whole = p.disc;
  std::fill(whole.bond_precut.begin(), whole.bond_precut.end(), std::uint8_t{0});
  statics::StaticSolver uncut(whole, p.model, p.supports, p.loads);
  EXPECT_TRUE(uncut.solve().ok());
  statics::StaticSolver cracked(p.disc, p.model, p.supports, p.loads);
  EXPECT_TRUE(cracked.solve().ok());
  statics::CrackFaceContact contact(p.disc, p.model, p.supports, p.loads, {});
  const std::vector<std::int64_t> rank(p.disc.bond_precut.size(), -1);
  std::vector<double> s_contact, s_uncut, s_cracked;
  EXPECT_TRUE(contact.compressive_stretch(cracked.intact(), rank, 0.0, s_contact).ok());
  uncut.stretch(-1.0, 0.0, s_uncut);
  cracked.stretch(-1.0, 0.0, s_cracked);
  Compared c;
  for (std::size_t b = 0; b < s_uncut.size(); ++b) {
    c.scale = std::max(c.scale, std::abs(s_uncut[b]));
    c.worst = std::max(c.worst, std::abs(s_contact[b] - s_uncut[b]));
    if (p.disc.bond_precut[b]) c.through = std::min(c.through, s_cracked[b]);
  }
  c.open = contact.open_bonds();
  return c;
}

TEST_P(CrackFaceContactTest, FacesPressedTogetherTransmitTheLoadOfTheUncutBody) {
  // Confined: every bond across the cut is compressed in the uncut body, so closing them all is
  // the contact solution and it IS the uncut body, to round-off.
  const auto p = cut_plate(GetParam(), true);
  std::size_t cut = 0;
  for (auto b : p.disc.bond_precut) cut += b;
  ASSERT_GT(cut, 30u);
  const Compared c = compare_with_uncut(p);
  EXPECT_TRUE(c.open.empty());
  EXPECT_LT(c.worst, 1e-9 * c.scale);
  // Without contact the cut's faces pass through each other: its bonds "stretch" by the overlap,
  // far beyond any intact bond's strain.
  EXPECT_LT(c.through, -2.0 * c.scale);
}

TEST_P(CrackFaceContactTest, FreeSidesLeaveOnlyTheShallowBondsOpenThatThePoissonExpansionPulls) {
  // Free sides: the lateral expansion ν|ε_yy| stretches a bond at angle θ to the cut by
  // |ε_yy|(ν cos²θ − sin²θ) in the uncut body: the shallow bonds across the cut (tan²θ < ν) are
  // in tension and stay open (a crack has no adhesion); the frictionless faces still carry the
  // normal load, the stretches within 1 % of the uncut body's.
  const auto p = cut_plate(GetParam(), false);
  const Compared c = compare_with_uncut(p);
  EXPECT_FALSE(c.open.empty());
  for (auto b : c.open) {
    const double sin_theta = p.disc.bond_sin[static_cast<std::size_t>(b)];
    EXPECT_LT(sin_theta * sin_theta, 0.33 / 1.33) << b;  // tan²θ < ν
  }
  EXPECT_LT(c.worst, 0.01 * c.scale);
}

TEST_P(CrackFaceContactTest, UnderBendingPartOfTheCutOpensAndTheSignoriniConditionsHold) {
  // A shear on the top edge bends the plate about the cut: one end of the cut closes, the other
  // opens. At the active set's fixed point every closed cut bond is in compression and every open
  // one has a gap >= 0; the answer does not depend on the warm start.
  auto p = cut_plate(GetParam(), false);
  p.loads[0].constant = {4.0, 0.3};  // mostly shear: P = −1 pushes the top edge in −x
  statics::StaticSolver cracked(p.disc, p.model, p.supports, p.loads);
  ASSERT_TRUE(cracked.solve().ok());
  statics::CrackFaceContact contact(p.disc, p.model, p.supports, p.loads, {});
  const std::vector<std::int64_t> rank(p.disc.bond_precut.size(), -1);
  std::vector<double> s;
  ASSERT_TRUE(contact.compressive_stretch(cracked.intact(), rank, 0.0, s).ok());
  EXPECT_EQ(contact.unconverged(), 0);
  const auto open = contact.open_bonds();
  std::size_t cut = 0;
  for (auto c : p.disc.bond_precut) cut += c;
  EXPECT_GT(open.size(), 5u);
  EXPECT_LT(open.size(), cut - 5);
  std::vector<std::uint8_t> is_open(s.size(), 0);
  for (auto b : open) is_open[static_cast<std::size_t>(b)] = 1;
  for (std::size_t b = 0; b < s.size(); ++b) {
    if (!p.disc.bond_precut[b]) continue;
    if (is_open[b]) {
      EXPECT_GT(s[b], 0.0) << b;
    } else {
      EXPECT_LE(s[b], 0.0) << b;
    }
  }
  // Warm-started from another angle's open set, the same answer bit for bit.
  std::vector<double> other, again;
  ASSERT_TRUE(contact.compressive_stretch(cracked.intact(), rank, 1.3, other).ok());
  ASSERT_TRUE(contact.compressive_stretch(cracked.intact(), rank, 0.0, again).ok());
  EXPECT_EQ(again, s);
  EXPECT_EQ(contact.open_bonds(), open);
}

INSTANTIATE_TEST_SUITE_P(
    Models, CrackFaceContactTest,
    ::testing::Values(model::ModelKind::bond_based, model::ModelKind::state_based),
    [](const auto& i) {
      return std::string(i.param == model::ModelKind::bond_based ? "bond_based" : "state_based");
    });

// ------------------------------------------------------------------ the engine's rules

/// Strain-range parameters for the notched plate: its most stretched intact bond fails after
/// about `first_failure` cycles of P_max = `load` at R = 0 (000 Eq. 21).
fatigue::FatigueSettings plate_settings(const statics::Specimen& p, double load,
                                        double first_failure) {
  const double smax = testing::largest_intact_stretch(p, load);
  fatigue::FatigueSettings f;
  f.law = fatigue::FatigueLaw::strain_range;
  f.critical_stretch = 4 * smax;
  f.strain.m1 = 2.29153;
  f.strain.m2 = 2.6183;
  f.strain.A1 = 1.0 / (first_failure * std::pow(smax, f.strain.m1));
  f.strain.A2 = 0.2 / (first_failure * std::pow(smax, f.strain.m2));
  return f;
}

class ContactEngine : public ::testing::TestWithParam<model::ModelKind> {};

TEST_P(ContactEngine, BlocksWithReversedCyclesEqualTheCycleByCycleOracle) {
  // Exact block stepping with the contact solution at P_min: the contact set is recomputed after
  // every break (the crack's new faces close or open), inside blocks, bit for bit as per cycle.
  const auto plate = make_notched_plate(GetParam());
  auto settings = plate_settings(plate, 1000.0, 60.0);
  settings.compression = fatigue::CompressionRule::contact;
  fatigue::FatigueEngine fast(plate.disc, plate.model, plate.supports, plate.loads, settings);
  fatigue::FatigueEngine slow(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(fast.initialize());
  ASSERT_TRUE(slow.initialize());
  const std::vector<core::LoadBlock> blocks = {{1000.0, -1.0, 0.0, 130},
                                               {1000.0, 0.1, 0.0, 20},
                                               {900.0, -2.0, 0.3, 60},
                                               {1000.0, -0.5, 0.0, 200}};
  for (const auto& block : blocks) {
    fast.apply(block);
    slow.apply_per_cycle(block);
    testing::expect_same_breaks(fast, slow);
    const auto la = fast.remaining_life();
    const auto lb = slow.remaining_life();
    ASSERT_EQ(la, lb);
  }
  EXPECT_GT(fast.break_events().size(), 10u);
  EXPECT_FALSE(fast.failed());
  ASSERT_NE(fast.contact(), nullptr);
  // The notch's faces close under P < 0 (they are a zero-width cut): the contact is real here.
  EXPECT_LT(fast.contact()->open_bonds().size(), 102u);
}

TEST_P(ContactEngine, AtNonNegativeLoadRatiosContactIsTheFullRangeRule) {
  // R >= 0: no face touches at P_min; the direct mode's lives equal the dose mode's to rounding.
  const auto plate = make_notched_plate(GetParam());
  const auto full = plate_settings(plate, 1000.0, 60.0);
  auto touching = full;
  touching.compression = fatigue::CompressionRule::contact;
  fatigue::FatigueEngine a(plate.disc, plate.model, plate.supports, plate.loads, full);
  fatigue::FatigueEngine b(plate.disc, plate.model, plate.supports, plate.loads, touching);
  ASSERT_TRUE(a.initialize());
  ASSERT_TRUE(b.initialize());
  for (const core::LoadBlock& block :
       {core::LoadBlock{1000.0, 0.1, 0.0, 500}, core::LoadBlock{1200.0, 0.3, 0.2, 400}}) {
    a.apply(block);
    b.apply(block);
  }
  testing::expect_same_breaks(a, b);
  EXPECT_GT(a.break_events().size(), 3u);
  const auto la = a.remaining_life();
  const auto lb = b.remaining_life();
  for (std::size_t i = 0; i < la.size(); ++i) EXPECT_NEAR(la[i], lb[i], 1e-12) << i;
}

TEST_P(ContactEngine, AReversedCycleCostsTheTipTheContactSolutionsRangeNotTheFullOne) {
  // 100 cycles at P_max = 1 kN, R = −1, before any break. The engine's life of the hottest bond
  // against an independent solve: the plate with every bond intact except the contact's open set
  // (StaticSolver of the uncut plate, those bonds broken) at P = −1 gives s⁻, and 000 Eq. (15),
  // (17)-(19) give 1 − 100·A·|s⁺ − s⁻|^m. The physics: the compressive half of the cycle adds the
  // closed body's strain, a fraction of the tensile half's at the notch tip, where the full range
  // rule doubles the range.
  const auto plate = make_notched_plate(GetParam());
  const auto full = plate_settings(plate, 1000.0, 400.0);
  auto touching = full;
  touching.compression = fatigue::CompressionRule::contact;
  fatigue::FatigueEngine e(plate.disc, plate.model, plate.supports, plate.loads, touching);
  ASSERT_TRUE(e.initialize());
  const auto phases = e.bond_phase();
  e.apply({1000.0, -1.0, 0.0, 100});
  ASSERT_TRUE(e.break_events().empty());
  const auto open = e.contact()->open_bonds();
  // Free sides: the shallow bonds across the notch that the Poisson expansion pulls stay open.
  EXPECT_LT(open.size(), 40u);
  mesh::Discretization whole = plate.disc;
  std::fill(whole.bond_precut.begin(), whole.bond_precut.end(), std::uint8_t{0});
  statics::StaticSolver closed(whole, plate.model, plate.supports, plate.loads);
  closed.set_incremental(false);
  ASSERT_TRUE(closed.solve().ok());
  ASSERT_TRUE(closed.break_bonds(open).ok());
  std::vector<double> s_min, s_max;
  closed.stretch(-1000.0, 0.0, s_min);
  e.solver().stretch(1000.0, 0.0, s_max);
  std::size_t hot = 0;
  for (std::size_t b = 0; b < s_max.size(); ++b) {
    if (!plate.disc.bond_precut[b] && s_max[b] > s_max[hot]) hot = b;
  }
  for (const auto b : open) EXPECT_GE(s_min[static_cast<std::size_t>(b)], 0.0);
  const bool phase1 = phases[hot] == 1;
  const double a = phase1 ? full.strain.A1 : full.strain.A2;
  const double m = phase1 ? full.strain.m1 : full.strain.m2;
  const double decrement = a * std::pow(std::abs(s_max[hot] - s_min[hot]), m);
  EXPECT_NEAR(e.remaining_life()[hot], 1.0 - 100.0 * decrement, 1e-9);
  const double tensile_half = a * std::pow(s_max[hot], m);
  const double full_range = a * std::pow(2.0 * s_max[hot], m);
  EXPECT_GT(decrement, tensile_half);
  EXPECT_LT(decrement, 0.5 * full_range);
}

TEST_P(ContactEngine, ACheckpointAndAForkContinueBitForBit) {
  // The contact solution is a function of the broken set and α alone (statics/crack_contact.h):
  // an engine resumed from an exported state, and a fork, whose contact solvers start afresh,
  // continue as the uninterrupted one does, bit for bit, through reversed blocks with breaks.
  const auto plate = make_notched_plate(GetParam());
  auto settings = plate_settings(plate, 1000.0, 60.0);
  settings.compression = fatigue::CompressionRule::contact;
  const std::vector<core::LoadBlock> first_half = {{1000.0, -1.0, 0.0, 150},
                                                   {900.0, -2.0, 0.3, 40}};
  const std::vector<core::LoadBlock> second_half = {{1000.0, -1.0, 0.0, 120},
                                                    {1000.0, -0.5, 0.3, 80}};
  fatigue::FatigueEngine straight(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(straight.initialize());
  for (const auto& b : first_half) straight.apply(b);
  const fatigue::EngineState saved = straight.export_state();
  const auto fork = straight.fork(settings);
  for (const auto& b : second_half) straight.apply(b);
  fatigue::FatigueEngine resumed(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(resumed.initialize());
  ASSERT_TRUE(resumed.import_state(saved));
  for (const auto& b : second_half) {
    resumed.apply(b);
    fork->apply(b);
  }
  EXPECT_GT(straight.break_events().size(), saved.events.size());  // breaks after the checkpoint
  EXPECT_EQ(resumed.state_hash(), straight.state_hash());
  EXPECT_EQ(fork->state_hash(), straight.state_hash());
}

INSTANTIATE_TEST_SUITE_P(
    Models, ContactEngine,
    ::testing::Values(model::ModelKind::bond_based, model::ModelKind::state_based),
    [](const auto& i) {
      return std::string(i.param == model::ModelKind::bond_based ? "bond_based" : "state_based");
    });

TEST(ClosureEngine, AReversedCycleIsTheFullRangeCycleAtNewmansOpeningRatio) {
  // The closure rule puts f(R) where the full-range rule has R (ΔK_eff = (1 − f)K_max): the same
  // doses, so the same lives and breaks bit for bit.
  const auto plate = make_notched_plate(model::ModelKind::state_based);
  const auto full = plate_settings(plate, 1000.0, 150.0);
  auto closure = full;
  closure.compression = fatigue::CompressionRule::closure;
  closure.closure = {1.5, 0.4};
  fatigue::FatigueEngine a(plate.disc, plate.model, plate.supports, plate.loads, closure);
  fatigue::FatigueEngine b(plate.disc, plate.model, plate.supports, plate.loads, full);
  ASSERT_TRUE(a.initialize());
  ASSERT_TRUE(b.initialize());
  for (const double r : {-1.0, 0.1, -2.5, 0.5}) {
    const double f = fatigue::newman_opening_ratio(r, closure.closure);
    a.apply({1000.0, r, 0.0, 1500});
    b.apply({1000.0, f, 0.0, 1500});
  }
  testing::expect_same_breaks(a, b);
  EXPECT_GT(a.break_events().size(), 3u);
  EXPECT_EQ(a.remaining_life(), b.remaining_life());
}

TEST(CompressionRules, RefusedWhereTheLawCannotUseThem) {
  const auto plate = make_notched_plate(model::ModelKind::bond_based);
  auto f = plate_settings(plate, 1000.0, 150.0);
  f.law = fatigue::FatigueLaw::kinetic;
  f.compression = fatigue::CompressionRule::closure;
  EXPECT_THROW(fatigue::FatigueEngine(plate.disc, plate.model, plate.supports, plate.loads, f),
               std::invalid_argument);
  f.law = fatigue::FatigueLaw::energy;
  f.compression = fatigue::CompressionRule::contact;
  EXPECT_THROW(fatigue::FatigueEngine(plate.disc, plate.model, plate.supports, plate.loads, f),
               std::invalid_argument);
  f.law = fatigue::FatigueLaw::strain_range;
  f.compression = fatigue::CompressionRule::closure;
  f.closure.constraint = 4.0;
  EXPECT_THROW(fatigue::FatigueEngine(plate.disc, plate.model, plate.supports, plate.loads, f),
               std::invalid_argument);
}

}  // namespace
}  // namespace peritwin
