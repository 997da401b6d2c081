#include "ElementBench.h"

#include "BenchSupport.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>

#include "brittle/database/Pack.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshIO.h"
#include "brittle/precompute/ModelSizing.h"
#include "brittle/runtime/World.h"

namespace brittle::bench {
namespace {

struct ElementCase {
  std::string name;
  std::string material;
  double referenceHz = 0.0;
  std::vector<int64_t> p1Tets, p2Tets;
};

// The default ladders. Mesh_3 does not make the plate coarser than ~7.4k tets (one element
// through its 10 mm), whatever the target.
const std::map<std::string, ElementCase> kElementCases = {
    {"plate", {"plate", "glass", 389.4, {7000, 15000, 30000}, {6000, 12000}}},
    {"beam", {"beam", "glass", 526.0, {1000, 4000, 16000}, {300, 1000, 4000}}},
    {"brick", {"brick", "concrete", 4267.0, {500, 2000, 8000}, {300, 800, 3000}}},
};

}  // namespace

Status runElementBench(const ElementBenchSettings& s) {
  if (s.modes < 1 || s.impacts < 1 || !(s.speedMps > 0.0 && std::isfinite(s.speedMps))) {
    return makeError(ErrorCode::InvalidArgument, "bench elements: modes and impacts must be ≥ 1, the speed finite and > 0");
  }
  for (const std::string& c : s.cases) {
    if (!kElementCases.contains(c)) return makeError(ErrorCode::InvalidArgument, "bench elements: unknown case '" + c + "' (plate, beam, brick)");
  }
  std::ofstream csv(s.csv);
  if (!csv) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  csv << "case,element,target_tets,tets,dofs,first_frequency_hz,reference_hz,error,bake_s,impacts,median_impact_ms,"
         "median_stress_ms,broken_fraction\n";
  for (const std::string& name : s.cases) {
    const ElementCase& c = kElementCases.at(name);
    TriangleMesh surface;
    if (name == "plate") surface = boxSurface(0.3, 0.3, 0.01);
    if (name == "beam") surface = boxSurface(1.0, 0.1, 0.1);
    if (name == "brick") {
      auto read = readSurfaceMesh(s.brickMesh);
      if (!read) return read.error();
      surface = std::move(read).value();
    }
    const Material material = materialPreset(c.material).value();
    for (ElementOrder order : {ElementOrder::P1, ElementOrder::P2}) {
      const std::vector<int64_t>& given = order == ElementOrder::P1 ? s.p1Tets : s.p2Tets;
      const std::vector<int64_t>& targets = given.empty() ? (order == ElementOrder::P1 ? c.p1Tets : c.p2Tets) : given;
      for (int64_t target : targets) {
        ObjectBakeSettings b;
        b.name = name;
        b.material = material;
        b.tetMesh.targetTets = target;
        b.modal.modeCount = s.modes;
        b.elementOrder = order;
        auto asset = bakeSurface(surface, b);
        if (!asset) return asset.error();
        const ObjectAsset& a = asset.value();
        const double f1 = a.modal.frequenciesHz(0);
        const int64_t dofs = a.modal.modes.rows();

        Pack pack;
        pack.materials.push_back(material);
        pack.objects.push_back(a);
        WorldSettings ws;
        ws.seed = s.seed;
        auto world = World::create(std::move(pack), ws);
        if (!world) return world.error();
        SceneObjectRange range;
        range.name = name;
        range.minSpeedMps = range.maxSpeedMps = s.speedMps;
        range.impactors.push_back(SceneImpactor{.massKg = 0.1, .radiusM = 0.02, .material = materialPreset("steel").value()});
        std::vector<double> totalMs, stressMs;
        int broken = 0;
        ImpactResult result;
        for (ImpactDesc d : drawSceneImpacts(a, range, s.impacts, s.seed)) {
          auto id = world.value().addObject({.asset = name});
          if (!id) return id.error();
          if (Status st = world.value().waitUntilPrepared(); !st) return st;
          d.object = id.value();
          if (Status st = world.value().impact(d, result); !st) return st;
          totalMs.push_back(1e3 * result.times.totalS());
          stressMs.push_back(1e3 * result.times.stressS);
          broken += result.broken ? 1 : 0;
          if (world.value().isAlive(id.value())) (void)world.value().removeObject(id.value());
          for (const FragmentResult& f : result.fragments)
            if (f.object.valid()) (void)world.value().removeObject(f.object);
        }
        const double error = f1 / c.referenceHz - 1.0;
        csv << name << "," << elementOrderName(order) << "," << target << "," << a.tetMesh.tets.rows() << "," << dofs << ","
            << f1 << "," << c.referenceHz << "," << error << "," << a.bake.totalS << "," << totalMs.size() << ","
            << percentile(totalMs, 0.5) << "," << percentile(stressMs, 0.5) << ","
            << static_cast<double>(broken) / static_cast<double>(std::max<size_t>(totalMs.size(), 1)) << "\n";
        if (!s.quiet) {
          std::fprintf(stderr, "bench elements: %-5s %s %6lld tets %7lld dofs: f1 %8.1f Hz (%+.2f %%), bake %.1f s, impact %.2f ms\n",
                       name.c_str(), elementOrderName(order), static_cast<long long>(a.tetMesh.tets.rows()),
                       static_cast<long long>(dofs), f1, 100.0 * error, a.bake.totalS, percentile(totalMs, 0.5));
        }
      }
    }
  }
  if (!csv.flush()) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  return Ok{};
}

}  // namespace brittle::bench
