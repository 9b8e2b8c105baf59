// Fuzz target: the input as the saved state of the replay side's incremental rainflow
// (RainflowCounter::restore, loads/rainflow.h) and of its cycle -> block conversion
// (CycleBlocks::restore, loads/cycle_blocks.h): a stream's state file. Properties: a state or a
// one-line reason naming which state; a restored state saves to a text that restores to the same
// text, and counting on from it (a few samples, finish) gives blocks the daemon accepts.
#include <string>
#include <vector>

#include "loads/cycle_blocks.h"
#include "loads/rainflow.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace peritwin::loads;
  using peritwin::fuzz::require;
  const std::string_view text = peritwin::fuzz::text(data, size);
  std::vector<peritwin::loads::CountedCycle> cycles;
  std::vector<peritwin::core::LoadBlock> blocks;
  auto counter = peritwin::loads::RainflowCounter::restore(text);
  if (!counter) {
    require(counter.error().rfind("rainflow counter state: ", 0) == 0 &&
                counter.error().find('\n') == std::string::npos,
            "a refused counter state says why in one line");
  } else {
    const std::string saved = counter->save();
    const auto again = peritwin::loads::RainflowCounter::restore(saved);
    require(again.ok() && again->save() == saved, "a restored counter round-trips");
    for (const double v : {0.0, 1e3, -1e3, 5.0}) counter->push(v, 0.0, cycles);
    counter->finish(peritwin::loads::ResidueRule::whole, cycles);
  }
  auto converter = peritwin::loads::CycleBlocks::restore(text);
  if (!converter) {
    require(converter.error().rfind("cycle blocks state: ", 0) == 0 &&
                converter.error().find('\n') == std::string::npos,
            "a refused conversion state says why in one line");
    return 0;
  }
  const std::string saved = converter->save();
  const auto again = peritwin::loads::CycleBlocks::restore(saved);
  require(again.ok() && again->save() == saved, "a restored conversion round-trips");
  for (const peritwin::loads::CountedCycle& c : cycles) converter->add(c, blocks);
  for (const peritwin::core::LoadBlock& b : blocks) {
    require(static_cast<bool>(peritwin::core::check_load_block(b)), "every block is valid");
  }
  return 0;
}
