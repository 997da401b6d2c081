// Hdf5Reader.cpp — the checked HDF5 reads (Hdf5Reader.h).
#include "Hdf5Reader.h"

#include <cmath>
#include <cstring>
#include <type_traits>

namespace brittle::hdf5 {
namespace {

// zlib cannot inflate more than about 1032 bytes per stored byte, so a dataset that claims more
// than this many bytes per stored byte is lying about its shape. Checking this before allocating
// bounds every allocation by the size of the file, whatever its dataspaces claim.
constexpr hsize_t kMaxInflateRatio = 1100;

// "[i, j]" of a flat row-major index.
std::string indexString(size_t flat, const std::vector<hsize_t>& dims) {
  std::vector<hsize_t> index(dims.size());
  for (size_t d = dims.size(); d-- > 0;) {
    index[d] = dims[d] == 0 ? 0 : flat % dims[d];
    flat = dims[d] == 0 ? 0 : flat / dims[d];
  }
  return shapeString(index);
}

// A failed read of a dataset whose shape and type checked out means its stored bytes are bad:
// the Fletcher-32 filter found a mismatch, or deflate could not decode the chunk. `dims` are the
// dataset's; only `rows` of them are read.
void readRows(const Handle& dset, const std::string& path, hid_t memType, void* buffer, size_t count,
              const std::vector<hsize_t>& dims = {}, Rows rows = {}) {
  if (count == 0) return;
  Handle fileSpace, memSpace;
  if (rows.count != kAny) {
    std::vector<hsize_t> start(dims.size(), 0), extent = dims;
    start[0] = rows.first;
    extent[0] = rows.count;
    fileSpace = hdf5::dataspaceHandle(H5Dget_space(dset.get()));
    memSpace = hdf5::dataspaceHandle(H5Screate_simple(static_cast<int>(extent.size()), extent.data(), nullptr));
    if (!fileSpace.valid() || !memSpace.valid() ||
        H5Sselect_hyperslab(fileSpace.get(), H5S_SELECT_SET, start.data(), nullptr, extent.data(), nullptr) < 0) {
      fail(ErrorCode::PackIoError, "cannot select rows of dataset '" + path + "'" + hdf5::withDetail());
    }
  }
  const hid_t mem = memSpace.valid() ? memSpace.get() : H5S_ALL;
  const hid_t file = fileSpace.valid() ? fileSpace.get() : H5S_ALL;
  if (H5Dread(dset.get(), memType, mem, file, H5P_DEFAULT, buffer) < 0) {
    // A read the disk failed (a network file system's EIO) is not damage: it may work next time.
    if (hdf5::lastErrorIsIo()) {
      fail(ErrorCode::PackIoError, "cannot read dataset '" + path + "': the file's read failed" + hdf5::withDetail());
    }
    fail(ErrorCode::PackCorrupt,
         "cannot read dataset '" + path + "': checksum mismatch or damaged data" + hdf5::withDetail());
  }
}

// The HDF5 memory type of a value type a Dataset reads; its class and its name follow from T.
template <typename T>
hid_t memTypeOf() {
  if constexpr (std::is_same_v<T, double>) return H5T_NATIVE_DOUBLE;
  if constexpr (std::is_same_v<T, float>) return H5T_NATIVE_FLOAT;
  if constexpr (std::is_same_v<T, int64_t>) return H5T_NATIVE_INT64;
  if constexpr (std::is_same_v<T, int32_t>) return H5T_NATIVE_INT32;
  if constexpr (std::is_same_v<T, uint8_t>) return H5T_NATIVE_UINT8;
}

}  // namespace

[[noreturn]] void fail(ErrorCode code, std::string message) { throw ReadFailure{makeError(code, std::move(message))}; }

std::string shapeString(const std::vector<hsize_t>& dims) {
  std::string s = "[";
  for (size_t d = 0; d < dims.size(); ++d) {
    if (d > 0) s += ", ";
    s += dims[d] == kAny ? std::string("*") : std::to_string(dims[d]);
  }
  return s + "]";
}

FileReader::FileReader(hid_t file, uintmax_t fileBytes) : mFile(file), mFileBytes(fileBytes) {}

bool FileReader::exists(const std::string& path) {
  const htri_t found = H5Lexists(mFile, path.c_str(), H5P_DEFAULT);
  if (found < 0) fail(ErrorCode::PackCorrupt, "cannot look up '" + path + "'" + hdf5::withDetail());
  return found > 0;
}

void FileReader::requireGroup(const std::string& path) {
  Handle group = openObject(path, "group");
  if (H5Iget_type(group.get()) != H5I_GROUP) fail(ErrorCode::PackShapeMismatch, "'" + path + "' is not a group");
}

std::optional<std::string> FileReader::stringAttribute(const std::string& where, const char* name) {
  Handle attr = openAttribute(where, name);
  if (!attr.valid()) return std::nullopt;
  const std::string what = "attribute '" + std::string(name) + "' of '" + where + "'";
  Handle type = hdf5::datatypeHandle(H5Aget_type(attr.get()));
  if (!type.valid()) fail(ErrorCode::PackCorrupt, "cannot read the type of " + what + hdf5::withDetail());
  if (H5Tget_class(type.get()) != H5T_STRING || pointCount(attr) != 1) return std::nullopt;
  const H5T_cset_t cset = H5Tget_cset(type.get());
  if (H5Tis_variable_str(type.get()) > 0) {
    // Other tools (h5py, h5py-based editors) write attributes as variable-length strings.
    Handle mem = stringMemType(H5T_VARIABLE, cset);
    char* value = nullptr;
    if (H5Aread(attr.get(), mem.get(), &value) < 0)
      fail(ErrorCode::PackCorrupt, "cannot read " + what + hdf5::withDetail());
    std::string out = value ? value : "";
    H5free_memory(value);
    return out;
  }
  const size_t width = H5Tget_size(type.get());
  if (width == 0 || width > mFileBytes) fail(ErrorCode::PackCorrupt, what + " has an impossible width");
  Handle mem = stringMemType(width, cset);
  std::vector<char> buffer(width, '\0');
  if (H5Aread(attr.get(), mem.get(), buffer.data()) < 0) {
    fail(ErrorCode::PackCorrupt, "cannot read " + what + hdf5::withDetail());
  }
  return std::string(buffer.data(), strnlen(buffer.data(), width));
}

std::optional<int64_t> FileReader::intAttribute(const std::string& where, const char* name) {
  Handle attr = openAttribute(where, name);
  if (!attr.valid()) return std::nullopt;
  Handle type = hdf5::datatypeHandle(H5Aget_type(attr.get()));
  if (!type.valid() || H5Tget_class(type.get()) != H5T_INTEGER || pointCount(attr) != 1) return std::nullopt;
  int64_t value = 0;
  if (H5Aread(attr.get(), H5T_NATIVE_INT64, &value) < 0) {
    fail(ErrorCode::PackCorrupt,
         "cannot read attribute '" + std::string(name) + "' of '" + where + "'" + hdf5::withDetail());
  }
  return value;
}

Array<double> FileReader::f64(const std::string& path, const std::vector<hsize_t>& shape) {
  return open<double>(path, shape).read();
}

Array<float> FileReader::f32(const std::string& path, const std::vector<hsize_t>& shape) {
  return open<float>(path, shape).read();
}

Array<int64_t> FileReader::i64(const std::string& path, const std::vector<hsize_t>& shape) {
  return open<int64_t>(path, shape).read();
}

Array<int32_t> FileReader::i32(const std::string& path, const std::vector<hsize_t>& shape) {
  return open<int32_t>(path, shape).read();
}

Array<uint8_t> FileReader::u8(const std::string& path, const std::vector<hsize_t>& shape) {
  return open<uint8_t>(path, shape).read();
}

std::vector<std::string> FileReader::strings(const std::string& path, hsize_t count) {
  Handle dset = openDataset(path);
  Handle type = hdf5::datatypeHandle(H5Dget_type(dset.get()));
  if (!type.valid())
    fail(ErrorCode::PackCorrupt, "cannot read the type of dataset '" + path + "'" + hdf5::withDetail());
  // Variable-length strings live in the global heap, outside the checksummed chunks, so schema
  // v1 only admits fixed-length ones.
  if (H5Tget_class(type.get()) != H5T_STRING || H5Tis_variable_str(type.get()) != 0) {
    fail(ErrorCode::PackShapeMismatch, "dataset '" + path + "' must hold fixed-length strings");
  }
  const size_t width = H5Tget_size(type.get());
  if (width == 0) fail(ErrorCode::PackCorrupt, "dataset '" + path + "' has strings of width 0");
  const std::vector<hsize_t> dims = checkedDims(dset, path, {count}, width);
  Handle mem = stringMemType(width, H5Tget_cset(type.get()));
  std::vector<char> buffer(dims[0] * width, '\0');
  readRows(dset, path, mem.get(), buffer.data(), dims[0]);
  std::vector<std::string> out(dims[0]);
  for (size_t i = 0; i < out.size(); ++i) out[i].assign(&buffer[i * width], strnlen(&buffer[i * width], width));
  return out;
}

Handle FileReader::openObject(const std::string& path, const char* kind) {
  const htri_t exists = H5Lexists(mFile, path.c_str(), H5P_DEFAULT);
  if (exists < 0)
    fail(ErrorCode::PackCorrupt, "cannot look up " + std::string(kind) + " '" + path + "'" + hdf5::withDetail());
  if (exists == 0) fail(ErrorCode::PackShapeMismatch, std::string(kind) + " '" + path + "' is missing");
  // Soft and external links are refused: an external link would make HDF5 open another file
  // that none of the checks here cover.
  H5L_info_t link;
  if (H5Lget_info(mFile, path.c_str(), &link, H5P_DEFAULT) < 0) {
    fail(ErrorCode::PackCorrupt, "cannot look up " + std::string(kind) + " '" + path + "'" + hdf5::withDetail());
  }
  if (link.type != H5L_TYPE_HARD) {
    fail(ErrorCode::PackShapeMismatch, std::string(kind) + " '" + path + "' is a link, not a stored object");
  }
  Handle object(H5Oopen(mFile, path.c_str(), H5P_DEFAULT), H5Oclose);
  if (!object.valid())
    fail(ErrorCode::PackCorrupt, "cannot open " + std::string(kind) + " '" + path + "'" + hdf5::withDetail());
  return object;
}

Handle FileReader::openDataset(const std::string& path) {
  Handle dset = openObject(path, "dataset");
  if (H5Iget_type(dset.get()) != H5I_DATASET) fail(ErrorCode::PackShapeMismatch, "'" + path + "' is not a dataset");
  // A dataset's values must be stored in this file. HDF5 also lets them live in raw external
  // files or in datasets of other files (a virtual dataset): HDF5 would then open whatever
  // file the pack names (a FIFO blocks the read for ever), and no checksum covers those bytes.
  Handle dcpl = hdf5::propertyHandle(H5Dget_create_plist(dset.get()));
  const H5D_layout_t layout = dcpl.valid() ? H5Pget_layout(dcpl.get()) : H5D_LAYOUT_ERROR;
  const int externalFiles = dcpl.valid() ? H5Pget_external_count(dcpl.get()) : -1;
  if (layout == H5D_LAYOUT_ERROR || externalFiles < 0) {
    fail(ErrorCode::PackCorrupt, "cannot read the storage properties of '" + path + "'" + hdf5::withDetail());
  }
  if (layout == H5D_VIRTUAL || externalFiles > 0) {
    fail(ErrorCode::PackShapeMismatch, "dataset '" + path + "' keeps its values in another file");
  }
  return dset;
}

Handle FileReader::openAttribute(const std::string& where, const char* name) {
  const htri_t exists = H5Aexists_by_name(mFile, where.c_str(), name, H5P_DEFAULT);
  if (exists < 0) {
    fail(ErrorCode::PackCorrupt,
         "cannot look up attribute '" + std::string(name) + "' of '" + where + "'" + hdf5::withDetail());
  }
  if (exists == 0) return Handle();
  Handle attr = hdf5::attributeHandle(H5Aopen_by_name(mFile, where.c_str(), name, H5P_DEFAULT, H5P_DEFAULT));
  if (!attr.valid()) {
    fail(ErrorCode::PackCorrupt,
         "cannot open attribute '" + std::string(name) + "' of '" + where + "'" + hdf5::withDetail());
  }
  return attr;
}

hssize_t FileReader::pointCount(const Handle& attr) {
  Handle space = hdf5::dataspaceHandle(H5Aget_space(attr.get()));
  return space.valid() ? H5Sget_simple_extent_npoints(space.get()) : -1;
}

Handle FileReader::stringMemType(size_t width, H5T_cset_t cset) {
  Handle type = hdf5::datatypeHandle(H5Tcopy(H5T_C_S1));
  // The memory type takes the file's character set: HDF5 does not convert between sets.
  if (!type.valid() || H5Tset_size(type.get(), width) < 0 || H5Tset_cset(type.get(), cset) < 0 ||
      (width != H5T_VARIABLE && H5Tset_strpad(type.get(), H5T_STR_NULLPAD) < 0)) {
    fail(ErrorCode::PackIoError, "cannot create a string type" + hdf5::withDetail());
  }
  return type;
}

template <typename T>
Dataset<T> FileReader::open(const std::string& path, const std::vector<hsize_t>& shape) {
  Dataset<T> d;
  d.mPath = path;
  d.mDset = openDataset(path);
  Handle type = hdf5::datatypeHandle(H5Dget_type(d.mDset.get()));
  if (!type.valid())
    fail(ErrorCode::PackCorrupt, "cannot read the type of dataset '" + path + "'" + hdf5::withDetail());
  // The exact type is required: HDF5 would otherwise convert silently, and a narrowing
  // conversion (float64 → int32, int64 → int32) clips values instead of failing.
  constexpr bool floating = std::is_floating_point_v<T>;
  const H5T_class_t typeClass = floating ? H5T_FLOAT : H5T_INTEGER;
  if (H5Tget_class(type.get()) != typeClass || H5Tget_size(type.get()) != sizeof(T) ||
      (!floating && H5Tget_sign(type.get()) != H5Tget_sign(memTypeOf<T>()))) {
    const std::string name = std::string(floating ? "float" : std::is_signed_v<T> ? "int" : "uint") +
                             std::to_string(8 * sizeof(T));  // "float64", "int32", "uint8"
    fail(ErrorCode::PackShapeMismatch, "dataset '" + path + "' must hold " + name);
  }
  d.mDims = checkedDims(d.mDset, path, shape, sizeof(T));
  return d;
}

template <typename T>
Array<T> Dataset<T>::read(Rows rows) const {
  Array<T> a;
  a.dims = mDims;
  if (rows.count != kAny) {
    if (mDims.empty() || rows.first > mDims[0] || rows.count > mDims[0] - rows.first) {
      fail(ErrorCode::PackShapeMismatch, "dataset '" + mPath + "' has shape " + shapeString(mDims) +
                                             ", without rows " + std::to_string(rows.first) + " to " +
                                             std::to_string(rows.first + rows.count));
    }
    a.dims[0] = rows.count;
  }
  size_t count = 1;
  for (hsize_t d : a.dims) count *= d;
  a.values.resize(count);
  readRows(mDset, mPath, memTypeOf<T>(), a.values.data(), count, mDims, rows);
  if constexpr (std::is_floating_point_v<T>) {
    const size_t rowSize = a.dims.empty() || a.dims[0] == 0 ? 1 : count / a.dims[0];
    const size_t skipped = rows.count == kAny ? 0 : rows.first * rowSize;
    for (size_t i = 0; i < count; ++i) {
      if (!std::isfinite(a.values[i])) {
        fail(ErrorCode::PackCorrupt, "dataset '" + mPath + "' holds a non-finite value (" +
                                         std::to_string(a.values[i]) + ") at " + indexString(skipped + i, mDims));
      }
    }
  }
  return a;
}

template Dataset<double> FileReader::open<double>(const std::string&, const std::vector<hsize_t>&);
template Dataset<float> FileReader::open<float>(const std::string&, const std::vector<hsize_t>&);
template Dataset<int64_t> FileReader::open<int64_t>(const std::string&, const std::vector<hsize_t>&);
template Dataset<int32_t> FileReader::open<int32_t>(const std::string&, const std::vector<hsize_t>&);
template Dataset<uint8_t> FileReader::open<uint8_t>(const std::string&, const std::vector<hsize_t>&);
template class Dataset<double>;
template class Dataset<float>;
template class Dataset<int64_t>;
template class Dataset<int32_t>;
template class Dataset<uint8_t>;

std::vector<hsize_t> FileReader::checkedDims(const Handle& dset, const std::string& path, const std::vector<hsize_t>& shape,
                                             size_t elementBytes) {
  Handle space = hdf5::dataspaceHandle(H5Dget_space(dset.get()));
  if (!space.valid())
    fail(ErrorCode::PackCorrupt, "cannot read the dataspace of '" + path + "'" + hdf5::withDetail());
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) fail(ErrorCode::PackCorrupt, "cannot read the rank of '" + path + "'" + hdf5::withDetail());
  std::vector<hsize_t> dims(static_cast<size_t>(rank));
  if (rank > 0 && H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr) < 0) {
    fail(ErrorCode::PackCorrupt, "cannot read the shape of '" + path + "'" + hdf5::withDetail());
  }
  bool matches = H5Sget_simple_extent_type(space.get()) == H5S_SIMPLE && dims.size() == shape.size();
  for (size_t d = 0; matches && d < dims.size(); ++d) matches = shape[d] == kAny || dims[d] == shape[d];
  if (!matches) {
    fail(ErrorCode::PackShapeMismatch,
         "dataset '" + path + "' has shape " + shapeString(dims) + ", expected " + shapeString(shape));
  }
  hsize_t bytes = elementBytes;
  for (hsize_t d : dims) {
    if (__builtin_mul_overflow(bytes, d, &bytes)) {
      fail(ErrorCode::PackCorrupt, "dataset '" + path + "' claims an impossible shape " + shapeString(dims));
    }
  }
  if (bytes > 0) {
    const hsize_t stored = H5Dget_storage_size(dset.get());
    if (stored == 0 || stored > mFileBytes || bytes / kMaxInflateRatio > stored) {
      fail(ErrorCode::PackCorrupt, "dataset '" + path + "' claims shape " + shapeString(dims) + " (" +
                                       std::to_string(bytes) + " bytes) but the file stores " +
                                       std::to_string(stored) + " bytes of it");
    }
  }
  return dims;
}

}  // namespace brittle::hdf5
