// FlannBackend.cpp — FLANN's randomized kd-forest and autotuned index, built reproducibly.
//
// FLANN 1.9.2 (Debian 12) draws the seed of the shuffle that starts each kd-tree (and of the
// k-means centres the autotuner tries) from a fresh std::random_device, which no call of FLANN's
// API controls: two builds of the same data differed in 147 of 200 answers. FLANN is header-only
// for these templates, so this unit compiles it with std::random_device spelled as SeededDevice
// below: each "device" draws from a per-thread splitmix64 stream that build() seeds from the
// settings' seed. std::srand (flann::seed_random) still fixes the split dimensions. The result is
// the same forest for the same data and seed, in any process.
//
// The spelling must name a type in namespace std (FLANN writes std::random_device), hence the
// alias below; <random> is included first, so no standard header sees the macro, and the macro is
// undefined right after FLANN's headers. This unit stays out of unity batches (CMakeLists.txt), so
// no other source includes FLANN before it and no other source sees the macro.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "brittle/core/Random.h"
#include "IndexBackends.h"

namespace brittle::search {
namespace {

thread_local SplitMix64 tSeedStream{0};

// What FLANN's headers get for std::random_device in this unit.
class SeededDevice {
 public:
  using result_type = unsigned int;
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return std::numeric_limits<result_type>::max(); }
  result_type operator()() { return static_cast<result_type>(tSeedStream.next() >> 32); }
  double entropy() const noexcept { return 0.0; }
};

}  // namespace
}  // namespace brittle::search

namespace std {
using brittle_flann_seeded_device = ::brittle::search::SeededDevice;
}  // namespace std

#define random_device brittle_flann_seeded_device
#include <flann/flann.hpp>
#undef random_device

namespace brittle::search {
namespace {

// FLANN writes neighbour indices as size_t. Writing them through a size_t* straight into the
// caller's int64_t array is allowed (unsigned type of the same rank) and saves a scratch copy.
static_assert(std::is_same_v<std::make_unsigned_t<int64_t>, std::size_t>,
              "FLANN's size_t indices are written in place into int64_t ids");

class FlannBackend final : public Backend {
 public:
  FlannBackend(const flann::Matrix<float>& data, const flann::IndexParams& index, flann::SearchParams params)
      : mIndex(data, index), mParams(params) {}
  void build() { mIndex.buildIndex(); }

  Status query(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const override {
    // Pre-fill so a short FLANN answer (not expected for k <= size()) is visible, not garbage.
    for (int i = 0; i < k; ++i) {
      ids[i] = -1;
      squaredDistances[i] = std::numeric_limits<float>::infinity();
    }
    try {
      // FLANN's Matrix wants non-const data; it does not write to the queries.
      flann::Matrix<float> queryMatrix(const_cast<float*>(descriptor), 1, mIndex.veclen());
      flann::Matrix<std::size_t> indexMatrix(reinterpret_cast<std::size_t*>(ids), 1, static_cast<std::size_t>(k));
      flann::Matrix<float> distanceMatrix(squaredDistances, 1, static_cast<std::size_t>(k));
      const int found = mIndex.knnSearch(queryMatrix, indexMatrix, distanceMatrix, static_cast<std::size_t>(k), mParams);
      if (found < k)
        return invalidArgument("DescriptorIndex query: FLANN returned " + std::to_string(found) + " of " +
                               std::to_string(k) + " neighbours");
    } catch (const std::exception& e) {
      return invalidArgument(std::string("DescriptorIndex query: FLANN search failed: ") + e.what());
    }
    sortByDistanceThenId(k, ids, squaredDistances);
    return Ok{};
  }

  int64_t memoryBytes() const override { return static_cast<int64_t>(mIndex.usedMemory()); }
  // FLANN's trees are private, and the file it writes them to (flann::Index::save) holds
  // uninitialised header bytes, compressed: two saves of one forest differ. Its digest is its
  // answers instead: up to 1 024 evenly spaced rows of its own data as queries, the 8 nearest each
  // (ids and distances), which another forest changes.
  Status addToDigest(Fingerprint& digest) const override {
    const auto rows = static_cast<int64_t>(mIndex.size());
    const int k = static_cast<int>(std::min<int64_t>(rows, 8));
    const int64_t queries = std::min<int64_t>(rows, 1024);
    std::vector<int64_t> ids(static_cast<size_t>(k));
    std::vector<float> distances(static_cast<size_t>(k));
    for (int64_t q = 0; q < queries; ++q) {
      const auto row = static_cast<size_t>(q * rows / queries);
      if (Status st = query(mIndex.getPoint(row), k, ids.data(), distances.data()); !st) return st;
      digest.add(ids, distances);
    }
    return Ok{};
  }

 private:
  // knnSearch is const in FLANN's API but not on flann::Index; searches share no scratch.
  mutable flann::Index<flann::L2<float>> mIndex;
  flann::SearchParams mParams;
};

}  // namespace

Result<std::unique_ptr<Backend>> buildFlann(const float* data, int64_t rows, int64_t dims,
                                            const DescriptorIndexSettings& settings) {
  using Kind = DescriptorIndexSettings::Kind;
  // FLANN 1.9 stores point indices and dimensions as int internally.
  if (rows > std::numeric_limits<int>::max() || dims > std::numeric_limits<int>::max())
    return invalidArgument("DescriptorIndex: FLANN backends need rows and dims <= INT32_MAX");
  if (settings.kind == Kind::KdForest && settings.trees < 1)
    return invalidArgument("DescriptorIndex: settings.trees must be >= 1, got " + std::to_string(settings.trees));
  if (settings.kind == Kind::KdForest && settings.checks < 1)
    return invalidArgument("DescriptorIndex: settings.checks must be >= 1, got " + std::to_string(settings.checks));
  if (settings.kind == Kind::Autotuned && !(settings.targetPrecision > 0.0f && settings.targetPrecision <= 1.0f))
    return invalidArgument("DescriptorIndex: settings.targetPrecision must be in (0, 1], got " +
                           std::to_string(settings.targetPrecision));
  try {
    // A non-owning view of DescriptorIndex's copy, which outlives the backend at the same address.
    flann::Matrix<float> matrix(const_cast<float*>(data), static_cast<std::size_t>(rows), static_cast<std::size_t>(dims));
    flann::seed_random(static_cast<unsigned int>(settings.seed));
    tSeedStream = SplitMix64(settings.seed);
    std::unique_ptr<FlannBackend> backend;
    if (settings.kind == Kind::KdForest) {
      backend = std::make_unique<FlannBackend>(matrix, flann::KDTreeIndexParams(settings.trees),
                                               flann::SearchParams(settings.checks));
    } else {
      // build_weight 0.01 (build time matters little), memory_weight 0, sample_fraction 0.1.
      backend = std::make_unique<FlannBackend>(
          matrix, flann::AutotunedIndexParams(settings.targetPrecision, 0.01f, 0.0f, 0.1f),
          flann::SearchParams(flann::FLANN_CHECKS_AUTOTUNED));
    }
    backend->build();
    return std::unique_ptr<Backend>(std::move(backend));
  } catch (const std::exception& e) {
    return invalidArgument(std::string("DescriptorIndex: ") + descriptorIndexKindName(settings.kind) +
                           " build failed: " + e.what());
  }
}

}  // namespace brittle::search
