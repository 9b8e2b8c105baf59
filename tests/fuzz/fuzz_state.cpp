// Fuzz target: a damage_state_t payload off the bus, as peritwin-replay receives it ->
// verify_encoded (with a fixed key) and decode_state, then what the replay tool does with a state
// (state_json, summary_json, crack_length, applied_seq). Properties: decode_state never lets LCM's
// decoder allocate beyond the payload (ASan, -malloc_limit_mb); a decoded state re-encodes to the
// same bytes; verify_encoded on the bytes agrees with verify on the decoded message.
#include <algorithm>
#include <cstring>
#include <numeric>
#include <vector>

#include "messages/auth.h"
#include "messages/codec.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace peritwin::messages;
  using peritwin::fuzz::require;
  AuthKey key;
  std::iota(key.bytes.begin(), key.bytes.end(), std::uint8_t{1});
  const peritwin::Status on_bytes = verify_encoded<peritwin_msgs::damage_state_t>(data, size, key);
  const auto state = decode_state(data, size);
  if (!state) return 0;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(state->getEncodedSize()));
  require(state->encode(bytes.data(), 0, static_cast<int>(bytes.size())) ==
              static_cast<int>(bytes.size()),
          "a decoded state encodes");
  require(bytes.size() == size && std::equal(bytes.begin(), bytes.end(), data),
          "encode(decode(payload)) == payload");
  const peritwin::Status on_message = verify(*state, key);
  // The reasons agree unless the bytes read both ways (auth.h, verify_encoded).
  const bool reads_both_ways =
      peritwin::fuzz::auth_reason_is_a_guess(data, size, state->tag_length);
  require(
      on_bytes.ok() == on_message.ok() && (on_bytes.ok() || reads_both_ways ||
                                           on_bytes.error().reason == on_message.error().reason),
      "verify_encoded(bytes) == verify(decode(bytes))");
  require(!state_json(*state).empty() && !summary_json(*state).empty(), "a state prints");
  (void)crack_length(*state);
  (void)applied_seq(*state, "replay");
  return 0;
}
