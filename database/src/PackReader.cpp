// PackReader.cpp — reads and validates a pack (database/PACK_SCHEMA.md): the schema, on top of the
// checked HDF5 reads of Hdf5Reader.h.
//
// Nothing read here is trusted: the format and version are checked first, then every dataset's
// type and shape (before anything is allocated for it), every offset table, every checksum (by
// HDF5's Fletcher-32 filter during the read), every float for finiteness and every index for
// range. Only a pack that passes all of it reaches the runtime.
#include <hdf5.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include "Hdf5Reader.h"
#include "PackSchema.h"
#include "brittle/database/Pack.h"
#include "brittle/descriptors/VolumeMoments.h"

namespace brittle {
namespace {

namespace fs = std::filesystem;
using hdf5::Array;
using hdf5::Dataset;
using hdf5::fail;
using hdf5::FileReader;
using hdf5::Handle;
using hdf5::kAny;
using hdf5::shapeString;

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

// An object table (/objects or /database/entries) read but for the arrays that grow with the
// mesh: every object's other fields, those arrays checked and open, and their offset tables
// checked against their row counts. readObjectArrays reads the arrays of any run of objects.
struct ObjectTable {
  std::string prefix;
  std::vector<ObjectAsset> objects;  // without tetMesh, surfaceFaces, modal.modes, stressModes, eliminationOrder
  Dataset<double> nodes, modes, stressModes;
  Dataset<int32_t> tets, faces;
  std::optional<Dataset<int32_t>> elimination;
  std::vector<int64_t> nodeOffsets, tetOffsets, faceOffsets, modesOffsets, stressOffsets, eliminationOffsets;
};

ObjectTable readObjectTable(FileReader& r, const std::string& prefix, const std::vector<Material>& materials,
                            int64_t version) {
  r.requireGroup(prefix);
  r.requireGroup(prefix + "/quality");
  r.requireGroup(prefix + "/bake");
  ObjectTable table;
  table.prefix = prefix;
  const std::vector<std::string> names = r.strings(prefix + "/name", kAny);
  const hsize_t o = names.size();
  const std::vector<std::string> materialNames = r.strings(prefix + "/material_name", o);
  // Version 3 added the element order; older packs are all P1.
  const std::vector<int32_t> orders =
      version >= 3 ? r.i32(prefix + "/element_order", {o}).values : std::vector<int32_t>(o, 1);

  const auto offsets = [&](const std::string& offsetsName, const auto& values, const std::string& valuesName) {
    return readOffsets(r, prefix + "/" + offsetsName, o, values.dims()[0], prefix + "/" + valuesName);
  };
  table.nodes = r.open<double>(prefix + "/nodes", {kAny, 3});
  table.nodeOffsets = offsets("node_offsets", table.nodes, "nodes");
  table.tets = r.open<int32_t>(prefix + "/tets", {kAny, 4});
  table.tetOffsets = offsets("tet_offsets", table.tets, "tets");
  table.faces = r.open<int32_t>(prefix + "/surface_faces", {kAny, 3});
  table.faceOffsets = offsets("face_offsets", table.faces, "surface_faces");

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
  table.modes = r.open<double>(prefix + "/modes", {kAny});
  table.modesOffsets = offsets("modes_value_offsets", table.modes, "modes");
  table.stressModes = r.open<double>(prefix + "/stress_modes", {kAny});
  table.stressOffsets = offsets("stress_modes_value_offsets", table.stressModes, "stress_modes");
  // Optional, without a version bump (PACK_SCHEMA.md): packs baked before it have none.
  if (r.exists(prefix + "/elimination_order")) {
    table.elimination = r.open<int32_t>(prefix + "/elimination_order", {kAny});
    table.eliminationOffsets = offsets("elimination_order_offsets", *table.elimination, "elimination_order");
  }

  const auto qNodes = r.i64(prefix + "/quality/node_count", {o}).values;
  const auto qTets = r.i64(prefix + "/quality/tet_count", {o}).values;
  const auto qFaces = r.i64(prefix + "/quality/surface_face_count", {o}).values;
  const auto qMinDihedral = r.f64(prefix + "/quality/min_dihedral_deg", {o}).values;
  const auto qMaxDihedral = r.f64(prefix + "/quality/max_dihedral_deg", {o}).values;
  const auto qMaxRatio = r.f64(prefix + "/quality/max_radius_edge_ratio", {o}).values;
  const auto qMeanRatio = r.f64(prefix + "/quality/mean_radius_edge_ratio", {o}).values;
  const auto qMinVolume = r.f64(prefix + "/quality/min_tet_volume_m3", {o}).values;

  // Optional, without a version bump (PACK_SCHEMA.md): packs baked before it give none (0).
  const auto spread = r.exists(prefix + "/contact_spread_fraction") ? r.f64(prefix + "/contact_spread_fraction", {o}).values
                                                                      : std::vector<double>(static_cast<size_t>(o), 0.0);
  const auto sourceMesh = r.strings(prefix + "/bake/source_mesh", o);
  const auto targetTets = r.i64(prefix + "/bake/target_tets", {o}).values;
  const auto cellSize = r.f64(prefix + "/bake/cell_size_m", {o}).values;
  // Optional, without a version bump (PACK_SCHEMA.md): packs baked before it were not stretched.
  const auto thinStretch = r.exists(prefix + "/bake/thin_stretch") ? r.f64(prefix + "/bake/thin_stretch", {o}).values
                                                                    : std::vector<double>(static_cast<size_t>(o), 1.0);
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

  table.objects.resize(o);
  for (size_t i = 0; i < o; ++i) {
    ObjectAsset& a = table.objects[i];
    a.name = names[i];
    a.materialName = materialNames[i];
    if (a.name.empty()) fail(ErrorCode::PackCorrupt, "object " + std::to_string(i) + " has an empty name");
    if (!objectSet.insert(a.name).second) fail(ErrorCode::PackCorrupt, "two objects are named '" + a.name + "'");
    if (materialSet.count(a.materialName) == 0) {
      fail(ErrorCode::PackCorrupt,
           "object '" + a.name + "' names material '" + a.materialName + "', which is not in the pack's materials");
    }
    if (orders[i] != 1 && orders[i] != 2) {
      fail(ErrorCode::PackCorrupt, "dataset '" + prefix + "/element_order' [" + std::to_string(i) + "] = " +
                                       std::to_string(orders[i]) + " is neither 1 (P1) nor 2 (P2)");
    }
    a.elementOrder = static_cast<ElementOrder>(orders[i]);
    a.contactSpreadFraction = spread[i];
    if (!isContactSpreadFraction(a.contactSpreadFraction)) {
      fail(ErrorCode::PackCorrupt, "dataset '" + prefix + "/contact_spread_fraction' [" + std::to_string(i) + "] is " +
                                       std::to_string(a.contactSpreadFraction) + ", outside [0, 1)");
    }

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
    const int64_t m = modeOffsets[i + 1] - modeOffsets[i];
    modal.eigenvaluesRad2PerS2 = Eigen::Map<const Eigen::VectorXd>(eigenvalues.values.data() + modeOffsets[i], m);
    modal.frequenciesHz = Eigen::Map<const Eigen::VectorXd>(frequencies.data() + modeOffsets[i], m);
    modal.residuals = Eigen::Map<const Eigen::VectorXd>(residuals.data() + modeOffsets[i], m);
    modal.orthonormalityError = orthonormality[i];

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
    b.thinStretch = thinStretch[i];
    if (!isThinStretch(b.thinStretch)) {
      fail(ErrorCode::PackCorrupt, "dataset '" + prefix + "/bake/thin_stretch' [" + std::to_string(i) + "] is " +
                                       std::to_string(b.thinStretch) + ", outside [1, 16]");
    }
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
  return table;
}

// The rows [offsets[first], offsets[last]) of a ragged dataset: a run of objects' arrays.
hdf5::Rows rowsOf(const std::vector<int64_t>& offsets, size_t first, size_t last) {
  return {static_cast<hsize_t>(offsets[first]), static_cast<hsize_t>(offsets[last] - offsets[first])};
}

// Reads the arrays of objects [first, last) of `table` into objectAt(i), an ObjectAsset& whose
// other fields are read, and checks them: every index in range, every block of the size its
// object's mesh and modes give, every elimination order a permutation.
template <class ObjectAt>
void readObjectArrays(const ObjectTable& t, size_t first, size_t last, ObjectAt&& objectAt) {
  const std::string& prefix = t.prefix;
  const Array<double> nodes = t.nodes.read(rowsOf(t.nodeOffsets, first, last));
  const Array<int32_t> tets = t.tets.read(rowsOf(t.tetOffsets, first, last));
  const Array<int32_t> faces = t.faces.read(rowsOf(t.faceOffsets, first, last));
  const Array<double> modes = t.modes.read(rowsOf(t.modesOffsets, first, last));
  const Array<double> stressModes = t.stressModes.read(rowsOf(t.stressOffsets, first, last));
  Array<int32_t> elimination;
  if (t.elimination) elimination = t.elimination->read(rowsOf(t.eliminationOffsets, first, last));
  // Where object i's rows start in what was read.
  const auto at = [&](const std::vector<int64_t>& offsets, size_t i) { return offsets[i] - offsets[first]; };

  for (size_t i = first; i < last; ++i) {
    ObjectAsset& a = objectAt(i);
    const int64_t n = t.nodeOffsets[i + 1] - t.nodeOffsets[i];
    const int64_t tetCount = t.tetOffsets[i + 1] - t.tetOffsets[i];
    const int64_t f = t.faceOffsets[i + 1] - t.faceOffsets[i];
    const auto m = a.modal.eigenvaluesRad2PerS2.size();
    a.tetMesh.nodes = Eigen::Map<const Points>(nodes.values.data() + 3 * at(t.nodeOffsets, i), n, 3);
    a.tetMesh.tets = Eigen::Map<const Tetrahedra>(tets.values.data() + 4 * at(t.tetOffsets, i), tetCount, 4);
    checkIndices(a.tetMesh.tets, prefix + "/tets", t.tetOffsets[i], n, a.name);
    a.surfaceFaces = Eigen::Map<const Triangles>(faces.values.data() + 3 * at(t.faceOffsets, i), f, 3);
    checkIndices(a.surfaceFaces, prefix + "/surface_faces", t.faceOffsets[i], n, a.name);
    const int64_t femNodes = femNodeCount(a.tetMesh, a.elementOrder);
    checkBlockSize(t.modesOffsets, i, prefix + "/modes", 3, femNodes, m, a.name);
    checkBlockSize(t.stressOffsets, i, prefix + "/stress_modes", 6 * stressPointsPerElement(a.elementOrder), tetCount,
                   m, a.name);
    if (t.elimination && t.eliminationOffsets[i + 1] > t.eliminationOffsets[i]) {
      a.eliminationOrder = Eigen::Map<const Eigen::VectorXi>(elimination.values.data() + at(t.eliminationOffsets, i),
                                                             t.eliminationOffsets[i + 1] - t.eliminationOffsets[i]);
      if (!isPermutation(a.eliminationOrder, 3 * femNodes)) {
        fail(ErrorCode::PackCorrupt, "dataset '" + prefix + "/elimination_order' of object '" + a.name +
                                         "' is not a permutation of its " + std::to_string(3 * femNodes) +
                                         " degrees of freedom");
      }
    }
    a.modal.modes = Eigen::Map<const MatrixXdRow>(modes.values.data() + at(t.modesOffsets, i), 3 * femNodes, m);
    a.stressModes = Eigen::Map<const MatrixXdRow>(stressModes.values.data() + at(t.stressOffsets, i),
                                                  6 * stressPointsPerElement(a.elementOrder) * tetCount, m);
  }
}

// Every object of the table, whole.
std::vector<ObjectAsset> readObjects(FileReader& r, const std::string& prefix, const std::vector<Material>& materials,
                                     int64_t version) {
  ObjectTable table = readObjectTable(r, prefix, materials, version);
  readObjectArrays(table, 0, table.objects.size(), [&](size_t i) -> ObjectAsset& { return table.objects[i]; });
  return std::move(table.objects);
}

// One value of a [1] dataset.
template <typename T>
T scalar(const Array<T>& a) {
  return a.values.front();
}

// The database entries' exact surfaces: /database/fragments/surface_*, open, and their offsets.
struct SurfaceTable {
  Dataset<double> vertices;
  Dataset<int32_t> faces;
  std::vector<int64_t> vertexOffsets, faceOffsets;
};

// Reads the surfaces of entries [first, last) into entryAt(i), a FragmentEntry&, and checks their
// faces.
template <class EntryAt>
void readEntrySurfaces(const SurfaceTable& t, size_t first, size_t last, EntryAt&& entryAt) {
  const Array<double> vertices = t.vertices.read(rowsOf(t.vertexOffsets, first, last));
  const Array<int32_t> faces = t.faces.read(rowsOf(t.faceOffsets, first, last));
  for (size_t i = first; i < last; ++i) {
    FragmentEntry& e = entryAt(i);
    const int64_t nv = t.vertexOffsets[i + 1] - t.vertexOffsets[i];
    const int64_t nf = t.faceOffsets[i + 1] - t.faceOffsets[i];
    e.surface.vertices =
        Eigen::Map<const Points>(vertices.values.data() + 3 * (t.vertexOffsets[i] - t.vertexOffsets[first]), nv, 3);
    e.surface.faces = Eigen::Map<const Triangles>(faces.values.data() + 3 * (t.faceOffsets[i] - t.faceOffsets[first]), nf, 3);
    checkIndices(e.surface.faces, "/database/fragments/surface_faces", t.faceOffsets[i], nv, e.asset.name);
  }
}

// The descriptor matrices of /database/descriptors, open, by kind.
using DescriptorTable = std::array<Dataset<float>, kDescriptorKindCount>;

// A descriptor matrix read whole (its shape, #entries × the kind's width, checked at open).
DescriptorMatrix readDescriptors(const Dataset<float>& dataset) {
  const Array<float> m = dataset.read();
  return Eigen::Map<const DescriptorMatrix>(m.values.data(), static_cast<Eigen::Index>(m.dims[0]),
                                            static_cast<Eigen::Index>(m.dims[1]));
}

// The entries of a pack read with EntryReading::OnDemand (Pack.h): it keeps the file, the
// entries' array datasets and the descriptor matrices open (their shapes and stored sizes checked
// once, at open) and reads an entry's rows, or a kind's matrix, with the same checks as a whole
// read, each time it is asked.
class PackEntrySource final : public FragmentEntrySource {
 public:
  PackEntrySource(Handle file, std::string label, ObjectTable table, SurfaceTable surfaces,
                  DescriptorTable descriptors, std::vector<FragmentEntry> skeletons, Material reference)
      : mFile(std::move(file)), mLabel(std::move(label)), mTable(std::move(table)),
        mSurfaces(std::move(surfaces)), mDescriptors(std::move(descriptors)), mSkeletons(std::move(skeletons)),
        mReference(std::move(reference)) {}

  // Closed quietly: a host may keep a pack (or its World) in a static that outlives HDF5's own
  // exit handler, and closing then must not print HDF5's errors.
  ~PackEntrySource() override {
    hdf5::ErrorSilencer silencer;
    mDescriptors = {};
    mSurfaces = {};
    mTable = {};
    mFile = {};
  }
  PackEntrySource(const PackEntrySource&) = delete;
  PackEntrySource& operator=(const PackEntrySource&) = delete;

  Result<DescriptorMatrix> descriptors(DescriptorKind kind) const override {
    auto serial = serialised();
    hdf5::ErrorSilencer silencer;
    try {
      return readDescriptors(mDescriptors[static_cast<size_t>(kind)]);
    } catch (const hdf5::ReadFailure& failure) {
      return makeError(failure.error.code, mLabel + ": " + failure.error.message);
    } catch (const std::exception& e) {
      return makeError(ErrorCode::PackIoError, mLabel + ": " + e.what());
    }
  }

  Result<FragmentEntry> load(int64_t entry) const override {
    if (entry < 0 || entry >= entryCount()) {
      return makeError(ErrorCode::InvalidArgument, "entry " + std::to_string(entry) + " out of range");
    }
    const auto i = static_cast<size_t>(entry);
    auto serial = serialised();
    hdf5::ErrorSilencer silencer;
    try {
      FragmentEntry e = mSkeletons[i];
      readObjectArrays(mTable, i, i + 1, [&](size_t) -> ObjectAsset& { return e.asset; });
      readEntrySurfaces(mSurfaces, i, i + 1, [&](size_t) -> FragmentEntry& { return e; });
      if (Status valid = validateFragmentEntry(e, mReference); !valid) {
        return makeError(ErrorCode::PackCorrupt, mLabel + ": /database: " + valid.error().message);
      }
      return e;
    } catch (const hdf5::ReadFailure& failure) {
      return makeError(failure.error.code, mLabel + ": " + failure.error.message);
    } catch (const std::exception& e) {
      return makeError(ErrorCode::PackIoError, mLabel + ": " + e.what());
    }
  }

  int64_t tetCount(int64_t entry) const override {
    const auto i = static_cast<size_t>(entry);
    return entry < 0 || entry >= entryCount() ? 0 : mTable.tetOffsets[i + 1] - mTable.tetOffsets[i];
  }

 private:
  int64_t entryCount() const { return static_cast<int64_t>(mSkeletons.size()); }

  // Workers read entries at once. A thread-safe HDF5 (Debian's, which the project builds with)
  // serialises its calls, and its error silencer is per thread; any other build is serialised here.
  std::unique_lock<std::mutex> serialised() const {
    static const bool threadSafe = [] {
      hbool_t safe = 0;
      return H5is_library_threadsafe(&safe) >= 0 && safe > 0;
    }();
    return threadSafe ? std::unique_lock<std::mutex>() : std::unique_lock<std::mutex>(mSerial);
  }

  Handle mFile;  // closed last, after the datasets of the members below
  std::string mLabel;
  ObjectTable mTable;  // its objects moved to mSkeletons
  SurfaceTable mSurfaces;
  DescriptorTable mDescriptors;
  std::vector<FragmentEntry> mSkeletons;  // every field but the arrays
  Material mReference;
  mutable std::mutex mSerial;
};

// Reads /database. With `onDemand` (the open file's handle), the entries' arrays and the
// descriptor matrices are left in the file, and the database's entrySource reads them: it takes
// over the handle and labels its errors with `label`.
FragmentDatabase readDatabase(FileReader& r, int64_t version, Handle* onDemand, const std::string& label) {
  r.requireGroup("/database");
  FragmentDatabase db;
  db.seed = static_cast<uint64_t>(scalar(r.i64("/database/seed", {1})));
  const std::vector<Material> reference = readMaterials(r, "/database/reference_material");
  if (reference.size() != 1) {
    fail(ErrorCode::PackShapeMismatch, "'/database/reference_material' must hold exactly one material");
  }
  db.referenceMaterial = reference.front();
  ObjectTable table = readObjectTable(r, "/database/entries", reference, version);
  const hsize_t count = table.objects.size();

  r.requireGroup("/database/fragments");
  const auto shapes = r.strings("/database/fragments/base_shape", count);
  const auto cuts = r.strings("/database/fragments/cut", count);
  const auto seeds = r.i64("/database/fragments/seed", {count}).values;
  const auto fractions = r.f64("/database/fragments/base_volume_fraction", {count}).values;
  SurfaceTable surfaces;
  surfaces.vertices = r.open<double>("/database/fragments/surface_vertices", {kAny, 3});
  surfaces.vertexOffsets = readOffsets(r, "/database/fragments/surface_vertex_offsets", count,
                                       surfaces.vertices.dims()[0], "/database/fragments/surface_vertices");
  surfaces.faces = r.open<int32_t>("/database/fragments/surface_faces", {kAny, 3});
  surfaces.faceOffsets = readOffsets(r, "/database/fragments/surface_face_offsets", count, surfaces.faces.dims()[0],
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
  DescriptorTable descriptors;
  for (DescriptorKind kind : kAllDescriptorKinds) {
    const std::string path = std::string("/database/descriptors/") + descriptorKindName(kind);
    const auto width = static_cast<hsize_t>(descriptorSize(kind, d));
    descriptors[static_cast<size_t>(kind)] = r.open<float>(path, {count, width});
    // On demand, a kind is read when an index is built over it (FragmentMatcher::build).
    if (!onDemand) db.descriptors[static_cast<size_t>(kind)] = readDescriptors(descriptors[static_cast<size_t>(kind)]);
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
  // A binned error model (MatchErrors.h); optional: packs baked before its calibration have none.
  auto readModel = [&](const std::string& group, MatchErrorModel& m) {
    if (!r.exists(group)) return;
    m.distance = r.f64(group + "/distance", {kAny}).values;
    const hsize_t bins = m.distance.size();
    m.medianError = r.f64(group + "/median_error", {bins}).values;
    m.p90Error = r.f64(group + "/p90_error", {bins}).values;
    m.samples = r.i64(group + "/samples", {1}).values[0];
    if (Status st = validateMatchErrorModel(m); !st) fail(ErrorCode::PackCorrupt, group + ": " + st.error().message);
  };
  for (DescriptorKind kind : kAllDescriptorKinds)
    readModel(std::string("/database/match_errors/") + descriptorKindName(kind), db.matchErrors[static_cast<size_t>(kind)]);
  if (r.exists("/database/frequency_errors")) {  // packs before it have none (brittle calibrate-errors adds it)
    readModel("/database/frequency_errors/ritz", db.frequencyErrors.ritz);
    readModel("/database/frequency_errors/checked", db.frequencyErrors.checked);
    readModel("/database/frequency_errors/checked_p2", db.frequencyErrors.checkedP2);
    const int64_t degree = r.i64("/database/frequency_errors/degree", {1}).values[0];
    if (degree < 3 || degree > kMaxMomentOrder / 2) fail(ErrorCode::PackCorrupt, "/database/frequency_errors/degree: " + std::to_string(degree));
    db.frequencyErrors.degree = static_cast<int>(degree);
  }

  db.entries.resize(count);
  for (size_t i = 0; i < count; ++i) {
    FragmentEntry& e = db.entries[i];
    e.asset = std::move(table.objects[i]);
    e.baseShape = shapes[i];
    e.cut = cuts[i];
    e.seed = static_cast<uint64_t>(seeds[i]);
    e.baseVolumeFraction = fractions[i];
  }
  if (onDemand) {
    db.entrySource = std::make_shared<PackEntrySource>(std::move(*onDemand), label, std::move(table),
                                                       std::move(surfaces), std::move(descriptors), db.entries,
                                                       db.referenceMaterial);
  } else {
    const auto entryAt = [&](size_t i) -> FragmentEntry& { return db.entries[i]; };
    readObjectArrays(table, 0, count, [&](size_t i) -> ObjectAsset& { return db.entries[i].asset; });
    readEntrySurfaces(surfaces, 0, count, entryAt);
  }
  if (Status valid = validateFragmentDatabase(db); !valid) fail(ErrorCode::PackCorrupt, "/database: " + valid.error().message);
  return db;
}

}  // namespace

Result<Pack> readPack(const fs::path& path, EntryReading entries) {
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
    if (version >= 2 && reader.exists("/database")) {
      pack.database = readDatabase(reader, version, entries == EntryReading::OnDemand ? &file : nullptr, label);
    }
    return pack;
  } catch (const hdf5::ReadFailure& failure) {
    return makeError(failure.error.code, label + ": " + failure.error.message);
  } catch (const std::exception& e) {
    // Only allocation can throw here, and the sizes were bounded first; still never throw out.
    return makeError(ErrorCode::PackIoError, label + ": " + e.what());
  }
}

}  // namespace brittle
