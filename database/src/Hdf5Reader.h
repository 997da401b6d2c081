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

/// Rows [first, first + count) of a dataset's first dimension; the default is every row.
struct Rows {
  hsize_t first = 0;
  hsize_t count = kAny;
};

/// "[2, 3]"; kAny reads "*".
std::string shapeString(const std::vector<hsize_t>& dims);

/// A dataset of T (double, float, int64_t, int32_t or uint8_t) whose type, shape and stored size
/// were checked when FileReader::open opened it, kept open to read rows of it. A reader of a few
/// rows at a time (an entry read on demand, PackReader.cpp) pays those checks once: the stored
/// size walks the dataset's whole chunk index. Move-only; reads are thread-safe (HDF5 is built
/// thread-safe and serialises them).
template <typename T>
class Dataset {
 public:
  const std::vector<hsize_t>& dims() const { return mDims; }

  /// `rows` of it (the result's dims[0] is rows.count), every float checked finite. Throws
  /// ReadFailure: rows past its end (PackShapeMismatch), stored bytes that fail their checksum or
  /// do not inflate, or a non-finite float (PackCorrupt).
  Array<T> read(Rows rows = {}) const;

 private:
  friend class FileReader;
  Handle mDset;
  std::string mPath;
  std::vector<hsize_t> mDims;
};

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

  /// The dataset at `path`, its exact type T and its shape checked (kAny: any size there), and
  /// its claimed size against what the file stores, before anything is allocated for it.
  template <typename T>
  Dataset<T> open(const std::string& path, const std::vector<hsize_t>& shape);

  /// open(path, shape).read(): the whole dataset.
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

  // The dataset's dimensions, once its rank and fixed dimensions match `shape` and its claimed
  // size is plausible for what the file stores.
  std::vector<hsize_t> checkedDims(const Handle& dset, const std::string& path, const std::vector<hsize_t>& shape,
                                   size_t elementBytes);

  hid_t mFile;
  uintmax_t mFileBytes;
};

}  // namespace brittle::hdf5
