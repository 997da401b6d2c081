// ModelSizing.cpp — sizeObjectModes, sizeScene and writeSizedManifest (ModelSizing.h).
#include "brittle/precompute/ModelSizing.h"

#include "brittle/database/MatchErrors.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <random>

#include "brittle/core/AtomicFile.h"
#include "brittle/core/Timing.h"
#include "brittle/precompute/FrequencyErrorCalibration.h"
#include "brittle/precompute/FullFemReference.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/runtime/World.h"
#include "Support.h"

namespace brittle {
namespace {

using detail::kInf;
using detail::unit;
using detail::median;

/// The fewest fragments a scene's own match-error model is fitted to (two per bin of four bins);
/// with fewer, the sized pack keeps the database's leave-one-out model.
constexpr size_t kSceneMatchErrorSamples = 8;

}  // namespace

std::vector<ImpactDesc> drawSceneImpacts(const ObjectAsset& asset, const SceneObjectRange& range, int points, uint64_t seed) {
  const auto& nodes = asset.tetMesh.nodes;
  const auto& faces = asset.surfaceFaces;
  std::vector<double> cumulative(static_cast<size_t>(faces.rows()));
  double area = 0.0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = nodes.row(faces(f, 0)), b = nodes.row(faces(f, 1)), c = nodes.row(faces(f, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
    cumulative[static_cast<size_t>(f)] = area;
  }
  std::mt19937_64 rng(seed ^ 0x5CE7E5151ull);
  std::vector<ImpactDesc> impacts;
  for (int p = 0; p < points; ++p) {
    // A sphere hits a point drawn by area, along the face's normal.
    const double u = unit(rng) * area;
    const auto f = static_cast<Eigen::Index>(
        std::min<size_t>(std::lower_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin(), cumulative.size() - 1));
    const Eigen::Vector3d a = nodes.row(faces(f, 0)), b = nodes.row(faces(f, 1)), c = nodes.row(faces(f, 2));
    // The ground meets a body that falls with a random orientation at its lowest point: the
    // surface node farthest along a direction drawn uniformly on the sphere (a flat face on flat
    // ground has no Hertz contact).
    const double z = 2.0 * unit(rng) - 1.0, phi = 2.0 * std::numbers::pi * unit(rng);
    const Eigen::Vector3d down(std::sqrt(1.0 - z * z) * std::cos(phi), std::sqrt(1.0 - z * z) * std::sin(phi), z);
    Eigen::Index lowest = faces(0, 0);
    for (Eigen::Index i = 0; i < faces.size(); ++i) {
      const Eigen::Index n = faces.data()[i];
      if (nodes.row(n).dot(down) > nodes.row(lowest).dot(down)) lowest = n;
    }
    for (const SceneImpactor& imp : range.impactors) {
      for (double speed : {range.minSpeedMps, range.maxSpeedMps}) {
        ImpactDesc d;
        if (imp.ground()) {
          d.pointWorld = nodes.row(lowest).transpose();
          d.normalWorld = down;
        } else {
          d.pointWorld = (a + b + c) / 3.0;
          d.normalWorld = (b - a).cross(c - a).normalized();
        }
        d.speedMps = speed;
        d.impactorMassKg = imp.massKg;
        d.impactorRadiusM = imp.radiusM;
        d.impactorYoungsModulusPa = imp.material.youngsModulusPa;
        d.impactorPoissonRatio = imp.material.poissonRatio;
        impacts.push_back(d);
        if (range.minSpeedMps == range.maxSpeedMps) break;
      }
    }
  }
  return impacts;
}

Result<ObjectSizing> sizeObjectModes(const ObjectAsset& asset, const Material& material, const SceneObjectRange& range,
                                     double targetError, const ModelSizingSettings& settings, ProgressSink* progress) {
  std::vector<int> ladder = settings.modeLadder;
  std::sort(ladder.begin(), ladder.end());
  ladder.erase(std::unique(ladder.begin(), ladder.end()), ladder.end());
  if (ladder.empty() || ladder.front() < 1 || settings.points < 1 || settings.timingRepeats < 1 ||
      !(settings.modeClusterGap >= 0.0 && settings.modeClusterGap < 1.0) ||
      settings.referenceStepsPerContact < 2 || !(targetError > 0.0) || range.impactors.empty() ||
      !(range.minSpeedMps > 0.0 && range.minSpeedMps <= range.maxSpeedMps)) {
    return makeError(ErrorCode::InvalidArgument, "model sizing: bad settings or scene range for " + asset.name);
  }
  const int stored = static_cast<int>(asset.modal.eigenvaluesRad2PerS2.size());
  if (stored < ladder.front()) {
    return makeError(ErrorCode::InvalidArgument, "model sizing: " + asset.name + " holds " + std::to_string(stored) +
                                                     " modes, fewer than the ladder's first count");
  }
  ladder.erase(std::remove_if(ladder.begin(), ladder.end(), [&](int k) { return k > stored; }), ladder.end());
  // A count inside a cluster of nearly equal frequencies keeps the whole cluster (the count after
  // the stored modes is unknown, so the last stored one ends a cluster).
  const Eigen::VectorXd& hz = asset.modal.frequenciesHz;
  for (int& k : ladder) {
    while (k < stored && k < hz.size() && hz[k] - hz[k - 1] < settings.modeClusterGap * hz[k - 1]) ++k;
  }
  ladder.erase(std::unique(ladder.begin(), ladder.end()), ladder.end());

  const std::vector<ImpactDesc> impacts = drawSceneImpacts(asset, range, settings.points, settings.seed);

  Pack pack;
  pack.materials.push_back(material);
  pack.objects.push_back(asset);
  pack.objects.back().materialName = material.name;
  ObjectSizing out;
  out.object = asset.name;
  out.elementOrder = asset.elementOrder;
  out.impacts = static_cast<int>(impacts.size());
  std::vector<double> reference(impacts.size(), 0.0);
  const std::string stage = "sizing " + asset.name;
  // Largest count first: its runs give the load the reference is solved under.
  for (auto k = ladder.rbegin(); k != ladder.rend(); ++k) {
    WorldSettings ws;
    ws.seed = settings.seed;
    ws.fracture.modeCount = *k;
    ws.fracture.staticCorrection = true;
    ws.fracture.matchFragments = false;
    auto world = World::create(Pack(pack), ws);
    if (!world) return world.error();
    ModeTrial trial;
    trial.modes = *k;
    std::vector<double> times;
    for (size_t i = 0; i < impacts.size(); ++i) {
      double peak = 0.0;
      for (int rep = 0; rep < settings.timingRepeats; ++rep) {
        auto id = world.value().addObject({.asset = asset.name});
        if (!id) return id.error();
        ImpactDesc d = impacts[i];
        d.object = id.value();
        auto r = world.value().impact(d);
        if (!r) return r.error();
        if (world.value().isAlive(d.object)) (void)world.value().removeObject(d.object);
        times.push_back(1e3 * r.value().times.totalS());
        peak = r.value().peakPrincipalStressPa;
        if (k == ladder.rbegin() && rep == 0) {
          FullFemSettings fs;
          fs.stepsPerContact = settings.referenceStepsPerContact;
          fs.extraS = r.value().ringDownS;
          fs.elementOrder = asset.elementOrder;
          const auto start = SteadyClock::now();
          auto ref = solveFullFemImpact(asset.tetMesh, material, r.value().loadWeights, r.value().forceDirectionLocal,
                                        r.value().contact, fs);
          if (!ref) return ref.error();
          out.referenceS += secondsSince(start);
          reference[i] = ref.value().peakPrincipalPa;
          reportProgress(progress, stage + ": full-FEM reference",
                         static_cast<double>(i + 1) / static_cast<double>(impacts.size()));
        }
      }
      if (isInterrupted(progress)) return makeError(ErrorCode::Cancelled, stage + ": interrupted");
      const double err = reference[i] > 0.0 ? std::abs(peak / reference[i] - 1.0) : (peak > 0.0 ? kInf : 0.0);
      trial.worstError = std::max(trial.worstError, err);
    }
    trial.medianImpactMs = median(times);
    reportProgress(progress, stage + ": mode counts",
                   static_cast<double>(k - ladder.rbegin() + 1) / static_cast<double>(ladder.size()));
    out.trials.insert(out.trials.begin(), trial);
  }
  const auto met = std::find_if(out.trials.begin(), out.trials.end(),
                                [&](const ModeTrial& t) { return t.worstError <= targetError; });
  out.targetMet = met != out.trials.end();
  const ModeTrial& chosen = out.targetMet ? *met : out.trials.back();
  out.chosenModes = chosen.modes;
  out.chosenError = chosen.worstError;
  return out;
}

namespace {

std::string objectName(const ObjectBakeSettings& s) { return s.name.empty() ? s.meshPath.stem().string() : s.name; }

// The values an impact on `asset` reads with r modes: its stress modes (6 per stress point) and
// its modes (3 per FEM node), r each.
double impactValues(const ObjectAsset& asset, int modes) {
  const double points = static_cast<double>(asset.tetMesh.tets.rows()) * stressPointsPerElement(asset.elementOrder);
  const double dofs = 3.0 * static_cast<double>(femNodeCount(asset.tetMesh, asset.elementOrder));
  return (6.0 * points + dofs) * modes;
}

double medianImpactMsAt(const ObjectSizing& s) {
  for (const auto& t : s.trials)
    if (t.modes == s.chosenModes) return t.medianImpactMs;
  return 0.0;
}

// The element orders tried: each scene object sized in each order, the cheapest that meets both
// targets kept (ModelSizingSettings::elementOrders). `assets[o]` is the object in order o. When
// none meets both, the one with the smallest frequency error (P2) is kept, and the result says
// the target was not met.
ObjectSizing chooseElementOrder(std::vector<ObjectSizing> sizings, const std::vector<const ObjectAsset*>& assets,
                                double frequencyTarget) {
  double quadraticHz = 0.0;
  for (size_t o = 0; o < assets.size(); ++o)
    if (assets[o]->elementOrder == ElementOrder::P2) quadraticHz = assets[o]->modal.frequenciesHz(0);
  std::vector<ElementTrial> trials;
  size_t best = assets.size(), fallback = 0;
  for (size_t o = 0; o < assets.size(); ++o) {
    ElementTrial t;
    t.elementOrder = assets[o]->elementOrder;
    t.firstFrequencyHz = assets[o]->modal.frequenciesHz(0);
    t.frequencyError = std::abs(t.firstFrequencyHz - quadraticHz) / quadraticHz;
    t.chosenModes = sizings[o].chosenModes;
    t.targetMet = sizings[o].targetMet && t.frequencyError <= frequencyTarget;
    t.impactValues = impactValues(*assets[o], t.chosenModes);
    t.medianImpactMs = medianImpactMsAt(sizings[o]);
    if (t.targetMet && (best == assets.size() || t.impactValues < trials[best].impactValues)) best = o;
    if (trials.empty() || t.frequencyError < trials[fallback].frequencyError) fallback = o;
    trials.push_back(t);
  }
  const size_t chosen = best < assets.size() ? best : fallback;
  ObjectSizing out = std::move(sizings[chosen]);
  out.targetMet = trials[chosen].targetMet;
  out.elementTrials = std::move(trials);
  return out;
}

/// Bakes the objects (and the database, when given) into a pack, written to `path` once `finish`
/// (when given) has completed it.
Result<Pack> bakeAndWrite(const std::vector<ObjectBakeSettings>& objects, const FragmentDatabase* database,
                          const std::filesystem::path& path, ProgressSink* progress, double* seconds, int64_t* bytes,
                          const std::function<Status(Pack&)>& finish = {}) {
  const auto start = SteadyClock::now();
  auto pack = bakePack(objects, progress);
  if (!pack) return pack.error();
  *seconds = secondsSince(start);
  if (database) pack.value().database = *database;
  if (finish) {
    if (Status st = finish(pack.value()); !st) return st.error();
  }
  if (Status st = writePack(pack.value(), path); !st) return st.error();
  std::error_code ec;
  *bytes = static_cast<int64_t>(std::filesystem::file_size(path, ec));
  if (ec) return makeError(ErrorCode::PackIoError, "cannot measure " + path.string() + ": " + ec.message());
  return pack;
}

}  // namespace

Result<SceneSizingReport> sizeScene(const std::vector<ObjectBakeSettings>& manifestIn,
                                    const std::optional<DatabaseBakeSettings>& database,
                                    const SceneRequirements& requirements, const SceneSizingPaths& paths,
                                    const ModelSizingSettings& settings, ProgressSink* progress) {
  if (settings.modeLadder.empty()) return makeError(ErrorCode::InvalidArgument, "model sizing: empty mode ladder");
  if (settings.frequencyErrorPoints < 0 || settings.frequencyErrorPiecesPerImpact < 1)
    return makeError(ErrorCode::InvalidArgument, "model sizing: frequency-error points must be ≥ 0 and pieces per impact ≥ 1");
  const std::vector<ElementOrder>& orders = settings.elementOrders;
  for (size_t o = 0; o < orders.size(); ++o) {
    if (std::find(orders.begin() + static_cast<std::ptrdiff_t>(o) + 1, orders.end(), orders[o]) != orders.end()) {
      return makeError(ErrorCode::InvalidArgument, "model sizing: element order " + std::string(elementOrderName(orders[o])) +
                                                       " listed twice");
    }
  }
  if (orders.size() > 1 && std::find(orders.begin(), orders.end(), ElementOrder::P2) == orders.end()) {
    return makeError(ErrorCode::InvalidArgument, "model sizing: choosing an element order needs p2 among the orders "
                                                 "(each order's frequency error is estimated against it)");
  }
  if (orders.size() > 1 && !(settings.frequencyErrorTarget > 0.0 && settings.frequencyErrorTarget < 1.0)) {
    return makeError(ErrorCode::InvalidArgument, "model sizing: the frequency error target must lie in (0, 1)");
  }
  // One order given: every object in it, as if the manifest said so.
  std::vector<ObjectBakeSettings> manifest = manifestIn;
  if (orders.size() == 1)
    for (auto& m : manifest) m.elementOrder = orders[0];
  const int largest = *std::max_element(settings.modeLadder.begin(), settings.modeLadder.end());
  SceneSizingReport report;
  report.targetError = requirements.peakStressError;
  report.matchTargetError = requirements.matchFrequencyError;
  if (orders.size() > 1) report.frequencyTargetError = settings.frequencyErrorTarget;
  report.refracture = requirements.refracture;
  std::vector<size_t> used;  // manifest index of each scene object
  for (const auto& range : requirements.objects) {
    size_t i = 0;
    while (i < manifest.size() && objectName(manifest[i]) != range.name) ++i;
    if (i == manifest.size()) {
      std::string known;
      for (const auto& m : manifest) known += (known.empty() ? "" : ", ") + objectName(m);
      return makeError(ErrorCode::InvalidArgument,
                       "the scene uses \"" + range.name + "\", which the manifest does not bake (it has: " + known + ")");
    }
    used.push_back(i);
  }
  for (size_t i = 0; i < manifest.size(); ++i) {
    if (std::find(used.begin(), used.end(), i) == used.end()) report.skippedObjects.push_back(objectName(manifest[i]));
  }

  // The database is the same on both sides: baked once, counted in both bake times.
  std::optional<FragmentDatabase> db;
  if (database) {
    const auto start = SteadyClock::now();
    auto baked = bakeFragmentDatabase(*database, progress);
    if (!baked) return baked.error();
    report.databaseBakeS = secondsSince(start);
    db = std::move(baked).value();
  }

  std::vector<ObjectBakeSettings> maximum = manifest;
  for (auto& m : maximum) m.modal.modeCount = largest;
  std::filesystem::path maxPath = paths.maximumPack;
  if (maxPath.empty()) maxPath = paths.sizedPack.string() + ".maximum.h5";
  auto maxPack = bakeAndWrite(maximum, db ? &*db : nullptr, maxPath, progress, &report.maximumBakeS, &report.maximumPackBytes);
  if (paths.maximumPack.empty()) {
    std::error_code ignored;
    std::filesystem::remove(maxPath, ignored);
  }
  if (!maxPack) return maxPack.error();
  report.maximumBakeS += report.databaseBakeS;

  // Several element orders (then exactly P1 and P2, no order twice): each scene object in each
  // order at the largest count, `inOrder[o][k]`. Its manifest's order is the all-maximum pack's
  // asset; the other is baked here, the objects that need it in one bake per order.
  std::vector<std::vector<const ObjectAsset*>> inOrder(orders.size(), std::vector<const ObjectAsset*>(used.size()));
  std::vector<Pack> otherOrders;
  otherOrders.reserve(orders.size());  // inOrder points into them
  for (size_t o = 0; orders.size() > 1 && o < orders.size(); ++o) {
    std::vector<ObjectBakeSettings> toBake;
    std::vector<size_t> baked;  // k of each object in toBake
    for (size_t k = 0; k < used.size(); ++k) {
      if (maximum[used[k]].elementOrder == orders[o]) {
        inOrder[o][k] = &maxPack.value().objects[used[k]];
        continue;
      }
      toBake.push_back(maximum[used[k]]);
      toBake.back().elementOrder = orders[o];
      baked.push_back(k);
    }
    if (toBake.empty()) continue;
    auto pack = bakePack(toBake, progress);
    if (!pack) return pack.error();
    otherOrders.push_back(std::move(pack).value());
    for (size_t j = 0; j < baked.size(); ++j) inOrder[o][baked[j]] = &otherOrders.back().objects[j];
  }
  // The asset each scene object is sized and studied on: its chosen order's.
  std::vector<const ObjectAsset*> chosenAssets;
  std::vector<ObjectBakeSettings> sized;
  for (size_t k = 0; k < used.size(); ++k) {
    const ObjectAsset* asset = &maxPack.value().objects[used[k]];
    ObjectSizing sizing;
    if (orders.size() > 1) {
      std::vector<ObjectSizing> perOrder;
      std::vector<const ObjectAsset*> assets;
      for (size_t o = 0; o < orders.size(); ++o) {
        assets.push_back(inOrder[o][k]);
        auto s = sizeObjectModes(*inOrder[o][k], manifest[used[k]].material, requirements.objects[k],
                                 requirements.peakStressError, settings, progress);
        if (!s) return s.error();
        // The all-maximum side is the manifest's own order, always one of the two.
        if (inOrder[o][k] == asset) report.maximumImpactMs += s.value().trials.back().medianImpactMs;
        perOrder.push_back(std::move(s).value());
      }
      sizing = chooseElementOrder(std::move(perOrder), assets, settings.frequencyErrorTarget);
      for (size_t o = 0; o < orders.size(); ++o)
        if (orders[o] == sizing.elementOrder) asset = inOrder[o][k];
    } else {
      auto s = sizeObjectModes(*asset, manifest[used[k]].material, requirements.objects[k],
                               requirements.peakStressError, settings, progress);
      if (!s) return s.error();
      sizing = std::move(s).value();
      report.maximumImpactMs += sizing.trials.back().medianImpactMs;
    }
    report.sizedImpactMs += medianImpactMsAt(sizing);
    chosenAssets.push_back(asset);
    sized.push_back(manifest[used[k]]);
    sized.back().modal.modeCount = sizing.chosenModes;
    sized.back().elementOrder = sizing.elementOrder;
    report.objects.push_back(std::move(sizing));
  }
  // What the fragments need: the debris threshold, and the descriptor and search precision the
  // sized pack's database stores.
  const auto fragmentStart = SteadyClock::now();
  std::vector<FragmentRecord> fragments;
  std::vector<Material> materials;
  for (size_t k = 0; k < used.size(); ++k) {
    const ObjectAsset& asset = *chosenAssets[k];
    const Material& material = manifest[used[k]].material;
    auto records = sceneFragments(asset, material, requirements.objects[k], report.objects[k].chosenModes, settings, progress);
    if (!records) return records.error();
    report.debris.push_back(chooseDebrisThreshold(asset.name, records.value()));
    fragments.insert(fragments.end(), records.value().begin(), records.value().end());
    if (std::none_of(materials.begin(), materials.end(), [&](const Material& m) { return m.name == material.name; })) {
      materials.push_back(material);
    }
  }
  report.debrisVolumeFraction = 0.5;
  for (const auto& d : report.debris) report.debrisVolumeFraction = std::min(report.debrisVolumeFraction, d.debrisVolumeFraction);
  std::optional<FragmentDatabase> sizedDb;
  if (requirements.refracture && db) {
    sizedDb = *db;
    if (!fragments.empty()) {
      auto search = chooseSearch(*db, fragments, materials, requirements.matchFrequencyError, settings);
      if (!search) return search.error();
      sizedDb->indexSettings[static_cast<size_t>(search.value().kind)] = search.value().index;
      report.search = std::move(search).value();
      // The calibration searched with the bake's index; the sized pack's matches use this one. The
      // chosen kind's model is then fitted to the scene's own fragments where there are enough
      // (queries of the runtime's kind; MatchErrors.h).
      if (Status st = calibrateDatabaseMatchErrors(*sizedDb); !st) return st.error();
      if (report.search->distanceErrors.size() >= kSceneMatchErrorSamples) {
        auto fitted = fitMatchErrors(report.search->distanceErrors);
        if (!fitted) return fitted.error();
        sizedDb->matchErrors[static_cast<size_t>(report.search->kind)] = std::move(fitted).value();
      }
    }
  }
  report.fragmentSizingS = secondsSince(fragmentStart);
  const FragmentDatabase* keep = sizedDb ? &*sizedDb : nullptr;
  // The bodies' frequency errors, at the scene's own impacts, before the pack is written (once).
  auto calibrate = [&](Pack& pack) -> Status {
    if (!keep || settings.frequencyErrorPoints < 1) return Ok{};
    if (!pack.database.hasPhysics()) {
      report.frequencyErrors.emplace().note = "the database has no physics: no body to predict";
      return Ok{};
    }
    const auto start = SteadyClock::now();
    FrequencyErrorCalibrationSettings fs;
    fs.scene = requirements.objects;
    fs.seeds = settings.frequencyErrorPoints;
    fs.maxFragmentsPerImpact = settings.frequencyErrorPiecesPerImpact;
    FrequencyErrorSizing& out = report.frequencyErrors.emplace();
    auto made = measureFrequencyErrors(pack, fs, progress);
    if (!made) return made.error();
    out.impacts = made.value().impacts;
    // No piece (the scene's impacts break off none with a truth) is a result, not a failure: the
    // pack then predicts nothing, as one baked without the calibration.
    if (made.value().samples.empty()) {
      out.seconds = secondsSince(start);
      out.note = "the scene's " + std::to_string(out.impacts) + " impacts broke off no piece to calibrate on";
      return Ok{};
    }
    auto models = fitFrequencyErrors(made.value().samples, fs);
    if (!models) return models.error();
    out.seconds = secondsSince(start);
    out.piecesPerObject = made.value().piecesPerObject;  // the scene's objects, in its order
    out.calibrated = true;
    out.ritzBins = static_cast<int>(models.value().ritz.distance.size());
    out.checkedBins = static_cast<int>(models.value().checked.distance.size());
    out.checkedP2Bins = static_cast<int>(models.value().checkedP2.distance.size());
    pack.database.frequencyErrors = std::move(models).value();
    return Ok{};
  };
  auto sizedPack = bakeAndWrite(sized, keep, paths.sizedPack, progress, &report.sizedBakeS, &report.sizedPackBytes, calibrate);
  if (!sizedPack) return sizedPack.error();
  if (keep) report.sizedBakeS += report.databaseBakeS;
  return report;
}

Status writeSizedManifest(const std::filesystem::path& manifest, const SceneSizingReport& report,
                          const std::filesystem::path& out) {
  std::ifstream in(manifest);
  if (!in) return makeError(ErrorCode::FileNotFound, "manifest not found: " + manifest.string());
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    return makeError(ErrorCode::ParseError, "manifest " + manifest.filename().string() + ": " + e.what());
  }
  const auto from = manifest.parent_path(), to = std::filesystem::absolute(out).parent_path();
  auto rebase = [&](const std::string& file) {
    const std::filesystem::path p(file);
    if (p.is_absolute()) return file;
    return std::filesystem::relative(std::filesystem::absolute(from / p), to).generic_string();
  };
  nlohmann::json objects = nlohmann::json::array();
  try {
    for (const auto& sizing : report.objects) {
      for (auto o : doc.at("objects")) {
        const std::string mesh = o.at("mesh").get<std::string>();
        const std::string name = o.value("name", std::filesystem::path(mesh).stem().string());
        if (name != sizing.object) continue;
        o["modes"] = sizing.chosenModes;
        o["element"] = elementOrderName(sizing.elementOrder);
        o["mesh"] = rebase(mesh);
        if (const std::string m = o.at("material").get<std::string>(); m.ends_with(".json")) o["material"] = rebase(m);
        objects.push_back(o);
      }
    }
    doc["objects"] = objects;
    if (!report.refracture) {
      doc.erase("database");
    } else if (doc.contains("database") && doc["database"].contains("shapes")) {
      doc["database"]["shapes"] = rebase(doc["database"]["shapes"].get<std::string>());
    }
  } catch (const std::exception& e) {
    return makeError(ErrorCode::ParseError, "manifest " + manifest.filename().string() + ": " + e.what());
  }
  return writeFileAtomically(out, doc.dump(2) + "\n");
}

}  // namespace brittle
