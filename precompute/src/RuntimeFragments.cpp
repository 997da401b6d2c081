#include "brittle/precompute/RuntimeFragments.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "brittle/database/Pack.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/runtime/FragmentModes.h"
#include "brittle/runtime/World.h"
#include "Support.h"

namespace brittle {
namespace {

using detail::unit;

Error bad(const std::string& message) { return makeError(ErrorCode::InvalidArgument, message); }

// A point uniform over the surface (by area) and the outward unit normal of its face.
void samplePoint(const TriangleMesh& s, std::mt19937_64& rng, Eigen::Vector3d& point, Eigen::Vector3d& normal) {
  std::vector<double> cumulative(static_cast<size_t>(s.faces.rows()));
  double total = 0.0;
  for (Eigen::Index f = 0; f < s.faces.rows(); ++f) {
    const Eigen::Vector3d a = s.vertices.row(s.faces(f, 0)), b = s.vertices.row(s.faces(f, 1)),
                          c = s.vertices.row(s.faces(f, 2));
    total += 0.5 * (b - a).cross(c - a).norm();
    cumulative[static_cast<size_t>(f)] = total;
  }
  const double pick = unit(rng) * total;
  const auto f = static_cast<Eigen::Index>(
      std::min<size_t>(cumulative.size() - 1, std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin()));
  const Eigen::Vector3d a = s.vertices.row(s.faces(f, 0)), b = s.vertices.row(s.faces(f, 1)),
                        c = s.vertices.row(s.faces(f, 2));
  const double r1 = std::sqrt(unit(rng)), r2 = unit(rng);  // uniform on the triangle
  point = (1.0 - r1) * a + r1 * (1.0 - r2) * b + r1 * r2 * c;
  normal = (b - a).cross(c - a).normalized();
}

}  // namespace

Status validateRuntimeFragmentSettings(const RuntimeFragmentSettings& s) {
  if (!(s.fraction >= 0.0 && s.fraction <= 1.0)) return bad("RuntimeFragmentSettings.fraction must be in [0, 1]");
  if (s.targetTets < 100) return bad("RuntimeFragmentSettings.targetTets must be ≥ 100");
  if (s.modeCount < 1) return bad("RuntimeFragmentSettings.modeCount must be ≥ 1");
  if (!(s.minSpeedMps > 0.0) || !(s.maxSpeedMps >= s.minSpeedMps) || !std::isfinite(s.maxSpeedMps)) {
    return bad("RuntimeFragmentSettings: speeds must satisfy 0 < minSpeedMps ≤ maxSpeedMps < ∞");
  }
  return Ok{};
}

Result<RuntimeFragmentSource> RuntimeFragmentSource::build(const std::vector<BaseShapeDefinition>& shapes,
                                                           const std::vector<TriangleMesh>& surfaces,
                                                           const Material& material,
                                                           const RuntimeFragmentSettings& settings,
                                                           ProgressSink* progress) {
  if (Status st = validateRuntimeFragmentSettings(settings); !st) return st.error();
  if (shapes.size() != surfaces.size() || shapes.empty()) return bad("runtime fragments: one surface per base shape");
  RuntimeFragmentSource source;
  source.mSettings = settings;
  source.mMaterial = material;
  for (size_t i = 0; i < shapes.size(); ++i) {
    if (progress) progress->report("runtime fragment objects", static_cast<double>(i) / static_cast<double>(shapes.size()));
    ObjectBakeSettings b;
    b.name = shapes[i].name;
    b.sourceName = "base shape " + shapes[i].name;
    b.material = material;
    b.tetMesh.targetTets = settings.targetTets;
    b.modal.modeCount = settings.modeCount;
    b.fillOrdering = false;  // broken here to make database entries, as before the baked orders
    auto asset = bakeSurface(surfaces[i], b);
    if (!asset) return Error{asset.error().code, "runtime fragments, base shape '" + shapes[i].name + "': " + asset.error().message};
    auto topology = buildTetTopology(asset.value().tetMesh);
    if (!topology) return topology.error();
    source.mTopologies.push_back(std::move(topology).value());
    source.mObjects.push_back(std::move(asset).value());
  }
  if (progress) progress->report("runtime fragment objects", 1.0);
  return source;
}

Result<TriangleMesh> RuntimeFragmentSource::fragment(size_t shape, uint64_t seed, std::string* how, TetMesh* solid) const {
  if (shape >= mObjects.size()) return bad("runtime fragments: shape index out of range");
  const ObjectAsset& object = mObjects[shape];
  Pack pack;
  pack.materials.push_back(mMaterial);
  pack.objects.push_back(object);
  WorldSettings ws;
  ws.maxObjects = 64;
  ws.seed = seed;
  ws.fracture.matchFragments = false;
  auto world = World::create(std::move(pack), ws);
  if (!world) return world.error();
  auto id = world.value().addObject({.asset = object.name});
  if (!id) return id.error();

  std::mt19937_64 rng(seed);
  ImpactDesc d;
  d.object = id.value();
  // The impact point on the tet mesh's own boundary (the runtime's surface), by area.
  TriangleMesh boundary;
  boundary.vertices = object.tetMesh.nodes;
  boundary.faces = object.surfaceFaces;
  samplePoint(boundary, rng, d.pointWorld, d.normalWorld);
  const double size = (object.tetMesh.nodes.colwise().maxCoeff() - object.tetMesh.nodes.colwise().minCoeff()).norm();
  d.impactorMassKg = object.massProperties.massKg * (0.05 + 0.45 * unit(rng));
  d.impactorRadiusM = size * (0.02 + 0.08 * unit(rng));
  const double speed = mSettings.minSpeedMps * std::pow(mSettings.maxSpeedMps / mSettings.minSpeedMps, unit(rng));
  const double choice = unit(rng);
  ImpactResult result;
  for (int doubling = 0; doubling < 4; ++doubling) {
    d.speedMps = speed * std::pow(2.0, doubling);
    if (Status st = world.value().impact(d, result); !st) return st.error();
    if (result.broken) break;
  }
  if (!result.broken) {
    return makeError(ErrorCode::MeshingFailed, "runtime fragments: the body did not break at " +
                                                   std::to_string(d.speedMps) + " m/s");
  }
  std::vector<size_t> pieces;
  for (size_t i = 0; i < result.fragments.size(); ++i) {
    if (!result.fragments[i].debris) pieces.push_back(i);
  }
  if (pieces.empty()) return makeError(ErrorCode::MeshingFailed, "runtime fragments: every fragment is debris");
  const size_t pick = pieces[std::min(pieces.size() - 1, static_cast<size_t>(choice * static_cast<double>(pieces.size())))];
  if (solid) {
    auto sub = fragmentSubMesh(object.tetMesh, mTopologies[shape], result.fracture.nodeLabels, result.fracture.edgeCuts,
                               static_cast<int>(pick));
    if (!sub) return sub.error();
    if (sub.value().droppedVolumeM3 > 1e-9 * result.fragments[pick].massProperties.volumeM3) {
      return makeError(ErrorCode::MeshingFailed, "runtime fragments: the fragment's tets are not one solid");
    }
    *solid = std::move(sub.value().mesh);
  }
  if (how) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, " v=%.1f m/s, fragment %zu of %zu", d.speedMps, pick + 1, result.fragments.size());
    *how = std::string(kRuntimeCutPrefix) + buffer;  // brokenByTheRuntime (FragmentDatabase.h) reads it
  }
  return std::move(result.fragments[pick].surface);
}

}  // namespace brittle
