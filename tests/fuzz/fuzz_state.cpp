// Fuzz target: a damage_state_t payload off the bus, as peritwin-replay receives it ->
// verify_encoded (with a fixed key) and decode_state (the properties of signed_message.h), then
// what the replay tool does with a state (state_json, summary_json, crack_length, applied_seq).
#include "messages/codec.h"
#include "tests/fuzz/signed_message.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace peritwin::messages;
  const auto state =
      peritwin::fuzz::decode_signed<peritwin_msgs::damage_state_t>(data, size, decode_state);
  if (!state) return 0;
  peritwin::fuzz::require(!state_json(*state).empty() && !summary_json(*state).empty(),
                          "a state prints");
  (void)crack_length(*state);
  (void)applied_seq(*state, "replay");
  return 0;
}
