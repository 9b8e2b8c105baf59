// Authentication of the signed message types (message set version 2): HMAC-SHA256 (libsodium's
// crypto_auth_hmacsha256) over every encoded byte of a load_batch_t, damage_state_t or reject_t
// before its tag_length field — the 8-byte fingerprint first, so a tag cannot be moved to another
// message type, and detail_id, source_id and seq included. Keys come from a key file (KeyRing).
// messages/README.md, "Authentication", says who holds which key and what this does not protect.
//
// Library target peritwin_auth (links libsodium and toml++ privately; link it next to
// peritwin_messages where messages are signed or checked).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <peritwin_msgs/damage_state_t.hpp>
#include <peritwin_msgs/load_batch_t.hpp>
#include <peritwin_msgs/load_samples_t.hpp>
#include <peritwin_msgs/observation_t.hpp>
#include <peritwin_msgs/reject_t.hpp>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/expected.h"
#include "messages/batch.h"

namespace peritwin::messages {

/// Bytes of a key (crypto_auth_hmacsha256_KEYBYTES).
inline constexpr std::size_t kAuthKeyBytes = 32;

/// A secret key. Never logged or printed: nothing in the project formats one, and no error text
/// quotes key material.
struct AuthKey {
  std::array<std::uint8_t, kAuthKeyBytes> bytes{};
};
using AuthTag = std::array<std::uint8_t, kAuthTagBytes>;

/// Key ids: 1 to kMaxSourceIdLength printable ASCII characters without blanks (the rule of
/// load_batch_t.source_id, so every source id can be one).
bool is_valid_key_id(std::string_view id);

/// The keys of a key file by id (a source id, or the daemon's key id).
class KeyRing {
 public:
  /// The key file: TOML, one table [keys] with `<key id> = "<64 hex digits>"` (quoted keys
  /// allowed, e.g. `"gauge.3" = "..."`), nothing else. Refused unless a regular file whose mode
  /// grants nothing to group and others (0600 or 0400; the error names the file and its mode).
  /// A bad hex string, a wrong length, a duplicate or invalid id, an empty or missing [keys], or
  /// any other top-level key or table is an error "file:line: ..." naming the key id, never
  /// the key material.
  static core::Expected<KeyRing> load(const std::filesystem::path& file);
  /// The same rules on the text of a key file (no mode check; `file_name` for the errors).
  static core::Expected<KeyRing> parse(std::string_view text, const std::string& file_name);

  /// nullptr if there is no key `id`.
  [[nodiscard]] const AuthKey* find(std::string_view id) const;
  /// Every id, sorted (bytewise).
  [[nodiscard]] std::vector<std::string> ids() const;
  [[nodiscard]] std::size_t size() const { return keys_.size(); }

 private:
  std::vector<std::pair<std::string, AuthKey>> keys_;  // sorted by id
};

/// Writes a new key file `file` with one fresh random key (libsodium randombytes_buf) per id, mode
/// 0600. Refuses to overwrite an existing file (or follow a symlink there), an empty id list, an
/// invalid or repeated id. The file is complete or absent.
core::Status write_key_file(const std::filesystem::path& file, std::span<const std::string> ids);

/// A producer run's nonce (load_batch_t.nonce): 64 random bits from libsodium's
/// randombytes_buf, never 0 (0 means none).
std::uint64_t random_nonce();

/// HMAC-SHA256 (libsodium crypto_auth_hmacsha256) of bytes [data, data + size).
AuthTag auth_tag(const AuthKey& key, const std::uint8_t* data, std::size_t size);
/// HMAC-SHA256 with a key of any length (RFC 2104; what auth_tag computes for 32-byte keys). For
/// checking the primitive against published test vectors.
AuthTag hmac_sha256(std::span<const std::uint8_t> key, const std::uint8_t* data, std::size_t size);
/// Constant-time check of `tag` against auth_tag(key, data, size); a tag of any other length than
/// kAuthTagBytes is false.
bool tag_matches(const AuthKey& key, const std::uint8_t* data, std::size_t size,
                 std::span<const std::uint8_t> tag);

/// Signs a message in place: clears the tag, encodes, computes the HMAC over every encoded byte
/// before tag_length (encoded size - 4) and stores it (tag_length = kAuthTagBytes). The message's
/// array counts must match its arrays (as for encode()); a string with a NUL byte inside cannot be
/// encoded faithfully and throws std::invalid_argument (the decoders refuse such strings).
void sign(peritwin_msgs::load_batch_t& m, const AuthKey& key);
void sign(peritwin_msgs::damage_state_t& m, const AuthKey& key);
void sign(peritwin_msgs::reject_t& m, const AuthKey& key);
void sign(peritwin_msgs::load_samples_t& m, const AuthKey& key);
void sign(peritwin_msgs::observation_t& m, const AuthKey& key);

/// Ok if `m` carries the tag `key` gives it; otherwise the error has field "auth_tag" and reason
/// exactly "unsigned" (tag_length 0) or "wrong tag" (any other tag, of any length).
core::Status verify(const peritwin_msgs::load_batch_t& m, const AuthKey& key);
core::Status verify(const peritwin_msgs::damage_state_t& m, const AuthKey& key);
core::Status verify(const peritwin_msgs::reject_t& m, const AuthKey& key);
core::Status verify(const peritwin_msgs::load_samples_t& m, const AuthKey& key);
core::Status verify(const peritwin_msgs::observation_t& m, const AuthKey& key);

/// verify() on the encoded bytes of a message of the type with fingerprint `fingerprint`, before
/// decoding anything: field "message", reason "wrong fingerprint: not a <type_name> of this
/// message set version" (or a payload shorter than a fingerprint and a tag length), or field
/// "auth_tag" with "unsigned" / "wrong tag" as verify(). For the encoding of a message M this
/// equals verify(M) in ok(), and in the reason unless the bytes read both ways, which only
/// decoding could tell: M's wrong tag ends in four zero bytes (called "unsigned" unless it is 32
/// bytes long), or M is unsigned and its last 36 bytes read as a 32-byte tag (called "wrong tag").
/// Use the template.
core::Status verify_encoded(const std::uint8_t* data, std::size_t size, std::int64_t fingerprint,
                            const char* type_name, const AuthKey& key);
template <typename Message>
core::Status verify_encoded(const void* data, std::size_t size, const AuthKey& key) {
  return verify_encoded(static_cast<const std::uint8_t*>(data), size, Message::getHash(),
                        Message::getTypeName(), key);
}

}  // namespace peritwin::messages
