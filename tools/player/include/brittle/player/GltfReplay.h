// GltfReplay.h — a played scene as a glTF 2.0 binary (.glb) that any glTF viewer replays.
//
// One node and one mesh per body (pack objects, fragments, debris: their surfaces; impactors: a
// sphere or a box), in metres, z up as in the scene (glTF's y-up convention is left to the viewer:
// a root node turns z up into y up). One animation samples every body's translation, rotation
// (LINEAR) and scale (STEP) at every frame boundary: a body that does not exist yet, or any more,
// has scale 0 and holds its first or last pose.
#pragma once

#include <filesystem>

#include "brittle/core/Result.h"
#include "brittle/player/Player.h"

namespace brittle {

/// Writes result as a .glb. Needs the per-frame tracks (PlayerSettings::recordTracks).
/// Errors: InvalidArgument (no tracks), PackIoError (cannot write the file).
Status writeGltfReplay(const PlayResult& result, const std::filesystem::path& path);

}  // namespace brittle
