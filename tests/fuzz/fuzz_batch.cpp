// Fuzz target: a load_batch_t payload as it comes off the bus -> decode_batch -> check_batch.
// Properties: decoding never reads or allocates beyond the payload (ASan); a decoded batch and
// its tag re-encode to the same bytes (utime aside) and decode to the same batch; the signed
// bytes, tag_length and the tag (0 or 32 bytes) are the whole payload; an error names its field.
#include <cstring>
#include <vector>

#include "messages/codec.h"
#include "tests/fuzz/fuzz_target.h"

namespace {

using peritwin::fuzz::require;
using namespace peritwin::messages;

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

bool same(const Batch& a, const Batch& b) {
  if (a.detail_id != b.detail_id || a.source_id != b.source_id || a.seq != b.seq ||
      a.blocks.size() != b.blocks.size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.blocks.size(); ++i) {
    const auto& x = a.blocks[i];
    const auto& y = b.blocks[i];
    if (!same_bits(x.p_max, y.p_max) || !same_bits(x.r, y.r) || !same_bits(x.alpha, y.alpha) ||
        x.count != y.count) {
      return false;
    }
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const Decoded decoded = decode_batch(data, size);
  if (!decoded.batch) {
    require(decoded.error.verdict == Verdict::decode && !decoded.error.why.empty(),
            "a payload that does not decode has a DECODE verdict and a reason");
    return 0;
  }
  const Batch& batch = *decoded.batch;
  for (const Outcome& o : {check_batch(batch, batch.detail_id), check_batch(batch, "b1-ct")}) {
    require(o.applied() || (!o.what.empty() && !o.why.empty()),
            "a rejected batch names the field and the reason");
  }
  require(decoded.auth_tag.empty() || decoded.auth_tag.size() == kAuthTagBytes,
          "the tag is absent or kAuthTagBytes long");
  require(decoded.signed_size + 4 + decoded.auth_tag.size() == size,
          "the signed bytes, tag_length and the tag are the whole payload");
  // Round trip through the generated encoder: the same bytes after the fingerprint and utime.
  auto msg = batch_message(batch, 0);
  msg.tag_length = static_cast<std::int32_t>(decoded.auth_tag.size());
  msg.auth_tag = decoded.auth_tag;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
  require(
      msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()),
      "a decoded batch encodes");
  require(bytes.size() == size && std::memcmp(bytes.data() + 16, data + 16, size - 16) == 0,
          "encode(decode(payload)) == payload but for utime");
  const Decoded again = decode_batch(bytes.data(), bytes.size());
  require(again.batch && same(*again.batch, batch) && again.signed_size == decoded.signed_size &&
              again.auth_tag == decoded.auth_tag,
          "decode(encode(batch)) == batch");
  return 0;
}
