// Scene.h — a scene the player runs: breakable pack objects, rigid impactors, a floor, gravity,
// the duration, the time step and the seed. Read from JSON (assets/scenes/*.json):
//
//   { "gravity": [0, 0, -9.81], "duration": 1.5, "time_step": 0.004, "substeps": 2, "seed": 1,
//     "floor": { "height": 0.0, "material": "concrete" },
//     "objects": [ { "asset": "glass-plate", "name": "pane", "position": [0, 0, 0.5],
//                    "rotation": { "axis": [1, 0, 0], "angle_deg": 90 },   // or "quaternion": [w, x, y, z]
//                    "static": false, "velocity": [0, 0, 0], "angular_velocity": [0, 0, 0] } ],
//     "impactors": [ { "shape": "sphere", "radius": 0.03, "mass": 0.2, "material": "steel",
//                      "position": [0, -1, 0.5], "velocity": [0, 8, 0] },
//                    { "shape": "box", "half_extents": [0.05, 0.05, 0.05], ... } ] }
//
// SI units, world z up (the floor is the plane z = height, normal +z). Required: "duration",
// "time_step", "objects" (may be empty only when there are impactors). Optional, with defaults:
// "name" (the file stem), "gravity" ([0, 0, −9.81]), "substeps" (1), "seed" (1), "floor" (none),
// per object "name" (the asset name), "rotation" (identity), "static" (false), "velocity" and
// "angular_velocity" (zero); per impactor "material" ("steel"), "velocity" (zero), and
// "angular_velocity" (zero). Unknown keys are refused, so a typo never passes silently.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle {

struct SceneObject {
  std::string name;                                      ///< label in the statistics
  std::string asset;                                     ///< an object name in the pack
  Eigen::Vector3d positionWorldM = Eigen::Vector3d::Zero();  ///< where the asset's local origin goes
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< local → world, unit
  bool isStatic = false;                                 ///< immovable (but breakable); its fragments move
  Eigen::Vector3d velocityMps = Eigen::Vector3d::Zero();       ///< of the centre of mass
  Eigen::Vector3d angularVelocityRadPerS = Eigen::Vector3d::Zero();
};

enum class ImpactorShape { Sphere, Box };

struct RigidImpactor {
  std::string name;
  ImpactorShape shape = ImpactorShape::Sphere;
  double radiusM = 0.05;                                 ///< sphere
  Eigen::Vector3d halfExtentsM = Eigen::Vector3d::Constant(0.05);  ///< box
  double massKg = 1.0;
  std::string material = "steel";                        ///< a material preset (MaterialLibrary.h)
  Eigen::Vector3d positionWorldM = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d velocityMps = Eigen::Vector3d::Zero();
  Eigen::Vector3d angularVelocityRadPerS = Eigen::Vector3d::Zero();
};

struct SceneFloor {
  double heightM = 0.0;
  std::string material = "concrete";
};

struct Scene {
  std::string name;
  Eigen::Vector3d gravityMps2 = Eigen::Vector3d(0.0, 0.0, -9.81);
  double durationS = 1.0;
  double timeStepS = 1.0 / 240.0;  ///< one frame
  int substeps = 1;                ///< fixed Bullet steps per frame (each timeStepS / substeps)
  uint64_t seed = 1;
  std::optional<SceneFloor> floor;
  std::vector<SceneObject> objects;
  std::vector<RigidImpactor> impactors;
};

/// Parses a scene from JSON text; sourceName is used in messages. Errors: ParseError (bad JSON, a
/// missing, mistyped or unknown key; the message names the key path, e.g. "objects[1].position"),
/// InvalidArgument (a value out of range: duration ≤ 0 or > 600 s, time step ≤ 0 or > 0.1 s or
/// above the duration, substeps outside [1, 64], mass or size ≤ 0, a zero rotation axis or
/// quaternion, non-finite numbers, more than 100000 frames, no objects nor impactors),
/// UnknownMaterial (a material that is not a preset).
Result<Scene> parseScene(std::string_view json, std::string_view sourceName = "scene");

/// Reads a scene file. Errors: FileNotFound, then those of parseScene. The name defaults to the
/// file's stem.
Result<Scene> loadScene(const std::filesystem::path& path);

}  // namespace brittle
