#include "brittle/runtime/World.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <numbers>
#include <optional>

#include "brittle/database/ScalingLaws.h"
#include "brittle/runtime/FragmentModes.h"
#include "brittle/runtime/FragmentSurfaces.h"
#include "brittle/runtime/ModalResponse.h"
#include "brittle/runtime/TetTopology.h"

namespace brittle {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

Error bad(const std::string& message) { return makeError(ErrorCode::InvalidArgument, message); }

uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection, §5.1.5), with its
// barycentric weights.
Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c, Eigen::Vector3d& bary) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) { bary = {1, 0, 0}; return a; }
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) { bary = {0, 1, 0}; return b; }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    bary = {1 - v, v, 0};
    return a + v * ab;
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) { bary = {0, 0, 1}; return c; }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    bary = {1 - w, 0, w};
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bary = {0, 1 - w, w};
    return b + w * (c - b);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  bary = {1 - v - w, v, w};
  return a + ab * v + ac * w;
}

// What the runtime keeps per distinct asset: the asset, its material, and what is precomputed
// from them once (topology, stress bounds, surface normals and neighbours).
struct Body {
  ObjectAsset asset;
  Material material;
  TetTopology topology;
  int modes = 0;
  Eigen::VectorXd omega, zeta;
  Eigen::MatrixXd stressBounds;  // T by modes
  // Built on the body's first impact, not when it is created: most fragments are never hit again,
  // and factorising K for each of them would dominate the impact that made them.
  mutable std::optional<StaticCorrection> correction;
  Points nodeNormals;                    // #N, area-weighted outward normals (boundary nodes)
  std::vector<std::vector<int32_t>> ring;  // boundary neighbours per node
  std::vector<int32_t> boundaryNodes;
  double sizeM = 0.0;                    // bounding-box diagonal
};

Result<std::shared_ptr<const Body>> makeBody(ObjectAsset asset, const Material& material, int modeCount) {
  if (asset.modal.modes.cols() == 0 || asset.stressModes.rows() != 6 * asset.tetMesh.tets.rows()) {
    return bad("object '" + asset.name + "' has no modal data or stress modes of the wrong size");
  }
  auto topo = buildTetTopology(asset.tetMesh);
  if (!topo) return Error{topo.error().code, "object '" + asset.name + "': " + topo.error().message};
  auto body = std::make_shared<Body>();
  body->topology = std::move(topo).value();
  body->material = material;
  const auto available = static_cast<int>(asset.modal.modes.cols());
  body->modes = modeCount > 0 ? std::min(modeCount, available) : available;
  body->omega = asset.modal.eigenvaluesRad2PerS2.head(body->modes).cwiseMax(0.0).cwiseSqrt();
  if (!(body->omega.minCoeff() > 0.0)) return bad("object '" + asset.name + "' has a zero-frequency elastic mode");
  body->zeta.resize(body->modes);
  for (int j = 0; j < body->modes; ++j) body->zeta[j] = rayleighDampingRatio(material, body->omega[j]);
  body->stressBounds = stressModeBounds(asset.stressModes, body->modes);
  const auto n = asset.tetMesh.nodes.rows();
  body->nodeNormals.setZero(n, 3);
  body->ring.assign(static_cast<size_t>(n), {});
  const Triangles& tri = body->topology.boundaryTriangles;
  for (Eigen::Index f = 0; f < tri.rows(); ++f) {
    const Eigen::Vector3d a = asset.tetMesh.nodes.row(tri(f, 0)), b = asset.tetMesh.nodes.row(tri(f, 1)),
                          c = asset.tetMesh.nodes.row(tri(f, 2));
    const Eigen::Vector3d areaNormal = 0.5 * (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) {
      body->nodeNormals.row(tri(f, k)) += areaNormal.transpose();
      auto& r = body->ring[static_cast<size_t>(tri(f, k))];
      for (int m = 1; m < 3; ++m) {
        const int32_t other = tri(f, (k + m) % 3);
        if (std::find(r.begin(), r.end(), other) == r.end()) r.push_back(other);
      }
    }
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    const double len = body->nodeNormals.row(i).norm();
    if (len > 0.0) {
      body->nodeNormals.row(i) /= len;
      body->boundaryNodes.push_back(static_cast<int32_t>(i));
    }
  }
  body->sizeM = (asset.tetMesh.nodes.colwise().maxCoeff() - asset.tetMesh.nodes.colwise().minCoeff()).norm();
  body->asset = std::move(asset);
  return std::shared_ptr<const Body>(std::move(body));
}

struct Slot {
  uint32_t generation = 0;
  bool alive = false;
  std::shared_ptr<const Body> body;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

}  // namespace

struct World::Impl {
  Pack pack;
  WorldSettings settings;
  std::optional<FragmentMatcher> matcher;
  std::vector<std::shared_ptr<const Body>> packBodies;  // per pack object, built on first use
  std::vector<Slot> slots;
  std::vector<uint32_t> freeSlots;
  uint64_t impacts = 0;
  int32_t live = 0;
  // The buffers of an impact, kept between impacts: once they have grown to the largest body hit,
  // an impact that does not break its body allocates nothing.
  struct Workspace {
    std::vector<double> times, force;
    Eigen::VectorXd modalLoad, staticStress;
    Eigen::MatrixXd q;
    StaticCorrection::Workspace correction;
    StressScanWorkspace scanBuffers;
    StressScan scan;
  } work;

  Result<Slot*> slot(ObjectId id) {
    if (!id.valid() || id.index >= slots.size()) return bad("invalid object id");
    Slot& s = slots[id.index];
    if (!s.alive || s.generation != id.generation) {
      return bad("stale object id (slot " + std::to_string(id.index) + ", generation " + std::to_string(id.generation) + ")");
    }
    return &s;
  }

  Result<ObjectId> place(std::shared_ptr<const Body> body, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& t) {
    uint32_t index;
    if (!freeSlots.empty()) {
      index = freeSlots.back();
      freeSlots.pop_back();
    } else {
      if (slots.size() >= static_cast<size_t>(settings.maxObjects)) {
        return bad("no free object slot: maxObjects = " + std::to_string(settings.maxObjects) + " reached");
      }
      index = static_cast<uint32_t>(slots.size());
      slots.emplace_back();
    }
    Slot& s = slots[index];
    s.alive = true;
    s.body = std::move(body);
    s.rotation = rotation;
    s.translation = t;
    ++live;
    return ObjectId{index, s.generation};
  }

  void remove(ObjectId id) {
    Slot& s = slots[id.index];
    s.alive = false;
    s.body.reset();
    ++s.generation;
    freeSlots.push_back(id.index);
    --live;
  }

  Status impact(const ImpactDesc& desc, ImpactResult& result);
};

namespace {

// Back to a default result, keeping the storage of loadWeights.
void resetResult(ImpactResult& r) {
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
  r.fracture = FractureState{};
  r.fragments.clear();
  r.times = StageTimes{};
}

}  // namespace

Status validateWorldSettings(const WorldSettings& s) {
  const FractureSettings& f = s.fracture;
  if (s.maxObjects < 1) return bad("WorldSettings: maxObjects must be ≥ 1");
  if (f.modeCount < 0 || f.pulseSteps < 2 || f.ringDownSteps < 0 || !(f.ringDownPeriods >= 0.0) ||
      !std::isfinite(f.ringDownPeriods) || !(f.debrisVolumeFraction >= 0.0 && f.debrisVolumeFraction < 1.0) ||
      f.exactModesMaxTets < 0 || f.exactModeCount < 1) {
    return bad("FractureSettings: modeCount ≥ 0, pulseSteps ≥ 2, ringDownSteps ≥ 0, ringDownPeriods ≥ 0 and finite, "
               "debrisVolumeFraction in [0, 1), exactModesMaxTets ≥ 0, exactModeCount ≥ 1");
  }
  if (f.crack.maxCracks < 0 || std::isnan(f.crack.propagationStressRatio) || !(f.crack.directionBlend >= 0.0) ||
      !(f.crack.directionBlend <= 1.0) || !(f.crack.noiseRad >= 0.0) || !std::isfinite(f.crack.noiseRad)) {
    return bad("CrackSettings: maxCracks ≥ 0, propagationStressRatio not NaN, directionBlend in [0, 1], noiseRad ≥ 0");
  }
  return Ok{};
}

World::World(std::unique_ptr<Impl> impl) : mImpl(std::move(impl)) {}
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;
World::~World() = default;

Result<World> World::create(Pack pack, const WorldSettings& settings) {
  if (Status st = validateWorldSettings(settings); !st) return st.error();
  try {
    auto impl = std::make_unique<Impl>();
    impl->pack = std::move(pack);
    impl->settings = settings;
    impl->packBodies.resize(impl->pack.objects.size());
    impl->slots.reserve(static_cast<size_t>(std::min(settings.maxObjects, 1 << 16)));
    const FragmentDatabase& db = impl->pack.database;
    if (settings.fracture.matchFragments && !db.empty() && db.hasPhysics()) {
      FragmentMatcherSettings ms;
      for (DescriptorKind k : kAllDescriptorKinds) ms.enabled[static_cast<size_t>(k)] = k == settings.fracture.descriptor;
      auto matcher = FragmentMatcher::build(db, ms);
      if (!matcher) return matcher.error();
      impl->matcher.emplace(std::move(matcher).value());
    }
    return World(std::move(impl));
  } catch (const std::exception& e) {
    return bad(std::string("world creation failed: ") + e.what());
  }
}

Result<ObjectId> World::addObject(const ObjectDesc& desc) {
  try {
    Impl& w = *mImpl;
    const auto it = std::find_if(w.pack.objects.begin(), w.pack.objects.end(),
                                 [&](const ObjectAsset& a) { return a.name == desc.asset; });
    if (it == w.pack.objects.end()) return bad("unknown object '" + desc.asset + "' (not in the pack)");
    if (!desc.rotation.allFinite() || !desc.translationM.allFinite() ||
        (desc.rotation.transpose() * desc.rotation - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
        std::abs(desc.rotation.determinant() - 1.0) > 1e-6) {
      return bad("object pose: the rotation must be orthonormal with det +1 and the pose finite");
    }
    const auto index = static_cast<size_t>(it - w.pack.objects.begin());
    if (!w.packBodies[index]) {
      const auto mat = std::find_if(w.pack.materials.begin(), w.pack.materials.end(),
                                    [&](const Material& m) { return m.name == it->materialName; });
      if (mat == w.pack.materials.end()) return bad("object '" + desc.asset + "' names a missing material");
      auto body = makeBody(*it, *mat, w.settings.fracture.modeCount);
      if (!body) return body.error();
      if (w.settings.fracture.staticCorrection) {  // pack objects pay the factorisation at load
        const Body& b = *body.value();
        auto correction = StaticCorrection::build(b.asset, b.material, b.modes);
        if (!correction) return Error{correction.error().code, "object '" + desc.asset + "': " + correction.error().message};
        b.correction.emplace(std::move(correction).value());
      }
      w.packBodies[index] = std::move(body).value();
    }
    return w.place(w.packBodies[index], desc.rotation, desc.translationM);
  } catch (const std::exception& e) {
    return bad(std::string("addObject failed: ") + e.what());
  }
}

Status World::removeObject(ObjectId id) {
  auto s = mImpl->slot(id);
  if (!s) return s.error();
  mImpl->remove(id);
  return Ok{};
}

bool World::isAlive(ObjectId id) const { return mImpl->slot(id).ok(); }
int32_t World::objectCount() const { return mImpl->live; }

Result<const ObjectAsset*> World::objectAsset(ObjectId id) const {
  auto s = mImpl->slot(id);
  if (!s) return s.error();
  return &s.value()->body->asset;
}

Result<ObjectDesc> World::objectPose(ObjectId id) const {
  auto s = mImpl->slot(id);
  if (!s) return s.error();
  ObjectDesc d;
  d.asset = s.value()->body->asset.name;
  d.rotation = s.value()->rotation;
  d.translationM = s.value()->translation;
  return d;
}

Result<ImpactResult> World::impact(const ImpactDesc& desc) {
  ImpactResult result;
  if (Status st = impact(desc, result); !st) return st.error();
  return result;
}

Status World::impact(const ImpactDesc& desc, ImpactResult& result) {
  try {
    return mImpl->impact(desc, result);
  } catch (const std::exception& e) {
    return bad(std::string("impact failed: ") + e.what());
  }
}

Status World::Impl::impact(const ImpactDesc& desc, ImpactResult& result) {
  resetResult(result);
  auto found = slot(desc.object);
  if (!found) return found.error();
  const Slot& s = *found.value();
  const std::shared_ptr<const Body> bodyRef = s.body;  // keeps the body alive past remove()
  const Body& body = *bodyRef;
  const ObjectAsset& asset = body.asset;
  const FractureSettings& fs = settings.fracture;
  if (!desc.pointWorld.allFinite() || !desc.normalWorld.allFinite() || std::abs(desc.normalWorld.norm() - 1.0) > 1e-6) {
    return bad("impact: the point must be finite and the normal a finite unit vector");
  }
  if (!(desc.speedMps > 0.0) || !std::isfinite(desc.speedMps)) return bad("impact: speed must be finite and > 0");
  if (!(desc.bodyRadiusM >= 0.0) || !(desc.pointToleranceM >= 0.0)) {
    return bad("impact: bodyRadiusM and pointToleranceM must be ≥ 0");
  }
  const uint64_t impactIndex = impacts++;

  // --- Contact: where, how curved, Hertz.
  auto t0 = Clock::now();
  const Eigen::Vector3d p = s.rotation.transpose() * (desc.pointWorld - s.translation);
  const Eigen::Vector3d n = s.rotation.transpose() * desc.normalWorld;
  const Points& x = asset.tetMesh.nodes;
  const Triangles& tri = body.topology.boundaryTriangles;
  double bestDistance = std::numeric_limits<double>::infinity();
  Eigen::Index bestFace = -1;
  Eigen::Vector3d bestBary;
  for (Eigen::Index f = 0; f < tri.rows(); ++f) {
    Eigen::Vector3d bary;
    const Eigen::Vector3d c = closestOnTriangle(p, x.row(tri(f, 0)), x.row(tri(f, 1)), x.row(tri(f, 2)), bary);
    const double d = (c - p).squaredNorm();
    if (d < bestDistance) {
      bestDistance = d;
      bestFace = f;
      bestBary = bary;
    }
  }
  bestDistance = std::sqrt(bestDistance);
  const double tolerance = desc.pointToleranceM > 0.0 ? desc.pointToleranceM : 0.05 * body.sizeM;
  if (bestFace < 0 || bestDistance > tolerance) {
    return bad("impact: the point is " + std::to_string(bestDistance) + " m from the surface of '" + asset.name +
               "' (tolerance " + std::to_string(tolerance) + " m)");
  }
  Eigen::Index corner;
  bestBary.maxCoeff(&corner);
  const int32_t nearest = tri(bestFace, corner);
  double radius = desc.bodyRadiusM;
  if (radius == 0.0) {
    // Normal curvature along each surface edge at the nearest node, κ = 2 n·(x_i − x_j)/|x_i − x_j|²,
    // averaged; flat or concave: ∞.
    const Eigen::Vector3d xi = x.row(nearest), ni = body.nodeNormals.row(nearest);
    double kappa = 0.0;
    for (int32_t j : body.ring[static_cast<size_t>(nearest)]) {
      const Eigen::Vector3d d = xi - x.row(j).transpose();
      kappa += 2.0 * ni.dot(d) / d.squaredNorm();
    }
    kappa /= std::max<size_t>(1, body.ring[static_cast<size_t>(nearest)].size());
    radius = kappa > 1e-3 / body.sizeM ? 1.0 / kappa : std::numeric_limits<double>::infinity();
  }
  result.bodyRadiusM = radius;
  HertzInput hi;
  hi.impactorMassKg = desc.impactorMassKg;
  hi.impactorRadiusM = desc.impactorRadiusM;
  hi.impactorYoungsModulusPa = desc.impactorYoungsModulusPa;
  hi.impactorPoissonRatio = desc.impactorPoissonRatio;
  hi.bodyMassKg = asset.massProperties.massKg;
  hi.bodyInertiaKgM2 = asset.massProperties.inertiaKgM2;
  hi.contactOffsetM = p - asset.massProperties.centerOfMassM;
  hi.normal = n.normalized();
  hi.bodyRadiusM = radius;
  hi.bodyYoungsModulusPa = body.material.youngsModulusPa;
  hi.bodyPoissonRatio = body.material.poissonRatio;
  hi.speedMps = desc.speedMps;
  hi.impulseNs = desc.impulseNs;
  hi.restitution = body.material.restitution;
  auto contact = computeHertzContact(hi);
  if (!contact) return contact.error();
  result.contact = contact.value();
  const HertzContact& hc = result.contact;

  // Load pattern: Hertz pressure √(1 − r²/a²) on the nodes inside the patch, weighted by their
  // area; a patch smaller than the mesh loads the nearest face's nodes barycentrically.
  auto& load = result.loadWeights;  // normalised below
  double total = 0.0;
  for (int32_t i : body.boundaryNodes) {
    const double r2 = (x.row(i).transpose() - p).squaredNorm() / (hc.patchRadiusM * hc.patchRadiusM);
    if (r2 >= 1.0) continue;
    const double w = std::sqrt(1.0 - r2) * body.topology.nodeAreasM2[i];
    load.emplace_back(i, w);
    total += w;
  }
  if (!(total > 0.0)) {
    load.clear();
    total = 0.0;
    for (int k = 0; k < 3; ++k) {
      load.emplace_back(tri(bestFace, k), bestBary[k]);
      total += bestBary[k];
    }
  }
  result.times.contactS = since(t0);

  // --- First impact on this body: factorise K for the static correction.
  t0 = Clock::now();
  // A fast impact (a host over its frame budget) does not factorise K: it takes the correction
  // only when the body already has it.
  const bool correct = fs.staticCorrection && (!desc.fast || body.correction.has_value());
  if (correct && !body.correction) {
    auto correction = StaticCorrection::build(asset, body.material, body.modes);
    if (!correction) return Error{correction.error().code, "object '" + asset.name + "': " + correction.error().message};
    body.correction.emplace(std::move(correction).value());
  }
  result.times.prepareS = since(t0);
  result.staticCorrectionUsed = correct;

  // --- Modal response over the pulse and the ring-down.
  t0 = Clock::now();
  const int r = body.modes;
  result.modesUsed = r;
  for (auto& [i, w] : load) w /= total;
  Eigen::VectorXd& g = work.modalLoad;
  g.setZero(r);
  for (const auto& [i, w] : load) {
    g.noalias() -= w * (asset.modal.modes.block(3 * i, 0, 3, r).transpose() * n);  // force along −n
  }
  const double lowestPeriod = 2.0 * std::numbers::pi / body.omega[0];
  result.forceDirectionLocal = -n;
  result.ringDownS = fs.ringDownPeriods * lowestPeriod;
  std::vector<double>& times = work.times;
  impactTimeGrid(hc.durationS, fs.pulseSteps, fs.ringDownPeriods * lowestPeriod,
                 fs.ringDownPeriods > 0.0 ? fs.ringDownSteps : 0, times);
  std::vector<double>& force = work.force;
  force.resize(times.size());
  for (size_t k = 0; k < times.size(); ++k) force[k] = hertzPulseForceN(hc, times[k]);
  Eigen::MatrixXd& q = work.q;
  if (Status st = integrateModalResponse(body.omega, body.zeta, g, times, force, q); !st) return st.error();
  result.times.modalS = since(t0);

  // --- Stresses, Rankine.
  t0 = Clock::now();
  const Eigen::VectorXd noStatic;
  Eigen::VectorXd& staticStress = work.staticStress;
  double compliance = 0.0;
  if (correct) {
    if (Status st = body.correction->stressPerNewton(result.loadWeights, -n, staticStress, compliance, work.correction);
        !st) {
      return st.error();
    }
  }
  StressScan& scan = work.scan;
  if (correct && fs.reportUncorrectedPeak) {
    // The truncated modes alone, for the report (peak only: no seeds needed).
    scanStresses(asset.stressModes, body.stressBounds, q, noStatic, force, std::numeric_limits<double>::infinity(),
                 fs.pruneStresses, work.scanBuffers, scan);
    result.peakWithoutCorrectionPa = scan.peakPrincipalPa;
  }
  const Eigen::VectorXd& scanStatic = correct ? staticStress : noStatic;
  scanStresses(asset.stressModes, body.stressBounds, q, scanStatic, force, body.material.tensileStrengthPa,
               fs.pruneStresses, work.scanBuffers, scan);
  result.peakPrincipalStressPa = scan.peakPrincipalPa;
  if (!correct) result.peakWithoutCorrectionPa = scan.peakPrincipalPa;
  result.peakElement = scan.peakElement;
  result.peakTimeS = scan.peakInstant >= 0 ? times[static_cast<size_t>(scan.peakInstant)] : 0.0;
  result.stressEvaluations = scan.evaluations;
  result.times.stressS = since(t0);
  if (scan.seeds.empty()) return Ok{};

  // --- Cracks.
  t0 = Clock::now();
  StressField field;
  field.stressModes = &asset.stressModes;
  field.q = q.row(scan.peakInstant).transpose();
  field.forceN = force[static_cast<size_t>(scan.peakInstant)];
  if (correct) field.staticStress = &staticStress;
  // Elastic energy at the peak: the kept modes' ½Σω²q², plus the truncated modes' static ½F²f·u_t.
  const double energy = 0.5 * (body.omega.array().square() * field.q.array().square()).sum() +
                        0.5 * field.forceN * field.forceN * compliance;
  CrackSettings cs = fs.crack;
  cs.seed = mix(settings.seed ^ mix(fs.crack.seed + impactIndex));
  auto state = propagateCracks(asset.tetMesh, body.topology, scan, field, body.material.tensileStrengthPa,
                               body.material.fractureEnergyJPerM2, energy, cs);
  if (!state) return state.error();
  result.fracture = std::move(state).value();
  result.times.propagationS = since(t0);
  if (result.fracture.fragmentCount < 2) return Ok{};

  // --- Fragment surfaces and mass properties.
  t0 = Clock::now();
  auto surfaces = buildFragmentSurfaces(asset.tetMesh, body.topology, result.fracture.nodeLabels,
                                        result.fracture.fragmentCount, result.fracture.edgeCuts);
  if (!surfaces) return surfaces.error();
  result.fragments.resize(surfaces.value().size());
  for (size_t i = 0; i < surfaces.value().size(); ++i) {
    FragmentResult& fr = result.fragments[i];
    fr.surface = std::move(surfaces.value()[i]);
    fr.massProperties = computeSurfaceMassProperties(fr.surface, body.material.densityKgPerM3);
    fr.debris = fr.massProperties.volumeM3 < fs.debrisVolumeFraction * body.topology.volumeM3;
  }
  result.times.surfacesS = since(t0);

  // --- New objects: each fragment that is not debris gets its own modal analysis when it is small
  // enough (the exact path), otherwise its nearest database entry.
  t0 = Clock::now();
  const Eigen::Matrix3d rotation = s.rotation;
  const Eigen::Vector3d translation = s.translation;
  remove(desc.object);
  result.broken = true;
  if (fs.matchFragments && fs.exactModesMaxTets > 0) {
    ExactModesSettings es;
    es.modeCount = fs.modeCount > 0 ? std::min(fs.modeCount, fs.exactModeCount) : fs.exactModeCount;
    const std::vector<int64_t> sizes =
        fragmentTetCounts(asset.tetMesh, result.fracture.nodeLabels, static_cast<int>(result.fragments.size()));
    for (size_t i = 0; i < result.fragments.size(); ++i) {
      FragmentResult& fr = result.fragments[i];
      if (fr.debris || sizes[i] > fs.exactModesMaxTets) continue;
      auto sub = fragmentSubMesh(asset.tetMesh, body.topology, result.fracture.nodeLabels, result.fracture.edgeCuts,
                                 static_cast<int>(i));
      if (!sub) continue;
      // A fragment the exact path cannot analyse (e.g. hanging by an edge) falls back to the match.
      auto own = exactFragmentAsset(sub.value(), body.material, es, asset.name + ".f" + std::to_string(i));
      if (!own) continue;
      auto child = makeBody(std::move(own).value(), body.material, fs.modeCount);
      if (!child) continue;
      auto id = place(std::move(child).value(), rotation, translation);
      if (!id) return id.error();
      fr.object = id.value();
      fr.exactModes = true;
    }
  }
  if (matcher) {
    for (FragmentResult& fr : result.fragments) {
      if (fr.debris || fr.exactModes) continue;
      auto match = matcher->match(fr.surface, fs.descriptor, 1);
      if (!match) continue;  // e.g. a sliver whose frame is undefined: left unmatched, reported as such
      const FragmentMatch& m = match.value().front();
      auto placed = instantiateEntry(pack.database.entries[static_cast<size_t>(m.entry)], pack.database.referenceMaterial,
                                     body.material, m.queryFrame);
      if (!placed) continue;
      fr.matchedEntry = m.entry;
      fr.matchDistance = m.distance;
      auto child = makeBody(std::move(placed).value(), body.material, fs.modeCount);
      if (!child) continue;
      auto id = place(std::move(child).value(), rotation, translation);
      if (!id) return id.error();
      fr.object = id.value();
    }
  }
  result.times.matchingS = since(t0);
  return Ok{};
}

}  // namespace brittle
