#include "ResolutionBench.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "BenchSupport.h"
#include "brittle/precompute/BakePipeline.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/precompute/MeshIO.h"

namespace brittle::bench {

Status runResolutionBench(const ResolutionBenchSettings& s) {
  if (s.tets.size() < 2 || s.modes < 1) {
    return makeError(ErrorCode::InvalidArgument, "bench resolution: needs two tet counts or more and modes ≥ 1");
  }
  auto surface = readSurfaceMesh(s.mesh);
  if (!surface) return surface.error();
  auto material = resolveMaterial(s.material);
  if (!material) return material.error();
  std::vector<int64_t> targets = s.tets;
  std::sort(targets.begin(), targets.end());

  struct Row {
    int64_t target = 0, tets = 0;
    double meshingS = 0.0, modalS = 0.0, totalS = 0.0;
    std::vector<double> frequencies;
  };
  std::vector<Row> rows;
  for (int64_t target : targets) {
    ObjectBakeSettings b;
    b.name = s.mesh.stem().string();
    b.material = material.value();
    b.tetMesh.targetTets = target;
    b.modal.modeCount = s.modes;
    auto asset = bakeSurface(surface.value(), b);
    if (!asset) return asset.error();
    const ObjectAsset& a = asset.value();
    Row row{target, a.tetMesh.tets.rows(), a.bake.meshingS, a.bake.modalS, a.bake.totalS, {}};
    for (int j = 0; j < s.modes; ++j) row.frequencies.push_back(a.modal.frequenciesHz(j));
    if (!s.quiet) {
      std::fprintf(stderr, "bench resolution: %lld tets (target %lld): f1 %.1f Hz, bake %.2f s\n",
                   static_cast<long long>(row.tets), static_cast<long long>(target), row.frequencies[0], row.totalS);
    }
    rows.push_back(std::move(row));
  }

  // Richardson: λ(h) = λ* + C h², h ∝ n^(−1/3), from the two finest meshes.
  const Row& fine = rows.back();
  const Row& next = rows[rows.size() - 2];
  const double ratio = std::pow(static_cast<double>(next.tets) / static_cast<double>(fine.tets), -2.0 / 3.0);  // h²_next / h²_fine
  std::vector<double> reference;
  for (int j = 0; j < s.modes; ++j) {
    const double lf = std::pow(fine.frequencies[j], 2), ln = std::pow(next.frequencies[j], 2);
    reference.push_back(std::sqrt(std::max(lf - (ln - lf) / (ratio - 1.0), 0.0)));
  }

  std::ofstream csv(s.csv);
  if (!csv) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  csv << "target_tets,tets,mode,frequency_hz,reference_hz,error,difference_from_finest,meshing_s,modal_s,bake_s\n";
  for (const Row& row : rows) {
    for (int j = 0; j < s.modes; ++j) {
      csv << row.target << "," << row.tets << "," << j << "," << row.frequencies[j] << "," << reference[j] << ","
          << row.frequencies[j] / reference[j] - 1.0 << "," << row.frequencies[j] / fine.frequencies[j] - 1.0 << ","
          << row.meshingS << "," << row.modalS << "," << row.totalS << "\n";
    }
  }
  if (!csv.flush()) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  return Ok{};
}

}  // namespace brittle::bench
