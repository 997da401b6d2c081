// ModelSizing.cpp — loadSceneRequirements and sizeObjectModes (ModelSizing.h).
#include "brittle/precompute/ModelSizing.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <set>

#include "brittle/precompute/AtomicFile.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/runtime/FullFemReference.h"
#include "brittle/runtime/World.h"

namespace brittle {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Error parseError(const std::string& where, const std::string& what) {
  return makeError(ErrorCode::ParseError, "requirements " + where + ": " + what);
}

Status checkKeys(const nlohmann::json& o, const std::set<std::string>& keys, const std::string& where) {
  if (!o.is_object()) return parseError(where, "not an object");
  for (const auto& [key, value] : o.items()) {
    if (!keys.count(key)) return parseError(where, "unknown key \"" + key + "\"");
  }
  return Ok{};
}

/// A uniform double in [0, 1) from 53 bits of the generator (the same on every platform).
double unit(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

Result<SceneRequirements> loadSceneRequirements(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return makeError(ErrorCode::FileNotFound, "requirements not found: " + path.string());
  const std::string file = path.filename().string();
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    return parseError(file, e.what());
  }
  SceneRequirements r;
  try {
    if (Status st = checkKeys(doc, {"peak_stress_error", "refracture", "objects"}, file); !st) return st.error();
    if (doc.contains("peak_stress_error")) {
      if (!doc["peak_stress_error"].is_number()) return parseError(file, "\"peak_stress_error\" must be a number");
      r.peakStressError = doc["peak_stress_error"].get<double>();
      if (!(r.peakStressError > 0.0 && r.peakStressError < 1.0)) {
        return parseError(file, "\"peak_stress_error\" must be in (0, 1)");
      }
    }
    if (doc.contains("refracture")) {
      if (!doc["refracture"].is_boolean()) return parseError(file, "\"refracture\" must be true or false");
      r.refracture = doc["refracture"].get<bool>();
    }
    if (!doc.contains("objects") || !doc["objects"].is_array() || doc["objects"].empty()) {
      return parseError(file, "needs a non-empty \"objects\" array");
    }
    std::set<std::string> names;
    for (size_t i = 0; i < doc["objects"].size(); ++i) {
      const auto& o = doc["objects"][i];
      const std::string where = file + ", object " + std::to_string(i);
      if (Status st = checkKeys(o, {"name", "speeds_mps", "impactors"}, where); !st) return st.error();
      SceneObjectRange range;
      if (!o.contains("name") || !o["name"].is_string()) return parseError(where, "needs a \"name\"");
      range.name = o["name"].get<std::string>();
      if (!names.insert(range.name).second) return parseError(where, "\"" + range.name + "\" is named twice");
      const auto& speeds = o.value("speeds_mps", nlohmann::json());
      if (!speeds.is_array() || speeds.size() != 2 || !speeds[0].is_number() || !speeds[1].is_number()) {
        return parseError(where, "\"speeds_mps\" must be [lowest, highest]");
      }
      range.minSpeedMps = speeds[0].get<double>();
      range.maxSpeedMps = speeds[1].get<double>();
      if (!(range.minSpeedMps > 0.0 && range.minSpeedMps <= range.maxSpeedMps && std::isfinite(range.maxSpeedMps))) {
        return parseError(where, "\"speeds_mps\" needs 0 < lowest ≤ highest");
      }
      const auto& impactors = o.value("impactors", nlohmann::json());
      if (!impactors.is_array() || impactors.empty()) return parseError(where, "needs a non-empty \"impactors\" array");
      for (size_t k = 0; k < impactors.size(); ++k) {
        const auto& m = impactors[k];
        const std::string at = where + ", impactor " + std::to_string(k);
        if (Status st = checkKeys(m, {"ground", "mass_kg", "radius_m", "material"}, at); !st) return st.error();
        SceneImpactor imp;
        std::string material = m.value("material", std::string("steel"));
        if (material.ends_with(".json")) material = (path.parent_path() / material).string();
        auto resolved = resolveMaterial(material);
        if (!resolved) return Error{resolved.error().code, "requirements " + at + ": " + resolved.error().message};
        imp.material = std::move(resolved).value();
        if (m.value("ground", false)) {
          if (m.contains("mass_kg") || m.contains("radius_m")) return parseError(at, "the ground takes no mass or radius");
          imp.massKg = kInf;
          imp.radiusM = kInf;
        } else {
          if (!m.contains("mass_kg") || !m["mass_kg"].is_number() || !m.contains("radius_m") || !m["radius_m"].is_number()) {
            return parseError(at, "a sphere needs \"mass_kg\" and \"radius_m\" (or \"ground\": true)");
          }
          imp.massKg = m["mass_kg"].get<double>();
          imp.radiusM = m["radius_m"].get<double>();
          if (!(imp.massKg > 0.0 && std::isfinite(imp.massKg) && imp.radiusM > 0.0 && std::isfinite(imp.radiusM))) {
            return parseError(at, "mass and radius must be positive and finite");
          }
        }
        range.impactors.push_back(std::move(imp));
      }
      r.objects.push_back(std::move(range));
    }
  } catch (const std::exception& e) {  // a value of the wrong type
    return parseError(file, e.what());
  }
  return r;
}

Result<ObjectSizing> sizeObjectModes(const ObjectAsset& asset, const Material& material, const SceneObjectRange& range,
                                     double targetError, const ModelSizingSettings& settings) {
  std::vector<int> ladder = settings.modeLadder;
  std::sort(ladder.begin(), ladder.end());
  ladder.erase(std::unique(ladder.begin(), ladder.end()), ladder.end());
  if (ladder.empty() || ladder.front() < 1 || settings.points < 1 || settings.timingRepeats < 1 ||
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

  // The scene's impacts: seeded surface points by area × impactors × the two ends of the speeds.
  const auto& nodes = asset.tetMesh.nodes;
  const auto& faces = asset.surfaceFaces;
  std::vector<double> cumulative(static_cast<size_t>(faces.rows()));
  double area = 0.0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = nodes.row(faces(f, 0)), b = nodes.row(faces(f, 1)), c = nodes.row(faces(f, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
    cumulative[static_cast<size_t>(f)] = area;
  }
  std::mt19937_64 rng(settings.seed ^ 0x5CE7E5151ull);
  std::vector<ImpactDesc> impacts;
  for (int p = 0; p < settings.points; ++p) {
    const double u = unit(rng) * area;
    const auto f = static_cast<Eigen::Index>(
        std::min<size_t>(std::lower_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin(), cumulative.size() - 1));
    const Eigen::Vector3d a = nodes.row(faces(f, 0)), b = nodes.row(faces(f, 1)), c = nodes.row(faces(f, 2));
    for (const SceneImpactor& imp : range.impactors) {
      for (double speed : {range.minSpeedMps, range.maxSpeedMps}) {
        ImpactDesc d;
        d.pointWorld = (a + b + c) / 3.0;
        d.normalWorld = (b - a).cross(c - a).normalized();
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

  Pack pack;
  pack.materials.push_back(material);
  pack.objects.push_back(asset);
  pack.objects.back().materialName = material.name;
  ObjectSizing out;
  out.object = asset.name;
  out.impacts = static_cast<int>(impacts.size());
  std::vector<double> reference(impacts.size(), 0.0);
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
          const auto start = std::chrono::steady_clock::now();
          auto ref = solveFullFemImpact(asset.tetMesh, material, r.value().loadWeights, r.value().forceDirectionLocal,
                                        r.value().contact, fs);
          if (!ref) return ref.error();
          out.referenceS += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          reference[i] = ref.value().peakPrincipalPa;
        }
      }
      const double err = reference[i] > 0.0 ? std::abs(peak / reference[i] - 1.0) : (peak > 0.0 ? kInf : 0.0);
      trial.worstError = std::max(trial.worstError, err);
    }
    trial.medianImpactMs = median(times);
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

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Bakes the objects (and the database, when given) into a pack, written to `path`.
Result<Pack> bakeAndWrite(const std::vector<ObjectBakeSettings>& objects, const FragmentDatabase* database,
                          const std::filesystem::path& path, ProgressSink* progress, double* seconds, int64_t* bytes) {
  const auto start = std::chrono::steady_clock::now();
  auto pack = bakePack(objects, progress);
  if (!pack) return pack.error();
  *seconds = secondsSince(start);
  if (database) pack.value().database = *database;
  if (Status st = writePack(pack.value(), path); !st) return st.error();
  std::error_code ec;
  *bytes = static_cast<int64_t>(std::filesystem::file_size(path, ec));
  if (ec) return makeError(ErrorCode::PackIoError, "cannot measure " + path.string() + ": " + ec.message());
  return pack;
}

}  // namespace

Result<SceneSizingReport> sizeScene(const std::vector<ObjectBakeSettings>& manifest,
                                    const std::optional<DatabaseBakeSettings>& database,
                                    const SceneRequirements& requirements, const SceneSizingPaths& paths,
                                    const ModelSizingSettings& settings, ProgressSink* progress) {
  if (settings.modeLadder.empty()) return makeError(ErrorCode::InvalidArgument, "model sizing: empty mode ladder");
  const int largest = *std::max_element(settings.modeLadder.begin(), settings.modeLadder.end());
  SceneSizingReport report;
  report.targetError = requirements.peakStressError;
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
    const auto start = std::chrono::steady_clock::now();
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

  std::vector<ObjectBakeSettings> sized;
  for (size_t k = 0; k < used.size(); ++k) {
    const ObjectAsset& asset = maxPack.value().objects[used[k]];
    reportProgress(progress, "sizing " + asset.name, static_cast<double>(k) / static_cast<double>(used.size()));
    auto sizing = sizeObjectModes(asset, manifest[used[k]].material, requirements.objects[k], requirements.peakStressError,
                                  settings);
    if (!sizing) return sizing.error();
    report.maximumImpactMs += sizing.value().trials.back().medianImpactMs;
    for (const auto& t : sizing.value().trials) {
      if (t.modes == sizing.value().chosenModes) report.sizedImpactMs += t.medianImpactMs;
    }
    sized.push_back(manifest[used[k]]);
    sized.back().modal.modeCount = sizing.value().chosenModes;
    report.objects.push_back(std::move(sizing).value());
  }
  reportProgress(progress, "sizing", 1.0);
  const FragmentDatabase* keep = requirements.refracture && db ? &*db : nullptr;
  auto sizedPack = bakeAndWrite(sized, keep, paths.sizedPack, progress, &report.sizedBakeS, &report.sizedPackBytes);
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
