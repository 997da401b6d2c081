#include "FractureStatsBench.h"

#include "BenchSupport.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/runtime/World.h"

namespace brittle::bench {
namespace {

struct Case {
  std::string name;
  Pack pack;
  std::vector<double> speeds;
};

Result<Case> bakeCase(const std::string& name, const TriangleMesh& surface, const std::string& material, int64_t tets,
                      int modes, std::vector<double> speeds) {
  auto m = materialPreset(material);
  if (!m) return m.error();
  ObjectBakeSettings b;
  b.name = name;
  b.material = m.value();
  b.tetMesh.targetTets = tets;
  b.modal.modeCount = modes;
  auto asset = bakeSurface(surface, b);
  if (!asset) return asset.error();
  Case c;
  c.name = name;
  c.pack.materials.push_back(m.value());
  c.pack.objects.push_back(std::move(asset).value());
  c.speeds = std::move(speeds);
  return c;
}

/// The impact of `seed` on the case: point, normal and impactor.
ImpactDesc impactFor(const Case& c, const FractureStatsBenchSettings& s, uint64_t seed, double speed) {
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 7);
  ImpactDesc d;
  d.speedMps = speed;
  if (c.name == "plate") {
    std::uniform_real_distribution<double> jitter(-s.jitterM, s.jitterM);
    const double x = jitter(rng), y = jitter(rng);
    d.pointWorld = Eigen::Vector3d(x, y, 0.005);
    d.normalWorld = Eigen::Vector3d::UnitZ();
    d.impactorMassKg = 0.1;
    d.impactorRadiusM = 0.02;
    return d;
  }
  // A corner of the brick's bounding box, its outward diagonal as the normal.
  const auto& v = c.pack.objects[0].tetMesh.nodes;
  const Eigen::Vector3d lo = v.colwise().minCoeff().transpose(), hi = v.colwise().maxCoeff().transpose();
  const int corner = static_cast<int>(rng() % 8);
  Eigen::Vector3d p, n;
  for (int i = 0; i < 3; ++i) {
    const bool high = (corner >> i) & 1;
    p[i] = high ? hi[i] : lo[i];
    n[i] = high ? 1.0 : -1.0;
  }
  d.pointWorld = p;
  d.normalWorld = n.normalized();
  d.impactorMassKg = std::numeric_limits<double>::infinity();
  d.impactorRadiusM = std::numeric_limits<double>::infinity();
  return d;
}

}  // namespace

Status runFractureStatsBench(const FractureStatsBenchSettings& s) {
  if (s.seeds < 1 || (s.plateSpeedsMps.empty() && s.brickSpeedsMps.empty())) {
    return makeError(ErrorCode::InvalidArgument, "bench fracture: needs speeds and seeds ≥ 1");
  }
  for (const auto* speeds : {&s.plateSpeedsMps, &s.brickSpeedsMps}) {
    for (double v : *speeds) {
      if (!(v > 0.0 && std::isfinite(v))) return makeError(ErrorCode::InvalidArgument, "bench fracture: speeds must be > 0");
    }
  }
  std::ofstream csv(s.csv);
  if (!csv) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  csv << "case,tets,modes,speed_mps,seed,broken,fragments,pieces,largest_mass_fraction,peak_pa,impact_ms\n";

  std::vector<Case> cases;
  if (!s.plateSpeedsMps.empty()) {
    auto plate = bakeCase("plate", boxSurface(0.3, 0.3, 0.01), "glass", s.plateTets, s.modes, s.plateSpeedsMps);
    if (!plate) return plate.error();
    cases.push_back(std::move(plate).value());
  }
  if (!s.brickSpeedsMps.empty()) {
    auto surface = readSurfaceMesh(s.brickMesh);
    if (!surface) return surface.error();
    auto brick = bakeCase("brick", surface.value(), "concrete", s.brickTets, s.modes, s.brickSpeedsMps);
    if (!brick) return brick.error();
    cases.push_back(std::move(brick).value());
  }

  for (const Case& c : cases) {
    const int64_t tets = c.pack.objects[0].tetMesh.tets.rows();
    for (double speed : c.speeds) {
      std::vector<double> counts;
      for (int seed = 1; seed <= s.seeds; ++seed) {
        WorldSettings ws;
        ws.seed = static_cast<uint64_t>(seed);
        ws.fracture.matchFragments = false;  // no database: the statistics are the fracture's own
        auto world = World::create(Pack(c.pack), ws);
        if (!world) return world.error();
        auto id = world.value().addObject({.asset = c.name});
        if (!id) return id.error();
        ImpactDesc d = impactFor(c, s, static_cast<uint64_t>(seed), speed);
        d.object = id.value();
        auto r = world.value().impact(d);
        if (!r) return r.error();
        const ImpactResult& res = r.value();
        int pieces = 0;
        double total = 0.0, largest = 0.0;
        for (const auto& f : res.fragments) {
          total += f.massProperties.massKg;
          largest = std::max(largest, f.massProperties.massKg);
          if (!f.debris) ++pieces;
        }
        const int fragments = res.broken ? static_cast<int>(res.fragments.size()) : 1;
        if (!res.broken) pieces = 1;
        const double largestFraction = res.broken && total > 0.0 ? largest / total : 1.0;
        counts.push_back(fragments);
        csv << c.name << "," << tets << "," << res.modesUsed << "," << speed << "," << seed << "," << res.broken << ","
            << fragments << "," << pieces << "," << largestFraction << "," << res.peakPrincipalStressPa << ","
            << 1e3 * res.times.totalS() << "\n";
      }
      if (!s.quiet) {
        std::fprintf(stderr, "bench fracture: %s at %5.1f m/s: fragments median %.0f, p10 %.0f, p90 %.0f over %d seeds\n",
                     c.name.c_str(), speed, percentile(counts, 0.5), percentile(counts, 0.1), percentile(counts, 0.9),
                     s.seeds);
      }
    }
  }
  if (!csv.flush()) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  return Ok{};
}

}  // namespace brittle::bench
