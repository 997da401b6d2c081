// PackWriter.cpp — writes a Pack as an HDF5 file (database/PACK_SCHEMA.md): the schema and its
// validation, on top of the checked HDF5 writes of Hdf5Writer.h.
//
// The whole pack is validated before a byte is written, then written to a temporary file in the
// target's directory, flushed to disk and renamed over the target (core/AtomicFile.h). A reader
// therefore sees either the old pack or the new one, never a half-written file.
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "Hdf5Writer.h"
#include "PackSchema.h"
#include "brittle/core/AtomicFile.h"
#include "brittle/database/Pack.h"

namespace brittle {
namespace {

namespace fs = std::filesystem;
using hdf5::failHdf5;
using hdf5::failIo;
using hdf5::FileWriter;
using hdf5::Handle;

// The chunk size of the database entries' arrays (writeDatabase).
constexpr hsize_t kEntryChunkBytes = 32 * 1024;

// ---------------------------------------------------------------------------------------------
// Validation: everything the reader would reject is rejected here, so a bake fails at write time
// with InvalidArgument instead of producing a pack that cannot be loaded.

Status checkFinite(const std::string& where, const double* values, Eigen::Index count) {
  for (Eigen::Index i = 0; i < count; ++i) {
    if (!std::isfinite(values[i])) {
      return invalidArgument(where + " holds a non-finite value at index " + std::to_string(i));
    }
  }
  return Ok{};
}

Status checkString(const std::string& where, const std::string& value) {
  // Fixed-length HDF5 strings are NUL-padded, so an embedded NUL would be cut off on reading.
  if (value.find('\0') != std::string::npos) return invalidArgument(where + " contains a NUL character");
  return Ok{};
}

template <typename IndexMatrix>
Status checkIndexRange(const std::string& where, const IndexMatrix& indices, Eigen::Index nodeCount) {
  for (Eigen::Index r = 0; r < indices.rows(); ++r) {
    for (Eigen::Index c = 0; c < indices.cols(); ++c) {
      const int32_t v = indices(r, c);
      if (v < 0 || v >= nodeCount) {
        return invalidArgument(where + "(" + std::to_string(r) + ", " + std::to_string(c) + ") = " + std::to_string(v) +
                       " is not a node index in [0, " + std::to_string(nodeCount) + ")");
      }
    }
  }
  return Ok{};
}

Status validateObject(const ObjectAsset& o, const std::string& label, const std::set<std::string>& materialNames) {
  if (o.name.empty()) return invalidArgument(label + " has an empty name");
  if (materialNames.count(o.materialName) == 0) {
    return invalidArgument(label + " names material '" + o.materialName + "', which is not in the pack");
  }
  const struct {
    const char* field;
    const std::string& value;
  } strings[] = {{"name", o.name},
                 {"materialName", o.materialName},
                 {"bake.sourceMesh", o.bake.sourceMesh},
                 {"bake.factorization", o.bake.factorization},
                 {"bake.generator", o.bake.generator}};
  for (const auto& s : strings) {
    if (Status st = checkString(label + " " + s.field, s.value); !st) return st;
  }

  const Eigen::Index n = o.tetMesh.nodes.rows();
  const Eigen::Index t = o.tetMesh.tets.rows();
  if (Status st = checkIndexRange(label + " tetMesh.tets", o.tetMesh.tets, n); !st) return st;
  if (Status st = checkIndexRange(label + " surfaceFaces", o.surfaceFaces, n); !st) return st;

  const ModalBasis& m = o.modal;
  const Eigen::Index r = m.eigenvaluesRad2PerS2.size();
  if (m.frequenciesHz.size() != r || m.residuals.size() != r) {
    return invalidArgument(label + ": modal has " + std::to_string(r) + " eigenvalues but " +
                   std::to_string(m.frequenciesHz.size()) + " frequencies and " + std::to_string(m.residuals.size()) +
                   " residuals");
  }
  if (o.elementOrder != ElementOrder::P1 && o.elementOrder != ElementOrder::P2) {
    return invalidArgument(label + ": elementOrder is neither P1 nor P2");
  }
  const Eigen::Index fem = femNodeCount(o.tetMesh, o.elementOrder);
  const Eigen::Index points = stressPointsPerElement(o.elementOrder);
  if (m.modes.rows() != 3 * fem || m.modes.cols() != r) {
    return invalidArgument(label + ": modal.modes is " + std::to_string(m.modes.rows()) + " by " +
                   std::to_string(m.modes.cols()) + ", expected 3N by r = " + std::to_string(3 * fem) + " by " +
                   std::to_string(r) + " (" + elementOrderName(o.elementOrder) + ")");
  }
  if (!isContactSpreadFraction(o.contactSpreadFraction)) {
    return invalidArgument(label + ": contactSpreadFraction " + std::to_string(o.contactSpreadFraction) + " is outside [0, 1)");
  }
  if (o.eliminationOrder.size() > 0 && !isPermutation(o.eliminationOrder, 3 * fem)) {
    return invalidArgument(label + ": eliminationOrder is not a permutation of its " + std::to_string(3 * fem) +
                           " degrees of freedom");
  }
  if (o.stressModes.rows() != 6 * points * t || o.stressModes.cols() != r) {
    return invalidArgument(label + ": stressModes is " + std::to_string(o.stressModes.rows()) + " by " +
                   std::to_string(o.stressModes.cols()) + ", expected 6PT by r = " + std::to_string(6 * points * t) +
                   " by " + std::to_string(r));
  }

  const MassProperties& mp = o.massProperties;
  const MeshQuality& q = o.quality;
  const BakeRecord& b = o.bake;
  const struct {
    const char* field;
    const double* values;
    Eigen::Index count;
  } arrays[] = {
      {"tetMesh.nodes", o.tetMesh.nodes.data(), o.tetMesh.nodes.size()},
      {"modal.eigenvaluesRad2PerS2", m.eigenvaluesRad2PerS2.data(), r},
      {"modal.frequenciesHz", m.frequenciesHz.data(), r},
      {"modal.residuals", m.residuals.data(), r},
      {"modal.orthonormalityError", &m.orthonormalityError, 1},
      {"modal.modes", m.modes.data(), m.modes.size()},
      {"stressModes", o.stressModes.data(), o.stressModes.size()},
      {"massProperties.volumeM3", &mp.volumeM3, 1},
      {"massProperties.massKg", &mp.massKg, 1},
      {"massProperties.centerOfMassM", mp.centerOfMassM.data(), 3},
      {"massProperties.inertiaKgM2", mp.inertiaKgM2.data(), 9},
      {"massProperties.secondMomentM5", mp.secondMomentM5.data(), 9},
      {"quality.minDihedralDeg", &q.minDihedralDeg, 1},
      {"quality.maxDihedralDeg", &q.maxDihedralDeg, 1},
      {"quality.maxRadiusEdgeRatio", &q.maxRadiusEdgeRatio, 1},
      {"quality.meanRadiusEdgeRatio", &q.meanRadiusEdgeRatio, 1},
      {"quality.minTetVolumeM3", &q.minTetVolumeM3, 1},
      {"bake.cellSizeM", &b.cellSizeM, 1},
      {"bake.thinStretch", &b.thinStretch, 1},
      {"bake.repairVolumeChange", &b.repairVolumeChange, 1},
      {"bake.shift", &b.shift, 1},
      {"bake.meshingS", &b.meshingS, 1},
      {"bake.assemblyS", &b.assemblyS, 1},
      {"bake.modalS", &b.modalS, 1},
      {"bake.stressModesS", &b.stressModesS, 1},
      {"bake.totalS", &b.totalS, 1},
  };
  for (const auto& a : arrays) {
    if (Status st = checkFinite(label + " " + a.field, a.values, a.count); !st) return st;
  }
  if (!isThinStretch(b.thinStretch)) {
    return invalidArgument(label + ": bake.thinStretch is " + std::to_string(b.thinStretch) + ", outside [1, 16]");
  }
  return Ok{};
}

Status validatePack(const Pack& pack) {
  std::set<std::string> materialNames;
  for (size_t i = 0; i < pack.materials.size(); ++i) {
    const Material& m = pack.materials[i];
    const std::string label = "material " + std::to_string(i) + " ('" + m.name + "')";
    if (Status st = validateMaterial(m); !st) return invalidArgument(st.error().message);
    if (Status st = checkString(label + " name", m.name); !st) return st;
    if (Status st = checkString(label + " source", m.source); !st) return st;
    if (!materialNames.insert(m.name).second) return invalidArgument("two materials are named '" + m.name + "'");
  }
  std::set<std::string> objectNames;
  for (size_t i = 0; i < pack.objects.size(); ++i) {
    const ObjectAsset& o = pack.objects[i];
    if (Status st = validateObject(o, "object " + std::to_string(i) + " ('" + o.name + "')", materialNames); !st) {
      return st;
    }
    if (!objectNames.insert(o.name).second) return invalidArgument("two objects are named '" + o.name + "'");
  }
  if (pack.database.entrySource) {
    return invalidArgument("database: its entries were read on demand (EntryReading::OnDemand) and are not all in "
                           "memory; read the pack whole to write it");
  }
  if (!pack.database.empty()) {
    if (Status st = validateFragmentDatabase(pack.database); !st) return invalidArgument("database: " + st.error().message);
    const std::set<std::string> reference{pack.database.referenceMaterial.name};
    for (const FragmentEntry& e : pack.database.entries) {
      if (Status st = validateObject(e.asset, "database entry '" + e.asset.name + "'", reference); !st) return st;
      for (const std::string* text : {&e.baseShape, &e.cut}) {
        if (Status st = checkString("database entry '" + e.asset.name + "'", *text); !st) return st;
      }
    }
  }
  return Ok{};
}

// ---------------------------------------------------------------------------------------------
// The schema: groups and datasets.

// The objects to write, in order. Pointers, so that database entries (which hold an ObjectAsset
// each) are written in place without copying their meshes and modes.
using ObjectList = std::vector<const ObjectAsset*>;

// One value per object, in object order: an [O] dataset.
template <typename T, typename Get>
std::vector<T> gather(const ObjectList& objects, Get get) {
  std::vector<T> out;
  out.reserve(objects.size());
  for (const ObjectAsset* o : objects) out.push_back(static_cast<T>(get(*o)));
  return out;
}

// Ragged arrays: the row offsets of each object's block, O + 1 entries starting at 0.
template <typename Rows>
std::vector<int64_t> offsetsOf(const ObjectList& objects, Rows rows) {
  std::vector<int64_t> offsets(1, 0);
  for (const ObjectAsset* o : objects) offsets.push_back(offsets.back() + static_cast<int64_t>(rows(*o)));
  return offsets;
}

// Concatenates row-major blocks (Eigen row-major storage is already the file layout).
template <typename T, typename Block>
std::vector<T> concat(const ObjectList& objects, Block block) {
  std::vector<T> out;
  for (const ObjectAsset* o : objects) {
    const auto& b = block(*o);
    out.insert(out.end(), b.data(), b.data() + b.size());
  }
  return out;
}

// Eigen's Matrix3d is column-major; the file stores [o][row][col].
template <typename Get>
std::vector<double> gatherMatrix3(const ObjectList& objects, Get get) {
  std::vector<double> out;
  out.reserve(objects.size() * 9);
  for (const ObjectAsset* o : objects) {
    const Eigen::Matrix3d& m = get(*o);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out.push_back(m(r, c));
  }
  return out;
}

void writeMaterials(FileWriter& w, const std::string& prefix, const std::vector<Material>& materials) {
  Handle group = w.createGroup(prefix);
  const hsize_t m = materials.size();
  auto column = [&](auto get) {
    std::vector<double> out;
    for (const auto& mat : materials) out.push_back(get(mat));
    return out;
  };
  std::vector<std::string> names, sources;
  for (const auto& mat : materials) {
    names.push_back(mat.name);
    sources.push_back(mat.source);
  }
  w.strings(prefix + "/name", names);
  w.f64(prefix + "/youngs_modulus_pa", column([](const Material& x) { return x.youngsModulusPa; }), {m}, "Pa");
  w.f64(prefix + "/poisson_ratio", column([](const Material& x) { return x.poissonRatio; }), {m}, "1");
  w.f64(prefix + "/density_kg_per_m3", column([](const Material& x) { return x.densityKgPerM3; }), {m}, "kg/m^3");
  w.f64(prefix + "/tensile_strength_pa", column([](const Material& x) { return x.tensileStrengthPa; }), {m}, "Pa");
  w.f64(prefix + "/fracture_energy_j_per_m2", column([](const Material& x) { return x.fractureEnergyJPerM2; }), {m},
        "J/m^2");
  w.f64(prefix + "/rayleigh_alpha_per_s", column([](const Material& x) { return x.rayleighAlphaPerS; }), {m}, "1/s");
  w.f64(prefix + "/rayleigh_beta_s", column([](const Material& x) { return x.rayleighBetaS; }), {m}, "s");
  w.f64(prefix + "/restitution", column([](const Material& x) { return x.restitution; }), {m}, "1");
  w.strings(prefix + "/source", sources);
}

void writeObjects(FileWriter& w, const std::string& prefix, const ObjectList& objects) {
  using O = ObjectAsset;
  Handle group = w.createGroup(prefix);
  const hsize_t count = objects.size();

  w.strings(prefix + "/name", gather<std::string>(objects, [](const O& o) { return o.name; }));
  w.strings(prefix + "/material_name", gather<std::string>(objects, [](const O& o) { return o.materialName; }));

  w.i32(prefix + "/element_order",
        gather<int32_t>(objects, [](const O& o) { return static_cast<int32_t>(o.elementOrder); }), {count});

  // Meshes.
  const auto nodeOffsets = offsetsOf(objects, [](const O& o) { return o.tetMesh.nodes.rows(); });
  const auto tetOffsets = offsetsOf(objects, [](const O& o) { return o.tetMesh.tets.rows(); });
  const auto faceOffsets = offsetsOf(objects, [](const O& o) { return o.surfaceFaces.rows(); });
  w.i64(prefix + "/node_offsets", nodeOffsets, {count + 1});
  w.f64(prefix + "/nodes", concat<double>(objects, [](const O& o) -> const Points& { return o.tetMesh.nodes; }),
        {static_cast<hsize_t>(nodeOffsets.back()), 3}, "m");
  w.i64(prefix + "/tet_offsets", tetOffsets, {count + 1});
  w.i32(prefix + "/tets", concat<int32_t>(objects, [](const O& o) -> const Tetrahedra& { return o.tetMesh.tets; }),
        {static_cast<hsize_t>(tetOffsets.back()), 4});
  w.i64(prefix + "/face_offsets", faceOffsets, {count + 1});
  w.i32(prefix + "/surface_faces",
        concat<int32_t>(objects, [](const O& o) -> const Triangles& { return o.surfaceFaces; }),
        {static_cast<hsize_t>(faceOffsets.back()), 3});

  // Mass properties.
  w.f64(prefix + "/mass_kg", gather<double>(objects, [](const O& o) { return o.massProperties.massKg; }), {count}, "kg");
  w.f64(prefix + "/volume_m3", gather<double>(objects, [](const O& o) { return o.massProperties.volumeM3; }), {count},
        "m^3");
  std::vector<double> com;
  for (const ObjectAsset* o : objects)
    com.insert(com.end(), o->massProperties.centerOfMassM.data(), o->massProperties.centerOfMassM.data() + 3);
  w.f64(prefix + "/center_of_mass_m", com, {count, 3}, "m");
  w.f64(prefix + "/inertia_kg_m2",
        gatherMatrix3(objects, [](const O& o) -> const Eigen::Matrix3d& { return o.massProperties.inertiaKgM2; }),
        {count, 3, 3}, "kg*m^2");
  w.f64(prefix + "/second_moment_m5",
        gatherMatrix3(objects, [](const O& o) -> const Eigen::Matrix3d& { return o.massProperties.secondMomentM5; }),
        {count, 3, 3}, "m^5");

  // Modal data. modes and stress_modes hold one row-major (3N by r) or (6PT by r) block per
  // object; r differs between objects, so they are flat and carry their own offsets.
  const auto modeOffsets = offsetsOf(objects, [](const O& o) { return o.modal.eigenvaluesRad2PerS2.size(); });
  const auto modesValueOffsets = offsetsOf(objects, [](const O& o) { return o.modal.modes.size(); });
  const auto stressValueOffsets = offsetsOf(objects, [](const O& o) { return o.stressModes.size(); });
  const hsize_t modeTotal = static_cast<hsize_t>(modeOffsets.back());
  w.i64(prefix + "/mode_offsets", modeOffsets, {count + 1});
  w.f64(prefix + "/eigenvalues_rad2_per_s2",
        concat<double>(objects, [](const O& o) -> const Eigen::VectorXd& { return o.modal.eigenvaluesRad2PerS2; }),
        {modeTotal}, "rad^2/s^2");
  w.f64(prefix + "/frequencies_hz",
        concat<double>(objects, [](const O& o) -> const Eigen::VectorXd& { return o.modal.frequenciesHz; }),
        {modeTotal}, "Hz");
  w.f64(prefix + "/residuals",
        concat<double>(objects, [](const O& o) -> const Eigen::VectorXd& { return o.modal.residuals; }), {modeTotal},
        "1");
  w.f64(prefix + "/orthonormality_error",
        gather<double>(objects, [](const O& o) { return o.modal.orthonormalityError; }), {count}, "1");
  w.i64(prefix + "/modes_value_offsets", modesValueOffsets, {count + 1});
  w.f64(prefix + "/modes", concat<double>(objects, [](const O& o) -> const MatrixXdRow& { return o.modal.modes; }),
        {static_cast<hsize_t>(modesValueOffsets.back())}, "kg^-1/2");
  w.i64(prefix + "/stress_modes_value_offsets", stressValueOffsets, {count + 1});
  w.f64(prefix + "/stress_modes",
        concat<double>(objects, [](const O& o) -> const MatrixXdRow& { return o.stressModes; }),
        {static_cast<hsize_t>(stressValueOffsets.back())}, "Pa/(kg^1/2*m)");
  // The optional elimination orders (ObjectAsset::eliminationOrder), written when an object has
  // one; an object without one has an empty block.
  if (std::any_of(objects.begin(), objects.end(), [](const O* o) { return o->eliminationOrder.size() > 0; })) {
    const auto orderOffsets = offsetsOf(objects, [](const O& o) { return o.eliminationOrder.size(); });
    w.i64(prefix + "/elimination_order_offsets", orderOffsets, {count + 1});
    w.i32(prefix + "/elimination_order",
          concat<int32_t>(objects, [](const O& o) -> const Eigen::VectorXi& { return o.eliminationOrder; }),
          {static_cast<hsize_t>(orderOffsets.back())});
  }

  // Mesh quality.
  {
    Handle quality = w.createGroup(prefix + "/quality");
    w.i64(prefix + "/quality/node_count", gather<int64_t>(objects, [](const O& o) { return o.quality.nodeCount; }),
          {count});
    w.i64(prefix + "/quality/tet_count", gather<int64_t>(objects, [](const O& o) { return o.quality.tetCount; }),
          {count});
    w.i64(prefix + "/quality/surface_face_count",
          gather<int64_t>(objects, [](const O& o) { return o.quality.surfaceFaceCount; }), {count});
    w.f64(prefix + "/quality/min_dihedral_deg",
          gather<double>(objects, [](const O& o) { return o.quality.minDihedralDeg; }), {count}, "deg");
    w.f64(prefix + "/quality/max_dihedral_deg",
          gather<double>(objects, [](const O& o) { return o.quality.maxDihedralDeg; }), {count}, "deg");
    w.f64(prefix + "/quality/max_radius_edge_ratio",
          gather<double>(objects, [](const O& o) { return o.quality.maxRadiusEdgeRatio; }), {count}, "1");
    w.f64(prefix + "/quality/mean_radius_edge_ratio",
          gather<double>(objects, [](const O& o) { return o.quality.meanRadiusEdgeRatio; }), {count}, "1");
    w.f64(prefix + "/quality/min_tet_volume_m3",
          gather<double>(objects, [](const O& o) { return o.quality.minTetVolumeM3; }), {count}, "m^3");
  }

  w.f64(prefix + "/contact_spread_fraction", gather<double>(objects, [](const O& o) { return o.contactSpreadFraction; }),
        {count}, "1");

  // Bake record.
  {
    Handle bake = w.createGroup(prefix + "/bake");
    w.strings(prefix + "/bake/source_mesh", gather<std::string>(objects, [](const O& o) { return o.bake.sourceMesh; }));
    w.i64(prefix + "/bake/target_tets", gather<int64_t>(objects, [](const O& o) { return o.bake.targetTets; }), {count});
    w.f64(prefix + "/bake/cell_size_m", gather<double>(objects, [](const O& o) { return o.bake.cellSizeM; }), {count},
          "m");
    w.f64(prefix + "/bake/thin_stretch", gather<double>(objects, [](const O& o) { return o.bake.thinStretch; }), {count},
          "1");
    w.i64(prefix + "/bake/requested_modes", gather<int64_t>(objects, [](const O& o) { return o.bake.requestedModes; }),
          {count});
    w.u8(prefix + "/bake/lumped_mass", gather<uint8_t>(objects, [](const O& o) { return o.bake.lumpedMass ? 1 : 0; }));
    w.u8(prefix + "/bake/repaired", gather<uint8_t>(objects, [](const O& o) { return o.bake.repaired ? 1 : 0; }));
    w.f64(prefix + "/bake/repair_volume_change",
          gather<double>(objects, [](const O& o) { return o.bake.repairVolumeChange; }), {count}, "1");
    w.strings(prefix + "/bake/factorization",
              gather<std::string>(objects, [](const O& o) { return o.bake.factorization; }));
    w.f64(prefix + "/bake/shift_rad2_per_s2", gather<double>(objects, [](const O& o) { return o.bake.shift; }), {count},
          "rad^2/s^2");
    w.i64(prefix + "/bake/seed", gather<int64_t>(objects, [](const O& o) { return o.bake.seed; }), {count});
    w.f64(prefix + "/bake/meshing_s", gather<double>(objects, [](const O& o) { return o.bake.meshingS; }), {count}, "s");
    w.f64(prefix + "/bake/assembly_s", gather<double>(objects, [](const O& o) { return o.bake.assemblyS; }), {count},
          "s");
    w.f64(prefix + "/bake/modal_s", gather<double>(objects, [](const O& o) { return o.bake.modalS; }), {count}, "s");
    w.f64(prefix + "/bake/stress_modes_s", gather<double>(objects, [](const O& o) { return o.bake.stressModesS; }),
          {count}, "s");
    w.f64(prefix + "/bake/total_s", gather<double>(objects, [](const O& o) { return o.bake.totalS; }), {count}, "s");
    w.strings(prefix + "/bake/generator", gather<std::string>(objects, [](const O& o) { return o.bake.generator; }));
  }
}

// Schema v2: the fragment database (PACK_SCHEMA.md, "/database").
void writeDatabase(FileWriter& w, const FragmentDatabase& db) {
  Handle group = w.createGroup("/database");
  w.i64("/database/seed", {static_cast<int64_t>(db.seed)}, {1});
  writeMaterials(w, "/database/reference_material", {db.referenceMaterial});
  ObjectList assets;
  for (const FragmentEntry& e : db.entries) assets.push_back(&e.asset);
  // A World reads an entry's rows alone when it is matched (EntryReading::OnDemand), so the
  // entries' arrays and surfaces come in chunks near one small entry's size: a read inflates
  // little more than the entry itself. The descriptors after them are read whole.
  w.setChunkBytes(kEntryChunkBytes);
  writeObjects(w, "/database/entries", assets);

  const hsize_t count = db.entries.size();
  {
    Handle fragments = w.createGroup("/database/fragments");
    std::vector<std::string> shapes, cuts;
    std::vector<int64_t> seeds, vertexOffsets{0}, faceOffsets{0};
    std::vector<double> fractions, vertices;
    std::vector<int32_t> faces;
    for (const FragmentEntry& e : db.entries) {
      shapes.push_back(e.baseShape);
      cuts.push_back(e.cut);
      seeds.push_back(static_cast<int64_t>(e.seed));
      fractions.push_back(e.baseVolumeFraction);
      vertices.insert(vertices.end(), e.surface.vertices.data(), e.surface.vertices.data() + e.surface.vertices.size());
      faces.insert(faces.end(), e.surface.faces.data(), e.surface.faces.data() + e.surface.faces.size());
      vertexOffsets.push_back(vertexOffsets.back() + e.surface.vertices.rows());
      faceOffsets.push_back(faceOffsets.back() + e.surface.faces.rows());
    }
    w.strings("/database/fragments/base_shape", shapes);
    w.strings("/database/fragments/cut", cuts);
    w.i64("/database/fragments/seed", seeds, {count});
    w.f64("/database/fragments/base_volume_fraction", fractions, {count}, "1");
    w.i64("/database/fragments/surface_vertex_offsets", vertexOffsets, {count + 1});
    w.f64("/database/fragments/surface_vertices", vertices, {static_cast<hsize_t>(vertexOffsets.back()), 3}, "1");
    w.i64("/database/fragments/surface_face_offsets", faceOffsets, {count + 1});
    w.i32("/database/fragments/surface_faces", faces, {static_cast<hsize_t>(faceOffsets.back()), 3});
  }
  w.setChunkBytes(hdf5::kDefaultChunkBytes);
  {
    const ShapeDescriptorSettings& d = db.descriptorSettings;
    Handle settings = w.createGroup("/database/descriptor_settings");
    const CanonicalFrameSettings& f = d.frame;
    w.f64("/database/descriptor_settings/frame_tolerances",
          {f.eigenGapTolerance, f.skewnessTolerance, f.shapeTolerance, f.tieTolerance, f.duplicateTolerance}, {5}, "1");
    w.i64("/database/descriptor_settings/frame_max_candidates", {f.maxCandidates}, {1});
    w.i64("/database/descriptor_settings/moment_max_order", {d.moment.maxOrder}, {1});
    w.f64("/database/descriptor_settings/moment_order_weights", d.moment.orderWeights, {d.moment.orderWeights.size()},
          "1");
    w.i64("/database/descriptor_settings/voxel_resolution", {d.voxel.resolution}, {1});
    w.f64("/database/descriptor_settings/voxel_half_extent", {d.voxel.halfExtent}, {1}, "1");
    w.i64("/database/descriptor_settings/voxel_improved_resolution", {d.voxelImproved.resolution}, {1});
    w.f64("/database/descriptor_settings/voxel_improved_half_extent", {d.voxelImproved.halfExtent}, {1}, "1");
    w.f64("/database/descriptor_settings/voxel_improved_clamp_voxels", {d.voxelImproved.clampVoxels}, {1}, "1");
  }
  {
    Handle descriptors = w.createGroup("/database/descriptors");
    for (DescriptorKind kind : kAllDescriptorKinds) {
      const DescriptorMatrix& m = db.descriptorsOf(kind);
      w.f32(std::string("/database/descriptors/") + descriptorKindName(kind), m.data(),
            {static_cast<hsize_t>(m.rows()), static_cast<hsize_t>(m.cols())});
    }
  }
  {
    Handle index = w.createGroup("/database/index");
    std::vector<std::string> kinds, backends;
    std::vector<int64_t> trees, checks, seeds;
    std::vector<double> precision;
    for (DescriptorKind kind : kAllDescriptorKinds) {
      const DescriptorIndexSettings& s = db.indexSettings[static_cast<size_t>(kind)];
      kinds.push_back(descriptorKindName(kind));
      backends.push_back(descriptorIndexKindName(s.kind));
      trees.push_back(s.trees);
      checks.push_back(s.checks);
      seeds.push_back(static_cast<int64_t>(s.seed));
      precision.push_back(s.targetPrecision);
    }
    const hsize_t k = kinds.size();
    w.strings("/database/index/descriptor", kinds);
    w.strings("/database/index/backend", backends);
    w.i64("/database/index/trees", trees, {k});
    w.i64("/database/index/checks", checks, {k});
    w.f64("/database/index/target_precision", precision, {k}, "1");
    w.i64("/database/index/seed", seeds, {k});
  }
  // A binned error model (MatchErrors.h) in its own group; an empty one is not written.
  auto writeModel = [&](const MatchErrorModel& m, const std::string& path) {
    if (m.empty()) return;
    Handle modelGroup = w.createGroup(path);
    const hsize_t bins = m.distance.size();
    w.f64(path + "/distance", m.distance, {bins}, "1");
    w.f64(path + "/median_error", m.medianError, {bins}, "1");
    w.f64(path + "/p90_error", m.p90Error, {bins}, "1");
    w.i64(path + "/samples", {m.samples}, {1});
  };
  {
    Handle errors = w.createGroup("/database/match_errors");
    for (DescriptorKind kind : kAllDescriptorKinds)
      writeModel(db.matchErrors[static_cast<size_t>(kind)], std::string("/database/match_errors/") + descriptorKindName(kind));
  }
  if (!db.frequencyErrors.empty()) {
    Handle errors = w.createGroup("/database/frequency_errors");
    writeModel(db.frequencyErrors.ritz, "/database/frequency_errors/ritz");
    writeModel(db.frequencyErrors.checked, "/database/frequency_errors/checked");
    writeModel(db.frequencyErrors.checkedP2, "/database/frequency_errors/checked_p2");
    w.i64("/database/frequency_errors/degree", {db.frequencyErrors.degree}, {1});
  }
}

void writeFile(const Pack& pack, const fs::path& file) {
  // The 1.10 file format indexes a single-chunk or fixed-size dataset without a B-tree, which
  // cuts the overhead of each of the ~56 datasets from about 2.6 KiB to about 0.5 KiB. Pinning both bounds
  // to 1.10 keeps packs readable by HDF5 1.10 even when written by a newer library.
  Handle fapl = hdf5::propertyHandle(H5Pcreate(H5P_FILE_ACCESS));
  if (!fapl.valid() || H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V110, H5F_LIBVER_V110) < 0) {
    failHdf5("cannot set up file access properties");
  }
  // No modification times in object headers: the same pack then always gives the same bytes,
  // so bakes can be compared by hash.
  Handle fcpl = hdf5::propertyHandle(H5Pcreate(H5P_FILE_CREATE));
  if (!fcpl.valid() || H5Pset_obj_track_times(fcpl.get(), false) < 0) {
    failHdf5("cannot set up file creation properties");
  }
  Handle h5 = hdf5::fileHandle(H5Fcreate(file.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get()));
  if (!h5.valid()) failHdf5("cannot create '" + file.string() + "'");
  FileWriter w(h5.get());
  {
    Handle root = hdf5::groupHandle(H5Gopen2(h5.get(), "/", H5P_DEFAULT));
    if (!root.valid()) failHdf5("cannot open the root group");
    w.stringAttribute(root.get(), "/", "format", kPackFormatName);
    w.intAttribute(root.get(), "/", "version", kPackVersion);
    for (const auto& unit : packschema::kUnitAttributes) w.stringAttribute(root.get(), "/", unit.name, unit.value);
    w.stringAttribute(root.get(), "/", "voigt_order", packschema::kVoigtOrder);
    w.stringAttribute(root.get(), "/", "generator", std::string("brittle ") + BRITTLE_VERSION);
  }
  writeMaterials(w, "/materials", pack.materials);
  ObjectList objects;
  for (const ObjectAsset& o : pack.objects) objects.push_back(&o);
  writeObjects(w, "/objects", objects);
  if (!pack.database.empty()) writeDatabase(w, pack.database);
  // Closing flushes HDF5's metadata cache; a failure here means the file is incomplete.
  if (!h5.close()) failHdf5("cannot close (flush) '" + file.string() + "'");
}

}  // namespace

Status writePack(const Pack& pack, const fs::path& path) {
  if (Status valid = validatePack(pack); !valid) {
    return makeError(ErrorCode::InvalidArgument, "cannot write pack '" + path.string() + "': " + valid.error().message);
  }
  if (!path.has_filename()) {
    return makeError(ErrorCode::PackIoError, "cannot write pack '" + path.string() + "': not a file name");
  }
  hdf5::ErrorSilencer silencer;
  Status written = writeAtomically(path, [&](const fs::path& temporary) -> Status {
    try {
      writeFile(pack, temporary);
    } catch (const hdf5::WriteFailure& failure) {
      return failure.error;
    } catch (const std::exception& e) {
      return makeError(ErrorCode::PackIoError, e.what());
    }
    return Ok{};
  });
  if (!written) {
    return makeError(written.error().code, "cannot write pack '" + path.string() + "': " + written.error().message);
  }
  return Ok{};
}

}  // namespace brittle
