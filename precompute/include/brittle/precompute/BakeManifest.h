// BakeManifest.h — the bake manifest: the JSON file that lists the objects of a pack and how
// each is baked (bakePack in BakePipeline.h takes what it reads).
#pragma once

#include <filesystem>
#include <vector>

#include "brittle/core/Result.h"
#include "brittle/precompute/BakePipeline.h"

namespace brittle {

/// Reads a bake manifest (JSON):
///   { "objects": [ { "name": "glass-plate", "mesh": "meshes/plate.off", "material": "glass",
///                    "tets": 6000, "modes": 20, "element": "p1", "repair": false, "lumped_mass": false,
///                    "seed": 1, "sharp_features": true, "sliver_bound": 5,
///                    "meshing_runs": 4, "stretch": 1, "contact_spread": 0 }, ... ] }
/// "mesh" and a "material" that names a .json file are relative to the manifest's directory;
/// "name", "tets", "modes", "element" ("p1" or "p2": ObjectBakeSettings::elementOrder), "repair",
/// "lumped_mass", "seed", "sharp_features", "sliver_bound" and
/// "meshing_runs" (TetMeshSettings::meshingRuns, 1 to 8), "stretch" (TetMeshSettings::thinStretch,
/// 1 to 16) and "contact_spread" (ObjectBakeSettings::contactSpreadFraction, 0 to 0.99) are optional (defaults as in the
/// settings structs). Errors: FileNotFound, ParseError (naming the key), UnknownMaterial,
/// InvalidMaterial.
Result<std::vector<ObjectBakeSettings>> loadBakeManifest(const std::filesystem::path& path);

}  // namespace brittle
