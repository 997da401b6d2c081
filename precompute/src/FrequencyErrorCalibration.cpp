#include "brittle/precompute/FrequencyErrorCalibration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "brittle/precompute/ModelSizing.h"
#include "brittle/runtime/FragmentModes.h"
#include "brittle/runtime/PolynomialModes.h"

namespace brittle {
namespace {

Error calibrationError(const std::string& message) { return makeError(ErrorCode::InvalidArgument, "frequency errors: " + message); }

Status validateCalibration(const FrequencyErrorCalibrationSettings& s) {
  if (s.scene.empty() &&
      (s.speedsMps.empty() || std::any_of(s.speedsMps.begin(), s.speedsMps.end(), [](double v) { return !(v > 0.0) || !std::isfinite(v); })))
    return calibrationError("speeds must be finite and > 0, at least one");
  if (s.seeds < 1 || s.maxFragmentsPerImpact < 1) return calibrationError("seeds and max fragments must be ≥ 1");
  if (s.degree < 3 || s.degree > kMaxPolynomialModeDegree)
    return calibrationError("degree " + std::to_string(s.degree) + " is outside [3, " + std::to_string(kMaxPolynomialModeDegree) + "]");
  if (s.checkMaxDof < 0 || s.referenceMaxTets < 1) return calibrationError("check max DOF must be ≥ 0 and reference max tets ≥ 1");
  if (s.bins.bins < 1) return calibrationError("bins must be ≥ 1");
  return Ok{};
}

// One fragment's sample; false when it has no truth (too large, or its analysis failed) or no
// Ritz values.
bool measureFragment(const ObjectAsset& asset, const TetTopology& topology, const Material& material, const FractureState& fracture,
             const FragmentResult& fr, int label, const FrequencyErrorCalibrationSettings& s, FrequencyErrorSample& out) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto sub = fragmentSubMesh(asset.tetMesh, topology, fracture.nodeLabels, fracture.edgeCuts, label);
  if (!sub || sub.value().mesh.tets.rows() > s.referenceMaxTets) return false;
  ExactModesSettings rs;
  rs.modeCount = kMeshRatioModes;
  rs.elementOrder = ElementOrder::P2;
  auto truth = exactFragmentAsset(sub.value(), material, rs, asset.name + ".f" + std::to_string(label) + ".truth");
  if (!truth || truth.value().modal.frequenciesHz.size() < kMeshRatioModes) return false;
  const Eigen::VectorXd& truthHz = truth.value().modal.frequenciesHz;
  // As the World: the Ritz values from the surface's moments, degree p and p − 2 (ImpactStages.cpp, placeEntry).
  auto high = polynomialModes(fr.surface, material, s.degree, /*withShapes=*/false, kMeshRatioModes);
  auto low = polynomialModes(fr.surface, material, s.degree - 2, /*withShapes=*/false, kMeshRatioModes);
  if (!high || !low) return false;
  out.fragment = label;
  out.truthF1Hz = truthHz[0];
  out.ritzIndicator = matchFrequencyError(low.value().frequenciesHz, high.value().frequenciesHz);  // as placeEntry
  out.ritzError = matchFrequencyError(high.value().frequenciesHz, truthHz);
  out.checkDof = fragmentCutDof(asset.tetMesh, topology, fracture.nodeLabels, label, ElementOrder::P1, CutCells::Prisms);
  out.checkIndicator = out.checkError = out.checkP2Indicator = out.checkP2Error = nan;
  if (out.checkDof > 0 && out.checkDof <= s.checkMaxDof) {
    auto check = fragmentSubMesh(asset.tetMesh, topology, fracture.nodeLabels, fracture.edgeCuts, label, CutCells::Prisms);
    auto checkIn = [&](ElementOrder order, double& indicator, double& error) {
      auto ratios = check ? meshFrequencyRatios(check.value(), material, s.degree, kMeshRatioModes, order)
                          : Result<MeshFrequencyRatios>(check.error());
      if (!ratios) return;
      Eigen::VectorXd checked = high.value().frequenciesHz;
      applyMeshRatios(checked, ratios.value());
      indicator = meshGain(ratios.value());
      error = matchFrequencyError(checked, truthHz);
    };
    checkIn(ElementOrder::P1, out.checkIndicator, out.checkError);
    if (s.p2Checks) checkIn(ElementOrder::P2, out.checkP2Indicator, out.checkP2Error);
  }
  return std::isfinite(out.ritzIndicator) && std::isfinite(out.ritzError);
}

}  // namespace

std::vector<size_t> piecesSpreadOverSizes(const ImpactResult& r, int count) {
  std::vector<size_t> order;
  for (size_t i = 0; i < r.fragments.size(); ++i)
    if (!r.fragments[i].debris) order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return r.fragments[a].massProperties.volumeM3 > r.fragments[b].massProperties.volumeM3;
  });
  const auto k = static_cast<size_t>(count);
  if (order.size() <= k) return order;
  std::vector<size_t> spread;
  const size_t n = order.size();
  for (size_t j = 0; j < k; ++j) spread.push_back(order[k == 1 ? 0 : j * (n - 1) / (k - 1)]);
  return spread;
}

ImpactDesc seededImpact(const ObjectAsset& a, ObjectId id, uint64_t seed, double speedMps) {
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 11);
  const Eigen::Index f = static_cast<Eigen::Index>(rng() % static_cast<uint64_t>(a.surfaceFaces.rows()));
  const Eigen::Vector3d p0 = a.tetMesh.nodes.row(a.surfaceFaces(f, 0)), p1 = a.tetMesh.nodes.row(a.surfaceFaces(f, 1)),
                        p2 = a.tetMesh.nodes.row(a.surfaceFaces(f, 2));
  ImpactDesc d;
  d.object = id;
  d.pointWorld = (p0 + p1 + p2) / 3.0;
  d.normalWorld = (p1 - p0).cross(p2 - p0).normalized();
  d.speedMps = speedMps;
  d.impactorMassKg = 0.2 * a.massProperties.massKg;
  d.impactorRadiusM = 0.05 * (a.tetMesh.nodes.colwise().maxCoeff() - a.tetMesh.nodes.colwise().minCoeff()).norm();
  return d;
}

Result<FrequencyErrorCalibration> measureFrequencyErrors(const Pack& pack, const FrequencyErrorCalibrationSettings& s,
                                                         ProgressSink* progress) {
  if (Status st = validateCalibration(s); !st) return st.error();
  if (pack.objects.empty()) return calibrationError("the pack has no object");
  auto inPack = [&](const std::string& name) {
    return std::find_if(pack.objects.begin(), pack.objects.end(), [&](const ObjectAsset& a) { return a.name == name; });
  };
  auto inScene = [&](const std::string& name) {
    return std::find_if(s.scene.begin(), s.scene.end(), [&](const SceneObjectRange& r) { return r.name == name; });
  };
  for (const std::string& name : s.objects) {
    if (inPack(name) == pack.objects.end()) return calibrationError("no object '" + name + "' in the pack");
    if (!s.scene.empty() && inScene(name) == s.scene.end()) return calibrationError("object '" + name + "' is not in the scene");
  }
  // Each object's impacts, with the seed of the World that makes each: the steel ball at every
  // speed and seed, or the scene's own (drawSceneImpacts, its points drawn from firstSeed).
  struct ObjectImpacts {
    const ObjectAsset* asset;
    std::vector<std::pair<ImpactDesc, uint64_t>> impacts;
  };
  std::vector<ObjectImpacts> jobs;
  auto wanted = [&](const std::string& name) { return s.objects.empty() || std::find(s.objects.begin(), s.objects.end(), name) != s.objects.end(); };
  if (s.scene.empty()) {
    for (const ObjectAsset& a : pack.objects) {
      if (!wanted(a.name)) continue;
      ObjectImpacts job{&a, {}};
      for (double speed : s.speedsMps)
        for (int k = 0; k < s.seeds; ++k) {
          const uint64_t seed = s.firstSeed + static_cast<uint64_t>(k);
          job.impacts.emplace_back(seededImpact(a, ObjectId{}, seed, speed), seed);
        }
      jobs.push_back(std::move(job));
    }
  } else {
    for (const SceneObjectRange& range : s.scene) {
      if (!wanted(range.name)) continue;
      const auto a = inPack(range.name);
      if (a == pack.objects.end()) return calibrationError("the scene's object '" + range.name + "' is not in the pack");
      if (range.impactors.empty() || !(range.minSpeedMps > 0.0 && range.minSpeedMps <= range.maxSpeedMps) || !std::isfinite(range.maxSpeedMps))
        return calibrationError("the scene's object '" + range.name + "' needs an impactor and 0 < min speed ≤ max speed");
      ObjectImpacts job{&*a, {}};
      const std::vector<ImpactDesc> drawn = drawSceneImpacts(*a, range, s.seeds, s.firstSeed);
      for (size_t k = 0; k < drawn.size(); ++k) job.impacts.emplace_back(drawn[k], s.firstSeed + k);
      jobs.push_back(std::move(job));
    }
  }
  FrequencyErrorCalibration out;
  size_t impacts = 0, done = 0;
  for (const ObjectImpacts& job : jobs) impacts += job.impacts.size();
  out.impacts = static_cast<int>(impacts);
  for (const ObjectImpacts& job : jobs) {
    const ObjectAsset* asset = job.asset;
    const size_t before = out.samples.size();
    auto material = std::find_if(pack.materials.begin(), pack.materials.end(), [&](const Material& m) { return m.name == asset->materialName; });
    if (material == pack.materials.end()) return calibrationError("object '" + asset->name + "' names no material of the pack");
    auto topology = buildTetTopology(asset->tetMesh);
    if (!topology) return topology.error();
    for (const auto& [desc, seed] : job.impacts) {
      reportProgress(progress, "frequency errors", static_cast<double>(done++) / static_cast<double>(impacts));
      if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, "frequency errors: interrupted");
      WorldSettings ws;
      ws.seed = seed;
      ws.fracture.matchFragments = false;  // the fragments alone: their bodies are measured here
      ws.fracture.exactModesMaxTets = 0;   // nor their own analyses, made on the workers and dropped
      Pack one;
      one.materials = {*material};
      one.objects = {*asset};
      auto world = World::create(std::move(one), ws);
      if (!world) return world.error();
      auto id = world.value().addObject({.asset = asset->name});
      if (!id) return id.error();
      ImpactDesc hitDesc = desc;
      hitDesc.object = id.value();
      auto hit = world.value().impact(hitDesc);
      if (!hit) return hit.error();
      if (!hit.value().broken) continue;
      const ImpactResult& r = hit.value();
      for (size_t i : piecesSpreadOverSizes(r, s.maxFragmentsPerImpact)) {
        FrequencyErrorSample sample;
        sample.object = asset->name;
        sample.speedMps = desc.speedMps;
        sample.seed = seed;
        if (measureFragment(*asset, topology.value(), *material, r.fracture, r.fragments[i], static_cast<int>(i), s, sample))
          out.samples.push_back(std::move(sample));
      }
    }
    out.piecesPerObject.emplace_back(asset->name, static_cast<int>(out.samples.size() - before));
  }
  reportProgress(progress, "frequency errors", 1.0);
  return out;
}

Result<FrequencyErrorModels> fitFrequencyErrors(const std::vector<FrequencyErrorSample>& samples,
                                                const FrequencyErrorCalibrationSettings& s) {
  if (Status st = validateCalibration(s); !st) return st.error();
  std::vector<std::pair<double, double>> ritz, checked, checkedP2;
  for (const FrequencyErrorSample& x : samples) {
    ritz.emplace_back(x.ritzIndicator, x.ritzError);
    if (std::isfinite(x.checkIndicator) && std::isfinite(x.checkError)) checked.emplace_back(x.checkIndicator, x.checkError);
    if (std::isfinite(x.checkP2Indicator) && std::isfinite(x.checkP2Error)) checkedP2.emplace_back(x.checkP2Indicator, x.checkP2Error);
  }
  if (ritz.empty()) return calibrationError("no fragment to calibrate on (no impact broke an object, or none had a truth): more speeds or seeds");
  FrequencyErrorModels models;
  auto ritzModel = fitMatchErrors(std::move(ritz), s.bins);
  if (!ritzModel) return ritzModel.error();
  models.ritz = std::move(ritzModel).value();
  models.degree = s.degree;
  for (auto [pairs, model] : {std::pair{&checked, &models.checked}, std::pair{&checkedP2, &models.checkedP2}}) {
    if (pairs->empty()) continue;
    auto fitted = fitMatchErrors(std::move(*pairs), s.bins);
    if (!fitted) return fitted.error();
    *model = std::move(fitted).value();
  }
  return models;
}

Result<FrequencyErrorCalibration> calibrateFrequencyErrors(const Pack& pack, const FrequencyErrorCalibrationSettings& s,
                                                           ProgressSink* progress) {
  auto out = measureFrequencyErrors(pack, s, progress);
  if (!out) return out;
  auto models = fitFrequencyErrors(out.value().samples, s);
  if (!models) return models.error();
  out.value().models = std::move(models).value();
  return out;
}

}  // namespace brittle
