#include "outputs/checkpoint_io.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <system_error>
#include <utility>

#include "core/fnv1a.h"
#include "outputs/h5_file.h"

namespace peritwin::outputs {

namespace {

constexpr const char* kFormat = "peritwin-checkpoint";
constexpr std::int64_t kLayoutVersion = 1;

// --- the checksum: byte-wise FNV-1a 64 (core/fnv1a.h) over a canonical serialization ---

class ChecksumWriter {
 public:
  void u64(std::uint64_t v) {
    unsigned char le[8];
    for (int i = 0; i < 8; ++i) le[i] = static_cast<unsigned char>(v >> (8 * i));
    h_.bytes(le, 8);
  }
  void name(std::string_view s) {
    h_.bytes(s);
    const unsigned char nul = 0;
    h_.bytes(&nul, 1);
  }
  template <class T>
  void array(const std::vector<T>& values) {
    u64(values.size());
    if constexpr (std::endian::native == std::endian::little || sizeof(T) == 1) {
      h_.bytes(values.data(), values.size() * sizeof(T));
    } else {
      for (const T& v : values) u64(std::bit_cast<std::uint64_t>(v));
    }
  }
  void bytes(const void* data, std::size_t n) { h_.bytes(data, n); }
  [[nodiscard]] std::uint64_t value() const { return h_.get(); }

 private:
  core::Fnv1a64 h_;
};

void check_name(const std::string& name) {
  if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos) {
    throw std::invalid_argument("checkpoint entry name '" + name +
                                "' is invalid (empty, '.', '..' or contains '/')");
  }
}

template <class Map>
void check_names(const Map& map) {
  for (const auto& entry : map) check_name(entry.first);
}

/// An owned POSIX file descriptor.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  [[nodiscard]] int get() const { return fd_; }
  int release() { return std::exchange(fd_, -1); }

 private:
  int fd_;
};

[[noreturn]] void throw_errno(const std::string& what, const std::filesystem::path& path) {
  throw std::system_error(errno, std::generic_category(), what + " '" + path.string() + "'");
}

void fsync_path(const std::filesystem::path& path, int flags, const char* what) {
  Fd fd(::open(path.c_str(), flags | O_CLOEXEC));
  if (fd.get() < 0) throw_errno(std::string("cannot open ") + what, path);
  if (::fsync(fd.get()) != 0) throw_errno(std::string("cannot fsync ") + what, path);
  if (::close(fd.release()) != 0) throw_errno(std::string("cannot close ") + what, path);
}

std::filesystem::path directory_of(const std::filesystem::path& path) {
  const auto dir = path.parent_path();
  return dir.empty() ? std::filesystem::path(".") : dir;
}

std::filesystem::path tmp_path_of(const std::filesystem::path& path) {
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  return tmp;
}

/// seq of "<prefix>-<digits><suffix>", or nullopt.
std::optional<std::uint64_t> parse_seq(std::string_view name, std::string_view prefix,
                                       std::string_view suffix) {
  if (name.size() <= prefix.size() + 1 + suffix.size()) return std::nullopt;
  if (name.substr(0, prefix.size()) != prefix || name[prefix.size()] != '-') return std::nullopt;
  if (name.substr(name.size() - suffix.size()) != suffix) return std::nullopt;
  const std::string_view digits =
      name.substr(prefix.size() + 1, name.size() - prefix.size() - 1 - suffix.size());
  if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return std::nullopt;
  }
  std::uint64_t seq = 0;
  const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), seq);
  if (ec != std::errc() || ptr != digits.data() + digits.size()) return std::nullopt;
  return seq;
}

/// What reading a checkpoint may allocate: no more than the file holds, since a checkpoint
/// stores every element of its arrays and strings (contiguous, uncompressed). HDF5 reads a
/// dataset whose storage was never written as fill values, so without this a few-kB corrupt file
/// could declare terabytes and have them allocated and filled.
class ReadBudget {
 public:
  explicit ReadBudget(std::uintmax_t file_bytes) : left_(file_bytes) {}
  [[nodiscard]] std::uintmax_t left() const { return left_; }
  /// Takes n elements of `element_bytes` each, or throws naming `what`.
  void take(std::uint64_t n, std::size_t element_bytes, const std::string& what) {
    if (n > left_ / element_bytes) {
      throw std::runtime_error(what + " claims " + std::to_string(n) + " elements of " +
                               std::to_string(element_bytes) + " bytes, more than the " +
                               std::to_string(left_) + " bytes of the file left to read");
    }
    left_ -= n * element_bytes;
  }

 private:
  std::uintmax_t left_;
};

template <h5::Element T>
void read_arrays(const h5::Group& group, std::map<std::string, std::vector<T>>& out,
                 ReadBudget& budget) {
  for (const auto& name : group.children()) {
    const h5::Dataset ds = group.open_dataset(name);
    if (ds.element_type() != h5::element_type_of<T>()) {
      throw std::runtime_error("array '" + ds.path() + "' holds " +
                               h5::to_string(ds.element_type()) + ", expected " +
                               h5::to_string(h5::element_type_of<T>()));
    }
    budget.take(ds.size(), sizeof(T), "array '" + ds.path() + "'");
    out.emplace(name, ds.read<T>());
  }
}

/// The longest root attribute string (format name, checksum) a checkpoint has.
constexpr std::size_t kMaxAttributeString = 64;

}  // namespace

CheckpointError::CheckpointError(const std::filesystem::path& path, const std::string& reason)
    : std::runtime_error("checkpoint '" + path.string() + "': " + reason), path_(path) {}

std::uint64_t checkpoint_checksum(const twin::CheckpointData& data) {
  ChecksumWriter h;
  h.u64(static_cast<std::uint64_t>(data.format_version));
  auto arrays = [&h](const char* section, const auto& map) {
    h.name(section);
    for (const auto& [name, values] : map) {
      h.name(name);
      h.array(values);
    }
  };
  arrays("#f64", data.f64_arrays);
  arrays("#i64", data.i64_arrays);
  arrays("#u8", data.u8_arrays);
  h.name("#i64-scalars");
  for (const auto& [name, v] : data.i64_scalars) {
    h.name(name);
    h.u64(static_cast<std::uint64_t>(v));
  }
  h.name("#f64-scalars");
  for (const auto& [name, v] : data.f64_scalars) {
    h.name(name);
    h.u64(std::bit_cast<std::uint64_t>(v));
  }
  h.name("#strings");
  for (const auto& [name, s] : data.strings) {
    h.name(name);
    h.u64(s.size());
    h.bytes(s.data(), s.size());
  }
  return h.value();
}

void write_checkpoint(const std::filesystem::path& path, const twin::CheckpointData& data) {
  check_names(data.f64_arrays);
  check_names(data.i64_arrays);
  check_names(data.u8_arrays);
  check_names(data.i64_scalars);
  check_names(data.f64_scalars);
  check_names(data.strings);
  const std::filesystem::path tmp = tmp_path_of(path);
  std::error_code ignore;
  std::filesystem::remove(tmp, ignore);
  try {
    h5::File file(tmp, h5::File::Mode::create_truncate);
    {
      h5::Group f64 = file.create_group("arrays/f64");
      for (const auto& [name, values] : data.f64_arrays) f64.write<double>(name, values);
      h5::Group i64 = file.create_group("arrays/i64");
      for (const auto& [name, values] : data.i64_arrays) i64.write<std::int64_t>(name, values);
      h5::Group u8 = file.create_group("arrays/u8");
      for (const auto& [name, values] : data.u8_arrays) u8.write<std::uint8_t>(name, values);
      h5::Group si = file.create_group("scalars/i64");
      for (const auto& [name, v] : data.i64_scalars) si.set_attribute(name, v);
      h5::Group sf = file.create_group("scalars/f64");
      for (const auto& [name, v] : data.f64_scalars) sf.set_attribute(name, v);
      h5::Group strings = file.create_group("strings");
      for (const auto& [name, s] : data.strings) strings.write_string(name, s);
      file.set_attribute("format", std::string_view(kFormat));
      file.set_attribute("layout_version", kLayoutVersion);
      file.set_attribute("format_version", data.format_version);
      file.set_attribute("checksum_fnv1a64", core::hex64(checkpoint_checksum(data)));
    }
    file.flush();
    file.close();
    fsync_file(tmp);
    std::filesystem::rename(tmp, path);
    fsync_directory(directory_of(path));
  } catch (const std::exception& e) {
    std::filesystem::remove(tmp, ignore);
    throw CheckpointError(path, std::string("write failed: ") + e.what());
  }
}

twin::CheckpointData read_checkpoint(const std::filesystem::path& path) {
  twin::CheckpointData data;
  std::string stored_checksum;
  try {
    if (!std::filesystem::is_regular_file(path)) throw std::runtime_error("no such file");
    ReadBudget budget(std::filesystem::file_size(path));
    const h5::File file(path, h5::File::Mode::read_only);
    if (!file.has_attribute("format") ||
        file.attribute_string("format", kMaxAttributeString) != kFormat) {
      throw std::runtime_error("not a peritwin checkpoint (attribute 'format' missing or wrong)");
    }
    const std::int64_t layout = file.attribute_int64("layout_version");
    if (layout != kLayoutVersion) {
      throw std::runtime_error("layout_version " + std::to_string(layout) +
                               " is not supported (this build reads " +
                               std::to_string(kLayoutVersion) + ")");
    }
    data.format_version = file.attribute_int64("format_version");
    stored_checksum = file.attribute_string("checksum_fnv1a64", kMaxAttributeString);
    read_arrays(file.open_group("arrays/f64"), data.f64_arrays, budget);
    read_arrays(file.open_group("arrays/i64"), data.i64_arrays, budget);
    read_arrays(file.open_group("arrays/u8"), data.u8_arrays, budget);
    const h5::Group si = file.open_group("scalars/i64");
    for (const auto& name : si.attribute_names()) data.i64_scalars[name] = si.attribute_int64(name);
    const h5::Group sf = file.open_group("scalars/f64");
    for (const auto& name : sf.attribute_names())
      data.f64_scalars[name] = sf.attribute_double(name);
    const h5::Group strings = file.open_group("strings");
    for (const auto& name : strings.children()) {
      std::string value = strings.read_string(name, budget.left());
      budget.take(value.size(), 1, "string '" + name + "'");
      data.strings[name] = std::move(value);
    }
  } catch (const std::exception& e) {
    throw CheckpointError(path, std::string("unreadable: ") + e.what());
  }
  const std::string computed = core::hex64(checkpoint_checksum(data));
  if (computed != stored_checksum) {
    throw CheckpointError(path, "corrupt: checksum mismatch (stored " + stored_checksum +
                                    ", computed " + computed + ")");
  }
  return data;
}

std::filesystem::path checkpoint_path(const std::filesystem::path& dir, std::string_view prefix,
                                      std::uint64_t seq) {
  char digits[32];
  std::snprintf(digits, sizeof digits, "%012llu", static_cast<unsigned long long>(seq));
  return dir / (std::string(prefix) + "-" + digits + ".h5");
}

std::vector<CheckpointFile> list_checkpoints(const std::filesystem::path& dir,
                                             std::string_view prefix) {
  std::vector<CheckpointFile> out;
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return out;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (const auto seq = parse_seq(name, prefix, ".h5")) out.push_back({entry.path(), *seq});
  }
  std::sort(out.begin(), out.end(),
            [](const CheckpointFile& a, const CheckpointFile& b) { return a.seq > b.seq; });
  return out;
}

std::optional<FoundCheckpoint> newest_valid_checkpoint(const std::filesystem::path& dir,
                                                       std::string_view prefix,
                                                       std::vector<std::string>* skipped) {
  for (const auto& file : list_checkpoints(dir, prefix)) {
    try {
      return FoundCheckpoint{file, read_checkpoint(file.path)};
    } catch (const CheckpointError& e) {
      if (skipped != nullptr) skipped->push_back(e.what());
    }
  }
  return std::nullopt;
}

std::vector<std::filesystem::path> prune_checkpoints(const std::filesystem::path& dir,
                                                     std::string_view prefix, std::size_t keep) {
  if (keep == 0) throw std::invalid_argument("prune_checkpoints: keep must be at least 1");
  std::vector<std::filesystem::path> removed;
  const auto files = list_checkpoints(dir, prefix);
  if (files.empty()) return removed;
  for (std::size_t i = keep; i < files.size(); ++i) {
    if (std::filesystem::remove(files[i].path)) removed.push_back(files[i].path);
  }
  const std::uint64_t newest = files.front().seq;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const auto seq = parse_seq(entry.path().filename().string(), prefix, ".h5.tmp");
    if (seq && *seq < newest && std::filesystem::remove(entry.path())) {
      removed.push_back(entry.path());
    }
  }
  if (!removed.empty()) fsync_directory(dir);
  return removed;
}

// --- durable file helpers ----------------------------------------------------------------------

void fsync_file(const std::filesystem::path& path) { fsync_path(path, O_RDONLY, "file"); }

void fsync_directory(const std::filesystem::path& dir) {
  fsync_path(dir, O_RDONLY | O_DIRECTORY, "directory");
}

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes,
                           bool durable) {
  const std::filesystem::path tmp = tmp_path_of(path);
  try {
    Fd fd(::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
    if (fd.get() < 0) throw_errno("cannot create", tmp);
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(fd.get(), bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw_errno("cannot write", tmp);
      done += static_cast<std::size_t>(n);
    }
    if (durable && ::fsync(fd.get()) != 0) throw_errno("cannot fsync", tmp);
    if (::close(fd.release()) != 0) throw_errno("cannot close", tmp);
    if (::rename(tmp.c_str(), path.c_str()) != 0) throw_errno("cannot rename into", path);
  } catch (...) {
    std::error_code ignore;
    std::filesystem::remove(tmp, ignore);
    throw;
  }
  if (durable) fsync_directory(directory_of(path));
}

}  // namespace peritwin::outputs
