// Fuzz target: loadSceneRequirements (SceneRequirements.h) on arbitrary bytes. The file sits next to a
// valid custom material file, "custom.json", so that impactors can reach the material-file
// branch. Whatever it accepts must be inside the documented ranges: a target in (0, 1), at least
// one object with 0 < lowest ≤ highest finite speed, and impactors that are the ground or a
// sphere of positive finite mass and radius with a valid material.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "FuzzSupport.h"
#include "brittle/precompute/SceneRequirements.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  brittle::fuzz::writeCustomMaterialFile();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace brittle;
  const auto path = fuzz::writeScratchFile("scene.json", data, size);
  const Result<SceneRequirements> r = loadSceneRequirements(path);
  fuzz::expectDocumentedError(r, {ErrorCode::FileNotFound, ErrorCode::ParseError, ErrorCode::UnknownMaterial,
                                  ErrorCode::InvalidMaterial});
  if (!r.ok()) return 0;
  const SceneRequirements& s = r.value();
  if (!(s.peakStressError > 0.0 && s.peakStressError < 1.0)) fuzz::finding("target out of (0, 1)");
  if (s.objects.empty()) fuzz::finding("no objects");
  for (const SceneObjectRange& o : s.objects) {
    if (!(o.minSpeedMps > 0.0 && o.minSpeedMps <= o.maxSpeedMps && std::isfinite(o.maxSpeedMps))) {
      fuzz::finding("speeds out of range");
    }
    if (o.impactors.empty()) fuzz::finding("an object without impactors");
    for (const SceneImpactor& i : o.impactors) {
      if (!validateMaterial(i.material).ok()) fuzz::finding("an impactor with an invalid material");
      const bool ground = i.ground() && std::isinf(i.radiusM);
      const bool sphere = i.massKg > 0.0 && std::isfinite(i.massKg) && i.radiusM > 0.0 && std::isfinite(i.radiusM);
      if (!ground && !sphere) fuzz::finding("an impactor that is neither the ground nor a sphere");
    }
  }
  return 0;
}
