#include "brittle/precompute/FragmentDatabaseBake.h"

#include "brittle/database/MatchErrors.h"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <tuple>
#include <cstdio>
#include <mutex>
#include <optional>
#include <memory>
#include <unistd.h>

#include "brittle/core/AtomicFile.h"
#include "brittle/core/EigenBlocking.h"
#include "brittle/core/JsonChecks.h"
#include "brittle/core/Random.h"
#include "brittle/database/Pack.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshValidation.h"
#include "brittle/runtime/FragmentModes.h"

namespace brittle {
namespace {

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
  // A fragment is a cut polyhedron: every crease is a real edge, so all are protected; and the
  // database bake meshes a fragment that splits finer itself (bakeEntry), or draws another, so
  // one Mesh_3 run each. This keeps database entries as they were before meshing retries.
  s.minFeatureLengthCells = 0.0;
  s.needleTurnDeg = 0.0;
  s.meshingRuns = 1;
  // A fragment's run takes 0.05–5 s at 300–1000 tets; one that runs on (TetMeshSettings) is
  // given up after a minute, and the fragment meshed finer (bakeFragmentEntry) or drawn again.
  s.runTimeLimitS = 60.0;
  return s;
}

uint64_t fragmentEntrySeed(uint64_t seed, int64_t entry) { return splitmix64(seed + static_cast<uint64_t>(entry)); }

bool isRuntimeFragmentEntry(uint64_t entrySeed, double fraction) {
  return unitInterval(splitmix64(entrySeed ^ 0x52554e54494d45ull)) < fraction;
}

Result<FragmentEntry> bakeFragmentEntry(const TriangleMesh& fragment, const std::string& name,
                                        const DatabaseBakeSettings& settings,
                                        std::array<Descriptor, kDescriptorKindCount>& descriptors,
                                        ProgressSink* progress, const TetMesh* solid) {
  pinEigenBlocking();
  auto frames = computeCanonicalFrames(fragment, settings.descriptors.frame);
  if (!frames) return frames.error();
  const CanonicalFrame& frame = frames.value().candidates.front();
  FragmentEntry entry;
  entry.surface.vertices = frame.pointsToCanonical(fragment.vertices);
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

  if (settings.physics && solid) {
    // The fragment's own tets, in the same canonical frame as its surface.
    FragmentSubMesh own;
    own.mesh.nodes = frame.pointsToCanonical(solid->nodes);
    own.mesh.tets = solid->tets;
    ExactModesSettings modes;
    modes.modeCount = settings.modeCount;
    modes.elementOrder = settings.elementOrder;
    auto asset = exactFragmentAsset(own, settings.referenceMaterial, modes, name);
    if (!asset) return asset.error();
    entry.asset = std::move(asset).value();
    entry.asset.bake.sourceMesh = name;
    entry.asset.bake.generator = std::string("brittle ") + BRITTLE_VERSION;
  } else if (settings.physics) {
    ObjectBakeSettings bake;
    bake.name = name;
    bake.sourceName = name;
    bake.material = settings.referenceMaterial;
    bake.tetMesh = settings.tetMesh;
    bake.modal.modeCount = settings.modeCount;
    bake.elementOrder = settings.elementOrder;
    bake.fillOrdering = false;  // not stored for entries (BakePipeline.h)
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

namespace {

// What every entry of one bake shares: the base shapes, their volumes and, for a runtime share,
// the runtime source. bake() fills entries [first, end) in parallel (TBB).
class EntryBaker {
 public:
  static Result<std::unique_ptr<EntryBaker>> create(const DatabaseBakeSettings& settings, ProgressSink* progress) {
    if (settings.shapes.empty()) return makeError(ErrorCode::InvalidArgument, "the fragment database needs base shapes");
    if (settings.entryCount < 1) return makeError(ErrorCode::InvalidArgument, "the fragment database needs ≥ 1 entry");
    if (Status st = validateShapeDescriptorSettings(settings.descriptors); !st) return st.error();
    if (Status st = validateMaterial(settings.referenceMaterial); !st) return st.error();
    auto baker = std::unique_ptr<EntryBaker>(new EntryBaker(settings));
    for (const BaseShapeDefinition& def : settings.shapes) {
      auto mesh = makeBaseShape(def);
      if (!mesh) return Error{mesh.error().code, "base shape '" + def.name + "': " + mesh.error().message};
      baker->mBaseVolumes.push_back(computeSurfaceMassProperties(mesh.value(), 1.0).volumeM3);
      baker->mBases.push_back(std::move(mesh).value());
    }
    if (settings.runtimeFragments.fraction > 0.0) {
      auto source = RuntimeFragmentSource::build(settings.shapes, baker->mBases, settings.referenceMaterial,
                                                 settings.runtimeFragments, progress);
      if (!source) return source.error();
      baker->mRuntime.emplace(std::move(source).value());
    } else if (Status st = validateRuntimeFragmentSettings(settings.runtimeFragments); !st) {
      return st.error();
    }
    return baker;
  }

  using Row = std::array<Descriptor, kDescriptorKindCount>;
  /// Called with a range's entries and rows (entry first + k at k) once its last entry is made.
  using RangeDone = std::function<Status(size_t range, std::vector<FragmentEntry>&& entries, std::vector<Row>&& rows)>;

  // Bakes the entries of `ranges` ([first, end) each), handing them to the workers one at a time
  // in entry order, and gives a range to `done` as soon as its last entry is made, on the worker
  // that made it (one call at a time). No worker waits at the end of a range for its slowest
  // entry: with a wait after each 64-entry chunk, a 10⁴-entry bake kept 2 cores 83 % busy.
  // Errors: the failing entry's of the lowest index (every entry before it was handed out and
  // finished, so it is the same on any thread count), done's first error, Cancelled.
  Status bake(const std::vector<std::pair<int64_t, int64_t>>& ranges, SharedProgress& shared,
              const RangeDone& done) const {
    struct Pending {
      std::vector<std::optional<Result<FragmentEntry>>> results;
      std::vector<Row> rows;
      std::atomic<int64_t> left{0};
    };
    std::vector<Pending> pending(ranges.size());
    std::vector<int64_t> starts;  // position of each range's first entry in the hand-out order
    int64_t total = 0;
    for (size_t r = 0; r < ranges.size(); ++r) {
      const int64_t count = ranges[r].second - ranges[r].first;
      pending[r].results.resize(static_cast<size_t>(count));
      pending[r].rows.assign(static_cast<size_t>(count), {});
      pending[r].left = count;
      starts.push_back(total);
      total += count;
    }
    std::atomic<int64_t> next{0};
    std::atomic<bool> stop{false};
    std::mutex doneMutex;
    std::optional<Error> doneError;
    auto work = [&] {
      for (int64_t n; !stop.load() && (n = next++) < total;) {
        const size_t r = static_cast<size_t>(std::upper_bound(starts.begin(), starts.end(), n) - starts.begin()) - 1;
        const auto k = static_cast<size_t>(n - starts[r]);
        Pending& range = pending[r];
        if (shared.interrupted()) {
          stop = true;
          range.results[k] = Result<FragmentEntry>(makeError(ErrorCode::Cancelled, "fragment database bake cancelled"));
          return;
        }
        range.results[k] = bakeEntry(ranges[r].first + static_cast<int64_t>(k), range.rows[k]);
        if (!range.results[k]->ok()) {
          stop = true;
          return;
        }
        shared.entryDone();
        if (--range.left > 0) continue;
        std::vector<FragmentEntry> entries;
        entries.reserve(range.results.size());
        for (auto& result : range.results) entries.push_back(std::move(*result).value());
        range.results = {};
        const std::lock_guard<std::mutex> lock(doneMutex);
        if (doneError) return;
        if (Status st = done(r, std::move(entries), std::move(range.rows)); !st) {
          doneError = st.error();
          stop = true;
        }
      }
    };
    std::optional<tbb::global_control> limit;
    if (mSettings.threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, mSettings.threads);
    const int workers = mSettings.threads > 0 ? mSettings.threads : tbb::info::default_concurrency();
    tbb::parallel_for(0, workers, [&](int) { work(); });

    for (const Pending& range : pending) {
      for (const auto& result : range.results) {
        if (result && !*result) return result->error();  // the lowest failing entry's
      }
    }
    if (doneError) return *doneError;
    for (const Pending& range : pending) {
      if (range.left > 0) return makeError(ErrorCode::Cancelled, "fragment database bake stopped early");
    }
    return Ok{};
  }

 private:
  explicit EntryBaker(const DatabaseBakeSettings& settings) : mSettings(settings) {}

  Result<FragmentEntry> bakeEntry(int64_t i, std::array<Descriptor, kDescriptorKindCount>& row) const {
    const size_t shape = static_cast<size_t>(i) % mBases.size();
    const std::string name = entryName(mSettings.shapes[shape].name, i);
    uint64_t seed = fragmentEntrySeed(mSettings.seed, i);
    const bool fromRuntime = mRuntime && isRuntimeFragmentEntry(seed, mSettings.runtimeFragments.fraction);
    std::optional<Error> lastError;
    for (int attempt = 0; attempt < kEntryAttempts; ++attempt, seed = splitmix64(seed)) {
      std::string cut;
      TetMesh solid;
      const bool ownTets = fromRuntime && mSettings.physics;
      auto fragment = fromRuntime ? mRuntime->fragment(shape, seed, &cut, ownTets ? &solid : nullptr)
                                  : generateFragment(mBases[shape], mSettings.fragments, seed, &cut);
      if (!fragment) {
        lastError = fragment.error();
        continue;
      }
      auto entry = bakeFragmentEntry(fragment.value(), name, mSettings, row, nullptr, ownTets ? &solid : nullptr);
      if (!entry) {
        lastError = entry.error();
        continue;
      }
      entry.value().baseShape = mSettings.shapes[shape].name;
      entry.value().cut = cut;
      entry.value().seed = seed;
      entry.value().baseVolumeFraction =
          computeSurfaceMassProperties(fragment.value(), 1.0).volumeM3 / mBaseVolumes[shape];
      return entry;
    }
    return Error{lastError->code, "entry '" + name + "' failed " + std::to_string(kEntryAttempts) +
                                      " times; last error: " + lastError->message};
  }

  const DatabaseBakeSettings& mSettings;
  std::vector<TriangleMesh> mBases;
  std::vector<double> mBaseVolumes;
  std::optional<RuntimeFragmentSource> mRuntime;
};

// The database of these entries (rows in entry order) with the bake's settings.
FragmentDatabase databaseOf(const DatabaseBakeSettings& settings, std::vector<FragmentEntry> entries,
                            const std::vector<std::array<Descriptor, kDescriptorKindCount>>& rows) {
  FragmentDatabase db;
  db.referenceMaterial = settings.referenceMaterial;
  db.descriptorSettings = settings.descriptors;
  db.seed = settings.seed;
  const auto count = static_cast<Eigen::Index>(entries.size());
  for (DescriptorKind kind : kAllDescriptorKinds) {
    const auto k = static_cast<size_t>(kind);
    db.indexSettings[k] = settings.index[k].value_or(defaultIndexSettings(kind, count));
  }
  db.entries = std::move(entries);
  for (DescriptorKind kind : kAllDescriptorKinds) {
    const auto k = static_cast<size_t>(kind);
    DescriptorMatrix& m = db.descriptors[k];
    m.resize(count, settings.kinds[k] ? descriptorSize(kind, settings.descriptors) : 0);
    for (Eigen::Index i = 0; i < count; ++i) m.row(i) = rows[static_cast<size_t>(i)][k].transpose();
  }
  return db;
}

}  // namespace

Result<FragmentDatabase> bakeFragmentDatabase(const DatabaseBakeSettings& settings, ProgressSink* progress) {
  pinEigenBlocking();  // the same database on every CPU (EigenBlocking.h)
  auto baker = EntryBaker::create(settings, progress);
  if (!baker) return baker.error();
  SharedProgress shared(progress, settings.entryCount);
  std::vector<FragmentEntry> entries;
  std::vector<std::array<Descriptor, kDescriptorKindCount>> rows;
  Status baked = baker.value()->bake({{0, settings.entryCount}}, shared, [&](size_t, auto&& e, auto&& r) -> Status {
    entries = std::move(e);
    rows = std::move(r);
    return Ok{};
  });
  if (!baked) return baked.error();
  FragmentDatabase db = databaseOf(settings, std::move(entries), rows);
  if (Status st = calibrateDatabaseMatchErrors(db); !st) return st.error();
  return db;
}

// --- Checkpoints ---------------------------------------------------------------------------------

namespace {

constexpr const char* kCheckpointManifest = "bake.json";

Status validateCheckpointSettings(const DatabaseBakeSettings& settings, const DatabaseCheckpointSettings& c) {
  if (c.directory.empty()) return makeError(ErrorCode::InvalidArgument, "checkpoints need a directory");
  if (c.chunkEntries < 1) return makeError(ErrorCode::InvalidArgument, "checkpoint chunks need ≥ 1 entry");
  if (c.ranks < 1 || c.rank < 0 || c.rank >= c.ranks) {
    return makeError(ErrorCode::InvalidArgument, "checkpoint rank " + std::to_string(c.rank) + " of " +
                                                     std::to_string(c.ranks) + " ranks");
  }
  for (bool on : settings.kinds) {
    if (!on) return makeError(ErrorCode::InvalidArgument, "checkpointed bakes compute every descriptor kind");
  }
  return Ok{};
}

// The manifest text: the settings and the chunking, so a resume under other settings is refused.
std::string checkpointManifest(const DatabaseBakeSettings& settings, const DatabaseCheckpointSettings& c) {
  nlohmann::json doc = nlohmann::json::parse(describeDatabaseBake(settings));
  doc["chunk_entries"] = c.chunkEntries;
  return doc.dump(2) + "\n";
}

Status checkManifest(const DatabaseBakeSettings& settings, const DatabaseCheckpointSettings& c) {
  std::ifstream in(c.directory / kCheckpointManifest, std::ios::binary);
  if (!in) {
    return makeError(ErrorCode::FileNotFound, "no checkpoint manifest in '" + c.directory.string() + "'");
  }
  const std::string found((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (found != checkpointManifest(settings, c)) {
    return makeError(ErrorCode::InvalidArgument, "the checkpoints in '" + c.directory.string() +
                                                     "' belong to a bake with other settings; remove them or bake afresh");
  }
  return Ok{};
}

std::pair<int64_t, int64_t> chunkRange(const DatabaseBakeSettings& settings, const DatabaseCheckpointSettings& c,
                                       int64_t chunk) {
  const int64_t first = chunk * c.chunkEntries;
  return {first, std::min(settings.entryCount, first + c.chunkEntries)};
}

// The chunk as written, or an error if it is missing, unreadable or not the entries it should be.
Result<FragmentDatabase> readChunk(const DatabaseBakeSettings& settings, const DatabaseCheckpointSettings& c,
                                   int64_t chunk) {
  const std::filesystem::path path = fragmentDatabaseChunkPath(settings, c, chunk);
  auto pack = readPack(path);
  if (!pack) return pack.error();
  FragmentDatabase& db = pack.value().database;
  const auto [first, end] = chunkRange(settings, c, chunk);
  bool same = static_cast<int64_t>(db.entries.size()) == end - first && db.seed == settings.seed;
  for (int64_t i = first; same && i < end; ++i) {
    const std::string expected = entryName(settings.shapes[static_cast<size_t>(i) % settings.shapes.size()].name, i);
    same = db.entries[static_cast<size_t>(i - first)].asset.name == expected;
  }
  if (!same) return makeError(ErrorCode::PackCorrupt, "checkpoint '" + path.string() + "' holds other entries");
  return std::move(pack.value().database);
}

}  // namespace

std::string describeDatabaseBake(const DatabaseBakeSettings& s) {
  nlohmann::json shapes = nlohmann::json::array();
  for (const BaseShapeDefinition& d : s.shapes) {
    nlohmann::json shape = {{"name", d.name}, {"kind", baseShapeKindName(d.kind)},
                            {"size", {d.sizeM.x(), d.sizeM.y(), d.sizeM.z()}}, {"segments", d.segments},
                            {"noise", d.noiseAmplitude}, {"seed", d.seed}};
    if (d.kind == BaseShapeKind::Mesh) shape["mesh"] = d.meshPath.filename().generic_string();
    shapes.push_back(std::move(shape));
  }
  const Material& m = s.referenceMaterial;
  const TetMeshSettings& t = s.tetMesh;
  const ShapeDescriptorSettings& d = s.descriptors;
  nlohmann::json index = nlohmann::json::array();
  for (const std::optional<DescriptorIndexSettings>& x : s.index) {
    if (!x) {
      index.push_back("sized to the entries");  // defaultIndexSettings
      continue;
    }
    index.push_back({static_cast<int>(x->kind), x->trees, x->checks, x->targetPrecision, x->seed});
  }
  const nlohmann::json doc = {
      {"generator", std::string("brittle ") + BRITTLE_VERSION},
      {"shapes", shapes},
      {"entries", s.entryCount},
      {"seed", s.seed},
      {"fragments", {s.fragments.minCells, s.fragments.maxCells, s.fragments.planeCutFraction,
                     s.fragments.minVolumeFraction, s.fragments.maxAttempts}},
      {"material", {m.name, m.youngsModulusPa, m.poissonRatio, m.densityKgPerM3, m.tensileStrengthPa,
                    m.fractureEnergyJPerM2, m.rayleighAlphaPerS, m.rayleighBetaS, m.restitution}},
      {"physics", s.physics},
      {"tet_mesh", {t.targetTets, t.countTolerance, t.maxAttempts, t.cellSizeM, t.facetAngleDeg,
                    t.facetDistanceFraction, t.cellRadiusEdgeRatio, t.detectSharpFeatures, t.featureAngleDeg,
                    t.optimize, t.sliverBoundDeg, t.seed}},
      {"modes", s.modeCount},
      {"element", elementOrderName(s.elementOrder)},
      {"frame", {d.frame.eigenGapTolerance, d.frame.skewnessTolerance, d.frame.shapeTolerance,
                 d.frame.tieTolerance, d.frame.duplicateTolerance, d.frame.maxCandidates}},
      {"moment", {d.moment.maxOrder, d.moment.orderWeights}},
      {"voxel", {d.voxel.resolution, d.voxel.halfExtent}},
      {"voxel_improved", {d.voxelImproved.resolution, d.voxelImproved.halfExtent, d.voxelImproved.clampVoxels}},
      {"kinds", s.kinds},
      {"index", index},
      {"runtime", {s.runtimeFragments.fraction, s.runtimeFragments.targetTets, s.runtimeFragments.modeCount,
                   s.runtimeFragments.minSpeedMps, s.runtimeFragments.maxSpeedMps}}};
  return doc.dump();
}

int64_t fragmentDatabaseChunkCount(const DatabaseBakeSettings& settings, const DatabaseCheckpointSettings& c) {
  if (c.chunkEntries < 1 || settings.entryCount < 1) return 0;
  return (settings.entryCount + c.chunkEntries - 1) / c.chunkEntries;
}

std::filesystem::path fragmentDatabaseChunkPath(const DatabaseBakeSettings& settings,
                                                const DatabaseCheckpointSettings& c, int64_t chunk) {
  const auto [first, end] = chunkRange(settings, c, chunk);
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "entries-%09lld-%09lld.h5", static_cast<long long>(first),
                static_cast<long long>(end));
  return c.directory / buffer;
}

Status prepareFragmentDatabaseCheckpoints(const DatabaseBakeSettings& settings, const DatabaseCheckpointSettings& c) {
  if (Status st = validateCheckpointSettings(settings, c); !st) return st;
  std::error_code ec;
  std::filesystem::create_directories(c.directory, ec);
  if (ec || !std::filesystem::is_directory(c.directory)) {
    return makeError(ErrorCode::PackIoError, "cannot create the checkpoint directory '" + c.directory.string() + "'");
  }
  const bool hasManifest = std::filesystem::exists(c.directory / kCheckpointManifest);
  if (c.resume && hasManifest) return checkManifest(settings, c);
  if (!c.resume) {
    // Afresh: every chunk file of an earlier bake goes, whatever its settings were.
    for (const auto& file : std::filesystem::directory_iterator(c.directory, ec)) {
      const std::string name = file.path().filename().string();
      if (name.rfind("entries-", 0) == 0 && file.path().extension() == ".h5") std::filesystem::remove(file.path(), ec);
    }
  }
  return writeFileAtomically(c.directory / kCheckpointManifest, checkpointManifest(settings, c));
}

Result<DatabaseCheckpointReport> bakeFragmentDatabaseChunks(const DatabaseBakeSettings& settings,
                                                            const DatabaseCheckpointSettings& c,
                                                            ProgressSink* progress) {
  pinEigenBlocking();
  if (Status st = validateCheckpointSettings(settings, c); !st) return st.error();
  if (Status st = checkManifest(settings, c); !st) return st.error();
  DatabaseCheckpointReport report;
  std::vector<int64_t> missing;
  int64_t mine = 0;
  for (int64_t chunk = c.rank; chunk < fragmentDatabaseChunkCount(settings, c); chunk += c.ranks) {
    const auto [first, end] = chunkRange(settings, c, chunk);
    mine += end - first;
    if (c.resume && readChunk(settings, c, chunk)) {
      ++report.chunksReused;
      report.entriesReused += end - first;
    } else {
      missing.push_back(chunk);
    }
  }
  SharedProgress shared(progress, std::max<int64_t>(mine, 1));
  for (int64_t k = 0; k < report.entriesReused; ++k) shared.entryDone();
  if (missing.empty()) return report;

  auto baker = EntryBaker::create(settings, progress);
  if (!baker) return baker.error();
  std::vector<std::pair<int64_t, int64_t>> ranges;
  for (int64_t chunk : missing) ranges.push_back(chunkRange(settings, c, chunk));
  // Each chunk is written as soon as its entries are made, while the other workers go on.
  Status baked = baker.value()->bake(ranges, shared, [&](size_t r, auto&& entries, auto&& rows) -> Status {
    Pack pack;
    pack.database = databaseOf(settings, std::move(entries), rows);  // not calibrated: see the assembly
    if (Status st = writePack(pack, fragmentDatabaseChunkPath(settings, c, missing[r])); !st) return st.error();
    ++report.chunksBaked;
    report.entriesBaked += ranges[r].second - ranges[r].first;
    return Ok{};
  });
  if (!baked) return baked.error();
  return report;
}

Result<FragmentDatabase> assembleFragmentDatabase(const DatabaseBakeSettings& settings,
                                                  const DatabaseCheckpointSettings& c) {
  if (Status st = validateCheckpointSettings(settings, c); !st) return st.error();
  if (Status st = checkManifest(settings, c); !st) return st.error();
  FragmentDatabase db;
  for (int64_t chunk = 0; chunk < fragmentDatabaseChunkCount(settings, c); ++chunk) {
    auto part = readChunk(settings, c, chunk);
    if (!part) return Error{part.error().code, "checkpoint chunk " + std::to_string(chunk) + ": " + part.error().message};
    if (chunk == 0) {
      db = std::move(part).value();
      continue;
    }
    FragmentDatabase& p = part.value();
    for (FragmentEntry& e : p.entries) db.entries.push_back(std::move(e));
    for (size_t k = 0; k < kDescriptorKindCount; ++k) {
      DescriptorMatrix& m = db.descriptors[k];
      const Eigen::Index rows = m.rows();
      m.conservativeResize(rows + p.descriptors[k].rows(), Eigen::NoChange);
      m.bottomRows(p.descriptors[k].rows()) = p.descriptors[k];
    }
  }
  // Over the whole database, once: a chunk's own calibration would see a fraction of it.
  if (Status st = calibrateDatabaseMatchErrors(db); !st) return st.error();
  return db;
}

Result<FragmentDatabase> bakeFragmentDatabase(const DatabaseBakeSettings& settings,
                                              const DatabaseCheckpointSettings& checkpoints, ProgressSink* progress,
                                              DatabaseCheckpointReport* report) {
  if (Status st = prepareFragmentDatabaseCheckpoints(settings, checkpoints); !st) return st.error();
  auto baked = bakeFragmentDatabaseChunks(settings, checkpoints, progress);
  if (!baked) return baked.error();
  if (report) *report = baked.value();
  return assembleFragmentDatabase(settings, checkpoints);
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
                                                "runtime_fraction", "element"};
    if (Status st = checkKnownKeys(d, kKeys, where); !st) return st.error();
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
    if (d.contains("element")) {
      const auto order = d["element"].is_string() ? parseElementOrder(d["element"].get<std::string>()) : std::nullopt;
      if (!order) return makeError(ErrorCode::ParseError, where + ": \"element\" must be \"p1\" or \"p2\"");
      s.elementOrder = *order;
    }
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
