// A thin RAII layer over the HDF5 C API (Debian's serial 1.10, built thread-safe): files, groups,
// 1-D datasets of double/float/int64/uint8, scalar strings, attributes, and extendible (chunked,
// unlimited) 1-D datasets with append. Every hid_t is owned by exactly one object and closed by
// its destructor. Every failure throws h5::Error naming the file and the HDF5 object path, with
// HDF5's own innermost reason appended; HDF5's automatic error printing is switched off.
//
// hdf5.h is not included here: users of this header need no HDF5 include directory.
#pragma once

#include <concepts>
#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace peritwin::outputs::h5 {

/// hid_t of HDF5 1.10 (a static_assert in h5_file.cpp checks the two agree).
using Hid = std::int64_t;

/// An HDF5 failure: what failed, on which file, at which object path.
class Error : public std::runtime_error {
 public:
  Error(const std::string& message, std::string file, std::string object);
  [[nodiscard]] const std::string& file() const noexcept { return file_; }
  [[nodiscard]] const std::string& object() const noexcept { return object_; }

 private:
  std::string file_;
  std::string object_;
};

/// Element types this layer writes (stored little-endian IEEE / two's complement) and reads.
enum class ElementType { f64, f32, i64, u8, string, other };

template <class T>
concept Element = std::same_as<T, double> || std::same_as<T, float> ||
    std::same_as<T, std::int64_t> || std::same_as<T, std::uint8_t>;

template <Element T>
constexpr ElementType element_type_of() {
  if constexpr (std::same_as<T, double>) return ElementType::f64;
  if constexpr (std::same_as<T, float>) return ElementType::f32;
  if constexpr (std::same_as<T, std::int64_t>) return ElementType::i64;
  return ElementType::u8;
}

const char* to_string(ElementType type);

/// Owns one hid_t and closes it with the H5*close that matches its kind.
class Handle {
 public:
  enum class Kind { none, file, group, dataset, dataspace, datatype, attribute, plist, object };
  Handle() = default;
  Handle(Hid id, Kind kind) : id_(id), kind_(kind) {}
  ~Handle() { reset(); }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& other) noexcept : id_(other.id_), kind_(other.kind_) { other.id_ = -1; }
  Handle& operator=(Handle&& other) noexcept;

  [[nodiscard]] Hid get() const noexcept { return id_; }
  [[nodiscard]] bool valid() const noexcept { return id_ >= 0; }
  /// Closes now; returns false when HDF5 reported an error while closing.
  bool reset() noexcept;

 private:
  Hid id_ = -1;
  Kind kind_ = Kind::none;
};

/// Options of a fixed-size dataset: 0 = contiguous; 1..9 = chunked, shuffle + deflate level.
struct WriteOptions {
  int deflate_level = 0;
  /// > 1: a 2-D dataset of n / columns rows by `columns` (n must be a multiple), e.g. one row of
  /// components per node; 1: a 1-D dataset of n elements.
  std::size_t columns = 1;
};

/// What groups, datasets and files share: the handle, the file name, the path, attributes.
class Object {
 public:
  /// No limit on the bytes a string read may take.
  static constexpr std::size_t kUnbounded = static_cast<std::size_t>(-1);

  [[nodiscard]] const std::string& file_name() const noexcept { return file_; }
  [[nodiscard]] const std::string& path() const noexcept { return path_; }
  [[nodiscard]] Hid id() const noexcept { return handle_.get(); }

  [[nodiscard]] bool has_attribute(std::string_view name) const;
  [[nodiscard]] std::vector<std::string> attribute_names() const;
  /// Integers are stored as int64, floating point as double, anything convertible to a
  /// string_view as a fixed-length UTF-8 string. An existing attribute is replaced.
  template <class T>
  void set_attribute(std::string_view name, const T& value) {
    if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
      const auto v = static_cast<std::int64_t>(value);
      set_attribute_raw(name, ElementType::i64, &v);
    } else if constexpr (std::is_floating_point_v<T>) {
      const auto v = static_cast<double>(value);
      set_attribute_raw(name, ElementType::f64, &v);
    } else {
      set_string_attribute(name, std::string_view(value));
    }
  }
  /// A 1-D float64 attribute of values.size() elements (an empty span: a 1-D one of none).
  void set_attribute_array(std::string_view name, std::span<const double> values);
  [[nodiscard]] std::int64_t attribute_int64(std::string_view name) const;
  [[nodiscard]] double attribute_double(std::string_view name) const;
  /// Every element of a numeric attribute (scalar or array, integer or float) as double.
  [[nodiscard]] std::vector<double> attribute_doubles(std::string_view name) const;
  /// Whether the attribute is a string (else a number or an array of them).
  [[nodiscard]] bool attribute_is_string(std::string_view name) const;
  /// A string attribute. With `max_bytes` a fixed-length string longer than that, and any
  /// variable-length one (HDF5 allocates it before we could look), is an Error, never allocated.
  [[nodiscard]] std::string attribute_string(std::string_view name,
                                             std::size_t max_bytes = kUnbounded) const;

 protected:
  Object() = default;
  Object(Handle handle, std::string file, std::string path)
      : handle_(std::move(handle)), file_(std::move(file)), path_(std::move(path)) {}
  [[noreturn]] void fail(std::string_view what, std::string_view child = {}) const;
  [[nodiscard]] std::string child_path(std::string_view child) const;

  Handle handle_;
  std::string file_;
  std::string path_;

 private:
  void set_attribute_raw(std::string_view name, ElementType type, const void* value);
  void set_string_attribute(std::string_view name, std::string_view value);
  void read_attribute_raw(std::string_view name, ElementType type, void* out) const;
  /// The attribute `name` opened (errors quieted), or fail("open attribute <name> of").
  [[nodiscard]] Handle open_attribute(const std::string& name) const;
};

/// A 1-D dataset, a 2-D one of rows of components (WriteOptions::columns), or a scalar string
/// dataset. size() and read() count and read every element, row by row.
class Dataset : public Object {
 public:
  Dataset() = default;
  /// Current number of elements (1 for a scalar string).
  [[nodiscard]] std::uint64_t size() const;
  [[nodiscard]] ElementType element_type() const;
  [[nodiscard]] bool extendible() const;

  /// Reads every element; HDF5 converts the stored numeric type to T.
  template <Element T>
  [[nodiscard]] std::vector<T> read() const {
    std::vector<T> out(static_cast<std::size_t>(size()));
    read_raw(element_type_of<T>(), out.data(), out.size());
    return out;
  }
  /// The scalar string; `max_bytes` as for Object::attribute_string.
  [[nodiscard]] std::string read_string(std::size_t max_bytes = kUnbounded) const;

  /// Appends to an extendible dataset (see Group::create_extendible).
  template <Element T>
  void append(std::span<const T> values) {
    append_raw(element_type_of<T>(), values.data(), values.size());
  }
  template <Element T>
  void append(T value) {
    append_raw(element_type_of<T>(), &value, 1);
  }
  /// Sets the extent of an extendible dataset (shrinking drops the tail).
  void resize(std::uint64_t n);

 private:
  friend class Group;
  Dataset(Handle handle, std::string file, std::string path)
      : Object(std::move(handle), std::move(file), std::move(path)) {}
  void read_raw(ElementType type, void* out, std::size_t n) const;
  void append_raw(ElementType type, const void* data, std::size_t n);
};

/// A group (or, through File, the root group). Paths are relative to the group and may contain
/// '/'; intermediate groups are created on writes.
class Group : public Object {
 public:
  Group() = default;

  Group create_group(std::string_view path);
  [[nodiscard]] Group open_group(std::string_view path) const;
  /// Opens the group, creating it (and its parents) when missing.
  Group require_group(std::string_view path);
  /// True when every component of the path exists (as any kind of object).
  [[nodiscard]] bool exists(std::string_view path) const;
  /// Unlinks an object (its space is not reclaimed in the file).
  void remove(std::string_view path);
  /// Names of the direct children, in name order.
  [[nodiscard]] std::vector<std::string> children() const;

  template <Element T>
  Dataset write(std::string_view path, std::span<const T> values,
                const WriteOptions& options = {}) {
    return write_raw(path, element_type_of<T>(), values.data(), values.size(), options);
  }
  template <Element T>
  Dataset write(std::string_view path, const std::vector<T>& values,
                const WriteOptions& options = {}) {
    return write<T>(path, std::span<const T>(values), options);
  }
  template <Element T>
  [[nodiscard]] std::vector<T> read(std::string_view path) const {
    return open_dataset(path).read<T>();
  }
  /// A scalar fixed-length UTF-8 string dataset (no size limit, unlike attributes).
  Dataset write_string(std::string_view path, std::string_view value);
  [[nodiscard]] std::string read_string(std::string_view path,
                                        std::size_t max_bytes = kUnbounded) const;

  /// An empty 1-D dataset with unlimited maximum extent, chunked by `chunk` elements.
  template <Element T>
  Dataset create_extendible(std::string_view path, std::uint64_t chunk = 1024,
                            int deflate_level = 0) {
    return create_extendible_raw(path, element_type_of<T>(), chunk, deflate_level);
  }
  [[nodiscard]] Dataset open_dataset(std::string_view path) const;

 protected:
  Group(Handle handle, std::string file, std::string path)
      : Object(std::move(handle), std::move(file), std::move(path)) {}

 private:
  Dataset write_raw(std::string_view path, ElementType type, const void* data, std::size_t n,
                    const WriteOptions& options);
  Dataset create_extendible_raw(std::string_view path, ElementType type, std::uint64_t chunk,
                                int deflate_level);
};

/// An HDF5 file; as a Group it is the root group "/". Objects opened from it keep the file open
/// until they are destroyed (HDF5's weak close), except File::close(), which insists on being last.
class File : public Group {
 public:
  enum class Mode {
    read_only,
    read_write,
    create_truncate,   ///< create, replacing an existing file
    create_exclusive,  ///< create, fail if the file exists
  };
  struct Options {
    /// HDF5 1.10's flock-based file locking. Off lets a viewer open a results file the daemon
    /// is still writing (the daemon flushes after every write, so what it sees is consistent).
    bool file_locking = true;
  };

  File() = default;
  File(const std::filesystem::path& path, Mode mode);
  File(const std::filesystem::path& path, Mode mode, const Options& options);

  /// Pushes every buffered byte to the operating system (H5Fflush, global scope).
  void flush();
  /// Closes the file now. Throws if other objects of this file are still open (then the file
  /// would stay open and not be durable yet) or if HDF5 fails to close it.
  void close();
  [[nodiscard]] bool is_open() const noexcept { return handle_.valid(); }
};

}  // namespace peritwin::outputs::h5
