// FragmentSizing.h — what a scene's fragments need (part of the sizing of ModelSizing.h).
//
// sceneFragments, chooseDebrisThreshold, chooseSearch: every impact of the scene at its top speed
// breaks the object (at its chosen modes, no debris threshold); each fragment gets its own modes by the runtime's exact path (FragmentModes.h) and
// is hit again, at one drawn point, by each of the scene's impactors at the top speed.
//   * Debris threshold: half the volume fraction of the smallest fragment that broke again
//     (nothing smaller would break in this scene, so it can be rigid), within [0.001, 0.5]; 0.5
//     when none broke. The scene's threshold is the smallest over its objects.
//   * Descriptor and search precision: each descriptor kind of the database × each precision of
//     the ladder matches every fragment. A precision scales the `checks` of the index the database
//     stores for that kind (a graph's ef, an inverted file's lists probed, a kd-forest's checks:
//     defaultIndexSettings unless its bake named another); 0 is the exact search. The error is the
//     largest relative error of the match's first three frequencies against the fragment's own
//     modes, and the time covers descriptors, search and rescaling. The choice is the cheapest
//     trial whose median error meets matchFrequencyError (the fewest bytes of rows and keys a
//     query compares, searchBytesCompared; the first tried on ties), else the most accurate, and
//     the result says which. A measured time is reported, not weighed: it would make the sized
//     pack differ from run to run. The sized pack's database stores the chosen index settings.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "brittle/core/MeshTypes.h"
#include "brittle/core/Result.h"
#include "brittle/database/DescriptorIndex.h"
#include "brittle/database/FragmentDatabase.h"
#include "brittle/database/Material.h"
#include "brittle/database/ObjectAsset.h"
#include "brittle/precompute/Progress.h"
#include "brittle/precompute/SceneRequirements.h"

namespace brittle {

/// One fragment of the scene (see the header comment).
struct FragmentRecord {
  std::string object;                 ///< the scene object it came from
  std::string material;
  double volumeFraction = 0.0;        ///< of the object
  bool brokeAgain = false;
  TriangleMesh surface;               ///< closed, outward, object frame (m)
  Eigen::Vector3d frequenciesHz = Eigen::Vector3d::Zero();  ///< first three of its own modes
};

/// Errors: InvalidArgument (settings, range), those of the runtime.
Result<std::vector<FragmentRecord>> sceneFragments(const ObjectAsset& asset, const Material& material,
                                                   const SceneObjectRange& range, int modes,
                                                   const ModelSizingSettings& settings = {},
                                                   ProgressSink* progress = nullptr);

struct DebrisSizing {
  std::string object;
  int fragments = 0, brokeAgain = 0;
  double smallestBrokenFraction = std::numeric_limits<double>::quiet_NaN();  ///< NaN: none broke again
  double debrisVolumeFraction = 0.5;  ///< chosen
};
DebrisSizing chooseDebrisThreshold(const std::string& object, const std::vector<FragmentRecord>& fragments);

/// The bytes of rows and keys one query of `index` compares in `rows` rows of `cols` values: what
/// chooseSearch weighs, since it is the same in every run (a measured time is not). An estimate
/// from each index's design, with R the row's bytes (4 a value; 1/8 for the bit codes of
/// hnsw-binary and FAISS's binary indexes):
/// - brute force, faiss-binary-flat: rows × R;
/// - kd-forest, autotuned: min(checks, rows) × R;
/// - the graphs (hnsw, hnsw-binary, faiss-hnsw, faiss-binary-hnsw): min(ef × M, rows) × R, as each
///   of about ef expanded nodes measures about M unvisited neighbours (a probe counted ~600 rows
///   at ef 32, M 16 on 10⁴ occupancy grids);
/// - hnsw-pooled, hnsw-principal: the same walk over their keys (512 and 64 floats), plus the ef
///   rows ranked exactly;
/// - ivf: the centroids and the probed lists' rows by their keys (the first ≤ 16 components and
///   two norms), plus one row ranked exactly (4.7 a query measured at 10⁵; they are negligible);
/// - faiss-ivf: the centroids and the probed lists' rows, each R.
double searchBytesCompared(const DescriptorIndexSettings& index, int64_t rows, int64_t cols);

/// The database's stored index for a kind at `precision` times its `checks` (rounded, ≥ 1; an
/// inverted file's probes at most its lists); 0: the exact search (brute force). The exact kinds
/// and the autotuned kd-forest have no precision to scale and come back as they are.
DescriptorIndexSettings indexAtPrecision(const DescriptorIndexSettings& stored, double precision);

struct SearchTrial {
  DescriptorKind kind = DescriptorKind::Moment;
  double precision = 0.0;             ///< the ladder's factor on the stored index's checks; 0: exact
  DescriptorIndexSettings index;      ///< indexAtPrecision(the stored index, precision)
  int matched = 0;                    ///< fragments matched (a frame can be undefined)
  double medianFrequencyError = std::numeric_limits<double>::quiet_NaN();
  double bytesCompared = 0.0;         ///< searchBytesCompared of the index over the database, per frame's query
  double medianMatchMs = 0.0;  ///< measured and reported, not weighed
  /// Per matched fragment: the match's descriptor distance and its error against the fragment's
  /// own first three frequencies (what MatchErrors.h's models are fitted to).
  std::vector<std::pair<double, double>> distanceErrors;
};

struct SearchSizing {
  DescriptorKind kind = DescriptorKind::Moment;
  double precision = 0.0;             ///< the chosen trial's
  DescriptorIndexSettings index;      ///< the chosen trial's: what the sized pack stores for `kind`
  bool targetMet = false;
  double medianFrequencyError = std::numeric_limits<double>::quiet_NaN();
  double medianMatchMs = 0.0;
  int fragments = 0;
  std::vector<SearchTrial> trials;
  std::vector<std::pair<double, double>> distanceErrors;  ///< the chosen trial's
};

/// Errors: InvalidArgument (empty database or fragment list, an empty precision ladder or a
/// negative or non-finite precision, a fragment whose material is not in `materials`), those of
/// FragmentMatcher::build.
Result<SearchSizing> chooseSearch(const FragmentDatabase& database, const std::vector<FragmentRecord>& fragments,
                                  const std::vector<Material>& materials, double targetError,
                                  const ModelSizingSettings& settings = {});

}  // namespace brittle
