#include "brittle/precompute/BakePipeline.h"

#include <set>

#include "brittle/core/EigenBlocking.h"
#include "brittle/core/Timing.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/FillOrdering.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/precompute/MeshValidation.h"

namespace brittle {
namespace {

Error inObject(const std::string& name, const Error& e) {
  return Error{e.code, "object '" + name + "': " + e.message};
}

// Forwards a stage's progress with the object's name in front, so a multi-object bake shows
// which object is working.
class NamedProgress final : public ProgressSink {
 public:
  NamedProgress(ProgressSink* inner, std::string name) : mInner(inner), mName(std::move(name)) {}
  void report(std::string_view stage, double fraction) override {
    if (mInner) mInner->report(mName + ": " + std::string(stage), fraction);
  }
  bool wasInterrupted() override { return mInner && mInner->wasInterrupted(); }

 private:
  ProgressSink* mInner;
  std::string mName;
};

}  // namespace

static Result<ObjectAsset> bakeSurfaceSince(TriangleMesh mesh, const ObjectBakeSettings& s, ProgressSink* progressIn,
                                            ObjectBakeReport* report, SteadyClock::time_point start);

Result<ObjectAsset> bakeObject(const ObjectBakeSettings& s, ProgressSink* progressIn, ObjectBakeReport* report) {
  pinEigenBlocking();  // the same pack on every CPU (EigenBlocking.h)
  const auto start = SteadyClock::now();
  const std::string name = s.name.empty() ? s.meshPath.stem().string() : s.name;
  NamedProgress progress(progressIn, name);
  if (Status m = validateMaterial(s.material); !m) return inObject(name, m.error());

  progress.report("reading", 0.0);
  auto surface = readSurfaceMesh(s.meshPath);
  if (!surface) return inObject(name, surface.error());
  ObjectBakeSettings named = s;
  named.name = name;
  return bakeSurfaceSince(std::move(surface).value(), named, progressIn, report, start);
}

Result<ObjectAsset> bakeSurface(TriangleMesh mesh, const ObjectBakeSettings& s, ProgressSink* progressIn,
                                ObjectBakeReport* report) {
  pinEigenBlocking();
  return bakeSurfaceSince(std::move(mesh), s, progressIn, report, SteadyClock::now());
}

static Result<ObjectAsset> bakeSurfaceSince(TriangleMesh mesh, const ObjectBakeSettings& s, ProgressSink* progressIn,
                                            ObjectBakeReport* report, SteadyClock::time_point start) {
  const std::string& name = s.name;
  NamedProgress progress(progressIn, name);
  ObjectBakeReport localReport;
  ObjectBakeReport& rep = report ? *report : localReport;
  if (name.empty()) return makeError(ErrorCode::InvalidArgument, "an object to bake needs a name");
  if (Status m = validateMaterial(s.material); !m) return inObject(name, m.error());
  if (!isContactSpreadFraction(s.contactSpreadFraction)) {
    return inObject(name, makeError(ErrorCode::InvalidArgument, "the contact spread must be in [0, 1) of the diagonal"));
  }
  if (s.repair) {
    auto repaired = repairSurfaceMesh(mesh, s.repairSettings, &rep.repair, &progress);
    if (!repaired) return inObject(name, repaired.error());
    mesh = std::move(repaired).value();
  }
  progress.report("validating", 0.0);
  if (Status valid = validateSurfaceMesh(mesh); !valid) return inObject(name, valid.error());
  rep.surfaceVolumeM3 = computeSurfaceMassProperties(mesh, 1.0).volumeM3;

  ObjectAsset asset;
  asset.name = name;
  asset.materialName = s.material.name;
  asset.contactSpreadFraction = s.contactSpreadFraction;
  BakeRecord& rec = asset.bake;
  rec.sourceMesh = s.sourceName.empty() ? s.meshPath.filename().string() : s.sourceName;
  rec.targetTets = s.tetMesh.targetTets;
  rec.thinStretch = s.tetMesh.thinStretch;
  rec.requestedModes = s.modal.modeCount;
  rec.lumpedMass = s.fem.lumpedMass;
  rec.repaired = s.repair;
  rec.repairVolumeChange = s.repair ? rep.repair.relativeVolumeChange : 0.0;
  rec.factorization = factorizationName(s.modal.factorization);
  rec.seed = static_cast<int64_t>(s.modal.seed);
  rec.generator = std::string("brittle ") + BRITTLE_VERSION;

  auto t = SteadyClock::now();
  auto tets = tetrahedralize(mesh, s.tetMesh, &progress);
  if (!tets) return inObject(name, tets.error());
  rec.meshingS = secondsSince(t);
  rec.cellSizeM = tets.value().cellSizeM;
  rep.meshingRuns = tets.value().meshingRuns;
  rep.meshingAdjustments = tets.value().adjustments;
  asset.tetMesh = std::move(tets.value().mesh);
  asset.surfaceFaces = std::move(tets.value().surfaceFaces);
  asset.quality = tets.value().quality;

  t = SteadyClock::now();
  progress.report("assembling K and M", 0.0);
  asset.elementOrder = s.elementOrder;
  auto fem = makeFemMesh(asset.tetMesh, s.elementOrder);
  if (!fem) return inObject(name, fem.error());
  auto system = assembleFem(fem.value(), s.material, s.fem);
  if (!system) return inObject(name, system.error());
  // The runtime's factorisation order (FillOrdering.h): on K's pattern, which K + μM shares.
  if (s.fillOrdering) {
    auto order = fillReducingOrdering(system.value().stiffness);
    if (!order) return inObject(name, order.error());
    asset.eliminationOrder = std::move(order).value();
  }
  rec.assemblyS = secondsSince(t);

  t = SteadyClock::now();
  ModalSettings modal = s.modal;
  if (modal.shiftRad2PerS2 == 0.0) modal.shiftRad2PerS2 = defaultShift(asset.tetMesh.nodes, s.material);
  rec.shift = modal.shiftRad2PerS2;
  auto modes = computeModes(system.value(), fem.value().nodes(), modal, &progress);
  if (!modes) return inObject(name, modes.error());
  rec.modalS = secondsSince(t);
  rep.modalStats = modes.value().stats;
  asset.modal = std::move(modes.value().basis);

  t = SteadyClock::now();
  progress.report("stress modes", 0.0);
  asset.stressModes = computeStressModes(fem.value(), s.material, asset.modal.modes);
  rec.stressModesS = secondsSince(t);

  asset.massProperties = computeTetMassProperties(asset.tetMesh, s.material.densityKgPerM3);
  rep.tetVolumeRelativeError = (asset.massProperties.volumeM3 - rep.surfaceVolumeM3) / rep.surfaceVolumeM3;
  rec.totalS = secondsSince(start);
  progress.report("done", 1.0);
  return asset;
}

Result<Pack> bakePack(const std::vector<ObjectBakeSettings>& objects, ProgressSink* progress,
                      std::vector<ObjectBakeReport>* reports) {
  pinEigenBlocking();
  Pack pack;
  if (reports) reports->clear();
  std::set<std::string> names;
  for (const auto& o : objects) {
    const std::string name = o.name.empty() ? o.meshPath.stem().string() : o.name;
    if (!names.insert(name).second) return makeError(ErrorCode::InvalidArgument, "duplicate object name '" + name + "'");
    const Material* existing = nullptr;
    for (const auto& m : pack.materials)
      if (m.name == o.material.name) existing = &m;
    if (existing && !(*existing == o.material)) {
      return makeError(ErrorCode::InvalidArgument, "two different materials are named '" + o.material.name + "'");
    }
    if (!existing) pack.materials.push_back(o.material);
  }
  for (const auto& o : objects) {
    ObjectBakeReport report;
    auto asset = bakeObject(o, progress, &report);
    if (!asset) return asset.error();
    pack.objects.push_back(std::move(asset).value());
    if (reports) reports->push_back(report);
  }
  return pack;
}

}  // namespace brittle
