#include "brittle/precompute/FragmentDatabaseBake.h"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <tuple>
#include <cstdio>
#include <mutex>
#include <optional>

#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshValidation.h"

namespace brittle {
namespace {

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Progress from many worker threads: one lock, fraction = entries done / entries.
class SharedProgress {
 public:
  SharedProgress(ProgressSink* sink, int64_t total) : mSink(sink), mTotal(total) {}
  void entryDone() {
    const int64_t done = ++mDone;
    if (!mSink) return;
    const std::lock_guard<std::mutex> lock(mMutex);
    mSink->report("fragment database", static_cast<double>(done) / static_cast<double>(mTotal));
  }
  bool interrupted() {
    if (!mSink) return false;
    const std::lock_guard<std::mutex> lock(mMutex);
    return mSink->wasInterrupted();
  }

 private:
  ProgressSink* mSink;
  int64_t mTotal;
  std::atomic<int64_t> mDone{0};
  std::mutex mMutex;
};

std::string entryName(const std::string& shape, int64_t i) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "-%05lld", static_cast<long long>(i));
  return shape + buffer;
}

}  // namespace

Material DatabaseBakeSettings::referenceFragmentMaterial() { return materialPreset("glass").value(); }

TetMeshSettings DatabaseBakeSettings::defaultFragmentTetMeshSettings() {
  TetMeshSettings s;
  s.targetTets = 1000;
  s.countTolerance = 0.35;
  s.maxAttempts = 3;
  return s;
}

uint64_t fragmentEntrySeed(uint64_t seed, int64_t entry) { return splitmix64(seed + static_cast<uint64_t>(entry)); }

bool isRuntimeFragmentEntry(uint64_t entrySeed, double fraction) {
  return static_cast<double>(splitmix64(entrySeed ^ 0x52554e54494d45ull) >> 11) * 0x1.0p-53 < fraction;
}

Result<FragmentEntry> bakeFragmentEntry(const TriangleMesh& fragment, const std::string& name,
                                        const DatabaseBakeSettings& settings,
                                        std::array<Descriptor, kDescriptorKindCount>& descriptors,
                                        ProgressSink* progress) {
  auto frames = computeCanonicalFrames(fragment, settings.descriptors.frame);
  if (!frames) return frames.error();
  FragmentEntry entry;
  entry.surface.vertices = frames.value().candidates.front().pointsToCanonical(fragment.vertices);
  entry.surface.faces = fragment.faces;
  if (Status valid = validateSurfaceMesh(entry.surface); !valid) return valid.error();

  // Descriptors of the stored (canonical) surface in its primary frame, which is the identity up
  // to rounding: a query's candidate frame that matches this row maps the entry onto the query.
  auto canonicalFrames = computeCanonicalFrames(entry.surface, settings.descriptors.frame);
  if (!canonicalFrames) return canonicalFrames.error();
  CanonicalFrames primary = std::move(canonicalFrames).value();
  primary.candidates.resize(1);
  for (DescriptorKind kind : kAllDescriptorKinds) {
    if (!settings.kinds[static_cast<size_t>(kind)]) {
      descriptors[static_cast<size_t>(kind)].resize(0);
      continue;
    }
    auto d = computeShapeDescriptors(entry.surface, primary, kind, settings.descriptors);
    if (!d) return d.error();
    descriptors[static_cast<size_t>(kind)] = d.value().row(0).transpose();
  }

  if (settings.physics) {
    ObjectBakeSettings bake;
    bake.name = name;
    bake.sourceName = name;
    bake.material = settings.referenceMaterial;
    bake.tetMesh = settings.tetMesh;
    bake.modal.modeCount = settings.modeCount;
    // A fragment thinner than the cell size in places comes out of Mesh_3 in pieces: mesh the
    // same fragment finer (2×, 4× the tets) before the caller draws another one.
    auto asset = bakeSurface(entry.surface, bake, progress);
    for (int finer = 0; finer < 2 && !asset && asset.error().code == ErrorCode::MeshingFailed &&
                        bake.tetMesh.targetTets > 0;
         ++finer) {
      bake.tetMesh.targetTets *= 2;
      asset = bakeSurface(entry.surface, bake, progress);
    }
    if (!asset) return asset.error();
    entry.asset = std::move(asset).value();
  } else {
    entry.asset.name = name;
    entry.asset.materialName = settings.referenceMaterial.name;
    entry.asset.massProperties = computeSurfaceMassProperties(entry.surface, settings.referenceMaterial.densityKgPerM3);
    entry.asset.modal.modes.resize(0, 0);
    entry.asset.bake.sourceMesh = name;
    entry.asset.bake.generator = std::string("brittle ") + BRITTLE_VERSION;
  }
  return entry;
}

Result<FragmentDatabase> bakeFragmentDatabase(const DatabaseBakeSettings& settings, ProgressSink* progress) {
  if (settings.shapes.empty()) return makeError(ErrorCode::InvalidArgument, "the fragment database needs base shapes");
  if (settings.entryCount < 1) return makeError(ErrorCode::InvalidArgument, "the fragment database needs ≥ 1 entry");
  if (Status st = validateShapeDescriptorSettings(settings.descriptors); !st) return st.error();
  if (Status st = validateMaterial(settings.referenceMaterial); !st) return st.error();

  std::vector<TriangleMesh> bases;
  std::vector<double> baseVolumes;
  for (const BaseShapeDefinition& def : settings.shapes) {
    auto mesh = makeBaseShape(def);
    if (!mesh) return Error{mesh.error().code, "base shape '" + def.name + "': " + mesh.error().message};
    baseVolumes.push_back(computeSurfaceMassProperties(mesh.value(), 1.0).volumeM3);
    bases.push_back(std::move(mesh).value());
  }

  std::optional<RuntimeFragmentSource> runtime;
  if (settings.runtimeFragments.fraction > 0.0) {
    auto source = RuntimeFragmentSource::build(settings.shapes, bases, settings.referenceMaterial,
                                               settings.runtimeFragments, progress);
    if (!source) return source.error();
    runtime.emplace(std::move(source).value());
  } else if (Status st = validateRuntimeFragmentSettings(settings.runtimeFragments); !st) {
    return st.error();
  }

  const auto count = static_cast<size_t>(settings.entryCount);
  std::vector<std::optional<Result<FragmentEntry>>> results(count);
  std::vector<std::array<Descriptor, kDescriptorKindCount>> rows(count);
  SharedProgress shared(progress, settings.entryCount);
  std::atomic<bool> stop{false};

  // Runtime fragments' crack faces zigzag at the runtime mesh's scale: their creases are not
  // features to keep, and protecting them starves Mesh_3 of cells.
  DatabaseBakeSettings runtimeEntrySettings = settings;
  runtimeEntrySettings.tetMesh.detectSharpFeatures = false;

  auto bakeOne = [&](size_t i) {
    if (stop.load()) return;
    if (shared.interrupted()) {
      stop = true;
      results[i] = Result<FragmentEntry>(makeError(ErrorCode::Cancelled, "fragment database bake cancelled"));
      return;
    }
    const size_t shape = i % bases.size();
    const std::string name = entryName(settings.shapes[shape].name, static_cast<int64_t>(i));
    uint64_t seed = fragmentEntrySeed(settings.seed, static_cast<int64_t>(i));
    const bool fromRuntime = runtime && isRuntimeFragmentEntry(seed, settings.runtimeFragments.fraction);
    std::optional<Error> lastError;
    for (int attempt = 0; attempt < kEntryAttempts; ++attempt, seed = splitmix64(seed)) {
      std::string cut;
      auto fragment = fromRuntime ? runtime->fragment(shape, seed, &cut)
                                  : generateFragment(bases[shape], settings.fragments, seed, &cut);
      if (!fragment) {
        lastError = fragment.error();
        continue;
      }
      auto entry = bakeFragmentEntry(fragment.value(), name, fromRuntime ? runtimeEntrySettings : settings, rows[i]);
      if (!entry) {
        lastError = entry.error();
        continue;
      }
      entry.value().baseShape = settings.shapes[shape].name;
      entry.value().cut = cut;
      entry.value().seed = seed;
      entry.value().baseVolumeFraction = computeSurfaceMassProperties(fragment.value(), 1.0).volumeM3 / baseVolumes[shape];
      results[i] = std::move(entry);
      shared.entryDone();
      return;
    }
    results[i] = Result<FragmentEntry>(Error{lastError->code, "entry '" + name + "' failed " +
                                                                  std::to_string(kEntryAttempts) +
                                                                  " times; last error: " + lastError->message});
    stop = true;
  };

  std::optional<tbb::global_control> limit;
  if (settings.threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, settings.threads);
  tbb::parallel_for(size_t{0}, count, bakeOne);

  FragmentDatabase db;
  db.referenceMaterial = settings.referenceMaterial;
  db.descriptorSettings = settings.descriptors;
  db.seed = settings.seed;
  db.indexSettings = settings.index;
  db.entries.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    if (!results[i]) continue;  // skipped after another entry failed
    if (!*results[i]) return results[i]->error();
  }
  for (size_t i = 0; i < count; ++i) {
    if (!results[i]) return makeError(ErrorCode::Cancelled, "fragment database bake stopped early");
    db.entries.push_back(std::move(*results[i]).value());
  }
  for (DescriptorKind kind : kAllDescriptorKinds) {
    const auto k = static_cast<size_t>(kind);
    DescriptorMatrix& m = db.descriptors[k];
    m.resize(static_cast<Eigen::Index>(count), settings.kinds[k] ? descriptorSize(kind, settings.descriptors) : 0);
    for (size_t i = 0; i < count; ++i) m.row(static_cast<Eigen::Index>(i)) = rows[i][k].transpose();
  }
  return db;
}

Result<std::vector<BaseShapeDefinition>> selectBaseShapes(const std::vector<BaseShapeDefinition>& shapes,
                                                          const std::vector<std::string>& names) {
  std::vector<BaseShapeDefinition> out;
  for (const std::string& name : names) {
    const auto it = std::find_if(shapes.begin(), shapes.end(), [&](const auto& s) { return s.name == name; });
    if (it == shapes.end()) {
      std::string known;
      for (const auto& s : shapes) known += (known.empty() ? "" : ", ") + s.name;
      return makeError(ErrorCode::InvalidArgument, "unknown base shape '" + name + "' (known: " + known + ")");
    }
    out.push_back(*it);
  }
  return out;
}

Result<std::optional<DatabaseBakeSettings>> loadDatabaseManifest(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return makeError(ErrorCode::FileNotFound, "manifest not found: " + path.string());
  const std::string where = "manifest " + path.filename().string() + ", database";
  try {
    const nlohmann::json doc = nlohmann::json::parse(in);
    if (!doc.is_object() || !doc.contains("database")) return std::optional<DatabaseBakeSettings>();
    const nlohmann::json& d = doc["database"];
    if (!d.is_object()) return makeError(ErrorCode::ParseError, where + ": not an object");
    static const std::set<std::string> kKeys = {"shapes", "only", "entries", "seed", "tets", "modes",
                                                "descriptors_only", "moment_order", "voxel_resolution",
                                                "runtime_fraction"};
    for (const auto& [key, value] : d.items()) {
      if (!kKeys.count(key)) return makeError(ErrorCode::ParseError, where + ": unknown key \"" + key + "\"");
    }
    if (!d.contains("shapes")) return makeError(ErrorCode::ParseError, where + ": \"shapes\" is required");
    for (const auto& [key, lo, hi] : {std::tuple{"entries", 1.0, 1e7}, std::tuple{"seed", 0.0, 9.007199254740992e15},
                                       std::tuple{"tets", 100.0, 1e6}, std::tuple{"modes", 1.0, 200.0},
                                       std::tuple{"moment_order", 2.0, 10.0}, std::tuple{"voxel_resolution", 2.0, 64.0}}) {
      if (!d.contains(key)) continue;
      const bool ok = d[key].is_number() && d[key].get<double>() >= lo && d[key].get<double>() <= hi &&
                      d[key].get<double>() == std::floor(d[key].get<double>());
      if (!ok) {
        return makeError(ErrorCode::ParseError, where + ": \"" + key + "\" must be an integer in [" +
                                                    std::to_string(static_cast<int64_t>(lo)) + ", " +
                                                    std::to_string(static_cast<int64_t>(hi)) + "]");
      }
    }
    if (d.contains("runtime_fraction") &&
        !(d["runtime_fraction"].is_number() && d["runtime_fraction"].get<double>() >= 0.0 &&
          d["runtime_fraction"].get<double>() <= 1.0)) {
      return makeError(ErrorCode::ParseError, where + ": \"runtime_fraction\" must be a number in [0, 1]");
    }
    DatabaseBakeSettings s;
    auto shapes = loadBaseShapes(path.parent_path() / d["shapes"].get<std::string>());
    if (!shapes) return shapes.error();
    s.shapes = std::move(shapes).value();
    if (d.contains("only")) {
      auto picked = selectBaseShapes(s.shapes, d["only"].get<std::vector<std::string>>());
      if (!picked) return Error{ErrorCode::ParseError, where + ": " + picked.error().message};
      s.shapes = std::move(picked).value();
    }
    s.entryCount = d.value("entries", s.entryCount);
    s.seed = d.value("seed", s.seed);
    s.tetMesh.targetTets = d.value("tets", s.tetMesh.targetTets);
    s.tetMesh.seed = s.seed;
    s.modeCount = d.value("modes", s.modeCount);
    s.physics = !d.value("descriptors_only", false);
    s.descriptors.moment.maxOrder = d.value("moment_order", s.descriptors.moment.maxOrder);
    s.descriptors.voxel.resolution = d.value("voxel_resolution", s.descriptors.voxel.resolution);
    s.descriptors.voxelImproved.resolution = s.descriptors.voxel.resolution;
    s.runtimeFragments.fraction = d.value("runtime_fraction", 0.0);
    return std::optional<DatabaseBakeSettings>(std::move(s));
  } catch (const nlohmann::json::exception& e) {
    return makeError(ErrorCode::ParseError, where + ": " + e.what());
  }
}

}  // namespace brittle
