// BaseShapes.h — the solids the fragment database is cut from: procedural ones (box, plate, rod,
// sphere, cone, wedge, blob) and surface meshes read from files (mesh: the scene's own objects,
// so that the database holds pieces of what the runtime breaks), and their JSON definitions
// (assets/shapes/base-shapes.json).
//
// Every shape is centred on its bounding box at the origin, in metres, and is closed, outward
// (counter-clockwise seen from outside), manifold, one component and free of degenerate faces, so
// it passes validateSurfaceMesh (MeshValidation.h).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"

namespace brittle {

enum class BaseShapeKind { Box, Plate, Rod, Sphere, Cone, Wedge, Blob, Mesh };

/// "box", "plate", "rod", "sphere", "cone", "wedge", "blob", "mesh".
const char* baseShapeKindName(BaseShapeKind kind);
/// Inverse of baseShapeKindName. Error: InvalidArgument listing the kinds.
Result<BaseShapeKind> parseBaseShapeKind(std::string_view name);

struct BaseShapeDefinition {
  std::string name;
  BaseShapeKind kind = BaseShapeKind::Box;
  /// Full extents along x, y, z (m). Box and plate: the box (a plate is a flat box, e.g.
  /// 1 × 1 × 0.1). Rod and cone: diameters along x and y, length along z (cone apex at +z).
  /// Sphere and blob: the three diameters (an ellipsoid when they differ). Wedge: a right
  /// triangle with legs x and z, extruded along y.
  Eigen::Vector3d sizeM = Eigen::Vector3d::Ones();
  /// Rod and cone: segments around the axis, in [3, 256]. Sphere and blob: icosphere subdivision
  /// level, in [0, 6] (20·4^level faces), so the default 24 must be set for them (the JSON loader
  /// defaults them to 3). Ignored by box, plate and wedge.
  int segments = 24;
  /// Blob only: relative amplitude of the smooth radial bumps, in [0, 0.9) (e.g. 0.25).
  double noiseAmplitude = 0.0;
  uint64_t seed = 1;  ///< blob only: places the bumps
  /// Mesh only: the closed surface mesh (any format readSurfaceMesh reads), in metres; it keeps
  /// its own size and proportions (sizeM is ignored) and is centred on its bounding box.
  std::filesystem::path meshPath;
};

/// The surface of one base shape. Rod: a capped prism on the inscribed regular n-gon; cone: a
/// pyramid on it; sphere: a subdivided icosahedron with vertices on the ellipsoid; blob: that
/// icosphere with radius r(u) = 1 + noise·tanh(Σ_k w_k exp(−|u − c_k|²/0.5)) along each unit
/// direction u, from six seeded bumps (centres c_k, weights w_k in [−1, 1]). r > 0 keeps the blob
/// star-shaped about the origin, which makes it valid for every seed.
/// Mesh: the file, read and checked as a bake's input (validateSurfaceMesh: closed, outward,
/// manifold, one component), then centred on its bounding box.
/// Errors: InvalidArgument (non-finite or non-positive size, segments or noise out of range, a
/// mesh shape without a path); a mesh shape's file: those of readSurfaceMesh and
/// validateSurfaceMesh, naming the shape.
Result<TriangleMesh> makeBaseShape(const BaseShapeDefinition& definition);

/// Reads base shape definitions:
///   { "shapes": [ { "name": "box", "kind": "box", "size": [1, 1, 1] },
///                 { "name": "blob", "kind": "blob", "size": [1, 0.8, 0.7], "segments": 3,
///                   "noise": 0.25, "seed": 7 }, ... ] }
/// "size" is sizeM (m). "segments" (default 24; sphere and blob: 3), "noise" (default 0) and
/// "seed" (unsigned, default 1) are optional; other keys are rejected. A mesh shape has "mesh", a
/// path relative to the JSON file (or absolute), instead of "size":
///   { "name": "plate", "kind": "mesh", "mesh": "../meshes/plate.off" }
/// Its file is checked to exist here and read when the shape is built. Names are unique and
/// non-empty. Every shape is checked as makeBaseShape checks it (without building its mesh).
/// Errors: FileNotFound; ParseError naming the file, the shape index and the key (bad JSON, a
/// missing, unknown or mistyped key, a duplicate name, a shape makeBaseShape rejects).
Result<std::vector<BaseShapeDefinition>> loadBaseShapes(const std::filesystem::path& jsonPath);

}  // namespace brittle
