// Fuzz target: the input as an observations CSV (issue 32, peritwin-replay --observations) ->
// read_observations_csv. Properties: a result or a one-line error naming the file; every
// observation read passes messages::check_observation, and the rows are in cycle order.
#include <sstream>

#include "loads/load_history.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using peritwin::fuzz::require;
  std::istringstream in{std::string(peritwin::fuzz::text(data, size))};
  const auto read = peritwin::loads::read_observations_csv(in, "fuzz.csv");
  if (!read) {
    const std::string m = read.error().message();
    require(m.rfind("fuzz.csv", 0) == 0 && m.find('\n') == std::string::npos,
            "an error is one line naming the file");
    return 0;
  }
  std::int64_t last = 0;
  for (const auto& o : read.value()) {
    require(static_cast<bool>(peritwin::messages::check_observation(o)),
            "every observation read is valid");
    require(o.cycle >= last, "rows in cycle order");
    last = o.cycle;
  }
  return 0;
}
