// peritwin-fuzz-seeds DIR: writes the generated seeds of the fuzz corpus into DIR/<target>/:
// encoded load batches (batch, and inside LCM logs for lcm_log), samples (samples), states and
// rejects (state,
// reject; unsigned and signed with the fuzz targets' fixed key), a key file (key_file) and a tiny
// checkpoint (checkpoint). Deterministic (fixed utimes, fixed content): rerun it after a change of
// the message types or of the checkpoint layout and commit what changed (tests/fuzz/README.md).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "messages/auth.h"
#include "messages/channels.h"
#include "messages/codec.h"
#include "messages/mesh.h"
#include "outputs/checkpoint_io.h"

namespace fs = std::filesystem;
using peritwin::core::LoadBlock;

namespace {

// An unsigned batch, or one carrying `tag` (not a valid HMAC: the decoder only bounds it).
std::vector<std::uint8_t> encode(const peritwin::messages::Batch& batch,
                                 const std::vector<std::uint8_t>& tag = {}) {
  auto msg = peritwin::messages::batch_message(batch, 1'700'000'000'000'000);
  msg.tag_length = static_cast<std::int32_t>(tag.size());
  msg.auth_tag = tag;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

void write(const fs::path& file, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + file.string());
  std::printf("%s (%zu bytes)\n", file.c_str(), bytes.size());
}

// The batches of the seeds: valid ones of the demo's shape, edge values, invalid values (a
// well-formed payload whose check_batch rejects it).
std::vector<std::pair<std::string, peritwin::messages::Batch>> batches() {
  return {
      {"one-block", {"b1-ct", "replay", 1, {{4000.0, 0.1, 0.0, 1000}}}},
      {"three-blocks",
       {"b1-ct",
        "strain-gauge-3",
        42,
        {{4000.0, 0.1, 0.0, 3000}, {4400.0, -1.0, 0.785, 500}, {3000.0, 0.5, -0.2, 1}}}},
      {"long-ids",
       {std::string(32, 'd'),
        std::string(64, 's'),
        9'007'199'254'740'993,
        {{1e-3, -10.0, 0.0, 1}}}},
      {"max-count", {"b1-ct", "replay", 7, {{4000.0, 0.1, 0.0, std::int64_t{1} << 50}}}},
      {"invalid-values", {"b1-ct", "replay", 0, {{-1.0, 1.0, 0.0, 0}, {4000.0, 0.1, 0.0, -5}}}},
      {"no-blocks", {"b1-ct", "replay", 3, {}}},
  };
}

void batch_seeds(const fs::path& dir) {
  fs::create_directories(dir);
  for (const auto& [name, batch] : batches()) write(dir / (name + ".bin"), encode(batch));
  std::vector<std::uint8_t> tag(peritwin::messages::kAuthTagBytes);
  for (std::size_t i = 0; i < tag.size(); ++i) tag[i] = static_cast<std::uint8_t>(0xa5 ^ i);
  write(dir / "tagged.bin", encode(batches().front().second, tag));
}

template <typename Message>
std::vector<std::uint8_t> encode_message(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

/// load_samples_t seeds: evenly spaced, with times and angles, signed-looking, invalid values.
void samples_seeds(const fs::path& dir) {
  fs::create_directories(dir);
  const peritwin::messages::Samples even{
      "b1-ct", "gauge-1", 1, 12.5, 1e-4, {400.0, 4000.0, 400.0, 4000.0}, {}, {}};
  const peritwin::messages::Samples timed{
      "b1-ct", "gauge-1", 2, 0.0, 0.0, {400.0, 4000.0, 500.0}, {0.0, 0.01, 0.03}, {0.0, 0.1, 0.2}};
  const peritwin::messages::Samples invalid{"b1-ct", "gauge-1",  0,     0.0,
                                            -1.0,    {1.0, 2.0}, {1.0}, {}};
  write(dir / "even.bin", encode_message(peritwin::messages::samples_message(even, 1)));
  write(dir / "timed.bin", encode_message(peritwin::messages::samples_message(timed, 1)));
  write(dir / "invalid.bin", encode_message(peritwin::messages::samples_message(invalid, 1)));
  auto tagged = peritwin::messages::samples_message(even, 1);
  tagged.auth_tag.assign(peritwin::messages::kAuthTagBytes, 0xa5);
  tagged.tag_length = static_cast<std::int32_t>(tagged.auth_tag.size());
  write(dir / "tagged.bin", encode_message(tagged));
}

/// The fuzz targets' key (fuzz_state.cpp, fuzz_reject.cpp): bytes 1, 2, ..., 32.
peritwin::messages::AuthKey fuzz_key() {
  peritwin::messages::AuthKey key;
  std::iota(key.bytes.begin(), key.bytes.end(), std::uint8_t{1});
  return key;
}

void state_seeds(const fs::path& dir) {
  fs::create_directories(dir);
  peritwin_msgs::damage_state_t initial{};
  initial.utime = 1'700'000'000'000'000;
  initial.detail_id = "b1-ct";
  initial.remaining_cycles = initial.remaining_cycles_low = initial.remaining_cycles_high =
      std::numeric_limits<double>::quiet_NaN();
  initial.remaining_life_seq = -1;
  initial.state_hash = "0123456789abcdef";
  write(dir / "initial.bin", encode_message(initial));

  peritwin_msgs::damage_state_t s = initial;
  s.state_seq = 12;
  s.source_ids = {"gauge", "replay"};
  s.applied_seq = {3, 9};
  s.checkpointed_seq = {0, 8};
  s.history = {0, 0x2f6e1d0b9c4a8e57};
  s.history_start = {0, 1};
  s.num_sources = 2;
  s.total_cycles = 12000;
  s.broken_bonds = 36;
  s.max_damage = 0.41;
  peritwin_msgs::crack_t crack{};
  crack.notch_index = 0;
  crack.origin_x = 0.0275;
  crack.tip_x = 0.0285;
  crack.length_m = crack.projected_length_m = 0.001;
  crack.num_nodes = 4;
  crack.phase = peritwin_msgs::crack_t::PHASE_PROPAGATION;
  s.cracks = {crack};
  s.num_cracks = 1;
  s.k_i = 5.2e6;
  s.k_ii = 0.0;
  s.remaining_cycles = 48000;
  s.remaining_cycles_low = 40000;
  s.remaining_cycles_high = std::numeric_limits<double>::infinity();
  s.remaining_life_seq = 10;
  s.remaining_life_source = "replay";
  s.echo_source = "replay";
  s.echo_nonce = 0x1d5c9e0b7a3f4260;
  write(dir / "two-sources.bin", encode_message(s));
  // A learning twin's state (message set version 9): percentiles, posterior, observations.
  peritwin_msgs::damage_state_t learning = s;
  learning.num_particles = 64;
  learning.ensemble_estimate_cycle = 12000;
  learning.effective_sample_size = 40.5;
  learning.percentiles = {5, 50, 95};
  learning.end_of_life_percentiles = {30000, 39000, 47000};
  learning.remaining_percentiles = {18000, 27000, 35000};
  learning.num_percentiles = 3;
  learning.horizon_cycles = 10000;
  learning.probability_within_horizon = 0.02;
  learning.parameter_names = {"a2", "load_scale"};
  learning.parameter_medians = {1301.0, 1.0};
  learning.parameter_covs = {0.2, 0.05};
  learning.num_parameters = 2;
  learning.observation_count = 1;
  learning.observation_cycles = {8000};
  learning.observation_kinds = {2};
  learning.observation_lengths_m = {std::numeric_limits<double>::quiet_NaN()};
  learning.observation_sigmas_m = {std::numeric_limits<double>::quiet_NaN()};
  learning.observation_pod_a50s_m = {0.001};
  learning.observation_predicted_m = {0.0};
  learning.num_observations = 1;
  learning.observation_source_ids = {"ndt"};
  learning.observation_applied_seq = {1};
  learning.num_observation_sources = 1;
  write(dir / "learning.bin", encode_message(learning));
  peritwin::messages::sign(s, fuzz_key());
  write(dir / "signed.bin", encode_message(s));
}

// Observations (issue 32): a crack measured, none found (signed), one of another detail.
void observation_seeds(const fs::path& dir) {
  fs::create_directories(dir);
  peritwin::messages::Observation o;
  o.detail_id = "b1-ct";
  o.source_id = "ndt";
  o.seq = 1;
  o.nonce = 0x1d5c9e0b7a3f4260;
  o.cycle = 20000;
  o.length_m = 0.0018;
  o.sigma_m = 0.0003;
  write(dir / "crack.bin", encode_message(peritwin::messages::observation_message(o, 1)));
  peritwin::messages::Observation none = o;
  none.seq = 2;
  none.kind = peritwin::messages::ObservationKind::no_crack;
  none.length_m = none.sigma_m = std::numeric_limits<double>::quiet_NaN();
  none.pod_a50_m = 0.001;
  none.pod_slope = 3;
  auto signed_none = peritwin::messages::observation_message(none, 1);
  peritwin::messages::sign(signed_none, fuzz_key());
  write(dir / "no-crack-signed.bin", encode_message(signed_none));
  peritwin::messages::Observation other = o;
  other.detail_id = "b2-cts";
  other.origin = "hole 0";
  write(dir / "other-detail.bin",
        encode_message(peritwin::messages::observation_message(other, 1)));
}

void reject_seeds(const fs::path& dir) {
  fs::create_directories(dir);
  peritwin::messages::Outcome why{peritwin::messages::Verdict::invalid, "blocks[3].r",
                                  "r = 1.2 must be < 1"};
  auto r = peritwin::messages::reject_message("b1-ct", "replay", 7, why, 1'700'000'000'000'000,
                                              0x1d5c9e0b7a3f4260);
  write(dir / "invalid.bin", encode_message(r));
  peritwin::messages::sign(r, fuzz_key());
  write(dir / "signed.bin", encode_message(r));
  write(dir / "undecodable.bin",
        encode_message(peritwin::messages::reject_message(
            "b1-ct", "", -1, {peritwin::messages::Verdict::decode, "message", "truncated"}, 0)));
}

// A mesh of one chunk (a 12 x 8 grid with its outline, a hole and a notch), a chunk of a
// two-chunk mesh, and a mesh request.
void mesh_seeds(const fs::path& dir) {
  fs::create_directories(dir);
  peritwin::messages::Mesh mesh;
  mesh.detail_id = "b1-ct";
  mesh.dx = 1e-3;
  mesh.horizon = 3.015e-3;
  mesh.x_max = 0.012;
  mesh.y_max = 0.008;
  for (int j = 0; j < 8; ++j) {
    for (int i = 0; i < 12; ++i) {
      mesh.x.push_back((i + 0.5) * 1e-3);
      mesh.y.push_back((j + 0.5) * 1e-3);
    }
  }
  using peritwin_msgs::mesh_polyline_t;
  mesh.polylines = {
      {mesh_polyline_t::KIND_OUTLINE, 0, true, {0, 0.012, 0.012, 0}, {0, 0, 0.008, 0.008}},
      {mesh_polyline_t::KIND_HOLE, 0, true, {0.008, 0.009, 0.008}, {0.004, 0.005, 0.006}},
      {mesh_polyline_t::KIND_NOTCH, 0, false, {0, 0.004}, {0.004, 0.004}}};
  write(dir / "one-chunk.bin", encode_message(peritwin::messages::mesh_messages(mesh, 0)[0]));
  auto second = peritwin::messages::mesh_messages(mesh, 0)[0];
  second.chunk_index = 1;
  second.num_chunks = 2;
  second.total_nodes = 200;
  second.first_node = 104;
  second.num_polylines = 0;
  second.polylines.clear();
  write(dir / "second-chunk.bin", encode_message(second));
  write(dir / "request.bin", encode_message(peritwin::messages::mesh_request_message(
                                 "b1-ct", "peritwin-dashboard", 1'700'000'000'000'000)));
}

void key_file_seed(const fs::path& dir) {
  fs::create_directories(dir);
  const std::string text =
      "# keys of the fuzz seeds (not secret)\n[keys]\n"
      "replay = \"0101010101010101010101010101010101010101010101010101010101010101\"\n"
      "\"gauge.3\" = \"00112233445566778899AABBCCDDEEFF00112233445566778899aabbccddeeff\"\n"
      "peritwin = \"ffeeddccbbaa99887766554433221100ffeeddccbbaa99887766554433221100\"\n";
  write(dir / "three-keys.toml", std::vector<std::uint8_t>(text.begin(), text.end()));
}

void lcm_log_seed(const fs::path& file, bool with_noise) {
  std::error_code ignore;
  fs::remove(file, ignore);
  {
    lcm::LogFile log(file.string(), "w");
    if (!log.good()) throw std::runtime_error("cannot create " + file.string());
    const std::string load = peritwin::messages::channel("b1-ct", peritwin::messages::Kind::kLoad);
    std::int64_t t = 1'700'000'000'000'000;
    auto event = [&](const std::string& channel, std::vector<std::uint8_t> bytes) {
      lcm::LogEvent e;
      e.timestamp = t;
      t += 1000;
      e.channel = channel;
      e.datalen = static_cast<std::int32_t>(bytes.size());
      e.data = bytes.data();
      log.writeEvent(&e);
    };
    const auto all = batches();
    event(load, encode(all[0].second));
    event(load, encode(all[1].second));
    if (with_noise) {
      event(load, encode(all[0].second));                    // duplicate (source, seq)
      event("PERITWIN_B2_CTS_LOAD", encode(all[1].second));  // another detail's channel
      event(load, {0xde, 0xad, 0xbe, 0xef});                 // undecodable
      event(load, encode({"b2-cts", "replay", 5, {{1.0, 0.0, 0.0, 1}}}));  // wrong detail
    }
  }
  std::printf("%s (%ju bytes)\n", file.c_str(), static_cast<std::uintmax_t>(fs::file_size(file)));
}

void checkpoint_seed(const fs::path& file) {
  peritwin::twin::CheckpointData data;
  data.format_version = 3;
  data.f64_arrays["life"] = {1.0, 0.5, 0.25, 0.0};
  data.i64_arrays["seq"] = {1, 2, 3};
  data.u8_arrays["broken"] = {0, 1, 0, 1, 1};
  data.u8_arrays["empty"] = {};
  data.i64_scalars["total_cycles"] = 64000;
  data.f64_scalars["max_damage"] = 0.375;
  data.strings["detail"] = "b1-ct";
  data.strings["sources"] = "replay\nstrain-gauge-3";
  peritwin::outputs::write_checkpoint(file, data);
  std::printf("%s (%ju bytes)\n", file.c_str(), static_cast<std::uintmax_t>(fs::file_size(file)));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s CORPUS_DIR  (e.g. tests/fuzz/corpus)\n", argv[0]);
    return 2;
  }
  try {
    const fs::path dir(argv[1]);
    batch_seeds(dir / "batch");
    state_seeds(dir / "state");
    reject_seeds(dir / "reject");
    observation_seeds(dir / "observation_msg");
    samples_seeds(dir / "samples");
    mesh_seeds(dir / "mesh");
    key_file_seed(dir / "key_file");
    fs::create_directories(dir / "lcm_log");
    lcm_log_seed(dir / "lcm_log" / "two-batches.lcmlog", false);
    lcm_log_seed(dir / "lcm_log" / "mixed.lcmlog", true);
    fs::create_directories(dir / "checkpoint");
    checkpoint_seed(dir / "checkpoint" / "tiny.h5");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "peritwin-fuzz-seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
