// Remaining life: rolling spectrum, forward simulation, band, synchronous estimates.
#include <cmath>

#include "tests/support/twin_fixtures.h"
#include "twin/coarse_life.h"
#include "twin/life.h"
#include "validation/b1_compact_tension.h"

namespace peritwin::twin {
namespace {

/// Coarse (1.5 mm) over fine (1 mm) central life on B1 at 28 000 cycles (4.2 mm of 8 grown):
/// measured 0.80 (8256 against 10373 cycles), conservative: the calibration window starts where
/// the mapped coarse crack is short and its fresh bond lives make it slow (docs/design.md).
constexpr double kCoarseTolerance = 0.25;
/// PD remaining life over the Paris integral with the ASTM E647 K (000 Eq. A2, A4): measured 0.82
/// fine and 0.65 coarse; the fine A2 is calibrated to the whole life at 4 kN, not to each stretch
/// of it.
constexpr double kParisTolerance = 0.40;

using testing::b1_config;
using testing::b1_model;
using testing::batch;
using testing::make_twin;

TEST(RollingSpectrum, MergesConsecutiveAndRolls) {
  twin::RollingSpectrum s;
  s.add({4000, 0.1, 0, 10});
  s.add({4000, 0.1, 0, 5});
  s.add({3000, 0.1, 0, 1});
  s.add({4000, 0.1, 0, 2});
  ASSERT_EQ(s.blocks().size(), 3u);
  EXPECT_EQ(s.blocks()[0].count, 15);
  const auto ref = s.reference();
  ASSERT_EQ(ref.size(), 2u);
  EXPECT_EQ(ref[0].p_max, 4000);
  EXPECT_EQ(ref[0].count, 17);
  EXPECT_EQ(ref[1].count, 1);
  for (int i = 0; i < 5000; ++i) s.add({1000.0 + i, 0.1, 0, 1});
  EXPECT_EQ(s.blocks().size(), twin::RollingSpectrum::kCapacity);
  EXPECT_EQ(s.blocks().front().p_max, 1000.0 + 5000 - twin::RollingSpectrum::kCapacity);
}

TEST(RollingSpectrum, ManyLevelsAreGroupedConservatively) {
  twin::RollingSpectrum s;
  for (int i = 0; i < 100; ++i) s.add({1000.0 + 10 * i, 0.0, 0, 3});
  const auto ref = s.reference();
  EXPECT_LE(ref.size(), twin::RollingSpectrum::kMaxLevels);
  std::int64_t total = 0;
  for (const auto& b : ref) total += b.count;
  EXPECT_EQ(total, 300);
  EXPECT_EQ(ref.back().p_max, 1990.0);  // the largest range represents the top group
  for (std::size_t i = 1; i < ref.size(); ++i) EXPECT_GT(ref[i].p_max, ref[i - 1].p_max);
}

class LifeTest : public ::testing::Test {
 public:
  static std::shared_ptr<const twin::DetailModel> no_band_model() {
    return b1_model(b1_config("every_batches = 2",
                              {{"critical_crack_length = 0.008", "critical_crack_length = 0.002"},
                               {"band = \"a2_scatter\"", "band = \"none\""},
                               {"a2_relative_scatter = 0.2", ""}}));
  }

 protected:
  // A short critical crack length keeps the forward simulations to a few dozen re-solves.
  static void SetUpTestSuite() {
    model_ = b1_model(b1_config(
        "every_batches = 2", {{"critical_crack_length = 0.008", "critical_crack_length = 0.002"}}));
  }
  static void TearDownTestSuite() { model_.reset(); }
  static std::shared_ptr<const twin::DetailModel> model_;
};
std::shared_ptr<const twin::DetailModel> LifeTest::model_;

TEST_F(LifeTest, ForwardSimulationIsExactAndDeterministic) {
  auto twin = make_twin(model_, twin::LifeMode::external);
  const twin::LifeJob job = twin->life_job();
  ASSERT_EQ(job.spectrum.size(), 1u);  // the configured reference spectrum
  const double a = twin::simulate_life(*model_, job.state, job.spectrum, 1.0);
  const double b = twin::simulate_life(*model_, job.state, job.spectrum, 1.0);
  ASSERT_TRUE(std::isfinite(a));
  EXPECT_GT(a, 0.0);
  EXPECT_EQ(a, b);
  // Applying exactly that many cycles of the reference reaches the criterion; one fewer does not.
  const auto& ref = job.spectrum.front();
  const auto n = static_cast<std::int64_t>(a);
  auto before = make_twin(model_, twin::LifeMode::external);
  ASSERT_TRUE(before->apply(batch(1, {{ref.p_max, ref.r, ref.alpha, n - 1}})).applied());
  EXPECT_EQ(before->failure(), twin::Failure::none);
  ASSERT_TRUE(before->apply(batch(2, {{ref.p_max, ref.r, ref.alpha, 1}})).applied());
  EXPECT_EQ(before->failure(), twin::Failure::end_criterion);
  EXPECT_EQ(twin::simulate_life(*model_, before->engine().export_state(), job.spectrum, 1.0), 0.0);
  // An empty spectrum gives no estimate.
  EXPECT_TRUE(std::isnan(twin::simulate_life(*model_, job.state, {}, 1.0)));
}

TEST_F(LifeTest, BandFromA2Scatter) {
  auto twin = make_twin(model_, twin::LifeMode::external);
  const twin::LifeJob job = twin->life_job();
  const twin::LifeEstimate e = twin::estimate_life(*model_, job.state, job.spectrum, true);
  EXPECT_LE(e.low, e.central);
  EXPECT_LE(e.central, e.high);
  EXPECT_LT(e.low, e.high);
  // The band is the range of the runs with A2·(1 ± 0.2) and A2 itself. At a 2 mm crack on the
  // 1 mm grid the order of the three need not follow A2 (which bonds break first may change).
  const double plus = twin::simulate_life(*model_, job.state, job.spectrum, 1.2);
  const double minus = twin::simulate_life(*model_, job.state, job.spectrum, 0.8);
  EXPECT_EQ(e.low, std::min({plus, minus, e.central}));
  EXPECT_EQ(e.high, std::max({plus, minus, e.central}));
}

TEST_F(LifeTest, EstimatesForkedFromTheLiveEngineEqualRebuiltOnesBitForBit) {
  // A state 12 000 cycles into B1 (the crack grows from about 10 000: bonds broken, re-solves
  // recorded): the estimate from forks of the live engine (the synchronous twin's path), from
  // the job's snapshot fork (the worker's path) and from fresh engines that import the state (the
  // path before FatigueEngine::fork) are the same three numbers, bit for bit.
  auto twin = make_twin(model_, twin::LifeMode::external);
  ASSERT_TRUE(twin->apply(batch(1, {{4000, 0.1, 0, 12000}})).applied());
  const twin::LifeJob job = twin->life_job();
  ASSERT_GT(job.state.resolve_groups.size(), 0u);
  ASSERT_NE(job.engine, nullptr);
  EXPECT_EQ(job.engine->state_hash(), twin->engine_hash());
  std::vector<twin::SimulationStats> forked_stats, rebuilt_stats;
  const twin::LifeEstimate rebuilt =
      twin::estimate_life(*model_, job.state, job.spectrum, true, nullptr, nullptr, &rebuilt_stats);
  const twin::LifeEstimate forked = twin::estimate_life(*model_, job.state, job.spectrum, true,
                                                        nullptr, &twin->engine(), &forked_stats);
  const twin::LifeEstimate snapshot =
      twin::estimate_life(*model_, job.state, job.spectrum, false, nullptr, job.engine.get());
  ASSERT_TRUE(std::isfinite(rebuilt.central));
  EXPECT_GT(rebuilt.central, 0.0);
  for (const twin::LifeEstimate* e : {&forked, &snapshot}) {
    EXPECT_EQ(e->central, rebuilt.central);
    EXPECT_EQ(e->low, rebuilt.low);
    EXPECT_EQ(e->high, rebuilt.high);
    EXPECT_TRUE(e->forked);
    EXPECT_EQ(e->start_cycles, 12000);
  }
  EXPECT_FALSE(rebuilt.forked);
  // Which path each took: a fork builds and imports nothing, a fresh engine copies nothing; both
  // broke the same bonds on the way.
  ASSERT_EQ(forked_stats.size(), 3u);
  ASSERT_EQ(rebuilt_stats.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(forked_stats[i].build_s, 0.0);
    EXPECT_EQ(forked_stats[i].import_s, 0.0);
    EXPECT_GT(rebuilt_stats[i].build_s, 0.0);
    EXPECT_EQ(rebuilt_stats[i].fork_s, 0.0);
    EXPECT_EQ(forked_stats[i].breaks, rebuilt_stats[i].breaks);
    EXPECT_GT(forked_stats[i].breaks, 0);
  }
  // The live twin is untouched by its forks.
  EXPECT_EQ(twin->engine().total_cycles(), 12000);
  EXPECT_EQ(twin->engine_hash(), job.engine->state_hash());
}

TEST_F(LifeTest, SynchronousEstimatesAtFixedPointsFall) {
  auto twin = make_twin(no_band_model(), twin::LifeMode::synchronous);
  twin->catch_up_life();  // state 0 is a fixed point
  EXPECT_EQ(twin->life().state_seq, 0);
  EXPECT_EQ(twin->life().seq, -1);
  const double at0 = twin->life().central;
  ASSERT_TRUE(std::isfinite(at0));
  ASSERT_TRUE(twin->apply(batch(1, {{4000, 0.1, 0, 2000}})).applied());
  EXPECT_EQ(twin->life().state_seq, 0);  // not a fixed point: the estimate lags
  ASSERT_TRUE(twin->apply(batch(2, {{4000, 0.1, 0, 2000}})).applied());
  EXPECT_EQ(twin->life().state_seq, 2);
  EXPECT_EQ(twin->life().seq, 2);
  EXPECT_EQ(twin->life().source, "test");
  // Under the reference load itself the estimate falls by the cycles applied (exactly, unless a
  // bond broke differently, which the same load cannot cause).
  EXPECT_EQ(twin->life().central, at0 - 4000);
}

TEST_F(LifeTest, EveryCyclesEstimatesWhereABatchPassesAMultipleOfItsCycles) {
  // every_cycles = 5000 alone, batches of 700 cycles: estimates at state 0 and at the states
  // whose batch took the count past 5000, 10000, ... (700 k crosses 5000 m at k = 8, 15, 22).
  auto model =
      b1_model(b1_config("every_batches = 0\nevery_cycles = 5000",
                         {{"critical_crack_length = 0.008", "critical_crack_length = 0.002"},
                          {"band = \"a2_scatter\"", "band = \"none\""},
                          {"a2_relative_scatter = 0.2", ""}}));
  ASSERT_TRUE(model);
  ASSERT_EQ(model->config().life.every_cycles, 5000);
  auto twin = make_twin(model, twin::LifeMode::synchronous);
  twin->catch_up_life();
  EXPECT_EQ(twin->life().state_seq, 0);
  std::vector<std::int64_t> estimated_at;
  for (std::int64_t s = 1; s <= 22; ++s) {
    ASSERT_TRUE(twin->apply(batch(s, {{4000, 0.1, 0, 700}})).applied());
    if (twin->life().state_seq == s) estimated_at.push_back(s);
  }
  EXPECT_EQ(estimated_at, (std::vector<std::int64_t>{8, 15, 22}));
}

// The coarser estimate model ([detail.life] dx, twin/coarse_life.h) on B1: the fine model is
// the demo grid (1 mm), the state 28 000 cycles in (the crack has grown several mm of its 8).
class CoarseLifeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fine_ = b1_model(b1_config("every_batches = 0", {{"band = \"a2_scatter\"", "band = \"none\""},
                                                     {"a2_relative_scatter = 0.2", ""}}));
    twin_ = make_twin(fine_, twin::LifeMode::external).release();
    ASSERT_TRUE(twin_->apply(batch(1, {{4000, 0.1, 0, 28000}})).applied());
    ASSERT_EQ(twin_->failure(), twin::Failure::none);
  }
  static void TearDownTestSuite() {
    delete twin_;
    fine_.reset();
  }
  static std::shared_ptr<const twin::DetailModel> fine_;
  static twin::Twin* twin_;
};
std::shared_ptr<const twin::DetailModel> CoarseLifeTest::fine_;
twin::Twin* CoarseLifeTest::twin_ = nullptr;

TEST_F(CoarseLifeTest, MappedCrackCutsTheCoarseBondsAcrossTheFinePath) {
  // B1's crack grows along y = 0 from the notch tip at x = 27.5 mm (mode I), locally stepping to
  // the next row of nodes and back. The mapped coarse bonds (dx 2 mm) must all cross y = 0
  // between the notch tip and the fine crack's tip (plus one fine facet), and most coarse bonds
  // crossing y = 0 inside that stretch must be among them — not all: where the fine crack runs a
  // row off y = 0 for a few mm, neither row's facets are open (the longer fine bonds across them
  // are intact) and the coarse bonds there stay (measured: 8 of 26 at 28 000 cycles). An
  // independent geometric check of the facet rule.
  const fatigue::EngineState state = twin_->engine().export_state();
  auto coarse = twin::coarse_model(*fine_, 0.002);
  ASSERT_TRUE(coarse.ok());
  const mesh::Discretization& c = (*coarse)->disc();
  const mesh::Discretization& f = fine_->disc();
  double tip = 0.0;  // the fine crack's farthest broken nearest-neighbour bond's x
  for (std::size_t b = 0; b < state.intact.size(); ++b) {
    if (state.intact[b] || f.bond_precut[b] || f.bond_length[b] > 1.2 * f.dx) continue;
    tip = std::max(tip, 0.5 * (f.position[static_cast<std::size_t>(f.bond_i[b])].x +
                               f.position[static_cast<std::size_t>(f.bond_j[b])].x));
  }
  ASSERT_GT(tip, 0.0275 + 2 * c.dx);  // a crack several coarse spacings long
  const auto mapped = twin::map_crack(f, state.intact, c);
  std::vector<std::uint8_t> is_mapped(static_cast<std::size_t>(c.num_bonds()), 0);
  for (mesh::BondIndex b : mapped) is_mapped[static_cast<std::size_t>(b)] = 1;
  int crossing = 0, unmapped = 0;
  for (std::size_t b = 0; b < is_mapped.size(); ++b) {
    const mesh::Point p = c.position[static_cast<std::size_t>(c.bond_i[b])];
    const mesh::Point q = c.position[static_cast<std::size_t>(c.bond_j[b])];
    const bool across = (p.y < 0) != (q.y < 0);
    const double x = across ? p.x + (q.x - p.x) * (0 - p.y) / (q.y - p.y) : 0.0;  // at y = 0
    if (is_mapped[b]) {
      EXPECT_TRUE(across) << "bond " << b;
      EXPECT_GE(x, 0.0275 - f.dx) << "bond " << b;
      EXPECT_LE(x, tip + f.dx) << "bond " << b;
      EXPECT_FALSE(c.bond_precut[b]);
    } else if (across && !c.bond_precut[b] && x > 0.0275 + f.dx && x < tip - f.dx) {
      ++unmapped;
    }
    if (across && !c.bond_precut[b] && x > 0.0275 + f.dx && x < tip - f.dx) ++crossing;
  }
  EXPECT_GT(crossing, 10);
  EXPECT_LE(unmapped, crossing / 3) << unmapped << " of " << crossing << " unmapped";
}

TEST_F(CoarseLifeTest, CalibratedCoarseEstimateMatchesTheFineOneAndParis) {
  const fatigue::EngineState state = twin_->engine().export_state();
  const std::vector<core::LoadBlock> spectrum = fine_->config().life.reference_spectrum;
  const twin::LifeEstimate fine =
      twin::estimate_life(*fine_, state, spectrum, true, nullptr, &twin_->engine());
  twin::CoarseLifeReport rep;
  const twin::LifeEstimate coarse =
      twin::estimate_life_coarse(*fine_, 0.0015, state, spectrum, true, nullptr, &rep);
  ASSERT_TRUE(std::isfinite(fine.central));
  ASSERT_TRUE(std::isfinite(coarse.central));
  EXPECT_TRUE(coarse.coarse);
  EXPECT_TRUE(rep.calibrated);
  EXPECT_GT(rep.mapped_bonds, 0);
  EXPECT_GT(rep.window_growth, 0.0);
  // Calibrated: the coarse model grows the window's crack in the fine model's cycles (2 %, the
  // calibration's own stopping rule, or its third correction unchecked: 10 %).
  EXPECT_NEAR(rep.coarse_window_cycles / rep.fine_window_cycles, 1.0, 0.10);
  // The estimate on the coarse grid against the fine one (tolerance: see docs/benchmarks.md).
  EXPECT_NEAR(coarse.central / fine.central, 1.0, kCoarseTolerance);
  // Both against the Paris law integrated with the ASTM E647 K (000 Eq. A2, A4) from the fine
  // crack's current length to the criterion (a0 + 8 mm), the law the fine A2 was calibrated to.
  const validation::CompactTensionSpec spec;
  const validation::ParisLaw paris;
  const double a0 = spec.initial_crack;
  const double a_now = a0 + rep.fine_length;
  const double a_end = a0 + 0.008;
  const double paris_remaining = validation::paris_life(spec, paris, 4000, 0.1, a_end) -
                                 validation::paris_life(spec, paris, 4000, 0.1, a_now);
  EXPECT_NEAR(fine.central / paris_remaining, 1.0, kParisTolerance);
  EXPECT_NEAR(coarse.central / paris_remaining, 1.0, kParisTolerance);
  std::printf(
      "fine %.0f coarse %.0f paris %.0f (a_now %.4f, a2 factor %.4f, window %.4f m %.0f c)\n",
      fine.central, coarse.central, paris_remaining, a_now, rep.a2_factor, rep.window_growth,
      rep.fine_window_cycles);
}

}  // namespace
}  // namespace peritwin::twin
