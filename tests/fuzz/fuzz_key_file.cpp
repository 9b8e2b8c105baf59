// Fuzz target: the input as the text of an [auth] key file -> KeyRing::parse (no mode check; the
// daemon and peritwin-replay --key-file load it). Properties: keys or a one-line error naming the
// file; every key found under the ids it lists.
#include "messages/auth.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using peritwin::fuzz::require;
  const auto ring =
      peritwin::messages::KeyRing::parse(peritwin::fuzz::text(data, size), "fuzz.keys");
  if (!ring) {
    const std::string m = ring.error().message();
    require(m.find("fuzz.keys") != std::string::npos && m.find('\n') == std::string::npos,
            "an error is one line naming the file");
    return 0;
  }
  require(ring.value().size() >= 1, "a key file has at least one key");
  for (const auto& id : ring.value().ids()) {
    require(ring.value().find(id) != nullptr, "every id listed has its key");
  }
  return 0;
}
