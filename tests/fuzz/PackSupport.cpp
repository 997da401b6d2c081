#include "PackSupport.h"

#include <hdf5.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

#include "FuzzSupport.h"

namespace brittle::fuzz {
namespace {

Material makeMaterial(const std::string& name, double youngsPa, double nu) {
  Material m;
  m.name = name;
  m.youngsModulusPa = youngsPa;
  m.poissonRatio = nu;
  m.densityKgPerM3 = 2500.0;
  m.tensileStrengthPa = 4.5e7;
  m.fractureEnergyJPerM2 = 7.6;
  m.rayleighAlphaPerS = 0.0;
  m.rayleighBetaS = 1.6e-7;
  m.restitution = 0.5;
  m.source = "fuzz seed";
  return m;
}

// A positively oriented unit right tetrahedron, or two of them sharing a face (five nodes).
TetMesh makeTets(bool two) {
  TetMesh mesh;
  mesh.nodes.resize(two ? 5 : 4, 3);
  mesh.nodes.topRows(4) << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  if (two) mesh.nodes.row(4) << 1, 1, 1;
  mesh.tets.resize(two ? 2 : 1, 4);
  mesh.tets.row(0) << 0, 1, 2, 3;
  if (two) mesh.tets.row(1) << 1, 2, 3, 4;
  return mesh;
}

ObjectAsset makeObject(const std::string& name, const std::string& material, bool two, int modeCount) {
  ObjectAsset o;
  o.name = name;
  o.materialName = material;
  o.tetMesh = makeTets(two);
  o.surfaceFaces.resize(4, 3);
  o.surfaceFaces << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  const auto n = o.tetMesh.nodes.rows(), t = o.tetMesh.tets.rows();
  o.quality = {n, t, o.surfaceFaces.rows(), 35.26, 90.0, 1.2, 1.1, 1.0 / 6.0};
  o.massProperties.volumeM3 = static_cast<double>(t) / 6.0;
  o.massProperties.massKg = 2500.0 * o.massProperties.volumeM3;
  o.massProperties.centerOfMassM = Eigen::Vector3d::Constant(0.25);
  o.massProperties.inertiaKgM2 = Eigen::Matrix3d::Identity();
  o.massProperties.secondMomentM5 = Eigen::Matrix3d::Identity() * 1e-3;
  ModalBasis& m = o.modal;
  m.eigenvaluesRad2PerS2.resize(modeCount);
  m.frequenciesHz.resize(modeCount);
  m.residuals.resize(modeCount);
  for (int k = 0; k < modeCount; ++k) {
    m.eigenvaluesRad2PerS2(k) = 1e6 * (k + 1);
    m.frequenciesHz(k) = std::sqrt(m.eigenvaluesRad2PerS2(k)) / (2.0 * 3.141592653589793);
    m.residuals(k) = 1e-12;
  }
  m.orthonormalityError = 1e-14;
  m.modes = MatrixXdRow::Constant(3 * n, modeCount, 0.125);
  o.stressModes = MatrixXdRow::Constant(6 * t, modeCount, -2.5e6);
  BakeRecord& b = o.bake;
  b.sourceMesh = name + ".off";
  b.targetTets = 1000;
  b.cellSizeM = 0.1;
  b.requestedModes = modeCount;
  b.factorization = "cholmod";
  b.shift = -1e3;
  b.seed = 1;
  b.generator = "brittle fuzz seed";
  return o;
}

}  // namespace

Pack makeSeedPack() {
  Pack pack;
  pack.materials = {makeMaterial("glass", 7.0e10, 0.2), makeMaterial("stone", 6.0e10, 0.25)};
  pack.objects = {makeObject("tet", "glass", false, 2), makeObject("pair", "stone", true, 1)};
  // The optional elimination order (PACK_SCHEMA.md) on one object: its DOFs reversed.
  const auto dofs = static_cast<int>(pack.objects[1].modal.modes.rows());
  pack.objects[1].eliminationOrder = Eigen::VectorXi::LinSpaced(dofs, dofs - 1, 0);
  pack.objects[1].bake.thinStretch = 2.0;  // the optional bake/thin_stretch, present and not 1
  pack.objects[1].contactSpreadFraction = 0.15;  // the optional contact_spread_fraction, not 0

  FragmentDatabase& db = pack.database;
  db.referenceMaterial = makeMaterial("reference", 7.0e10, 0.2);
  db.seed = 7;
  db.descriptorSettings.moment.maxOrder = 2;
  db.descriptorSettings.voxel.resolution = 2;
  db.descriptorSettings.voxelImproved.resolution = 2;
  db.descriptorSettings.voxelImproved.clampVoxels = 1.0;
  for (int i = 0; i < 2; ++i) {
    FragmentEntry e;
    // Entry 0 has physics, entry 1 descriptors only (no tets, no modes).
    e.asset = i == 0 ? makeObject("entry-0", "reference", false, 1) : ObjectAsset{};
    if (i == 1) {
      e.asset.name = "entry-1";
      e.asset.materialName = "reference";
    }
    e.surface.vertices = makeTets(false).nodes;
    e.surface.faces.resize(4, 3);
    e.surface.faces << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
    e.baseShape = "box";
    e.cut = i == 0 ? "planes" : "voronoi";
    e.seed = 100 + static_cast<uint64_t>(i);
    e.baseVolumeFraction = 0.25;
    db.entries.push_back(std::move(e));
  }
  for (DescriptorKind kind : kAllDescriptorKinds) {
    db.descriptors[static_cast<size_t>(kind)] = DescriptorMatrix::Constant(2, descriptorSize(kind, db.descriptorSettings), 0.5f);
  }
  // A match-error model (MatchErrors.h) for one kind, so the fuzzers reach its reader.
  MatchErrorModel& errors = db.matchErrors[static_cast<size_t>(DescriptorKind::Moment)];
  errors.distance = {0.1, 0.5};
  errors.medianError = {0.05, 0.1};
  errors.p90Error = {0.1, 0.3};
  errors.samples = 4;
  // And the bodies' frequency-error models, so the fuzzers reach theirs.
  db.frequencyErrors.ritz = errors;
  db.frequencyErrors.checked = errors;
  db.frequencyErrors.checkedP2 = errors;
  db.frequencyErrors.degree = 5;
  return pack;
}

namespace {

// Empty when the pack is sound, else what is wrong.
std::string packProblem(const Pack& pack) {
  // writePack validates before it creates anything, so a path in a missing directory gives the
  // validation's verdict without the cost of a write: InvalidArgument for a pack it refuses,
  // PackIoError for one it accepts.
  const Status written = writePack(pack, scratchDir() / "missing" / "pack.h5");
  if (!written.ok() && written.error().code == ErrorCode::InvalidArgument) return written.error().message;
  if (!pack.database.empty()) {
    if (Status s = validateFragmentDatabase(pack.database); !s) return s.error().message;
  }
  std::set<std::string> materials;
  for (const Material& m : pack.materials) materials.insert(m.name);
  for (const ObjectAsset& o : pack.objects) {
    if (!materials.count(o.materialName)) return "object '" + o.name + "' has no material";
  }
  return {};
}

}  // namespace

void checkOnDemandRead(const std::filesystem::path& path, bool wholeReadOk) {
  bool everyEntryOk = true;
  {
    auto read = readPack(path, EntryReading::OnDemand);
    expectDocumentedError(read, {ErrorCode::FileNotFound, ErrorCode::PackIoError, ErrorCode::PackFormatMismatch,
                                 ErrorCode::PackVersionMismatch, ErrorCode::PackShapeMismatch, ErrorCode::PackCorrupt});
    everyEntryOk = read.ok();
    if (read.ok() && read.value().database.entrySource) {
      const FragmentDatabase& db = read.value().database;
      for (DescriptorKind kind : kAllDescriptorKinds) {
        auto matrix = db.entrySource->descriptors(kind);
        expectDocumentedError(matrix, {ErrorCode::PackIoError, ErrorCode::PackShapeMismatch, ErrorCode::PackCorrupt});
        everyEntryOk = everyEntryOk && matrix.ok();
        if (matrix.ok() && (matrix.value().rows() != static_cast<Eigen::Index>(db.entries.size()) ||
                            matrix.value().cols() != descriptorSize(kind, db.descriptorSettings))) {
          finding("a descriptor matrix read on demand has the wrong shape");
        }
      }
      for (size_t i = 0; i < db.entries.size(); ++i) {
        auto entry = db.entrySource->load(static_cast<int64_t>(i));
        expectDocumentedError(entry, {ErrorCode::PackIoError, ErrorCode::PackShapeMismatch, ErrorCode::PackCorrupt});
        everyEntryOk = everyEntryOk && entry.ok();
        if (entry.ok()) {
          if (Status s = validateFragmentEntry(entry.value(), db.referenceMaterial); !s) {
            finding("an entry read on demand passed a check it fails: " + s.error().message);
          }
          if (entry.value().asset.tetMesh.tets.rows() != db.entrySource->tetCount(static_cast<int64_t>(i))) {
            finding("an entry read on demand has another tet count than its table's");
          }
        }
      }
    }
  }
  if (everyEntryOk != wholeReadOk) {
    finding(std::string("read whole the pack ") + (wholeReadOk ? "passed" : "failed") + ", read on demand it " +
            (everyEntryOk ? "passed" : "failed") + " (with every entry read)");
  }
  if (const ssize_t open = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL); open != 0) {
    finding("a pack read on demand left " + std::to_string(open) + " HDF5 objects open once it was gone");
  }
}

void checkReadResult(const Result<Pack>& result) {
  // For looking at what a corpus reaches: BRITTLE_FUZZ_VERBOSE=1 <target> -runs=0 <corpus>.
  static const bool verbose = std::getenv("BRITTLE_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "readPack: %s\n", result.ok() ? "ok" : result.error().message.c_str());
  expectDocumentedError(result, {ErrorCode::FileNotFound, ErrorCode::PackIoError, ErrorCode::PackFormatMismatch,
                                 ErrorCode::PackVersionMismatch, ErrorCode::PackShapeMismatch, ErrorCode::PackCorrupt});
  if (const ssize_t open = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL); open != 0) {
    finding("readPack left " + std::to_string(open) + " HDF5 objects open");
  }
  if (result.ok()) {
    if (const std::string problem = packProblem(result.value()); !problem.empty()) {
      finding("readPack accepted a pack the runtime cannot trust: " + problem);
    }
  }
}

}  // namespace brittle::fuzz
