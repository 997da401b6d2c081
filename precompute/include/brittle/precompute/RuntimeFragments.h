// RuntimeFragments.h — the database's second source of fragments: base shapes broken by the
// runtime itself (World.h), so the database holds the shapes the runtime makes, with their
// crack-surface roughness and proportions, next to the exact cuts of FragmentGenerator.h.
//
// Each base shape is baked once as an object (tet mesh, modes, stress modes) at the reference
// material. A fragment for (shape, seed) comes from one seeded impact on a fresh World: a point
// drawn uniformly over the shape's surface (by area), a steel ball of seeded mass (5–50 % of the
// body's) and radius (2–10 % of its size), at a seeded speed (log-uniform in [min, max]),
// doubled up to three times until the body breaks; then one of the fragments that are not debris,
// chosen by the seed. Same shape and seed, same fragment (the runtime is deterministic).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"
#include "brittle/precompute/BaseShapes.h"
#include "brittle/precompute/Progress.h"
#include "brittle/runtime/TetTopology.h"

namespace brittle {

struct RuntimeFragmentSettings {
  /// Share of database entries made by runtime fracture instead of cutting, in [0, 1].
  double fraction = 0.0;
  int64_t targetTets = 3000;   ///< tets of each base shape's object
  int modeCount = 20;          ///< its modes
  double minSpeedMps = 10.0;   ///< impact speeds are log-uniform in [min, max]
  double maxSpeedMps = 80.0;
};

/// Checks ranges: fraction in [0, 1], targetTets ≥ 100, modeCount ≥ 1, 0 < min ≤ max speed.
/// Error: InvalidArgument naming the field.
Status validateRuntimeFragmentSettings(const RuntimeFragmentSettings& settings);

/// The base shapes as breakable objects. Thread-safe to use from several threads at once:
/// fragment() builds its own World.
class RuntimeFragmentSource {
 public:
  /// Bakes every base shape (validated surface → tets → modes → stress modes) with `material`.
  /// Progress reports "runtime fragment objects". Errors: those of bakeSurface (naming the shape).
  static Result<RuntimeFragmentSource> build(const std::vector<BaseShapeDefinition>& shapes,
                                             const std::vector<TriangleMesh>& surfaces, const Material& material,
                                             const RuntimeFragmentSettings& settings,
                                             ProgressSink* progress = nullptr);

  /// One fragment of shape `shape`, from `seed`, in the shape's frame (m): closed and outward.
  /// *how (if given) receives "runtime: v=… m/s, fragment i of n". *solid (if given) receives the
  /// fragment's own tets, cut out of the broken body as the runtime's exact path cuts them
  /// (fragmentSubMesh, FragmentModes.h): the solid the surface encloses, in the same frame.
  /// Errors: InvalidArgument (shape out of range), MeshingFailed (the body did not break at 8 ×
  /// the drawn speed, left no fragment that is not debris, or, with solid, a fragment whose tets
  /// are not one face-connected solid), those of the World and of fragmentSubMesh.
  Result<TriangleMesh> fragment(size_t shape, uint64_t seed, std::string* how = nullptr, TetMesh* solid = nullptr) const;

  size_t shapeCount() const { return mObjects.size(); }

 private:
  RuntimeFragmentSettings mSettings;
  Material mMaterial;
  std::vector<ObjectAsset> mObjects;
  std::vector<TetTopology> mTopologies;  ///< of mObjects' tets, for the fragments' own tets
};

}  // namespace brittle
