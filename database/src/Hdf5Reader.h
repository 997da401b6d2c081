// Hdf5Reader.h — a reader of HDF5 files that trusts nothing it reads: hard links only, values
// stored in the file itself, the exact type required, every shape checked before anything is
// allocated for it and bounded by the size of the file, every float finite. A failed check
// throws ReadFailure with a typed error; the caller catches it at its API boundary. It knows no
// schema: the pack reader (PackReader.cpp) names the groups and datasets.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "Hdf5Util.h"
#include "brittle/core/Result.h"

namespace brittle::hdf5 {

/// Thrown inside a read and caught at the reader's API (readPack): validation is a long sequence
/// of checks that each may end the read, and an exception keeps each one to a single line.
struct ReadFailure {
  Error error;
};

[[noreturn]] void fail(ErrorCode code, std::string message);

/// A dimension the caller checks itself (against a count read elsewhere).
inline constexpr hsize_t kAny = std::numeric_limits<hsize_t>::max();

/// A dataset's values, row-major, and its dimensions.
template <typename T>
struct Array {
  std::vector<T> values;
  std::vector<hsize_t> dims;
};

/// "[2, 3]"; kAny reads "*".
std::string shapeString(const std::vector<hsize_t>& dims);

/// Reads checked attributes and datasets from an open file of `fileBytes` bytes.
class FileReader {
 public:
  FileReader(hid_t file, uintmax_t fileBytes);

  /// True when a link named path exists (whatever it points to).
  bool exists(const std::string& path);

  void requireGroup(const std::string& path);

  /// nullopt when the attribute is missing or is not one string.
  std::optional<std::string> stringAttribute(const std::string& where, const char* name);

  /// nullopt when the attribute is missing or is not one integer.
  std::optional<int64_t> intAttribute(const std::string& where, const char* name);

  Array<double> f64(const std::string& path, const std::vector<hsize_t>& shape);
  Array<float> f32(const std::string& path, const std::vector<hsize_t>& shape);
  Array<int64_t> i64(const std::string& path, const std::vector<hsize_t>& shape);
  Array<int32_t> i32(const std::string& path, const std::vector<hsize_t>& shape);
  Array<uint8_t> u8(const std::string& path, const std::vector<hsize_t>& shape);

  /// A 1-D dataset of fixed-length strings of `count` entries (kAny: any).
  std::vector<std::string> strings(const std::string& path, hsize_t count);

 private:
  Handle openObject(const std::string& path, const char* kind);

  Handle openDataset(const std::string& path);

  // An invalid handle when the attribute is missing.
  Handle openAttribute(const std::string& where, const char* name);

  static hssize_t pointCount(const Handle& attr);

  static Handle stringMemType(size_t width, H5T_cset_t cset);

  template <typename T>
  Array<T> numeric(const std::string& path, const std::vector<hsize_t>& shape, H5T_class_t typeClass, hid_t memType,
                   const char* typeName);

  // The dataset's dimensions, once its rank and fixed dimensions match `shape` and its claimed
  // size is plausible for what the file stores.
  std::vector<hsize_t> checkedDims(const Handle& dset, const std::string& path, const std::vector<hsize_t>& shape,
                                   size_t elementBytes);

  // A failed read of a dataset whose shape and type checked out means its stored bytes are bad:
  // the Fletcher-32 filter found a mismatch, or deflate could not decode the chunk.
  static void read(const Handle& dset, const std::string& path, hid_t memType, void* buffer, size_t count);

  hid_t mFile;
  uintmax_t mFileBytes;
};

}  // namespace brittle::hdf5
