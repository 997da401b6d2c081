// SearchBench.h — the descriptor similarity-search benchmark behind `brittle bench search`.
//
// For each database size × descriptor kind × index setting it measures, against exact
// brute-force search over the same rows in the same run:
//   recall@1, query time (median, p99; the search only, descriptors precomputed), build time and
//   memory; and, on a subset of queries, the physical error of the match: relative error of mass,
//   principal inertia and the first three elastic frequencies of the matched entry rescaled to
//   the query (ScalingLaws.h) against a direct bake (tet mesh + modal analysis) of the query.
// It also times the canonical frames and each descriptor kind per fragment, on the query fragments
// refined by midpoint subdivision (the same solids) to at least minQueryTriangles triangles, so the
// cost is measured at the ≈1k triangles the targets are stated for. Output: CSV files for
// plot_search.py.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "brittle/database/DescriptorIndex.h"
#include "brittle/descriptors/ShapeDescriptors.h"
#include "brittle/precompute/BaseShapes.h"

namespace brittle::bench {

struct IndexChoice {
  std::string label;              ///< "kd-forest 4x64", "brute-force"
  DescriptorIndexSettings settings;
  bool framesAsOneSet = false;  ///< true: ":set", a fragment's candidate frames in one walk of a graph
};

/// "kd-forest:TREES:CHECKS", "hnsw:M:EF[:set]", "hnsw-binary:M:EF[:set]", "hnsw-pooled:M:EF[:set]", "hnsw-principal:M:EF[:set]", "faiss-hnsw:M:EF", "faiss-ivf:LISTS:PROBES",
/// "faiss-binary-hnsw:M:EF", "autotuned:PRECISION", "brute-force" or "faiss-binary-flat".
Result<IndexChoice> parseIndexChoice(const std::string& text);

struct SearchBenchSettings {
  std::vector<BaseShapeDefinition> shapes;
  std::vector<int64_t> sizes = {1000, 10000, 100000};
  std::vector<DescriptorKind> kinds = {DescriptorKind::Moment, DescriptorKind::Voxel, DescriptorKind::VoxelImproved};
  /// Voxel kinds cost ~100× the moments per fragment; sizes above this use moments only.
  int64_t voxelSizeLimit = 10000;
  std::vector<IndexChoice> indices;
  int queries = 200;
  int physicsQueries = 12;         ///< queries with a direct bake as ground truth (0: skip)
  int64_t physicsTets = 1000;
  int64_t minQueryTriangles = 500;  ///< queries are subdivided up to this (cut fragments have 100–500; mean ≈1k after)
  /// Share of database entries broken off by the runtime (DatabaseBakeSettings::runtimeFragments).
  double runtimeFraction = 0.0;
  /// Where the query fragments come from: exact cuts, or runtime fracture of the base shapes
  /// (what the runtime asks the database about).
  bool runtimeQueries = false;
  int voxelResolution = 16;
  int momentOrder = 4;             ///< highest order of the moment descriptor (database and queries)
  uint64_t seed = 1;
  /// Empty: bake the database each run. Else a pack whose fragment database (`bake-db`, for
  /// example `--descriptors-only` at 10⁵ entries) is searched instead, read whole; its descriptor
  /// settings describe the queries, and sizes above its entry count are skipped. The queries are
  /// cut as without it (from `shapes`, with `seed`).
  std::filesystem::path database;
  std::filesystem::path searchCsv = "docs/results/data/search.csv";
  std::filesystem::path descriptorCsv = "docs/results/data/descriptor_cost.csv";
  bool quiet = false;
};

/// Runs the benchmark and writes both CSV files. Errors: those of the bakes, PackIoError when a
/// CSV cannot be written.
Status runSearchBench(const SearchBenchSettings& settings);

}  // namespace brittle::bench
