// ViewerScript.h — timed inputs for `brittle view --script`, so that the viewer runs unattended
// (tests under Xvfb, recorded demos):
//
//   { "events": [
//       { "frame": 10, "action": "throw", "from": [0, -1, 0.3], "to": [0, 0, 0.02], "speed": 12,
//         "radius": 0.02, "mass": 0.2, "material": "steel" },
//       { "frame": 40, "action": "screenshot", "file": "after.png" },
//       { "frame": 40, "action": "camera", "yaw_deg": 30, "pitch_deg": 25, "distance": 1.2 },
//       { "frame": 50, "action": "pause" }, { "frame": 50, "action": "step" },
//       { "frame": 50, "action": "resume" }, { "frame": 80, "action": "quit" } ] }
//
// An event fires when the simulation has played `frame` frames (events of the same frame fire in
// file order; while paused, the next event fires on the next drawn frame). "throw" launches a
// sphere from "from" towards "to" at "speed" m/s (radius 0.02 m, mass 0.2 kg and steel unless
// given); "screenshot" writes a PNG of what is drawn; "camera" sets the orbit (any of its keys);
// "step" plays one frame while paused. Unknown keys and actions are refused.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle {

enum class ScriptAction { Throw, Screenshot, Camera, Pause, Resume, Step, Quit };
std::string_view scriptActionName(ScriptAction action);

struct ScriptEvent {
  int64_t frame = 0;
  ScriptAction action = ScriptAction::Quit;
  // throw
  Eigen::Vector3d from = Eigen::Vector3d::Zero(), to = Eigen::Vector3d::Zero();
  double speedMps = 10.0, radiusM = 0.02, massKg = 0.2;
  std::string material = "steel";
  // screenshot
  std::filesystem::path file;
  // camera
  std::optional<double> yawDeg, pitchDeg, distanceM;
};

struct ViewerScript {
  std::vector<ScriptEvent> events;  ///< ordered by frame, file order within a frame
};

/// Parses a script. Errors: ParseError (bad JSON, a missing, mistyped or unknown key or action,
/// naming "events[i].key"), InvalidArgument (a negative frame, speed, radius or mass ≤ 0 or not
/// finite, "from" equal to "to", an empty file name), UnknownMaterial.
Result<ViewerScript> parseViewerScript(std::string_view json, std::string_view sourceName = "script");

/// Reads a script file; screenshot paths are relative to the current directory. Errors:
/// FileNotFound, then those of parseViewerScript.
Result<ViewerScript> loadViewerScript(const std::filesystem::path& path);

}  // namespace brittle
