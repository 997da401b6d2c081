#include "SearchBench.h"

#include "BenchSupport.h"

#include "brittle/descriptors/MeshRefinement.h"

#include <array>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <string_view>

#include "brittle/core/Timing.h"
#include "brittle/database/FragmentMatcher.h"
#include "brittle/database/Pack.h"
#include "brittle/database/ScalingLaws.h"
#include "brittle/descriptors/MeshRefinement.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/precompute/RuntimeFragments.h"

namespace brittle::bench {
namespace {


struct Query {
  TriangleMesh surface;
  CanonicalFrames frames;
  std::array<DescriptorMatrix, kDescriptorKindCount> descriptors;
};

struct Physics {
  double massKg = 0.0;
  Eigen::Vector3d principalInertia = Eigen::Vector3d::Zero();
  Eigen::Vector3d frequenciesHz = Eigen::Vector3d::Zero();
};

Physics physicsOf(const ObjectAsset& a) {
  Physics p;
  p.massKg = a.massProperties.massKg;
  p.principalInertia = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(a.massProperties.inertiaKgM2).eigenvalues();
  p.frequenciesHz = a.modal.frequenciesHz.head<3>();
  return p;
}


void log(bool quiet, const char* format, auto... args) {
  if (quiet) return;
  std::fprintf(stderr, format, args...);
  std::fflush(stderr);
}

}  // namespace

Result<IndexChoice> parseIndexChoice(const std::string& text) {
  using Kind = DescriptorIndexSettings::Kind;
  IndexChoice c;
  c.label = text;
  // NAME:TREES:CHECKS for the kd-forest and the graphs and lists, NAME alone for the exact scans.
  const std::string name = text.substr(0, text.find(':'));
  auto kind = parseDescriptorIndexKind(name);
  const auto bad = [&] {
    return makeError(ErrorCode::InvalidArgument,
                     "index '" + text + "': expected kd-forest:TREES:CHECKS, hnsw:M:EF[:set], hnsw-binary:M:EF[:set], hnsw-pooled:M:EF[:set], hnsw-principal:M:EF[:set], faiss-hnsw:M:EF, "
                     "ivf:LISTS:PROBES, ivf-binary:LISTS:PROBES, faiss-ivf:LISTS:PROBES, faiss-binary-hnsw:M:EF, autotuned:PRECISION, brute-force or "
                     "faiss-binary-flat");
  };
  if (!kind) return bad();
  c.settings.kind = kind.value();
  if (kind.value() == Kind::BruteForce || kind.value() == Kind::FaissBinaryFlat) {
    if (text != name) return bad();
    return c;
  }
  if (kind.value() == Kind::Autotuned) {
    float precision = 0.0f;
    char tail = 0;
    if (std::sscanf(text.c_str() + name.size(), ":%f%c", &precision, &tail) != 1 || !(precision > 0.0f && precision <= 1.0f))
      return bad();
    c.settings.targetPrecision = precision;
    return c;
  }
  int trees = 0, checks = 0;
  char tail = 0;
  std::string rest = text.substr(name.size());
  // The graphs' ":set": a fragment's candidate frames in one walk (FragmentMatcherSettings::framesAsOneSet).
  constexpr std::string_view kSet = ":set";
  const bool graph = kind.value() == Kind::Hnsw || kind.value() == Kind::HnswBinary || kind.value() == Kind::HnswPooled ||
                     kind.value() == Kind::HnswPrincipal;
  if (graph && rest.size() > kSet.size() && rest.compare(rest.size() - kSet.size(), kSet.size(), kSet) == 0) {
    rest.resize(rest.size() - kSet.size());
    c.framesAsOneSet = true;
  }
  if (std::sscanf(rest.c_str(), ":%d:%d%c", &trees, &checks, &tail) != 2 || trees < 1 || checks < 1)
    return bad();
  c.settings.trees = trees;
  c.settings.checks = checks;
  return c;
}

Status runSearchBench(const SearchBenchSettings& s) {
  if (s.sizes.empty() || s.kinds.empty() || s.shapes.empty() || s.queries < 1) {
    return makeError(ErrorCode::InvalidArgument, "bench search needs sizes, kinds, shapes and queries");
  }
  const int64_t maxSize = *std::max_element(s.sizes.begin(), s.sizes.end());
  const bool anyVoxel = std::any_of(s.kinds.begin(), s.kinds.end(), [](auto k) { return k != DescriptorKind::Moment; });
  int64_t fullSize = anyVoxel ? std::min(maxSize, s.voxelSizeLimit) : 0;

  DatabaseBakeSettings bake;
  bake.shapes = s.shapes;
  bake.seed = s.seed;
  bake.physics = false;
  bake.descriptors.voxel.resolution = bake.descriptors.voxelImproved.resolution = s.voxelResolution;
  bake.descriptors.moment.maxOrder = s.momentOrder;
  bake.runtimeFragments.fraction = s.runtimeFraction;

  // Databases: every kind up to fullSize entries, moments only beyond (same seed: same fragments);
  // or a pack's, whole, with the queries described by its descriptor settings.
  FragmentDatabase full, big;
  if (!s.database.empty()) {
    auto t = SteadyClock::now();
    auto pack = readPack(s.database);
    if (!pack) return pack.error();
    full = std::move(pack.value().database);
    if (full.empty()) return makeError(ErrorCode::InvalidArgument, s.database.string() + " holds no fragment database (bake one with bake-db)");
    for (DescriptorKind kind : s.kinds) {
      if (full.descriptorsOf(kind).rows() != static_cast<Eigen::Index>(full.entries.size())) {
        return makeError(ErrorCode::InvalidArgument, s.database.string() + ": its database has no " + descriptorKindName(kind) + " descriptors");
      }
    }
    bake.descriptors = full.descriptorSettings;
    fullSize = static_cast<int64_t>(full.entries.size());
    log(s.quiet, "database: %lld entries read from %s in %.1f s\n", static_cast<long long>(fullSize), s.database.string().c_str(),
        secondsSince(t));
  } else {
    if (fullSize > 0) {
      auto t = SteadyClock::now();
      bake.entryCount = fullSize;
      auto db = bakeFragmentDatabase(bake);
      if (!db) return db.error();
      full = std::move(db).value();
      log(s.quiet, "database: %lld entries with every descriptor in %.1f s\n", static_cast<long long>(fullSize), secondsSince(t));
    }
    if (maxSize > fullSize) {
      auto t = SteadyClock::now();
      bake.entryCount = maxSize;
      bake.kinds = {true, false, false};
      auto db = bakeFragmentDatabase(bake);
      if (!db) return db.error();
      big = std::move(db).value();
      log(s.quiet, "database: %lld entries with moments in %.1f s\n", static_cast<long long>(maxSize), secondsSince(t));
    }
  }
  // What the CSV reports of the database: the pack's own where one was given.
  const int momentOrder = bake.descriptors.moment.maxOrder, voxelResolution = bake.descriptors.voxel.resolution;
  double runtimeFraction = s.runtimeFraction;
  if (!s.database.empty()) {
    const auto fromRuntime = std::count_if(full.entries.begin(), full.entries.end(), brokenByTheRuntime);
    runtimeFraction = static_cast<double>(fromRuntime) / static_cast<double>(full.entries.size());
  }

  // Queries: new fragments (another seed) in random poses and sizes.
  std::vector<TriangleMesh> bases;
  for (const auto& def : s.shapes) bases.push_back(makeBaseShape(def).value());
  std::optional<RuntimeFragmentSource> runtime;
  if (s.runtimeQueries) {
    RuntimeFragmentSettings rs = bake.runtimeFragments;
    rs.fraction = 1.0;
    auto source = RuntimeFragmentSource::build(s.shapes, bases, bake.referenceMaterial, rs);
    if (!source) return source.error();
    runtime.emplace(std::move(source).value());
  }
  std::vector<Query> queries;
  std::mt19937_64 rng(s.seed ^ 0x9e3779b97f4a7c15ull);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> size(0.05, 2.0), shift(-5.0, 5.0);
  std::ofstream costCsv(s.descriptorCsv);
  if (!costCsv) return makeError(ErrorCode::PackIoError, "cannot write " + s.descriptorCsv.string());
  std::array<std::vector<double>, kDescriptorKindCount> costUs, totalUs;
  std::vector<double> frameUs, cutUs, warmFrameUs, warmMomentTotalUs;
  double triangles = 0.0;
  for (int q = 0; q < s.queries; ++q) {
    const auto cutStart = SteadyClock::now();
    // Like the database bake, a draw that yields no acceptable fragment is redrawn from the next seed.
    uint64_t querySeed = fragmentEntrySeed(s.seed + 0x5eed0000ull, q);
    const size_t shape = static_cast<size_t>(q) % bases.size();
    auto draw = [&] {
      return runtime ? runtime->fragment(shape, querySeed) : generateFragment(bases[shape], bake.fragments, querySeed);
    };
    auto fragment = draw();
    for (int attempt = 1; !fragment && attempt < kEntryAttempts; ++attempt) {
      querySeed = fragmentEntrySeed(querySeed, 1);
      fragment = draw();
    }
    if (!fragment) return fragment.error();
    cutUs.push_back(1e6 * secondsSince(cutStart));
    Eigen::Vector4d g;
    for (int c = 0; c < 4; ++c) g[c] = normal(rng);  // one draw per statement: fixed order
    const Eigen::Matrix3d r = Eigen::Quaterniond(g[0], g[1], g[2], g[3]).normalized().toRotationMatrix();
    const double scale = size(rng);
    Eigen::Vector3d offset;
    for (int c = 0; c < 3; ++c) offset[c] = shift(rng);
    Query query;
    query.surface = subdivideToAtLeast(fragment.value(), s.minQueryTriangles);
    query.surface.vertices = ((query.surface.vertices * r.transpose()) * scale).rowwise() + offset.transpose();
    triangles += static_cast<double>(query.surface.faces.rows());
    auto t = SteadyClock::now();
    auto frames = computeCanonicalFrames(query.surface, bake.descriptors.frame);
    if (!frames) return frames.error();
    frameUs.push_back(1e6 * secondsSince(t));
    query.frames = std::move(frames).value();
    // Each step again at once, its code and data now in the caches: the cost when fragments come one
    // after another (as the runtime matches them) rather than each after an 8 ms cut.
    t = SteadyClock::now();
    if (auto again = computeCanonicalFrames(query.surface, bake.descriptors.frame); !again) return again.error();
    warmFrameUs.push_back(1e6 * secondsSince(t));
    for (DescriptorKind kind : kAllDescriptorKinds) {
      t = SteadyClock::now();
      auto d = computeShapeDescriptors(query.surface, query.frames, kind, bake.descriptors);
      if (!d) return d.error();
      const double us = 1e6 * secondsSince(t);
      costUs[static_cast<size_t>(kind)].push_back(us / static_cast<double>(query.frames.candidates.size()));
      totalUs[static_cast<size_t>(kind)].push_back(frameUs.back() + us);  // everything from a raw mesh
      if (kind == DescriptorKind::Moment) {
        t = SteadyClock::now();
        if (auto again = computeShapeDescriptors(query.surface, query.frames, kind, bake.descriptors); !again) return again.error();
        warmMomentTotalUs.push_back(warmFrameUs.back() + 1e6 * secondsSince(t));
      }
      query.descriptors[static_cast<size_t>(kind)] = std::move(d).value();
    }
    queries.push_back(std::move(query));
  }
  triangles /= static_cast<double>(queries.size());
  {
    // How many frames a query is searched in (one to four): a fragment's search costs about that many searches.
    std::array<int, 5> perCount{};
    double frames = 0.0;
    for (const Query& q : queries) {
      const size_t n = q.frames.candidates.size();
      ++perCount[std::min<size_t>(n, perCount.size() - 1)];
      frames += static_cast<double>(n);
    }
    log(s.quiet, "query frames: mean %.2f; 1: %d, 2: %d, 3: %d, 4+: %d queries\n", frames / static_cast<double>(queries.size()),
        perCount[1], perCount[2], perCount[3], perCount[4]);
  }
  costCsv << "stage,fragments,mean_triangles,median_us,p99_us,median_us_per_1k_triangles\n";
  auto costRow = [&](const std::string& stage, const std::vector<double>& us) {
    costCsv << stage << "," << us.size() << "," << triangles << "," << percentile(us, 0.5) << "," << percentile(us, 0.99)
            << "," << percentile(us, 0.5) * 1000.0 / triangles << "\n";
    log(s.quiet, "descriptor cost %-16s median %8.1f us (%.0f triangles)\n", stage.c_str(), percentile(us, 0.5), triangles);
  };
  costRow("fragment-cut", cutUs);  // generateFragment on the base shapes in turn (exact clipping)
  costRow("canonical-frame", frameUs);
  // Per candidate frame, from the frames (the moment kind reuses the frames' moment pass).
  for (DescriptorKind kind : kAllDescriptorKinds) costRow(descriptorKindName(kind), costUs[static_cast<size_t>(kind)]);
  // Frames + descriptors of every candidate frame: the whole cost of describing a new fragment.
  for (DescriptorKind kind : kAllDescriptorKinds) {
    costRow(std::string(descriptorKindName(kind)) + "-total", totalUs[static_cast<size_t>(kind)]);
  }
  costRow("canonical-frame-warm", warmFrameUs);
  costRow("moment-total-warm", warmMomentTotalUs);

  // Ground truth physics of the first queries: their own tet mesh and modes.
  const Material glass = bake.referenceMaterial;
  const int physicsQueries = std::min(s.physicsQueries, s.queries);
  // A query whose own bake fails (Mesh_3 can leave a degenerate tet on a thin fragment) has no
  // ground truth and is left out of the physical error, which the log and CSV count.
  std::vector<std::optional<Physics>> truth;
  int truthCount = 0;
  for (int q = 0; q < physicsQueries; ++q) {
    ObjectBakeSettings b;
    b.name = "query-" + std::to_string(q);
    b.material = glass;
    b.tetMesh.targetTets = s.physicsTets;
    // As the database bake meshes its entries: runtime fragments without feature protection (their
    // creases are the runtime mesh's zigzag), and a fragment in pieces meshed finer.
    b.tetMesh.detectSharpFeatures = !s.runtimeQueries;
    b.modal.modeCount = 3;
    auto asset = bakeSurface(queries[static_cast<size_t>(q)].surface, b);
    for (int finer = 0; finer < 2 && !asset && asset.error().code == ErrorCode::MeshingFailed; ++finer) {
      b.tetMesh.targetTets *= 2;
      asset = bakeSurface(queries[static_cast<size_t>(q)].surface, b);
    }
    if (!asset) {
      log(s.quiet, "ground truth: query %d skipped (%s)\n", q, asset.error().message.c_str());
      truth.emplace_back();
      continue;
    }
    truth.emplace_back(physicsOf(asset.value()));
    ++truthCount;
  }
  if (physicsQueries > 0) log(s.quiet, "ground truth: %d of %d query fragments meshed and solved\n", truthCount, physicsQueries);
  std::map<int64_t, FragmentEntry> physical;  // entries baked with physics on demand
  DatabaseBakeSettings physicsBake = bake;
  physicsBake.physics = true;
  physicsBake.kinds = {false, false, false};
  physicsBake.tetMesh.targetTets = s.physicsTets;
  physicsBake.modeCount = 3;
  DatabaseBakeSettings runtimePhysicsBake = physicsBake;  // as the database bake meshes runtime entries
  runtimePhysicsBake.tetMesh.detectSharpFeatures = false;

  std::ofstream csv(s.searchCsv);
  if (!csv) return makeError(ErrorCode::PackIoError, "cannot write " + s.searchCsv.string());
  csv << "entries,descriptor,index,trees,checks,build_s,memory_mb,query_median_us,query_p99_us,brute_median_us,"
         "speedup_vs_brute,recall_at_1,physics_queries,mass_err_median,inertia_err_median,frequency_err_median,"
         "database_runtime_fraction,query_source,moment_order,voxel_resolution,frames\n";

  for (int64_t n : s.sizes) {
    for (DescriptorKind kind : s.kinds) {
      const FragmentDatabase& db = kind == DescriptorKind::Moment && n > fullSize ? big : full;
      if (static_cast<int64_t>(db.entries.size()) < n) {
        log(s.quiet, "skip %s at %lld entries (%s %lld)\n", descriptorKindName(kind), static_cast<long long>(n),
            s.database.empty() ? "voxel kinds stop at" : "the pack's database holds", static_cast<long long>(fullSize));
        continue;
      }
      std::vector<IndexChoice> choices{parseIndexChoice("brute-force").value()};
      choices.insert(choices.end(), s.indices.begin(), s.indices.end());
      std::vector<int64_t> exactTop;
      std::vector<float> exactDistance;
      double bruteMedian = 0.0;
      for (const IndexChoice& choice : choices) {
        if (indexTakesBits(choice.settings.kind) && kind != DescriptorKind::Voxel) continue;  // 0/1 codes only
        if ((choice.settings.kind == DescriptorIndexSettings::Kind::HnswPooled ||
             choice.settings.kind == DescriptorIndexSettings::Kind::HnswPrincipal) && kind == DescriptorKind::Moment) continue;  // grids only
        const bool inverted = choice.settings.kind == DescriptorIndexSettings::Kind::Ivf ||
                              choice.settings.kind == DescriptorIndexSettings::Kind::IvfBinary ||
                              choice.settings.kind == DescriptorIndexSettings::Kind::FaissIvf;
        if (inverted && choice.settings.trees > n) {  // more lists than entries: the setting is for larger sizes
          log(s.quiet, "%7lld %-14s %-22s skipped: %d lists for %lld entries\n", static_cast<long long>(n),
              descriptorKindName(kind), descriptorIndexKindName(choice.settings.kind), choice.settings.trees,
              static_cast<long long>(n));
          continue;
        }
        FragmentMatcherSettings ms;
        ms.enabled = {false, false, false};
        ms.enabled[static_cast<size_t>(kind)] = true;
        ms.entryLimit = n;
        ms.indexOverride[static_cast<size_t>(kind)] = choice.settings;
        ms.framesAsOneSet = choice.framesAsOneSet;
        auto t = SteadyClock::now();
        auto matcher = FragmentMatcher::build(db, ms);
        if (!matcher) return matcher.error();
        const double buildS = secondsSince(t);
        std::vector<double> times;
        std::vector<FragmentMatch> top;
        for (const Query& q : queries) {
          t = SteadyClock::now();
          auto m = matcher.value().matchDescriptors(q.frames, q.descriptors[static_cast<size_t>(kind)], kind, 1);
          times.push_back(1e6 * secondsSince(t));
          if (!m) return m.error();
          top.push_back(m.value().front());
        }
        if (choice.settings.kind == DescriptorIndexSettings::Kind::BruteForce) {
          for (const auto& m : top) {
            exactTop.push_back(m.entry);
            exactDistance.push_back(m.distance);
          }
          bruteMedian = percentile(times, 0.5);
        }
        int hits = 0;
        for (size_t q = 0; q < top.size(); ++q) hits += top[q].entry == exactTop[q] || top[q].distance <= exactDistance[q];
        // Physical error of this setting's matches.
        std::vector<double> massErr, inertiaErr, freqErr;
        for (int q = 0; q < physicsQueries; ++q) {
          if (!truth[static_cast<size_t>(q)]) continue;
          const FragmentMatch& m = top[static_cast<size_t>(q)];
          auto it = physical.find(m.entry);
          if (it == physical.end()) {
            std::array<Descriptor, kDescriptorKindCount> unused;
            const FragmentEntry& e = db.entries[static_cast<size_t>(m.entry)];
            auto entry = bakeFragmentEntry(e.surface, e.asset.name, brokenByTheRuntime(e) ? runtimePhysicsBake : physicsBake, unused);
            if (!entry) continue;  // counted out like a query without ground truth
            it = physical.emplace(m.entry, std::move(entry).value()).first;
          }
          auto placed = instantiateEntry(it->second, glass, glass, m.queryFrame);
          if (!placed) return placed.error();
          const Physics p = physicsOf(placed.value());
          const Physics& g = *truth[static_cast<size_t>(q)];
          massErr.push_back(std::abs(p.massKg - g.massKg) / g.massKg);
          inertiaErr.push_back(maxRelative(p.principalInertia, g.principalInertia));
          freqErr.push_back(maxRelative(p.frequenciesHz, g.frequenciesHz));
        }
        const double median = percentile(times, 0.5);
        const double recall = static_cast<double>(hits) / static_cast<double>(top.size());
        csv << n << "," << descriptorKindName(kind) << "," << descriptorIndexKindName(choice.settings.kind) << ","
            << choice.settings.trees << "," << choice.settings.checks << "," << buildS << ","
            << static_cast<double>(matcher.value().index(kind)->memoryBytes()) / 1048576.0 << "," << median << ","
            << percentile(times, 0.99) << "," << bruteMedian << "," << bruteMedian / median << "," << recall << ","
            << massErr.size() << "," << percentile(massErr, 0.5) << "," << percentile(inertiaErr, 0.5) << ","
            << percentile(freqErr, 0.5) << "," << runtimeFraction << "," << (s.runtimeQueries ? "runtime" : "cut") << ","
            << momentOrder << "," << voxelResolution << ","
            << (choice.framesAsOneSet ? "set" : "each")  // parseIndexChoice sets it for the graphs only
            << "\n";
        csv.flush();
        log(s.quiet, "%7lld %-14s %-22s recall %.3f  median %8.1f us  p99 %8.1f us  (brute %8.1f us)  freq err %.3f\n",
            static_cast<long long>(n), descriptorKindName(kind), choice.label.c_str(), recall, median,
            percentile(times, 0.99), bruteMedian, percentile(freqErr, 0.5));
      }
    }
  }
  return Ok{};
}

}  // namespace brittle::bench
