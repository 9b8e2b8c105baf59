// Fuzz target: the input as the TOML text of a config -> parse_config (the schema's checks only;
// no discretization, no model). Properties: either a config or at least one error, every error
// a single line naming the file.
#include "config/config.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using peritwin::fuzz::require;
  const auto result = peritwin::config::parse_config(peritwin::fuzz::text(data, size), "fuzz.toml");
  require(result.ok() != !result.errors.empty(), "a config xor its errors");
  for (const auto& e : result.errors) {
    const std::string m = e.message();
    require(m.rfind("fuzz.toml", 0) == 0, "an error names the file");
    require(m.find('\n') == std::string::npos, "an error is one line");
  }
  return 0;
}
