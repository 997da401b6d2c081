// DescriptorIndex.cpp — brute-force, FLANN and hnswlib backends of DescriptorIndex.
#include "brittle/database/DescriptorIndex.h"

#include <climits>
#include <cmath>
#include <cstddef>
#include <exception>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>

#include <Eigen/Core>
#include <flann/flann.hpp>
// hnswlib 0.6.2's SSE path prefetches through the entry one past a full link list, a heap
// over-read that AddressSanitizer reports. Without it (no manual vectorisation) the graph code is
// clean, and the distance below is vectorised by Eigen instead.
#define NO_MANUAL_VECTORIZATION
#include <hnswlib/hnswlib.h>

namespace brittle {

// FLANN writes neighbour indices as size_t. Writing them through a size_t* straight into the
// caller's int64_t array is allowed (unsigned type of the same rank) and saves a scratch copy.
static_assert(std::is_same_v<std::make_unsigned_t<int64_t>, std::size_t>,
              "FLANN's size_t indices are written in place into int64_t ids");

struct DescriptorIndex::Flann {
  flann::Index<flann::L2<float>> index;
  flann::SearchParams searchParams;
};

namespace {

// Squared L2 over `dims` floats, as hnswlib's L2Space but through Eigen's SIMD.
class EigenL2Space : public hnswlib::SpaceInterface<float> {
 public:
  explicit EigenL2Space(size_t dims) : mDims(dims) {}
  size_t get_data_size() override { return mDims * sizeof(float); }
  hnswlib::DISTFUNC<float> get_dist_func() override { return &distance; }
  void* get_dist_func_param() override { return &mDims; }

 private:
  static float distance(const void* a, const void* b, const void* param) {
    const auto n = static_cast<Eigen::Index>(*static_cast<const size_t*>(param));
    if (n == 28) {  // the default moment descriptor (order 4): unrolled at compile time
      using Fixed = Eigen::Matrix<float, 28, 1>;
      return (Eigen::Map<const Fixed>(static_cast<const float*>(a)) - Eigen::Map<const Fixed>(static_cast<const float*>(b)))
          .squaredNorm();
    }
    const Eigen::Map<const Eigen::VectorXf> x(static_cast<const float*>(a), n), y(static_cast<const float*>(b), n);
    return (x - y).squaredNorm();
  }
  size_t mDims;
};

}  // namespace

struct DescriptorIndex::Hnsw {
  std::unique_ptr<EigenL2Space> space;  // squared L2, as the other backends
  std::unique_ptr<hnswlib::HierarchicalNSW<float>> graph;
};

namespace {


// Orders the k results by (distance, id) so ties break by lower id whatever order a backend found
// them in. k is small, so insertion sort.
void sortByDistanceThenId(int k, int64_t* ids, float* distances) {
  for (int i = 1; i < k; ++i) {
    const int64_t id = ids[i];
    const float d = distances[i];
    int j = i;
    while (j > 0 && (distances[j - 1] > d || (distances[j - 1] == d && ids[j - 1] > id))) {
      ids[j] = ids[j - 1];
      distances[j] = distances[j - 1];
      --j;
    }
    ids[j] = id;
    distances[j] = d;
  }
}

}  // namespace

DescriptorIndex::DescriptorIndex(DescriptorIndex&&) noexcept = default;
DescriptorIndex& DescriptorIndex::operator=(DescriptorIndex&&) noexcept = default;
DescriptorIndex::~DescriptorIndex() = default;

const char* descriptorIndexKindName(DescriptorIndexSettings::Kind kind) {
  switch (kind) {
    case DescriptorIndexSettings::Kind::BruteForce: return "brute-force";
    case DescriptorIndexSettings::Kind::KdForest: return "kd-forest";
    case DescriptorIndexSettings::Kind::Autotuned: return "autotuned";
    case DescriptorIndexSettings::Kind::Hnsw: return "hnsw";
  }
  return "unknown";
}

Result<DescriptorIndexSettings::Kind> parseDescriptorIndexKind(std::string_view name) {
  using Kind = DescriptorIndexSettings::Kind;
  for (Kind kind : {Kind::BruteForce, Kind::KdForest, Kind::Autotuned, Kind::Hnsw}) {
    if (name == descriptorIndexKindName(kind)) return kind;
  }
  return makeError(ErrorCode::InvalidArgument, "unknown index backend '" + std::string(name) +
                                                   "' (expected brute-force, kd-forest, autotuned or hnsw)");
}

Result<DescriptorIndex> DescriptorIndex::build(const float* data, int64_t rows, int64_t dims,
                                               const DescriptorIndexSettings& settings) {
  using Kind = DescriptorIndexSettings::Kind;
  if (data == nullptr) return invalidArgument("DescriptorIndex: data is null");
  if (rows < 1) return invalidArgument("DescriptorIndex: rows must be >= 1, got " + std::to_string(rows));
  if (dims < 1) return invalidArgument("DescriptorIndex: dims must be >= 1, got " + std::to_string(dims));
  if (rows > std::numeric_limits<int64_t>::max() / dims ||
      static_cast<uint64_t>(rows * dims) > std::numeric_limits<std::size_t>::max() / sizeof(float))
    return invalidArgument("DescriptorIndex: rows * dims overflows");
  const bool flannKind = settings.kind == Kind::KdForest || settings.kind == Kind::Autotuned;
  // FLANN 1.9 stores point indices and dimensions as int internally.
  if (flannKind && (rows > INT_MAX || dims > INT_MAX))
    return invalidArgument("DescriptorIndex: FLANN backends need rows and dims <= INT32_MAX");
  if (settings.kind == Kind::KdForest && settings.trees < 1)
    return invalidArgument("DescriptorIndex: settings.trees must be >= 1, got " + std::to_string(settings.trees));
  if (settings.kind == Kind::KdForest && settings.checks < 1)
    return invalidArgument("DescriptorIndex: settings.checks must be >= 1, got " + std::to_string(settings.checks));
  if (settings.kind == Kind::Hnsw && (settings.trees < 2 || settings.trees > 1024))
    return invalidArgument("DescriptorIndex: settings.trees (HNSW M) must be in [2, 1024], got " + std::to_string(settings.trees));
  if (settings.kind == Kind::Hnsw && settings.checks < 1)
    return invalidArgument("DescriptorIndex: settings.checks (HNSW ef) must be >= 1, got " + std::to_string(settings.checks));
  if (settings.kind == Kind::Hnsw && rows > static_cast<int64_t>(std::numeric_limits<uint32_t>::max()))
    return invalidArgument("DescriptorIndex: HNSW needs rows <= UINT32_MAX");
  if (settings.kind == Kind::Autotuned &&
      !(settings.targetPrecision > 0.0f && settings.targetPrecision <= 1.0f))
    return invalidArgument("DescriptorIndex: settings.targetPrecision must be in (0, 1], got " +
                   std::to_string(settings.targetPrecision));
  for (int64_t r = 0; r < rows; ++r) {
    for (int64_t c = 0; c < dims; ++c) {
      if (!std::isfinite(data[r * dims + c]))
        return invalidArgument("DescriptorIndex: non-finite value in data at row " + std::to_string(r) +
                       ", column " + std::to_string(c));
    }
  }

  try {
    DescriptorIndex result;
    result.mSettings = settings;
    result.mRows = rows;
    result.mDims = dims;
    result.mData.assign(data, data + rows * dims);
    if (settings.kind == Kind::Hnsw) {
      auto hnsw = std::make_unique<Hnsw>();
      hnsw->space = std::make_unique<EigenL2Space>(static_cast<size_t>(dims));
      hnsw->graph = std::make_unique<hnswlib::HierarchicalNSW<float>>(
          hnsw->space.get(), static_cast<size_t>(rows), static_cast<size_t>(settings.trees), size_t{200},
          static_cast<size_t>(settings.seed));
      for (int64_t r = 0; r < rows; ++r) {
        hnsw->graph->addPoint(result.mData.data() + r * dims, static_cast<hnswlib::labeltype>(r));
      }
      hnsw->graph->setEf(static_cast<size_t>(settings.checks));
      result.mHnsw = std::move(hnsw);
      return result;
    }
    if (!flannKind) return result;

    // The Matrix is a non-owning view of mData. mData's buffer never moves after this point
    // (std::vector keeps its buffer when the DescriptorIndex is moved), so the view stays valid.
    flann::Matrix<float> matrix(result.mData.data(), static_cast<std::size_t>(rows),
                                static_cast<std::size_t>(dims));
    flann::seed_random(static_cast<unsigned int>(settings.seed));
    if (settings.kind == Kind::KdForest) {
      result.mFlann.reset(new Flann{
          flann::Index<flann::L2<float>>(matrix, flann::KDTreeIndexParams(settings.trees)),
          flann::SearchParams(settings.checks)});
    } else {
      // build_weight 0.01 (build time matters little), memory_weight 0, sample_fraction 0.1.
      result.mFlann.reset(new Flann{
          flann::Index<flann::L2<float>>(
              matrix, flann::AutotunedIndexParams(settings.targetPrecision, 0.01f, 0.0f, 0.1f)),
          flann::SearchParams(flann::FLANN_CHECKS_AUTOTUNED)});
    }
    result.mFlann->index.buildIndex();
    return result;
  } catch (const std::exception& e) {
    return invalidArgument(std::string("DescriptorIndex: ") + descriptorIndexKindName(settings.kind) + " build failed: " + e.what());
  }
}

int64_t DescriptorIndex::memoryBytes() const {
  const auto data = static_cast<int64_t>(mData.size() * sizeof(float));
  if (mHnsw) {  // level 0 (links, its own copy of the data, labels) plus the upper levels' links
    const auto& g = *mHnsw->graph;
    int64_t bytes = static_cast<int64_t>(g.max_elements_ * g.size_data_per_element_);
    for (size_t i = 0; i < g.cur_element_count; ++i) {
      bytes += static_cast<int64_t>(g.size_links_per_element_) * g.element_levels_[i];
    }
    return data + bytes;
  }
  return data + (mFlann ? static_cast<int64_t>(mFlann->index.usedMemory()) : 0);
}

Status DescriptorIndex::validateQuery(const float* descriptor, int k, int64_t queryRow,
                                      bool batch) const {
  if (descriptor == nullptr) return invalidArgument("DescriptorIndex query: descriptor is null");
  if (k < 1) return invalidArgument("DescriptorIndex query: k must be >= 1, got " + std::to_string(k));
  if (k > mRows)
    return invalidArgument("DescriptorIndex query: k = " + std::to_string(k) + " exceeds the " +
                   std::to_string(mRows) + " entries");
  for (int64_t c = 0; c < mDims; ++c) {
    if (!std::isfinite(descriptor[c]))
      return invalidArgument("DescriptorIndex query: non-finite value " +
                     (batch ? "at query row " + std::to_string(queryRow) + ", " : std::string("at ")) +
                     "column " + std::to_string(c));
  }
  return Ok{};
}

Status DescriptorIndex::query(const float* descriptor, int k, int64_t* ids,
                              float* squaredDistances) const {
  if (ids == nullptr || squaredDistances == nullptr)
    return invalidArgument("DescriptorIndex query: ids or squaredDistances is null");
  Status valid = validateQuery(descriptor, k, 0, false);
  if (!valid) return valid;
  return queryBackend(descriptor, k, ids, squaredDistances);
}

Status DescriptorIndex::queryBackend(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const {
  if (mHnsw) return queryHnsw(descriptor, k, ids, squaredDistances);
  if (mFlann) return queryFlann(descriptor, k, ids, squaredDistances);
  queryBruteForce(descriptor, k, ids, squaredDistances);
  return Ok{};
}

Status DescriptorIndex::queryBatch(const float* descriptors, int64_t count, int k, int64_t* ids,
                                   float* squaredDistances) const {
  if (descriptors == nullptr) return invalidArgument("DescriptorIndex queryBatch: descriptors is null");
  if (ids == nullptr || squaredDistances == nullptr)
    return invalidArgument("DescriptorIndex queryBatch: ids or squaredDistances is null");
  if (count < 1) return invalidArgument("DescriptorIndex queryBatch: count must be >= 1, got " + std::to_string(count));
  for (int64_t q = 0; q < count; ++q) {
    Status valid = validateQuery(descriptors + q * mDims, k, q, true);
    if (!valid) return valid;
  }
  // One query at a time, in order: same results as query(), single-threaded and deterministic.
  for (int64_t q = 0; q < count; ++q) {
    const float* descriptor = descriptors + q * mDims;
    int64_t* rowIds = ids + q * k;
    float* rowDistances = squaredDistances + q * k;
    Status status = queryBackend(descriptor, k, rowIds, rowDistances);
    if (!status) return status;
  }
  return Ok{};
}

void DescriptorIndex::queryBruteForce(const float* descriptor, int k, int64_t* ids,
                                      float* squaredDistances) const {
  // Keeps the best k so far, sorted by (distance, id), in the caller's arrays. Rows are scanned
  // in increasing id, so a later row only displaces a kept one on a strictly smaller distance:
  // that is what makes ties go to the lower id.
  int filled = 0;
  for (int64_t r = 0; r < mRows; ++r) {
    const float* row = mData.data() + r * mDims;
    double sum = 0.0;  // double accumulation: the reference should not lose digits to rounding
    for (int64_t c = 0; c < mDims; ++c) {
      const double diff = static_cast<double>(row[c]) - static_cast<double>(descriptor[c]);
      sum += diff * diff;
    }
    const float d = static_cast<float>(sum);
    if (filled == k && !(d < squaredDistances[k - 1])) continue;
    int j = filled < k ? filled++ : k - 1;
    while (j > 0 && squaredDistances[j - 1] > d) {
      squaredDistances[j] = squaredDistances[j - 1];
      ids[j] = ids[j - 1];
      --j;
    }
    squaredDistances[j] = d;
    ids[j] = r;
  }
}

Status DescriptorIndex::queryFlann(const float* descriptor, int k, int64_t* ids,
                                   float* squaredDistances) const {
  // Pre-fill so a short FLANN answer (not expected for k <= size()) is visible, not garbage.
  for (int i = 0; i < k; ++i) {
    ids[i] = -1;
    squaredDistances[i] = std::numeric_limits<float>::infinity();
  }
  try {
    // FLANN's Matrix wants non-const data; it does not write to the queries.
    flann::Matrix<float> queryMatrix(const_cast<float*>(descriptor), 1, static_cast<std::size_t>(mDims));
    flann::Matrix<std::size_t> indexMatrix(reinterpret_cast<std::size_t*>(ids), 1, static_cast<std::size_t>(k));
    flann::Matrix<float> distanceMatrix(squaredDistances, 1, static_cast<std::size_t>(k));
    const int found = mFlann->index.knnSearch(queryMatrix, indexMatrix, distanceMatrix,
                                              static_cast<std::size_t>(k), mFlann->searchParams);
    if (found < k)
      return invalidArgument("DescriptorIndex query: FLANN returned " + std::to_string(found) + " of " +
                     std::to_string(k) + " neighbours");
  } catch (const std::exception& e) {
    return invalidArgument(std::string("DescriptorIndex query: FLANN search failed: ") + e.what());
  }
  sortByDistanceThenId(k, ids, squaredDistances);
  return Ok{};
}

Status DescriptorIndex::queryHnsw(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const {
  try {
    auto found = mHnsw->graph->searchKnn(descriptor, static_cast<size_t>(k));  // max-heap: farthest on top
    if (static_cast<int>(found.size()) < k)
      return invalidArgument("DescriptorIndex query: HNSW returned " + std::to_string(found.size()) + " of " +
                     std::to_string(k) + " neighbours");
    for (int i = k - 1; i >= 0; --i) {
      squaredDistances[i] = found.top().first;
      ids[i] = static_cast<int64_t>(found.top().second);
      found.pop();
    }
  } catch (const std::exception& e) {
    return invalidArgument(std::string("DescriptorIndex query: HNSW search failed: ") + e.what());
  }
  sortByDistanceThenId(k, ids, squaredDistances);
  return Ok{};
}

}  // namespace brittle
