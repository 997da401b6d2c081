// Player.cpp — the player's public API: settings validation, play sessions over a Simulation, and
// frame-time summaries. The simulation itself is in Simulation.h and the files it names.
#include "brittle/player/Player.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "DebrisHulls.h"
#include "Simulation.h"
#include "brittle/core/Timing.h"
#include "brittle/precompute/MaterialLibrary.h"

namespace brittle {

using play::buildHulls;
using play::Hull;
using play::HullStore;
using play::Simulation;

std::string_view bodyKindName(BodyKind kind) {
  switch (kind) {
    case BodyKind::Object: return "object";
    case BodyKind::Fragment: return "fragment";
    case BodyKind::Debris: return "debris";
    case BodyKind::Impactor: return "impactor";
  }
  return "object";
}

Status validatePlayerSettings(const PlayerSettings& s) {
  auto bad = [](const std::string& what) { return makeError(ErrorCode::InvalidArgument, "player settings: " + what); };
  if (!(s.impactThresholdMps > 0.0) || !std::isfinite(s.impactThresholdMps)) return bad("impactThresholdMps must be finite and > 0");
  if (!(s.cooldownS >= 0.0) || !std::isfinite(s.cooldownS)) return bad("cooldownS must be finite and ≥ 0");
  if (s.maxImpactsPerStep < 1) return bad("maxImpactsPerStep must be ≥ 1");
  if (!(s.fractureBudgetS >= 0.0) || !std::isfinite(s.fractureBudgetS)) return bad("fractureBudgetS must be finite and ≥ 0");
  if (s.maxBudgetWaits < 0) return bad("maxBudgetWaits must be ≥ 0");
  if (s.fractureLatencyFrames < -1 || s.fractureLatencyFrames > 600) return bad("fractureLatencyFrames must be in [-1, 600]");
  if (!(s.frictionCoefficient >= 0.0) || !std::isfinite(s.frictionCoefficient)) return bad("frictionCoefficient must be finite and ≥ 0");
  if (!(s.collisionMarginM > 0.0 && s.collisionMarginM <= 0.05)) return bad("collisionMarginM must be in (0, 0.05]");
  if (!(s.pointToleranceFraction > 0.0 && s.pointToleranceFraction <= 1.0)) return bad("pointToleranceFraction must be in (0, 1]");
  if (s.hullMaxVertices != 0 && (s.hullMaxVertices < 8 || s.hullMaxVertices > 4096)) return bad("hullMaxVertices must be 0 or in [8, 4096]");
  return validateWorldSettings(s.world);
}

struct PlaySession::Impl {
  Scene scene;  // the Simulation keeps a reference to it
  std::unique_ptr<Simulation> sim;
  double loadS = 0.0;
};

PlaySession::PlaySession(std::unique_ptr<Impl> impl) : mImpl(std::move(impl)) {}
PlaySession::~PlaySession() = default;

Result<std::unique_ptr<PlaySession>> PlaySession::create(Pack pack, const Scene& scene, const PlayerSettings& settings) {
  if (Status st = validatePlayerSettings(settings); !st) return st.error();
  for (const SceneObject& o : scene.objects) {
    const bool known = std::any_of(pack.objects.begin(), pack.objects.end(), [&](const ObjectAsset& a) { return a.name == o.asset; });
    if (!known) return makeError(ErrorCode::InvalidArgument, "scene '" + scene.name + "': object '" + o.name + "' names asset '" + o.asset + "', which the pack does not have");
  }
  const auto t0 = SteadyClock::now();
  auto impl = std::make_unique<Impl>();
  impl->scene = scene;
  std::vector<Material> materials = pack.materials;
  WorldSettings ws = settings.world;
  ws.seed = scene.seed;
  auto hulls = std::make_shared<HullStore>();
  ws.onImpactComputed = [hulls, cap = settings.hullMaxVertices](ImpactTicket t, const ImpactResult& r) {
    if (!r.broken) return;
    std::vector<Hull> built;
    buildHulls(r, cap, built);
    hulls->put(t, std::move(built));
  };
  auto world = World::create(std::move(pack), ws);
  if (!world) return world.error();
  impl->sim = std::make_unique<Simulation>(std::move(world).value(), impl->scene, settings, hulls);
  impl->sim->setMaterials(std::move(materials));
  if (Status st = impl->sim->addFloor(); !st) return st.error();
  for (const SceneObject& o : impl->scene.objects)
    if (Status st = impl->sim->addObject(o); !st) return st.error();
  for (const RigidImpactor& imp : impl->scene.impactors) impl->sim->addImpactor(imp);
  // The objects' preparation (their K factorised on the World's workers) is part of loading, as a
  // level load would be: no first impact waits for it.
  if (Status st = impl->sim->waitUntilPrepared(); !st) return st.error();
  impl->sim->begin();
  impl->loadS = secondsSince(t0);
  return std::unique_ptr<PlaySession>(new PlaySession(std::move(impl)));
}

FrameStats PlaySession::stepFrame() { return mImpl->sim->stepFrame(); }
int64_t PlaySession::frame() const { return mImpl->sim->frame(); }
int64_t PlaySession::frameCount() const { return mImpl->sim->frameCount(); }
double PlaySession::timeS() const { return mImpl->sim->timeS(); }
const Scene& PlaySession::scene() const { return mImpl->scene; }
const PlayResult& PlaySession::progress() const { return mImpl->sim->progress(); }
std::vector<BodyView> PlaySession::bodies() const { return mImpl->sim->liveBodies(); }

Status PlaySession::throwSphere(const RigidImpactor& impactor) {
  auto bad = [](const std::string& what) { return makeError(ErrorCode::InvalidArgument, "throw: " + what); };
  if (impactor.shape != ImpactorShape::Sphere) return bad("only spheres are thrown");
  if (!(impactor.radiusM > 0.0 && std::isfinite(impactor.radiusM))) return bad("radius must be finite and > 0");
  if (!(impactor.massKg > 0.0 && std::isfinite(impactor.massKg))) return bad("mass must be finite and > 0");
  if (!impactor.positionWorldM.allFinite() || !impactor.velocityMps.allFinite() || !impactor.angularVelocityRadPerS.allFinite()) {
    return bad("position and velocities must be finite");
  }
  if (!materialPreset(impactor.material)) return makeError(ErrorCode::UnknownMaterial, "throw: unknown material '" + impactor.material + "'");
  mImpl->sim->throwImpactor(impactor);
  return Ok{};
}

PlayResult PlaySession::finish() {
  PlayResult r = mImpl->sim->finish();
  r.loadS = mImpl->loadS;
  return r;
}

Result<PlayResult> playScene(Pack pack, const Scene& scene, const PlayerSettings& settings) {
  auto session = PlaySession::create(std::move(pack), scene, settings);
  if (!session) return session.error();
  PlaySession& s = *session.value();
  while (s.frame() < s.frameCount()) s.stepFrame();
  return s.finish();
}

FrameTimeSummary summarizeFrameTimes(const std::vector<FrameStats>& frames) {
  FrameTimeSummary s;
  if (frames.empty()) return s;
  std::vector<double> t;
  t.reserve(frames.size());
  for (const FrameStats& f : frames) {
    t.push_back(f.bulletS + f.fractureS);
    s.bulletS += f.bulletS;
    s.fractureS += f.fractureS;
  }
  std::sort(t.begin(), t.end());
  auto quantile = [&](double q) { return t[std::min(t.size() - 1, static_cast<size_t>(std::ceil(q * static_cast<double>(t.size())) - 1))]; };
  s.medianS = quantile(0.5);
  s.p99S = quantile(0.99);
  s.maxS = t.back();
  return s;
}

}  // namespace brittle
