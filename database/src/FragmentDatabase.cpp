#include "brittle/database/FragmentDatabase.h"
#include "brittle/descriptors/VolumeMoments.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

namespace brittle {

bool FragmentDatabase::hasPhysics() const {
  for (size_t i = 0; i < entries.size(); ++i) {
    const FragmentEntry& e = entries[i];
    const int64_t tets = entrySource ? entrySource->tetCount(static_cast<int64_t>(i)) : e.asset.tetMesh.tets.rows();
    if (tets == 0 || e.asset.modal.eigenvaluesRad2PerS2.size() == 0) return false;
  }
  return !entries.empty();
}

namespace {

// An inverted file of about `rowsPerList` rows a list, at most 1 024 lists (PackReader's bound on
// trees), `probes` of them probed (all of them while there are fewer).
DescriptorIndexSettings listsOf(DescriptorIndexSettings::Kind kind, int64_t entries, int64_t rowsPerList, int probes) {
  constexpr int64_t kMaxLists = 1024;
  DescriptorIndexSettings s;
  s.kind = kind;
  s.trees = static_cast<int>(std::clamp<int64_t>(entries / rowsPerList, 1, kMaxLists));
  s.checks = std::min(s.trees, probes);
  return s;
}

}  // namespace

DescriptorIndexSettings sizedInvertedFile(int64_t entries, DescriptorKind kind) {
  // The moments' rows are filed by 16 components, the grids' by 64 (IvfBackend.cpp).
  if (kind == DescriptorKind::Moment) return listsOf(DescriptorIndexSettings::Kind::Ivf, entries, kIvfRowsPerList, 4);
  return listsOf(DescriptorIndexSettings::Kind::Ivf, entries, kIvfWideRowsPerList, 40);
}

DescriptorIndexSettings defaultIndexSettings(DescriptorKind kind, int64_t entries) {
  if (kind == DescriptorKind::Voxel) return listsOf(DescriptorIndexSettings::Kind::IvfBinary, entries, kIvfBinaryRowsPerList, 32);
  return sizedInvertedFile(entries, kind);
}

namespace {

Status invalid(std::string message) { return makeError(ErrorCode::InvalidArgument, std::move(message)); }

// validateFragmentEntry, the surface only where `withSurface`.
Status checkEntry(const FragmentEntry& e, const Material& reference, const std::string& label, bool withSurface) {
  if (e.asset.materialName != reference.name) {
    return invalid(label + " names material '" + e.asset.materialName + "', not the reference material '" +
                   reference.name + "'");
  }
  if (withSurface) {
    const TriangleMesh& s = e.surface;
    if (s.vertices.rows() < 4 || s.faces.rows() < 4) return invalid(label + " has no closed surface");
    if (!s.vertices.allFinite()) return invalid(label + " surface has a non-finite vertex");
    if (s.faces.minCoeff() < 0 || s.faces.maxCoeff() >= s.vertices.rows()) {
      return invalid(label + " surface has a face index out of range");
    }
  }
  if (!std::isfinite(e.baseVolumeFraction) || e.baseVolumeFraction < 0.0) {
    return invalid(label + " has an invalid baseVolumeFraction");
  }
  return Ok{};
}

std::string entryLabel(size_t i, const FragmentEntry& e) {
  return "entry " + std::to_string(i) + " ('" + e.asset.name + "')";
}

}  // namespace

Status validateFragmentEntry(const FragmentEntry& entry, const Material& referenceMaterial) {
  return checkEntry(entry, referenceMaterial, "entry '" + entry.asset.name + "'", true);
}

Status validateFragmentDatabase(const FragmentDatabase& db) {
  if (Status st = validateMaterial(db.referenceMaterial); !st) return invalid("reference material: " + st.error().message);
  if (Status st = validateShapeDescriptorSettings(db.descriptorSettings); !st) return st;
  const auto rows = static_cast<Eigen::Index>(db.entries.size());
  std::set<std::string> names;
  for (size_t i = 0; i < db.entries.size(); ++i) {
    const FragmentEntry& e = db.entries[i];
    if (!names.insert(e.asset.name).second) return invalid("two entries are named '" + e.asset.name + "'");
    if (Status st = checkEntry(e, db.referenceMaterial, entryLabel(i, e), !db.entrySource); !st) return st;
  }
  for (DescriptorKind kind : kAllDescriptorKinds) {
    const DescriptorMatrix& m = db.descriptorsOf(kind);
    const std::string what = std::string(descriptorKindName(kind)) + " descriptor matrix";
    const bool unread = db.entrySource && m.size() == 0;  // read, and checked, when it is indexed
    if (!unread && (m.rows() != rows || m.cols() != descriptorSize(kind, db.descriptorSettings))) {
      return invalid(what + " is " + std::to_string(m.rows()) + " x " + std::to_string(m.cols()) + ", expected " +
                     std::to_string(rows) + " x " + std::to_string(descriptorSize(kind, db.descriptorSettings)));
    }
    // In storage order: Eigen's allFinite walks a row-major matrix by columns, a stride of a row
    // per value (1 s of a 10⁴-entry database's 1.9 s read).
    if (!Eigen::Map<const Eigen::ArrayXf>(m.data(), m.size()).allFinite()) return invalid(what + " holds a non-finite value");
    const DescriptorIndexSettings& index = db.indexSettings[static_cast<size_t>(kind)];
    if (index.trees < 1 || index.checks < 1 || !(index.targetPrecision > 0.0f && index.targetPrecision <= 1.0f)) {
      return invalid("index settings of the " + std::string(descriptorKindName(kind)) + " descriptor are out of range");
    }
    if (Status st = validateMatchErrorModel(db.matchErrors[static_cast<size_t>(kind)]); !st) {
      return invalid(std::string(descriptorKindName(kind)) + " " + st.error().message);
    }
  }
  for (const MatchErrorModel* m : {&db.frequencyErrors.ritz, &db.frequencyErrors.checked, &db.frequencyErrors.checkedP2})
    if (Status st = validateMatchErrorModel(*m); !st) return invalid("frequency " + st.error().message);
  // The Ritz indicator compares degrees p − 2 and p, p at most what the moments allow.
  if (!db.frequencyErrors.empty() && (db.frequencyErrors.degree < 3 || db.frequencyErrors.degree > kMaxMomentOrder / 2)) {
    return invalid("frequency errors: calibrated at degree " + std::to_string(db.frequencyErrors.degree) + ", outside [3, " +
                   std::to_string(kMaxMomentOrder / 2) + "]");
  }
  return Ok{};
}

}  // namespace brittle
