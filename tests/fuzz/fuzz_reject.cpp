// Fuzz target: a reject_t payload off the bus, as peritwin-replay receives it -> verify_encoded
// (with a fixed key) and decode_reject. Properties: as fuzz_state's.
#include <algorithm>
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
  const peritwin::Status on_bytes = verify_encoded<peritwin_msgs::reject_t>(data, size, key);
  const auto reject = decode_reject(data, size);
  if (!reject) return 0;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(reject->getEncodedSize()));
  require(reject->encode(bytes.data(), 0, static_cast<int>(bytes.size())) ==
              static_cast<int>(bytes.size()),
          "a decoded reject encodes");
  require(bytes.size() == size && std::equal(bytes.begin(), bytes.end(), data),
          "encode(decode(payload)) == payload");
  const peritwin::Status on_message = verify(*reject, key);
  // The reasons agree unless the bytes read both ways (auth.h, verify_encoded).
  const bool reads_both_ways =
      peritwin::fuzz::auth_reason_is_a_guess(data, size, reject->tag_length);
  require(
      on_bytes.ok() == on_message.ok() && (on_bytes.ok() || reads_both_ways ||
                                           on_bytes.error().reason == on_message.error().reason),
      "verify_encoded(bytes) == verify(decode(bytes))");
  return 0;
}
