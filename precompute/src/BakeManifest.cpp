// BakeManifest.cpp — loadBakeManifest (BakeManifest.h). Kept apart from BakePipeline.cpp so
// that the manifest parser links without the mesher and the modal solver: the fuzz targets
// (tests/fuzz) build it from its own sources.
#include "brittle/precompute/BakeManifest.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "brittle/core/JsonChecks.h"
#include "brittle/precompute/MaterialLibrary.h"

namespace brittle {

Result<std::vector<ObjectBakeSettings>> loadBakeManifest(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return makeError(ErrorCode::FileNotFound, "manifest not found: " + path.string());
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    return makeError(ErrorCode::ParseError, "manifest " + path.filename().string() + ": " + e.what());
  }
  const auto dir = path.parent_path();
  std::vector<ObjectBakeSettings> out;
  try {
    // A manifest may hold only a fragment database (FragmentDatabaseBake.h reads that section).
    if (doc.is_object() && !doc.contains("objects") && doc.contains("database")) return out;
    if (!doc.is_object() || !doc.contains("objects") || !doc["objects"].is_array()) {
      return makeError(ErrorCode::ParseError, "manifest " + path.filename().string() + ": needs an \"objects\" array");
    }
    static const std::set<std::string> kKeys = {"name", "mesh", "material", "tets", "modes", "element", "repair", "lumped_mass", "seed",
                                                "sharp_features", "sliver_bound", "meshing_runs", "stretch", "contact_spread"};
    for (size_t i = 0; i < doc["objects"].size(); ++i) {
      const auto& o = doc["objects"][i];
      const std::string where = "manifest " + path.filename().string() + ", object " + std::to_string(i);
      if (!o.is_object()) return makeError(ErrorCode::ParseError, where + ": not an object");
      if (Status st = checkKnownKeys(o, kKeys, where); !st) return st.error();
      if (!o.contains("mesh") || !o.contains("material")) {
        return makeError(ErrorCode::ParseError, where + ": \"mesh\" and \"material\" are required");
      }
      ObjectBakeSettings s;
      s.meshPath = dir / o.at("mesh").get<std::string>();
      s.name = o.value("name", std::string());
      std::string material = o.at("material").get<std::string>();
      if (material.ends_with(".json")) material = (dir / material).string();
      auto m = resolveMaterial(material);
      if (!m) return Error{m.error().code, where + ": " + m.error().message};
      s.material = std::move(m).value();
      // Range checks, so a typo does not become a 2^64 seed or a million-mode solve.
      struct Range {
        const char* key;
        double lo, hi;
        bool integer;
      };
      for (const Range& r : {Range{"tets", 0.0, 5e6, true}, Range{"modes", 1.0, 2000.0, true},
                             Range{"seed", 0.0, 9.007199254740992e15, true}, Range{"sliver_bound", 0.0, 30.0, false},
                             Range{"meshing_runs", 1.0, 8.0, true}, Range{"stretch", 1.0, kMaxThinStretch, false},
                             Range{"contact_spread", 0.0, 0.99, false}}) {
        if (!o.contains(r.key)) continue;
        const double v = o[r.key].is_number() ? o[r.key].get<double>() : std::nan("");
        if (!(v >= r.lo && v <= r.hi) || (r.integer && v != std::floor(v))) {
          char range[64];
          std::snprintf(range, sizeof range, "[%g, %g]", r.lo, r.hi);
          return makeError(ErrorCode::ParseError, where + ": \"" + r.key + "\" must be a number in " + range + (r.integer ? ", integer" : ""));
        }
      }
      if (o.contains("element")) {
        const auto order = o["element"].is_string() ? parseElementOrder(o["element"].get<std::string>()) : std::nullopt;
        if (!order) return makeError(ErrorCode::ParseError, where + ": \"element\" must be \"p1\" or \"p2\"");
        s.elementOrder = *order;
      }
      s.tetMesh.targetTets = o.value("tets", s.tetMesh.targetTets);
      s.modal.modeCount = o.value("modes", s.modal.modeCount);
      s.repair = o.value("repair", false);
      s.fem.lumpedMass = o.value("lumped_mass", false);
      s.tetMesh.detectSharpFeatures = o.value("sharp_features", true);
      s.tetMesh.sliverBoundDeg = o.value("sliver_bound", s.tetMesh.sliverBoundDeg);
      s.tetMesh.meshingRuns = o.value("meshing_runs", s.tetMesh.meshingRuns);
      s.tetMesh.thinStretch = o.value("stretch", s.tetMesh.thinStretch);
      s.contactSpreadFraction = o.value("contact_spread", s.contactSpreadFraction);
      const auto seed = o.value("seed", static_cast<uint64_t>(1));
      s.modal.seed = s.tetMesh.seed = seed;
      out.push_back(std::move(s));
    }
  } catch (const nlohmann::json::exception& e) {
    return makeError(ErrorCode::ParseError, "manifest " + path.filename().string() + ": " + e.what());
  }
  return out;
}

}  // namespace brittle
