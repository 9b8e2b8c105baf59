// What every fuzz target of tests/fuzz shares: libFuzzer's entry point and a check that aborts
// (a finding for libFuzzer, a failed fuzz_corpus.* test otherwise) when a property breaks.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace peritwin::fuzz {

/// Aborts with `what` on stderr unless `ok`.
inline void require(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz property violated: %s\n", what);
    std::abort();
  }
}

/// The input as text.
inline std::string_view text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// Whether the bytes of a signed message type say "unsigned" or "wrong tag" only by a guess
/// (messages/auth.h, verify_encoded): they end in four zero bytes (an unsigned trailer) and either
/// also read as a 32-byte tag (tag_length 32 at 36 bytes from the end) or decode with a tag
/// (`tag_length` of the decoded message) that ends in those zeros.
inline bool auth_reason_is_a_guess(const std::uint8_t* data, std::size_t size,
                                   std::int32_t decoded_tag_length) {
  if (size < 8 + 4) return false;
  const std::uint8_t* end = data + size;
  if (end[-4] != 0 || end[-3] != 0 || end[-2] != 0 || end[-1] != 0) return false;
  const bool tag_trailer =
      size >= 8 + 4 + 32 && end[-36] == 0 && end[-35] == 0 && end[-34] == 0 && end[-33] == 32;
  return tag_trailer || decoded_tag_length != 0;
}

/// A file of this process for readers that only take a path; rewritten per input, removed at
/// exit. In /dev/shm (tmpfs) when there is one: on ext4, truncating and rewriting a file starts
/// its writeback at close, which held each input for up to 50 ms.
class TempFile {
 public:
  explicit TempFile(std::string_view suffix)
      : path_(directory() / ("peritwin-fuzz-" + std::to_string(::getpid()) + std::string(suffix))) {
  }
  ~TempFile() {
    std::error_code ignore;
    std::filesystem::remove(path_, ignore);
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  /// Replaces the file's content with the input; its path.
  const std::filesystem::path& write(const std::uint8_t* data, std::size_t size) {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    out.close();
    require(out.good(), "cannot write the temp file");
    return path_;
  }

 private:
  static std::filesystem::path directory() {
    std::error_code ec;
    if (std::filesystem::is_directory("/dev/shm", ec)) return "/dev/shm";
    return std::filesystem::temp_directory_path();
  }
  std::filesystem::path path_;
};

}  // namespace peritwin::fuzz
