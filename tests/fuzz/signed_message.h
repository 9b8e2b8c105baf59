// What the fuzz targets of the daemon's signed answers (fuzz_state, fuzz_reject) check alike: a
// payload off the bus -> verify_encoded with the targets' fixed key (bytes 1, 2, ..., 32; the
// seeds of make_seeds.cpp are signed with it) and the checked decoder. Properties: the decoder
// never lets LCM's decoder allocate beyond the payload (ASan, -malloc_limit_mb); a decoded
// message re-encodes to the same bytes; verify_encoded on the bytes agrees with verify on the
// decoded message (in the reason too, unless the bytes read both ways: auth.h).
#pragma once

#include <algorithm>
#include <numeric>
#include <optional>
#include <vector>

#include "messages/auth.h"
#include "tests/fuzz/fuzz_target.h"

namespace peritwin::fuzz {

/// The decoded message when `decode` takes the payload, after the properties above hold.
template <class Message, class Decode>
std::optional<Message> decode_signed(const std::uint8_t* data, std::size_t size, Decode&& decode) {
  using namespace peritwin::messages;
  AuthKey key;
  std::iota(key.bytes.begin(), key.bytes.end(), std::uint8_t{1});
  const core::Status on_bytes = verify_encoded<Message>(data, size, key);
  std::optional<Message> message = decode(data, size);
  if (!message) return message;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message->getEncodedSize()));
  require(message->encode(bytes.data(), 0, static_cast<int>(bytes.size())) ==
              static_cast<int>(bytes.size()),
          "a decoded message encodes");
  require(bytes.size() == size && std::equal(bytes.begin(), bytes.end(), data),
          "encode(decode(payload)) == payload");
  const core::Status on_message = verify(*message, key);
  const bool reads_both_ways = auth_reason_is_a_guess(data, size, message->tag_length);
  require(
      on_bytes.ok() == on_message.ok() && (on_bytes.ok() || reads_both_ways ||
                                           on_bytes.error().reason == on_message.error().reason),
      "verify_encoded(bytes) == verify(decode(bytes))");
  return message;
}

}  // namespace peritwin::fuzz
