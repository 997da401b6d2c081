// BakeFixtures.h — the preset glass and a glass plate baked with it, for the suites that bake
// objects (runtime, precompute). Header-only: its users link brittle::precompute.
#pragma once

#include <cstdint>
#include <utility>

#include "brittle/database/Pack.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/testing/Fixtures.h"

namespace brittle::testing {

/// The shipped "glass" preset (EN 572-1 values; MaterialLibrary.h cites them).
inline const Material& presetGlass() {
  static const Material m = materialPreset("glass").value();
  return m;
}

/// A pack of one object named "plate": a preset-glass plate sideM × sideM × 0.01 m (the box
/// [0, sideM]² × [0, 0.01]) of about `targetTets` tets of the given element with `modes` modes,
/// and its material.
inline Result<Pack> makeGlassPlatePack(int64_t targetTets, int modes, double sideM = 0.3,
                                       ElementOrder order = ElementOrder::P1) {
  ObjectBakeSettings b;
  b.name = "plate";
  b.elementOrder = order;
  b.material = presetGlass();
  b.tetMesh.targetTets = targetTets;
  b.modal.modeCount = modes;
  auto plate = bakeSurface(makeBoxSurface(sideM, sideM, 0.01), b);
  if (!plate) return plate.error();
  Pack pack;
  pack.materials.push_back(presetGlass());
  pack.objects.push_back(std::move(plate).value());
  return pack;
}

}  // namespace brittle::testing
