// Renderer.h — draws a playing scene with OpenGL 2.1 (fixed function: it runs on Mesa's software
// renderer under Xvfb as on any desktop driver), shared by the viewer and `brittle play --frames`.
//
// Bodies are drawn flat-shaded from their surfaces (local frame, posed by BodyView), one colour
// per kind (objects blue-grey, fragments teal, debris sand, impactors steel); the floor is a
// checkered square around the scene. The camera orbits a target (yaw about z, pitch above the
// horizon, distance) and is framed on the scene's bodies at the start.
//
// A GL context must be current on the calling thread for every call but the camera's.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <vector>

#include "brittle/core/Result.h"
#include "brittle/player/Player.h"

namespace brittle {

struct OrbitCamera {
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  double yawDeg = 35.0, pitchDeg = 25.0, distanceM = 2.0;
  double fovYDeg = 45.0;
  Eigen::Vector3d eye() const;
  /// A camera that sees every body and a margin around them.
  static OrbitCamera framing(const std::vector<BodyView>& bodies, std::optional<double> floorHeightM);
  /// The world ray through window pixel (x, y) (origin top-left) of a width × height view.
  void ray(double x, double y, int width, int height, Eigen::Vector3d& origin, Eigen::Vector3d& direction) const;
};

class Renderer {
 public:
  /// Draws the bodies (and the floor at floorHeightM, if any) into the current framebuffer.
  void draw(const std::vector<BodyView>& bodies, const OrbitCamera& camera, std::optional<double> floorHeightM,
            int width, int height);
  /// Drops the cached body meshes (they are kept by body index): call when a new play starts.
  void forget() { mMeshes.clear(); }
  /// The current framebuffer as RGBA, top row first.
  std::vector<uint8_t> readPixels(int width, int height) const;
  /// Error: PackIoError (the PNG cannot be written).
  static Status writePng(const std::filesystem::path& path, const std::vector<uint8_t>& rgba, int width, int height);

 private:
  struct Mesh {
    std::vector<float> positions, normals;  // per triangle corner, local frame
  };
  const Mesh& meshFor(const BodyView& body);
  std::map<int32_t, Mesh> mMeshes;  // by body index
};

}  // namespace brittle
