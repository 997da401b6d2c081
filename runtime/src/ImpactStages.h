// ImpactStages.h — one impact's fracture, computed as named stages from inputs fixed when it was
// submitted: contact → load → modal response → stress scan → cracks → fragment surfaces → new
// bodies. Private to the runtime: World.cpp runs it on the caller's thread (World::impact) or on a
// worker (World::submitImpact), and then applies its outcome to the world.
//
// computeImpact changes nothing outside its arguments: it reads the struck body (immutable, but
// for its static correction, built at most once; Body.h), the database and the matcher (const,
// safe to share between threads), and writes the result, the workspace and the new bodies. The
// same job gives the same outcome on any thread, in any order with other jobs.
#pragma once

#include <Eigen/Core>
#include <oneapi/tbb/task_arena.h>
#include <memory>
#include <vector>

#include "Body.h"
#include "EntryCache.h"
#include "EntryCorrections.h"
#include "brittle/database/FragmentMatcher.h"
#include "brittle/runtime/CrackPropagation.h"
#include "brittle/runtime/FragmentSurfaces.h"
#include "brittle/runtime/StaticCorrection.h"
#include "brittle/runtime/World.h"

namespace brittle::detail {

/// What an impact's computation reads.
struct ImpactJob {
  std::shared_ptr<const BodySource> source;  ///< the struck body, made on first use
  std::shared_ptr<const Body> body;          ///< the same once made (set by computeImpact)
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< its pose when the impact was reported
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  ImpactDesc desc;
  uint64_t crackSeed = 0;            ///< from the world seed and the impact's number
  const FractureSettings* settings = nullptr;
  const FragmentMatcher* matcher = nullptr;  ///< null: no database search
  /// The database entries' shared static corrections (WorldSettings::shareEntryCorrections); null:
  /// each matched fragment factorises its own.
  const EntryCorrections* entryCorrections = nullptr;
  /// The database entries' connectivity and bases at other Poisson ratios, shared by every matched
  /// fragment (EntryCache.h): set whenever `matcher` is (World.cpp), and what places the entries.
  const EntryCache* entryCache = nullptr;
  int32_t maxFragments = 256;          ///< WorldSettings::maxFragmentsPerImpact
  /// WorldSettings::prepareInBackground: a matched fragment's static correction is scheduled when
  /// its body is made (the World builds it on the workers), else on its first impact.
  bool prepareFragments = true;
  tbb::task_arena* workers = nullptr;  ///< where the fragments' new bodies are made in parallel; null: the caller's
};

/// The buffers of an impact, kept between impacts: once they have grown to the largest body hit
/// (the crack and surface buffers are reserved for the pack's largest object when the World is
/// made), an impact allocates only what it hands over (World.h, "Allocation").
struct ImpactWorkspace {
  std::vector<double> times, force;
  std::vector<int32_t> contactFaces;  ///< the faces the contact load may reach (ContactGeometry.h)
  Eigen::VectorXd modalLoad, staticStress;
  Eigen::MatrixXd q;
  StaticCorrection::Workspace correction;
  StressScanWorkspace scanBuffers;
  StressScan scan;
  CrackWorkspace crack;
  Eigen::VectorXd crackQ;  ///< the modal coordinates at the peak, crack growth's field (its storage reused)
  FragmentSurfaceWorkspace surfaceBuffers;
  std::vector<TriangleMesh> surfaces;
  std::vector<double> fragmentMoments;  ///< per fragment, kFragmentMomentCount moments about the body's centre
  std::vector<double> momentChunkSums;  ///< fragmentVolumeMoments' per-range sums
  /// Reserves the crack and surface buffers for a body of the given mesh and topology.
  void reserve(const TetMesh& mesh, const TetTopology& topology, const FractureSettings& settings);
};

/// Computes the impact into `result` (reset first; fragment object ids are left invalid) and, per
/// fragment, the body it becomes (`born`, parallel to result.fragments; null for debris and
/// fragments that are not new objects), to be made on first use. Errors: those of the stages (InvalidArgument for a point
/// off the surface, FactorizationFailed, …), each naming its stage.
Status computeImpact(const ImpactJob& job, ImpactWorkspace& workspace, ImpactResult& result,
                     std::vector<std::shared_ptr<const BodySource>>& born);

/// Back to a default result, keeping the storage of loadWeights, the fracture state's lists and
/// the fragments vector.
void resetImpactResult(ImpactResult& result);

}  // namespace brittle::detail
