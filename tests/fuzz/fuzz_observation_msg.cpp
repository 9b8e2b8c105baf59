// Fuzz target: an observation_t payload as it comes off the bus (issue 32) -> decode_observation
// -> check_observation_message. Properties: decoding never reads or allocates beyond the payload
// (ASan); a payload that does not decode has a DECODE verdict (INVALID for a kind that is none of
// the KIND_* constants) and a reason; a decoded observation re-encodes, with its tag, to the same
// bytes after the utime, and its signed bytes and tag are the whole payload; a refusal names the
// observation's field.
#include <cstring>
#include <vector>

#include "messages/codec.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace peritwin::messages;
  using peritwin::fuzz::require;
  const DecodedObservation decoded = decode_observation(data, size);
  if (!decoded.observation) {
    require(
        (decoded.error.verdict == Verdict::decode ||
         (decoded.error.verdict == Verdict::invalid && decoded.error.what == "observation.kind")) &&
            !decoded.error.why.empty(),
        "an observation that does not decode has a DECODE (or kind INVALID) verdict and a reason");
    return 0;
  }
  const Observation& o = *decoded.observation;
  require(decoded.signed_size + 4 + decoded.auth_tag.size() == size,
          "the signed bytes, tag_length and the tag are the whole payload");
  auto m = observation_message(o, 0);
  m.tag_length = static_cast<std::int32_t>(decoded.auth_tag.size());
  m.auth_tag = decoded.auth_tag;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  require(
      m.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()),
      "a decoded observation encodes");
  // utime (8 bytes after the 8-byte fingerprint) is not kept by the decoder.
  require(bytes.size() == size && std::memcmp(bytes.data(), data, 8) == 0 &&
              std::memcmp(bytes.data() + 16, data + 16, size - 16) == 0,
          "encode(decode(payload)) == payload, utime aside");
  const Outcome checked = check_observation_message(o, "b1-ct");
  require(checked.applied() || (checked.what.starts_with("observation") && !checked.why.empty()),
          "a refused observation names its field and why");
  return 0;
}
