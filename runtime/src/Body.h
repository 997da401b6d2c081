// Body.h — what the runtime keeps per distinct asset (a pack object, or a fragment made by an
// impact): the asset, its material, and what is precomputed from them once (topology, stress
// bounds, surface normals and neighbours, the boundary's box tree, the static correction's
// factorised K, the tets' moments). Private to the
// runtime: World.cpp places bodies in slots, ImpactStages.cpp reads them.
//
// A Body is immutable once made, except for its static correction, stress bounds and tets' moments, each made
// on first use by whichever thread asks first (OnceValue.h): a background task the World starts when a
// pack object is placed, or the body's first impact, which makes its own copy should that task's thread be
// starved. Several threads may read a Body at once.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <atomic>
#include <functional>
#include <memory>
#include <vector>

#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/runtime/CrackPropagation.h"
#include "brittle/core/Result.h"
#include "brittle/runtime/FragmentModes.h"
#include "brittle/runtime/FragmentSurfaces.h"
#include "brittle/runtime/StaticCorrection.h"
#include "brittle/runtime/TetTopology.h"
#include "brittle/runtime/World.h"
#include "OnceValue.h"
#include "TriangleBoxTree.h"

namespace brittle::detail {

struct Body {
  ObjectAsset asset;
  Material material;
  TetTopology topology;
  int modes = 0;
  Eigen::VectorXd omega, zeta;
  Points nodeNormals;                      // #N, area-weighted outward normals (boundary nodes)
  std::vector<std::vector<int32_t>> ring;  // boundary neighbours per node
  std::vector<int32_t> boundaryNodes;
  TriangleBoxTree boundaryTree;            // over topology.boundaryTriangles: the contact's searches
  double sizeM = 0.0;                      // bounding-box diagonal
  Eigen::Vector3d centreM = Eigen::Vector3d::Zero();  // bounding-box centre: the origin of the tet moments
  /// The eigenvalues its static correction is built for when they are not its own (empty: its
  /// own; the correction's shift μ is 10⁻⁶ λ₁). A matched body that rings at its fragment's own
  /// frequencies keeps its entry's here (its shapes are the entry's), so that the correction it
  /// builds equals the entry's shared one (ImpactStages.cpp: placeEntry).
  Eigen::VectorXd correctionEigenvalues;
  /// A matched body's own polynomial Ritz frequencies (Hz, all that PolynomialModes gave) before
  /// any check scaled them; empty for other bodies. A later version's check scales these
  /// (ImpactStages.cpp: checkedVersion), not the version's own, which may be checked already.
  Eigen::VectorXd ritzFrequenciesHz;
  /// Where its frequencies come from and their predicted error (World::frequencyError): Own for
  /// a pack object and the exact path; a matched body's maker sets it before handing the body out.
  FrequencyErrorPrediction frequencyError;

  /// The stress scan's bounds per stress point over `modes` modes, weighted by 1/ω
  /// (CrackPropagation.h: stressModeBounds); made on first use, as the static correction (the
  /// plate's 30k points take ~50 ms, not to be paid on the caller's thread when it is placed).
  const StressBounds& stressBounds() const;

  /// Each tet's volume moments about centreM (FragmentSurfaces.h: tetVolumeMoments), from which a
  /// breaking impact sums its fragments' moments; made on first use, as the static correction.
  const TetMoments& tetMoments() const;

  /// The factorised K of the static correction (StaticCorrection.h), built on first use; waits
  /// when another thread is building it. Its errors are those of StaticCorrection::build.
  const Result<StaticCorrection>& staticCorrection() const;
  /// Whether staticCorrection() would return at once (built, or failed).
  bool staticCorrectionReady() const { return mCorrection.ready(); }
  /// Whether its build was started or asked for: a pack object's when it is placed, a matched
  /// fragment's when its body is made (ImpactStages.cpp); the World then builds it on the workers.
  bool staticCorrectionScheduled() const { return mCorrectionScheduled.load(std::memory_order_acquire); }
  void scheduleStaticCorrection() const { mCorrectionScheduled.store(true, std::memory_order_release); }
  /// Installs a static correction built elsewhere (makeBody, from the exact path's factor; a
  /// matched fragment's maker, its entry's placed) before the body is handed out: it then counts
  /// as built and scheduled. Const as the lazily built members are: the first install or build
  /// wins (OnceValue).
  void adoptStaticCorrection(Result<StaticCorrection> correction) const;

 private:
  mutable std::atomic<bool> mCorrectionScheduled{false};
  OnceValue<Result<StaticCorrection>> mCorrection;
  OnceValue<StressBounds> mStressBounds;
  OnceValue<TetMoments> mTetMoments;
};

/// A body made on first use: a fragment's new object, whose modal data (its own analysis, or its
/// matched entry rescaled) are made on a worker after the impact that broke its parent, or by
/// whichever thread needs them first (OnceValue: others wait, or make their own copy when its
/// maker's thread is starved). Making is a pure function of what the maker captured, so when and
/// where it runs changes nothing.
class BodySource {
 public:
  using Maker = std::function<Result<std::shared_ptr<const Body>>()>;
  static std::shared_ptr<const BodySource> ready(std::shared_ptr<const Body> body);
  static std::shared_ptr<const BodySource> deferred(Maker make);
  /// A deferred body with a chain of later versions (FractureSettings::meshRatioLateMaxDof's later
  /// check, then frequencyErrorTarget's escalation), due times ascending: each is made by its
  /// LateMaker from the result of the one before it (it may hand that back unchanged), which it
  /// holds weakly (no cycle), and impacts at a host time of at least its due time use it (sourceAt).
  using LateMaker = std::function<Result<std::shared_ptr<const Body>>(const Result<std::shared_ptr<const Body>>& base)>;
  struct Later {
    LateMaker make;
    double dueS = 0.0;
    /// Made with the first bodies' urgency (BackgroundThreads::Urgency::Now): cheap and due soon
    /// (FractureSettings::meshRatioDelayS's check). false: it can wait behind the next break's
    /// first bodies (Urgency::Later).
    bool soon = false;
  };
  static std::shared_ptr<const BodySource> deferred(Maker make, std::vector<Later> laters);
  /// The later version, null if none; its due time (host seconds).
  const std::shared_ptr<const BodySource>& late() const { return mLate; }
  double lateDueS() const { return mLateDueS; }
  /// Whether this version is made with the first bodies' urgency (a first body, or a Later::soon).
  bool wantedSoon() const { return mWantedSoon; }
  /// The body, made now if it was not; its errors are the maker's.
  const Result<std::shared_ptr<const Body>>& get() const;
  bool isMade() const { return mBody.ready(); }
  /// Marks this version and every later one as wanted by nobody (the object they are for was
  /// removed or broken): background jobs for them are skipped, or stop at their next cancellation
  /// point (Cancellation.h). Only a source no other object shares may be abandoned.
  void abandon() const;
  bool abandoned() const { return mAbandoned.load(std::memory_order_relaxed); }
  /// The flag a job making this version runs with (Cancellation.h's tJobCancelFlag).
  const std::atomic<bool>* abandonedFlag() const { return &mAbandoned; }

 private:
  mutable std::atomic<bool> mAbandoned{false};
  mutable Maker mMake;  // released once made and no thread is in it
  OnceValue<Result<std::shared_ptr<const Body>>> mBody;
  std::shared_ptr<const BodySource> mLate;
  double mLateDueS = 0.0;
  bool mWantedSoon = true;
};

/// The version of `source` an impact at host time `timeS` uses: the last of its chain whose due
/// time has come (a NaN time never reaches one), else itself.
inline const std::shared_ptr<const BodySource>& sourceAt(const std::shared_ptr<const BodySource>& source, double timeS) {
  return source && source->late() && timeS >= source->lateDueS() ? sourceAt(source->late(), timeS) : source;
}

/// The modes a body keeps of `available`: the first `requested`, or all of them when requested ≤ 0.
inline int keptModeCount(int requested, int available) { return requested > 0 ? std::min(requested, available) : available; }

/// Builds a body with the first `modeCount` stored modes (0: all, keptModeCount). With `factor` (the exact
/// path's, holding a factorisation), its static correction is built at once from that factor
/// (μ = −σ) instead of a second factorisation on its first impact. `correctionEigenvalues`: see Body.
/// `sameTets`, when given, is a topology of a mesh with the asset's tets (a matched entry's own,
/// EntryCache.h): its connectivity is reused, buildTetTopology(mesh, sameTets), the same bits.
/// Errors: InvalidArgument (no modal data, stress modes of the wrong size, a zero-frequency
/// elastic mode), those of buildTetTopology.
Result<std::shared_ptr<const Body>> makeBody(ObjectAsset asset, const Material& material, int modeCount,
                                             const ExactModesFactor* factor = nullptr,
                                             Eigen::VectorXd correctionEigenvalues = {},
                                             const TetTopology* sameTets = nullptr);

/// `base` ringing at `rates`' frequencies, eigenvalues and residuals (as many as base's asset
/// has; rates' modes are not read): the same mesh, shapes, stress modes, topology and static
/// correction (base's, built now if it was scheduled and not built: a correction does not depend
/// on the frequencies when base has correctionEigenvalues), with ω, ζ and the stress bounds its
/// own. A matched body's later, checked version (ImpactStages.cpp: checkedVersion) without placing
/// its entry and building its geometry again. frequencyError and ritzFrequenciesHz are base's; the
/// caller sets them. Errors: InvalidArgument (base has no correctionEigenvalues, `rates` of
/// another size, a zero-frequency mode).
Result<std::shared_ptr<Body>> withFrequencies(const Body& base, const ModalBasis& rates);

}  // namespace brittle::detail
