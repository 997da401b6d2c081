// DescriptorIndex.h — k-nearest-neighbour search over a row-major float32 descriptor matrix.
//
// One API, four backends:
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
//
// Distances are squared Euclidean (no square root). Entry ids are 0-based row indices.
//
// Lifetime: build() copies the matrix into the index; the caller's array may be freed right after.
// FLANN's Matrix does not own memory, so the FLANN index points into that private copy, which
// lives (and stays at the same address, including across moves) as long as the DescriptorIndex.
// The index is move-only.
//
// Determinism: the seed is passed to flann::seed_random (std::srand) before every FLANN build,
// which fixes FLANN's choice of split dimensions. KNOWN LIMITATION: FLANN 1.9.2 (Debian 12) also
// shuffles the points with a std::random_device-seeded generator when it builds each tree, so two
// KdForest/Autotuned builds of the same data and seed can differ and approximate results can
// differ between them. Results of one built index are deterministic. BruteForce is fully
// deterministic. Because std::srand is process-global, do not build FLANN indices from several
// threads at once.
//
// Allocation (HNSW: its result heaps allocate per query, like FLANN's): query() never allocates
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
#include <string_view>
#include <vector>

#include "brittle/core/Result.h"

namespace brittle {

struct DescriptorIndexSettings {
  enum class Kind { BruteForce, KdForest, Autotuned, Hnsw };
  Kind kind = Kind::KdForest;
  int trees = 4;                  ///< KdForest: number of randomized kd-trees, ≥ 1. Hnsw: M, in [2, 1024].
  int checks = 64;                ///< KdForest: leaves visited per query, ≥ 1 (more: slower, better). Hnsw: ef, ≥ 1.
  float targetPrecision = 0.95f;  ///< Autotuned: wanted fraction of exact neighbours, in (0, 1].
  uint64_t seed = 1;              ///< FLANN random seed (only its low 32 bits are used).
};

/// "brute-force", "kd-forest", "autotuned" or "hnsw" (the CLI and pack spelling).
const char* descriptorIndexKindName(DescriptorIndexSettings::Kind kind);
/// Inverse of descriptorIndexKindName. Error: InvalidArgument listing the valid names.
Result<DescriptorIndexSettings::Kind> parseDescriptorIndexKind(std::string_view name);

class DescriptorIndex {
 public:
  /// Builds an index over `data`, a row-major rows × dims float32 matrix (entry i is row i).
  /// The data is copied. Errors (InvalidArgument): null data, rows < 1, dims < 1, rows·dims
  /// overflow, rows > INT32_MAX for FLANN backends, a non-finite value (names row and column),
  /// trees < 1, checks < 1, targetPrecision outside (0, 1], or a FLANN failure (message says so).
  static Result<DescriptorIndex> build(const float* data, int64_t rows, int64_t dims,
                                       const DescriptorIndexSettings& settings);

  /// The k nearest entries to `descriptor` (dims floats). Writes k ids and k squared L2
  /// distances, nearest first; equal distances are ordered by lower id. Errors (InvalidArgument):
  /// null pointer, k < 1, k > size(), a non-finite query value (names the column).
  [[nodiscard]] Status query(const float* descriptor, int k, int64_t* ids,
                             float* squaredDistances) const;

  /// `count` queries at once: `descriptors` is count × dims row-major; `ids` and
  /// `squaredDistances` are count × k row-major. Every query is validated before any is run, so
  /// on error nothing is written. Errors: as query(), plus count < 1; a non-finite value names
  /// the query row and column.
  [[nodiscard]] Status queryBatch(const float* descriptors, int64_t count, int k, int64_t* ids,
                                  float* squaredDistances) const;

  /// Bytes held: the descriptor copy plus FLANN's index structures (FLANN's own count).
  int64_t memoryBytes() const;

  int64_t size() const { return mRows; }
  int64_t dims() const { return mDims; }
  const DescriptorIndexSettings& settings() const { return mSettings; }

  DescriptorIndex(DescriptorIndex&&) noexcept;
  DescriptorIndex& operator=(DescriptorIndex&&) noexcept;
  DescriptorIndex(const DescriptorIndex&) = delete;
  DescriptorIndex& operator=(const DescriptorIndex&) = delete;
  ~DescriptorIndex();

 private:
  struct Flann;  // FLANN state, kept out of this header.
  struct Hnsw;   // hnswlib state, likewise.

  DescriptorIndex() = default;
  Status validateQuery(const float* descriptor, int k, int64_t queryRow, bool batch) const;
  void queryBruteForce(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const;
  Status queryFlann(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const;
  Status queryHnsw(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const;
  Status queryBackend(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const;

  DescriptorIndexSettings mSettings;
  int64_t mRows = 0;
  int64_t mDims = 0;
  std::vector<float> mData;  ///< rows × dims row-major copy; FLANN points into it.
  std::unique_ptr<Flann> mFlann;
  std::unique_ptr<Hnsw> mHnsw;
};

}  // namespace brittle
