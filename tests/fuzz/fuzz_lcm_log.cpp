// Fuzz target: the input as an LCM log file (the replay tool's --format lcm-log) -> read_lcm_log,
// i.e. loads/lcm_log.h's bounded reader and the batch decoder on every event of the detail's
// channel. Properties: blocks or a one-line error naming the file.
#include <sstream>

#include "replay/replay_tool.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using peritwin::fuzz::require;
  std::istringstream in{std::string(peritwin::fuzz::text(data, size))};
  const auto read = peritwin::replay::read_lcm_log(in, "fuzz.lcmlog", "b1-ct");
  if (!read) {
    const std::string& m = read.error().reason;
    require(m.rfind("fuzz.lcmlog: ", 0) == 0 && m.find('\n') == std::string::npos,
            "an error is one line naming the file");
    return 0;
  }
  // The blocks are as the batches carried them: the replay tool's check_blocks judges them.
  require(!read.value().blocks.empty(), "a log read without error has blocks");
  return 0;
}
