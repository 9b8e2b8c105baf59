// Fuzz target: a reject_t payload off the bus, as peritwin-replay receives it -> verify_encoded
// (with a fixed key) and decode_reject; the properties of signed_message.h.
#include "messages/codec.h"
#include "tests/fuzz/signed_message.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)peritwin::fuzz::decode_signed<peritwin_msgs::reject_t>(data, size,
                                                               peritwin::messages::decode_reject);
  return 0;
}
