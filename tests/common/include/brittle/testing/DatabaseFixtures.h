// DatabaseFixtures.h — small fragment databases from the shipped base shapes, for the suites that
// bake one (database, precompute, runtime, player). Header-only: its users link brittle::precompute.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/testing/Fixtures.h"

namespace brittle::testing {

/// The base shapes the project ships (assets/shapes/base-shapes.json).
inline std::vector<BaseShapeDefinition> shippedBaseShapes() {
  auto shapes = loadBaseShapes(sourceDir() / "assets" / "shapes" / "base-shapes.json");
  return shapes ? shapes.value() : std::vector<BaseShapeDefinition>{};
}

/// The first row of a chunk of `chunkRows` rows (of /database/entries/stress_modes in a pack of
/// `db`) that lies wholly inside entry `entry`'s rows, so that damaging it damages that entry
/// alone; nullopt when the entry spans no whole chunk.
inline std::optional<uint64_t> stressChunkInsideEntry(const FragmentDatabase& db, size_t entry, uint64_t chunkRows) {
  if (chunkRows == 0 || entry >= db.entries.size()) return std::nullopt;
  uint64_t start = 0;  // the entry's first row: the stress modes are stored entry after entry
  for (size_t e = 0; e < entry; ++e) start += static_cast<uint64_t>(db.entries[e].asset.stressModes.size());
  const uint64_t end = start + static_cast<uint64_t>(db.entries[entry].asset.stressModes.size());
  const uint64_t first = (start + chunkRows - 1) / chunkRows * chunkRows;
  return first + chunkRows <= end ? std::optional<uint64_t>(first) : std::nullopt;
}

/// Settings for a small, fast database: coarse tets and few modes.
inline DatabaseBakeSettings smallDatabaseSettings(int64_t entries, bool physics) {
  DatabaseBakeSettings s;
  s.shapes = shippedBaseShapes();
  s.entryCount = entries;
  s.seed = 7;
  s.physics = physics;
  s.tetMesh.targetTets = 400;
  s.modeCount = 6;
  s.descriptors.voxel.resolution = s.descriptors.voxelImproved.resolution = 12;
  return s;
}

/// The default settings on the named shipped shapes, with `entries` entries of about `tets` tets
/// and `modes` modes each. An unknown name leaves the shapes empty (the bake then refuses).
inline DatabaseBakeSettings shippedShapesDatabase(const std::vector<std::string>& names, int64_t entries, int64_t tets,
                                                  int modes) {
  DatabaseBakeSettings s;
  auto shapes = selectBaseShapes(shippedBaseShapes(), names);
  if (shapes) s.shapes = std::move(shapes).value();
  s.entryCount = entries;
  s.tetMesh.targetTets = tets;
  s.modeCount = modes;
  return s;
}

/// Small settings for a database of the brick's own pieces (assets/shapes/default-objects.json),
/// broken off by the runtime, in P2 tets: the database of a scene's own objects, kept small. An
/// unreadable shapes file leaves the shapes empty (the bake then refuses).
inline DatabaseBakeSettings brickPiecesDatabase(int64_t entries) {
  DatabaseBakeSettings s = smallDatabaseSettings(entries, true);
  s.shapes.clear();
  if (auto shapes = loadBaseShapes(sourceDir() / "assets" / "shapes" / "default-objects.json")) {
    if (auto brick = selectBaseShapes(shapes.value(), {"brick"})) s.shapes = std::move(brick).value();
  }
  s.runtimeFragments.fraction = 1.0;
  s.runtimeFragments.targetTets = 800;
  s.runtimeFragments.modeCount = 12;
  s.elementOrder = ElementOrder::P2;
  return s;
}

}  // namespace brittle::testing
