// peritwin-fuzz-seeds DIR: writes the generated seeds of the fuzz corpus into DIR/<target>/:
// encoded load batches (batch, and inside LCM logs for lcm_log) and a tiny checkpoint
// (checkpoint). Deterministic (fixed utimes, fixed content): rerun it after a change of the
// message types or of the checkpoint layout and commit what changed (tests/fuzz/README.md).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "messages/channels.h"
#include "messages/codec.h"
#include "twin/io/checkpoint_io.h"

namespace fs = std::filesystem;
using peritwin::LoadBlock;
using peritwin::messages::Batch;

namespace {

// An unsigned batch, or one carrying `tag` (not a valid HMAC: the decoder only bounds it).
std::vector<std::uint8_t> encode(const Batch& batch, const std::vector<std::uint8_t>& tag = {}) {
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
std::vector<std::pair<std::string, Batch>> batches() {
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
  peritwin::twin::write_checkpoint(file, data);
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
