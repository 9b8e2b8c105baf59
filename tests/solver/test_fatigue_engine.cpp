#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <ostream>

#include "solver/fatigue/fatigue_engine.h"
#include "solver/statics/specimen.h"
#include "tests/support/plates.h"

namespace peritwin {
namespace {

using NotchedPlate = statics::Specimen;
using testing::make_notched_plate;

/// Parameters scaled so that the most stretched bond fails after about `first_failure` cycles
/// of P_max = p, R = r: A = 1/(N·ε^m) from 000 Eq. (21).
fatigue::FatigueSettings settings_for(
    const NotchedPlate& p, fatigue::FatigueLaw law, double load, double r, double first_failure,
    double eps_inf_fraction = 0.0,
    fatigue::StaticFailure static_failure = fatigue::StaticFailure::critical_stretch) {
  statics::StaticSolver probe(p.disc, p.model, p.supports, p.loads);
  EXPECT_TRUE(probe.solve().ok());
  std::vector<double> s;
  probe.stretch(load, 0.0, s);
  double smax = 0.0;  // over intact bonds: a bond cut by the notch "stretches" by the opening
  for (std::size_t b = 0; b < s.size(); ++b) {
    if (!p.disc.bond_precut[b]) smax = std::max(smax, s[b]);
  }
  const double eps = smax * (1 - r);
  fatigue::FatigueSettings f;
  f.law = law;
  f.critical_stretch = 4 * smax;  // phase III only for the bonds at the very tip, late
  f.static_failure = static_failure;
  if (static_failure == fatigue::StaticFailure::critical_bond_energy) {
    // 000 Eq. (9): g_c 10 % above the largest intact-bond ḡ (Eq. 31) at the load, so that phase
    // III breaks bonds in the blocks at a higher P_max.
    std::vector<double> theta, g;
    model::dilatations(p.disc, p.model, probe.intact(), s, theta);
    model::bond_energy_release_rates(p.disc, p.model, s, theta, g);
    double gmax = 0.0;
    for (std::size_t b = 0; b < g.size(); ++b) {
      if (!p.disc.bond_precut[b]) gmax = std::max(gmax, g[b]);
    }
    f.critical_bond_energy = 1.1 * gmax;
  }
  f.strain.m1 = 2.29153;
  f.strain.m2 = 2.6183;
  f.strain.eps_inf = eps_inf_fraction * eps;
  f.strain.A1 = 1.0 / (first_failure * std::pow(eps - f.strain.eps_inf, f.strain.m1));
  f.strain.A2 = 0.2 / (first_failure * std::pow(eps, f.strain.m2));
  f.incremental = false;
  if (law == fatigue::FatigueLaw::kinetic) {
    // 004 Eq. (12)-(15): pick the activation energy U so that the most stressed bond
    // (σ = E·s_max) loses its unit life in `first_failure` cycles (Φ monotone in U: bisection).
    // 004's test conditions (T = 293 K, f = 0.56 Hz) and the activation volume γ with γσ/θ = 10
    // at the most stressed bond (Φ ∝ e^(γσ/θ) falls by e^-1 at 0.9σ). Measured on this plate:
    // γσ/θ = 5 or 10 grows the crack by ~35 bonds over the five blocks; γσ/θ ≈ 1.2 (γ = 1e-28 m³)
    // ages every tensile bond almost alike and 20 or 40 make the crack run: the plate comes
    // apart (final failure) within the first 270 cycles.
    auto& k = f.kinetic;
    k.temperature = 293.0;
    k.frequency = 0.56;
    const double sigma = p.model.material.youngs_modulus * smax;
    const double theta = fatigue::kt_thermal_energy(k.temperature);
    k.gamma = 10 * theta / sigma;
    double lo = 0.0, hi = 1e-17;
    for (int i = 0; i < 200; ++i) {
      const double u = 0.5 * (lo + hi);
      const double dose = fatigue::kt_cycle_dose(sigma, r, k.frequency, u, k.gamma, theta);
      (dose > 1.0 / first_failure ? lo : hi) = u;
    }
    k.U = 0.5 * (lo + hi);
  }
  return f;
}

void expect_same_state(const fatigue::FatigueEngine& a, const fatigue::FatigueEngine& b) {
  testing::expect_same_breaks(a, b);
  const auto la = a.remaining_life();
  const auto lb = b.remaining_life();
  for (std::size_t i = 0; i < la.size(); ++i) ASSERT_EQ(la[i], lb[i]) << "bond " << i;  // bitwise
  EXPECT_EQ(a.bond_phase(), b.bond_phase());
}

/// 004 Eq. (12)-(15) outside the engine: from the virgin state, with no bond broken yet, `cycles`
/// cycles at the constant P_max, R of `block` leave the most stretched intact bond (stretch
/// s_max from a separate static solve) the remaining life 1 − cycles·Φ(E·s_max), Φ the per-cycle
/// dose, which settings_for calibrated to 1/first_failure.
void expect_kinetic_hottest_life(const NotchedPlate& p, const fatigue::FatigueSettings& f,
                                 const fatigue::FatigueEngine& engine, const core::LoadBlock& block,
                                 double first_failure) {
  ASSERT_EQ(engine.break_events().size(), 0u) << engine.broken_bonds();
  statics::StaticSolver probe(p.disc, p.model, p.supports, p.loads);
  ASSERT_TRUE(probe.solve().ok());
  std::vector<double> s;
  probe.stretch(block.p_max, block.alpha, s);
  std::size_t hottest = s.size();
  for (std::size_t b = 0; b < s.size(); ++b) {
    if (!p.disc.bond_precut[b] && (hottest == s.size() || s[b] > s[hottest])) hottest = b;
  }
  ASSERT_LT(hottest, s.size());
  const auto& k = f.kinetic;
  const double dose =
      fatigue::kt_cycle_dose(p.model.material.youngs_modulus * s[hottest], block.r, k.frequency,
                             k.U, k.gamma, fatigue::kt_thermal_energy(k.temperature));
  EXPECT_NEAR(dose * first_failure, 1.0, 1e-9);  // the calibration of settings_for
  const double expected = 1.0 - static_cast<double>(block.count) * dose;
  EXPECT_GT(expected, 0.0);
  EXPECT_NEAR(engine.remaining_life()[hottest], expected, 1e-12);
}

struct LawCase {
  const char* name;
  fatigue::FatigueLaw law;
  model::ModelKind kind;
  double eps_inf_fraction;
  fatigue::StaticFailure static_failure = fatigue::StaticFailure::critical_stretch;
  bool compressed_bonds_fatigue = true;
  /// Bonds broken in the blocks at least (measured: 1 or 2 for the strain-range and energy
  /// laws, whose phase II rate A2 is a fifth of A1; ~35 for the kinetic law).
  std::size_t min_fatigue_breaks = 1;
};

/// gtest prints the case by its name (the default would print its bytes, pointer included).
void PrintTo(const LawCase& c, std::ostream* os) { *os << c.name; }

class BlockEqualsPerCycle : public ::testing::TestWithParam<LawCase> {};

TEST_P(BlockEqualsPerCycle, SameBreaksSameCyclesSameLives) {
  // The exact-stepping contract: applying blocks with next-break jumps gives bit-identical
  // states to cycle-by-cycle integration (the oracle), for a mixed sequence of blocks.
  const auto c = GetParam();
  const auto plate = make_notched_plate(c.kind);
  auto settings =
      settings_for(plate, c.law, 1000.0, 0.1, 150.0, c.eps_inf_fraction, c.static_failure);
  settings.compressed_bonds_fatigue = c.compressed_bonds_fatigue;
  fatigue::FatigueEngine fast(plate.disc, plate.model, plate.supports, plate.loads, settings);
  fatigue::FatigueEngine slow(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(fast.initialize());
  ASSERT_TRUE(slow.initialize());
  const std::vector<core::LoadBlock> blocks = {{1000.0, 0.1, 0.0, 120},
                                               {800.0, 0.1, 0.0, 1},
                                               {1000.0, 0.3, 0.0, 37},
                                               {1100.0, -0.2, 0.2, 90},
                                               {1000.0, 0.1, 0.0, 400}};
  for (const auto& block : blocks) {
    fast.apply(block);
    slow.apply_per_cycle(block);
    expect_same_state(fast, slow);
    if (c.law == fatigue::FatigueLaw::kinetic && &block == &blocks.front()) {
      expect_kinetic_hottest_life(plate, settings, fast, block, 150.0);
    }
  }
  EXPECT_GT(fast.broken_bonds(), 20);  // the test must actually crack the plate
  // broken_bonds() counts the notch's 102 pre-cut bonds too; the breaks in these blocks:
  EXPECT_GE(fast.break_events().size(), c.min_fatigue_breaks);
  EXPECT_FALSE(fast.failed());  // every block was applied, none cut short by final failure
  if (c.static_failure == fatigue::StaticFailure::critical_bond_energy) {
    const auto overloads = std::count_if(
        fast.break_events().begin(), fast.break_events().end(),
        [](const fatigue::BreakEvent& e) { return e.cause == fatigue::BreakCause::overload; });
    EXPECT_GT(overloads, 0);  // phase III by 000 Eq. (9) must actually have happened
  }
}

INSTANTIATE_TEST_SUITE_P(
    Laws, BlockEqualsPerCycle,
    ::testing::Values(
        LawCase{"strain_dose_bb", fatigue::FatigueLaw::strain_range, model::ModelKind::bond_based,
                0},
        LawCase{"strain_dose_osb", fatigue::FatigueLaw::strain_range, model::ModelKind::state_based,
                0},
        LawCase{"strain_limit_bb", fatigue::FatigueLaw::strain_range, model::ModelKind::bond_based,
                0.3},
        LawCase{"energy_osb", fatigue::FatigueLaw::energy, model::ModelKind::state_based, 0},
        LawCase{"strain_dose_bb_gc", fatigue::FatigueLaw::strain_range,
                model::ModelKind::bond_based, 0, fatigue::StaticFailure::critical_bond_energy},
        LawCase{"strain_limit_osb_gc", fatigue::FatigueLaw::strain_range,
                model::ModelKind::state_based, 0.3, fatigue::StaticFailure::critical_bond_energy},
        LawCase{"energy_osb_gc", fatigue::FatigueLaw::energy, model::ModelKind::state_based, 0,
                fatigue::StaticFailure::critical_bond_energy},
        LawCase{"strain_dose_bb_tension_only", fatigue::FatigueLaw::strain_range,
                model::ModelKind::bond_based, 0, fatigue::StaticFailure::critical_stretch, false},
        LawCase{"energy_osb_tension_only", fatigue::FatigueLaw::energy,
                model::ModelKind::state_based, 0, fatigue::StaticFailure::critical_stretch, false},
        // 004's kinetic law; settings_for picks U so that the most stressed bond fails after
        // about 150 cycles of the first block.
        LawCase{"kinetic_bb", fatigue::FatigueLaw::kinetic, model::ModelKind::bond_based, 0,
                fatigue::StaticFailure::critical_stretch, true, 21},
        LawCase{"kinetic_osb", fatigue::FatigueLaw::kinetic, model::ModelKind::state_based, 0,
                fatigue::StaticFailure::critical_stretch, true, 21}),
    [](const ::testing::TestParamInfo<LawCase>& p) { return std::string(p.param.name); });

TEST(EnergyLaw, EqualsTheStrainRangeLawIncludingBondsWithNegativeEnergyReleaseRate) {
  // 000 Eq. (34a)/(35c) take |C0| and Eq. (44b) derives B_i from the same C1, so B_i·g^n_i =
  // A_i·ε^m_i for every bond, also where the dilatation term makes ḡ of Eq. (31) negative (a
  // compressed bond in a dilated region). The state-based plate must break the same bonds at the
  // same cycles under both laws, with remaining lives equal to rounding (1e-9 relative).
  const auto plate = make_notched_plate(model::ModelKind::state_based);
  {  // the test must contain bonds with ḡ < 0 at the load
    statics::StaticSolver probe(plate.disc, plate.model, plate.supports, plate.loads);
    ASSERT_TRUE(probe.solve().ok());
    std::vector<double> s, theta, g;
    probe.stretch(1000.0, 0.0, s);
    model::dilatations(plate.disc, plate.model, probe.intact(), s, theta);
    model::bond_energy_release_rates(plate.disc, plate.model, s, theta, g);
    const auto negative = std::count_if(g.begin(), g.end(), [](double v) { return v < 0.0; });
    EXPECT_GT(negative, 0);
  }
  const auto strain = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  auto energy = strain;
  energy.law = fatigue::FatigueLaw::energy;
  auto run = [&plate](const fatigue::FatigueSettings& settings) {
    auto engine = std::make_unique<fatigue::FatigueEngine>(plate.disc, plate.model, plate.supports,
                                                           plate.loads, settings);
    EXPECT_TRUE(engine->initialize());
    engine->apply({1000.0, 0.1, 0.0, 300});
    return engine;
  };
  const auto by_strain = run(strain);
  const auto by_energy = run(energy);
  testing::expect_same_breaks(*by_strain, *by_energy);
  EXPECT_GT(by_strain->broken_bonds(), 10);
  const auto a = by_strain->remaining_life();
  const auto b = by_energy->remaining_life();
  ASSERT_EQ(a.size(), b.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) worst = std::max(worst, std::abs(a[k] - b[k]));
  EXPECT_LT(worst, 1e-9);  // λ ∈ [0, 1]: absolute is relative to the initial life
}

TEST(CompressedBonds, FatigueBy000Eq15AndNotWhenTurnedOff) {
  // 000 Eq. (15) takes |s⁺(1 − R)|: a bond compressed at P_max loses life like one stretched as
  // much. With compressed_bonds_fatigue = false it keeps its full life; bonds in tension are
  // unchanged bit for bit. 100 cycles, before the first break (about 150), in both the dose path
  // (strain range) and the per-block path (energy law).
  for (const fatigue::FatigueLaw law :
       {fatigue::FatigueLaw::strain_range, fatigue::FatigueLaw::energy}) {
    const auto plate = make_notched_plate(model::ModelKind::state_based);
    statics::StaticSolver probe(plate.disc, plate.model, plate.supports, plate.loads);
    ASSERT_TRUE(probe.solve().ok());
    std::vector<double> s;
    probe.stretch(1000.0, 0.0, s);
    auto run = [&plate](const fatigue::FatigueSettings& settings) {
      auto engine = std::make_unique<fatigue::FatigueEngine>(plate.disc, plate.model,
                                                             plate.supports, plate.loads, settings);
      EXPECT_TRUE(engine->initialize());
      engine->apply({1000.0, 0.1, 0.0, 100});
      EXPECT_TRUE(engine->break_events().empty());  // no break yet (pre-cut bonds aside)
      return engine->remaining_life();
    };
    auto settings = settings_for(plate, law, 1000.0, 0.1, 150.0);
    const auto both = run(settings);
    settings.compressed_bonds_fatigue = false;
    const auto tension_only = run(settings);
    int compressed = 0;
    for (std::size_t b = 0; b < s.size(); ++b) {
      if (plate.disc.bond_precut[b] || s[b] == 0.0) continue;
      if (s[b] < 0.0) {
        ++compressed;
        EXPECT_LT(both[b], 1.0) << "bond " << b;
        EXPECT_EQ(tension_only[b], 1.0) << "bond " << b;
      } else {
        EXPECT_EQ(tension_only[b], both[b]) << "bond " << b;
      }
    }
    EXPECT_GT(compressed, 100);  // the plate's lateral bonds contract
  }
}

TEST(BlockStepping, ManyOneCycleBlocksEqualOneLongBlock) {
  // A rainflow-counted history is mostly 1-cycle blocks: 600 blocks of one cycle must give the
  // state of one block of 600 cycles, bit for bit (dose accumulation is repeated addition).
  const auto plate = make_notched_plate(model::ModelKind::bond_based);
  const auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  fatigue::FatigueEngine one(plate.disc, plate.model, plate.supports, plate.loads, settings);
  fatigue::FatigueEngine many(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(one.initialize());
  ASSERT_TRUE(many.initialize());
  one.apply({1000.0, 0.1, 0.0, 600});
  for (int i = 0; i < 600; ++i) many.apply({1000.0, 0.1, 0.0, 1});
  expect_same_state(one, many);
  EXPECT_GT(one.broken_bonds(), 5);
}

TEST(SingleBond, FirstFailureMatchesNguyenEq21) {
  // B4: the most stretched bond at constant strain range ε fails at N = 1/(A1 ε^m1) (000 Eq. 21),
  // here with A1 set so that N = 150.4: the first break must come at cycle ceil(150.4) = 151.
  // No notch: a notch puts its tip nodes in phase II from the start (000 Sec. 4.4).
  const auto plate = make_notched_plate(model::ModelKind::bond_based, false);
  auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.4);
  fatigue::FatigueEngine engine(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(engine.initialize());
  engine.apply({1000.0, 0.1, 0.0, 1000});
  ASSERT_FALSE(engine.break_events().empty());
  EXPECT_EQ(engine.break_events().front().cycle, 151);
  EXPECT_EQ(engine.break_events().front().cause, fatigue::BreakCause::fatigue);
}

TEST(PropagationLimit, SetBetweenBlocksFreezesPhaseTwoAndMatchesPerCycle) {
  // 002 Sec. 7 raises ε̃∞ (002 Eq. 12) with the load between blocks. Starting without limits (dose
  // mode), a limit above every strain range freezes the phase II lives while phase I keeps
  // losing life; switching limits back and forth, blocks equal the per-cycle oracle bit for bit.
  const auto plate = make_notched_plate(model::ModelKind::bond_based);
  const auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  fatigue::FatigueEngine block(plate.disc, plate.model, plate.supports, plate.loads, settings);
  fatigue::FatigueEngine oracle(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(block.initialize());
  ASSERT_TRUE(oracle.initialize());
  block.apply({1000.0, 0.1, 0.0, 40});
  oracle.apply_per_cycle({1000.0, 0.1, 0.0, 40});
  const auto before = block.remaining_life();
  block.set_propagation_limit(1.0);
  oracle.set_propagation_limit(1.0);
  block.apply({1000.0, 0.1, 0.0, 30});
  oracle.apply_per_cycle({1000.0, 0.1, 0.0, 30});
  const auto after = block.remaining_life();
  int phase_one_changed = 0;
  for (std::size_t b = 0; b < after.size(); ++b) {
    if (block.bond_phase()[b] == 2) {
      EXPECT_EQ(after[b], before[b]) << "bond " << b;
    }
    if (block.bond_phase()[b] == 1 && after[b] < before[b]) ++phase_one_changed;
  }
  EXPECT_GT(phase_one_changed, 0);
  block.set_propagation_limit(0.0);
  oracle.set_propagation_limit(0.0);
  block.apply({1000.0, 0.1, 0.0, 200});
  oracle.apply_per_cycle({1000.0, 0.1, 0.0, 200});
  expect_same_state(block, oracle);
  EXPECT_GT(block.broken_bonds(), 5);
  EXPECT_THROW(block.set_propagation_limit(-1e-4), std::invalid_argument);
  EXPECT_THROW(block.set_propagation_limit(std::nan("")), std::invalid_argument);
}

TEST(LoadBlockValidation, RejectsWhatCannotBeApplied) {
  EXPECT_TRUE(core::check_load_block(core::LoadBlock{1000, 0.1, 0, 1}).ok());
  EXPECT_EQ(core::check_load_block(core::LoadBlock{std::nan(""), 0.1, 0, 1}).error().field,
            "p_max");
  EXPECT_EQ(core::check_load_block(core::LoadBlock{1000, 1.0, 0, 1}).error().field, "r");
  EXPECT_EQ(core::check_load_block(core::LoadBlock{1000, -10.5, 0, 1}).error().field, "r");
  EXPECT_TRUE(core::check_load_block(core::LoadBlock{1000, -10.0, 0, 1}).ok());
  EXPECT_EQ(core::check_load_block(core::LoadBlock{1000, 0.1, 0, 0}).error().field, "count");
  EXPECT_EQ(core::check_load_block(core::LoadBlock{1000, 0.1, 0, core::kMaxBatchCycles + 1})
                .error()
                .field,
            "count");
  EXPECT_EQ(core::check_load_block(core::LoadBlock{-5, 0.1, 0, 1}).error().field, "p_max");
  EXPECT_EQ(core::check_load_block(core::LoadBlock{1000, 0.1, std::nan(""), 1}).error().field,
            "alpha");
  // The batch total: two blocks of 2^49 + 1 pass alone and fail together, at the second.
  const core::LoadBlock half{1000, 0.1, 0, core::kMaxBatchCycles / 2 + 1};
  EXPECT_TRUE(core::check_load_blocks(std::vector<core::LoadBlock>{half}).ok());
  EXPECT_EQ(core::check_load_blocks(std::vector<core::LoadBlock>{half, half}).error().field,
            "blocks[1].count");
}

}  // namespace
}  // namespace peritwin

namespace peritwin {
namespace {

/// The state hash the way it was first defined: word-wise FNV-1a over export_state()'s copy.
std::uint64_t hash_of_exported_state(const fatigue::FatigueEngine& engine) {
  core::Fnv1a64 h;
  const fatigue::EngineState state = engine.export_state();
  fatigue::for_each_field(
      state, [&h](std::string_view, const auto& field) { fatigue::hash_field(h, field); });
  return h.get();
}

TEST(EngineState, HashReadInPlaceEqualsTheHashOfTheExportedCopy) {
  // state_hash() reads the engine's fields in place (the solver's intact flags); the oracle hashes
  // export_state()'s copy. A pair of hashes fed the same words gives each one's value.
  const auto plate = make_notched_plate(model::ModelKind::bond_based);
  const auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  fatigue::FatigueEngine engine(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(engine.initialize());
  for (const core::LoadBlock& block :
       {core::LoadBlock{1000.0, 0.1, 0.0, 333}, core::LoadBlock{900.0, 0.2, 0.0, 400}}) {
    engine.apply(block);
    EXPECT_EQ(engine.state_hash(), hash_of_exported_state(engine));
    core::Fnv1a64Pair pair{core::Fnv1a64::from(12345), core::Fnv1a64{}};
    engine.hash_state(pair);
    core::Fnv1a64 alone = core::Fnv1a64::from(12345);
    engine.hash_state(alone);
    EXPECT_EQ(pair.first.get(), alone.get());
    EXPECT_EQ(pair.second.get(), engine.state_hash());
  }
  EXPECT_GT(engine.broken_bonds(), 5);  // the intact flags hashed are not all ones
}

TEST(EngineState, ExportImportResumesBitIdentically) {
  // Checkpoint contract: stop anywhere (here in the middle of a dose accumulation), restore into a
  // fresh engine, continue: the final state equals the uninterrupted run bit for bit.
  const auto plate = make_notched_plate(model::ModelKind::bond_based);
  const auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  fatigue::FatigueEngine straight(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(straight.initialize());
  straight.apply({1000.0, 0.1, 0.0, 333});
  straight.apply({900.0, 0.2, 0.0, 400});
  fatigue::FatigueEngine first(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(first.initialize());
  first.apply({1000.0, 0.1, 0.0, 333});
  const fatigue::EngineState saved = first.export_state();
  fatigue::FatigueEngine resumed(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(resumed.initialize());
  ASSERT_TRUE(resumed.import_state(saved));
  EXPECT_EQ(resumed.state_hash(), first.state_hash());
  resumed.apply({900.0, 0.2, 0.0, 400});
  expect_same_state(straight, resumed);
  EXPECT_EQ(straight.state_hash(), resumed.state_hash());
  EXPECT_GT(straight.broken_bonds(), 5);
}

TEST(Phases, UpdatedAfterEachGroupOfBreaksAsIfRecomputedFromScratch) {
  // resolve() updates the damage and the phases only at the new breaks' end nodes (issue 37);
  // import_state() recomputes both for every node and bond (update_phases). After every block
  // of a growing crack the two agree bit for bit, and phase II spreads beyond the notch tip.
  const auto plate = make_notched_plate(model::ModelKind::state_based);
  const auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  fatigue::FatigueEngine engine(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(engine.initialize());
  const auto count_phase_two = [](const fatigue::FatigueEngine& e) {
    return std::count(e.bond_phase().begin(), e.bond_phase().end(), std::uint8_t{2});
  };
  const auto at_start = count_phase_two(engine);
  for (int block = 0; block < 20; ++block) {
    engine.apply({1000.0, 0.1, 0.0, 150});
    fatigue::FatigueEngine fresh(plate.disc, plate.model, plate.supports, plate.loads, settings);
    ASSERT_TRUE(fresh.initialize());
    ASSERT_TRUE(fresh.import_state(engine.export_state()));
    EXPECT_EQ(engine.bond_phase(), fresh.bond_phase()) << block;
    EXPECT_EQ(engine.node_damage(), fresh.node_damage()) << block;
  }
  EXPECT_GT(engine.broken_bonds(), 300);  // the notch's 102 and the crack's
  EXPECT_GT(count_phase_two(engine), 2 * at_start);
}

}  // namespace
}  // namespace peritwin

namespace peritwin {
namespace {

class IncrementalEqualsRefactor : public ::testing::TestWithParam<model::ModelKind> {};

TEST_P(IncrementalEqualsRefactor, SameBreakSequence) {
  // The incremental re-solve (CHOLMOD rank updates) against the refactorizing oracle: the same
  // bonds break at the same cycles; lives agree to round-off.
  const auto plate = make_notched_plate(GetParam());
  auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  fatigue::FatigueEngine refactor(plate.disc, plate.model, plate.supports, plate.loads, settings);
  settings.incremental = true;
  fatigue::FatigueEngine incremental(plate.disc, plate.model, plate.supports, plate.loads,
                                     settings);
  ASSERT_TRUE(refactor.initialize());
  ASSERT_TRUE(incremental.initialize());
  for (const core::LoadBlock block :
       {core::LoadBlock{1000.0, 0.1, 0.0, 500}, core::LoadBlock{1100.0, 0.1, 0.3, 300}}) {
    refactor.apply(block);
    incremental.apply(block);
  }
  testing::expect_same_breaks(refactor, incremental);
  const auto a = refactor.remaining_life();
  const auto b = incremental.remaining_life();
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-9);
  EXPECT_GT(refactor.broken_bonds(), 20);
  EXPECT_EQ(incremental.solver().factorizations(), 1);
}

TEST_P(IncrementalEqualsRefactor, PeriodicRebuildsKeepResumeBitIdenticalAndShort) {
  // Rebuilding the factor every 4 re-solves: the same break sequence as pure updates (lives to
  // round-off), and a resume from an exported state replays only the re-solves since the last
  // rebuild yet continues bit for bit like the uninterrupted run.
  const auto plate = make_notched_plate(GetParam());
  auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  settings.incremental = true;
  settings.refactor_every_resolves = 0;
  fatigue::FatigueEngine updates_only(plate.disc, plate.model, plate.supports, plate.loads,
                                      settings);
  settings.refactor_every_resolves = 4;
  fatigue::FatigueEngine straight(plate.disc, plate.model, plate.supports, plate.loads, settings);
  fatigue::FatigueEngine first(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(updates_only.initialize());
  ASSERT_TRUE(straight.initialize());
  ASSERT_TRUE(first.initialize());
  const core::LoadBlock a{1000.0, 0.1, 0.0, 500}, b{1100.0, 0.1, 0.3, 700},
      c{1100.0, 0.1, 0.3, 300};
  for (auto* e : {&updates_only, &straight, &first}) {
    e->apply(a);
    e->apply(b);
  }
  updates_only.apply(c);
  straight.apply(c);
  const fatigue::EngineState saved = first.export_state();
  const auto groups = saved.resolve_groups.size();
  ASSERT_GE(groups, 6u);  // at least one rebuild and re-solves after it
  fatigue::FatigueEngine resumed(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(resumed.initialize());
  ASSERT_TRUE(resumed.import_state(saved));
  EXPECT_EQ(resumed.state_hash(), first.state_hash());
  // initialize + one solve for everything up to the last rebuild + the replayed re-solves
  EXPECT_EQ(resumed.solves(), 1 + 1 + static_cast<int>(groups % 4));
  resumed.apply(c);
  EXPECT_GT(resumed.solves(), 1 + 1 + static_cast<int>(groups % 4));  // c breaks bonds too
  expect_same_state(straight, resumed);
  EXPECT_EQ(straight.state_hash(), resumed.state_hash());

  testing::expect_same_breaks(updates_only, straight);
  const auto la = updates_only.remaining_life();
  const auto lb = straight.remaining_life();
  for (std::size_t i = 0; i < la.size(); ++i) EXPECT_NEAR(la[i], lb[i], 1e-9);
}

TEST_P(IncrementalEqualsRefactor, ForkContinuesBitForBitAsAFreshEngineThatImports) {
  // FatigueEngine::fork (the remaining-life simulations, twin/life.h) copies the live
  // factor instead of rebuilding it. With other coefficients (A2 and A1 × 1.2, the life band), a
  // rebuild every 4 re-solves and re-solves after it, in dose mode and in direct mode (a fatigue
  // limit), the fork's state and every later step equal those of a fresh engine with the same
  // coefficients that initialize()d and import_state()d the exported state: bit for bit.
  const auto plate = make_notched_plate(GetParam());
  for (const double eps_inf_fraction : {0.0, 0.2}) {
    SCOPED_TRACE(eps_inf_fraction);
    auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0,
                                 eps_inf_fraction);
    settings.incremental = true;
    settings.refactor_every_resolves = 4;
    fatigue::FatigueEngine live(plate.disc, plate.model, plate.supports, plate.loads, settings);
    ASSERT_TRUE(live.initialize());
    live.apply({1000.0, 0.1, 0.0, 500});
    live.apply({1100.0, 0.1, 0.3, 700});
    ASSERT_GE(live.export_state().resolve_groups.size(), 6u);  // a rebuild and re-solves after
    ASSERT_GT(live.rebuilds(), 0);
    fatigue::FatigueSettings band = settings;
    band.strain.A2 *= 1.2;
    band.strain.A1 *= 1.2;
    fatigue::FatigueEngine fresh(plate.disc, plate.model, plate.supports, plate.loads, band);
    ASSERT_TRUE(fresh.initialize());
    ASSERT_TRUE(fresh.import_state(live.export_state()));
    const auto fork = live.fork(band);
    EXPECT_EQ(fork->state_hash(), fresh.state_hash());
    EXPECT_EQ(fork->state_hash(), live.state_hash());  // the state is the same, not the rates
    const core::LoadBlock c{1100.0, 0.1, 0.3, 400}, d{900.0, 0.2, 0.0, 2000};
    for (const auto& block : {c, d}) {
      EXPECT_EQ(fork->apply(block), fresh.apply(block));
    }
    EXPECT_GT(fresh.break_events().size(), live.break_events().size());  // they broke bonds
    expect_same_state(*fork, fresh);
    EXPECT_EQ(fork->state_hash(), fresh.state_hash());
    // The live engine was not touched by its fork's steps.
    EXPECT_EQ(live.total_cycles(), 1200);
  }
}

TEST(FatigueEngineFork, RefusesOtherStructuralSettingsAndTheBilinearLaw) {
  const auto plate = make_notched_plate(model::ModelKind::bond_based);
  auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  fatigue::FatigueEngine engine(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(engine.initialize());
  fatigue::FatigueSettings other = settings;
  other.critical_stretch *= 2;
  EXPECT_THROW((void)engine.fork(other), std::invalid_argument);
  other = settings;
  other.law = fatigue::FatigueLaw::energy;
  EXPECT_THROW((void)engine.fork(other), std::invalid_argument);
  other = settings;
  other.law = fatigue::FatigueLaw::bilinear;
  EXPECT_THROW((void)engine.fork(other), std::logic_error);
}

TEST_P(IncrementalEqualsRefactor, ReleasingTheIdleFactorChangesNoBit) {
  // release_idle_factor frees the factor after initialize and after each rebuild; the first
  // break after it factorizes the same stiffness with the same analysis again. The states must
  // be those of the engine that kept its factor, bit for bit (rebuilds every 4 re-solves, so
  // that the release after a rebuild is exercised too).
  const auto plate = make_notched_plate(GetParam());
  auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  settings.incremental = true;
  settings.refactor_every_resolves = 4;
  fatigue::FatigueEngine kept(plate.disc, plate.model, plate.supports, plate.loads, settings);
  settings.release_idle_factor = true;
  fatigue::FatigueEngine released(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(kept.initialize());
  ASSERT_TRUE(released.initialize());
  EXPECT_TRUE(kept.solver().factor().has_values());
  EXPECT_FALSE(released.solver().factor().has_values());
  EXPECT_TRUE(released.solver().factor_released());
  EXPECT_EQ(kept.state_hash(), released.state_hash());
  // A fork of the engine whose factor is released (a remaining-life simulation of an idle live
  // twin) factorizes again at its first break and continues as the engine that kept its factor.
  fatigue::FatigueSettings simulation = settings;
  simulation.release_idle_factor = false;
  const auto fork = released.fork(simulation);
  EXPECT_FALSE(fork->solver().factor().has_values());
  const core::LoadBlock a{1000.0, 0.1, 0.0, 500}, b{1100.0, 0.1, 0.3, 700};
  for (auto* e : {&kept, &released, fork.get()}) {
    e->apply(a);
    e->apply(b);
  }
  expect_same_state(kept, *fork);
  ASSERT_GE(released.solves(), 6);  // re-solves after the first break and at least one rebuild
  ASSERT_GE(released.rebuilds(), 1);
  expect_same_state(kept, released);
  EXPECT_EQ(kept.state_hash(), released.state_hash());
  testing::expect_same_breaks(kept, released);
}

TEST_P(IncrementalEqualsRefactor, TiesStayThroughUpdatesAndRebuilds) {
  // A tie (Tie: a fixture outside the bonds) holds the top corners' x displacements equal. The
  // engine keeps it in every solve: rank updates with a rebuild every 4 re-solves give the
  // refactorizing oracle's break sequence and lives (to round-off), and the tie changes the run
  // (without it the lives differ).
  const auto plate = make_notched_plate(GetParam());
  const double h = 0.008;
  const mesh::NodeIndex left = plate.disc.nearest_node({0.0, h});
  const mesh::NodeIndex right = plate.disc.nearest_node({0.024, h});
  const std::vector<statics::Tie> ties = {{{{left, 0, 1.0}, {right, 0, -1.0}}, 1e12}};
  auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  fatigue::FatigueEngine refactor(plate.disc, plate.model, plate.supports, plate.loads, settings,
                                  ties);
  fatigue::FatigueEngine untied(plate.disc, plate.model, plate.supports, plate.loads, settings);
  settings.incremental = true;
  settings.refactor_every_resolves = 4;
  fatigue::FatigueEngine incremental(plate.disc, plate.model, plate.supports, plate.loads, settings,
                                     ties);
  for (auto* e : {&refactor, &untied, &incremental}) {
    ASSERT_TRUE(e->initialize());
    e->apply({1000.0, 0.1, 0.3, 800});
  }
  testing::expect_same_breaks(refactor, incremental);
  EXPECT_GT(incremental.rebuilds(), 0);
  const auto a = refactor.remaining_life();
  const auto b = incremental.remaining_life();
  const auto c = untied.remaining_life();
  double tie_effect = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a[i], b[i], 1e-9);
    tie_effect = std::max(tie_effect, std::abs(a[i] - c[i]));
  }
  EXPECT_GT(refactor.broken_bonds(), 20);
  EXPECT_GT(tie_effect, 1e-3);
}

INSTANTIATE_TEST_SUITE_P(BothModels, IncrementalEqualsRefactor,
                         ::testing::Values(model::ModelKind::bond_based,
                                           model::ModelKind::state_based),
                         testing::model_kind_param_name);

}  // namespace
}  // namespace peritwin

namespace peritwin {
namespace {

TEST(Phases, PreCrackPutsItsTipInPhaseTwoAndFarBondsInPhaseOne) {
  // 000 Sec. 4.4: the nodes along a cut have φ ≥ φ0 = 0.398 (0.409 in the interior for
  // δ = 3.015Δx with the partial volumes of 001 Eq. (36), more near a free edge), so the
  // pre-crack's neighbourhood is in phase II from the start; a bond far from it (more than 2δ) is
  // in phase I.
  const auto plate = make_notched_plate(model::ModelKind::bond_based);
  const auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  fatigue::FatigueEngine engine(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(engine.initialize());
  const double dx = plate.disc.dx;
  const mesh::NodeIndex face = plate.disc.nearest_node({3 * dx, 0.5 * dx});
  EXPECT_GE(engine.node_damage()[static_cast<std::size_t>(face)], 0.398);
  for (mesh::BondIndex b = 0; b < plate.disc.num_bonds(); ++b) {
    const mesh::Point a = plate.disc.position[plate.disc.bond_i[b]];
    const mesh::Point c = plate.disc.position[plate.disc.bond_j[b]];
    const double mid_x = 0.5 * (a.x + c.x), mid_y = 0.5 * (a.y + c.y);
    if (std::abs(mid_y) < dx && mid_x < 6 * dx) {
      EXPECT_EQ(engine.bond_phase()[b], 2) << b;
    }
    if (mid_x > 6 * dx + 3 * plate.disc.horizon) {
      EXPECT_EQ(engine.bond_phase()[b], 1) << b;
    }
  }
}

TEST(NoFailZone, BondsInsideNeverBreak) {
  // 002 Sec. 7: a no-fail zone around the notch tip: its bonds keep losing life but never break,
  // while the same load breaks them without the zone.
  auto plate = make_notched_plate(model::ModelKind::bond_based);
  const auto settings = settings_for(plate, fatigue::FatigueLaw::strain_range, 1000.0, 0.1, 150.0);
  const mesh::Circle zone{{6 * plate.disc.dx, 0.0}, 4 * plate.disc.dx};
  for (mesh::NodeIndex k = 0; k < plate.disc.num_nodes(); ++k) {
    plate.disc.no_fail[static_cast<std::size_t>(k)] = zone.contains(plate.disc.position[k]) ? 1 : 0;
  }
  fatigue::FatigueEngine engine(plate.disc, plate.model, plate.supports, plate.loads, settings);
  ASSERT_TRUE(engine.initialize());
  engine.apply({1000.0, 0.1, 0.0, 1000});  // the phase II tip bonds last 750 cycles
  for (const auto& e : engine.break_events()) {
    const auto i = static_cast<std::size_t>(plate.disc.bond_i[e.bond]);
    const auto j = static_cast<std::size_t>(plate.disc.bond_j[e.bond]);
    EXPECT_FALSE(plate.disc.no_fail[i] || plate.disc.no_fail[j]) << "bond " << e.bond;
  }
  const auto lives = engine.remaining_life();
  EXPECT_LT(*std::min_element(lives.begin(), lives.end()), 0.0);  // protected bonds went past 0
}

}  // namespace
}  // namespace peritwin
