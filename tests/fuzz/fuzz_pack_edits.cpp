// Fuzz target: readPack (Pack.h) on valid packs edited the way a buggy writer, another tool or a
// damaged disk would. Random bytes rarely get past HDF5's own structure and the Fletcher-32
// checksums, so this target edits the seed pack (PackSupport.h) through the HDF5 API instead,
// which keeps the file well formed and the checksums right, and so reaches the reader's own
// validation: shapes, types, offset tables, index ranges, finite values, names, attributes.
//
// Input: a list of edits, each an op byte followed by its arguments (FuzzedDataProvider):
//   set an element of a dataset to a chosen value (NaN, ±inf, an out-of-range index, ...);
//   recreate a dataset with another shape, or another type, with contents from the input, or
//   with its values in another file (external storage, virtual dataset);
//   delete a dataset or group, or put a soft, hard or external link or a group in its place;
//   replace, retype or delete a root attribute;
//   flip bytes at an offset, or truncate the file (applied after HDF5 has closed it).
// The result goes through the same checks as fuzz_pack_bytes (checkReadResult, checkOnDemandRead).
#include <fuzzer/FuzzedDataProvider.h>
#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "FuzzSupport.h"
#include "PackSupport.h"

namespace {

using brittle::fuzz::finding;

constexpr int kMaxEdits = 6;
// Datasets recreated with more elements than this are left without contents: HDF5 accepts such a
// dataset, and the reader must refuse it from its claimed size alone.
constexpr hsize_t kMaxWrittenElements = 4096;

struct Base {
  std::string bytes;                  // the seed pack's file
  std::vector<std::string> datasets;  // every dataset's path, in name order
  std::vector<std::string> groups;    // every group's path but the root's
};
Base gBase;

// Closes an HDF5 identifier at scope exit; edits ignore HDF5's failures (the edit then does less).
struct Id {
  hid_t id;
  herr_t (*close)(hid_t);
  ~Id() {
    if (id >= 0) close(id);
  }
};

herr_t collect(hid_t file, const char* name, const H5L_info_t*, void*) {
  const std::string path = std::string("/") + name;
  const Id object{H5Oopen(file, path.c_str(), H5P_DEFAULT), H5Oclose};
  const H5I_type_t type = H5Iget_type(object.id);
  if (type == H5I_DATASET) gBase.datasets.push_back(path);
  if (type == H5I_GROUP) gBase.groups.push_back(path);
  return 0;
}

template <typename T>
const T& pick(FuzzedDataProvider& in, const std::vector<T>& from) {
  return from[in.ConsumeIntegralInRange<size_t>(0, from.size() - 1)];
}

double anyDouble(FuzzedDataProvider& in) {
  static constexpr std::array<double, 12> kValues = {
      std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
      -std::numeric_limits<double>::infinity(), 0.0, -0.0, std::numeric_limits<double>::denorm_min(),
      std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(), 1.0, -1.0, 0.5, 1e300};
  if (in.ConsumeBool()) return kValues[in.ConsumeIntegralInRange<size_t>(0, kValues.size() - 1)];
  const uint64_t bits = in.ConsumeIntegral<uint64_t>();
  double value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

int64_t anyInteger(FuzzedDataProvider& in) {
  static constexpr std::array<int64_t, 14> kValues = {
      0, 1, -1, 2, 3, 4, 6, 255, 256, (1 << 20) + 1, std::numeric_limits<int32_t>::max(),
      std::numeric_limits<int32_t>::min(), std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::min()};
  if (in.ConsumeBool()) return kValues[in.ConsumeIntegralInRange<size_t>(0, kValues.size() - 1)];
  return in.ConsumeIntegral<int64_t>();
}

hsize_t anyDimension(FuzzedDataProvider& in) {
  static constexpr std::array<hsize_t, 5> kHuge = {1ULL << 31, 1ULL << 32, 1ULL << 40, 1ULL << 60,
                                                   std::numeric_limits<hsize_t>::max() / 2};
  if (in.ConsumeIntegralInRange(0, 7) == 0) return kHuge[in.ConsumeIntegralInRange<size_t>(0, kHuge.size() - 1)];
  return in.ConsumeIntegralInRange<hsize_t>(0, 12);
}

// Element `flat` (row-major) of a dataset gets a value chosen for its type class.
void setElement(FuzzedDataProvider& in, hid_t file) {
  const Id dset{H5Dopen2(file, pick(in, gBase.datasets).c_str(), H5P_DEFAULT), H5Dclose};
  const Id space{H5Dget_space(dset.id), H5Sclose};
  const Id type{H5Dget_type(dset.id), H5Tclose};
  const hssize_t points = H5Sget_simple_extent_npoints(space.id);
  const int rank = H5Sget_simple_extent_ndims(space.id);
  if (points <= 0 || rank < 1 || rank > 3) return;
  // One element written into a contiguous dataset allocates all of its storage. A recreated
  // dataset that claims 2^60 elements would then end beyond any file offset, and HDF5 could no
  // longer flush or close the file. Such datasets stay unwritten: the reader must refuse them
  // from their claimed size alone (kMaxWrittenElements).
  const Id dcpl{H5Dget_create_plist(dset.id), H5Pclose};
  if (H5Pget_layout(dcpl.id) == H5D_CONTIGUOUS && H5Dget_storage_size(dset.id) == 0 &&
      static_cast<hsize_t>(points) > kMaxWrittenElements) {
    return;
  }
  hsize_t dims[3] = {1, 1, 1}, coords[3] = {0, 0, 0};
  H5Sget_simple_extent_dims(space.id, dims, nullptr);
  auto flat = in.ConsumeIntegralInRange<hsize_t>(0, static_cast<hsize_t>(points) - 1);
  for (int d = rank - 1; d >= 0; --d) {
    coords[d] = flat % dims[d];
    flat /= dims[d];
  }
  std::vector<hsize_t> coordList(coords, coords + rank);
  H5Sselect_elements(space.id, H5S_SELECT_SET, 1, coordList.data());
  const hsize_t one = 1;
  const Id memSpace{H5Screate_simple(1, &one, nullptr), H5Sclose};
  switch (H5Tget_class(type.id)) {
    case H5T_FLOAT: {
      const double value = anyDouble(in);
      H5Dwrite(dset.id, H5T_NATIVE_DOUBLE, memSpace.id, space.id, H5P_DEFAULT, &value);
      break;
    }
    case H5T_INTEGER: {
      const int64_t value = anyInteger(in);
      H5Dwrite(dset.id, H5T_NATIVE_INT64, memSpace.id, space.id, H5P_DEFAULT, &value);
      break;
    }
    case H5T_STRING: {
      if (H5Tis_variable_str(type.id) > 0) return;
      std::string value = in.ConsumeRandomLengthString(64);
      value.resize(H5Tget_size(type.id), '\0');
      H5Dwrite(dset.id, type.id, memSpace.id, space.id, H5P_DEFAULT, value.data());
      break;
    }
    default: break;
  }
}

// Set when an edit made a dataset whose values live in another file, which the reader must refuse.
bool gValuesOutside = false;

// A new dataset at `path` of the given type and shape, with contents from the input when it is
// small enough: chunked with the pack's filters, contiguous or compact, or with its values in
// another file (raw external storage, or a virtual dataset over the seed pack's file).
void createDataset(FuzzedDataProvider& in, hid_t file, const std::string& path, hid_t type,
                   const std::vector<hsize_t>& dims) {
  const Id space{dims.empty() ? H5Screate(H5S_SCALAR)
                              : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                 H5Sclose};
  const Id dcpl{H5Pcreate(H5P_DATASET_CREATE), H5Pclose};
  const int layout = in.ConsumeIntegralInRange(0, 4);
  if (layout == 3) {
    const auto raw = brittle::fuzz::writeScratchFile("outside.raw", in.ConsumeRandomLengthString(256));
    H5Pset_external(dcpl.id, raw.c_str(), 0, H5F_UNLIMITED);
  } else if (layout == 4) {
    const std::string source = pick(in, gBase.datasets);
    H5Pset_virtual(dcpl.id, space.id, (brittle::fuzz::scratchDir() / "base.h5").c_str(), source.c_str(), space.id);
  } else if (layout == 0 && !dims.empty()) {
    std::vector<hsize_t> chunk(dims.size()), maxDims(dims.size(), H5S_UNLIMITED);
    for (size_t d = 0; d < dims.size(); ++d) chunk[d] = std::clamp<hsize_t>(dims[d], 1, 16);
    H5Sset_extent_simple(space.id, static_cast<int>(dims.size()), dims.data(), maxDims.data());
    H5Pset_chunk(dcpl.id, static_cast<int>(chunk.size()), chunk.data());
    H5Pset_shuffle(dcpl.id);
    H5Pset_deflate(dcpl.id, 1);
    H5Pset_fletcher32(dcpl.id);
  } else if (layout == 1) {
    H5Pset_layout(dcpl.id, H5D_COMPACT);
  }
  const Id dset{H5Dcreate2(file, path.c_str(), type, space.id, H5P_DEFAULT, dcpl.id, H5P_DEFAULT), H5Dclose};
  if (dset.id >= 0 && layout >= 3) gValuesOutside = true;
  if (dset.id < 0 || layout == 4 || H5Tis_variable_str(type) > 0) return;
  hsize_t count = 1;
  for (hsize_t d : dims) count = d != 0 && count > kMaxWrittenElements / d ? kMaxWrittenElements + 1 : count * d;
  if (count == 0 || count > kMaxWrittenElements) return;
  // The input's bytes, repeated: the same bytes give the same contents whatever the type.
  std::vector<uint8_t> bytes(count * H5Tget_size(type));
  const std::vector<uint8_t> pattern = in.ConsumeBytes<uint8_t>(in.ConsumeIntegralInRange<size_t>(1, 64));
  for (size_t i = 0; i < bytes.size() && !pattern.empty(); ++i) bytes[i] = pattern[i % pattern.size()];
  H5Dwrite(dset.id, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data());
}

// Recreates a dataset with the same type and another shape.
void reshape(FuzzedDataProvider& in, hid_t file) {
  const std::string& path = pick(in, gBase.datasets);
  const Id dset{H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose};
  if (dset.id < 0) return;
  const Id type{H5Dget_type(dset.id), H5Tclose};
  std::vector<hsize_t> dims(in.ConsumeIntegralInRange(0, 3));
  for (hsize_t& d : dims) d = anyDimension(in);
  if (H5Ldelete(file, path.c_str(), H5P_DEFAULT) < 0) return;
  createDataset(in, file, path, type.id, dims);
}

// A type the pack never uses where it does use one, or one it uses in the wrong place.
hid_t newType(FuzzedDataProvider& in) {
  const std::array<hid_t, 10> kTypes = {H5T_IEEE_F64LE, H5T_IEEE_F32LE, H5T_IEEE_F64BE, H5T_STD_I64LE, H5T_STD_I32LE,
                                        H5T_STD_I32BE,  H5T_STD_U8LE,   H5T_STD_I8LE,   H5T_STD_U64LE, H5T_STD_B8LE};
  const size_t choice = in.ConsumeIntegralInRange<size_t>(0, kTypes.size() + 1);
  if (choice < kTypes.size()) return H5Tcopy(kTypes[choice]);
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, choice == kTypes.size() ? H5T_VARIABLE : in.ConsumeIntegralInRange<size_t>(1, 40));
  return type;
}

// Recreates a dataset with the same shape and another type.
void retype(FuzzedDataProvider& in, hid_t file) {
  const std::string& path = pick(in, gBase.datasets);
  std::vector<hsize_t> dims;
  {
    const Id dset{H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose};
    const Id space{H5Dget_space(dset.id), H5Sclose};
    const int rank = H5Sget_simple_extent_ndims(space.id);
    if (rank < 0 || rank > 3) return;
    dims.resize(static_cast<size_t>(rank));
    H5Sget_simple_extent_dims(space.id, dims.data(), nullptr);
  }
  const Id type{newType(in), H5Tclose};
  if (H5Ldelete(file, path.c_str(), H5P_DEFAULT) < 0) return;
  createDataset(in, file, path, type.id, dims);
}

void unlink(FuzzedDataProvider& in, hid_t file) {
  const bool group = in.ConsumeBool();
  H5Ldelete(file, pick(in, group ? gBase.groups : gBase.datasets).c_str(), H5P_DEFAULT);
}

// Puts a link or a group where a dataset was.
void relink(FuzzedDataProvider& in, hid_t file) {
  const std::string& path = pick(in, gBase.datasets);
  const std::string& other = pick(in, gBase.datasets);
  const int kind = in.ConsumeIntegralInRange(0, 3);
  if (kind == 1) {
    // A second hard link to another dataset: HDF5 accepts it, and the reader sees that dataset's
    // contents under this name.
    if (H5Ldelete(file, path.c_str(), H5P_DEFAULT) >= 0) H5Lcreate_hard(file, other.c_str(), file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT);
    return;
  }
  if (H5Ldelete(file, path.c_str(), H5P_DEFAULT) < 0) return;
  if (kind == 0) H5Lcreate_soft(other.c_str(), file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  if (kind == 2) H5Lcreate_external("missing.h5", other.c_str(), file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  if (kind == 3) {
    const Id group{H5Gcreate2(file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose};
  }
}

// Deletes a root attribute and, most of the time, writes one of another type or value in its place.
void editAttribute(FuzzedDataProvider& in, hid_t file) {
  static const std::array<const char*, 8> kNames = {"format",    "version",   "length_unit",          "mass_unit",
                                                    "time_unit", "stress_unit", "energy_per_area_unit", "frequency_unit"};
  const char* name = kNames[in.ConsumeIntegralInRange<size_t>(0, kNames.size() - 1)];
  if (H5Aexists(file, name) > 0) H5Adelete(file, name);
  const int kind = in.ConsumeIntegralInRange(0, 4);
  if (kind == 0) return;
  const hsize_t two = 2;
  const Id space{in.ConsumeIntegralInRange(0, 3) == 0 ? H5Screate_simple(1, &two, nullptr) : H5Screate(H5S_SCALAR),
                 H5Sclose};
  const hssize_t points = H5Sget_simple_extent_npoints(space.id);
  if (kind == 1 || kind == 2) {
    // A fixed-length (1) or variable-length (2) string.
    std::vector<std::string> values(static_cast<size_t>(points));
    for (std::string& v : values) v = in.ConsumeRandomLengthString(32);
    const Id type{H5Tcopy(H5T_C_S1), H5Tclose};
    if (kind == 1) {
      size_t width = 1;
      for (const std::string& v : values) width = std::max(width, v.size());
      H5Tset_size(type.id, width);
      std::string buffer;
      for (std::string v : values) buffer += v.append(width - v.size(), '\0');
      const Id attr{H5Acreate2(file, name, type.id, space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
      H5Awrite(attr.id, type.id, buffer.data());
    } else {
      H5Tset_size(type.id, H5T_VARIABLE);
      std::vector<const char*> pointers;
      for (const std::string& v : values) pointers.push_back(v.c_str());
      const Id attr{H5Acreate2(file, name, type.id, space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
      H5Awrite(attr.id, type.id, pointers.data());
    }
    return;
  }
  if (kind == 3) {
    const std::vector<int64_t> values(static_cast<size_t>(points), anyInteger(in));
    const hid_t fileType = in.ConsumeBool() ? H5T_STD_I64LE : H5T_STD_U8LE;
    const Id attr{H5Acreate2(file, name, fileType, space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
    H5Awrite(attr.id, H5T_NATIVE_INT64, values.data());
    return;
  }
  const std::vector<double> values(static_cast<size_t>(points), anyDouble(in));
  const Id attr{H5Acreate2(file, name, H5T_IEEE_F64LE, space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose};
  H5Awrite(attr.id, H5T_NATIVE_DOUBLE, values.data());
}

// Whether a dataset the reader reads keeps its values in another file.
bool readsValuesOutside(hid_t file) {
  for (const std::string& path : gBase.datasets) {
    H5L_info_t link;
    if (H5Lexists(file, path.c_str(), H5P_DEFAULT) <= 0 || H5Lget_info(file, path.c_str(), &link, H5P_DEFAULT) < 0 ||
        link.type != H5L_TYPE_HARD) {
      continue;
    }
    const Id dset{H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose};
    if (dset.id < 0) continue;
    const Id dcpl{H5Dget_create_plist(dset.id), H5Pclose};
    if (H5Pget_layout(dcpl.id) == H5D_VIRTUAL || H5Pget_external_count(dcpl.id) > 0) return true;
  }
  return false;
}

// Byte-level damage, applied once HDF5 has closed the file.
struct ByteEdit {
  bool truncate = false;
  size_t offset = 0;
  std::vector<uint8_t> mask;
};

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  using namespace brittle;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const auto basePath = fuzz::scratchDir() / "base.h5";
  if (const Status written = writePack(fuzz::makeSeedPack(), basePath); !written.ok()) {
    finding("the seed pack cannot be written: " + written.error().message);
  }
  if (const Result<Pack> read = readPack(basePath); !read.ok()) {
    finding("the seed pack cannot be read: " + read.error().message);
  }
  std::ifstream in(basePath, std::ios::binary);
  gBase.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  const Id file{H5Fopen(basePath.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  H5Lvisit(file.id, H5_INDEX_NAME, H5_ITER_INC, collect, nullptr);
  if (gBase.datasets.empty() || gBase.groups.empty()) finding("the seed pack has no datasets or groups");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace brittle;
  FuzzedDataProvider in(data, size);
  const auto path = fuzz::writeScratchFile("pack.h5", gBase.bytes);
  std::vector<ByteEdit> byteEdits;
  bool outside = false;
  gValuesOutside = false;
  {
    const Id file{H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose};
    if (file.id < 0) finding("the seed pack's copy cannot be opened");
    for (int e = 0; e < kMaxEdits && in.remaining_bytes() > 0; ++e) {
      switch (in.ConsumeIntegralInRange(0, 7)) {
        case 0: setElement(in, file.id); break;
        case 1: reshape(in, file.id); break;
        case 2: retype(in, file.id); break;
        case 3: unlink(in, file.id); break;
        case 4: relink(in, file.id); break;
        case 5: editAttribute(in, file.id); break;
        case 6: {
          ByteEdit flip;
          flip.offset = in.ConsumeIntegral<uint32_t>();
          flip.mask = in.ConsumeBytes<uint8_t>(in.ConsumeIntegralInRange<size_t>(1, 8));
          byteEdits.push_back(flip);
          break;
        }
        case 7: byteEdits.push_back({true, in.ConsumeIntegral<uint32_t>(), {}}); break;
      }
    }
    outside = gValuesOutside && readsValuesOutside(file.id);
  }
  if (H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL) != 0) finding("an edit left an HDF5 object open");
  if (!byteEdits.empty()) {
    std::ifstream file(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    for (const ByteEdit& edit : byteEdits) {
      if (bytes.empty()) break;
      const size_t at = edit.offset % (bytes.size() + (edit.truncate ? 1 : 0));
      if (edit.truncate) bytes.resize(at);
      for (size_t i = 0; i < edit.mask.size() && at + i < bytes.size(); ++i) bytes[at + i] ^= static_cast<char>(edit.mask[i]);
    }
    fuzz::writeScratchFile("pack.h5", bytes);
  }
  const Result<Pack> pack = readPack(path);
  fuzz::checkReadResult(pack);
  if (pack.ok() && outside) finding("readPack accepted a pack whose values are kept in another file");
  fuzz::checkOnDemandRead(path, pack.ok());
  return 0;
}
