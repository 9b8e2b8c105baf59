// The stream's state file (stream/stream_tool.h): the pipeline and the unacknowledged batches
// read back equal to what was saved, including the last seq taken per source of load_samples_t
// (version 2); a version-1 file (without them) still reads, as having taken none; a bad source
// entry or a changed byte is refused with its reason.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "config/config.h"
#include "stream/stream_tool.h"

namespace peritwin::stream {
namespace {

namespace fs = std::filesystem;

class StreamState : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto loaded =
        config::load_config(std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml");
    ASSERT_TRUE(loaded.ok()) << loaded.error_text();
    detail_ = loaded.config->details.at(0);
    file_ = fs::temp_directory_path() / ("peritwin_stream_state_" + std::to_string(::getpid()));
  }
  void TearDown() override {
    fs::remove(file_);
    fs::remove(file_.string() + ".tmp");
  }
  static std::string read(const fs::path& f) {
    std::ifstream in(f);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  /// A pipeline that has taken a few cycles (an open batch and an open residue).
  stream::Pipeline fed() const {
    stream::Pipeline p(detail_, "stream", batching_, 1);
    std::vector<messages::Batch> closed;
    const double loads[] = {400, 4000, 400, 4000, 400, 3000, 1000, 3500};
    double t = 0;
    for (const double load : loads) p.sample(t += 0.01, load, 0.0, closed);
    return p;
  }
  config::DetailConfig detail_;
  loads::BatchingOptions batching_{};
  fs::path file_;
};

TEST_F(StreamState, SamplesTakenPerSourceSurviveTheStateFile) {
  stream::Pipeline p = fed();
  p.samples_taken = {{"gauge", 57}, {"gauge 2\n\"x\"", 1}, {"g", (std::int64_t{1} << 62) + 3}};
  ASSERT_TRUE(stream::save_state(file_, p, {})) << "save";
  const auto back = stream::load_state(file_, detail_, "stream", batching_);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->pipeline.samples_taken, p.samples_taken);
  EXPECT_EQ(back->pipeline.save(), p.save());  // everything else bit-identical too
}

/// FNV-1a 64 as 16 lowercase hex digits from `basis` (the state file's checksum, written here
/// from the algorithm's definition, not the production code).
std::string fnv1a_hex(std::string_view text, std::uint64_t basis = 0xcbf29ce484222325ULL) {
  std::uint64_t h = basis;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}
/// Version 1's checksum: FNV-1a from the offset basis with its last digit lost.
constexpr std::uint64_t kVersionOneBasis = 1469598103934665603ULL;

TEST_F(StreamState, VersionOneFileReadsAsHavingTakenNoSamples) {
  const stream::Pipeline p = fed();
  ASSERT_TRUE(stream::save_state(file_, p, {}));
  // The same state as version 1 wrote it: version 1, no samples_taken line, its own checksum.
  const std::string text = read(file_);
  std::string body = text.substr(0, text.rfind("checksum "));
  ASSERT_EQ(text.substr(body.size()), "checksum " + fnv1a_hex(body) + "\n");  // the definition
  const std::string v2 = "peritwin-stream-state 2\n", v1 = "peritwin-stream-state 1\n";
  ASSERT_TRUE(body.starts_with(v2)) << body;
  body.replace(0, v2.size(), v1);
  const std::string taken = "\nsamples_taken 0";
  const auto at = body.find(taken);
  ASSERT_NE(at, std::string::npos) << body;
  body.erase(at, taken.size());
  std::ofstream(file_, std::ios::trunc) << body << "checksum " << fnv1a_hex(body) << "\n";
  EXPECT_FALSE(stream::load_state(file_, detail_, "stream", batching_));  // v1 had its own checksum
  std::ofstream(file_, std::ios::trunc)
      << body << "checksum " << fnv1a_hex(body, kVersionOneBasis) << "\n";
  const auto back = stream::load_state(file_, detail_, "stream", batching_);
  ASSERT_TRUE(back) << back.error();
  EXPECT_TRUE(back->pipeline.samples_taken.empty());
  EXPECT_EQ(back->pipeline.save(), p.save());

  // A repeated source in a version-2 file is refused with its reason.
  std::string twice = text.substr(0, text.rfind("checksum "));
  const auto zero = twice.find(taken);
  twice.replace(zero, taken.size(), "\nsamples_taken 2 6761 1 6761 2");  // "ga" twice
  std::ofstream(file_, std::ios::trunc) << twice << "checksum " << fnv1a_hex(twice) << "\n";
  const auto refused = stream::load_state(file_, detail_, "stream", batching_);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().find("samples_taken: bad or repeated source \"6761\""),
            std::string::npos)
      << refused.error();
}

}  // namespace
}  // namespace peritwin::stream
