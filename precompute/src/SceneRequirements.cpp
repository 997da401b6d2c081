// SceneRequirements.cpp — loadSceneRequirements (SceneRequirements.h). Kept apart from ModelSizing.cpp
// so that the reader links without the bake, the runtime and the reference solver: the fuzz
// targets (tests/fuzz) build it from its own sources.
#include "brittle/precompute/SceneRequirements.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "brittle/core/JsonChecks.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "Support.h"

namespace brittle {
namespace {

using detail::kInf;

Error sceneFileError(const std::string& where, const std::string& what) { return parseError("requirements " + where, what); }

Status checkKeys(const nlohmann::json& o, const std::set<std::string>& keys, const std::string& where) {
  if (!o.is_object()) return sceneFileError(where, "not an object");
  return checkKnownKeys(o, keys, "requirements " + where);
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
    return sceneFileError(file, e.what());
  }
  SceneRequirements r;
  try {
    if (Status st = checkKeys(doc, {"peak_stress_error", "match_frequency_error", "refracture", "objects"}, file); !st) {
      return st.error();
    }
    if (doc.contains("match_frequency_error")) {
      if (!doc["match_frequency_error"].is_number()) return sceneFileError(file, "\"match_frequency_error\" must be a number");
      r.matchFrequencyError = doc["match_frequency_error"].get<double>();
      if (!(r.matchFrequencyError > 0.0 && r.matchFrequencyError < 100.0)) {
        return sceneFileError(file, "\"match_frequency_error\" must be in (0, 100)");
      }
    }
    if (doc.contains("peak_stress_error")) {
      if (!doc["peak_stress_error"].is_number()) return sceneFileError(file, "\"peak_stress_error\" must be a number");
      r.peakStressError = doc["peak_stress_error"].get<double>();
      if (!(r.peakStressError > 0.0 && r.peakStressError < 1.0)) {
        return sceneFileError(file, "\"peak_stress_error\" must be in (0, 1)");
      }
    }
    if (doc.contains("refracture")) {
      if (!doc["refracture"].is_boolean()) return sceneFileError(file, "\"refracture\" must be true or false");
      r.refracture = doc["refracture"].get<bool>();
    }
    if (!doc.contains("objects") || !doc["objects"].is_array() || doc["objects"].empty()) {
      return sceneFileError(file, "needs a non-empty \"objects\" array");
    }
    std::set<std::string> names;
    for (size_t i = 0; i < doc["objects"].size(); ++i) {
      const auto& o = doc["objects"][i];
      const std::string where = file + ", object " + std::to_string(i);
      if (Status st = checkKeys(o, {"name", "speeds_mps", "impactors"}, where); !st) return st.error();
      SceneObjectRange range;
      if (!o.contains("name") || !o["name"].is_string()) return sceneFileError(where, "needs a \"name\"");
      range.name = o["name"].get<std::string>();
      if (!names.insert(range.name).second) return sceneFileError(where, "\"" + range.name + "\" is named twice");
      const auto& speeds = o.value("speeds_mps", nlohmann::json());
      if (!speeds.is_array() || speeds.size() != 2 || !speeds[0].is_number() || !speeds[1].is_number()) {
        return sceneFileError(where, "\"speeds_mps\" must be [lowest, highest]");
      }
      range.minSpeedMps = speeds[0].get<double>();
      range.maxSpeedMps = speeds[1].get<double>();
      if (!(range.minSpeedMps > 0.0 && range.minSpeedMps <= range.maxSpeedMps && std::isfinite(range.maxSpeedMps))) {
        return sceneFileError(where, "\"speeds_mps\" needs 0 < lowest ≤ highest");
      }
      const auto& impactors = o.value("impactors", nlohmann::json());
      if (!impactors.is_array() || impactors.empty()) return sceneFileError(where, "needs a non-empty \"impactors\" array");
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
          if (m.contains("mass_kg") || m.contains("radius_m")) return sceneFileError(at, "the ground takes no mass or radius");
          imp.massKg = kInf;
          imp.radiusM = kInf;
        } else {
          if (!m.contains("mass_kg") || !m["mass_kg"].is_number() || !m.contains("radius_m") || !m["radius_m"].is_number()) {
            return sceneFileError(at, "a sphere needs \"mass_kg\" and \"radius_m\" (or \"ground\": true)");
          }
          imp.massKg = m["mass_kg"].get<double>();
          imp.radiusM = m["radius_m"].get<double>();
          if (!(imp.massKg > 0.0 && std::isfinite(imp.massKg) && imp.radiusM > 0.0 && std::isfinite(imp.radiusM))) {
            return sceneFileError(at, "mass and radius must be positive and finite");
          }
        }
        range.impactors.push_back(std::move(imp));
      }
      r.objects.push_back(std::move(range));
    }
  } catch (const std::exception& e) {  // a value of the wrong type
    return sceneFileError(file, e.what());
  }
  return r;
}

}  // namespace brittle
