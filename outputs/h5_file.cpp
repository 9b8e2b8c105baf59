#include "outputs/h5_file.h"

#include <hdf5.h>

#include <algorithm>
#include <array>
#include <utility>

namespace peritwin::outputs::h5 {

static_assert(std::is_same_v<hid_t, Hid>, "h5::Hid must be HDF5's hid_t");

namespace {

/// HDF5's automatic error printing is per thread in a thread-safe build: switch it off on every
/// thread that enters this layer.
void quiet() {
  thread_local bool silenced = false;
  if (!silenced) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    silenced = true;
  }
}

herr_t collect_error(unsigned n, const H5E_error2_t* err, void* data) {
  auto* out = static_cast<std::vector<std::string>*>(data);
  if (n < 2 && err->desc != nullptr && err->desc[0] != '\0') out->emplace_back(err->desc);
  return 0;
}

/// The innermost two descriptions of the current HDF5 error stack (the most specific reason
/// first), then clears the stack.
std::string hdf5_reason() {
  std::vector<std::string> parts;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, collect_error, &parts);
  H5Eclear2(H5E_DEFAULT);
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : "; ") + p;
  return out.empty() ? std::string("unknown HDF5 error") : out;
}

[[noreturn]] void raise(std::string_view what, const std::string& file, const std::string& object) {
  std::string msg = "HDF5: cannot " + std::string(what) + " '" + object + "' in file '" + file +
                    "': " + hdf5_reason();
  throw Error(msg, file, object);
}

hid_t file_type(ElementType type) {
  switch (type) {
    case ElementType::f64:
      return H5T_IEEE_F64LE;
    case ElementType::f32:
      return H5T_IEEE_F32LE;
    case ElementType::i64:
      return H5T_STD_I64LE;
    case ElementType::u8:
      return H5T_STD_U8LE;
    default:
      return -1;
  }
}

hid_t memory_type(ElementType type) {
  switch (type) {
    case ElementType::f64:
      return H5T_NATIVE_DOUBLE;
    case ElementType::f32:
      return H5T_NATIVE_FLOAT;
    case ElementType::i64:
      return H5T_NATIVE_INT64;
    case ElementType::u8:
      return H5T_NATIVE_UINT8;
    default:
      return -1;
  }
}

ElementType classify(hid_t type) {
  const H5T_class_t cls = H5Tget_class(type);
  const std::size_t size = H5Tget_size(type);
  if (cls == H5T_FLOAT && size == 8) return ElementType::f64;
  if (cls == H5T_FLOAT && size == 4) return ElementType::f32;
  if (cls == H5T_INTEGER && size == 8 && H5Tget_sign(type) == H5T_SGN_2) return ElementType::i64;
  if (cls == H5T_INTEGER && size == 1 && H5Tget_sign(type) == H5T_SGN_NONE) return ElementType::u8;
  if (cls == H5T_STRING) return ElementType::string;
  return ElementType::other;
}

/// Link creation: parents created on the way, names in UTF-8.
Handle link_create_plist() {
  Handle lcpl(H5Pcreate(H5P_LINK_CREATE), Handle::Kind::plist);
  if (lcpl.valid()) {
    H5Pset_create_intermediate_group(lcpl.get(), 1);
    H5Pset_char_encoding(lcpl.get(), H5T_CSET_UTF8);
  }
  return lcpl;
}

/// A fixed-length UTF-8 string type of `size` bytes (at least 1), NUL-padded.
Handle string_type(std::size_t size) {
  Handle t(H5Tcopy(H5T_C_S1), Handle::Kind::datatype);
  if (t.valid()) {
    H5Tset_size(t.get(), std::max<std::size_t>(size, 1));
    H5Tset_strpad(t.get(), H5T_STR_NULLPAD);
    H5Tset_cset(t.get(), H5T_CSET_UTF8);
  }
  return t;
}

/// Empty when a string stored in `type` may be read within `max_bytes`, else why not.
std::string string_too_long(hid_t type, std::size_t max_bytes) {
  if (max_bytes == Object::kUnbounded || H5Tget_class(type) != H5T_STRING) return {};
  if (H5Tis_variable_str(type) > 0) return "a variable-length string (its size is not bounded)";
  const std::size_t size = H5Tget_size(type);
  if (size > max_bytes) {
    return "a string of " + std::to_string(size) + " bytes, more than the " +
           std::to_string(max_bytes) + " allowed";
  }
  return {};
}

/// Reads a string stored in `type` through `read(memtype, buffer)` (dataset or attribute).
template <class ReadFn>
bool read_string_value(hid_t type, hid_t space, ReadFn read, std::string& out) {
  if (H5Tget_class(type) != H5T_STRING) return false;
  if (H5Tis_variable_str(type) > 0) {
    Handle mem(H5Tcopy(H5T_C_S1), Handle::Kind::datatype);
    if (!mem.valid() || H5Tset_size(mem.get(), H5T_VARIABLE) < 0) return false;
    char* ptr = nullptr;
    if (read(mem.get(), static_cast<void*>(&ptr)) < 0) return false;
    out = ptr != nullptr ? std::string(ptr) : std::string();
    H5Dvlen_reclaim(mem.get(), space, H5P_DEFAULT, &ptr);
    return true;
  }
  const std::size_t size = H5Tget_size(type);
  Handle mem = string_type(size);
  std::string buffer(size, '\0');
  if (!mem.valid() || read(mem.get(), static_cast<void*>(buffer.data())) < 0) return false;
  if (H5Tget_strpad(type) == H5T_STR_NULLPAD) {
    // Exact for every string without trailing NULs (what this layer writes).
    while (!buffer.empty() && buffer.back() == '\0') buffer.pop_back();
  } else {
    buffer.resize(std::min(buffer.size(), buffer.find('\0')));
  }
  out = std::move(buffer);
  return true;
}

}  // namespace

Error::Error(const std::string& message, std::string file, std::string object)
    : std::runtime_error(message), file_(std::move(file)), object_(std::move(object)) {}

const char* to_string(ElementType type) {
  switch (type) {
    case ElementType::f64:
      return "float64";
    case ElementType::f32:
      return "float32";
    case ElementType::i64:
      return "int64";
    case ElementType::u8:
      return "uint8";
    case ElementType::string:
      return "string";
    default:
      return "other";
  }
}

// --- Handle ---------------------------------------------------------------------------------

Handle& Handle::operator=(Handle&& other) noexcept {
  if (this != &other) {
    reset();
    id_ = std::exchange(other.id_, -1);
    kind_ = other.kind_;
  }
  return *this;
}

bool Handle::reset() noexcept {
  if (id_ < 0) return true;
  quiet();
  herr_t status = 0;
  switch (kind_) {
    case Kind::file:
      status = H5Fclose(id_);
      break;
    case Kind::group:
      status = H5Gclose(id_);
      break;
    case Kind::dataset:
      status = H5Dclose(id_);
      break;
    case Kind::dataspace:
      status = H5Sclose(id_);
      break;
    case Kind::datatype:
      status = H5Tclose(id_);
      break;
    case Kind::attribute:
      status = H5Aclose(id_);
      break;
    case Kind::plist:
      status = H5Pclose(id_);
      break;
    case Kind::object:
      status = H5Oclose(id_);
      break;
    case Kind::none:
      break;
  }
  id_ = -1;
  if (status < 0) H5Eclear2(H5E_DEFAULT);
  return status >= 0;
}

// --- Object: attributes -----------------------------------------------------------------------

std::string Object::child_path(std::string_view child) const {
  if (child.empty()) return path_;
  std::string out;
  if (child.front() != '/') {
    out.append(path_);
    if (out.empty() || out.back() != '/') out.push_back('/');
  }
  out.append(child);
  return out;
}

void Object::fail(std::string_view what, std::string_view child) const {
  raise(what, file_, child_path(child));
}

bool Object::has_attribute(std::string_view name) const {
  quiet();
  const htri_t e = H5Aexists(id(), std::string(name).c_str());
  if (e < 0) fail("look up attribute '" + std::string(name) + "' of");
  return e > 0;
}

std::vector<std::string> Object::attribute_names() const {
  quiet();
  std::vector<std::string> names;
  auto cb = [](hid_t, const char* name, const H5A_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  hsize_t idx = 0;
  if (H5Aiterate2(id(), H5_INDEX_NAME, H5_ITER_INC, &idx, cb, &names) < 0) {
    fail("list the attributes of");
  }
  return names;
}

void Object::set_attribute_raw(std::string_view name, ElementType type, const void* value) {
  quiet();
  const std::string n(name);
  if (has_attribute(name) && H5Adelete(id(), n.c_str()) < 0) fail("replace attribute " + n + " of");
  Handle space(H5Screate(H5S_SCALAR), Handle::Kind::dataspace);
  Handle attr(H5Acreate2(id(), n.c_str(), file_type(type), space.get(), H5P_DEFAULT, H5P_DEFAULT),
              Handle::Kind::attribute);
  if (!attr.valid() || H5Awrite(attr.get(), memory_type(type), value) < 0) {
    fail("write attribute " + n + " of");
  }
}

void Object::set_string_attribute(std::string_view name, std::string_view value) {
  quiet();
  const std::string n(name);
  if (has_attribute(name) && H5Adelete(id(), n.c_str()) < 0) fail("replace attribute " + n + " of");
  Handle type = string_type(value.size());
  Handle space(H5Screate(H5S_SCALAR), Handle::Kind::dataspace);
  Handle attr(H5Acreate2(id(), n.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
              Handle::Kind::attribute);
  std::string buffer(std::max<std::size_t>(value.size(), 1), '\0');
  std::copy(value.begin(), value.end(), buffer.begin());
  if (!attr.valid() || H5Awrite(attr.get(), type.get(), buffer.data()) < 0) {
    fail("write attribute " + n + " of");
  }
}

void Object::set_attribute_array(std::string_view name, std::span<const double> values) {
  quiet();
  const std::string n(name);
  if (has_attribute(name) && H5Adelete(id(), n.c_str()) < 0) fail("replace attribute " + n + " of");
  const hsize_t dims[1] = {static_cast<hsize_t>(values.size())};
  Handle space(H5Screate_simple(1, dims, nullptr), Handle::Kind::dataspace);
  Handle attr(H5Acreate2(id(), n.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
              Handle::Kind::attribute);
  if (!attr.valid() ||
      (!values.empty() && H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, values.data()) < 0)) {
    fail("write attribute " + n + " of");
  }
}

Handle Object::open_attribute(const std::string& name) const {
  quiet();
  Handle attr(H5Aopen(id(), name.c_str(), H5P_DEFAULT), Handle::Kind::attribute);
  if (!attr.valid()) fail("open attribute " + name + " of");
  return attr;
}

std::vector<double> Object::attribute_doubles(std::string_view name) const {
  const std::string n(name);
  const Handle attr = open_attribute(n);
  Handle ftype(H5Aget_type(attr.get()), Handle::Kind::datatype);
  Handle space(H5Aget_space(attr.get()), Handle::Kind::dataspace);
  const H5T_class_t cls = H5Tget_class(ftype.get());
  const hssize_t count = H5Sget_simple_extent_npoints(space.get());
  if ((cls != H5T_INTEGER && cls != H5T_FLOAT) || count < 0) {
    throw Error(
        "HDF5: attribute " + n + " of '" + path_ + "' in file '" + file_ + "' is not numeric",
        file_, path_);
  }
  std::vector<double> out(static_cast<std::size_t>(count));
  if (!out.empty() && H5Aread(attr.get(), H5T_NATIVE_DOUBLE, out.data()) < 0) {
    fail("read attribute " + n + " of");
  }
  return out;
}

bool Object::attribute_is_string(std::string_view name) const {
  const std::string n(name);
  const Handle attr = open_attribute(n);
  Handle ftype(H5Aget_type(attr.get()), Handle::Kind::datatype);
  return H5Tget_class(ftype.get()) == H5T_STRING;
}

void Object::read_attribute_raw(std::string_view name, ElementType type, void* out) const {
  const std::string n(name);
  const Handle attr = open_attribute(n);
  Handle ftype(H5Aget_type(attr.get()), Handle::Kind::datatype);
  Handle space(H5Aget_space(attr.get()), Handle::Kind::dataspace);
  const H5T_class_t want = type == ElementType::i64 ? H5T_INTEGER : H5T_FLOAT;
  if (H5Tget_class(ftype.get()) != want || H5Sget_simple_extent_npoints(space.get()) != 1) {
    throw Error("HDF5: attribute " + n + " of '" + path_ + "' in file '" + file_ +
                    "' is not a scalar " + (want == H5T_INTEGER ? "integer" : "float"),
                file_, path_);
  }
  if (H5Aread(attr.get(), memory_type(type), out) < 0) fail("read attribute " + n + " of");
}

std::int64_t Object::attribute_int64(std::string_view name) const {
  std::int64_t v = 0;
  read_attribute_raw(name, ElementType::i64, &v);
  return v;
}

double Object::attribute_double(std::string_view name) const {
  double v = 0.0;
  read_attribute_raw(name, ElementType::f64, &v);
  return v;
}

std::string Object::attribute_string(std::string_view name, std::size_t max_bytes) const {
  const std::string n(name);
  const Handle attr = open_attribute(n);
  Handle ftype(H5Aget_type(attr.get()), Handle::Kind::datatype);
  Handle space(H5Aget_space(attr.get()), Handle::Kind::dataspace);
  if (const std::string why = string_too_long(ftype.get(), max_bytes); !why.empty()) {
    throw Error("HDF5: attribute " + n + " of '" + path_ + "' in file '" + file_ + "' is " + why,
                file_, path_);
  }
  std::string out;
  auto read = [&](hid_t mem, void* buf) { return H5Aread(attr.get(), mem, buf); };
  if (!read_string_value(ftype.get(), space.get(), read, out)) {
    fail("read string attribute " + n + " of");
  }
  return out;
}

// --- Dataset ---------------------------------------------------------------------------------

std::uint64_t Dataset::size() const {
  quiet();
  Handle space(H5Dget_space(id()), Handle::Kind::dataspace);
  const hssize_t n = space.valid() ? H5Sget_simple_extent_npoints(space.get()) : -1;
  if (n < 0) fail("get the size of dataset");
  return static_cast<std::uint64_t>(n);
}

ElementType Dataset::element_type() const {
  quiet();
  Handle type(H5Dget_type(id()), Handle::Kind::datatype);
  if (!type.valid()) fail("get the type of dataset");
  return classify(type.get());
}

bool Dataset::extendible() const {
  quiet();
  Handle space(H5Dget_space(id()), Handle::Kind::dataspace);
  if (!space.valid() || H5Sget_simple_extent_ndims(space.get()) != 1) return false;
  hsize_t dims[1] = {0}, maxdims[1] = {0};
  H5Sget_simple_extent_dims(space.get(), dims, maxdims);
  return maxdims[0] == H5S_UNLIMITED;
}

void Dataset::read_raw(ElementType type, void* out, std::size_t n) const {
  quiet();
  const ElementType stored = element_type();
  if (stored == ElementType::string || stored == ElementType::other) {
    throw Error("HDF5: dataset '" + path_ + "' in file '" + file_ + "' holds " + to_string(stored) +
                    ", not " + to_string(type),
                file_, path_);
  }
  if (n == 0) return;
  if (H5Dread(id(), memory_type(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, out) < 0) {
    fail("read dataset");
  }
}

std::string Dataset::read_string(std::size_t max_bytes) const {
  quiet();
  Handle ftype(H5Dget_type(id()), Handle::Kind::datatype);
  Handle space(H5Dget_space(id()), Handle::Kind::dataspace);
  if (const std::string why = string_too_long(ftype.get(), max_bytes); !why.empty()) {
    throw Error("HDF5: dataset '" + path_ + "' in file '" + file_ + "' is " + why, file_, path_);
  }
  std::string out;
  auto read = [&](hid_t mem, void* buf) {
    return H5Dread(id(), mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
  };
  if (!ftype.valid() || H5Sget_simple_extent_npoints(space.get()) != 1 ||
      !read_string_value(ftype.get(), space.get(), read, out)) {
    fail("read a scalar string from dataset");
  }
  return out;
}

void Dataset::resize(std::uint64_t n) {
  quiet();
  const hsize_t dims[1] = {static_cast<hsize_t>(n)};
  if (H5Dset_extent(id(), dims) < 0) fail("resize dataset");
}

void Dataset::append_raw(ElementType type, const void* data, std::size_t n) {
  quiet();
  if (n == 0) return;
  const hsize_t start[1] = {static_cast<hsize_t>(size())};
  const hsize_t count[1] = {static_cast<hsize_t>(n)};
  const hsize_t dims[1] = {start[0] + count[0]};
  if (H5Dset_extent(id(), dims) < 0) fail("extend dataset");
  Handle filespace(H5Dget_space(id()), Handle::Kind::dataspace);
  Handle memspace(H5Screate_simple(1, count, nullptr), Handle::Kind::dataspace);
  if (!filespace.valid() || !memspace.valid() ||
      H5Sselect_hyperslab(filespace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr) < 0 ||
      H5Dwrite(id(), memory_type(type), memspace.get(), filespace.get(), H5P_DEFAULT, data) < 0) {
    fail("append to dataset");
  }
}

// --- Group -----------------------------------------------------------------------------------

Group Group::create_group(std::string_view path) {
  quiet();
  Handle lcpl = link_create_plist();
  Handle g(H5Gcreate2(id(), std::string(path).c_str(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT),
           Handle::Kind::group);
  if (!g.valid()) fail("create group", path);
  return Group(std::move(g), file_, child_path(path));
}

Group Group::open_group(std::string_view path) const {
  quiet();
  Handle g(H5Gopen2(id(), std::string(path).c_str(), H5P_DEFAULT), Handle::Kind::group);
  if (!g.valid()) fail("open group", path);
  return Group(std::move(g), file_, child_path(path));
}

Group Group::require_group(std::string_view path) {
  return exists(path) ? open_group(path) : create_group(path);
}

bool Group::exists(std::string_view path) const {
  quiet();
  std::string prefix;
  std::size_t pos = 0;
  if (!path.empty() && path.front() == '/') {
    prefix = "/";
    pos = 1;
  }
  while (pos < path.size()) {
    const std::size_t next = std::min(path.find('/', pos), path.size());
    if (next > pos) {
      if (!prefix.empty() && prefix.back() != '/') prefix += '/';
      prefix.append(path.substr(pos, next - pos));
      const htri_t e = H5Lexists(id(), prefix.c_str(), H5P_DEFAULT);
      if (e < 0) fail("look up", prefix);
      if (e == 0) return false;
    }
    pos = next + 1;
  }
  return true;
}

void Group::remove(std::string_view path) {
  quiet();
  if (H5Ldelete(id(), std::string(path).c_str(), H5P_DEFAULT) < 0) fail("remove", path);
}

std::vector<std::string> Group::children() const {
  quiet();
  std::vector<std::string> names;
  auto cb = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  hsize_t idx = 0;
  if (H5Literate(id(), H5_INDEX_NAME, H5_ITER_INC, &idx, cb, &names) < 0) {
    fail("list the children of");
  }
  return names;
}

Dataset Group::write_raw(std::string_view path, ElementType type, const void* data, std::size_t n,
                         const WriteOptions& options) {
  quiet();
  const hsize_t columns = std::max<hsize_t>(options.columns, 1);
  if (n % columns != 0) {
    throw Error("HDF5: " + std::to_string(n) + " values for dataset '" + std::string(path) +
                    "' in file '" + file_ + "' do not fill rows of " + std::to_string(columns),
                file_, child_path(path));
  }
  const int rank = columns > 1 ? 2 : 1;
  const hsize_t dims[2] = {static_cast<hsize_t>(n) / columns, columns};
  Handle space(H5Screate_simple(rank, dims, nullptr), Handle::Kind::dataspace);
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), Handle::Kind::plist);
  if (options.deflate_level > 0 && n > 0) {
    const hsize_t chunk[2] = {std::min<hsize_t>(dims[0], 65536 / columns + 1), columns};
    H5Pset_chunk(dcpl.get(), rank, chunk);
    H5Pset_shuffle(dcpl.get());
    H5Pset_deflate(dcpl.get(), static_cast<unsigned>(std::min(options.deflate_level, 9)));
  }
  Handle lcpl = link_create_plist();
  Handle ds(H5Dcreate2(id(), std::string(path).c_str(), file_type(type), space.get(), lcpl.get(),
                       dcpl.get(), H5P_DEFAULT),
            Handle::Kind::dataset);
  if (!ds.valid()) fail("create dataset", path);
  if (n > 0 && H5Dwrite(ds.get(), memory_type(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    fail("write dataset", path);
  }
  return Dataset(std::move(ds), file_, child_path(path));
}

Dataset Group::write_string(std::string_view path, std::string_view value) {
  quiet();
  Handle type = string_type(value.size());
  Handle space(H5Screate(H5S_SCALAR), Handle::Kind::dataspace);
  Handle lcpl = link_create_plist();
  Handle ds(H5Dcreate2(id(), std::string(path).c_str(), type.get(), space.get(), lcpl.get(),
                       H5P_DEFAULT, H5P_DEFAULT),
            Handle::Kind::dataset);
  if (!ds.valid()) fail("create string dataset", path);
  std::string buffer(std::max<std::size_t>(value.size(), 1), '\0');
  std::copy(value.begin(), value.end(), buffer.begin());
  if (H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data()) < 0) {
    fail("write string dataset", path);
  }
  return Dataset(std::move(ds), file_, child_path(path));
}

std::string Group::read_string(std::string_view path, std::size_t max_bytes) const {
  return open_dataset(path).read_string(max_bytes);
}

Dataset Group::create_extendible_raw(std::string_view path, ElementType type, std::uint64_t chunk,
                                     int deflate_level) {
  quiet();
  const hsize_t dims[1] = {0};
  const hsize_t maxdims[1] = {H5S_UNLIMITED};
  const hsize_t chunk_dims[1] = {std::max<hsize_t>(chunk, 1)};
  Handle space(H5Screate_simple(1, dims, maxdims), Handle::Kind::dataspace);
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), Handle::Kind::plist);
  H5Pset_chunk(dcpl.get(), 1, chunk_dims);
  if (deflate_level > 0) {
    H5Pset_shuffle(dcpl.get());
    H5Pset_deflate(dcpl.get(), static_cast<unsigned>(std::min(deflate_level, 9)));
  }
  Handle lcpl = link_create_plist();
  Handle ds(H5Dcreate2(id(), std::string(path).c_str(), file_type(type), space.get(), lcpl.get(),
                       dcpl.get(), H5P_DEFAULT),
            Handle::Kind::dataset);
  if (!ds.valid()) fail("create extendible dataset", path);
  return Dataset(std::move(ds), file_, child_path(path));
}

Dataset Group::open_dataset(std::string_view path) const {
  quiet();
  Handle ds(H5Dopen2(id(), std::string(path).c_str(), H5P_DEFAULT), Handle::Kind::dataset);
  if (!ds.valid()) fail("open dataset", path);
  return Dataset(std::move(ds), file_, child_path(path));
}

// --- File ------------------------------------------------------------------------------------

File::File(const std::filesystem::path& path, Mode mode) : File(path, mode, Options{}) {}

File::File(const std::filesystem::path& path, Mode mode, const Options& options)
    : Group(Handle(), path.string(), std::string(1, '/')) {
  quiet();
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), Handle::Kind::plist);
  // Object headers with checksums (1.8 format and later): corruption of metadata is detected.
  H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_LATEST);
  H5Pset_file_locking(fapl.get(), options.file_locking ? 1 : 0, 1);
  hid_t id = -1;
  const char* what = "open";
  switch (mode) {
    case Mode::read_only:
      id = H5Fopen(file_.c_str(), H5F_ACC_RDONLY, fapl.get());
      break;
    case Mode::read_write:
      id = H5Fopen(file_.c_str(), H5F_ACC_RDWR, fapl.get());
      break;
    case Mode::create_truncate:
      what = "create";
      id = H5Fcreate(file_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get());
      break;
    case Mode::create_exclusive:
      what = "create";
      id = H5Fcreate(file_.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, fapl.get());
      break;
  }
  if (id < 0) raise(what, file_, "/");
  handle_ = Handle(id, Handle::Kind::file);
}

void File::flush() {
  quiet();
  if (H5Fflush(id(), H5F_SCOPE_GLOBAL) < 0) fail("flush");
}

void File::close() {
  quiet();
  if (!handle_.valid()) return;
  const ssize_t open = H5Fget_obj_count(id(), H5F_OBJ_ALL | H5F_OBJ_LOCAL);
  if (open > 1) {
    throw Error("HDF5: cannot close file '" + file_ + "': " + std::to_string(open - 1) +
                    " object(s) of it are still open",
                file_, "/");
  }
  if (!handle_.reset()) {
    throw Error("HDF5: closing file '" + file_ + "' failed", file_, "/");
  }
}

}  // namespace peritwin::outputs::h5
