// Hdf5Writer.cpp — the checked HDF5 writes (Hdf5Writer.h).
#include "Hdf5Writer.h"

#include <algorithm>

namespace brittle::hdf5 {
namespace {

constexpr unsigned kDeflateLevel = 4;

Handle fixedStringType(size_t width) {
  Handle type = datatypeHandle(H5Tcopy(H5T_C_S1));
  // HDF5 has no zero-width strings; width 1 of NUL padding reads back as "".
  if (!type.valid() || H5Tset_size(type.get(), std::max<size_t>(width, 1)) < 0 ||
      H5Tset_strpad(type.get(), H5T_STR_NULLPAD) < 0 || H5Tset_cset(type.get(), H5T_CSET_UTF8) < 0) {
    failHdf5("cannot create a string type of width " + std::to_string(width));
  }
  return type;
}

}  // namespace

[[noreturn]] void failIo(const std::string& message) { throw WriteFailure{makeError(ErrorCode::PackIoError, message)}; }

[[noreturn]] void failHdf5(const std::string& message) { failIo(message + withDetail()); }

FileWriter::FileWriter(hid_t file) : mFile(file) {}

Handle FileWriter::createGroup(const std::string& path) {
  Handle gcpl = propertyHandle(H5Pcreate(H5P_GROUP_CREATE));
  if (!gcpl.valid() || H5Pset_obj_track_times(gcpl.get(), false) < 0) {
    failHdf5("cannot set up group '" + path + "'");
  }
  Handle group = groupHandle(H5Gcreate2(mFile, path.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT));
  if (!group.valid()) failHdf5("cannot create group '" + path + "'");
  return group;
}

void FileWriter::stringAttribute(hid_t loc, const std::string& where, const char* name, const std::string& value) {
  Handle type = fixedStringType(value.size());
  std::vector<char> buffer(std::max<size_t>(value.size(), 1), '\0');
  std::copy(value.begin(), value.end(), buffer.begin());
  writeAttribute(loc, where, name, type.get(), type.get(), buffer.data());
}

void FileWriter::intAttribute(hid_t loc, const std::string& where, const char* name, int32_t value) {
  writeAttribute(loc, where, name, H5T_STD_I32LE, H5T_NATIVE_INT32, &value);
}

void FileWriter::f64(const std::string& path, const std::vector<double>& values, const std::vector<hsize_t>& dims,
                     const char* unit) {
  dataset(path, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), dims, unit);
}

void FileWriter::f32(const std::string& path, const float* values, const std::vector<hsize_t>& dims) {
  dataset(path, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, values, dims, "1");
}

void FileWriter::i64(const std::string& path, const std::vector<int64_t>& values, const std::vector<hsize_t>& dims) {
  dataset(path, H5T_STD_I64LE, H5T_NATIVE_INT64, values.data(), dims, nullptr);
}

void FileWriter::i32(const std::string& path, const std::vector<int32_t>& values, const std::vector<hsize_t>& dims) {
  dataset(path, H5T_STD_I32LE, H5T_NATIVE_INT32, values.data(), dims, nullptr);
}

void FileWriter::u8(const std::string& path, const std::vector<uint8_t>& values) {
  dataset(path, H5T_STD_U8LE, H5T_NATIVE_UINT8, values.data(), {values.size()}, nullptr);
}

void FileWriter::strings(const std::string& path, const std::vector<std::string>& values) {
  size_t width = 1;
  for (const auto& s : values) width = std::max(width, s.size());
  std::vector<char> buffer(values.size() * width, '\0');
  for (size_t i = 0; i < values.size(); ++i) std::copy(values[i].begin(), values[i].end(), &buffer[i * width]);
  Handle type = fixedStringType(width);
  dataset(path, type.get(), type.get(), buffer.data(), {values.size()}, nullptr);
}

void FileWriter::writeAttribute(hid_t loc, const std::string& where, const char* name, hid_t fileType, hid_t memType,
                                const void* data) {
  const std::string what = "attribute '" + std::string(name) + "' of '" + where + "'";
  Handle space = dataspaceHandle(H5Screate(H5S_SCALAR));
  if (!space.valid()) failHdf5("cannot create the dataspace of " + what);
  Handle attr = attributeHandle(H5Acreate2(loc, name, fileType, space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!attr.valid()) failHdf5("cannot create " + what);
  if (H5Awrite(attr.get(), memType, data) < 0) failHdf5("cannot write " + what);
}

void FileWriter::dataset(const std::string& path, hid_t fileType, hid_t memType, const void* data,
                         const std::vector<hsize_t>& dims, const char* unit) {
  const int rank = static_cast<int>(dims.size());
  std::vector<hsize_t> maxDims = dims;
  std::vector<hsize_t> chunk(dims.size());
  hsize_t rowBytes = H5Tget_size(memType);
  hsize_t count = 1;
  for (int d = 0; d < rank; ++d) {
    count *= dims[d];
    // Chunk dimensions must be positive and, for a fixed-size dimension, no larger than it: an
    // empty dimension is therefore declared extensible so that a chunk of 1 is legal.
    if (dims[d] == 0) maxDims[d] = H5S_UNLIMITED;
    if (d > 0) {
      chunk[d] = std::max<hsize_t>(dims[d], 1);
      rowBytes *= chunk[d];
    }
  }
  chunk[0] = std::clamp<hsize_t>(mChunkBytes / rowBytes, 1, std::max<hsize_t>(dims[0], 1));

  Handle space = dataspaceHandle(H5Screate_simple(rank, dims.data(), maxDims.data()));
  if (!space.valid()) failHdf5("cannot create the dataspace of dataset '" + path + "'");
  Handle dcpl = propertyHandle(H5Pcreate(H5P_DATASET_CREATE));
  if (!dcpl.valid() || H5Pset_chunk(dcpl.get(), rank, chunk.data()) < 0 || H5Pset_shuffle(dcpl.get()) < 0 ||
      H5Pset_deflate(dcpl.get(), kDeflateLevel) < 0 || H5Pset_fletcher32(dcpl.get()) < 0 ||
      H5Pset_obj_track_times(dcpl.get(), false) < 0) {
    failHdf5("cannot set up chunking and filters of dataset '" + path + "'");
  }
  Handle dset = datasetHandle(
      H5Dcreate2(mFile, path.c_str(), fileType, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT));
  if (!dset.valid()) failHdf5("cannot create dataset '" + path + "'");
  if (count > 0 && H5Dwrite(dset.get(), memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    failHdf5("cannot write dataset '" + path + "'");
  }
  if (unit) stringAttribute(dset.get(), path, "unit", unit);
}

}  // namespace brittle::hdf5
