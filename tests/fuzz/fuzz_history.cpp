// Fuzz target: the input as a load-history CSV (series, cycles or spectrum: the target is built
// once per format, PERITWIN_FUZZ_FORMAT) -> read_blocks, i.e. reading, rainflow counting and
// spectrum expansion as the replay tool does them. Properties: a result or a one-line error
// naming the file; every block valid by check_load_block (a cycles or spectrum file's rows are
// checked; a series' cycles are converted by loads/cycle_blocks.h's rules).
#include <sstream>

#include "loads/load_history.h"
#include "tests/fuzz/fuzz_target.h"

namespace {
constexpr auto kFormat = peritwin::loads::HistoryFormat::PERITWIN_FUZZ_FORMAT;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace peritwin::loads;
  using peritwin::fuzz::require;
  std::istringstream in{std::string(peritwin::fuzz::text(data, size))};
  const auto read = peritwin::loads::read_blocks(in, "fuzz.csv", kFormat);
  if (!read) {
    const std::string m = read.error().message();
    require(m.rfind("fuzz.csv", 0) == 0 && m.find('\n') == std::string::npos,
            "an error is one line naming the file");
    return 0;
  }
  for (const auto& b : read.value().blocks) {
    // A series' rainflow cycles too: below R = -10 remapped, compressive ones mirrored
    // (loads/cycle_blocks.h), so every block is one the daemon accepts.
    require(static_cast<bool>(peritwin::core::check_load_block(b)), "every block read is valid");
  }
  return 0;
}
