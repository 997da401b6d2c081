// PackReader.cpp — reads and validates a pack in schema v1 (database/PACK_SCHEMA.md).
//
// Nothing read here is trusted: the format and version are checked first, then every dataset's
// type and shape (before anything is allocated for it), every offset table, every checksum (by
// HDF5's Fletcher-32 filter during the read), every float for finiteness and every index for
// range. Only a pack that passes all of it reaches the runtime.
#include <hdf5.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include "Hdf5Util.h"
#include "brittle/database/Pack.h"

namespace brittle {
namespace {

namespace fs = std::filesystem;
using hdf5::Handle;

// zlib cannot inflate more than about 1032 bytes per stored byte, so a dataset that claims more
// than this many bytes per stored byte is lying about its shape. Checking this before allocating
// bounds every allocation by the size of the file, whatever its dataspaces claim.
constexpr hsize_t kMaxInflateRatio = 1100;

// A dimension the caller checks itself (against a count read elsewhere).
constexpr hsize_t kAny = std::numeric_limits<hsize_t>::max();

// Thrown inside the reader and caught in readPack: validation is a long sequence of checks that
// each may end the read, and an exception keeps each one to a single line.
struct ReadFailure {
  Error error;
};

[[noreturn]] void fail(ErrorCode code, std::string message) { throw ReadFailure{makeError(code, std::move(message))}; }

template <typename T>
struct Array {
  std::vector<T> values;
  std::vector<hsize_t> dims;
};

std::string shapeString(const std::vector<hsize_t>& dims) {
  std::string s = "[";
  for (size_t d = 0; d < dims.size(); ++d) {
    if (d > 0) s += ", ";
    s += dims[d] == kAny ? std::string("*") : std::to_string(dims[d]);
  }
  return s + "]";
}

// "[i, j]" of a flat row-major index.
std::string indexString(size_t flat, const std::vector<hsize_t>& dims) {
  std::vector<hsize_t> index(dims.size());
  for (size_t d = dims.size(); d-- > 0;) {
    index[d] = dims[d] == 0 ? 0 : flat % dims[d];
    flat = dims[d] == 0 ? 0 : flat / dims[d];
  }
  return shapeString(index);
}

class FileReader {
 public:
  FileReader(hid_t file, uintmax_t fileBytes) : mFile(file), mFileBytes(fileBytes) {}

  /// True when a link named path exists (whatever it points to).
  bool exists(const std::string& path) {
    const htri_t found = H5Lexists(mFile, path.c_str(), H5P_DEFAULT);
    if (found < 0) fail(ErrorCode::PackCorrupt, "cannot look up '" + path + "'" + hdf5::withDetail());
    return found > 0;
  }

  void requireGroup(const std::string& path) {
    Handle group = openObject(path, "group");
    if (H5Iget_type(group.get()) != H5I_GROUP) fail(ErrorCode::PackShapeMismatch, "'" + path + "' is not a group");
  }

  /// nullopt when the attribute is missing or is not one string.
  std::optional<std::string> stringAttribute(const std::string& where, const char* name) {
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

  /// nullopt when the attribute is missing or is not one integer.
  std::optional<int64_t> intAttribute(const std::string& where, const char* name) {
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

  Array<double> f64(const std::string& path, const std::vector<hsize_t>& shape) {
    Array<double> a = numeric<double>(path, shape, H5T_FLOAT, H5T_NATIVE_DOUBLE, "float64");
    for (size_t i = 0; i < a.values.size(); ++i) {
      if (!std::isfinite(a.values[i])) {
        fail(ErrorCode::PackCorrupt, "dataset '" + path + "' holds a non-finite value (" + std::to_string(a.values[i]) +
                                         ") at " + indexString(i, a.dims));
      }
    }
    return a;
  }
  Array<float> f32(const std::string& path, const std::vector<hsize_t>& shape) {
    Array<float> a = numeric<float>(path, shape, H5T_FLOAT, H5T_NATIVE_FLOAT, "float32");
    for (size_t i = 0; i < a.values.size(); ++i) {
      if (!std::isfinite(a.values[i])) {
        fail(ErrorCode::PackCorrupt, "dataset '" + path + "' holds a non-finite value at " + indexString(i, a.dims));
      }
    }
    return a;
  }
  Array<int64_t> i64(const std::string& path, const std::vector<hsize_t>& shape) {
    return numeric<int64_t>(path, shape, H5T_INTEGER, H5T_NATIVE_INT64, "int64");
  }
  Array<int32_t> i32(const std::string& path, const std::vector<hsize_t>& shape) {
    return numeric<int32_t>(path, shape, H5T_INTEGER, H5T_NATIVE_INT32, "int32");
  }
  Array<uint8_t> u8(const std::string& path, const std::vector<hsize_t>& shape) {
    return numeric<uint8_t>(path, shape, H5T_INTEGER, H5T_NATIVE_UINT8, "uint8");
  }

  /// A 1-D dataset of fixed-length strings of `count` entries (kAny: any).
  std::vector<std::string> strings(const std::string& path, hsize_t count) {
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
    read(dset, path, mem.get(), buffer.data(), dims[0]);
    std::vector<std::string> out(dims[0]);
    for (size_t i = 0; i < out.size(); ++i) out[i].assign(&buffer[i * width], strnlen(&buffer[i * width], width));
    return out;
  }

 private:
  Handle openObject(const std::string& path, const char* kind) {
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

  Handle openDataset(const std::string& path) {
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

  // An invalid handle when the attribute is missing.
  Handle openAttribute(const std::string& where, const char* name) {
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

  static hssize_t pointCount(const Handle& attr) {
    Handle space = hdf5::dataspaceHandle(H5Aget_space(attr.get()));
    return space.valid() ? H5Sget_simple_extent_npoints(space.get()) : -1;
  }

  static Handle stringMemType(size_t width, H5T_cset_t cset) {
    Handle type = hdf5::datatypeHandle(H5Tcopy(H5T_C_S1));
    // The memory type takes the file's character set: HDF5 does not convert between sets.
    if (!type.valid() || H5Tset_size(type.get(), width) < 0 || H5Tset_cset(type.get(), cset) < 0 ||
        (width != H5T_VARIABLE && H5Tset_strpad(type.get(), H5T_STR_NULLPAD) < 0)) {
      fail(ErrorCode::PackIoError, "cannot create a string type" + hdf5::withDetail());
    }
    return type;
  }

  template <typename T>
  Array<T> numeric(const std::string& path, const std::vector<hsize_t>& shape, H5T_class_t typeClass, hid_t memType,
                   const char* typeName) {
    Handle dset = openDataset(path);
    Handle type = hdf5::datatypeHandle(H5Dget_type(dset.get()));
    if (!type.valid())
      fail(ErrorCode::PackCorrupt, "cannot read the type of dataset '" + path + "'" + hdf5::withDetail());
    // The exact type is required: HDF5 would otherwise convert silently, and a narrowing
    // conversion (float64 → int32, int64 → int32) clips values instead of failing.
    if (H5Tget_class(type.get()) != typeClass || H5Tget_size(type.get()) != sizeof(T) ||
        (typeClass == H5T_INTEGER && H5Tget_sign(type.get()) != H5Tget_sign(memType))) {
      fail(ErrorCode::PackShapeMismatch, "dataset '" + path + "' must hold " + typeName);
    }
    Array<T> a;
    a.dims = checkedDims(dset, path, shape, sizeof(T));
    size_t count = 1;
    for (hsize_t d : a.dims) count *= d;
    a.values.resize(count);
    read(dset, path, memType, a.values.data(), count);
    return a;
  }

  // The dataset's dimensions, once its rank and fixed dimensions match `shape` and its claimed
  // size is plausible for what the file stores.
  std::vector<hsize_t> checkedDims(const Handle& dset, const std::string& path, const std::vector<hsize_t>& shape,
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

  // A failed read of a dataset whose shape and type checked out means its stored bytes are bad:
  // the Fletcher-32 filter found a mismatch, or deflate could not decode the chunk.
  static void read(const Handle& dset, const std::string& path, hid_t memType, void* buffer, size_t count) {
    if (count > 0 && H5Dread(dset.get(), memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer) < 0) {
      fail(ErrorCode::PackCorrupt,
           "cannot read dataset '" + path + "': checksum mismatch or damaged data" + hdf5::withDetail());
    }
  }

  hid_t mFile;
  uintmax_t mFileBytes;
};

// Validates an offset table of a ragged array: O + 1 entries, starting at 0, non-decreasing,
// ending at the number of rows of the values dataset.
std::vector<int64_t> readOffsets(FileReader& r, const std::string& path, hsize_t objectCount, hsize_t rows,
                                 const std::string& valuesPath) {
  std::vector<int64_t> offsets = r.i64(path, {objectCount + 1}).values;
  if (offsets[0] != 0) {
    fail(ErrorCode::PackShapeMismatch, "dataset '" + path + "' starts at " + std::to_string(offsets[0]) + ", not 0");
  }
  for (size_t i = 0; i + 1 < offsets.size(); ++i) {
    if (offsets[i + 1] < offsets[i]) {
      fail(ErrorCode::PackShapeMismatch, "dataset '" + path + "' decreases at index " + std::to_string(i + 1));
    }
  }
  if (static_cast<hsize_t>(offsets.back()) != rows) {
    fail(ErrorCode::PackShapeMismatch, "dataset '" + path + "' ends at " + std::to_string(offsets.back()) + " but '" +
                                           valuesPath + "' has " + std::to_string(rows) + " rows");
  }
  return offsets;
}

// Per-object block sizes of a flat modal array must be rowsPerItem × items × modes.
void checkBlockSize(const std::vector<int64_t>& valueOffsets, size_t i, const std::string& path, int64_t rowsPerItem,
                    int64_t items, int64_t modes, const std::string& name) {
  int64_t expected = 0;
  const bool overflow =
      __builtin_mul_overflow(rowsPerItem, items, &expected) || __builtin_mul_overflow(expected, modes, &expected);
  if (overflow || valueOffsets[i + 1] - valueOffsets[i] != expected) {
    fail(ErrorCode::PackShapeMismatch, "dataset '" + path + "': object '" + name + "' has " +
                                           std::to_string(valueOffsets[i + 1] - valueOffsets[i]) + " values, expected " +
                                           std::to_string(rowsPerItem) + " x " + std::to_string(items) + " x " +
                                           std::to_string(modes));
  }
}

template <typename Indices>
void checkIndices(const Indices& indices, const std::string& path, int64_t firstRow, int64_t nodeCount,
                  const std::string& objectName) {
  for (Eigen::Index r = 0; r < indices.rows(); ++r) {
    for (Eigen::Index c = 0; c < indices.cols(); ++c) {
      const int32_t v = indices(r, c);
      if (v < 0 || v >= nodeCount) {
        fail(ErrorCode::PackCorrupt, "dataset '" + path + "' [" + std::to_string(firstRow + r) + ", " +
                                         std::to_string(c) + "] = " + std::to_string(v) + " is not a node of object '" +
                                         objectName + "' (it has " + std::to_string(nodeCount) + " nodes)");
      }
    }
  }
}

int64_t checkRoot(FileReader& r) {
  const std::optional<std::string> format = r.stringAttribute("/", "format");
  if (!format) fail(ErrorCode::PackFormatMismatch, "no 'format' string attribute: not a brittle pack");
  if (*format != kPackFormatName) {
    fail(ErrorCode::PackFormatMismatch, "format is '" + *format + "', expected '" + kPackFormatName + "'");
  }
  const std::optional<int64_t> version = r.intAttribute("/", "version");
  if (!version) fail(ErrorCode::PackVersionMismatch, "no integer 'version' attribute");
  if (*version < kOldestReadablePackVersion || *version > kPackVersion) {
    fail(ErrorCode::PackVersionMismatch, "pack version " + std::to_string(*version) + ", this reader reads versions " +
                                             std::to_string(kOldestReadablePackVersion) + " to " +
                                             std::to_string(kPackVersion));
  }
  for (const auto& unit : packschema::kUnitAttributes) {
    const std::optional<std::string> value = r.stringAttribute("/", unit.name);
    if (value != unit.value) {
      fail(ErrorCode::PackFormatMismatch, "attribute '" + std::string(unit.name) + "' is " +
                                              (value ? "'" + *value + "'" : std::string("missing")) + ", expected '" +
                                              unit.value + "'");
    }
  }
  return *version;
}

std::vector<Material> readMaterials(FileReader& r, const std::string& prefix) {
  r.requireGroup(prefix);
  const std::vector<std::string> names = r.strings(prefix + "/name", kAny);
  const hsize_t m = names.size();
  const auto column = [&](const char* name) { return r.f64(prefix + "/" + name, {m}).values; };
  const auto youngs = column("youngs_modulus_pa");
  const auto poisson = column("poisson_ratio");
  const auto density = column("density_kg_per_m3");
  const auto tensile = column("tensile_strength_pa");
  const auto fracture = column("fracture_energy_j_per_m2");
  const auto alpha = column("rayleigh_alpha_per_s");
  const auto beta = column("rayleigh_beta_s");
  const auto restitution = column("restitution");
  const auto sources = r.strings(prefix + "/source", m);

  std::vector<Material> materials(m);
  std::set<std::string> seen;
  for (size_t i = 0; i < m; ++i) {
    Material& mat = materials[i];
    mat.name = names[i];
    mat.youngsModulusPa = youngs[i];
    mat.poissonRatio = poisson[i];
    mat.densityKgPerM3 = density[i];
    mat.tensileStrengthPa = tensile[i];
    mat.fractureEnergyJPerM2 = fracture[i];
    mat.rayleighAlphaPerS = alpha[i];
    mat.rayleighBetaS = beta[i];
    mat.restitution = restitution[i];
    mat.source = sources[i];
    if (Status valid = validateMaterial(mat); !valid) {
      fail(ErrorCode::PackCorrupt, prefix + " row " + std::to_string(i) + ": " + valid.error().message);
    }
    if (!seen.insert(mat.name).second) fail(ErrorCode::PackCorrupt, "two materials are named '" + mat.name + "'");
  }
  return materials;
}

std::vector<ObjectAsset> readObjects(FileReader& r, const std::string& prefix, const std::vector<Material>& materials,
                                     int64_t version) {
  r.requireGroup(prefix);
  r.requireGroup(prefix + "/quality");
  r.requireGroup(prefix + "/bake");
  const std::vector<std::string> names = r.strings(prefix + "/name", kAny);
  const hsize_t o = names.size();
  const std::vector<std::string> materialNames = r.strings(prefix + "/material_name", o);
  // Version 3 added the element order; older packs are all P1.
  const std::vector<int32_t> orders =
      version >= 3 ? r.i32(prefix + "/element_order", {o}).values : std::vector<int32_t>(o, 1);

  const Array<double> nodes = r.f64(prefix + "/nodes", {kAny, 3});
  const auto nodeOffsets = readOffsets(r, prefix + "/node_offsets", o, nodes.dims[0], prefix + "/nodes");
  const Array<int32_t> tets = r.i32(prefix + "/tets", {kAny, 4});
  const auto tetOffsets = readOffsets(r, prefix + "/tet_offsets", o, tets.dims[0], prefix + "/tets");
  const Array<int32_t> faces = r.i32(prefix + "/surface_faces", {kAny, 3});
  const auto faceOffsets = readOffsets(r, prefix + "/face_offsets", o, faces.dims[0], prefix + "/surface_faces");

  const auto massKg = r.f64(prefix + "/mass_kg", {o}).values;
  const auto volumeM3 = r.f64(prefix + "/volume_m3", {o}).values;
  const auto centerOfMass = r.f64(prefix + "/center_of_mass_m", {o, 3}).values;
  const auto inertia = r.f64(prefix + "/inertia_kg_m2", {o, 3, 3}).values;
  const auto secondMoment = r.f64(prefix + "/second_moment_m5", {o, 3, 3}).values;

  const Array<double> eigenvalues = r.f64(prefix + "/eigenvalues_rad2_per_s2", {kAny});
  const hsize_t modeTotal = eigenvalues.dims[0];
  const auto modeOffsets = readOffsets(r, prefix + "/mode_offsets", o, modeTotal, prefix + "/eigenvalues_rad2_per_s2");
  const auto frequencies = r.f64(prefix + "/frequencies_hz", {modeTotal}).values;
  const auto residuals = r.f64(prefix + "/residuals", {modeTotal}).values;
  const auto orthonormality = r.f64(prefix + "/orthonormality_error", {o}).values;
  const Array<double> modes = r.f64(prefix + "/modes", {kAny});
  const auto modesOffsets = readOffsets(r, prefix + "/modes_value_offsets", o, modes.dims[0], prefix + "/modes");
  const Array<double> stressModes = r.f64(prefix + "/stress_modes", {kAny});
  const auto stressOffsets =
      readOffsets(r, prefix + "/stress_modes_value_offsets", o, stressModes.dims[0], prefix + "/stress_modes");

  const auto qNodes = r.i64(prefix + "/quality/node_count", {o}).values;
  const auto qTets = r.i64(prefix + "/quality/tet_count", {o}).values;
  const auto qFaces = r.i64(prefix + "/quality/surface_face_count", {o}).values;
  const auto qMinDihedral = r.f64(prefix + "/quality/min_dihedral_deg", {o}).values;
  const auto qMaxDihedral = r.f64(prefix + "/quality/max_dihedral_deg", {o}).values;
  const auto qMaxRatio = r.f64(prefix + "/quality/max_radius_edge_ratio", {o}).values;
  const auto qMeanRatio = r.f64(prefix + "/quality/mean_radius_edge_ratio", {o}).values;
  const auto qMinVolume = r.f64(prefix + "/quality/min_tet_volume_m3", {o}).values;

  const auto sourceMesh = r.strings(prefix + "/bake/source_mesh", o);
  const auto targetTets = r.i64(prefix + "/bake/target_tets", {o}).values;
  const auto cellSize = r.f64(prefix + "/bake/cell_size_m", {o}).values;
  const auto requestedModes = r.i64(prefix + "/bake/requested_modes", {o}).values;
  const auto lumpedMass = r.u8(prefix + "/bake/lumped_mass", {o}).values;
  const auto repaired = r.u8(prefix + "/bake/repaired", {o}).values;
  const auto repairVolumeChange = r.f64(prefix + "/bake/repair_volume_change", {o}).values;
  const auto factorization = r.strings(prefix + "/bake/factorization", o);
  const auto shift = r.f64(prefix + "/bake/shift_rad2_per_s2", {o}).values;
  const auto seed = r.i64(prefix + "/bake/seed", {o}).values;
  const auto meshingS = r.f64(prefix + "/bake/meshing_s", {o}).values;
  const auto assemblyS = r.f64(prefix + "/bake/assembly_s", {o}).values;
  const auto modalS = r.f64(prefix + "/bake/modal_s", {o}).values;
  const auto stressModesS = r.f64(prefix + "/bake/stress_modes_s", {o}).values;
  const auto totalS = r.f64(prefix + "/bake/total_s", {o}).values;
  const auto generator = r.strings(prefix + "/bake/generator", o);

  std::set<std::string> materialSet, objectSet;
  for (const auto& m : materials) materialSet.insert(m.name);
  const auto flag = [](const std::vector<uint8_t>& values, size_t i, const std::string& path) {
    if (values[i] > 1) {
      fail(ErrorCode::PackCorrupt, "dataset '" + path + "' [" + std::to_string(i) +
                                       "] = " + std::to_string(values[i]) + " is not a boolean (0 or 1)");
    }
    return values[i] == 1;
  };

  std::vector<ObjectAsset> objects(o);
  for (size_t i = 0; i < o; ++i) {
    ObjectAsset& a = objects[i];
    a.name = names[i];
    a.materialName = materialNames[i];
    if (a.name.empty()) fail(ErrorCode::PackCorrupt, "object " + std::to_string(i) + " has an empty name");
    if (!objectSet.insert(a.name).second) fail(ErrorCode::PackCorrupt, "two objects are named '" + a.name + "'");
    if (materialSet.count(a.materialName) == 0) {
      fail(ErrorCode::PackCorrupt,
           "object '" + a.name + "' names material '" + a.materialName + "', which is not in the pack's materials");
    }

    const int64_t n = nodeOffsets[i + 1] - nodeOffsets[i];
    const int64_t t = tetOffsets[i + 1] - tetOffsets[i];
    const int64_t f = faceOffsets[i + 1] - faceOffsets[i];
    const int64_t m = modeOffsets[i + 1] - modeOffsets[i];
    a.tetMesh.nodes = Eigen::Map<const Points>(nodes.values.data() + 3 * nodeOffsets[i], n, 3);
    a.tetMesh.tets = Eigen::Map<const Tetrahedra>(tets.values.data() + 4 * tetOffsets[i], t, 4);
    checkIndices(a.tetMesh.tets, prefix + "/tets", tetOffsets[i], n, a.name);
    a.surfaceFaces = Eigen::Map<const Triangles>(faces.values.data() + 3 * faceOffsets[i], f, 3);
    checkIndices(a.surfaceFaces, prefix + "/surface_faces", faceOffsets[i], n, a.name);
    if (orders[i] != 1 && orders[i] != 2) {
      fail(ErrorCode::PackCorrupt, "dataset '" + prefix + "/element_order' [" + std::to_string(i) + "] = " +
                                       std::to_string(orders[i]) + " is neither 1 (P1) nor 2 (P2)");
    }
    a.elementOrder = static_cast<ElementOrder>(orders[i]);
    const int64_t femNodes = femNodeCount(a.tetMesh, a.elementOrder);
    checkBlockSize(modesOffsets, i, prefix + "/modes", 3, femNodes, m, a.name);
    checkBlockSize(stressOffsets, i, prefix + "/stress_modes", 6 * stressPointsPerElement(a.elementOrder), t, m, a.name);

    MassProperties& mp = a.massProperties;
    mp.massKg = massKg[i];
    mp.volumeM3 = volumeM3[i];
    mp.centerOfMassM = Eigen::Map<const Eigen::Vector3d>(centerOfMass.data() + 3 * i);
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) {
        mp.inertiaKgM2(row, col) = inertia[9 * i + 3 * row + col];
        mp.secondMomentM5(row, col) = secondMoment[9 * i + 3 * row + col];
      }
    }

    ModalBasis& modal = a.modal;
    modal.eigenvaluesRad2PerS2 = Eigen::Map<const Eigen::VectorXd>(eigenvalues.values.data() + modeOffsets[i], m);
    modal.frequenciesHz = Eigen::Map<const Eigen::VectorXd>(frequencies.data() + modeOffsets[i], m);
    modal.residuals = Eigen::Map<const Eigen::VectorXd>(residuals.data() + modeOffsets[i], m);
    modal.orthonormalityError = orthonormality[i];
    modal.modes = Eigen::Map<const MatrixXdRow>(modes.values.data() + modesOffsets[i], 3 * femNodes, m);
    a.stressModes = Eigen::Map<const MatrixXdRow>(stressModes.values.data() + stressOffsets[i],
                                                  6 * stressPointsPerElement(a.elementOrder) * t, m);

    MeshQuality& q = a.quality;
    q.nodeCount = qNodes[i];
    q.tetCount = qTets[i];
    q.surfaceFaceCount = qFaces[i];
    q.minDihedralDeg = qMinDihedral[i];
    q.maxDihedralDeg = qMaxDihedral[i];
    q.maxRadiusEdgeRatio = qMaxRatio[i];
    q.meanRadiusEdgeRatio = qMeanRatio[i];
    q.minTetVolumeM3 = qMinVolume[i];

    BakeRecord& b = a.bake;
    b.sourceMesh = sourceMesh[i];
    b.targetTets = targetTets[i];
    b.cellSizeM = cellSize[i];
    b.requestedModes = requestedModes[i];
    b.lumpedMass = flag(lumpedMass, i, prefix + "/bake/lumped_mass");
    b.repaired = flag(repaired, i, prefix + "/bake/repaired");
    b.repairVolumeChange = repairVolumeChange[i];
    b.factorization = factorization[i];
    b.shift = shift[i];
    b.seed = seed[i];
    b.meshingS = meshingS[i];
    b.assemblyS = assemblyS[i];
    b.modalS = modalS[i];
    b.stressModesS = stressModesS[i];
    b.totalS = totalS[i];
    b.generator = generator[i];
  }
  return objects;
}

// One value of a [1] dataset.
template <typename T>
T scalar(const Array<T>& a) {
  return a.values.front();
}

FragmentDatabase readDatabase(FileReader& r, int64_t version) {
  r.requireGroup("/database");
  FragmentDatabase db;
  db.seed = static_cast<uint64_t>(scalar(r.i64("/database/seed", {1})));
  const std::vector<Material> reference = readMaterials(r, "/database/reference_material");
  if (reference.size() != 1) {
    fail(ErrorCode::PackShapeMismatch, "'/database/reference_material' must hold exactly one material");
  }
  db.referenceMaterial = reference.front();
  std::vector<ObjectAsset> assets = readObjects(r, "/database/entries", reference, version);
  const hsize_t count = assets.size();

  r.requireGroup("/database/fragments");
  const auto shapes = r.strings("/database/fragments/base_shape", count);
  const auto cuts = r.strings("/database/fragments/cut", count);
  const auto seeds = r.i64("/database/fragments/seed", {count}).values;
  const auto fractions = r.f64("/database/fragments/base_volume_fraction", {count}).values;
  const Array<double> vertices = r.f64("/database/fragments/surface_vertices", {kAny, 3});
  const auto vertexOffsets = readOffsets(r, "/database/fragments/surface_vertex_offsets", count, vertices.dims[0],
                                         "/database/fragments/surface_vertices");
  const Array<int32_t> faces = r.i32("/database/fragments/surface_faces", {kAny, 3});
  const auto faceOffsets = readOffsets(r, "/database/fragments/surface_face_offsets", count, faces.dims[0],
                                       "/database/fragments/surface_faces");

  const std::string s = "/database/descriptor_settings";
  r.requireGroup(s);
  ShapeDescriptorSettings& d = db.descriptorSettings;
  const auto tolerances = r.f64(s + "/frame_tolerances", {5}).values;
  d.frame.eigenGapTolerance = tolerances[0];
  d.frame.skewnessTolerance = tolerances[1];
  d.frame.shapeTolerance = tolerances[2];
  d.frame.tieTolerance = tolerances[3];
  d.frame.duplicateTolerance = tolerances[4];
  const auto narrow = [&](const std::string& path) {
    const int64_t v = scalar(r.i64(path, {1}));
    if (v < 0 || v > 1 << 20) fail(ErrorCode::PackCorrupt, "dataset '" + path + "' = " + std::to_string(v) + " is out of range");
    return static_cast<int>(v);
  };
  d.frame.maxCandidates = narrow(s + "/frame_max_candidates");
  d.moment.maxOrder = narrow(s + "/moment_max_order");
  d.moment.orderWeights = r.f64(s + "/moment_order_weights", {kAny}).values;
  d.voxel.resolution = narrow(s + "/voxel_resolution");
  d.voxel.halfExtent = scalar(r.f64(s + "/voxel_half_extent", {1}));
  d.voxelImproved.resolution = narrow(s + "/voxel_improved_resolution");
  d.voxelImproved.halfExtent = scalar(r.f64(s + "/voxel_improved_half_extent", {1}));
  d.voxelImproved.clampVoxels = scalar(r.f64(s + "/voxel_improved_clamp_voxels", {1}));
  if (Status valid = validateShapeDescriptorSettings(d); !valid) fail(ErrorCode::PackCorrupt, s + ": " + valid.error().message);

  r.requireGroup("/database/descriptors");
  for (DescriptorKind kind : kAllDescriptorKinds) {
    const std::string path = std::string("/database/descriptors/") + descriptorKindName(kind);
    const auto width = static_cast<hsize_t>(descriptorSize(kind, d));
    const Array<float> m = r.f32(path, {count, width});
    db.descriptors[static_cast<size_t>(kind)] =
        Eigen::Map<const DescriptorMatrix>(m.values.data(), static_cast<Eigen::Index>(count), static_cast<Eigen::Index>(width));
  }

  r.requireGroup("/database/index");
  const hsize_t kinds = kDescriptorKindCount;
  const auto names = r.strings("/database/index/descriptor", kinds);
  const auto backends = r.strings("/database/index/backend", kinds);
  const auto trees = r.i64("/database/index/trees", {kinds}).values;
  const auto checks = r.i64("/database/index/checks", {kinds}).values;
  const auto precision = r.f64("/database/index/target_precision", {kinds}).values;
  const auto indexSeeds = r.i64("/database/index/seed", {kinds}).values;
  for (size_t k = 0; k < kinds; ++k) {
    const auto kind = parseDescriptorKind(names[k]);
    const auto backend = parseDescriptorIndexKind(backends[k]);
    if (!kind || !backend) fail(ErrorCode::PackCorrupt, "/database/index row " + std::to_string(k) + ": unknown name");
    if (trees[k] < 1 || trees[k] > 1024 || checks[k] < 1 || checks[k] > INT32_MAX) {
      fail(ErrorCode::PackCorrupt, "/database/index row " + std::to_string(k) + ": trees or checks out of range");
    }
    DescriptorIndexSettings& is = db.indexSettings[static_cast<size_t>(kind.value())];
    is.kind = backend.value();
    is.trees = static_cast<int>(trees[k]);
    is.checks = static_cast<int>(checks[k]);
    is.targetPrecision = static_cast<float>(precision[k]);
    is.seed = static_cast<uint64_t>(indexSeeds[k]);
  }

  db.entries.resize(count);
  for (size_t i = 0; i < count; ++i) {
    FragmentEntry& e = db.entries[i];
    e.asset = std::move(assets[i]);
    e.baseShape = shapes[i];
    e.cut = cuts[i];
    e.seed = static_cast<uint64_t>(seeds[i]);
    e.baseVolumeFraction = fractions[i];
    const int64_t nv = vertexOffsets[i + 1] - vertexOffsets[i];
    const int64_t nf = faceOffsets[i + 1] - faceOffsets[i];
    e.surface.vertices = Eigen::Map<const Points>(vertices.values.data() + 3 * vertexOffsets[i], nv, 3);
    e.surface.faces = Eigen::Map<const Triangles>(faces.values.data() + 3 * faceOffsets[i], nf, 3);
    checkIndices(e.surface.faces, "/database/fragments/surface_faces", faceOffsets[i], nv, e.asset.name);
  }
  if (Status valid = validateFragmentDatabase(db); !valid) fail(ErrorCode::PackCorrupt, "/database: " + valid.error().message);
  return db;
}

}  // namespace

Result<Pack> readPack(const fs::path& path) {
  const std::string label = "pack '" + path.string() + "'";
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found) return makeError(ErrorCode::FileNotFound, label + " does not exist");
  if (ec) return makeError(ErrorCode::PackIoError, label + ": " + ec.message());
  if (!fs::is_regular_file(status)) return makeError(ErrorCode::PackIoError, label + " is not a regular file");
  const uintmax_t fileBytes = fs::file_size(path, ec);
  if (ec) return makeError(ErrorCode::PackIoError, label + ": " + ec.message());
  if (!std::ifstream(path, std::ios::binary))
    return makeError(ErrorCode::PackIoError, label + " cannot be opened for reading");

  hdf5::ErrorSilencer silencer;
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    return makeError(ErrorCode::PackIoError, label + " is not an HDF5 file");
  }
  // The signature is there, so a file HDF5 cannot open is damaged, typically truncated.
  Handle file = hdf5::fileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!file.valid()) {
    return makeError(ErrorCode::PackCorrupt,
                     label + " is an HDF5 file that cannot be opened (truncated or damaged)" + hdf5::withDetail());
  }
  try {
    FileReader reader(file.get(), fileBytes);
    const int64_t version = checkRoot(reader);
    Pack pack;
    pack.materials = readMaterials(reader, "/materials");
    pack.objects = readObjects(reader, "/objects", pack.materials, version);
    // The database is optional from version 2 on; version 1 packs have none.
    if (version >= 2 && reader.exists("/database")) pack.database = readDatabase(reader, version);
    return pack;
  } catch (const ReadFailure& failure) {
    return makeError(failure.error.code, label + ": " + failure.error.message);
  } catch (const std::exception& e) {
    // Only allocation can throw here, and the sizes were bounded first; still never throw out.
    return makeError(ErrorCode::PackIoError, label + ": " + e.what());
  }
}

}  // namespace brittle
