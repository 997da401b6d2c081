#include "brittle/runtime/World.h"

#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>
#include <oneapi/tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "BackgroundThreads.h"
#include "Cancellation.h"
#include "Body.h"
#include "ImpactStages.h"
#include "brittle/core/EigenBlocking.h"
#include "brittle/core/Random.h"
#include "brittle/runtime/PolynomialModes.h"

namespace brittle {
namespace {

using detail::Body;
using detail::BodySource;
using detail::makeBody;


struct Slot {
  uint32_t generation = 0;
  bool alive = false;
  bool pending = false;  // a submitted impact on it is not collected yet
  std::shared_ptr<const BodySource> source;
  bool ownsSource = false;  // a fragment's: no other object shares it, so it is abandoned with the object
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

// The checks on an impact's values that need no body.
Status validateImpactDesc(const ImpactDesc& desc) {
  if (!desc.pointWorld.allFinite() || !desc.normalWorld.allFinite() || std::abs(desc.normalWorld.norm() - 1.0) > 1e-6) {
    return invalidArgument("impact: the point must be finite and the normal a finite unit vector");
  }
  if (!(desc.speedMps > 0.0) || !std::isfinite(desc.speedMps)) return invalidArgument("impact: speed must be finite and > 0");
  if (std::isinf(desc.timeS)) return invalidArgument("impact: timeS must be finite or NaN (no time)");
  if (!(desc.bodyRadiusM >= 0.0) || !(desc.pointToleranceM >= 0.0) || !(desc.flatPairRadiusM >= 0.0) ||
      !std::isfinite(desc.flatPairRadiusM)) {
    return invalidArgument("impact: bodyRadiusM and pointToleranceM must be ≥ 0, flatPairRadiusM finite and ≥ 0");
  }
  return Ok{};
}

// A submitted impact: its inputs, its own buffers, and what the worker wrote.
struct PendingImpact {
  ObjectId object;
  detail::ImpactJob job;
  std::unique_ptr<detail::ImpactWorkspace> workspace;
  ImpactResult result;
  std::vector<std::shared_ptr<const BodySource>> born;
  std::optional<Status> status;  // set by the worker, before done
  std::atomic<bool> done{false};
  tbb::task_group group;
};

}  // namespace

struct World::Impl {
  Pack pack;
  WorldSettings settings;
  std::optional<FragmentMatcher> matcher;
  std::unique_ptr<detail::EntryCache> entryCache;              // with a matcher
  std::unique_ptr<detail::EntryCorrections> entryCorrections;  // with a matcher and shareEntryCorrections
  std::set<std::string> entryCorrectionsScheduled;  // materials whose entries placement has scheduled
  struct ScheduledEntryCorrection {  // one of their entries' corrections
    int32_t entry;
    Material material;
    int modes;
  };
  // Those not yet asked for by waitUntilPrepared, which makes any a starved thread has not.
  std::vector<ScheduledEntryCorrection> scheduledEntryCorrections;
  std::vector<std::shared_ptr<const BodySource>> packBodies;  // per pack object, built on first use
  std::vector<Slot> slots;
  std::vector<uint32_t> freeSlots;
  uint64_t impacts = 0;
  int32_t live = 0;
  detail::ImpactWorkspace work;  // the synchronous impact()'s buffers
  std::vector<std::shared_ptr<const BodySource>> born;
  // Asynchronous work: submitted impacts by ticket, spare workspaces, background preparation.
  // Impacts run in a oneTBB arena of workerThreads' concurrency (one slot the host's, for a
  // synchronous impact's parallel loops); background work (placement, the fragments' new bodies)
  // on threads of the World's own at idle priority (BackgroundThreads.h), so that it takes the
  // cores impacts and the host leave. A host waiting for an impact helps with impacts only, never
  // with a background job, which would hold it for as long as that job runs (a fragment's modal
  // analysis, a placed object's factorisation).
  // Set when the World closes: its background jobs and submitted impacts stop at their next
  // cancellation point instead of being waited for (Cancellation.h).
  std::atomic<bool> closing{false};
  std::unique_ptr<tbb::task_arena> arena;
  std::unique_ptr<detail::BackgroundThreads> backgroundThreads;
  std::map<uint64_t, std::unique_ptr<PendingImpact>> pending;
  std::vector<std::unique_ptr<detail::ImpactWorkspace>> spareWorkspaces;
  uint64_t nextTicket = 1;

  ~Impl() {
    // Nothing still to come is wanted (its results die with the World): background work not started
    // is dropped, and the jobs and impacts running stop at their next cancellation point, a few ms
    // at most, instead of running to their end (a placed object's preparation: seconds).
    closing.store(true, std::memory_order_relaxed);
    if (backgroundThreads) backgroundThreads->cancel();
    // Work still running reads this World's pack and bodies: wait for it to stop.
    if (arena) {
      arena->execute([&] {
        for (auto& [ticket, p] : pending) p->group.wait();
      });
    }
    backgroundThreads.reset();
  }

  // Submitted impacts (and the parallel loops of any impact), ahead of the host's own arenas.
  tbb::task_arena& workers() {
    if (!arena) {
      const int concurrency = settings.workerThreads > 0 ? int{settings.workerThreads} : int{tbb::task_arena::automatic};
      arena = std::make_unique<tbb::task_arena>(concurrency, 1, tbb::task_arena::priority::high);
    }
    return *arena;
  }
  // Placement and the fragments' new bodies: workerThreads threads (0: one per core; 1: none, the
  // work runs when the host waits for it or needs it).
  detail::BackgroundThreads& background() {
    if (!backgroundThreads) {
      const int threads = settings.workerThreads > 0 ? int{settings.workerThreads} : tbb::info::default_concurrency();
      backgroundThreads = std::make_unique<detail::BackgroundThreads>(threads > 1 ? threads : 0, &closing);
    }
    return *backgroundThreads;
  }

  Result<Slot*> slot(ObjectId id) {
    if (!id.valid() || id.index >= slots.size()) return invalidArgument("invalid object id");
    Slot& s = slots[id.index];
    if (!s.alive || s.generation != id.generation) {
      return invalidArgument("stale object id (slot " + std::to_string(id.index) + ", generation " + std::to_string(id.generation) + ")");
    }
    return &s;
  }

  // Slots free for new objects, counting the ones a removal of `freed` objects would give back.
  size_t freeCapacity(size_t freed) const {
    return freeSlots.size() + freed + (static_cast<size_t>(settings.maxObjects) - std::min(slots.size(), static_cast<size_t>(settings.maxObjects)));
  }

  // `ownsSource`: a fragment's source, which no other object shares (a pack object's is shared by
  // its instances).
  Result<ObjectId> place(std::shared_ptr<const BodySource> source, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& t,
                         bool ownsSource = false) {
    uint32_t index;
    if (!freeSlots.empty()) {
      index = freeSlots.back();
      freeSlots.pop_back();
    } else {
      if (slots.size() >= static_cast<size_t>(settings.maxObjects)) {
        return makeError(ErrorCode::CapacityExceeded,
                         "no free object slot: maxObjects = " + std::to_string(settings.maxObjects) + " reached");
      }
      index = static_cast<uint32_t>(slots.size());
      slots.emplace_back();
    }
    Slot& s = slots[index];
    s.alive = true;
    s.pending = false;
    s.source = std::move(source);
    s.ownsSource = ownsSource;
    s.rotation = rotation;
    s.translation = t;
    ++live;
    return ObjectId{index, s.generation};
  }

  void remove(ObjectId id) {
    Slot& s = slots[id.index];
    // A fragment's versions not made yet are nobody's any more: their background jobs are skipped or
    // stopped (a broken pane piece's checks and own analysis: up to hundreds of ms of a background
    // thread each, which a new break's first bodies wait behind). A pack object's source is kept, its
    // preparation included: the World holds it (packBodies) for that object's next instance.
    if (s.ownsSource && s.source) s.source->abandon();
    s.alive = false;
    s.pending = false;
    s.ownsSource = false;
    s.source.reset();
    ++s.generation;
    freeSlots.push_back(id.index);
    --live;
  }

  // The inputs of an impact on a live, non-pending object; numbers it (the crack seed).
  Result<detail::ImpactJob> makeJob(const ImpactDesc& desc) {
    auto found = slot(desc.object);
    if (!found) return found.error();
    const Slot& s = *found.value();
    if (s.pending) return invalidArgument("impact: an impact on this object is pending (collect it first)");
    if (Status st = validateImpactDesc(desc); !st) return st.error();
    detail::ImpactJob job;
    job.source = detail::sourceAt(s.source, desc.timeS);
    job.rotation = s.rotation;
    job.translation = s.translation;
    job.desc = desc;
    job.crackSeed = splitmix64(settings.seed ^ splitmix64(settings.fracture.crack.seed + impacts++));
    job.settings = &settings.fracture;
    job.prepareFragments = settings.prepareInBackground;
    job.matcher = matcher ? &*matcher : nullptr;
    job.entryCorrections = entryCorrections.get();
    job.entryCache = entryCache.get();
    job.workers = &workers();
    job.maxFragments = settings.maxFragmentsPerImpact;
    return job;
  }

  // A body made, with what every impact on it reads first: its stress bounds and, where scheduled,
  // its static correction (on the background threads); skipped, or stopped at a cancellation point,
  // once nobody can use it (its object was removed or broken: abandon()).
  static void prepare(const BodySource& source) {
    if (source.abandoned()) return;
    const detail::CancelScope scope(detail::tJobCancelFlag, source.abandonedFlag());
    const auto& body = source.get();
    if (!body) return;
    (void)body.value()->stressBounds();
    if (body.value()->staticCorrectionScheduled()) (void)body.value()->staticCorrection();
  }

  // Applies a computed impact: a broken object is replaced by its fragments, all or nothing.
  Status apply(ObjectId object, const detail::ImpactJob& job, ImpactResult& result,
               std::vector<std::shared_ptr<const BodySource>>& newBodies) {
    Slot& s = slots[object.index];
    s.pending = false;
    if (!result.broken) return Ok{};
    const auto count = static_cast<size_t>(std::count_if(newBodies.begin(), newBodies.end(), [](const auto& b) { return b != nullptr; }));
    if (count > freeCapacity(1)) {
      return makeError(ErrorCode::CapacityExceeded, "impact: " + std::to_string(count) +
                                                        " fragments do not fit in maxObjects = " +
                                                        std::to_string(settings.maxObjects) +
                                                        " (the object is left unbroken)");
    }
    // The background threads, started (if this is the first break) before the world changes: a
    // failure to start them leaves it as it was.
    detail::BackgroundThreads& makers = background();
    remove(object);
    for (size_t i = 0; i < newBodies.size(); ++i) {
      if (!newBodies[i]) continue;
      auto id = place(newBodies[i], job.rotation, job.translation, /*ownsSource=*/true);
      if (!id) return id.error();  // unreachable: capacity checked above
      result.fragments[i].object = id.value();
    }
    // The fragments' modal data, stress bounds and (where scheduled) static corrections are made on
    // the workers from now on (an impact or objectAsset that needs one first makes or waits for it).
    // Later versions (FractureSettings::meshRatioDelayS, meshRatioLateMaxDof, frequencyErrorTarget) after every first one.
    auto prepare = [&makers](std::shared_ptr<const BodySource> source, detail::BackgroundThreads::Urgency urgency, double dueS) {
      makers.submit([source = std::move(source)] { Impl::prepare(*source); }, urgency, dueS);
    };
    // Each version of the chain after every one before it (escalations last); all but the first
    // bodies and the checks due soon can wait behind the next break's first bodies, earliest due
    // first (BackgroundThreads::Urgency).
    auto urgency = [](const BodySource& source) {
      return source.wantedSoon() ? detail::BackgroundThreads::Urgency::Now : detail::BackgroundThreads::Urgency::Later;
    };
    for (auto& source : newBodies) {
      if (source) prepare(source, urgency(*source), job.desc.timeS);
    }
    for (bool any = true; any;) {  // newBodies[i]: the version submitted last
      any = false;
      for (auto& source : newBodies) {
        if (!source || !source->late()) continue;
        prepare(source->late(), urgency(*source->late()), source->lateDueS());  // due from the one before's lateDueS
        source = source->late();
        any = true;
      }
    }
    newBodies.clear();
    return Ok{};
  }
};

std::string_view fragmentPathName(FragmentPath path) {
  switch (path) {
    case FragmentPath::Debris: return "debris";
    case FragmentPath::ExactModes: return "exact_modes";
    case FragmentPath::Matched: return "matched";
    case FragmentPath::SurfaceOnly: return "surface_only";
  }
  return "unknown";
}

std::string_view frequencySourceName(FrequencySource source) {
  switch (source) {
    case FrequencySource::Own: return "own";
    case FrequencySource::Entry: return "entry";
    case FrequencySource::Ritz: return "ritz";
    case FrequencySource::Checked: return "checked";
    case FrequencySource::CheckedP2: return "checked_p2";
  }
  return "unknown";
}

Status validateWorldSettings(const WorldSettings& s) {
  const FractureSettings& f = s.fracture;
  if (s.maxObjects < 1) return invalidArgument("WorldSettings: maxObjects must be ≥ 1");
  if (s.maxPendingImpacts < 1 || s.workerThreads < 0 || s.maxFragmentsPerImpact < 2 || s.prepareEntryCorrections < 0 ||
      s.entryCacheCapacity < 0 || (s.entryCacheCapacity > 0 && s.prepareEntryCorrections > s.entryCacheCapacity)) {
    return invalidArgument("WorldSettings: maxPendingImpacts must be ≥ 1, workerThreads ≥ 0, maxFragmentsPerImpact ≥ 2, "
                           "prepareEntryCorrections ≥ 0 and entryCacheCapacity ≥ 0 (0: no bound), and no more entries "
                           "prepared than kept");
  }
  if (f.modeCount < 0 || f.pulseSteps < 2 || f.ringDownSteps < 0 || !(f.ringDownPeriods >= 0.0) ||
      !std::isfinite(f.ringDownPeriods) || !(f.debrisVolumeFraction >= 0.0 && f.debrisVolumeFraction < 1.0) ||
      !(f.contactSpreadFraction >= 0.0 && f.contactSpreadFraction < 1.0) ||
      f.exactModesMaxTets < 0 || f.exactModesMaxDof < 0 || f.exactModesBudgetDof < 0 || f.exactModeCount < 1 ||
      !(f.exactModesDelayS >= 0.0 && std::isfinite(f.exactModesDelayS)) ||
      !(f.matchErrorTarget >= 0.0 && std::isfinite(f.matchErrorTarget)) || f.polynomialModeDegree < 0 ||
      f.polynomialModeDegree > kMaxPolynomialModeDegree || f.meshRatioMaxDof < 0 || f.meshRatioLateMaxDof < 0 ||
      !(f.meshRatioLateDelayS >= 0.0) || !std::isfinite(f.meshRatioLateDelayS) ||
      !(f.meshRatioDelayS >= 0.0 && std::isfinite(f.meshRatioDelayS)) ||
      (f.meshRatioLateMaxDof > f.meshRatioMaxDof && f.meshRatioDelayS > f.meshRatioLateDelayS) || !(f.frequencyErrorTarget >= 0.0) ||
      !std::isfinite(f.frequencyErrorTarget) || !std::isfinite(f.meshRatioEscalationDelayS) ||
      !(f.meshRatioEscalationDelayS >= (f.frequencyErrorTarget > 0.0 ? f.meshRatioLateDelayS : 0.0))) {
    return invalidArgument("FractureSettings: modeCount ≥ 0, pulseSteps ≥ 2, ringDownSteps ≥ 0, ringDownPeriods ≥ 0 and finite, "
               "debrisVolumeFraction and contactSpreadFraction in [0, 1), exactModesMaxTets ≥ 0, exactModesMaxDof ≥ 0, exactModesBudgetDof ≥ 0, exactModeCount ≥ 1, exactModesDelayS finite and ≥ 0, matchErrorTarget finite and ≥ 0, polynomialModeDegree in [0, 5], meshRatioMaxDof ≥ 0, meshRatioLateMaxDof ≥ 0, meshRatioLateDelayS finite and ≥ 0, meshRatioDelayS finite and ≥ 0, and ≤ meshRatioLateDelayS with a later check, frequencyErrorTarget finite and ≥ 0, meshRatioEscalationDelayS finite and ≥ 0, and ≥ meshRatioLateDelayS with a frequencyErrorTarget");
  }
  if (f.crack.maxCracks < 0 || std::isnan(f.crack.propagationStressRatio) || !(f.crack.directionBlend >= 0.0) ||
      !(f.crack.directionBlend <= 1.0) || !(f.crack.noiseRad >= 0.0) || !std::isfinite(f.crack.noiseRad)) {
    return invalidArgument("CrackSettings: maxCracks ≥ 0, propagationStressRatio not NaN, directionBlend in [0, 1], noiseRad ≥ 0");
  }
  return Ok{};
}

World::World(std::unique_ptr<Impl> impl) : mImpl(std::move(impl)) {}
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;
World::~World() = default;

Result<World> World::create(Pack pack, const WorldSettings& settings) {
  if (Status st = validateWorldSettings(settings); !st) return st.error();
  pinEigenBlocking();  // the same fractures on every CPU, whatever the host set (EigenBlocking.h)
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
      const auto kept = static_cast<size_t>(settings.entryCacheCapacity);
      impl->entryCache = std::make_unique<detail::EntryCache>(db, kept);
      if (settings.shareEntryCorrections) {
        impl->entryCorrections = std::make_unique<detail::EntryCorrections>(*impl->entryCache, kept);
      }
    }
    return World(std::move(impl));
  } catch (const std::exception& e) {
    return invalidArgument(std::string("world creation failed: ") + e.what());
  }
}

Result<ObjectId> World::addObject(const ObjectDesc& desc) {
  try {
    Impl& w = *mImpl;
    const auto it = std::find_if(w.pack.objects.begin(), w.pack.objects.end(),
                                 [&](const ObjectAsset& a) { return a.name == desc.asset; });
    if (it == w.pack.objects.end()) return invalidArgument("unknown object '" + desc.asset + "' (not in the pack)");
    if (!desc.rotation.allFinite() || !desc.translationM.allFinite() ||
        (desc.rotation.transpose() * desc.rotation - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
        std::abs(desc.rotation.determinant() - 1.0) > 1e-6) {
      return invalidArgument("object pose: the rotation must be orthonormal with det +1 and the pose finite");
    }
    const auto index = static_cast<size_t>(it - w.pack.objects.begin());
    if (!w.packBodies[index]) {
      const auto mat = std::find_if(w.pack.materials.begin(), w.pack.materials.end(),
                                    [&](const Material& m) { return m.name == it->materialName; });
      if (mat == w.pack.materials.end()) return invalidArgument("object '" + desc.asset + "' names a missing material");
      auto body = makeBody(*it, *mat, w.settings.fracture.modeCount);
      if (!body) return body.error();
      std::shared_ptr<const Body> made = body.value();
      w.work.reserve(made->asset.tetMesh, made->topology, w.settings.fracture);  // the largest body's crack buffers
      // Pack objects are prepared before their first impact: the static correction's factorised K
      // and the tets' moments (what a breaking impact sums its fragments' moments from).
      const bool correct = w.settings.fracture.staticCorrection;
      if (w.settings.prepareInBackground) {
        if (correct) made->scheduleStaticCorrection();
        w.background().submit([made, correct] {
          (void)made->stressBounds();
          (void)made->tetMoments();
          if (correct) (void)made->staticCorrection();
        });
        if (correct && w.entryCorrections && w.entryCorrectionsScheduled.insert(mat->name).second) {
          // the database's first entries, in entry order, once per material
          const auto entries = std::min(w.pack.database.entries.size(),
                                        static_cast<size_t>(w.settings.prepareEntryCorrections));
          const int modeCount = w.settings.fracture.modeCount;
          for (size_t e = 0; e < entries; ++e) {
            // its frequencies: the entry's arrays may not be read yet (EntryReading::OnDemand)
            const auto stored = static_cast<int>(w.pack.database.entries[e].asset.modal.frequenciesHz.size());
            const int modes = detail::keptModeCount(modeCount, stored);  // the matched body's, as makeBody keeps them
            const auto& c = w.scheduledEntryCorrections.emplace_back(
                Impl::ScheduledEntryCorrection{static_cast<int32_t>(e), *mat, modes});
            w.background().submit([ec = w.entryCorrections.get(), c] { (void)ec->get(c.entry, c.material, c.modes); });
          }
        }
      } else {
        (void)made->stressBounds();
        (void)made->tetMoments();
        if (correct) {
          if (const auto& correction = made->staticCorrection(); !correction) return correction.error();
        }
      }
      w.packBodies[index] = BodySource::ready(std::move(made));
    }
    return w.place(w.packBodies[index], desc.rotation, desc.translationM);
  } catch (const std::exception& e) {
    return invalidArgument(std::string("addObject failed: ") + e.what());
  }
}

Status World::removeObject(ObjectId id) {
  auto s = mImpl->slot(id);
  if (!s) return s.error();
  if (s.value()->pending) return invalidArgument("removeObject: an impact on this object is pending (collect it first)");
  mImpl->remove(id);
  return Ok{};
}

bool World::isAlive(ObjectId id) const { return mImpl->slot(id).ok(); }
int32_t World::objectCount() const { return mImpl->live; }

Result<const ObjectAsset*> World::objectAsset(ObjectId id) const {
  auto s = mImpl->slot(id);
  if (!s) return s.error();
  const auto& body = s.value()->source->get();
  if (!body) return body.error();
  return &body.value()->asset;
}

Result<const ObjectAsset*> World::objectAsset(ObjectId id, double timeS) const {
  auto s = mImpl->slot(id);
  if (!s) return s.error();
  const auto& body = detail::sourceAt(s.value()->source, timeS)->get();
  if (!body) return body.error();
  return &body.value()->asset;
}

Result<FrequencyErrorPrediction> World::frequencyError(ObjectId id, double timeS) const {
  auto s = mImpl->slot(id);
  if (!s) return s.error();
  const auto& body = detail::sourceAt(s.value()->source, timeS)->get();
  if (!body) return body.error();
  return body.value()->frequencyError;
}

Result<ObjectDesc> World::objectPose(ObjectId id) const {
  auto s = mImpl->slot(id);
  if (!s) return s.error();
  ObjectDesc d;
  const auto& body = s.value()->source->get();
  if (!body) return body.error();
  d.asset = body.value()->asset.name;
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
    Impl& w = *mImpl;
    w.work.crack.recycle(result.fracture);  // a reused result's arrays: this growth's storage
    detail::resetImpactResult(result);
    auto job = w.makeJob(desc);
    if (!job) return job.error();
    if (Status st = detail::computeImpact(job.value(), w.work, result, w.born); !st) return st;
    return w.apply(desc.object, job.value(), result, w.born);
  } catch (const std::exception& e) {
    return invalidArgument(std::string("impact failed: ") + e.what());
  }
}

Result<ImpactTicket> World::submitImpact(const ImpactDesc& desc) {
  std::optional<ImpactTicket> recorded;
  try {
    Impl& w = *mImpl;
    if (w.pending.size() >= static_cast<size_t>(w.settings.maxPendingImpacts)) {
      return makeError(ErrorCode::CapacityExceeded,
                       "submitImpact: maxPendingImpacts = " + std::to_string(w.settings.maxPendingImpacts) + " reached");
    }
    auto job = w.makeJob(desc);
    if (!job) return job.error();
    auto p = std::make_unique<PendingImpact>();
    p->object = desc.object;
    p->job = std::move(job).value();
    if (!w.spareWorkspaces.empty()) {
      p->workspace = std::move(w.spareWorkspaces.back());
      w.spareWorkspaces.pop_back();
    } else {
      p->workspace = std::make_unique<detail::ImpactWorkspace>();
    }
    w.slots[desc.object.index].pending = true;
    const ImpactTicket ticket{w.nextTicket++};
    PendingImpact* raw = p.get();
    w.pending.emplace(ticket.id, std::move(p));
    // Should scheduling throw, the impact is forgotten and the object is no longer pending (a task
    // not scheduled yet is released with its handle, before the catch below runs).
    recorded = ticket;
    auto compute = [raw, ticket, &hook = w.settings.onImpactComputed, &closing = w.closing] {
      // made only when needed: an error's text allocates, and this runs on every submitted impact
      auto closed = [] { return invalidArgument("the World closed before the impact was computed"); };
      try {
        if (closing.load(std::memory_order_relaxed)) {
          raw->status = closed();  // not started before the World closed: nobody will collect it
        } else {
          {
            const detail::CancelScope scope(detail::tCancelFlag, &closing);  // a body it makes stops when the World closes
            raw->status = detail::computeImpact(raw->job, *raw->workspace, raw->result, raw->born);
          }
          if (*raw->status && hook) hook(ticket, raw->result);  // the host's code: never under the World's flag
        }
      } catch (const detail::Cancelled&) {
        raw->status = closed();
      } catch (const std::exception& e) {
        raw->status = invalidArgument(std::string("impact failed on a worker: ") + e.what());
      }
      raw->done.store(true, std::memory_order_release);
    };
    // A piece struck before its body is made: the body is made first, ahead of the background
    // threads' queue, and the impact goes to the workers only then. Made by the impact itself, it
    // had held the one impact worker a 2-core host leaves, and every impact submitted after it
    // (most of them on bodies long made) waited behind it: the pane scene's paced frames waited
    // 10–40 ms in most runs. The impact computes the same bits either way.
    if (raw->job.source && !raw->job.source->isMade() && w.backgroundThreads && w.backgroundThreads->threadCount() > 0) {
      auto deferred = std::make_shared<tbb::task_handle>();
      w.workers().execute([&] { *deferred = raw->group.defer(std::move(compute)); });
      w.backgroundThreads->submit(
          [source = raw->job.source, deferred, &arena = w.workers(), &closing = w.closing] {
            try {
              Impl::prepare(*source);
            } catch (const detail::Cancelled&) {
              return;  // the World is closing: the impact is dropped with its handle
            } catch (...) {
              // the impact meets the same failure and returns it as its error
            }
            if (closing.load(std::memory_order_relaxed)) return;  // made as it closed: dropped alike
            arena.enqueue(std::move(*deferred));
          },
          detail::BackgroundThreads::Urgency::First);
    } else {
      w.workers().execute([&] { raw->group.run(std::move(compute)); });
    }
    return ticket;
  } catch (const std::exception& e) {
    if (recorded) {
      mImpl->pending.erase(recorded->id);
      mImpl->slots[desc.object.index].pending = false;
    }
    return invalidArgument(std::string("submitImpact failed: ") + e.what());
  }
}

bool World::impactReady(ImpactTicket ticket) const {
  const auto it = mImpl->pending.find(ticket.id);
  return it != mImpl->pending.end() && it->second->done.load(std::memory_order_acquire);
}

Status World::collectImpact(ImpactTicket ticket, ImpactResult& result) {
  try {
    Impl& w = *mImpl;
    const auto it = w.pending.find(ticket.id);
    if (it == w.pending.end()) return invalidArgument("collectImpact: unknown or already collected ticket " + std::to_string(ticket.id));
    std::unique_ptr<PendingImpact> p = std::move(it->second);
    w.pending.erase(it);
    w.workers().execute([&] { p->group.wait(); });
    std::swap(result, p->result);
    p->workspace->crack.recycle(p->result.fracture);  // the caller's old arrays: a later growth's storage
    w.spareWorkspaces.push_back(std::move(p->workspace));
    Status status = p->status.value_or(Status(invalidArgument("collectImpact: the impact did not run")));
    if (!status) {
      w.slots[p->object.index].pending = false;
      return status;
    }
    return w.apply(p->object, p->job, result, p->born);
  } catch (const std::exception& e) {
    return invalidArgument(std::string("collectImpact failed: ") + e.what());
  }
}

int32_t World::pendingImpacts() const { return static_cast<int32_t>(mImpl->pending.size()); }

int32_t World::entryCorrectionsBuilt() const {
  return mImpl->entryCorrections ? mImpl->entryCorrections->built() : 0;
}

Status World::waitUntilPrepared() {
  try {
    Impl& w = *mImpl;
    // Where every core is kept busy, what placement scheduled and a starved background thread is
    // still making is made here instead (each is a OnceValue): the loading screen is not held up
    // by it. Where the threads ran, all of it is made already and these calls return at once.
    if (w.backgroundThreads) (void)w.backgroundThreads->wait(/*untilStarved=*/true);
    for (const auto& source : w.packBodies) {
      if (!source) continue;
      const std::shared_ptr<const Body>& body = source->get().value();  // pack bodies are made when placed
      (void)body->stressBounds();
      (void)body->tetMoments();
      if (!body->staticCorrectionScheduled()) continue;
      if (const auto& correction = body->staticCorrection(); !correction) return correction.error();
    }
    // Each once: one the cache drops later (entryCacheCapacity) is rebuilt when matched, as before.
    for (const auto& c : w.scheduledEntryCorrections) (void)w.entryCorrections->get(c.entry, c.material, c.modes);
    w.scheduledEntryCorrections.clear();
    return Ok{};
  } catch (const std::exception& e) {
    return invalidArgument(std::string("waitUntilPrepared failed: ") + e.what());
  }
}

}  // namespace brittle
