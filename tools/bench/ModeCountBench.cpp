#include "ModeCountBench.h"

#include "BenchSupport.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <random>

#include "brittle/core/Timing.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/FullFemReference.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/runtime/World.h"

namespace brittle::bench {
namespace {

double median(const std::vector<double>& v) { return percentile(v, 0.5); }

}  // namespace

Status runModeCountBench(const ModeCountBenchSettings& s) {
  if (s.modes.empty() || s.points < 1 || s.repeats < 1) {
    return makeError(ErrorCode::InvalidArgument, "bench modes: needs mode counts, points ≥ 1 and repeats ≥ 1");
  }
  std::ofstream csv(s.csv);
  if (!csv) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  csv << "point,x,y,tets,modes,reference_pa,corrected_pa,uncorrected_pa,corrected_error,uncorrected_error,"
         "impact_ms,impact_ms_without_correction,reference_s,broken\n";
  const Material glass = materialPreset("glass").value();
  ObjectBakeSettings b;
  b.name = "plate";
  b.material = glass;
  b.tetMesh.targetTets = s.tets;
  b.modal.modeCount = *std::max_element(s.modes.begin(), s.modes.end());
  const auto bakeStart = SteadyClock::now();
  auto asset = bakeSurface(boxSurface(0.3, 0.3, 0.01), b);
  if (!asset) return asset.error();
  if (!s.quiet) {
    std::fprintf(stderr, "bench modes: plate baked, %lld tets, %d modes, %.1f s\n",
                 static_cast<long long>(asset.value().tetMesh.tets.rows()), b.modal.modeCount,
                 secondsSince(bakeStart));
  }
  Pack pack;
  pack.materials.push_back(glass);
  pack.objects.push_back(std::move(asset).value());
  const TetMesh& mesh = pack.objects[0].tetMesh;

  std::mt19937_64 rng(s.seed);
  std::uniform_real_distribution<double> across(-0.12, 0.12);
  for (int point = 0; point < s.points; ++point) {
    const double x = point == 0 ? 0.0 : across(rng), y = point == 0 ? 0.0 : across(rng);
    ImpactDesc d;
    d.pointWorld = Eigen::Vector3d(x, y, 0.005);
    d.normalWorld = Eigen::Vector3d::UnitZ();
    d.speedMps = s.speedMps;
    d.impactorMassKg = 0.1;
    d.impactorRadiusM = 0.02;
    FullFemResult reference;
    double referenceS = 0.0;
    for (int modes : s.modes) {
      double corrected = 0.0, uncorrected = 0.0;
      bool broken = false;
      std::vector<double> times[2];
      for (bool correction : {true, false}) {
        WorldSettings ws;
        ws.seed = s.seed;
        ws.fracture.modeCount = modes;
        ws.fracture.staticCorrection = correction;
        ws.fracture.reportUncorrectedPeak = correction;
        ws.fracture.matchFragments = false;  // no database in this pack
        for (int rep = 0; rep < s.repeats; ++rep) {
          auto world = World::create(Pack(pack), ws);
          if (!world) return world.error();
          auto id = world.value().addObject({.asset = "plate"});
          if (!id) return id.error();
          d.object = id.value();
          auto r = world.value().impact(d);
          if (!r) return r.error();
          times[correction ? 0 : 1].push_back(1e3 * r.value().times.totalS());
          if (!correction) continue;
          corrected = r.value().peakPrincipalStressPa;
          uncorrected = r.value().peakWithoutCorrectionPa;
          broken = r.value().broken;
          if (referenceS == 0.0) {
            FullFemSettings fs;
            fs.stepsPerContact = s.referenceStepsPerContact;
            fs.extraS = r.value().ringDownS;
            const auto start = SteadyClock::now();
            auto ref = solveFullFemImpact(mesh, glass, r.value().loadWeights, r.value().forceDirectionLocal,
                                          r.value().contact, fs);
            if (!ref) return ref.error();
            referenceS = secondsSince(start);
            reference = ref.value();
          }
        }
      }
      const double ref = reference.peakPrincipalPa;
      csv << point << "," << x << "," << y << "," << mesh.tets.rows() << "," << modes << "," << ref << "," << corrected << ","
          << uncorrected << "," << corrected / ref - 1.0 << "," << uncorrected / ref - 1.0 << "," << median(times[0]) << ","
          << median(times[1]) << "," << referenceS << "," << broken << "\n";
      if (!s.quiet) {
        std::fprintf(stderr, "bench modes: point %d, %3d modes: %+.1f %% corrected, %+.1f %% without, %.2f ms (reference %.1f s)\n",
                     point, modes, 100.0 * (corrected / ref - 1.0), 100.0 * (uncorrected / ref - 1.0), median(times[0]),
                     referenceS);
      }
    }
  }
  if (!csv.flush()) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  return Ok{};
}

}  // namespace brittle::bench
