// brittle_consumer — loads a pack, places one object and hits the middle of its top face from above
// with a 0.1 kg steel ball at 3 m/s. Exit 0 only if the impact succeeded with a plausible contact.
//   brittle_consumer <pack.h5> [object]   (default: the pack's first object)
#include <cmath>
#include <iostream>
#include <string>
#include <utility>

#include "brittle/database/Pack.h"
#include "brittle/runtime/World.h"

namespace {

int fail(const brittle::Error& error) {
  std::cerr << "error [" << brittle::errorCodeName(error.code) << "]: " << error.message << "\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: brittle_consumer <pack.h5> [object]\n";
    return 2;
  }
  auto pack = brittle::readPack(argv[1]);
  if (!pack) return fail(pack.error());
  if (pack.value().objects.empty()) return fail({brittle::ErrorCode::InvalidArgument, "the pack has no object"});
  const std::string object = argc > 2 ? argv[2] : pack.value().objects.front().name;

  auto world = brittle::World::create(std::move(pack).value());
  if (!world) return fail(world.error());
  auto id = world.value().addObject({.asset = object});
  if (!id) return fail(id.error());
  auto asset = world.value().objectAsset(id.value());
  if (!asset) return fail(asset.error());
  // The object sits at the origin unrotated, so its local nodes are world positions.
  const brittle::Points& nodes = asset.value()->tetMesh.nodes;
  const Eigen::Vector3d lo = nodes.colwise().minCoeff().transpose(), hi = nodes.colwise().maxCoeff().transpose();

  auto result = world.value().impact({.object = id.value(),
                                      .pointWorld = {0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), hi.z()},
                                      .normalWorld = Eigen::Vector3d::UnitZ(),
                                      .speedMps = 3.0,
                                      .impactorMassKg = 0.1,
                                      .impactorRadiusM = 0.02});
  if (!result) return fail(result.error());
  const brittle::ImpactResult& r = result.value();
  std::cout << object << ": contact " << r.contact.durationS * 1e6 << " us, peak force " << r.contact.pulseAmplitudeN
            << " N, peak principal stress " << r.peakPrincipalStressPa / 1e6 << " MPa, " << r.modesUsed << " modes, "
            << (r.broken ? std::to_string(r.fragments.size()) + " fragments" : std::string("not broken")) << "\n";
  const bool plausible = std::isfinite(r.contact.durationS) && r.contact.durationS > 0.0 &&
                         std::isfinite(r.contact.pulseAmplitudeN) && r.contact.pulseAmplitudeN > 0.0 &&
                         std::isfinite(r.peakPrincipalStressPa) && r.peakPrincipalStressPa > 0.0 && r.modesUsed > 0;
  if (!plausible) return fail({brittle::ErrorCode::InvalidArgument, "implausible impact result"});
  return 0;
}
