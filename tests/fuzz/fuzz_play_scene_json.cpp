// Fuzz target: parseScene (the player's scene reader, Scene.h) on arbitrary bytes. Whatever it
// accepts must be inside the documented ranges: positive finite duration and time step with at
// most 100000 frames, substeps in [1, 64], finite gravity, unit rotations, positive masses and
// sizes, at least one object or impactor.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "FuzzSupport.h"
#include "brittle/player/Scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace brittle;
  const Result<Scene> r = parseScene(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.json");
  fuzz::expectDocumentedError(r, {ErrorCode::ParseError, ErrorCode::InvalidArgument, ErrorCode::UnknownMaterial});
  if (!r.ok()) return 0;
  const Scene& s = r.value();
  if (!(s.durationS > 0.0 && s.timeStepS > 0.0 && s.timeStepS <= s.durationS && s.durationS / s.timeStepS <= 100000.0)) {
    fuzz::finding("duration or time step out of range");
  }
  if (s.substeps < 1 || s.substeps > 64) fuzz::finding("substeps out of range");
  if (!s.gravityMps2.allFinite()) fuzz::finding("non-finite gravity");
  if (s.objects.empty() && s.impactors.empty()) fuzz::finding("an empty scene");
  for (const SceneObject& o : s.objects) {
    if (o.asset.empty() || !o.positionWorldM.allFinite() || std::abs(o.rotation.norm() - 1.0) > 1e-9) fuzz::finding("a bad object");
    if (!o.velocityMps.allFinite() || !o.angularVelocityRadPerS.allFinite()) fuzz::finding("a non-finite object velocity");
  }
  for (const RigidImpactor& i : s.impactors) {
    if (!(i.massKg > 0.0 && std::isfinite(i.massKg))) fuzz::finding("an impactor mass out of range");
    if (i.shape == ImpactorShape::Sphere && !(i.radiusM > 0.0 && std::isfinite(i.radiusM))) fuzz::finding("a bad sphere radius");
    if (i.shape == ImpactorShape::Box && !(i.halfExtentsM.minCoeff() > 0.0 && i.halfExtentsM.allFinite())) fuzz::finding("a bad box");
    if (!i.positionWorldM.allFinite() || !i.velocityMps.allFinite() || std::abs(i.rotation.norm() - 1.0) > 1e-9) {
      fuzz::finding("a bad impactor pose or velocity");
    }
  }
  return 0;
}
