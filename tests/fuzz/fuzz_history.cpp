// Fuzz target: the input as a load-history CSV (series, cycles or spectrum: the target is built
// once per format, PERITWIN_FUZZ_FORMAT) -> read_blocks, i.e. reading, rainflow counting and
// spectrum expansion as the replay tool does them. Properties: a result or a one-line error
// naming the file; the blocks of a cycles or spectrum file valid by check_load_block (the rows
// are checked), those of a series tensile cycles.
#include <sstream>

#include "replay/load_history.h"
#include "tests/fuzz/fuzz_target.h"

namespace {
constexpr auto kFormat = peritwin::replay::HistoryFormat::PERITWIN_FUZZ_FORMAT;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace peritwin::replay;
  using peritwin::fuzz::require;
  std::istringstream in{std::string(peritwin::fuzz::text(data, size))};
  const auto read = read_blocks(in, "fuzz.csv", kFormat);
  if (!read) {
    const std::string m = read.error().message();
    require(m.rfind("fuzz.csv", 0) == 0 && m.find('\n') == std::string::npos,
            "an error is one line naming the file");
    return 0;
  }
  for (const auto& b : read.value().blocks) {
    if constexpr (kFormat == HistoryFormat::series) {
      // Rainflow cycles: tensile (compressive ones are skipped), R < 1. An R below -10 is the
      // replay tool's check_blocks' to refuse, with the block named.
      require(b.p_max > 0.0 && b.r < 1.0 && b.count >= 1, "a counted cycle is tensile");
    } else {
      require(static_cast<bool>(peritwin::check_load_block(b)), "every block read is valid");
    }
  }
  return 0;
}
