// Hdf5Writer.h — a writer of HDF5 files whose every call is checked: groups and attributes without
// modification times, and every dataset chunked with shuffle + deflate + Fletcher-32, so that a
// reader (Hdf5Reader.h) can verify each stored byte. A failed call throws WriteFailure with a
// PackIoError; the caller catches it at its API boundary. It knows no schema: the pack writer
// (PackWriter.cpp) names the groups and datasets.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <string>
#include <vector>

#include "Hdf5Util.h"
#include "brittle/core/Result.h"

namespace brittle::hdf5 {

/// Thrown inside a write and caught at the writer's API (writePack): the write is a long straight
/// sequence of HDF5 calls, and an exception keeps each one to a single checked line.
struct WriteFailure {
  Error error;
};

/// Throws a PackIoError.
[[noreturn]] void failIo(const std::string& message);
/// Throws a PackIoError with HDF5's innermost message appended.
[[noreturn]] void failHdf5(const std::string& message);

/// About 256 KiB per chunk: few enough chunks that the chunk index stays small for big meshes,
/// small enough that the chunk cache and a partial read stay cheap.
inline constexpr hsize_t kDefaultChunkBytes = 256 * 1024;

/// Writes groups, attributes and datasets into an open file.
class FileWriter {
 public:
  explicit FileWriter(hid_t file);

  /// The bytes of a chunk of the datasets written next (whole rows, at least one): the
  /// default, or smaller where rows are read a few at a time (PackWriter.cpp).
  void setChunkBytes(hsize_t bytes) { mChunkBytes = bytes; }

  Handle createGroup(const std::string& path);

  void stringAttribute(hid_t loc, const std::string& where, const char* name, const std::string& value);

  void intAttribute(hid_t loc, const std::string& where, const char* name, int32_t value);

  void f64(const std::string& path, const std::vector<double>& values, const std::vector<hsize_t>& dims,
           const char* unit);
  void f32(const std::string& path, const float* values, const std::vector<hsize_t>& dims);
  void i64(const std::string& path, const std::vector<int64_t>& values, const std::vector<hsize_t>& dims);
  void i32(const std::string& path, const std::vector<int32_t>& values, const std::vector<hsize_t>& dims);
  void u8(const std::string& path, const std::vector<uint8_t>& values);
  void strings(const std::string& path, const std::vector<std::string>& values);

 private:
  void writeAttribute(hid_t loc, const std::string& where, const char* name, hid_t fileType, hid_t memType,
                      const void* data);

  // Every dataset is chunked with shuffle + deflate + Fletcher-32, in that order, so the checksum
  // covers the bytes exactly as stored and is verified before anything is decompressed. No
  // modification times are stored, so that the same pack gives the same bytes.
  void dataset(const std::string& path, hid_t fileType, hid_t memType, const void* data,
               const std::vector<hsize_t>& dims, const char* unit);

  hid_t mFile;
  hsize_t mChunkBytes = kDefaultChunkBytes;
};

}  // namespace brittle::hdf5
