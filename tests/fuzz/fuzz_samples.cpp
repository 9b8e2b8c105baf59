// Fuzz target: a load_samples_t payload as it comes off the bus -> decode_samples ->
// check_samples. Properties: decoding never reads or allocates beyond the payload (ASan); a
// decoded message and its tag re-encode to the same bytes (utime aside) and decode to the same
// samples; the signed bytes, tag_length and the tag are the whole payload; an error names its
// field and reason.
#include <cstring>
#include <vector>

#include "messages/codec.h"
#include "tests/fuzz/fuzz_target.h"

namespace {

using peritwin::fuzz::require;
using namespace peritwin::messages;

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

bool same(const Samples& a, const Samples& b) {
  return a.detail_id == b.detail_id && a.source_id == b.source_id && a.seq == b.seq &&
         std::memcmp(&a.t0, &b.t0, sizeof a.t0) == 0 &&
         std::memcmp(&a.sample_period, &b.sample_period, sizeof a.sample_period) == 0 &&
         same_bits(a.p, b.p) && same_bits(a.t, b.t) && same_bits(a.alpha, b.alpha);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const DecodedSamples decoded = decode_samples(data, size);
  if (!decoded.samples) {
    require(decoded.error.verdict == Verdict::decode && !decoded.error.why.empty(),
            "a payload that does not decode has a DECODE verdict and a reason");
    return 0;
  }
  const Samples& samples = *decoded.samples;
  for (const Outcome& o :
       {check_samples(samples, samples.detail_id), check_samples(samples, "b1-ct")}) {
    require(o.applied() || (!o.what.empty() && !o.why.empty()),
            "refused samples name the field and the reason");
  }
  require(decoded.auth_tag.empty() || decoded.auth_tag.size() == kAuthTagBytes,
          "the tag is absent or kAuthTagBytes long");
  require(decoded.signed_size + 4 + decoded.auth_tag.size() == size,
          "the signed bytes, tag_length and the tag are the whole payload");
  auto msg = samples_message(samples, 0);
  msg.tag_length = static_cast<std::int32_t>(decoded.auth_tag.size());
  msg.auth_tag = decoded.auth_tag;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
  require(
      msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()),
      "decoded samples encode");
  require(bytes.size() == size && std::memcmp(bytes.data() + 16, data + 16, size - 16) == 0,
          "encode(decode(payload)) == payload but for utime");
  const DecodedSamples again = decode_samples(bytes.data(), bytes.size());
  require(again.samples && same(*again.samples, samples) &&
              again.signed_size == decoded.signed_size && again.auth_tag == decoded.auth_tag,
          "decode(encode(samples)) == samples");
  return 0;
}
