#include "ImpactStages.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "ContactGeometry.h"
#include "OnceValue.h"
#include "brittle/core/Timing.h"
#include "brittle/database/ScalingLaws.h"
#include "brittle/runtime/FragmentModes.h"
#include "brittle/runtime/FragmentSurfaces.h"
#include "brittle/runtime/ModalResponse.h"
#include "brittle/runtime/PolynomialModes.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/parallel_invoke.h>
#include <oneapi/tbb/task_arena.h>

namespace brittle::detail {
namespace {

Error inStage(const char* stage, const Error& e) { return Error{e.code, std::string(stage) + ": " + e.message}; }

// Runs f in the World's arena, where the stages' parallel loops take its threads (already there
// for a submitted impact), or on the caller's thread alone.
template <class F>
void inArena(const ImpactJob& job, F&& f) {
  if (job.workers) job.workers->execute(f);
  else f();
}

// What the stages pass on to one another.
struct Flow {
  Eigen::Vector3d pointLocal, normalLocal;
  const StaticCorrection* correction = nullptr;  // null: the truncated modes alone
  double complianceMPerN = 0.0;                  // f·u_t of the truncated modes, per newton²
};

// How far the reported point may lie from a body's surface: the host's tolerance
// (ImpactDesc::pointToleranceM), or 5 % of the body's size without one. A matched fragment's mesh is
// its database entry's shape standing in for the fragment, and the host collides with the
// fragment, whose surface can lie farther than either from the entry's (the pane scene refused
// about 1 hit in 200 on such bodies): such a body takes a point up to its own size off, whatever
// the host's tolerance, so that only a point that cannot be on the fragment is refused. The
// nearest surface point takes the hit.
double pointTolerance(const Body& body, const ImpactDesc& desc) {
  const double host = desc.pointToleranceM > 0.0 ? desc.pointToleranceM : 0.05 * body.sizeM;
  return body.frequencyError.source == FrequencySource::Own ? host : std::max(host, body.sizeM);
}

// Contact: where on the surface, how curved there, Hertz, and the load's node weights.
Status contactStage(const ImpactJob& job, Flow& flow, ImpactWorkspace& ws, ImpactResult& result) {
  const Body& body = *job.body;
  const ImpactDesc& desc = job.desc;
  flow.pointLocal = job.rotation.transpose() * (desc.pointWorld - job.translation);
  flow.normalLocal = job.rotation.transpose() * desc.normalWorld;
  auto site = locateContact(body, flow.pointLocal, pointTolerance(body, desc));
  if (!site) return site.error();
  double radius = desc.bodyRadiusM != 0.0 ? desc.bodyRadiusM : surfaceRadiusAt(body, site.value());
  if (std::isinf(radius) && std::isinf(desc.impactorRadiusM) && desc.flatPairRadiusM > 0.0) radius = desc.flatPairRadiusM;
  result.bodyRadiusM = radius;
  HertzInput hi;
  hi.impactorMassKg = desc.impactorMassKg;
  hi.impactorRadiusM = desc.impactorRadiusM;
  hi.impactorYoungsModulusPa = desc.impactorYoungsModulusPa;
  hi.impactorPoissonRatio = desc.impactorPoissonRatio;
  hi.bodyMassKg = body.asset.massProperties.massKg;
  hi.bodyInertiaKgM2 = body.asset.massProperties.inertiaKgM2;
  hi.contactOffsetM = flow.pointLocal - body.asset.massProperties.centerOfMassM;
  hi.normal = flow.normalLocal.normalized();
  hi.bodyRadiusM = radius;
  hi.bodyYoungsModulusPa = body.material.youngsModulusPa;
  hi.bodyPoissonRatio = body.material.poissonRatio;
  hi.speedMps = desc.speedMps;
  hi.impulseNs = desc.impulseNs;
  hi.restitution = body.material.restitution;
  auto contact = computeHertzContact(hi);
  if (!contact) return contact.error();
  result.contact = contact.value();
  // The larger of the World's spread and the object's own (ObjectAsset::contactSpreadFraction).
  const double spread = std::max(job.settings->contactSpreadFraction, body.asset.contactSpreadFraction);
  result.loadRadiusM = contactLoadRadius(body, site.value(), result.contact.patchRadiusM, spread);
  contactLoadWeights(body, site.value(), flow.normalLocal, result.loadRadiusM, result.loadWeights, ws.contactFaces);
  return Ok{};
}

// The static correction's factorised K: built on the workers once a pack object is placed or a
// matched fragment's body is made (WorldSettings::prepareInBackground), or here if the impact
// comes first (it then waits for, or makes, that build). A fast impact (a host over its frame
// budget) takes it only when its build was scheduled already, so that it never factorises K
// itself and whether the correction is used never depends on timing.
Status prepareStage(const ImpactJob& job, Flow& flow, ImpactResult& result) {
  const Body& body = *job.body;
  const bool wanted = job.settings->staticCorrection && (!job.desc.fast || body.staticCorrectionScheduled());
  if (wanted) {
    const Result<StaticCorrection>& correction = body.staticCorrection();
    if (!correction) return correction.error();
    flow.correction = &correction.value();
  }
  result.staticCorrectionUsed = wanted;
  return Ok{};
}

// Modal response over the pulse and the ring-down: q (instants by modes) and the force pulse.
Status modalStage(const ImpactJob& job, const Flow& flow, ImpactWorkspace& ws, ImpactResult& result) {
  const Body& body = *job.body;
  const FractureSettings& fs = *job.settings;
  const int r = body.modes;
  result.modesUsed = r;
  Eigen::VectorXd& g = ws.modalLoad;
  g.setZero(r);
  for (const auto& [i, w] : result.loadWeights) {
    g.noalias() -= w * (body.asset.modal.modes.block(3 * i, 0, 3, r).transpose() * flow.normalLocal);  // along −n
  }
  const double lowestPeriod = 2.0 * std::numbers::pi / body.omega[0];
  result.forceDirectionLocal = -flow.normalLocal;
  result.ringDownS = fs.ringDownPeriods * lowestPeriod;
  impactTimeGrid(result.contact.durationS, fs.pulseSteps, fs.ringDownPeriods * lowestPeriod,
                 fs.ringDownPeriods > 0.0 ? fs.ringDownSteps : 0, ws.times);
  ws.force.resize(ws.times.size());
  for (size_t k = 0; k < ws.times.size(); ++k) ws.force[k] = hertzPulseForceN(result.contact, ws.times[k]);
  return integrateModalResponse(body.omega, body.zeta, g, ws.times, ws.force, ws.q);
}

// Element stresses over every instant (pruned by bounds), the peak, and Rankine seeds.
Status stressStage(const ImpactJob& job, Flow& flow, ImpactWorkspace& ws, ImpactResult& result) {
  const Body& body = *job.body;
  const FractureSettings& fs = *job.settings;
  static const Eigen::VectorXd kNoStatic;
  // The scan's preparation reads q alone, so it runs beside the correction, whose forward solve is
  // serial (on the P2 plate 1.1–1.6 ms of a 5 ms correction, the other core idle before). Each
  // writes only its own buffers, and the scan's answer is the same bits (prepareStressScan).
  const StressBounds& bounds = body.stressBounds();
  auto prepare = [&] { prepareStressScan(bounds, ws.q, fs.pruneStresses, ws.scanBuffers); };
  if (flow.correction) {
    Status st = Ok{};
    tbb::parallel_invoke(
        [&] {
          st = flow.correction->stressPerNewton(result.loadWeights, -flow.normalLocal, ws.staticStress,
                                                flow.complianceMPerN, ws.correction);
        },
        prepare);
    if (!st) return st;
  } else {
    prepare();
  }
  StressScan& scan = ws.scan;
  const int points = stressPointsPerElement(body.asset.elementOrder);
  if (flow.correction && fs.reportUncorrectedPeak) {
    // The truncated modes alone, for the report (peak only: no seeds needed).
    scanPreparedStresses(body.asset.stressModes, bounds, ws.q, kNoStatic, ws.force, std::numeric_limits<double>::infinity(),
                         fs.pruneStresses, ws.scanBuffers, scan, points);
    result.peakWithoutCorrectionPa = scan.peakPrincipalPa;
  }
  scanPreparedStresses(body.asset.stressModes, bounds, ws.q, flow.correction ? ws.staticStress : kNoStatic, ws.force,
                       body.material.tensileStrengthPa, fs.pruneStresses, ws.scanBuffers, scan, points);
  result.peakPrincipalStressPa = scan.peakPrincipalPa;
  if (!flow.correction) result.peakWithoutCorrectionPa = scan.peakPrincipalPa;
  result.peakElement = scan.peakElement;
  result.peakTimeS = scan.peakInstant >= 0 ? ws.times[static_cast<size_t>(scan.peakInstant)] : 0.0;
  result.stressEvaluations = scan.evaluations;
  return Ok{};
}

// Crack growth from the seeds with the Griffith stop, paid from the elastic energy at the peak:
// the kept modes' ½Σω²q², plus the truncated modes' static ½F²f·u_t.
Status crackStage(const ImpactJob& job, const Flow& flow, ImpactWorkspace& ws, ImpactResult& result) {
  const Body& body = *job.body;
  const StressScan& scan = ws.scan;
  StressField field;
  field.stressModes = &body.asset.stressModes;
  field.pointsPerElement = stressPointsPerElement(body.asset.elementOrder);
  // Through the workspace's vector, whose storage stays: a field's own would be allocated anew
  // each breaking impact.
  ws.crackQ = ws.q.row(scan.peakInstant).transpose();
  field.q.swap(ws.crackQ);
  field.forceN = ws.force[static_cast<size_t>(scan.peakInstant)];
  if (flow.correction) field.staticStress = &ws.staticStress;
  // A P2 body's corner stresses are nodal means (makeBody): each node's computed once, where the
  // scan found every node's points bit-equal, static correction included
  // (StressScanWorkspace::groupSame, which is StressBounds::groupUniform and more); else each point
  // is computed, as before.
  const std::vector<char>& same = ws.scanBuffers.groupSame;
  if (body.asset.elementOrder == ElementOrder::P2 && job.settings->pruneStresses && !same.empty() &&
      same.size() == body.stressBounds().groupUniform.size() &&
      std::all_of(same.begin(), same.end(), [](char c) { return c != 0; })) {
    ws.crack.nodeMemo.reset(body.asset.tetMesh.nodes.rows());
    field.corners = &body.asset.tetMesh.tets;
    field.nodeMemo = &ws.crack.nodeMemo;
  }
  const double energy = 0.5 * (body.omega.array().square() * field.q.array().square()).sum() +
                        0.5 * field.forceN * field.forceN * flow.complianceMPerN;
  CrackSettings cs = job.settings->crack;
  cs.seed = job.crackSeed;
  const Status grown = propagateCracks(body.asset.tetMesh, body.topology, scan, field, body.material.tensileStrengthPa,
                                       body.material.fractureEnergyJPerM2, energy, cs, ws.crack, result.fracture);
  ws.crackQ.swap(field.q);  // its storage back for the next impact
  return grown;
}

// Each fragment's closed surface and exact mass properties; the small ones are debris. More
// fragments than the World's capacity is an error (the impact then leaves the world unchanged).
Status surfaceStage(const ImpactJob& job, ImpactWorkspace& ws, ImpactResult& result) {
  const Body& body = *job.body;
  const int count = result.fracture.fragmentCount;
  if (count > job.maxFragments) {
    return makeError(ErrorCode::CapacityExceeded, std::to_string(count) + " fragments exceed maxFragmentsPerImpact = " +
                                                      std::to_string(job.maxFragments) + " (the object is left unbroken)");
  }
  // The surfaces, and beside them mass properties (and the matcher's moments) summed over the
  // fragments' tets and cut cells, which is exact for the same solids and far cheaper than a pass
  // over their dense surfaces. Each writes only its own buffers, so the two run at once.
  Status surfaces = Ok{}, moments = Ok{};
  auto both = [&] {
    tbb::parallel_invoke(
        [&] {
          surfaces = buildFragmentSurfaces(body.asset.tetMesh, body.topology, result.fracture.nodeLabels, count,
                                           result.fracture.edgeCuts, ws.surfaceBuffers, ws.surfaces);
        },
        [&] {
          moments = fragmentVolumeMoments(body.asset.tetMesh, body.topology, body.tetMoments(), result.fracture.nodeLabels,
                                          count, result.fracture.edgeCuts, ws.momentChunkSums, ws.fragmentMoments);
        });
  };
  inArena(job, both);
  if (!surfaces) return surfaces;
  if (!moments) return moments;
  // The declared capacity at the first break, so that a reused result never grows its list (a
  // later break with more fragments than the first would allocate; HotPathAllocationTest).
  if (result.fragments.capacity() < static_cast<size_t>(count)) result.fragments.reserve(static_cast<size_t>(job.maxFragments));
  result.fragments.resize(static_cast<size_t>(count));
  for (size_t i = 0; i < result.fragments.size(); ++i) {
    FragmentResult& fr = result.fragments[i];
    fr.surface.vertices.swap(ws.surfaces[i].vertices);  // handed over: the buffers' next use allocates anew
    fr.surface.faces.swap(ws.surfaces[i].faces);
    fr.massProperties = massPropertiesFromMoments(ws.fragmentMoments.data() + i * kFragmentMomentCount, body.centreM,
                                                  body.material.densityKgPerM3);
    fr.debris = fr.massProperties.volumeM3 < job.settings->debrisVolumeFraction * body.topology.volumeM3;
    fr.path = fr.debris ? FragmentPath::Debris : FragmentPath::SurfaceOnly;
  }
  return Ok{};
}

// What the fragments' deferred makers share: the broken body and its fracture state.
struct BrokenParent {
  std::shared_ptr<const Body> body;
  Eigen::VectorXi nodeLabels;
  Eigen::VectorXd edgeCuts;
};

// A matched fragment's body counts its static correction as scheduled from the moment it is made
// (the World builds it on the workers next, as it does a pack object's at placement). Its first
// impact then finds K factorised instead of paying for it, and a fast impact's use of the
// correction does not depend on how far that build has got. The exact path's body has it already
// (makeBody adopts its modal analysis's factor).
Result<std::shared_ptr<const Body>> withCorrectionScheduled(Result<std::shared_ptr<const Body>> made, bool correct) {
  if (made && correct) made.value()->scheduleStaticCorrection();
  return made;
}

// What a matched fragment's own-frequency check needs (FractureSettings::meshRatioMaxDof): its
// broken parent and label, and the largest linear-tet model it may cut out for it.
struct MeshCheck {
  std::shared_ptr<const BrokenParent> parent;  // null: no check
  int label = -1;
  int maxDof = 0;
  ElementOrder order = ElementOrder::P1;
};

// The size of a piece's check in linear DOF (fragmentCutDof over the broken parent, a crossed tet
// as a tet or prism); 0 without a parent.
int64_t checkDof(const MeshCheck& check) {
  if (!check.parent) return 0;
  const Body& body = *check.parent->body;
  return fragmentCutDof(body.asset.tetMesh, body.topology, check.parent->nodeLabels, check.label, ElementOrder::P1, CutCells::Prisms);
}

// The ratios of a piece's own mesh to its polynomial fields (FragmentModes.h,
// meshFrequencyRatios), where its `dof` are within the check's limit; an error otherwise, or where
// the check fails (a sub-mesh that hangs by an edge or a node).
Result<MeshFrequencyRatios> checkRatios(const MeshCheck& check, int64_t dof, const Material& material, int degree) {
  if (!check.parent || check.maxDof <= 0 || dof <= 0 || dof > check.maxDof) {
    return makeError(ErrorCode::InvalidArgument, "no check within the limit");
  }
  const Body& body = *check.parent->body;
  auto sub = fragmentSubMesh(body.asset.tetMesh, body.topology, check.parent->nodeLabels, check.parent->edgeCuts, check.label,
                             CutCells::Prisms);
  if (!sub) return sub.error();
  return meshFrequencyRatios(sub.value(), material, degree, kMeshRatioModes, check.order);
}

// A body's predicted frequency error from its source and indicator (World::frequencyError).
FrequencyErrorPrediction predictedFrequencyError(FrequencySource source, double indicator, const FrequencyErrorModels& models) {
  const MatchErrorModel& model = source == FrequencySource::Checked     ? models.checked
                                 : source == FrequencySource::CheckedP2 ? models.checkedP2
                                                                        : models.ritz;
  const MatchErrorPrediction p = predictMatchError(model, indicator);
  return FrequencyErrorPrediction{source, indicator, p.median, p.p90, p.beyondRange};
}

// A fragment keeps its parent's spread as a length (ObjectAsset::contactSpreadFraction times the
// parent's diagonal: what the parent's mesh resolves), as a fraction of its own diagonal, below 1.
// The exact path's sub-mesh is the parent's own elements; an entry's mesh is no finer than that.
void inheritContactSpread(const Body& parent, ObjectAsset& fragment) {
  if (!(parent.asset.contactSpreadFraction > 0.0)) return;
  const Points& x = fragment.tetMesh.nodes;
  if (x.rows() == 0) return;
  const double diagonal = (x.colwise().maxCoeff() - x.colwise().minCoeff()).norm();
  if (!(diagonal > 0.0)) return;
  fragment.contactSpreadFraction = std::min(0.99, parent.asset.contactSpreadFraction * parent.sizeM / diagonal);
}

// A matched entry placed on its fragment (ScalingLaws.h) and, with degree > 0, ringing at the
// fragment's own frequencies (PolynomialModes.h: from the fragment's surface; the entry keeps its
// shapes and stress modes), the lowest kMeshRatioModes of them corrected by the fragment's own
// mesh when `check` allows it (FragmentModes.h, meshFrequencyRatios: the fragment cut out of its
// parent in linear tets, a crossed tet's part as a tet or prism where one crack crosses it,
// CutCells::Prisms). `entryEigenvalues` then keeps the entry's own eigenvalues for the body's
// static correction, which stays the entry's, shared or not: the flexibility its kept modes leave
// out. Should the analysis fail (only on a surface an impact would not make), the body keeps the
// entry's frequencies; should the check fail (a sub-mesh that hangs by an edge or a node, whose
// linear tets have more than six rigid modes), the Ritz values stand. `estimate` says which it
// was and the error `models` predict for it: the Ritz values' at their convergence from degree
// p − 2 (the lowest three at p − 2, ~0.2 ms at p = 5), checked ones' at the mesh's gain.
// The entry is placed by the World's EntryCache (its basis at the material's ν shared). The body's
// mass properties are the fragment's own (`mass`, exact: FragmentResult::massProperties), not the
// entry's rescaled ones, which differ with the shape (inertia 6–13 % off at the median on cut
// queries, bench search): the contact of its next impact, and objectAsset, see the piece's own.
Result<ObjectAsset> placeEntry(const EntryCache& cache, const FragmentMatch& m, const Material& material, const TriangleMesh& surface,
                               const MassProperties& mass, int degree, const MeshCheck& check, const FrequencyErrorModels& models,
                               Eigen::VectorXd& entryEigenvalues, Eigen::VectorXd& ritzHz, FrequencyErrorPrediction& estimate) {
  const MatchErrorPrediction& e = m.predictedError;
  estimate = FrequencyErrorPrediction{FrequencySource::Entry, m.distance, e.median, e.p90, e.beyondRange};
  auto placed = cache.place(m.entry, material, m.queryFrame);
  if (placed) placed.value().massProperties = mass;
  if (placed && check.parent) inheritContactSpread(*check.parent->body, placed.value());
  if (!placed || degree <= 0 || surface.vertices.rows() == 0) return placed;
  // The surface's moments about its vertices' mean, once for both degrees (as polynomialModes
  // from a surface takes them).
  const Eigen::Vector3d origin = surface.vertices.colwise().mean().transpose();
  auto moments = computeVolumeMoments(surface, 2 * degree, origin);
  if (!moments) return placed;
  auto own = polynomialModes(moments.value(), material, degree, /*withShapes=*/false, placed.value().modal.eigenvaluesRad2PerS2.size());
  if (!own) return placed;
  auto lower = degree > 2 ? polynomialModes(moments.value(), material, degree - 2, /*withShapes=*/false, kMeshRatioModes)
                          : Result<PolynomialModes>(makeError(ErrorCode::InvalidArgument, "no degree two below"));
  // The Ritz values' own convergence (MatchErrors.h, FrequencyErrorModels::ritz): how far f1–f3
  // move from degree p − 2 to p, by the match errors' own measure. Not from p − 1: a mode of a
  // symmetric solid lies in one parity class and one degree more adds one parity only (two cubes
  // on a thin neck do not move from 4 to 5 at all; PolynomialModesTest). On chart 5's pieces its
  // rank correlation with the degree-5 values' error is 0.84 (0.73 from p − 1).
  const double convergence = lower ? matchFrequencyError(lower.value().frequenciesHz, own.value().frequenciesHz)
                                   : std::numeric_limits<double>::quiet_NaN();
  FrequencySource source = FrequencySource::Ritz;
  double indicator = convergence;
  Eigen::VectorXd ritz = own.value().frequenciesHz;
  if (check.parent && check.maxDof > 0) {
    if (auto ratios = checkRatios(check, checkDof(check), material, degree)) {
      applyMeshRatios(own.value().frequenciesHz, ratios.value());
      source = check.order == ElementOrder::P2 ? FrequencySource::CheckedP2 : FrequencySource::Checked;
      indicator = meshGain(ratios.value());
    }
  }
  Eigen::VectorXd entry = placed.value().modal.eigenvaluesRad2PerS2;
  if (adoptPolynomialFrequencies(placed.value(), own.value())) {
    entryEigenvalues = std::move(entry);
    ritzHz = std::move(ritz);
    estimate = predictedFrequencyError(source, indicator, models);
  }
  return placed;
}

// A matched body's version checked on the fragment's own mesh (`check`, its `dof` counted once
// for the chain), made from the version before it: base's Ritz values (Body::ritzFrequenciesHz)
// times the check's ratios, on base's mesh, shapes, stress modes and static correction
// (withFrequencies). The same bits as making the body again with the check (placeEntry), without
// placing the entry, the Ritz step and the body's geometry again, ~5 of a check version's ~16 ms
// in the pane scene (docs/realtime.md, stop 70). A piece whose check is out of its limit or
// fails keeps `base` itself, as do bodies without Ritz values (the entry's frequencies).
Result<std::shared_ptr<const Body>> checkedVersion(const Result<std::shared_ptr<const Body>>& base, const MeshCheck& check, int64_t dof,
                                                   int degree, const FrequencyErrorModels& models) {
  if (!base || base.value()->ritzFrequenciesHz.size() == 0) return base;
  const Body& b = *base.value();
  auto ratios = checkRatios(check, dof, b.material, degree);
  if (!ratios) return base;
  PolynomialModes own;
  own.frequenciesHz = b.ritzFrequenciesHz;
  applyMeshRatios(own.frequenciesHz, ratios.value());
  ModalBasis rates;
  rates.eigenvaluesRad2PerS2 = b.correctionEigenvalues;  // the entry's, as placeEntry adopts them over
  if (!adoptPolynomialFrequencies(rates, own)) return base;
  auto made = withFrequencies(b, rates);
  if (!made) return base;  // as a failed check: the values before it stand
  const FrequencySource source = check.order == ElementOrder::P2 ? FrequencySource::CheckedP2 : FrequencySource::Checked;
  made.value()->frequencyError = predictedFrequencyError(source, meshGain(ratios.value()), models);
  return std::shared_ptr<const Body>(std::move(made).value());
}

// The pack's frequency-error models where they were calibrated at `degree`, none otherwise: the
// indicators move with the degree (MatchErrors.h, FrequencyErrorModels::degree).
const FrequencyErrorModels& frequencyModelsAt(const FragmentMatcher& matcher, int degree) {
  static const FrequencyErrorModels kNone;
  const FrequencyErrorModels& models = matcher.database().frequencyErrors;
  return models.degree == degree ? models : kNone;
}

// The matched entry placed (placeEntry) and made a body, its tet connectivity the entry's own.
Result<std::shared_ptr<const Body>> matchedBody(const EntryCache& cache, const FragmentMatch& m, const Material& material,
                                                int modeCount, const TriangleMesh& surface, const MassProperties& mass, int degree,
                                                const MeshCheck& check, const FrequencyErrorModels& models) {
  Eigen::VectorXd entryEigenvalues, ritzHz;
  FrequencyErrorPrediction estimate;
  auto placed = placeEntry(cache, m, material, surface, mass, degree, check, models, entryEigenvalues, ritzHz, estimate);
  if (!placed) return Error{placed.error().code, "entry " + std::to_string(m.entry) + ": " + placed.error().message};
  const auto topology = cache.topology(m.entry);  // held while the body is made
  const TetTopology* sameTets = *topology ? &topology->value() : nullptr;  // else makeBody builds it and reports the error
  auto made = makeBody(std::move(placed).value(), material, modeCount, nullptr, std::move(entryEigenvalues), sameTets);
  // Not shared with anything yet: its maker is the one holder.
  if (made) {
    Body& body = *std::const_pointer_cast<Body>(made.value());
    body.frequencyError = estimate;
    body.ritzFrequenciesHz = std::move(ritzHz);
  }
  return made;
}

// A matched body with the entry's shared static correction placed as the entry was placed
// (x = L Rᵀ_frame x̂ + t), or its own correction scheduled: a matched piece's first body, and an
// exact-path piece's before its analysis is due (FractureSettings::exactModesDelayS).
Result<std::shared_ptr<const Body>> correctedMatchedBody(const EntryCache& cache, const EntryCorrections* shared,
                                                         const FragmentMatch& m, const Material& material, int modeCount,
                                                         bool correct, const TriangleMesh& surface, const MassProperties& mass,
                                                         int degree, const MeshCheck& check, const FrequencyErrorModels& models) {
  auto made = matchedBody(cache, m, material, modeCount, surface, mass, degree, check, models);
  if (made && correct && shared) {
    const auto entry = shared->get(m.entry, material, made.value()->modes);
    if (*entry) {
      made.value()->adoptStaticCorrection(entry->value().placed(m.queryFrame.rotation.transpose(), 1.0 / m.queryFrame.scalePerM));
      return made;
    }
  }
  return withCorrectionScheduled(std::move(made), correct);
}

// The database: the nearest entry and its placement (searched now, so that the result reports
// it); the entry rescaled to the fragment is made later (BodySource).
std::shared_ptr<const BodySource> matchedSource(const ImpactJob& job, const std::shared_ptr<const BrokenParent>& parent,
                                                const double* moments, FragmentResult& fr, size_t i) {
  const Material material = job.body->material;
  const int modeCount = job.settings->modeCount;
  auto note = [&](const std::string& why) { fr.reason += (fr.reason.empty() ? "" : "; ") + why; };
  VolumeMoments solid;
  solid.maxOrder = kFragmentMomentOrder;
  solid.values = Eigen::Map<const Eigen::VectorXd>(moments, kFragmentMomentCount);
  auto match = job.matcher->match(fr.surface, solid, job.body->centreM, job.settings->descriptor, 1);
  if (!match) {  // e.g. a sliver whose frame is undefined
    note("match: " + match.error().message);
    return nullptr;
  }
  const FragmentMatch m = match.value().front();
  fr.matchedEntry = m.entry;
  fr.matchDistance = m.distance;
  fr.predictedMatchError = m.predictedError.median;
  fr.predictedMatchErrorP90 = m.predictedError.p90;
  const EntryCorrections* shared = job.entryCorrections;
  const bool correct = job.settings->staticCorrection && job.prepareFragments;
  const int degree = job.settings->polynomialModeDegree;
  TriangleMesh surface = degree > 0 ? fr.surface : TriangleMesh{};  // for the worker: two allocations
  const FractureSettings& fs = *job.settings;
  const MeshCheck check{parent, static_cast<int>(i), fs.meshRatioMaxDof, fs.meshRatioElement};
  const EntryCache* cache = job.entryCache;
  const FrequencyErrorModels* models = &frequencyModelsAt(*job.matcher, degree);
  auto make = [cache, shared, m, material, modeCount, correct, degree, models, mass = fr.massProperties](
                  const TriangleMesh& own, const MeshCheck& limit) -> Result<std::shared_ptr<const Body>> {
    return correctedMatchedBody(*cache, shared, m, material, modeCount, correct, own, mass, degree, limit, *models);
  };
  // When the break has a time (a check needs the broken parent: without one there is nothing to
  // check later either):
  // - the check within the first limit after the first body, its Ritz values alone
  //   (FractureSettings::meshRatioDelayS);
  // - the later check (meshRatioLateMaxDof): the same body, checked up to the later limit.
  // A piece outside a version's limits keeps the body before it (that version is then the same).
  const bool timed = degree > 0 && std::isfinite(job.desc.timeS) && parent;
  const bool delayed = timed && fs.meshRatioMaxDof > 0 && fs.meshRatioDelayS > 0.0;
  const bool late = timed && fs.meshRatioLateMaxDof > fs.meshRatioMaxDof;
  if (!delayed && !late) {
    return BodySource::deferred([make, check, surface = std::move(surface)] { return make(surface, check); });
  }
  const MeshCheck lateCheck{parent, static_cast<int>(i), fs.meshRatioLateMaxDof, fs.meshRatioElement};
  // The later versions are the version before them checked (checkedVersion: a piece out of a
  // check's limit keeps that version), the piece's size in linear DOF counted once for them all.
  struct CountedDof {
    explicit CountedDof(const MeshCheck& c) : check(c) {}
    const MeshCheck check;
    OnceValue<int64_t> dof;
    int64_t get() const { return dof.get([this] { return checkDof(check); }); }
  };
  auto dof = std::make_shared<CountedDof>(check);
  std::vector<BodySource::Later> laters;
  if (delayed) {
    fr.checkDueS = job.desc.timeS + fs.meshRatioDelayS;
    laters.push_back({[check, dof, degree, models](const Result<std::shared_ptr<const Body>>& base) {
                        return checkedVersion(base, check, dof->get(), degree, *models);
                      },
                      fr.checkDueS, /*soon=*/true});
  }
  if (late) {
    fr.lateCheckDueS = job.desc.timeS + fs.meshRatioLateDelayS;
    laters.push_back({[check, lateCheck, dof, degree, models](const Result<std::shared_ptr<const Body>>& base) {
                        // Within the first limit the piece was checked already, with the same result.
                        if (dof->get() <= check.maxDof) return base;
                        return checkedVersion(base, lateCheck, dof->get(), degree, *models);
                      },
                      fr.lateCheckDueS});
  }
  // The escalation (FractureSettings::frequencyErrorTarget): the later body, when the pack
  // predicts it over the target, checked again in quadratic tets. Decided from the later body's
  // own prediction, a pure function of the break: a replay escalates the same pieces.
  if (late && fs.frequencyErrorTarget > 0.0 && fs.meshRatioElement == ElementOrder::P1 && !models->empty()) {
    const MeshCheck escalated{parent, static_cast<int>(i), fs.meshRatioLateMaxDof, ElementOrder::P2};
    const double target = fs.frequencyErrorTarget;
    fr.escalationDueS = job.desc.timeS + fs.meshRatioEscalationDelayS;
    laters.push_back({[escalated, dof, degree, models, target](const Result<std::shared_ptr<const Body>>& base) {
                        if (!base) return base;
                        const FrequencyErrorPrediction& p = base.value()->frequencyError;
                        const bool fromMesh = p.source == FrequencySource::Ritz || p.source == FrequencySource::Checked;
                        if (!fromMesh || !(p.p90 > target)) return base;
                        // A P2 check that fails leaves the later body: it is the better one.
                        return checkedVersion(base, escalated, dof->get(), degree, *models);
                      },
                      fr.escalationDueS});
  }
  const MeshCheck first{parent, static_cast<int>(i), delayed ? 0 : fs.meshRatioMaxDof, fs.meshRatioElement};
  return BodySource::deferred([make, first, surface = std::move(surface)] { return make(surface, first); }, std::move(laters));
}

// The exact path, all of it on the workers (BodySource): the fragment's own solid cut out of its
// parent, then its modal analysis. The cut was once made in the impact, and it was most of the
// matching stage: 15–17 thousand allocations an impact on a 1.5k-tet plate, and 0.45 of the
// 922-tet slab's 0.47 ms (docs/realtime.md, "The exact path's cut on the workers"). Should either
// fail (the cut only on inconsistent data: its checks), the object takes the fragment's database
// match when there is a database, as it did when the analysis failed. The caller has checked its
// size against exactModesMaxDof and the impact's budget. A timed break's piece, with a database
// and FractureSettings::exactModesDelayS, is first its match (its Ritz values, no mesh check),
// searched and placed on the workers too, and its analysis a later version due that long after
// the break (FragmentResult::exactDueS); an analysis that fails leaves the match, and a match
// that cannot be made gives way to the analysis at once.
std::shared_ptr<const BodySource> exactSource(const ImpactJob& job, const std::shared_ptr<const BrokenParent>& parent,
                                              FragmentResult& fr, size_t i) {
  const FractureSettings& fs = *job.settings;
  ExactModesSettings es;
  es.modeCount = keptModeCount(fs.modeCount, fs.exactModeCount);
  es.elementOrder = parent->body->asset.elementOrder;  // a fragment keeps its parent's element
  const int modeCount = fs.modeCount;
  const DescriptorKind kind = fs.descriptor;
  const FragmentMatcher* matcher = job.matcher;
  std::string name = parent->body->asset.name + ".f" + std::to_string(i);
  TriangleMesh surface = matcher ? fr.surface : TriangleMesh{};
  const bool correct = fs.staticCorrection;  // the exact path's body adopts its analysis's factor
  const bool scheduleMatch = correct && job.prepareFragments;
  const int degree = fs.polynomialModeDegree;
  const MeshCheck check{parent, static_cast<int>(i), fs.meshRatioMaxDof, fs.meshRatioElement};
  const EntryCache* cache = job.entryCache;
  // The fragment's own solid cut out of its parent, and its modal analysis.
  auto own = [parent, label = static_cast<int>(i), es, modeCount, correct, name = std::move(name)]() -> Result<std::shared_ptr<const Body>> {
    const Material& material = parent->body->material;
    const Body& body = *parent->body;
    auto mesh = fragmentSubMesh(body.asset.tetMesh, body.topology, parent->nodeLabels, parent->edgeCuts, label);
    if (!mesh) return Error{mesh.error().code, "exact path: " + mesh.error().message};
    ExactModesFactor factor;  // its modal analysis's factorisation: the static correction's too
    auto asset = exactFragmentAsset(mesh.value(), material, es, name, correct ? &factor : nullptr);
    if (!asset) return asset.error();
    inheritContactSpread(body, asset.value());
    return makeBody(std::move(asset).value(), material, modeCount, &factor);
  };
  // The fragment's database match, searched from its surface and placed on the workers, with the
  // entry's shared static correction (correctedMatchedBody, as a matched piece's): a timed piece's
  // first body, or what an analysis that fails gives way to. (The parent, not a copy of its
  // material: a copy allocates its name, and the impact's allocations per exact piece are counted,
  // HotPathAllocationTest.)
  auto matchSurface = [parent, matcher, kind, cache, shared = job.entryCorrections, modeCount, scheduleMatch, degree,
                       mass = fr.massProperties, surface = std::move(surface)](const MeshCheck& limit) -> Result<std::shared_ptr<const Body>> {
    auto match = matcher->match(surface, kind, 1);
    if (!match) return match.error();
    return correctedMatchedBody(*cache, shared, match.value().front(), parent->body->material, modeCount, scheduleMatch, surface,
                                mass, degree, limit, frequencyModelsAt(*matcher, degree));
  };
  if (fs.exactModesDelayS > 0.0 && std::isfinite(job.desc.timeS) && matcher && cache) {
    // The match at its Ritz values (no mesh check); where it cannot be made (a sliver whose frame
    // is undefined, an entry that fails), the analysis at once, as without the delay, and then the
    // later version does not make it again.
    auto first = [own, matchSurface = std::move(matchSurface),
                  ritzOnly = MeshCheck{parent, static_cast<int>(i), 0, fs.meshRatioElement}]() -> Result<std::shared_ptr<const Body>> {
      auto made = matchSurface(ritzOnly);
      return made ? made : own();
    };
    fr.exactDueS = job.desc.timeS + fs.exactModesDelayS;
    std::vector<BodySource::Later> laters;
    laters.push_back({[own](const Result<std::shared_ptr<const Body>>& base) -> Result<std::shared_ptr<const Body>> {
                        if (base && base.value()->frequencyError.source == FrequencySource::Own) return base;  // analysed already
                        auto made = own();
                        return made || !base ? made : base;
                      },
                      fr.exactDueS});
    return BodySource::deferred(std::move(first), std::move(laters));
  }
  return BodySource::deferred([own = std::move(own), matchSurface = std::move(matchSurface), matcher, check]() -> Result<std::shared_ptr<const Body>> {
    Result<std::shared_ptr<const Body>> made = own();
    if (made || !matcher) return made;
    auto matched = matchSurface(check);
    return matched ? matched : made.error();
  });
}

// Which exact-path candidates get it within the impact's budget (exactModesBudgetDof): the
// largest first (a match's error grows with the fragment's size, chart 5, and a larger piece
// carries more of the mass and is likelier to be struck again), ties by fragment index, each
// taken while the running total stays within the budget. A fixed order of values computed from
// the impact alone, so the choice is the same on every machine, thread count and run.
void grantExactBudget(const FractureSettings& fs, const std::vector<int64_t>& dof, std::vector<uint8_t>& granted,
                      ImpactResult& result) {
  if (fs.exactModesBudgetDof <= 0) return;
  std::vector<size_t> order;
  for (size_t i = 0; i < dof.size(); ++i)
    if (granted[i]) order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return dof[a] > dof[b]; });
  int64_t used = 0;
  for (size_t i : order) {
    if (used + dof[i] <= fs.exactModesBudgetDof) {
      used += dof[i];
      continue;
    }
    granted[i] = 0;
    std::string& reason = result.fragments[i].reason;
    reason += std::string(reason.empty() ? "" : "; ") + "exact path: its " + std::to_string(dof[i]) + " degrees of freedom would take this impact's " +
                                 "exact-path total past exactModesBudgetDof = " + std::to_string(fs.exactModesBudgetDof) +
                                 " (" + std::to_string(used) + " given to larger pieces)";
  }
}

// New objects for the fragments that are not debris: the exact path for small ones (at most
// exactModesMaxTets of the parent's tets and exactModesMaxDof degrees of freedom, together within
// exactModesBudgetDof), else the match (which the exact path also falls back to, on the workers,
// should it fail). The heavy part of each (a solid cut out and its modal analysis, an entry
// rescaled) is deferred into a BodySource, which the World makes on its workers once the impact is
// applied; what stays here is cheap. Fragments are independent
// and done in parallel, each writing only its own entries, but for the budget, which is shared
// and so decided between the two parallel passes.
void newBodiesStage(const ImpactJob& job, const ImpactWorkspace& ws, ImpactResult& result,
                    std::vector<std::shared_ptr<const BodySource>>& born) {
  const FractureSettings& fs = *job.settings;
  born.assign(result.fragments.size(), nullptr);
  if (!fs.matchFragments) {
    for (FragmentResult& fr : result.fragments)
      if (!fr.debris) fr.reason = "matchFragments is off: surface only";
    return;
  }
  const std::vector<int64_t> sizes = fragmentTetCounts(job.body->asset.tetMesh, result.fracture.nodeLabels,
                                                       static_cast<int>(result.fragments.size()));
  std::shared_ptr<const BrokenParent> parent;  // the exact path's, and matched fragments' mesh check
  if (fs.exactModesMaxTets > 0 || (fs.polynomialModeDegree > 0 && fs.meshRatioMaxDof > 0)) {
    parent = std::make_shared<const BrokenParent>(
        BrokenParent{job.body, result.fracture.nodeLabels, result.fracture.edgeCuts});
  }
  const double* moments = ws.fragmentMoments.data();
  const double target = fs.matchErrorTarget;
  const ElementOrder order = job.body->asset.elementOrder;
  auto percent = [](double x) { return std::to_string(static_cast<int>(std::lround(100.0 * x))) + " %"; };
  // The exact path's candidates: small enough, and not better served by a match predicted within
  // the target; their size in degrees of freedom, counted before anything is cut (fragmentCutDof).
  std::vector<int64_t> dof(result.fragments.size(), 0);
  std::vector<uint8_t> exact(result.fragments.size(), 0);
  auto weigh = [&](size_t i) {
    FragmentResult& fr = result.fragments[i];
    if (fr.debris || !parent || sizes[i] > fs.exactModesMaxTets) return;
    // With a target, a match predicted within it is taken instead of the exact path.
    if (target > 0.0 && job.matcher) {
      born[i] = matchedSource(job, parent, moments + i * kFragmentMomentCount, fr, i);
      if (born[i] && fr.predictedMatchErrorP90 <= target) {
        fr.path = FragmentPath::Matched;
        return;
      }
      born[i] = nullptr;
      fr.matchedEntry = -1;
      fr.matchDistance = 0.0;
      fr.checkDueS = fr.lateCheckDueS = fr.escalationDueS = std::numeric_limits<double>::quiet_NaN();  // the exact path has no later versions
      if (!std::isnan(fr.predictedMatchErrorP90)) {
        fr.reason = "match predicted at " + percent(fr.predictedMatchErrorP90) + " (p90), over the target " +
                    percent(target) + ": the exact path";
      }
    }
    dof[i] = fragmentCutDof(job.body->asset.tetMesh, job.body->topology, result.fracture.nodeLabels,
                            static_cast<int>(i), order);
    if (fs.exactModesMaxDof > 0 && dof[i] > fs.exactModesMaxDof) {
      fr.reason = "exact path: its " + std::string(elementOrderName(order)) + " model has " + std::to_string(dof[i]) +
                  " degrees of freedom, over exactModesMaxDof = " + std::to_string(fs.exactModesMaxDof);
      return;
    }
    exact[i] = 1;
  };
  auto make = [&](size_t i) {
    FragmentResult& fr = result.fragments[i];
    if (fr.debris || fr.path == FragmentPath::Matched) return;
    if (exact[i]) {
      born[i] = exactSource(job, parent, fr, i);
      fr.exactModes = true;
      fr.path = FragmentPath::ExactModes;
      return;
    }
    if (!job.matcher) {
      fr.reason += (fr.reason.empty() ? "" : "; ") + std::string("no database to match against");
      return;
    }
    born[i] = matchedSource(job, parent, moments + i * kFragmentMomentCount, fr, i);
    if (born[i]) fr.path = FragmentPath::Matched;
    if (born[i] && target > 0.0 && fr.predictedMatchErrorP90 > target) {
      fr.reason += (fr.reason.empty() ? "" : "; ") + std::string("match predicted at ") + percent(fr.predictedMatchErrorP90) +
                   " (p90), over the target " + percent(target) + ", and the fragment over the exact path's budget";
    }
  };
  auto each = [&](auto&& f) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, result.fragments.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) f(i);
    });
  };
  inArena(job, [&] { each(weigh); });
  grantExactBudget(fs, dof, exact, result);
  inArena(job, [&] { each(make); });
}

}  // namespace

void ImpactWorkspace::reserve(const TetMesh& mesh, const TetTopology& topology, const FractureSettings& settings) {
  crack.reserve(mesh.nodes.rows(), mesh.tets.rows(), topology.edges.rows(), settings.crack.maxCracks);
  surfaceBuffers.reserve(mesh.nodes.rows(), mesh.tets.rows(), topology.edges.rows(),
                         static_cast<Eigen::Index>(topology.boundaryFaces.size()));
  fragmentMoments.reserve(64 * static_cast<size_t>(kFragmentMomentCount));
  contactFaces.reserve(topology.boundaryFaces.size());
}

void resetImpactResult(ImpactResult& r) {
  r.broken = false;
  r.contact = HertzContact{};
  r.bodyRadiusM = 0.0;
  r.peakPrincipalStressPa = 0.0;
  r.peakWithoutCorrectionPa = std::numeric_limits<double>::quiet_NaN();
  r.peakElement = -1;
  r.peakTimeS = 0.0;
  r.modesUsed = 0;
  r.staticCorrectionUsed = false;
  r.loadWeights.clear();
  r.forceDirectionLocal.setZero();
  r.ringDownS = 0.0;
  r.stressEvaluations = 0;
  r.fracture.clear();
  r.fragments.clear();
  r.times = StageTimes{};
}

Status computeImpact(const ImpactJob& submitted, ImpactWorkspace& ws, ImpactResult& result,
                     std::vector<std::shared_ptr<const BodySource>>& born) {
  resetImpactResult(result);
  born.clear();
  ImpactJob job = submitted;  // the struck body, made if it was not yet (a fragment's first impact)
  if (!job.body) {
    const auto& made = job.source->get();
    if (!made) return Error{made.error().code, "the struck object's modal data could not be made: " + made.error().message};
    job.body = made.value();
  }
  Flow flow;
  StageTimes& t = result.times;
  auto t0 = SteadyClock::now();
  if (Status st = contactStage(job, flow, ws, result); !st) return st;  // its errors name the impact already
  t.contactS = secondsSince(t0);

  t0 = SteadyClock::now();
  if (Status st = prepareStage(job, flow, result); !st) return inStage("static correction", st.error());
  t.prepareS = secondsSince(t0);

  t0 = SteadyClock::now();
  if (Status st = modalStage(job, flow, ws, result); !st) return inStage("modal response", st.error());
  t.modalS = secondsSince(t0);

  t0 = SteadyClock::now();
  Status stress = Ok{};
  inArena(job, [&] { stress = stressStage(job, flow, ws, result); });
  if (!stress) return inStage("stress scan", stress.error());
  t.stressS = secondsSince(t0);
  if (!ws.scan.hasSeeds()) return Ok{};

  t0 = SteadyClock::now();
  if (Status st = crackStage(job, flow, ws, result); !st) return inStage("crack growth", st.error());
  result.stressEvaluations += ws.crack.seedEvaluations;  // the seeds crack growth took
  t.propagationS = secondsSince(t0);
  if (result.fracture.fragmentCount < 2) return Ok{};

  t0 = SteadyClock::now();
  if (Status st = surfaceStage(job, ws, result); !st) return inStage("fragment surfaces", st.error());
  t.surfacesS = secondsSince(t0);

  t0 = SteadyClock::now();
  newBodiesStage(job, ws, result, born);
  t.matchingS = secondsSince(t0);
  result.broken = true;
  return Ok{};
}

}  // namespace brittle::detail
