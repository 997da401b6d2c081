// World.h — the runtime's public API: load a pack, place breakable objects, report impacts, get
// fragments back.
//
//   auto world = World::create(std::move(pack), WorldSettings{});     // Result<World>
//   auto plate = world.value().addObject({.asset = "glass-plate"});   // Result<ObjectId>
//   auto hit = world.value().impact({.object = plate.value(), .pointWorld = p, .normalWorld = n,
//                                    .speedMps = 5, .impactorMassKg = 0.1, .impactorRadiusM = 0.02});
//
// or, off the host's critical path (the fracture runs on a worker thread):
//
//   auto ticket = world.value().submitImpact(desc);        // returns at once
//   ... step the host's frames; the struck object stays rigid ...
//   ImpactResult hit;
//   world.value().collectImpact(ticket.value(), hit);      // at a frame the host fixes: waits only if not done
//
// No exception crosses this API: every call returns a Result or Status. Objects are reached by
// ObjectId (index + generation, as in Box2D): an id whose object was removed or broken is stale and
// every call with it returns InvalidArgument. Determinism: the same pack, settings, calls and
// seeds give bit-identical results, whether impacts run with impact() or with submitImpact() and
// collectImpact(), on any number of worker threads.
//
// Threading contract. A World's methods are called from one thread at a time (the host's). The
// work behind submitImpact, and the background preparation of placed objects
// (WorldSettings::prepareInBackground), runs on the World's own worker threads (oneTBB arenas of
// WorldSettings::workerThreads each: one for impacts, one of lower priority for background work, so
// that a free worker takes an impact first and a host waiting in collectImpact helps with impacts
// and never runs a background task); it reads only what no World call changes while it runs (the
// struck object's immutable data, the pack's database) and writes only its own result. Between
// submitImpact and collectImpact the struck object is pending: it stays in the world as it was,
// and impact(), submitImpact() and removeObject() on it return InvalidArgument. collectImpact
// applies the outcome (the broken object is removed, its fragments placed) on the host's thread,
// so object ids are handed out in the order the host collects. The World's destructor waits for
// work still running.
//
// An impact runs as stages: Hertz contact (HertzContact.h) → load over the contact patch → modal
// response, integrated exactly (ModalResponse.h), plus the static correction of the truncated
// modes (StaticCorrection.h) → stress scan with pruning and Rankine initiation → crack growth with
// the Griffith stop (CrackPropagation.h) → fragment surfaces (FragmentSurfaces.h) → per fragment:
// exact mass properties, and unless it is debris, the nearest database entry rescaled to it
// (FragmentMatcher.h, ScalingLaws.h) or, for small fragments, its own modal analysis
// (FragmentModes.h, exactModesMaxTets), which becomes a new object that can break again. The
// heavy part of a new object (its own modal analysis, or its entry rescaled) is made after the
// impact, on the World's workers, or by the first call that needs it (its first impact,
// objectAsset), which then waits for it: an impact returns once its fragments are known. A
// breaking impact is all or nothing: when a stage fails, or the fragments would not fit in
// maxObjects, the world is left as it was and the call returns the error.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "brittle/database/FragmentMatcher.h"
#include "brittle/database/Pack.h"
#include "brittle/core/Result.h"
#include "brittle/runtime/CrackPropagation.h"
#include "brittle/runtime/HertzContact.h"
#include "brittle/runtime/StaticCorrection.h"

namespace brittle {

/// An object handle: slot index and generation. Default-constructed ids are invalid.
struct ObjectId {
  uint32_t index = std::numeric_limits<uint32_t>::max();
  uint32_t generation = 0;
  bool valid() const { return index != std::numeric_limits<uint32_t>::max(); }
  bool operator==(const ObjectId&) const = default;
};

struct FractureSettings {
  int modeCount = 0;               ///< modes used per object (0: all stored); fewer is faster and less accurate
  int pulseSteps = 16;             ///< stress-evaluation instants during the contact
  double ringDownPeriods = 0.5;    ///< window after the contact, in periods of the lowest mode used
  int ringDownSteps = 24;          ///< instants in that window
  bool pruneStresses = true;       ///< skip elements and instants whose bound is below what is sought
  /// Add the quasi-static response of the modes beyond modeCount (StaticCorrection.h). Costs a
  /// factorisation per object at load and a sparse solve per impact.
  bool staticCorrection = true;
  /// Also scan the stresses without the correction, for ImpactResult::peakWithoutCorrectionPa
  /// (a second stress scan: off in the hot path, on in `brittle impact`).
  bool reportUncorrectedPeak = false;
  /// The contact load is Hertz's pressure spread over a disc of radius ρ = max(a, this × the
  /// body's bounding-box diagonal, the longest surface edge at the contact), a the Hertz patch
  /// radius, with the same resultant (ContactGeometry.h). The middle term is a length of the
  /// object, not of its mesh, so the stresses near the contact converge as the mesh is refined;
  /// finer detail under the contact (Hertzian cone cracks) is not modelled. 0: the mesh's ring
  /// only, which makes the contact stress a property of the mesh (docs/realtime.md, "Contact loads").
  /// An object whose pack gives its own (ObjectAsset::contactSpreadFraction: the brick and the
  /// stone ball of the default pack, 0.15) is spread over the larger of the two.
  double contactSpreadFraction = 0.05;
  CrackSettings crack;             ///< crack.seed is combined with the world seed and an impact counter
  double debrisVolumeFraction = 0.01;  ///< fragments below this fraction of the broken body are rigid debris
  /// Fragments that are not debris become new breakable objects: by the exact path below, or by
  /// the pack's database (when it has one). false: fragments come back as surfaces only.
  bool matchFragments = true;
  /// The exact path (FragmentModes.h): a fragment that holds a part of at most this many of the
  /// broken body's tets, and is not debris, gets its own modal analysis at runtime instead of the
  /// database match (and can break again even without a database; after a timed break, from
  /// exactModesDelayS on). 0: never. Chart 5 (docs/results/speed-accuracy.md),
  /// 20 modes: up to 150 tets the exact path costs 13.5 ms per fragment (p90 15.7 ms, within a
  /// 60 Hz frame; a match costs ~1.2 ms) and has the match's median frequency error (26 % against
  /// 24 %) but a bounded worst case (p90 38 % against 79 %); beyond, its cost grows about linearly
  /// (25 ms at 150–400 tets, 140 ms at 1000–3000) while the match's tail reaches hundreds of percent.
  int exactModesMaxTets = 150;
  /// ... and whose own model has at most this many degrees of freedom (3 × its FEM nodes, known
  /// once its solid is cut out): what the exact path costs. P1 fragments of up to 150 tets stay
  /// under it (at most ~1 000 sub-tets, ~1 500 DOF). A P2 fragment of the same 150 parent tets has
  /// 6–7k DOF and took 220–480 ms on the pane, where the match and a database entry's
  /// factorisation take ~10 ms; over the limit the fragment is matched. 0: no limit.
  int exactModesMaxDof = 2000;
  /// ... and, per impact, whose models together have at most this many degrees of freedom: the
  /// largest such fragments first, ties by fragment index (the others are matched, their reason
  /// says so). What one impact queues for the workers: an exact-path build costs about 15 µs per
  /// DOF (a P1 piece of 855 DOF 14 ms, of 1 600 DOF 18–20 ms), while a matched piece's body takes a
  /// few ms, so a break into many small pieces otherwise keeps a 2-core host's one worker busy for
  /// 50–80 ms, and a piece struck again meanwhile waits for it (docs/realtime.md, "A budget for the
  /// exact path"). 0: no budget.
  int exactModesBudgetDof = 2000;
  /// Modes of an exact-path fragment (at most modeCount when that is set). Fragments are smaller
  /// than their parent, so fewer of their modes fall in an impact's band; the static correction
  /// covers the rest. 40 modes cost ~1.5× what 20 do (chart 5).
  int exactModeCount = 20;
  /// ... when a timed break's exact-path piece (ImpactDesc::timeS) gets its own modal analysis:
  /// its impacts at a host time at least this long after the break use it
  /// (FragmentResult::exactDueS), the earlier ones its database match with its own polynomial
  /// Ritz frequencies (polynomialModeDegree; 0: the entry's), made first on the background
  /// threads (FragmentResult::matchedEntry stays −1: the match is searched there, from the
  /// piece's surface). The analysis is queued behind every first body, as the later checks are;
  /// an impact at or after the due time whose analysis is not made yet waits for it. A piece
  /// whose match cannot be made gets the analysis at once. With matchErrorTarget, a piece sent to
  /// the exact path because its match was predicted over the target still rings at that match
  /// until the due time. Made as the
  /// first body, the analysis (tens of ms of background time) kept every piece struck within
  /// frames of its birth waiting: over eight fracture histories of the pane scene, every impact
  /// that waited for its result waited for one (up to 22 ms past its latency; docs/realtime.md,
  /// "The exact path on the host's clock"). A break without a time, a pack without a database,
  /// or 0 here: the analysis is the first body. An analysis that fails leaves the match.
  double exactModesDelayS = 0.25;
  /// The scene's target for a match's error: the relative error of its first three frequencies,
  /// as the database predicts it at the match's descriptor distance (its 90th percentile,
  /// MatchErrors.h). 0: not used; fragments take the exact path by size alone. Above 0: a fragment
  /// small enough for the exact path takes its database match instead when the match is predicted
  /// within the target (a match costs ~1 ms, the exact path ~13 ms); a larger fragment still takes
  /// its match, and its reason says when the prediction is over the target. A database without a
  /// calibration (packs before version 4) predicts nothing, and fragments go by size.
  double matchErrorTarget = 0.0;
  /// A matched fragment's body rings at the fragment's own frequencies: the entry's r eigenvalues
  /// become the lowest r of a Rayleigh–Ritz analysis of the fragment's solid over polynomial fields
  /// of this degree (PolynomialModes.h, from its volume moments), and the entry keeps its mode
  /// shapes, stress modes and static correction. On the default objects' fragments degree 5 is 16 %
  /// off their own P2 frequencies (median) where the entries are 107 % off (chart 5). It costs
  /// ~3 ms a matched fragment (1 ms at degree 4), on the workers with the rest of the body, not in
  /// the impact. 0: the entry's own frequencies; at most kMaxPolynomialModeDegree (5).
  int polynomialModeDegree = 5;
  /// ... and the lowest kMeshRatioModes (3) of those frequencies are corrected by the fragment's
  /// own mesh when its linear-tet model (the fragment cut out of its parent, a crossed tet's part as
  /// a tet or prism where one crack crosses it: FragmentModes.h, CutCells::Prisms) has at most this
  /// many degrees of freedom: each Ritz value times the ratio of that mesh's own frequency to the
  /// polynomial fields' on it (meshFrequencyRatios). It finds the hinges and flaps no polynomial
  /// follows. A check costs ~7 ms a piece (median; ~11 ms at 1 500 DOF, ~70 ms at 5.6k) on the
  /// World's background threads, and an impact on a piece whose body is not made yet waits for it.
  /// On the current default pack's pieces (chart 5, 128 fragments; docs/results/speed-accuracy.md,
  /// "Every piece checked") the Ritz values are 31.6 % off (median; p90 400 %), checked up to 800
  /// DOF (the default until stop 65) 20.1 % (388 %), up to 1 500 14.0 % (190 %: 91 pieces), every
  /// piece 12.6 % (83 %). 1 500 keeps a check within a third of the player's 33 ms latency: with
  /// every piece checked the pane scene's pieces, struck soon after their birth, waited for their
  /// bodies in 3 of 8 paced runs (up to 17 ms; over the 33 ms frame goal in 8 of 26 runs this
  /// stop, against 1 of 31 at 800 and 1 of 17 at 1 500). 0: never.
  int meshRatioMaxDof = 1500;
  /// ... when a timed break's pieces (ImpactDesc::timeS) get that check: their impacts at a host
  /// time at least this long after the break (s) use the checked body, the earlier ones the Ritz
  /// values (FragmentResult::checkDueS). The check is made on the background threads right after
  /// the break's first bodies. Made in the first body instead, it made the pieces struck within
  /// frames of their birth wait for it. The pane scene, paced, ten interleaved runs: max frame
  /// 1.8–25.7 ms with the check at birth, 0.7–19.5 ms with it here; at 0.1 s, 5.9–48.4 ms, since
  /// most of its re-hits come 0.1–0.25 s after their break. The price: hits within the delay see
  /// the Ritz values, 31.6 % off (median) where checked bodies are 14.0 % (docs/realtime.md,
  /// "Pieces struck before their bodies are made"). A break without a time, or 0 here: the first
  /// body is checked (nothing later can apply to an untimed break). At most meshRatioLateDelayS.
  double meshRatioDelayS = 0.25;
  /// The check's element (meshRatioMaxDof still counts its mesh's linear DOF). P2 removes the
  /// linear tets' locking from the check: on chart 5's 169 pieces, checked every one, 1.4 % off
  /// (median) and 6 % (p90) against 10.3 % and 45 % with P1, which meets the matching targets
  /// (10 % and 25 %), at ~10 times the cost (58 ms a piece median, 243 ms p90, against 5.7 and
  /// 15.3): for a scene that needs its pieces' frequencies (sound) more than its frames.
  ElementOrder meshRatioElement = ElementOrder::P1;
  /// A matched piece over meshRatioMaxDof and within this many DOF is checked later, on the
  /// World's background threads: its impacts at a host time (ImpactDesc::timeS) at least
  /// meshRatioLateDelayS after the breaking impact's use its checked frequencies, the earlier ones
  /// its Ritz values, so that no impact waits for a large check while the host's clock decides, not
  /// the machine, which body an impact sees (FragmentResult::lateCheckDueS). An impact without a
  /// time, or a break without one, uses the Ritz values. On the default pack's pieces (chart 5)
  /// checking every piece takes the p90 from 190 % to 83 % (median 14.0 → 12.6 %); the largest
  /// piece's check, 5.6k DOF, took 72 ms (docs/results/speed-accuracy.md, "Every piece checked").
  /// 0: never.
  int meshRatioLateMaxDof = 12000;
  /// ... how long after its break (host seconds) a piece's later check applies: long enough for
  /// the background threads to have done it (the impact waits for it otherwise).
  double meshRatioLateDelayS = 0.5;
  /// The scene's target for a matched body's frequencies: the 90th percentile of its f1–f3 error as
  /// the pack predicts it (World::frequencyError; a pack calibrated by brittle calibrate-errors).
  /// Above 0, with the later check on (a break with a time, meshRatioElement P1): a piece whose later
  /// body is still predicted over the target gets a third version, checked in quadratic tets (up to
  /// meshRatioLateMaxDof linear DOF), used from meshRatioEscalationDelayS after its break. On chart 5's
  /// held-back pieces at 0.25 (the matching target): 73 of 128 pieces escalate, and from then on
  /// the bodies are 4.7 % off (median, p90 14.5 %: the targets met) where the later check alone gives
  /// 12.6 % (82 %); the P2 checks take ~70 ms a piece (median) of idle background time, queued
  /// behind every first body (the pane scene's frames as without it: max 1.1–2.7 ms). See
  /// docs/results/speed-accuracy.md, "Escalation by prediction". 0: off; a pack without the
  /// calibration escalates nothing (and its pieces report no escalationDueS).
  double frequencyErrorTarget = 0.25;
  /// ... when an escalated piece's P2 body applies (host seconds after its break), ≥ meshRatioLateDelayS
  /// when frequencyErrorTarget is above 0.
  double meshRatioEscalationDelayS = 2.0;
  DescriptorKind descriptor = DescriptorKind::Moment;
};

/// A submitted impact (World::submitImpact). Default-constructed tickets are invalid.
struct ImpactTicket {
  uint64_t id = 0;
  bool valid() const { return id != 0; }
  bool operator==(const ImpactTicket&) const = default;
};

struct ImpactResult;

/// Capacities are declared up front, as in Jolt: a call that would exceed one returns
/// ErrorCode::CapacityExceeded and changes nothing.
struct WorldSettings {
  int32_t maxObjects = 4096;   ///< capacity of object slots (live objects, including fragments)
  /// Fragments one impact may make (after crumb merging), at least 2; more leave the object
  /// unbroken. The default pack's hardest impacts make up to ~130.
  int32_t maxFragmentsPerImpact = 256;
  uint64_t seed = 1;
  /// Impacts submitted and not yet collected, at most.
  int32_t maxPendingImpacts = 64;
  /// Threads for the World's work; 0: one per core. Submitted impacts run in a oneTBB arena of this
  /// concurrency, one slot of it the host's (oneTBB starts a worker fewer than the cores). Background
  /// preparation (placement, the fragments' new bodies) runs on as many threads of the World's own
  /// at idle priority (Linux SCHED_IDLE), which take only the cores that impacts and the host
  /// leave: a host that sleeps between its frames lends them its core, and a synchronous impact
  /// keeps both of its threads (docs/realtime.md, "Background threads at idle priority"). 1: no
  /// worker and no background thread; the work runs when the host waits for it or needs it.
  /// Results do not depend on it.
  int32_t workerThreads = 0;
  /// Placing the first instance of a pack object starts the factorisation of its K (the static
  /// correction) on a background thread and returns at once; the object's first impact waits for
  /// it if it is not done. false: addObject factorises on the caller's thread and returns its
  /// errors. The same holds for a matched fragment's body: true, its K is factorised on a
  /// background thread right after the body is made; false, on its first impact.
  bool prepareInBackground = true;
  /// A matched fragment's static correction is its database entry's, factorised once per entry
  /// and material on first use and placed onto the fragment (StaticCorrection::placed: exact, the
  /// fragment's own factorisation within rounding), instead of a factorisation per fragment: an
  /// entry matched again costs none. false: every matched fragment factorises its own K.
  bool shareEntryCorrections = true;
  /// ... and, when a pack object is placed for the first time, the shared corrections of the
  /// database's first this-many entries are factorised for its material on the background
  /// workers (with shareEntryCorrections, the static correction and prepareInBackground; 0: none,
  /// each entry is factorised when a fragment is first matched to it). A break into many matched
  /// pieces then builds their bodies without a factorisation each: in the pane scene the one
  /// worker's queue of 26 body builds had made a piece struck 7 frames after its birth wait up to
  /// 24 ms. Costs about 6 ms of background work and 1.8 MB per entry (a 1k-tet P1 entry, 40
  /// modes): the default database's 70 entries 0.1–0.35 s and 128 MB. What a fracture computes
  /// does not depend on it. `brittle play` sets 256.
  int32_t prepareEntryCorrections = 0;
  /// What the World keeps of the database entries matched so far, shared by the fragments matched
  /// to them: each kept entry's connectivity, its basis at a material's ν other than the
  /// database's, and its static correction per material (~2.4 MB an entry of 1k tets and 12
  /// modes, ~0.8 MB at 300 tets). Past this many of each, the least recently matched is dropped
  /// and built again if matched again (to the same bits). 0: no bound (every entry ever matched
  /// is kept, which a long session with a 10⁴-entry database cannot afford). The default keeps
  /// the whole default database; it must be ≥ prepareEntryCorrections, or those would be dropped
  /// as they are made.
  int32_t entryCacheCapacity = 256;
  /// Called on a worker when the work of a submitted impact is done, before impactReady turns
  /// true, with the result collectImpact will hand over (the fragments' surfaces and mass
  /// properties are final; object ids are not assigned yet). A host builds what it needs per
  /// fragment there, off its own thread: its physics engine's collision hulls (the player's are
  /// its largest cost of a break), render meshes. Calls for different impacts may run at once,
  /// and it must not call the World. Should it throw, collectImpact returns the error and changes
  /// nothing. Not called for World::impact (the host has the result at once).
  std::function<void(ImpactTicket, const ImpactResult&)> onImpactComputed;
  FractureSettings fracture;
};

/// Checks ranges: maxObjects ≥ 1, maxPendingImpacts ≥ 1, maxFragmentsPerImpact ≥ 2, modeCount ≥ 0, pulseSteps ≥ 2, ringDownSteps ≥ 0,
/// ringDownPeriods ≥ 0, debrisVolumeFraction in [0, 1), crack settings. Error: InvalidArgument.
Status validateWorldSettings(const WorldSettings& settings);

struct ObjectDesc {
  std::string asset;                                             ///< an object name in the pack
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();        ///< local → world, det +1
  Eigen::Vector3d translationM = Eigen::Vector3d::Zero();        ///< world position of the local origin
};

/// An impact as the host reports it. Point and normal are in world coordinates; the normal is the
/// body's outward unit normal at the point (the impactor comes from that side).
struct ImpactDesc {
  ObjectId object;
  Eigen::Vector3d pointWorld = Eigen::Vector3d::Zero();
  Eigen::Vector3d normalWorld = Eigen::Vector3d::UnitZ();
  double speedMps = 0.0;                 ///< normal approach speed, > 0
  /// The host's clock at the impact (s), NaN: none. What it decides: which of a piece's versions
  /// its impact uses (its mesh checks, FractureSettings::meshRatioDelayS and meshRatioLateDelayS;
  /// its escalation; an exact-path piece's own analysis, exactModesDelayS), and when a break's
  /// pieces get them. Deterministic as the rest: the same
  /// times give the same results whatever the machine did meanwhile.
  double timeS = std::numeric_limits<double>::quiet_NaN();
  double impactorMassKg = 1.0;           ///< +∞: an immovable impactor (the ground)
  double impactorRadiusM = 0.01;         ///< +∞: flat
  double impactorYoungsModulusPa = 210e9;  ///< default: steel
  double impactorPoissonRatio = 0.3;
  double impulseNs = 0.0;                ///< the host's impulse; ≤ 0: (1 + e) m* v with the body's restitution
  double bodyRadiusM = 0.0;              ///< local radius of curvature; 0: estimated from the surface
  /// Radius (m) taken for the body where it is flat (or concave) at the point and the impactor is
  /// flat too, which Hertz cannot model: an edge or corner of that size meeting the flat. 0: such
  /// an impact is an InvalidArgument error.
  double flatPairRadiusM = 0.0;
  /// How far the point may lie from the body's surface (m); 0: 5 % of the body's size. The nearest
  /// surface point takes the hit. A matched fragment's mesh is its database entry's shape standing
  /// in for the fragment the host collides with, so such a body takes a point up to its own size
  /// (bounding-box diagonal) off, whatever this says.
  double pointToleranceM = 0.0;
  /// A host over its frame budget: skip the static correction unless the body's K factorisation
  /// was scheduled already (a pack object's when it was placed, a matched fragment's when its body
  /// was made, both with WorldSettings::prepareInBackground; a fragment's by an earlier impact),
  /// so that the impact never factorises K itself (StageTimes::prepareS). Less accurate when it
  /// skips (the truncated modes alone; see chart 1); ImpactResult::staticCorrectionUsed says which
  /// it was. Never depends on timing.
  bool fast = false;
};

/// What a fragment became.
enum class FragmentPath : uint8_t {
  Debris,       ///< below debrisVolumeFraction: a rigid piece, no modal data
  ExactModes,   ///< a new object with its own modal analysis (the exact path)
  Matched,      ///< a new object from its nearest database entry
  SurfaceOnly,  ///< not debris, but no new object: FragmentResult::reason says why
};

/// Stable snake_case name of a path: "debris", "exact_modes", "matched", "surface_only".
std::string_view fragmentPathName(FragmentPath path);

/// Where a body's lowest frequencies come from (World::frequencyError).
enum class FrequencySource : uint8_t {
  Own,      ///< its own modal analysis: a pack object, or a fragment on the exact path (a timed break's from its exactDueS)
  Entry,    ///< its database entry's, placed on it (polynomialModeDegree 0, or the Ritz analysis failed)
  Ritz,     ///< the fragment's polynomial Ritz values (polynomialModeDegree)
  Checked,  ///< those, the lowest three corrected by the fragment's own mesh (meshRatioMaxDof or the later check)
  CheckedP2,  ///< the same check in quadratic tets (meshRatioElement P2, or frequencyErrorTarget's escalation)
};

/// Stable snake_case name: "own", "entry", "ritz", "checked", "checked_p2".
std::string_view frequencySourceName(FrequencySource source);

/// How far a body's first three frequencies are predicted to be from its solid's own (the largest
/// relative error of the three, as chart 5 measures it against the fragment's P2 modes): the
/// pack's calibrated model for the body's source (MatchErrors.h), at the body's indicator.
struct FrequencyErrorPrediction {
  FrequencySource source = FrequencySource::Own;
  /// What the prediction is read at: Entry, the match's descriptor distance; Ritz, the Ritz values'
  /// convergence from degree p − 2 to p (MatchErrors.h); Checked, the mesh's gain over the
  /// polynomials (meshGain); Own, NaN.
  double indicator = std::numeric_limits<double>::quiet_NaN();
  /// Median and 90th percentile; NaN without a model: Own (nothing to predict), or a pack whose
  /// database has no calibration for the source (brittle calibrate-errors adds one).
  double median = std::numeric_limits<double>::quiet_NaN();
  double p90 = std::numeric_limits<double>::quiet_NaN();
  bool beyondRange = false;  ///< the indicator is beyond every calibrated one (the last bin's errors)
};

struct FragmentResult {
  /// The new breakable object; invalid for debris and unmatched fragments. Its modal data are made
  /// after the impact (see above); should that fail, its impacts and objectAsset return the error
  /// (an exact-path fragment whose analysis fails takes its database match instead, if any).
  ObjectId object;
  FragmentPath path = FragmentPath::SurfaceOnly;
  /// Why a fragment is SurfaceOnly (matching off, no database, the match or the entry failed), why
  /// the exact path fell back to the match, or, with FractureSettings::matchErrorTarget, why a
  /// fragment's match was predicted over the target; empty otherwise.
  std::string reason;
  bool debris = false;
  TriangleMesh surface;         ///< closed, outward; the broken object's local frame (m)
  MassProperties massProperties;  ///< exact, from the surface; local frame
  int64_t matchedEntry = -1;    ///< database entry, −1 if none
  bool exactModes = false;      ///< object built by the exact path (its own modal analysis, from exactDueS if that is set), not matched
  double matchDistance = 0.0;
  /// The match's predicted frequency error (median and 90th percentile, MatchErrors.h) when the
  /// fragment was matched or its match was weighed against the exact path; NaN otherwise.
  double predictedMatchError = std::numeric_limits<double>::quiet_NaN();
  double predictedMatchErrorP90 = std::numeric_limits<double>::quiet_NaN();
  /// A matched piece's later mesh check (FractureSettings::meshRatioLateMaxDof): its impacts at a
  /// timeS of at least this use the body with every check applied, World::objectAsset(id, timeS)
  /// shows it. NaN: none (the break had no time, or the later check is off).
  double lateCheckDueS = std::numeric_limits<double>::quiet_NaN();
  /// When a timed break's piece gets its check within FractureSettings::meshRatioMaxDof: its
  /// impacts at a timeS of at least this use that version (FractureSettings::meshRatioDelayS), the
  /// same body as before for a piece over the limit. NaN: the break had no time (its first body is
  /// checked), the delay is 0, or the piece is not matched.
  double checkDueS = std::numeric_limits<double>::quiet_NaN();
  /// Its escalation (FractureSettings::frequencyErrorTarget): from this host time on, its impacts
  /// use the body checked in quadratic tets if its later body was predicted over the target (the
  /// later body otherwise). NaN: none.
  double escalationDueS = std::numeric_limits<double>::quiet_NaN();
  /// An exact-path piece's own modal analysis (FractureSettings::exactModesDelayS): its impacts at a
  /// timeS of at least this use it, the earlier ones its database match. NaN: the analysis is its
  /// first body (the break had no time, no database, the delay is 0), or the piece is not on the
  /// exact path.
  double exactDueS = std::numeric_limits<double>::quiet_NaN();
};

struct StageTimes {
  double contactS = 0.0;
  double prepareS = 0.0;  ///< first impact on a fragment only: assembling and factorising its K (static correction)
  double modalS = 0.0, stressS = 0.0, propagationS = 0.0, surfacesS = 0.0;
  double matchingS = 0.0;  ///< new objects for the fragments: database matches and exact modal analyses
  double totalS() const { return contactS + prepareS + modalS + stressS + propagationS + surfacesS + matchingS; }
};

struct ImpactResult {
  bool broken = false;                 ///< the body fell apart (≥ 2 fragments); its id is then stale
  HertzContact contact;
  double bodyRadiusM = 0.0;            ///< the local radius of curvature used
  double peakPrincipalStressPa = 0.0;  ///< exact maximum over elements and instants
  /// The same from the truncated modes alone; NaN unless staticCorrection is off or
  /// reportUncorrectedPeak is on.
  double peakWithoutCorrectionPa = std::numeric_limits<double>::quiet_NaN();
  int32_t peakElement = -1;
  double peakTimeS = 0.0;
  int modesUsed = 0;
  bool staticCorrectionUsed = false;   ///< false when it is off, or skipped by a fast impact
  /// The contact load: nodes with weights summing to 1, force along forceDirectionLocal (the
  /// object's frame). What the offline full-FEM reference (brittle/precompute/FullFemReference.h) needs
  /// to solve the same impact.
  std::vector<std::pair<int32_t, double>> loadWeights;
  double loadRadiusM = 0.0;            ///< ρ, the radius the load was spread over (FractureSettings::contactSpreadFraction, or the object's own where larger)
  Eigen::Vector3d forceDirectionLocal = Eigen::Vector3d::Zero();
  double ringDownS = 0.0;              ///< the window simulated after the contact
  int64_t stressEvaluations = 0;
  FractureState fracture;
  std::vector<FragmentResult> fragments;  ///< empty unless broken; ordered by fragment label
  StageTimes times;
};

class World {
 public:
  /// Validates the settings and builds the search index of the pack's database (if any). Sets
  /// Eigen's product blocking process-wide to fixed cache sizes (brittle/core/EigenBlocking.h), so
  /// that fractures are the same bits on every CPU; call it where no other thread runs Eigen
  /// products at that moment. A pack read with EntryReading::OnDemand (Pack.h) gives the same
  /// fractures: the World reads the descriptor kind it searches here, and each database entry on a
  /// worker when a fragment is first matched to it, keeping it under entryCacheCapacity; the
  /// pack's file stays open while the World lives. An entry that fails its read (a damaged pack)
  /// fails the body of the fragment matched to it: objectAsset and impacts on that object return
  /// the read's typed error; nothing else is affected. Errors: InvalidArgument
  /// (settings), those of FragmentMatcher::build (with a pack read on demand, its read errors).
  static Result<World> create(Pack pack, const WorldSettings& settings = {});

  World(World&&) noexcept;
  World& operator=(World&&) noexcept;
  /// Drops the background work not started and stops the work running (placement, new bodies,
  /// submitted impacts not collected) at its next cancellation point instead of waiting for its
  /// end: the default vase destroyed as it is prepared, 8–130 ms (freeing its memory included)
  /// where it waited up to 1.7 s. Background threads that other work starves of every core still
  /// have to reach that point (docs/realtime.md, "A World destroyed without waiting").
  ~World();

  /// Places an instance of a pack object. The first instance of each pack object builds what
  /// impacts need (topology, stress bounds) and starts the factorisation of its K for the static
  /// correction: on a background thread (prepareInBackground, the default; an error there is returned by the
  /// object's first impact) or here.
  /// Errors: InvalidArgument (unknown asset name, a rotation
  /// that is not orthonormal with det +1, non-finite values), CapacityExceeded (no free slot:
  /// maxObjects reached), those of building the object's topology, and without prepareInBackground those of
  /// StaticCorrection::build.
  Result<ObjectId> addObject(const ObjectDesc& desc);
  /// A fragment's versions not made yet (its checks, its own analysis) are abandoned: their
  /// background work is skipped or stopped. Errors: InvalidArgument (stale or invalid id).
  Status removeObject(ObjectId id);
  bool isAlive(ObjectId id) const;
  int32_t objectCount() const;
  /// The object's asset (local frame) and pose. Errors: InvalidArgument (stale id).
  Result<const ObjectAsset*> objectAsset(ObjectId id) const;
  /// The asset an impact at host time `timeS` uses: the later-checked one from its
  /// FragmentResult::lateCheckDueS on (made now, or waited for, if it is not yet), the same as
  /// objectAsset(id) before it or for a NaN time.
  Result<const ObjectAsset*> objectAsset(ObjectId id, double timeS) const;
  Result<ObjectDesc> objectPose(ObjectId id) const;
  /// How the asset an impact at host time `timeS` uses got its frequencies, and how far off they
  /// are predicted to be (FrequencyErrorPrediction); for a fragment, known once its body is made
  /// (made now, or waited for, as objectAsset). A matched piece's prediction at its lateCheckDueS
  /// and after is its checked body's, at its escalationDueS and after its escalated body's (the
  /// P2 check's, or the later body's where it was within the target). Errors: InvalidArgument (stale id), those of the body's making.
  Result<FrequencyErrorPrediction> frequencyError(ObjectId id, double timeS = std::numeric_limits<double>::quiet_NaN()) const;

  /// Computes the fracture of one impact. When the body breaks, its id becomes stale and each
  /// matched fragment is a new object (same pose). Errors: InvalidArgument (stale id, non-finite
  /// or non-positive values, a point farther than the tolerance from the surface), those of the
  /// stages; Internal failures are reported as InvalidArgument with the stage named;
  /// CapacityExceeded (more fragments than maxFragmentsPerImpact, or than free object slots).
  Result<ImpactResult> impact(const ImpactDesc& desc);
  /// The same into `result`, which keeps its storage between calls. This is the hot path.
  /// Allocation: once the World's buffers have grown to the largest body hit (after one impact on
  /// it; the crack and surface buffers are reserved when a pack object is first placed), an impact
  /// that does not break the body allocates no heap memory (contact, modal response, static
  /// correction, stress scan), and one that breaks it computes its cracks, labels and surfaces in
  /// those buffers and allocates only what it hands over: the fracture state's two arrays (in the
  /// storage of those `result` held, when it held some as large), and per fragment its surface's
  /// two arrays, its reason text when it has one, and for a new object the source of its body (a
  /// task: the exact path cuts the fragment's own solid out and solves its modes, a match places
  /// its entry, both after the impact, on the workers). So the allocations are bounded by the
  /// fragments made, not by the body's size (tested: HotPathAllocationTest, with and without the
  /// exact path). A body's first impact may factorise its K (StaticCorrection.h).
  Status impact(const ImpactDesc& desc, ImpactResult& result);

  /// Starts the impact on a worker thread and returns at once; the struck object is pending until
  /// the impact is collected. Checks the id and the values (as impact()) before it starts.
  /// Errors: InvalidArgument (stale id, an object already pending, non-finite values),
  /// CapacityExceeded (maxPendingImpacts reached).
  Result<ImpactTicket> submitImpact(const ImpactDesc& desc);
  /// Whether collectImpact(ticket) would return without waiting. false for unknown tickets.
  bool impactReady(ImpactTicket ticket) const;
  /// Waits for the submitted impact if it is not done, then applies it as impact() would (the
  /// broken object is removed and its fragments placed; all or nothing) and writes its result.
  /// `result` keeps its storage between calls. A ticket is collected once.
  /// Errors: InvalidArgument (unknown or collected ticket), and those impact() returns: a failed
  /// impact leaves the object as it was, no longer pending.
  Status collectImpact(ImpactTicket ticket, ImpactResult& result);
  /// Impacts submitted and not yet collected.
  int32_t pendingImpacts() const;
  /// Waits until the background preparation of every placed pack object is done (a host's
  /// loading screen: afterwards no first impact waits for it), and the fragments' bodies being
  /// made. Where other work keeps every core busy, so that the background threads (at idle
  /// priority) get none, it makes what the pack objects still need on the calling thread instead,
  /// and leaves the rest running. Errors: the first failed
  /// preparation, in pack order (as StaticCorrection::build); the objects stay placed and their
  /// impacts return the same error.
  Status waitUntilPrepared();
  /// How many database entries' static corrections are factorised so far (each shared by the
  /// fragments matched to its entry: WorldSettings::prepareEntryCorrections at placement, or a
  /// matched fragment's first impact). 0 without a database or shareEntryCorrections.
  int32_t entryCorrectionsBuilt() const;

 private:
  struct Impl;
  explicit World(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> mImpl;
};

}  // namespace brittle
