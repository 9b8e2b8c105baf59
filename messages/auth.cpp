#include "messages/auth.h"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <toml++/toml.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "core/toml_text.h"

namespace peritwin::messages {

static_assert(kAuthKeyBytes == crypto_auth_hmacsha256_KEYBYTES);
static_assert(kAuthTagBytes == crypto_auth_hmacsha256_BYTES);

namespace {

/// A key file is a few lines; anything much larger is not one.
constexpr std::size_t kMaxKeyFileBytes = 1 << 20;
/// Encoded bytes after the signed region of a signed message: tag_length (int32) and the tag.
constexpr std::size_t kTrailerBytes = 4 + kAuthTagBytes;

void ensure_sodium() {
  static const bool ready = [] {
    if (sodium_init() < 0) throw std::runtime_error("libsodium: sodium_init failed");
    return true;
  }();
  (void)ready;
}

std::uint64_t read_be(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

std::string errno_text(int err) { return std::strerror(err); }

std::string octal_mode(mode_t mode) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04o", static_cast<unsigned>(mode & 07777));
  return buf;
}

/// The id as a TOML key: bare when it can be, else a basic string (ids are printable ASCII).
std::string toml_key(const std::string& id) {
  const bool bare = std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-';
  });
  if (bare) return id;
  std::string quoted = "\"";
  for (const char c : id) {
    if (c == '"' || c == '\\') quoted += '\\';
    quoted += c;
  }
  return quoted + "\"";
}

/// toml++'s description of a syntax error with every run of 8 or more hex digits replaced by
/// "...": a malformed line may hold key material, and no error may quote it.
std::string scrub_hex(std::string_view text) {
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    std::size_t j = i;
    while (j < text.size() && std::isxdigit(static_cast<unsigned char>(text[j])) != 0) ++j;
    if (j - i >= 8) {
      out += "...";
    } else {
      out.append(text.substr(i, j - i));
    }
    if (j < text.size()) out += text[j];
    i = j + 1;
  }
  return out;
}

/// The encoding of `m` with its tag cleared; empty when encode() does not write exactly
/// getEncodedSize() bytes (a string with a NUL inside: LCM's encoder stops at it).
template <typename Message>
std::vector<std::uint8_t> encode_unsigned(Message& m) {
  m.tag_length = 0;
  m.auth_tag.clear();
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  if (m.encode(bytes.data(), 0, static_cast<int>(bytes.size())) != static_cast<int>(bytes.size())) {
    bytes.clear();
  }
  return bytes;
}

template <typename Message>
void sign_message(Message& m, const AuthKey& key) {
  const std::vector<std::uint8_t> bytes = encode_unsigned(m);
  if (bytes.empty()) {
    throw std::invalid_argument(std::string("cannot sign a ") + Message::getTypeName() +
                                ": a string contains a NUL byte");
  }
  const AuthTag tag = auth_tag(key, bytes.data(), bytes.size() - 4);
  m.auth_tag.assign(tag.begin(), tag.end());
  m.tag_length = static_cast<std::int32_t>(kAuthTagBytes);
}

core::Error unsigned_error() { return {"auth_tag", "unsigned"}; }
core::Error wrong_tag_error() { return {"auth_tag", "wrong tag"}; }

template <typename Message>
core::Status verify_message(const Message& m, const AuthKey& key) {
  if (m.tag_length == 0) return unsigned_error();
  if (m.tag_length != static_cast<std::int32_t>(kAuthTagBytes) ||
      m.auth_tag.size() != kAuthTagBytes) {
    return wrong_tag_error();
  }
  Message copy = m;
  const std::vector<std::uint8_t> bytes = encode_unsigned(copy);
  if (bytes.empty() || !tag_matches(key, bytes.data(), bytes.size() - 4, m.auth_tag))
    return wrong_tag_error();
  return {};
}

}  // namespace

bool is_valid_key_id(std::string_view id) {
  if (id.empty() || id.size() > kMaxSourceIdLength) return false;
  return std::all_of(id.begin(), id.end(), [](char c) { return c >= 0x21 && c <= 0x7e; });
}

core::Expected<KeyRing> KeyRing::parse(std::string_view text, const std::string& file_name) {
  struct Problem {
    std::uint32_t line;
    std::string text;
  };
  std::vector<Problem> problems;
  KeyRing ring;
  if (const auto bad = core::find_unsafe_toml_character(text)) {
    return core::Error{core::one_line(file_name) + ":" + std::to_string(bad->line),
                       "TOML syntax error: non-ASCII character " + bad->where + " (column " +
                           std::to_string(bad->column) + ")"};
  }
  try {
    const toml::table root = toml::parse(text, file_name);
    const toml::table* keys = nullptr;
    for (const auto& [name, node] : root) {
      const std::uint32_t line = name.source().begin.line;
      if (name.str() == "keys" && node.is_table()) {
        keys = node.as_table();
      } else if (node.is_table()) {
        problems.push_back({line, "unknown table [" + std::string(name.str()) +
                                      "] (a key file has one table, [keys])"});
      } else {
        problems.push_back({line, "unknown top-level key \"" + std::string(name.str()) +
                                      "\" (keys go into the table [keys])"});
      }
    }
    if (keys == nullptr) {
      problems.push_back({1, "no [keys] table (a key file is [keys] with <id> = \"<" +
                                 std::to_string(2 * kAuthKeyBytes) + " hex digits>\" lines)"});
    } else if (keys->empty()) {
      problems.push_back({keys->source().begin.line, "[keys] is empty"});
    } else {
      for (const auto& [name, node] : *keys) {
        const std::string id(name.str());
        const std::uint32_t line = name.source().begin.line;
        const std::string what = "key \"" + id + "\": ";
        if (!is_valid_key_id(id)) {
          problems.push_back({line, "key id \"" + id + "\" must be 1 to " +
                                        std::to_string(kMaxSourceIdLength) +
                                        " printable ASCII characters without blanks"});
          continue;
        }
        const auto* value = node.as_string();
        if (value == nullptr) {
          problems.push_back({line, what + "must be a string of " +
                                        std::to_string(2 * kAuthKeyBytes) + " hex digits, is " +
                                        (node.is_table() ? "a table" : "not a string")});
          continue;
        }
        const std::string& hex = value->get();
        if (hex.size() != 2 * kAuthKeyBytes) {
          problems.push_back({line, what + std::to_string(hex.size()) + " characters, needs " +
                                        std::to_string(2 * kAuthKeyBytes) + " hex digits (" +
                                        std::to_string(kAuthKeyBytes) + " bytes)"});
          continue;
        }
        const auto bad = std::find_if(hex.begin(), hex.end(), [](char c) {
          return std::isxdigit(static_cast<unsigned char>(c)) == 0;
        });
        if (bad != hex.end()) {
          problems.push_back({line, what + "character " + std::to_string(bad - hex.begin() + 1) +
                                        " is not a hex digit"});
          continue;
        }
        AuthKey key;
        std::size_t decoded = 0;
        if (sodium_hex2bin(key.bytes.data(), key.bytes.size(), hex.data(), hex.size(), nullptr,
                           &decoded, nullptr) != 0 ||
            decoded != kAuthKeyBytes) {
          problems.push_back(
              {line, what + "not " + std::to_string(2 * kAuthKeyBytes) + " hex digits"});
          continue;
        }
        ring.keys_.emplace_back(id, key);
      }
    }
  } catch (const toml::parse_error& e) {
    const std::uint32_t line = e.source().begin.line;
    const std::string description(e.description());
    if (description.find("redefine") != std::string::npos) {
      // toml++ 3.3 garbles the key in this message ("'\"rereplay\" '"): name it from the line.
      std::string_view rest = text;
      for (std::uint32_t l = 1; l < line && !rest.empty(); ++l) {
        const auto nl = rest.find('\n');
        rest = nl == std::string_view::npos ? std::string_view() : rest.substr(nl + 1);
      }
      std::string_view key = rest.substr(0, std::min(rest.find('='), rest.find('\n')));
      while (!key.empty() && (key.back() == ' ' || key.back() == '\t')) key.remove_suffix(1);
      while (!key.empty() && (key.front() == ' ' || key.front() == '\t')) key.remove_prefix(1);
      problems.push_back({line, "key " + scrub_hex(key) + " is defined twice"});
    } else {
      problems.push_back({line, "TOML syntax error: " + scrub_hex(description)});
    }
  }
  if (!problems.empty()) {
    std::stable_sort(problems.begin(), problems.end(),
                     [](const Problem& a, const Problem& b) { return a.line < b.line; });
    std::string reason = problems.front().text;
    if (problems.size() > 1) {
      reason += " (and " + std::to_string(problems.size() - 1) + " more error" +
                (problems.size() > 2 ? "s" : "") + ")";
    }
    // One line whatever the file name or toml++'s echo of the text holds (found by
    // fuzz_key_file: "expected 'true', saw 't<newline>'").
    return core::Error{core::one_line(file_name) + ":" + std::to_string(problems.front().line),
                       core::one_line(reason)};
  }
  std::sort(ring.keys_.begin(), ring.keys_.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return ring;
}

core::Expected<KeyRing> KeyRing::load(const std::filesystem::path& file) {
  const std::string name = file.string();
  // O_NONBLOCK: a FIFO planted at the path must not block the open (it is refused below).
  const int fd = ::open(name.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) return core::Error{name, "cannot open the key file: " + errno_text(errno)};
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    return core::Error{name, "cannot stat the key file: " + errno_text(errno)};
  if (!S_ISREG(st.st_mode)) return core::Error{name, "the key file is not a regular file"};
  if ((st.st_mode & 077) != 0) {
    return core::Error{name,
                       "mode " + octal_mode(st.st_mode) +
                           " grants access to group or others; a key file must be 0600 or 0400 "
                           "(chmod 600 " +
                           name + ")"};
  }
  if (static_cast<std::uintmax_t>(st.st_size) > kMaxKeyFileBytes) {
    return core::Error{name, std::to_string(st.st_size) + " bytes is too large for a key file"};
  }
  std::string text;
  char chunk[4096];
  while (true) {
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return core::Error{name, "cannot read the key file: " + errno_text(errno)};
    if (n == 0) break;
    text.append(chunk, static_cast<std::size_t>(n));
    if (text.size() > kMaxKeyFileBytes) return core::Error{name, "too large for a key file"};
  }
  sodium_memzero(chunk, sizeof chunk);
  auto ring = parse(text, name);
  sodium_memzero(text.data(), text.size());
  return ring;
}

const AuthKey* KeyRing::find(std::string_view id) const {
  const auto it =
      std::lower_bound(keys_.begin(), keys_.end(), id,
                       [](const auto& entry, std::string_view v) { return entry.first < v; });
  return it != keys_.end() && it->first == id ? &it->second : nullptr;
}

std::vector<std::string> KeyRing::ids() const {
  std::vector<std::string> out;
  out.reserve(keys_.size());
  for (const auto& entry : keys_) out.push_back(entry.first);
  return out;
}

std::uint64_t random_nonce() {
  ensure_sodium();
  std::uint64_t nonce = 0;
  while (nonce == 0) randombytes_buf(&nonce, sizeof nonce);
  return nonce;
}

core::Status write_key_file(const std::filesystem::path& file, std::span<const std::string> ids) {
  ensure_sodium();
  const std::string name = file.string();
  if (ids.empty()) return core::Error{name, "no key ids to write"};
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (!is_valid_key_id(ids[i])) {
      return core::Error{name, "key id \"" + ids[i] + "\" must be 1 to " +
                                   std::to_string(kMaxSourceIdLength) +
                                   " printable ASCII characters without blanks"};
    }
    if (std::find(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(i), ids[i]) !=
        ids.begin() + static_cast<std::ptrdiff_t>(i)) {
      return core::Error{name, "key id \"" + ids[i] + "\" given twice"};
    }
  }
  std::string text =
      "# peritwin key file (messages/README.md, \"Authentication\"): HMAC-SHA256 keys by id.\n"
      "# Keep it mode 0600, and give each machine only the keys it needs.\n"
      "[keys]\n";
  for (const auto& id : ids) {
    AuthKey key;
    randombytes_buf(key.bytes.data(), key.bytes.size());
    char hex[2 * kAuthKeyBytes + 1];
    sodium_bin2hex(hex, sizeof hex, key.bytes.data(), key.bytes.size());
    text += toml_key(id) + " = \"" + hex + "\"\n";
    sodium_memzero(hex, sizeof hex);
    sodium_memzero(key.bytes.data(), key.bytes.size());
  }
  const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) {
    const int err = errno;
    sodium_memzero(text.data(), text.size());
    return core::Error{name, err == EEXIST ? std::string("exists; not overwriting a key file")
                                           : "cannot create the key file: " + errno_text(err)};
  }
  std::string problem;
  if (::fchmod(fd, 0600) != 0) problem = "cannot chmod 600: " + errno_text(errno);
  std::size_t written = 0;
  while (problem.empty() && written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      problem = "cannot write: " + errno_text(errno);
    } else {
      written += static_cast<std::size_t>(n);
    }
  }
  if (problem.empty() && ::fsync(fd) != 0) problem = "cannot sync: " + errno_text(errno);
  if (::close(fd) != 0 && problem.empty()) problem = "cannot close: " + errno_text(errno);
  sodium_memzero(text.data(), text.size());
  if (!problem.empty()) {
    ::unlink(name.c_str());
    return core::Error{name, problem};
  }
  return {};
}

AuthTag auth_tag(const AuthKey& key, const std::uint8_t* data, std::size_t size) {
  ensure_sodium();
  static constexpr std::uint8_t kNothing = 0;
  AuthTag tag;
  crypto_auth_hmacsha256(tag.data(), data != nullptr ? data : &kNothing, size, key.bytes.data());
  return tag;
}

AuthTag hmac_sha256(std::span<const std::uint8_t> key, const std::uint8_t* data, std::size_t size) {
  ensure_sodium();
  static constexpr std::uint8_t kNothing = 0;
  crypto_auth_hmacsha256_state state;
  crypto_auth_hmacsha256_init(&state, key.empty() ? &kNothing : key.data(), key.size());
  crypto_auth_hmacsha256_update(&state, data != nullptr ? data : &kNothing, size);
  AuthTag tag;
  crypto_auth_hmacsha256_final(&state, tag.data());
  sodium_memzero(&state, sizeof state);
  return tag;
}

bool tag_matches(const AuthKey& key, const std::uint8_t* data, std::size_t size,
                 std::span<const std::uint8_t> tag) {
  if (tag.size() != kAuthTagBytes) return false;
  const AuthTag expected = auth_tag(key, data, size);
  return crypto_verify_32(tag.data(), expected.data()) == 0;
}

void sign(peritwin_msgs::load_batch_t& m, const AuthKey& key) { sign_message(m, key); }
void sign(peritwin_msgs::damage_state_t& m, const AuthKey& key) { sign_message(m, key); }
void sign(peritwin_msgs::reject_t& m, const AuthKey& key) { sign_message(m, key); }
void sign(peritwin_msgs::load_samples_t& m, const AuthKey& key) { sign_message(m, key); }
void sign(peritwin_msgs::observation_t& m, const AuthKey& key) { sign_message(m, key); }
core::Status verify(const peritwin_msgs::observation_t& m, const AuthKey& key) {
  return verify_message(m, key);
}

core::Status verify(const peritwin_msgs::load_batch_t& m, const AuthKey& key) {
  return verify_message(m, key);
}
core::Status verify(const peritwin_msgs::damage_state_t& m, const AuthKey& key) {
  return verify_message(m, key);
}
core::Status verify(const peritwin_msgs::reject_t& m, const AuthKey& key) {
  return verify_message(m, key);
}
core::Status verify(const peritwin_msgs::load_samples_t& m, const AuthKey& key) {
  return verify_message(m, key);
}

core::Status verify_encoded(const std::uint8_t* data, std::size_t size, std::int64_t fingerprint,
                            const char* type_name, const AuthKey& key) {
  if (size < 8 + 4) {
    return core::Error{"message", std::to_string(size) + " bytes cannot be a " + type_name};
  }
  if (static_cast<std::int64_t>(read_be(data, 8)) != fingerprint) {
    return core::Error{"message", std::string("wrong fingerprint: not a ") + type_name +
                                      " of this message set version"};
  }
  // A signed message ends with tag_length = kAuthTagBytes and the tag. The tag is checked before
  // the "unsigned" trailer: a tag may end in four zero bytes. A payload that reads both ways (a
  // 32-byte tag trailer whose last four bytes are zero, which does not match) is called a wrong
  // tag: only decoding could tell, and a forged tag is the likelier reading (fuzz_state found it).
  const bool tag_trailer =
      size >= 8 + kTrailerBytes &&
      read_be(data + size - kTrailerBytes, 4) == static_cast<std::uint64_t>(kAuthTagBytes);
  if (tag_trailer &&
      tag_matches(key, data, size - kTrailerBytes,
                  std::span<const std::uint8_t>(data + size - kAuthTagBytes, kAuthTagBytes))) {
    return {};
  }
  if (!tag_trailer && read_be(data + size - 4, 4) == 0) return unsigned_error();
  return wrong_tag_error();
}

}  // namespace peritwin::messages
