// Fuzz target: the input as an LCM log file (the replay tool's --format lcm-log) -> read_history,
// which takes a path: the input goes through a temp file. Properties: blocks or a one-line error
// naming the file.
#include "replay/replay_tool.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using peritwin::fuzz::require;
  static peritwin::fuzz::TempFile file(".lcmlog");
  const auto& path = file.write(data, size);
  const auto read =
      peritwin::replay::read_history(path, peritwin::replay::InputFormat::lcm_log, "b1-ct");
  if (!read) {
    const std::string& m = read.error().reason;
    require(m.rfind(path.string(), 0) == 0 && m.find('\n') == std::string::npos,
            "an error is one line naming the file");
    return 0;
  }
  // The blocks are as the batches carried them: the replay tool's check_blocks judges them.
  require(!read.value().blocks.empty(), "a log read without error has blocks");
  return 0;
}
