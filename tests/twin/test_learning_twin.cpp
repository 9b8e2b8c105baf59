// Issue 32: the twin that learns (twin/twin.h "Learning"): observations taken in exactly once per
// source and seq, refused with the field and the reason and the state unchanged, the ensemble in
// the checkpoint (restore and go on: the bits of never stopping), the percentiles and the
// observations in STATE and through its checked decoder. B1 at Δx = 2 mm with 6 particles.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "messages/codec.h"
#include "outputs/detail_outputs.h"
#include "outputs/results_writer.h"
#include "tests/support/twin_fixtures.h"
#include "twin/messages_io.h"
#include "twin/twin.h"

namespace peritwin::twin {
namespace {

std::shared_ptr<const DetailModel> learning_b1(const std::string& extra = "",
                                               const std::string& results_dir = "") {
  std::string text = testing::b1_text("every_batches = 0", {{"dx = 0.001 ", "dx = 0.002 "}});
  text +=
      "\n[detail.uncertainty]\nparticles = 6\nseed = 11\na2 = { median = 1301.0, cov = 0.3 }\n"
      "load_scale = { median = 1.0, cov = 0.05 }\nhorizon_cycles = 5000\n" +
      extra;
  auto parsed = config::parse_config(text, "b1-learning.toml");
  EXPECT_TRUE(parsed.ok()) << parsed.error_text();
  auto detail = parsed.config->details.at(0);
  if (!results_dir.empty()) {
    detail.output.directory = results_dir;
    detail.output.png = false;
  }
  return testing::b1_model(detail);
}

messages::Observation observation(std::int64_t seq, std::int64_t cycle, double length,
                                  const std::string& source = "ndt") {
  messages::Observation o;
  o.detail_id = "b1-ct";
  o.source_id = source;
  o.seq = seq;
  o.cycle = cycle;
  o.kind = messages::ObservationKind::crack_length;
  o.length_m = length;
  o.sigma_m = 0.0005;
  return o;
}

void apply(Twin& t, std::int64_t seq, std::int64_t cycles) {
  const auto o = t.apply(testing::batch(seq, {{4000, 0.1, 0, cycles}}));
  ASSERT_TRUE(o.applied()) << o.what << ": " << o.why;
}

TEST(LearningTwin, ObservationsAreTakenInOncePerSourceAndSeqAndRefusalsChangeNothing) {
  const auto model = learning_b1();
  auto t = testing::make_twin(model);
  ASSERT_TRUE(t && t->ensemble());
  // The prior's percentiles at state 0: simulated, increasing.
  const auto prior = t->ensemble_estimate();
  ASSERT_TRUE(prior);
  EXPECT_EQ(t->ensemble()->estimate_cycle(), 0);
  ASSERT_EQ(prior->end_of_life.size(), 3u);
  EXPECT_GT(prior->end_of_life[0], 0.0);
  EXPECT_LE(prior->end_of_life[0], prior->end_of_life[1]);
  EXPECT_LE(prior->end_of_life[1], prior->end_of_life[2]);
  for (int k = 1; k <= 24; ++k) apply(*t, k, 1000);
  const std::string before = t->state_hash_hex();
  const std::string engine_before = core::hex64(t->engine_hash());

  struct Case {
    messages::Observation o;
    messages::Verdict verdict;
    std::string what;
  };
  std::vector<Case> refused;
  refused.push_back({observation(2, 20000, 0.002), messages::Verdict::gap, "observation.seq"});
  refused.push_back(
      {observation(1, 30000, 0.002), messages::Verdict::invalid, "observation.cycle"});
  refused.push_back(
      {observation(1, 20000, -0.001), messages::Verdict::invalid, "observation.length_m"});
  auto hole = observation(1, 20000, 0.002);
  hole.origin = "hole 0";
  refused.push_back({hole, messages::Verdict::invalid, "observation.origin"});
  auto other = observation(1, 20000, 0.002);
  other.detail_id = "b2-cts";
  refused.push_back({other, messages::Verdict::wrong_detail, "observation.detail_id"});
  auto nameless = observation(1, 20000, 0.002, "");
  refused.push_back({nameless, messages::Verdict::invalid, "observation.source_id"});
  for (const auto& c : refused) {
    const auto out = t->observe(c.o);
    EXPECT_EQ(out.verdict, c.verdict) << c.what << ": " << out.why;
    EXPECT_EQ(out.what, c.what) << out.why;
    EXPECT_FALSE(out.why.empty());
    EXPECT_EQ(t->state_hash_hex(), before) << c.what;
  }
  EXPECT_TRUE(t->observed().empty());

  // Taken in: the state moves (not the engine), the STATE lists it; the same again is a duplicate.
  const auto first = observation(1, 20000, 0.002);
  ASSERT_TRUE(t->observe(first).applied());
  EXPECT_NE(t->state_hash_hex(), before);
  EXPECT_EQ(core::hex64(t->engine_hash()), engine_before);
  EXPECT_EQ(t->observed().at("ndt"), 1);
  EXPECT_EQ(t->ensemble()->estimate_cycle(), 24000);
  const std::string after = t->state_hash_hex();
  const auto again = t->observe(first);
  EXPECT_EQ(again.verdict, messages::Verdict::duplicate);
  EXPECT_EQ(t->state_hash_hex(), after);
  // Another source has a sequence of its own.
  ASSERT_TRUE(t->observe(observation(1, 24000, 0.003, "gauge-team")).applied());

  const auto m = state_message(*t, 0);
  EXPECT_EQ(m.num_particles, 6);
  EXPECT_EQ(m.ensemble_estimate_cycle, 24000);
  ASSERT_EQ(m.num_percentiles, 3);
  EXPECT_EQ(m.percentiles, (std::vector<double>{5, 50, 95}));
  for (int k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(
        m.remaining_percentiles[static_cast<std::size_t>(k)],
        std::max(0.0, m.end_of_life_percentiles[static_cast<std::size_t>(k)] - 24000.0));
  }
  EXPECT_EQ(m.horizon_cycles, 5000.0);
  EXPECT_GE(m.probability_within_horizon, 0.0);
  EXPECT_LE(m.probability_within_horizon, 1.0);
  ASSERT_EQ(m.num_parameters, 2);
  EXPECT_EQ(m.parameter_names[0], "a2");
  EXPECT_EQ(m.observation_count, 2);
  ASSERT_EQ(m.num_observations, 2);
  EXPECT_EQ(m.observation_cycles, (std::vector<std::int64_t>{20000, 24000}));
  EXPECT_EQ(m.observation_lengths_m[0], 0.002);
  EXPECT_TRUE(std::isnan(m.observation_pod_a50s_m[0]));
  ASSERT_EQ(m.num_observation_sources, 2);
  EXPECT_EQ(m.observation_source_ids, (std::vector<std::string>{"gauge-team", "ndt"}));
  EXPECT_EQ(m.observation_applied_seq, (std::vector<std::int64_t>{1, 1}));
  // The JSON lines of the tools (state_json, summary_json) carry the same.
  for (const std::string& line : {messages::state_json(m), messages::summary_json(m)}) {
    const auto j = nlohmann::json::parse(line);
    EXPECT_EQ(j["observations"], 2) << line;
    EXPECT_EQ(j["end_of_life_percentiles"]["p50"], std::llround(m.end_of_life_percentiles[1]));
    EXPECT_EQ(j["remaining_percentiles"]["p95"], std::llround(m.remaining_percentiles[2]));
    EXPECT_EQ(j["posterior"]["a2"]["median"], m.parameter_medians[0]);
  }
  // Through the wire and the checked decoder.
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  const auto decoded = messages::decode_state(bytes.data(), bytes.size());
  ASSERT_TRUE(decoded);
  EXPECT_EQ(decoded->observation_cycles, m.observation_cycles);
  EXPECT_EQ(decoded->end_of_life_percentiles, m.end_of_life_percentiles);
  EXPECT_EQ(decoded->state_hash, m.state_hash);
  for (std::size_t cut : {bytes.size() - 1, bytes.size() / 2, std::size_t{40}}) {
    EXPECT_FALSE(messages::decode_state(bytes.data(), cut)) << cut;
  }
}

// The learning twin in a checkpoint: restored into a new twin and fed the same batches and
// observations, it ends with the bits of the twin that never stopped.
TEST(LearningTwin, ACheckpointedEnsembleGoesOnBitForBit) {
  const auto model = learning_b1();
  auto a = testing::make_twin(model);
  ASSERT_TRUE(a);
  for (int k = 1; k <= 20; ++k) apply(*a, k, 1000);
  ASSERT_TRUE(a->observe(observation(1, 18000, 0.0015)).applied());
  const CheckpointData saved = a->to_checkpoint();
  auto b = testing::make_twin(model);
  ASSERT_TRUE(b);
  ASSERT_TRUE(b->restore(saved).ok());
  EXPECT_EQ(b->state_hash_hex(), a->state_hash_hex());
  for (auto* t : {a.get(), b.get()}) {
    for (int k = 21; k <= 28; ++k) apply(*t, k, 1000);
    ASSERT_TRUE(t->observe(observation(2, 28000, 0.003)).applied());
    apply(*t, 29, 1000);
  }
  EXPECT_EQ(b->state_hash_hex(), a->state_hash_hex());
  EXPECT_EQ(b->ensemble()->state_hash(), a->ensemble()->state_hash());
  const auto ea = a->ensemble_estimate(), eb = b->ensemble_estimate();
  EXPECT_EQ(ea->end_of_life, eb->end_of_life);
  EXPECT_EQ(b->ensemble()->observations().size(), 2u);
  // A checkpoint of a twin that does not learn cannot restore a learning one.
  auto plain = Twin::create(model, {LifeMode::synchronous, true, false});
  ASSERT_TRUE(plain.ok());
  auto c = testing::make_twin(model);
  const auto refused = c->restore((*plain)->to_checkpoint());
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message().find("ensemble_filter"), std::string::npos);
}

// An observation the physics contradicts — a crack shorter than one measured before — is taken in
// as measured (docs/prognostics.md: the engines never un-break a bond; it favours the particles
// that grew least): applied and recorded with the ensemble's prediction, longer than what was
// measured; the state moves, the engine does not.
TEST(LearningTwin, AShorterCrackThanOneMeasuredBeforeIsTakenInAsMeasured) {
  const auto model = learning_b1();
  auto a = testing::make_twin(model), b = testing::make_twin(model);
  ASSERT_TRUE(a && b);
  for (auto* t : {a.get(), b.get()}) {
    for (int k = 1; k <= 26; ++k) apply(*t, k, 1000);
    ASSERT_TRUE(t->observe(observation(1, 24000, 0.003)).applied());
  }
  const auto shorter = a->observe(observation(2, 26000, 0.0005));
  ASSERT_TRUE(shorter.applied()) << shorter.what << ": " << shorter.why;
  const auto& records = a->ensemble()->observations();
  ASSERT_EQ(records.size(), 2u);
  EXPECT_GT(records[1].update.predicted_median_m, 0.0005);
  EXPECT_NE(a->state_hash_hex(), b->state_hash_hex());
  EXPECT_EQ(a->engine_hash(), b->engine_hash());
}

// Batches cut otherwise give the same learning twin's engine and ensemble; the observations are
// taken in between the same cycles.
TEST(LearningTwin, TheSameLoadsAndObservationsInOtherBatchesGiveTheSameEnsemble) {
  const auto model = learning_b1();
  auto a = testing::make_twin(model), b = testing::make_twin(model);
  ASSERT_TRUE(a && b);
  for (int k = 1; k <= 16; ++k) apply(*a, k, 1000);
  apply(*b, 1, 10000);
  apply(*b, 2, 6000);
  for (auto* t : {a.get(), b.get()})
    ASSERT_TRUE(t->observe(observation(1, 16000, 0.001)).applied());
  for (int k = 17; k <= 24; ++k) apply(*a, k, 1000);
  apply(*b, 3, 8000);
  EXPECT_EQ(a->engine_hash(), b->engine_hash());
  EXPECT_EQ(a->ensemble()->state_hash(), b->ensemble()->state_hash());
}

// Issue 32 item 6: the results file (outputs::DetailOutputs, as the daemon and peritwin-replay
// --results write it) has, per recorded state, the ensemble's percentiles, P(horizon), ESS and
// posterior, and every observation taken in; an observation adds no time-series row; rewind_to
// drops both tables' rows after the state like the time series'.
TEST(LearningTwin, TheResultsFileHasTheEnsembleAndTheObservations) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("peritwin-learning-results-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const auto model = learning_b1("", dir.string());
  auto t = testing::make_twin(model);
  ASSERT_TRUE(t && t->ensemble());
  const auto h5 = dir / "b1-ct.h5";
  {
    outputs::DetailOutputs out(*t);
    for (int k = 1; k <= 8; ++k) {
      apply(*t, k, 1000);
      out.record(*t);
    }
    auto none = observation(1, 3000, std::nan(""));
    none.kind = messages::ObservationKind::no_crack;
    none.sigma_m = std::nan("");
    none.pod_a50_m = 0.005;
    none.pod_slope = 3.0;
    ASSERT_TRUE(t->observe(none).applied());
    out.record(*t);
    for (int k = 9; k <= 12; ++k) {
      apply(*t, k, 1000);
      out.record(*t);
    }
    ASSERT_TRUE(t->observe(observation(2, 12000, 0.002)).applied());
    out.record(*t);
    out.finish(*t);
  }
  // One time-series row per state (0 to 12), none more for the observations.
  const auto rows = outputs::read_time_series(h5);
  ASSERT_EQ(rows.size(), 13u);
  const auto ens = outputs::read_named_table(h5, "ensemble");
  ASSERT_EQ(ens.rows(), 15u);  // 13 states and 2 observations
  EXPECT_EQ(ens.attributes.at("percentiles"), "5,50,95");
  const auto estimate = t->ensemble_estimate();
  ASSERT_TRUE(estimate);
  const std::size_t last = ens.rows() - 1;
  EXPECT_EQ(ens.ints.at("state_seq")[last], 12);
  EXPECT_EQ(ens.ints.at("total_cycles")[last], 12000);
  EXPECT_EQ(ens.ints.at("estimate_cycle")[last], t->ensemble()->estimate_cycle());
  EXPECT_EQ(ens.ints.at("observation_count")[last], 2);
  EXPECT_EQ(ens.ints.at("particles")[last], 6);
  EXPECT_EQ(ens.ints.at("observation_count")[0], 0);
  const char* keys[] = {"p05", "p50", "p95"};
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(ens.doubles.at(std::string("end_of_life_") + keys[k])[last], estimate->end_of_life[k])
        << keys[k];
    EXPECT_EQ(ens.doubles.at(std::string("remaining_") + keys[k])[last], estimate->remaining[k])
        << keys[k];
  }
  EXPECT_EQ(ens.doubles.at("probability_within_horizon")[last],
            estimate->probability_within_horizon);
  EXPECT_EQ(ens.doubles.at("horizon_cycles")[last], 5000.0);
  EXPECT_EQ(ens.doubles.at("effective_sample_size")[last], estimate->effective_sample_size);
  ASSERT_FALSE(estimate->posterior.empty());
  for (const auto& p : estimate->posterior) {
    EXPECT_EQ(ens.doubles.at(p.name + "_median")[last], p.median) << p.name;
    EXPECT_EQ(ens.doubles.at(p.name + "_cov")[last], p.coefficient_of_variation) << p.name;
  }
  // The observations, in the order taken in, with what each did.
  const auto obs = outputs::read_named_table(h5, "observations");
  ASSERT_EQ(obs.rows(), 2u);
  const auto& records = t->ensemble()->observations();
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(obs.ints.at("index"), (std::vector<std::int64_t>{0, 1}));
  EXPECT_EQ(obs.ints.at("state_seq"), (std::vector<std::int64_t>{8, 12}));
  EXPECT_EQ(obs.ints.at("cycle"), (std::vector<std::int64_t>{3000, 12000}));
  EXPECT_EQ(obs.ints.at("taken_at"), (std::vector<std::int64_t>{8000, 12000}));
  EXPECT_EQ(obs.ints.at("kind"), (std::vector<std::int64_t>{2, 1}));
  EXPECT_EQ(obs.ints.at("seq"), (std::vector<std::int64_t>{1, 2}));
  EXPECT_EQ(obs.strings.at("origins"), (std::vector<std::string>{"longest"}));
  EXPECT_EQ(obs.ints.at("origin_index"), (std::vector<std::int64_t>{0, 0}));
  EXPECT_EQ(obs.strings.at("sources"), (std::vector<std::string>{"ndt"}));
  EXPECT_TRUE(std::isnan(obs.doubles.at("length_m")[0]));
  EXPECT_EQ(obs.doubles.at("length_m")[1], 0.002);
  EXPECT_EQ(obs.doubles.at("sigma_m")[1], 0.0005);
  EXPECT_EQ(obs.doubles.at("pod_a50_m")[0], 0.005);
  EXPECT_EQ(obs.doubles.at("pod_slope")[0], 3.0);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(obs.doubles.at("predicted_median_m")[i], records[i].update.predicted_median_m);
    EXPECT_EQ(obs.doubles.at("log_evidence")[i], records[i].update.log_evidence);
    EXPECT_EQ(obs.doubles.at("ess_before_resampling")[i], records[i].update.ess_before_resampling);
    EXPECT_EQ(obs.ints.at("resampled")[i], records[i].update.resampled ? 1 : 0);
  }
  // A resume from the checkpoint of state 10: the rows after it go, both tables' too.
  {
    outputs::ResultsWriter writer(h5);
    writer.rewind_to(10);
  }
  EXPECT_EQ(outputs::read_time_series(h5).size(), 11u);
  EXPECT_EQ(outputs::read_named_table(h5, "ensemble").rows(), 12u);  // states 0-10, 1 observation
  EXPECT_EQ(outputs::read_named_table(h5, "observations").rows(), 1u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace peritwin::twin
