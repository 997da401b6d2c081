#include "ExactModesBench.h"

#include "BenchSupport.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <string>

#include "brittle/core/Timing.h"
#include "brittle/database/FragmentMatcher.h"
#include "brittle/database/ScalingLaws.h"
#include "brittle/precompute/FrequencyErrorCalibration.h"
#include "brittle/runtime/FragmentModes.h"
#include "brittle/runtime/PolynomialModes.h"
#include "brittle/runtime/World.h"

namespace brittle::bench {
namespace {

// Each tet split into eight (edge midpoints, shared by the tets around an edge; the inner
// octahedron along its m02–m13 diagonal): the same solid at half the element size.
TetMesh refine(const TetMesh& mesh) {
  std::map<std::pair<int32_t, int32_t>, int32_t> midpoint;
  std::vector<Eigen::Vector3d> points;
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) points.emplace_back(mesh.nodes.row(i).transpose());
  auto mid = [&](int32_t a, int32_t b) {
    auto [it, inserted] = midpoint.try_emplace({std::min(a, b), std::max(a, b)}, static_cast<int32_t>(points.size()));
    if (inserted) points.push_back(0.5 * (points[static_cast<size_t>(a)] + points[static_cast<size_t>(b)]));
    return it->second;
  };
  std::vector<std::array<int32_t, 4>> tets;
  auto add = [&](int32_t a, int32_t b, int32_t c, int32_t d) {
    const Eigen::Vector3d pa = points[static_cast<size_t>(a)];
    const double v = (points[static_cast<size_t>(b)] - pa).dot((points[static_cast<size_t>(c)] - pa).cross(points[static_cast<size_t>(d)] - pa));
    tets.push_back(v > 0.0 ? std::array<int32_t, 4>{a, b, c, d} : std::array<int32_t, 4>{a, c, b, d});
  };
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
    const int32_t n0 = mesh.tets(e, 0), n1 = mesh.tets(e, 1), n2 = mesh.tets(e, 2), n3 = mesh.tets(e, 3);
    const int32_t m01 = mid(n0, n1), m02 = mid(n0, n2), m03 = mid(n0, n3), m12 = mid(n1, n2), m13 = mid(n1, n3), m23 = mid(n2, n3);
    add(n0, m01, m02, m03);
    add(m01, n1, m12, m13);
    add(m02, m12, n2, m23);
    add(m03, m13, m23, n3);
    add(m02, m13, m01, m03);
    add(m02, m13, m03, m23);
    add(m02, m13, m23, m12);
    add(m02, m13, m12, m01);
  }
  TetMesh out;
  out.nodes.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) out.nodes.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  out.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (size_t i = 0; i < tets.size(); ++i)
    for (int k = 0; k < 4; ++k) out.tets(static_cast<Eigen::Index>(i), k) = tets[i][static_cast<size_t>(k)];
  return out;
}

}  // namespace

Status runExactModesBench(const ExactModesBenchSettings& s) {
  if (s.speedsMps.empty() || s.seeds < 1 || s.maxFragmentsPerImpact < 1 || s.exactModes < 1 || s.repeats < 1 || s.referenceMaxTets < 0 ||
      s.entryLimits.empty() || std::any_of(s.entryLimits.begin(), s.entryLimits.end(), [](int64_t n) { return n < 0; })) {
    return makeError(ErrorCode::InvalidArgument,
                     "bench exact-modes: speeds, seeds ≥ 1, max fragments ≥ 1, repeats ≥ 1 and reference max tets ≥ 0 needed");
  }
  auto pack = readPack(s.pack);
  if (!pack) return pack.error();
  const Pack& p = pack.value();
  if (p.database.empty() || !p.database.hasPhysics()) {
    return makeError(ErrorCode::InvalidArgument, "bench exact-modes: the pack " + s.pack.filename().string() + " has no fragment database");
  }
  std::vector<std::string> objects = s.objects;
  if (objects.empty())
    for (const ObjectAsset& a : p.objects) objects.push_back(a.name);
  for (const std::string& name : objects)
    if (std::none_of(p.objects.begin(), p.objects.end(), [&](const ObjectAsset& a) { return a.name == name; })) {
      return makeError(ErrorCode::InvalidArgument, "bench exact-modes: no object '" + name + "' in the pack");
    }
  FragmentMatcherSettings ms;
  for (DescriptorKind k : kAllDescriptorKinds) ms.enabled[static_cast<size_t>(k)] = k == s.descriptor;
  std::vector<FragmentMatcher> matchers;
  std::vector<int64_t> entryCounts;
  for (int64_t limit : s.entryLimits) {
    ms.entryLimit = limit;
    auto matcher = FragmentMatcher::build(p.database, ms);
    if (!matcher) return matcher.error();
    matchers.push_back(std::move(matcher).value());
    entryCounts.push_back(limit > 0 ? std::min<int64_t>(limit, static_cast<int64_t>(p.database.entries.size()))
                                    : static_cast<int64_t>(p.database.entries.size()));
  }

  std::ofstream csv(s.csv);
  if (!csv) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  csv << "object,speed_mps,seed,fragment,volume_fraction,parent_tets,sub_tets,dropped_volume_fraction,modes,match_s,exact_s,"
         "reference_s,match_distance,match_freq_err,exact_freq_err,reference_f1_hz,exact_f1_hz,match_f1_hz,"
         "predicted_err_median,predicted_err_p90,predicted_beyond_range,polynomial3_freq_err,polynomial4_freq_err,polynomial5_freq_err,"
         "polynomial5_f1_hz,polynomial3_s,polynomial4_s,polynomial5_s,mesh_ratio_freq_err,mesh_ratio_f1_hz,mesh_ratio_s,p1_dof,check_dof,mesh_ratio_p2_freq_err,mesh_ratio_p2_s,database_entries,"
         "ritz_indicator,ritz_predicted_median,ritz_predicted_p90,check_indicator,check_predicted_median,check_predicted_p90\n";
  csv.precision(9);
  for (const std::string& name : objects) {
    const ObjectAsset& asset = *std::find_if(p.objects.begin(), p.objects.end(), [&](const ObjectAsset& a) { return a.name == name; });
    const Material& material = *std::find_if(p.materials.begin(), p.materials.end(),
                                             [&](const Material& m) { return m.name == asset.materialName; });
    auto topology = buildTetTopology(asset.tetMesh);
    if (!topology) return topology.error();
    for (double speed : s.speedsMps)
      for (int seed = 1; seed <= s.seeds; ++seed) {
        WorldSettings ws;
        ws.seed = static_cast<uint64_t>(seed);
        ws.fracture.matchFragments = false;  // both paths are timed here, one fragment at a time
        Pack one;
        one.materials = p.materials;
        one.objects.push_back(asset);
        auto world = World::create(std::move(one), ws);
        if (!world) return world.error();
        auto id = world.value().addObject({.asset = name});
        if (!id) return id.error();
        auto hit = world.value().impact(seededImpact(asset, id.value(), static_cast<uint64_t>(seed), speed));
        if (!hit) return hit.error();
        if (!hit.value().broken) continue;
        const ImpactResult& r = hit.value();
        for (size_t i : piecesSpreadOverSizes(r, s.maxFragmentsPerImpact)) {
          const FragmentResult& fr = r.fragments[i];
          // Exact path.
          ExactModesSettings es;
          es.modeCount = s.exactModes;
          es.elementOrder = asset.elementOrder;  // as the World: a fragment keeps its parent's element
          Result<FragmentSubMesh> sub = makeError(ErrorCode::InvalidArgument, "no sub-mesh");
          Result<ObjectAsset> exact = makeError(ErrorCode::InvalidArgument, "no sub-mesh");
          const double exactS = medianSeconds(s.repeats, [&] {
            sub = fragmentSubMesh(asset.tetMesh, topology.value(), r.fracture.nodeLabels, r.fracture.edgeCuts, static_cast<int>(i));
            if (sub) exact = exactFragmentAsset(sub.value(), material, es, name + ".f" + std::to_string(i));
          });
          // Reference: the fragment's solid in quadratic tets (on the exact path's mesh, or that
          // mesh split 1:8 with referenceSplit), three modes.
          Result<ObjectAsset> reference = makeError(ErrorCode::InvalidArgument, "no sub-mesh");
          double referenceS = std::numeric_limits<double>::quiet_NaN();
          if (sub && sub.value().mesh.tets.rows() * (s.referenceSplit ? 8 : 1) <= s.referenceMaxTets) {
            const auto t0 = SteadyClock::now();
            FragmentSubMesh fine;
            fine.mesh = s.referenceSplit ? refine(sub.value().mesh) : sub.value().mesh;
            ExactModesSettings rs;
            rs.modeCount = 3;
            rs.elementOrder = ElementOrder::P2;
            reference = exactFragmentAsset(fine, material, rs, name + ".f" + std::to_string(i) + ".fine");
            referenceS = secondsSince(t0);
          }
          const double nan = std::numeric_limits<double>::quiet_NaN();
          const Eigen::VectorXd none;
          const Eigen::VectorXd& refHz = reference ? reference.value().modal.frequenciesHz : none;
          const Eigen::VectorXd& exactHz = exact ? exact.value().modal.frequenciesHz : none;
          double matchS = nan;
          // The fragment's own frequencies from its moments (PolynomialModes.h), at degrees 3–5.
          // As the runtime: without shapes, as many as an entry has modes.
          const Eigen::Index entryModes = p.database.entries.empty() ? -1 : p.database.entries.front().asset.modal.eigenvaluesRad2PerS2.size();
          Eigen::VectorXd polynomial[3];
          double polynomialS[3];
          for (int q = 0; q < 3; ++q) {
            polynomialS[q] = medianSeconds(s.repeats, [&] {
              auto modes = polynomialModes(fr.surface, material, q + 3, /*withShapes=*/false, entryModes);
              polynomial[q] = modes ? modes.value().frequenciesHz : none;
            });
          }
          // The degree-5 values times the fragment's own mesh's ratios (meshFrequencyRatios), as the
          // World takes them: its own cut (CutCells::Prisms) and the ratios, timed together.
          Eigen::VectorXd meshRatioHz;
          double checkIndicator = std::numeric_limits<double>::quiet_NaN();
          const int64_t p1Dof = fragmentCutDof(asset.tetMesh, topology.value(), r.fracture.nodeLabels, static_cast<int>(i), ElementOrder::P1);
          const int64_t checkDof = fragmentCutDof(asset.tetMesh, topology.value(), r.fracture.nodeLabels, static_cast<int>(i), ElementOrder::P1,
                                                  CutCells::Prisms);
          const double meshRatioS = medianSeconds(s.repeats, [&] {
            auto check = fragmentSubMesh(asset.tetMesh, topology.value(), r.fracture.nodeLabels, r.fracture.edgeCuts, static_cast<int>(i),
                                         CutCells::Prisms);
            auto ratios = check ? meshFrequencyRatios(check.value(), material, 5, kMeshRatioModes) : Result<MeshFrequencyRatios>(check.error());
            meshRatioHz = polynomial[2];
            if (ratios && meshRatioHz.size()) applyMeshRatios(meshRatioHz, ratios.value());
            if (ratios) checkIndicator = meshGain(ratios.value());
          });
          // The bodies' predicted errors (World::frequencyError): the pack's models at the indicators.
          const FrequencyErrorModels& bodyModels = p.database.frequencyErrors;
          const double ritzIndicator = matchFrequencyError(polynomial[0], polynomial[2]);  // degree 3 to 5, as the World
          const MatchErrorPrediction ritzPredicted = predictMatchError(bodyModels.ritz, ritzIndicator);
          const MatchErrorPrediction checkPredicted = predictMatchError(bodyModels.checked, checkIndicator);
          // The same check in quadratic tets (FractureSettings::meshRatioElement = P2).
          Eigen::VectorXd meshRatioP2Hz;
          const double meshRatioP2S = medianSeconds(s.repeats, [&] {
            auto check = fragmentSubMesh(asset.tetMesh, topology.value(), r.fracture.nodeLabels, r.fracture.edgeCuts, static_cast<int>(i),
                                         CutCells::Prisms);
            auto ratios = check ? meshFrequencyRatios(check.value(), material, 5, kMeshRatioModes, ElementOrder::P2) : Result<MeshFrequencyRatios>(check.error());
            meshRatioP2Hz = polynomial[2];
            if (ratios && meshRatioP2Hz.size()) applyMeshRatios(meshRatioP2Hz, ratios.value());
          });
          for (size_t m = 0; m < matchers.size(); ++m) {
            // Database path, against the first entryCounts[m] entries.
            Result<ObjectAsset> matched = makeError(ErrorCode::InvalidArgument, "no match");
            double distance = nan;
            MatchErrorPrediction predicted;
            matchS = medianSeconds(s.repeats, [&] {
              auto found = matchers[m].match(fr.surface, s.descriptor, 1);
              if (!found) return;
              distance = found.value().front().distance;
              predicted = found.value().front().predictedError;
              matched = instantiateEntry(p.database.entries[static_cast<size_t>(found.value().front().entry)],
                                         p.database.referenceMaterial, material, found.value().front().queryFrame);
            });
            const Eigen::VectorXd& matchHz = matched ? matched.value().modal.frequenciesHz : none;
            auto polynomialError = [&](int q) {
              return reference && polynomial[q].size() >= 3 ? matchFrequencyError(polynomial[q], refHz) : nan;
            };
            csv << name << "," << speed << "," << seed << "," << i << ","
                << fr.massProperties.volumeM3 / asset.massProperties.volumeM3 << ","
                << (sub ? sub.value().wholeTets + sub.value().splitTets : 0) << "," << (sub ? sub.value().mesh.tets.rows() : 0) << ","
                << (sub ? sub.value().droppedVolumeM3 / asset.massProperties.volumeM3 : nan) << ","
                << (exact ? exact.value().modal.modes.cols() : 0) << "," << matchS << "," << (exact ? exactS : nan) << ","
                << referenceS << "," << distance << "," << (reference && matched ? matchFrequencyError(matchHz, refHz) : nan) << ","
                << (reference && exact ? matchFrequencyError(exactHz, refHz) : nan) << "," << (reference ? refHz[0] : nan) << ","
                << (exact ? exactHz[0] : nan) << "," << (matched ? matchHz[0] : nan) << "," << predicted.median << ","
                << predicted.p90 << "," << (predicted.beyondRange ? 1 : 0) << "," << polynomialError(0) << "," << polynomialError(1)
                << "," << polynomialError(2) << "," << (polynomial[2].size() ? polynomial[2][0] : nan) << "," << polynomialS[0] << ","
                << polynomialS[1] << "," << polynomialS[2] << ","
                << (reference && meshRatioHz.size() >= 3 ? matchFrequencyError(meshRatioHz, refHz) : nan) << ","
                << (meshRatioHz.size() ? meshRatioHz[0] : nan) << "," << meshRatioS << "," << p1Dof << "," << checkDof << ","
                << (reference && meshRatioP2Hz.size() >= 3 ? matchFrequencyError(meshRatioP2Hz, refHz) : nan) << "," << meshRatioP2S << ","
                << entryCounts[m] << "," << ritzIndicator << "," << ritzPredicted.median << "," << ritzPredicted.p90 << ","
                << checkIndicator << "," << checkPredicted.median << "," << checkPredicted.p90 << "\n";
          }
          if (!s.quiet) {
            std::fprintf(stderr, "%s v=%g seed=%d fragment %zu: %ld tets, match %.2f ms, exact %.2f ms%s%s\n", name.c_str(), speed,
                         seed, i, sub ? static_cast<long>(sub.value().mesh.tets.rows()) : 0L, 1e3 * matchS, 1e3 * exactS,
                         reference ? "" : " (no reference: ", reference ? "" : (reference.error().message + ")").c_str());
          }
        }
      }
  }
  if (!csv) return makeError(ErrorCode::PackIoError, "cannot write " + s.csv.string());
  return Ok{};
}

}  // namespace brittle::bench
