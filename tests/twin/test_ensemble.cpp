// Issue 32: the learning ensemble (twin/ensemble.h) on B1 at Δx = 2 mm (about 930 nodes; A2 is
// not recalibrated for that grid: these tests check the ensemble, not the life). The filter's
// mathematics against closed-form and grid posteriors is tested in tests/prognostics.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "tests/support/twin_fixtures.h"
#include "twin/ensemble.h"

namespace peritwin::twin {
namespace {

/// B1 at Δx = 2 mm with `uncertainty` as its [detail.uncertainty] (the example's own prior, 64
/// particles, replaced).
std::shared_ptr<const DetailModel> coarse_b1(const std::string& uncertainty,
                                             testing::Edits edits = {}) {
  edits.insert(edits.begin(), {"dx = 0.001 ", "dx = 0.002 "});
  std::string text = testing::b1_text("every_batches = 0", edits);
  text += "\n[detail.uncertainty]\n" + uncertainty + "\n";
  auto parsed = config::parse_config(text, "b1-uncertain.toml");
  EXPECT_TRUE(parsed.ok()) << parsed.error_text();
  auto model = DetailModel::build(parsed.config->details.at(0));
  EXPECT_TRUE(model.ok());
  return *model;
}

std::unique_ptr<Ensemble> make(const std::shared_ptr<const DetailModel>& model) {
  auto e = Ensemble::create(model);
  EXPECT_TRUE(e.ok()) << (e.ok() ? "" : e.error().message());
  return e.ok() ? std::move(*e) : nullptr;
}

/// An inspection that measured `length` ± `sigma` of the longest crack at `cycle`.
messages::Observation crack(std::int64_t cycle, double length, double sigma) {
  messages::Observation o;
  o.cycle = cycle;
  o.kind = messages::ObservationKind::crack_length;
  o.length_m = length;
  o.sigma_m = sigma;
  return o;
}

const char* kPrior =
    "particles = 6\nseed = 3\na2 = { median = 1301.0, cov = 0.3 }\n"
    "load_scale = { median = 1.0, cov = 0.05 }\nhorizon_cycles = 5000";

// The same load in blocks of 1000 or of 4000 and 2000 cycles: every particle's engine, the
// parameters and the filter are the same bits (the engines' exact block stepping), and so is the
// estimate.
TEST(Ensemble, TheSameLoadInOtherBatchesGivesTheSameBits) {
  const auto model = coarse_b1(kPrior);
  auto a = make(model), b = make(model);
  ASSERT_TRUE(a && b);
  for (int k = 0; k < 12; ++k)
    ASSERT_TRUE(a->apply(std::vector<core::LoadBlock>{{4000, 0.1, 0, 1000}}).ok());
  ASSERT_TRUE(
      b->apply(std::vector<core::LoadBlock>{{4000, 0.1, 0, 4000}, {4000, 0.1, 0, 4000}}).ok());
  ASSERT_TRUE(
      b->apply(std::vector<core::LoadBlock>{{4000, 0.1, 0, 2000}, {4000, 0.1, 0, 2000}}).ok());
  EXPECT_EQ(a->total_cycles(), 12000);
  EXPECT_EQ(a->state_hash(), b->state_hash());
  const std::vector<core::LoadBlock> spectrum{{4000, 0.1, 0, 1000}};
  const EnsembleEstimate ea = a->estimate(spectrum), eb = b->estimate(spectrum);
  EXPECT_EQ(ea.end_of_life, eb.end_of_life);
  // Percentiles in order; remaining = end of life − cycle for particles still alive.
  ASSERT_EQ(ea.end_of_life.size(), 3u);
  EXPECT_LE(ea.end_of_life[0], ea.end_of_life[1]);
  EXPECT_LE(ea.end_of_life[1], ea.end_of_life[2]);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(ea.remaining[k], std::max(0.0, ea.end_of_life[k] - 12000.0));
  }
  ASSERT_EQ(ea.posterior.size(), 2u);
  EXPECT_EQ(ea.posterior[0].name, "a2");
  EXPECT_EQ(ea.posterior[1].name, "load_scale");
}

// The physics the filter relies on: at the same cycles a particle with a larger A2 or a larger
// load scale has grown a longer crack. An inspection that finds a longer crack than the ensemble
// predicts moves the posterior of A2 up, a shorter one down; each particle's weight follows its
// Gaussian likelihood.
TEST(Ensemble, AnInspectionMovesThePosteriorTheWayThePhysicsSays) {
  const char* prior = "particles = 8\nseed = 5\na2 = { median = 1301.0, cov = 0.3 }";
  const auto model = coarse_b1(prior);
  auto run = [&] {
    auto e = make(model);
    for (int k = 0; k < 30; ++k) {
      EXPECT_TRUE(e->apply(std::vector<core::LoadBlock>{{4000, 0.1, 0, 1000}}).ok());
    }
    return e;
  };
  auto e = run();
  ASSERT_TRUE(e);
  std::vector<std::pair<double, double>> a2_and_length;
  for (std::size_t i = 0; i < e->size(); ++i) {
    a2_and_length.emplace_back(e->a2_factor(i),
                               observed_crack_length(*model, e->engine(i), "longest"));
  }
  std::sort(a2_and_length.begin(), a2_and_length.end());
  // The node-based length grows with A2; the published (sub-grid) one lies within Δx/2 of it
  // (docs/design.md, "Sub-grid crack length"), so it may fall back by up to Δx/2 = 1 mm between
  // two particles whose cracks took other nodes.
  const double half_cell = 0.5 * model->disc().dx;
  for (std::size_t i = 1; i < a2_and_length.size(); ++i) {
    EXPECT_GE(a2_and_length[i].second, a2_and_length[i - 1].second - half_cell)
        << "A2 factor " << a2_and_length[i].first;
  }
  EXPECT_GT(a2_and_length.back().second, a2_and_length.front().second);
  double shortest = a2_and_length.front().second, longest = shortest;
  for (const auto& [a2, length] : a2_and_length) {
    shortest = std::min(shortest, length);
    longest = std::max(longest, length);
  }
  ASSERT_GT(longest, shortest) << "no spread of crack lengths to learn from";
  const double prior_median = e->estimate({{4000, 0.1, 0, 1000}}).posterior[0].median;

  const messages::Observation longer = crack(30000, longest, 0.25 * (longest - shortest));
  ASSERT_TRUE(e->observe(longer).ok());
  EXPECT_GT(e->estimate({{4000, 0.1, 0, 1000}}).posterior[0].median, prior_median);

  auto f = run();
  messages::Observation shorter = longer;
  shorter.length_m = shortest;
  ASSERT_TRUE(f->observe(shorter).ok());
  EXPECT_LT(f->estimate({{4000, 0.1, 0, 1000}}).posterior[0].median, prior_median);
}

// Observations the ensemble cannot take in are refused with the field and the reason, and
// change nothing.
TEST(Ensemble, AnObservationInTheFutureOrInvalidIsRefusedAndChangesNothing) {
  const auto model = coarse_b1(kPrior);
  auto e = make(model);
  ASSERT_TRUE(e);
  ASSERT_TRUE(e->apply(std::vector<core::LoadBlock>{{4000, 0.1, 0, 1000}}).ok());
  const std::uint64_t before = e->state_hash();
  const messages::Observation future = crack(2000, 0.001, 0.0002);
  auto r = e->observe(future);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().field, "cycle");
  EXPECT_NE(r.error().reason.find("future"), std::string::npos);
  messages::Observation bad = future;
  bad.cycle = 1000;
  bad.sigma_m = -1;
  r = e->observe(bad);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().field, "sigma_m");
  bad = crack(1000, 0.001, 0.0002);
  bad.origin = "hole 3";  // B1 has no hole
  r = e->observe(bad);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().field, "origin");
  EXPECT_EQ(e->state_hash(), before);
  // "No crack found" by a method that would have found any crack of this ensemble is taken in.
  messages::Observation none;
  none.cycle = 1000;
  none.kind = messages::ObservationKind::no_crack;
  none.pod_a50_m = 0.001;
  none.pod_slope = 3;
  EXPECT_TRUE(e->observe(none).ok());
}

// An inspection reported late (its cycle before the ensemble's) is compared with each particle's
// crack as it was at that cycle (its later breaks undone): the same predictions, evidence and
// weights, bit for bit, as when it is taken in at its own cycle. (No resampling here: that happens
// when the observation is taken in, on the particles as they are then.)
TEST(Ensemble, ALateObservationIsComparedWithTheCrackAtItsCycle) {
  const auto model = coarse_b1(
      "particles = 8\nseed = 7\na2 = { median = 1301.0, cov = 0.3 }\n"
      "resample_ess_fraction = 0.001");
  auto on_time = make(model), late = make(model);
  ASSERT_TRUE(on_time && late);
  for (int k = 0; k < 26; ++k) {
    ASSERT_TRUE(on_time->apply(std::vector<core::LoadBlock>{{4000, 0.1, 0, 1000}}).ok());
  }
  ASSERT_TRUE(late->apply(std::vector<core::LoadBlock>{{4000, 0.1, 0, 32000}}).ok());
  // The particles' cracks grew between 26,000 and 32,000 cycles: the late one sees other lengths
  // now, and the ones of 26,000 through its break history.
  double grew = 0.0;
  for (std::size_t i = 0; i < late->size(); ++i) {
    grew += observed_crack_length(*model, late->engine(i), "longest") -
            observed_crack_length(*model, on_time->engine(i), "longest");
    EXPECT_EQ(crack_length_at(*model, late->engine(i), 26000, "longest"),
              observed_crack_length(*model, on_time->engine(i), "longest"))
        << "particle " << i;
  }
  ASSERT_GT(grew, 0.0);
  const messages::Observation o = crack(26000, 0.004, 0.0005);
  auto a = on_time->observe(o);
  auto b = late->observe(o);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_FALSE(a->resampled);
  EXPECT_EQ(a->log_evidence, b->log_evidence);
  EXPECT_EQ(a->predicted_median_m, b->predicted_median_m);
  const auto wa = on_time->weights().weights(), wb = late->weights().weights();
  ASSERT_EQ(wa.size(), wb.size());
  for (std::size_t i = 0; i < wa.size(); ++i) EXPECT_EQ(wa[i], wb[i]) << i;
}

// Future loads from the empirical spectrum: each particle simulates its blocks in an order of its
// own (drawn from the seed, the cycle and the particle), the same on every call; from a reference
// spectrum, in the given order. Same particles, same spectrum: the ends of life differ.
TEST(Ensemble, TheEmpiricalSpectrumIsSimulatedInEachParticlesOwnBlockOrder) {
  const char* prior = "particles = 6\nseed = 4\na2 = { median = 1301.0, cov = 0.3 }";
  const std::string reference =
      "reference_spectrum = [{ p_max = 4000.0, r = 0.1, alpha = 0.0, count = 1000 }]";
  const auto empirical = coarse_b1(prior, {{reference, "# empirical"}});
  const auto fixed = coarse_b1(
      prior, {{reference,
               "reference_spectrum = [{ p_max = 6000.0, r = 0.1, alpha = 0.0, count = 3000 }, "
               "{ p_max = 3000.0, r = 0.1, alpha = 0.0, count = 3000 }, { p_max = 4500.0, r = "
               "0.5, alpha = 0.0, count = 3000 }]"}});
  ASSERT_TRUE(empirical->config().life.empirical_spectrum());
  const std::vector<core::LoadBlock> spectrum = fixed->config().life.reference_spectrum;
  auto a = make(empirical), b = make(fixed), c = make(empirical);
  ASSERT_TRUE(a && b && c);
  for (auto* e : {a.get(), b.get(), c.get()}) {
    ASSERT_TRUE(e->apply(std::vector<core::LoadBlock>{{4000, 0.1, 0, 12000}}).ok());
  }
  const auto ea = a->estimate(spectrum), eb = b->estimate(spectrum), ec = c->estimate(spectrum);
  EXPECT_EQ(ea.end_of_life, ec.end_of_life);  // deterministic
  int differ = 0;
  for (std::size_t k = 0; k < ea.end_of_life.size(); ++k) {
    EXPECT_TRUE(std::isfinite(ea.end_of_life[k]));
    differ += ea.end_of_life[k] != eb.end_of_life[k] ? 1 : 0;
  }
  EXPECT_GT(differ, 0) << "the block order changed no end of life";
}

}  // namespace
}  // namespace peritwin::twin
