// FragmentSizing.cpp — what a scene's fragments need: sceneFragments, chooseDebrisThreshold and
// chooseSearch (FragmentSizing.h).
#include "brittle/precompute/FragmentSizing.h"

#include <algorithm>
#include <cmath>

#include "brittle/core/Timing.h"
#include "brittle/database/FragmentMatcher.h"
#include "brittle/database/ScalingLaws.h"
#include "brittle/precompute/ModelSizing.h"
#include "Support.h"

namespace brittle {

using detail::median;

Result<std::vector<FragmentRecord>> sceneFragments(const ObjectAsset& asset, const Material& material,
                                                   const SceneObjectRange& range, int modes,
                                                   const ModelSizingSettings& settings, ProgressSink* progress) {
  if (modes < 1 || settings.points < 1 || settings.fragmentsPerImpact < 1 || range.impactors.empty() ||
      !(range.minSpeedMps > 0.0 && range.minSpeedMps <= range.maxSpeedMps)) {
    return makeError(ErrorCode::InvalidArgument, "fragment sizing: bad settings or scene range for " + asset.name);
  }
  SceneObjectRange top = range;
  top.minSpeedMps = range.maxSpeedMps;
  const std::vector<ImpactDesc> impacts = drawSceneImpacts(asset, top, settings.points, settings.seed);
  WorldSettings ws;
  ws.seed = settings.seed;
  ws.fracture.modeCount = modes;
  ws.fracture.debrisVolumeFraction = 0.0;                 // every fragment is studied
  ws.fracture.exactModesMaxTets = std::numeric_limits<int>::max();  // each gets its own modes: no database needed
  ws.fracture.exactModesMaxDof = 0;
  ws.fracture.exactModesBudgetDof = 0;
  Pack pack;
  pack.materials.push_back(material);
  pack.objects.push_back(asset);
  pack.objects.back().materialName = material.name;
  auto world = World::create(std::move(pack), ws);
  if (!world) return world.error();
  World& w = world.value();
  const double volume = asset.massProperties.volumeM3;
  std::vector<FragmentRecord> out;
  const std::string stage = "fragments of " + asset.name;
  for (size_t i = 0; i < impacts.size(); ++i) {
    reportProgress(progress, stage, static_cast<double>(i) / static_cast<double>(impacts.size()));
    if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, stage + ": interrupted");
    auto id = w.addObject({.asset = asset.name});
    if (!id) return id.error();
    ImpactDesc d = impacts[i];
    d.object = id.value();
    auto hit = w.impact(d);
    if (!hit) return hit.error();
    if (!hit.value().broken) {
      (void)w.removeObject(id.value());
      continue;
    }
    // The largest fragments that became objects (the exact path can refuse a sliver).
    std::vector<const FragmentResult*> pieces;
    for (const FragmentResult& f : hit.value().fragments)
      if (f.object.valid()) pieces.push_back(&f);
    std::stable_sort(pieces.begin(), pieces.end(), [](const FragmentResult* a, const FragmentResult* b) {
      return a->massProperties.volumeM3 > b->massProperties.volumeM3;
    });
    // Spread over the sizes, the largest and the smallest included: the debris threshold is
    // decided among the small ones.
    if (pieces.size() > static_cast<size_t>(settings.fragmentsPerImpact)) {
      std::vector<const FragmentResult*> spread;
      const size_t n = pieces.size(), k = static_cast<size_t>(settings.fragmentsPerImpact);
      for (size_t j = 0; j < k; ++j) spread.push_back(pieces[k == 1 ? 0 : j * (n - 1) / (k - 1)]);
      pieces = std::move(spread);
    }
    for (const FragmentResult* f : pieces) {
      auto fragmentAsset = w.objectAsset(f->object);
      if (!fragmentAsset) continue;
      const ObjectAsset& fa = *fragmentAsset.value();
      if (fa.modal.frequenciesHz.size() < 3) continue;
      FragmentRecord r;
      r.object = asset.name;
      r.material = material.name;
      r.volumeFraction = f->massProperties.volumeM3 / volume;
      r.surface = f->surface;
      r.frequenciesHz = fa.modal.frequenciesHz.head<3>();
      // Hit again by each impactor at the top speed, at one drawn point of the fragment's own
      // mesh, in a world of its own whose fragments stay surfaces.
      Pack alone;
      alone.materials.push_back(material);
      alone.objects.push_back(fa);
      WorldSettings again = ws;
      again.fracture.matchFragments = false;
      auto single = World::create(std::move(alone), again);
      if (!single) return single.error();
      for (const ImpactDesc& a : drawSceneImpacts(fa, top, 1, settings.seed + i)) {
        auto piece = single.value().addObject({.asset = fa.name});
        if (!piece) return piece.error();
        ImpactDesc e = a;
        e.object = piece.value();
        auto second = single.value().impact(e);
        if (second && second.value().broken) r.brokeAgain = true;
        if (single.value().isAlive(piece.value())) (void)single.value().removeObject(piece.value());
      }
      out.push_back(std::move(r));
    }
    // Remove what is left of this impact: the next one starts from a fresh object.
    for (const FragmentResult& f : hit.value().fragments)
      if (f.object.valid() && w.isAlive(f.object)) (void)w.removeObject(f.object);
  }
  reportProgress(progress, stage, 1.0);
  return out;
}

DebrisSizing chooseDebrisThreshold(const std::string& object, const std::vector<FragmentRecord>& fragments) {
  DebrisSizing d;
  d.object = object;
  for (const FragmentRecord& f : fragments) {
    if (f.object != object) continue;
    ++d.fragments;
    if (!f.brokeAgain) continue;
    ++d.brokeAgain;
    if (!(f.volumeFraction >= d.smallestBrokenFraction)) d.smallestBrokenFraction = f.volumeFraction;
  }
  d.debrisVolumeFraction = d.brokeAgain > 0 ? std::clamp(0.5 * d.smallestBrokenFraction, 0.001, 0.5) : 0.5;
  return d;
}

double searchBytesCompared(const DescriptorIndexSettings& index, int64_t rows, int64_t cols) {
  using Kind = DescriptorIndexSettings::Kind;
  const auto n = static_cast<double>(rows);
  const double rowBytes = indexTakesBits(index.kind) ? static_cast<double>(cols) / 8.0 : 4.0 * static_cast<double>(cols);
  const double ef = std::min<double>(index.checks, n);
  const double walked = std::min(static_cast<double>(index.checks) * index.trees, n);  // ef × M
  switch (index.kind) {
    case Kind::BruteForce:
    case Kind::FaissBinaryFlat: return n * rowBytes;
    case Kind::KdForest:
    case Kind::Autotuned: return ef * rowBytes;
    case Kind::Hnsw:
    case Kind::HnswBinary:
    case Kind::FaissHnsw:
    case Kind::FaissBinaryHnsw: return walked * rowBytes;
    case Kind::HnswPooled: return walked * 4.0 * 512.0 + ef * rowBytes;  // 8³ block sums
    case Kind::HnswPrincipal: return walked * 4.0 * 64.0 + ef * rowBytes;  // their first 64 components
    case Kind::Ivf: {
      // IvfBackend.cpp (InvertedFileKeys): rows of 17–128 values are filed by 16 components and two
      // norms; wider rows by 64 components, lists chosen by the centroids' first 32, rows scanned by
      // their first 16 and three bounds, and the few rows the bounds cannot rule out measured whole
      // (counted as one).
      using Keys = InvertedFileKeys;
      const double scanned = std::min(n, index.checks * std::ceil(n / index.trees));
      if (cols > Keys::kMaxProjectedDims) {
        return 4.0 * (index.trees * static_cast<double>(Keys::kWideListDims) + scanned * static_cast<double>(Keys::kWidePrefixDims + 3)) +
               rowBytes;
      }
      const double key = cols > Keys::kKeyDims ? static_cast<double>(Keys::kKeyDims + 2) : static_cast<double>(cols);
      return 4.0 * (index.trees * key + scanned * key) + rowBytes;
    }
    case Kind::IvfBinary: {
      // IvfBinaryBackend.cpp: 32-byte keys of the centroids and of the probed lists' rows, and a code
      // for the few rows the key cannot rule out (counted as one row).
      const double scanned = std::min(n, index.checks * std::ceil(n / index.trees));
      return 32.0 * (index.trees + scanned) + rowBytes;
    }
    case Kind::FaissIvf: return (index.trees + std::min(n, index.checks * std::ceil(n / index.trees))) * rowBytes;
  }
  return n * rowBytes;
}

DescriptorIndexSettings indexAtPrecision(const DescriptorIndexSettings& stored, double precision) {
  using Kind = DescriptorIndexSettings::Kind;
  if (precision == 0.0) return {.kind = Kind::BruteForce};
  DescriptorIndexSettings s = stored;
  if (s.kind == Kind::BruteForce || s.kind == Kind::FaissBinaryFlat || s.kind == Kind::Autotuned) return s;
  const double scaled = std::max(1.0, std::round(precision * s.checks));
  const bool lists = s.kind == Kind::Ivf || s.kind == Kind::IvfBinary || s.kind == Kind::FaissIvf;
  s.checks = static_cast<int>(std::min(scaled, lists ? static_cast<double>(s.trees) : 1e9));
  return s;
}

Result<SearchSizing> chooseSearch(const FragmentDatabase& database, const std::vector<FragmentRecord>& fragments,
                                  const std::vector<Material>& materials, double targetError,
                                  const ModelSizingSettings& settings) {
  if (database.empty() || !database.hasPhysics() || fragments.empty() || settings.searchPrecision.empty()) {
    return makeError(ErrorCode::InvalidArgument, "search sizing: needs a database with physics, fragments and a precision ladder");
  }
  for (double p : settings.searchPrecision) {
    if (!(std::isfinite(p) && p >= 0.0)) {
      return makeError(ErrorCode::InvalidArgument, "search sizing: precisions must be finite and ≥ 0 (0: exact), got " + std::to_string(p));
    }
  }
  std::vector<const Material*> material;
  for (const FragmentRecord& f : fragments) {
    auto m = std::find_if(materials.begin(), materials.end(), [&](const Material& x) { return x.name == f.material; });
    if (m == materials.end()) return makeError(ErrorCode::InvalidArgument, "search sizing: no material '" + f.material + "'");
    material.push_back(&*m);
  }
  SearchSizing out;
  out.fragments = static_cast<int>(fragments.size());
  for (DescriptorKind kind : kAllDescriptorKinds) {
    const DescriptorMatrix& rows = database.descriptorsOf(kind);
    if (rows.cols() == 0) continue;
    std::vector<DescriptorIndexSettings> tried;
    for (double precision : settings.searchPrecision) {
      const DescriptorIndexSettings index = indexAtPrecision(database.indexSettings[static_cast<size_t>(kind)], precision);
      // A precision that lands on an index already tried (a clamped probe count, an exact kind) is not tried twice.
      if (std::any_of(tried.begin(), tried.end(), [&](const DescriptorIndexSettings& x) {
            return x.kind == index.kind && x.trees == index.trees && x.checks == index.checks;
          })) {
        continue;
      }
      tried.push_back(index);
      FragmentMatcherSettings ms;
      for (DescriptorKind k : kAllDescriptorKinds) ms.enabled[static_cast<size_t>(k)] = k == kind;
      ms.indexOverride[static_cast<size_t>(kind)] = index;
      auto matcher = FragmentMatcher::build(database, ms);
      if (!matcher) return matcher.error();
      SearchTrial t;
      t.kind = kind;
      t.precision = precision;
      t.index = index;
      t.bytesCompared = searchBytesCompared(index, rows.rows(), rows.cols());
      std::vector<double> errors, times;
      for (size_t i = 0; i < fragments.size(); ++i) {
        const auto start = SteadyClock::now();
        auto m = matcher.value().match(fragments[i].surface, kind, 1);
        if (!m) continue;
        auto placed = instantiateEntry(database.entries[static_cast<size_t>(m.value().front().entry)],
                                       database.referenceMaterial, *material[i], m.value().front().queryFrame);
        times.push_back(1e3 * secondsSince(start));
        if (!placed || placed.value().modal.frequenciesHz.size() < 3) continue;
        errors.push_back(matchFrequencyError(placed.value().modal.frequenciesHz, fragments[i].frequenciesHz));
        t.distanceErrors.emplace_back(m.value().front().distance, errors.back());
        ++t.matched;
      }
      t.medianFrequencyError = median(errors);
      t.medianMatchMs = median(times);
      out.trials.push_back(t);
    }
  }
  if (out.trials.empty()) return makeError(ErrorCode::InvalidArgument, "search sizing: the database has no descriptors");
  // The cheapest that meets the target (fewest bytes compared, the first tried on ties); else
  // the most accurate. Measured times are not weighed: they would make the sized pack differ from
  // run to run.
  const SearchTrial* best = nullptr;
  for (const SearchTrial& t : out.trials)
    if (t.medianFrequencyError <= targetError && (!best || t.bytesCompared < best->bytesCompared)) best = &t;
  out.targetMet = best != nullptr;
  if (!best)
    for (const SearchTrial& t : out.trials)
      if (std::isfinite(t.medianFrequencyError) && (!best || t.medianFrequencyError < best->medianFrequencyError)) best = &t;
  if (!best) best = &out.trials.front();
  out.kind = best->kind;
  out.precision = best->precision;
  out.index = best->index;
  out.medianFrequencyError = best->medianFrequencyError;
  out.medianMatchMs = best->medianMatchMs;
  out.distanceErrors = best->distanceErrors;
  return out;
}

}  // namespace brittle
