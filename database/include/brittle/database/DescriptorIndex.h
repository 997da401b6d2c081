// DescriptorIndex.h — k-nearest-neighbour search over a row-major float32 descriptor matrix.
//
// One API, twelve backends:
//   - BruteForce: exact search, the reference. Squared L2 accumulated in double, reported as
//     float; ties (equal reported float distance) break by lower entry id.
//   - KdForest:   FLANN randomized kd-tree forest (flann::KDTreeIndexParams(trees)), searched with
//     flann::SearchParams(checks). Approximate: `checks` bounds the leaves visited per query.
//   - Autotuned:  FLANN picks the algorithm (kd-forest or k-means tree) and its parameters to reach
//     `targetPrecision` (fraction of true nearest neighbours found), then queries use the tuned
//     `checks`. COST: the build trains and times many candidate indices on a sample of the data
//     (default sample fraction 0.1) against linear-scan ground truth; it is one to several orders
//     of magnitude slower than a KdForest build (seconds at 1e4 entries, minutes at 1e5+). Use it
//     offline, then copy the chosen parameters into a KdForest setting.
//   - Hnsw:       hierarchical navigable small-world graph (hnswlib, Debian's libhnswlib-dev), a
//     peer of FLANN: `trees` is M (graph links per node), `checks` is ef (candidates kept per
//     query); built with ef_construction 200 by inserting rows in order, with `seed` as hnswlib's
//     level seed, so a build is deterministic. Approximate like KdForest.
//   - HnswBinary: the same graph over the binary codes of 0/1 descriptors (the occupancy voxel
//     kind), with the Hamming distance, which equals their squared L2 distance: a 16³ code is 512
//     bytes instead of 16 KiB of floats. Values other than 0 or 1 are an InvalidArgument.
//   - HnswPooled: for the voxel kinds (a cubic grid of R³ values, R a multiple of 8): the same
//     graph over a 512-value key per row, the grid's 8 × 8 × 8 block sums over √cells, whose
//     distance is a lower bound of the rows' own; the ef rows with the nearest keys are ranked by
//     their exact distance (brute force's; rows of 0/1 values by their bit codes, so their queries
//     must be 0/1 too). `trees` and `checks` as Hnsw; ef is also the number ranked.
//   - HnswPrincipal: HnswPooled with a 64-value key, the block sums' projection on their first 64
//     principal directions (a PCA of up to 4 096 evenly spaced rows, made by the build), still a
//     lower bound of the rows' distance; the ef nearest keys are ranked exactly, as HnswPooled's.
//     Its keys are 8× shorter, so its walk is cheaper.
//   - Ivf: an inverted file over float rows (IvfBackend.cpp): `trees` k-means lists, of which the
//     `checks` with the nearest centroids are scanned in SIMD registers; rows of 17–128 values (the
//     moment kind) are filed by their first 16 principal components and the norm of the rest, whose
//     bounds decide which rows get brute force's exact distance. Within the probed lists the answer
//     is exact; the lists probed decide the recall. k-means starts from evenly spaced rows and draws
//     nothing, so a build is the same in any process; `seed` is not used. For the moment kind at
//     10⁵ entries, where a graph's walk waits on memory.
//   - IvfBinary: the inverted file over 0/1 rows as bit codes (IvfBinaryBackend.cpp): `trees`
//     k-majority lists of the rows' codes over their varying columns, of which the `checks` whose
//     centroids are nearest are scanned by a 256-bit key (a lower bound of the code's distance), and
//     the rows the key cannot rule out ranked by their code. Within the probed lists the answer is
//     exact; the lists probed decide the recall. No random draw, so a build is the same in any
//     process; `seed` is not used. For the occupancy voxels at 10⁴–10⁵ entries, where a graph's
//     walk is long.
//   - FAISS (Debian's libfaiss-dev), the standard baselines for descriptor research:
//     FaissHnsw (IndexHNSWFlat: `trees` is M, `checks` efSearch, efConstruction 200), FaissIvf
//     (IndexIVFFlat: `trees` inverted lists from k-means, `checks` lists probed), and on binary
//     codes FaissBinaryFlat (exact Hamming scan) and FaissBinaryHnsw (M, efSearch as FaissHnsw).
//     The binary kinds take 0/1 descriptors (the occupancy voxel kind), whose Hamming distance is
//     their squared L2 distance; other values are an InvalidArgument. Built on one OpenMP thread
//     with seeded randomness, so a build is deterministic; queries run on the caller's thread.
//
// Distances are squared Euclidean (no square root). Entry ids are 0-based row indices.
//
// Lifetime: build() copies the matrix into the index; the caller's array may be freed right after.
// FLANN's Matrix does not own memory, so the FLANN index points into that private copy, which
// lives (and stays at the same address, including across moves) as long as the DescriptorIndex.
// The index is move-only.
//
// Determinism: every build is a function of the data and the settings (seed included), in any
// process. FLANN: the seed goes to flann::seed_random (std::srand), which fixes the split
// dimensions, and to the generator that stands in for the std::random_device FLANN 1.9.2 seeds each
// tree's shuffle from (FlannBackend.cpp). Because std::srand is process-global, do not build FLANN
// indices from several threads at once. The Autotuned choice also depends on timings, so it is
// not reproducible between runs; copy its parameters into a KdForest setting.
//
// Allocation (HNSW and FAISS: their result heaps allocate per query, like FLANN's): query() never allocates
// in the BruteForce backend (it writes straight into the
// caller's arrays, so there is no capacity limit beyond k ≤ size()). In the FLANN backends, FLANN
// 1.9 allocates on every query inside knnSearch: a k-entry result set, a branch heap that reserves
// room for size() branches (16 bytes each), and a size()-bit visited set. That cannot be avoided
// through FLANN's API; it is reported here rather than hidden.
//
// Thread safety: const methods may be called concurrently on one index (no shared scratch).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle {
namespace search {
class Backend;
}

/// The inverted file's keys (IvfBackend.cpp), shared with the estimates of the bytes a query reads
/// (precompute's FragmentSizing). A row of more than kKeyDims and at most kMaxProjectedDims values (the
/// moment descriptors) is keyed by its first kKeyDims principal components and the norm of the rest;
/// a wider row (the voxel grids) by kWideKeyDims directions, its list chosen by the centroids' first
/// kWideListDims values and its first bound taken from its key's first kWidePrefixDims.
struct InvertedFileKeys {
  static constexpr int64_t kKeyDims = 16;
  static constexpr int64_t kMaxProjectedDims = 128;
  static constexpr int64_t kWideKeyDims = 64;
  static constexpr int64_t kWideListDims = 32;
  static constexpr int64_t kWidePrefixDims = 16;
};

struct DescriptorIndexSettings {
  enum class Kind { BruteForce, KdForest, Autotuned, Hnsw, HnswBinary, FaissHnsw, FaissIvf, FaissBinaryFlat, FaissBinaryHnsw, HnswPooled, HnswPrincipal, Ivf, IvfBinary };
  Kind kind = Kind::KdForest;
  /// KdForest: number of randomized kd-trees, ≥ 1. Hnsw, HnswBinary, HnswPooled, HnswPrincipal and the FAISS graphs: M, in
  /// [2, 1024]. Ivf, IvfBinary and FaissIvf: inverted lists, in [1, rows].
  int trees = 4;
  /// KdForest: leaves visited per query, ≥ 1 (more: slower, better). Hnsw and the FAISS graphs:
  /// ef, ≥ 1. Ivf, IvfBinary and FaissIvf: lists probed, in [1, trees].
  int checks = 64;
  float targetPrecision = 0.95f;  ///< Autotuned: wanted fraction of exact neighbours, in (0, 1].
  uint64_t seed = 1;              ///< seed of every randomised build (FLANN uses the low 32 bits).
};

inline constexpr DescriptorIndexSettings::Kind kAllDescriptorIndexKinds[] = {
    DescriptorIndexSettings::Kind::BruteForce,      DescriptorIndexSettings::Kind::KdForest,
    DescriptorIndexSettings::Kind::Autotuned,       DescriptorIndexSettings::Kind::Hnsw,
    DescriptorIndexSettings::Kind::HnswBinary,      DescriptorIndexSettings::Kind::HnswPooled,
    DescriptorIndexSettings::Kind::HnswPrincipal,   DescriptorIndexSettings::Kind::Ivf,
    DescriptorIndexSettings::Kind::IvfBinary,
    DescriptorIndexSettings::Kind::FaissHnsw,       DescriptorIndexSettings::Kind::FaissIvf,
    DescriptorIndexSettings::Kind::FaissBinaryFlat, DescriptorIndexSettings::Kind::FaissBinaryHnsw};

/// The kinds that index 0/1 descriptors as bits (HnswBinary, IvfBinary and the FAISS binary kinds).
constexpr bool indexTakesBits(DescriptorIndexSettings::Kind kind) {
  return kind == DescriptorIndexSettings::Kind::HnswBinary || kind == DescriptorIndexSettings::Kind::IvfBinary || kind == DescriptorIndexSettings::Kind::FaissBinaryFlat ||
         kind == DescriptorIndexSettings::Kind::FaissBinaryHnsw;
}

/// "brute-force", "kd-forest", "autotuned", "hnsw", "hnsw-binary", "hnsw-pooled", "hnsw-principal", "ivf", "faiss-hnsw", "faiss-ivf",
/// "faiss-binary-flat" or "faiss-binary-hnsw" (the CLI and pack spelling).
const char* descriptorIndexKindName(DescriptorIndexSettings::Kind kind);
/// Inverse of descriptorIndexKindName. Error: InvalidArgument listing the valid names.
Result<DescriptorIndexSettings::Kind> parseDescriptorIndexKind(std::string_view name);
/// The settings as `bench search --index` spells them: "NAME:TREES:CHECKS" ("ivf:256:4",
/// "hnsw-binary:16:32"), "autotuned:PRECISION", or the exact kinds' name alone.
std::string describeIndexSettings(const DescriptorIndexSettings& settings);

class DescriptorIndex {
 public:
  /// Builds an index over `data`, a row-major rows × dims float32 matrix (entry i is row i).
  /// The data is copied. Errors (InvalidArgument): null data, rows < 1, dims < 1, rows·dims
  /// overflow, rows > INT32_MAX for FLANN and FAISS backends, a non-finite value (names row and
  /// column), trees or checks outside the kind's range, targetPrecision outside (0, 1], a value
  /// other than 0 or 1 for a binary kind, or a library failure (the message says which).
  static Result<DescriptorIndex> build(const float* data, int64_t rows, int64_t dims,
                                       const DescriptorIndexSettings& settings);

  /// The k nearest entries to `descriptor` (dims floats). Writes k ids and k squared L2
  /// distances, nearest first; equal distances are ordered by lower id. Errors (InvalidArgument):
  /// null pointer, k < 1, k > size(), a non-finite query value (names the column), a value other
  /// than 0 or 1 for a binary kind (HnswBinary and the FAISS binary kinds), fewer than k rows in the lists a FaissIvf query probes.
  [[nodiscard]] Status query(const float* descriptor, int k, int64_t* ids,
                             float* squaredDistances) const;

  /// `count` queries at once: `descriptors` is count × dims row-major; `ids` and
  /// `squaredDistances` are count × k row-major. Every query is validated before any is run, so
  /// on error nothing is written. Errors: as query(), plus count < 1; a non-finite value names
  /// the query row and column.
  [[nodiscard]] Status queryBatch(const float* descriptors, int64_t count, int k, int64_t* ids,
                                  float* squaredDistances) const;

  /// The k entries nearest to a set of `count` queries (`descriptors` is count × dims row-major),
  /// an entry's distance to the set being its smallest to any row: a fragment searched in all of
  /// its candidate frames at once. Writes k ids, k squared L2 distances and, in `rows`, the lowest
  /// query row that reaches each entry's distance; nearest first, ties by lower id, every entry
  /// once. The graph kinds (Hnsw, HnswBinary) walk their graph once under the set's distance, so a
  /// set costs about one query; the others answer each row's k nearest and merge them, which is
  /// exact for the set (an entry among the set's k nearest is among the k nearest of the row that
  /// reaches it); `eachRow` asks for that merge from every kind. Every row is validated first, so
  /// on error nothing is written. Errors: as queryBatch().
  [[nodiscard]] Status queryNearestOfSet(const float* descriptors, int64_t count, int k, int64_t* ids,
                                         float* squaredDistances, int32_t* rows, bool eachRow = false) const;

  /// Bytes held: the descriptor copy plus the backend's structures (FLANN's own count; the graph
  /// links, lists and codes of hnswlib and FAISS).
  int64_t memoryBytes() const;

  /// A 64-bit digest of the built index: its kind and settings, the data, and what the build made
  /// (FNV-1a over their bytes, brittle/core/Fingerprint.h). Equal digests: the same index, bit for
  /// bit, so that `brittle query --digest` can check a build across processes and machines. It reads
  /// every byte of the index (about a second a GB). Error: InvalidArgument when a library (FLANN,
  /// FAISS) cannot write its index out.
  Result<uint64_t> digest() const;

  int64_t size() const { return mRows; }
  int64_t dims() const { return mDims; }
  const DescriptorIndexSettings& settings() const { return mSettings; }

  DescriptorIndex(DescriptorIndex&&) noexcept;
  DescriptorIndex& operator=(DescriptorIndex&&) noexcept;
  DescriptorIndex(const DescriptorIndex&) = delete;
  DescriptorIndex& operator=(const DescriptorIndex&) = delete;
  ~DescriptorIndex();

 private:
  DescriptorIndex() = default;
  Status validateQuery(const float* descriptor, int k, int64_t queryRow, bool batch) const;
  void queryBruteForce(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const;
  Status queryBackend(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const;

  DescriptorIndexSettings mSettings;
  int64_t mRows = 0;
  int64_t mDims = 0;
  std::vector<float> mData;  ///< rows × dims row-major copy; FLANN points into it.
  std::unique_ptr<search::Backend> mBackend;  ///< null for BruteForce (IndexBackends.h)
};

}  // namespace brittle
