// HnswBackend.cpp — hnswlib's hierarchical navigable small-world graph (Debian's libhnswlib-dev),
// over float descriptors (squared L2) or over the binary codes of 0/1 descriptors (Hamming).
#include <cstddef>
#include <cstdint>
#include <algorithm>
#include <cstring>
#include <vector>
#include <exception>
#include <limits>
#include <memory>
#include <queue>
#include <string>
#include <utility>

#include <Eigen/Core>
// hnswlib 0.6.2's SSE path prefetches through the entry one past a full link list, a heap
// over-read that AddressSanitizer reports. Without it (no manual vectorisation) the graph code is
// clean, and the distance below is vectorised by Eigen instead.
#define NO_MANUAL_VECTORIZATION
#include <hnswlib/hnswlib.h>

#include "IndexBackends.h"

namespace brittle::search {
namespace {

// Squared L2 over `dims` floats, as hnswlib's L2Space but through Eigen's SIMD.
float squaredL2(const void* a, const void* b, const void* param) {
  const auto n = static_cast<Eigen::Index>(*static_cast<const size_t*>(param));
  if (n == 28) {  // the default moment descriptor (order 4): unrolled at compile time
    using Fixed = Eigen::Matrix<float, 28, 1>;
    return (Eigen::Map<const Fixed>(static_cast<const float*>(a)) - Eigen::Map<const Fixed>(static_cast<const float*>(b)))
        .squaredNorm();
  }
  const Eigen::Map<const Eigen::VectorXf> x(static_cast<const float*>(a), n), y(static_cast<const float*>(b), n);
  return (x - y).squaredNorm();
}

class EigenL2Space : public hnswlib::SpaceInterface<float> {
 public:
  explicit EigenL2Space(size_t dims) : mDims(dims) {}
  size_t get_data_size() override { return mDims * sizeof(float); }
  hnswlib::DISTFUNC<float> get_dist_func() override { return &squaredL2; }
  void* get_dist_func_param() override { return &mDims; }

 private:
  size_t mDims;
};

// Hamming distance between two codes of `words` 64-bit words. hnswlib keeps each code 4-byte
// aligned only, so the words are loaded through memcpy. The popcnt instruction is used where the
// CPU has it (chosen once, when the space is made); both versions give the same integer.
template <bool kPopcnt>
float hamming(const void* a, const void* b, const void* param) {
  const size_t words = *static_cast<const size_t*>(param);
  const auto* x = static_cast<const unsigned char*>(a);
  const auto* y = static_cast<const unsigned char*>(b);
  uint64_t sum = 0;
  for (size_t i = 0; i < words; ++i) {
    uint64_t u, v;
    std::memcpy(&u, x + 8 * i, 8);
    std::memcpy(&v, y + 8 * i, 8);
    if constexpr (kPopcnt) {
      uint64_t count;
      asm("popcntq %1, %0" : "=r"(count) : "r"(u ^ v));
      sum += count;
    } else {
      sum += static_cast<uint64_t>(__builtin_popcountll(u ^ v));
    }
  }
  return static_cast<float>(sum);  // exact: at most 2^24 bits
}

class HammingSpace : public hnswlib::SpaceInterface<float> {
 public:
  explicit HammingSpace(size_t words) : mWords(words) {}
  size_t get_data_size() override { return mWords * 8; }
  hnswlib::DISTFUNC<float> get_dist_func() override {
    return __builtin_cpu_supports("popcnt") ? &hamming<true> : &hamming<false>;
  }
  void* get_dist_func_param() override { return &mWords; }

 private:
  size_t mWords;
};

// Float rows are inserted as they are; 0/1 rows as their binary codes (8-byte words).
template <typename Space, bool kBinary>
class HnswBackend final : public Backend {
 public:
  HnswBackend(const float* data, int64_t rows, int64_t dims, const DescriptorIndexSettings& settings)
      : mDims(dims),
        mSpace(kBinary ? static_cast<size_t>(codeBytes(dims, 8) / 8) : static_cast<size_t>(dims)),
        mGraph(&mSpace, static_cast<size_t>(rows), static_cast<size_t>(settings.trees), size_t{200},
               static_cast<size_t>(settings.seed)) {
    // Rows inserted in order with a seeded level draw: the same graph in any process.
    std::vector<uint8_t> code(kBinary ? static_cast<size_t>(codeBytes(dims, 8)) : 0);
    for (int64_t r = 0; r < rows; ++r) {
      if constexpr (kBinary) {
        packBits(data + r * dims, 1, dims, 8, code.data());
        mGraph.addPoint(code.data(), static_cast<hnswlib::labeltype>(r));
      } else {
        mGraph.addPoint(data + r * dims, static_cast<hnswlib::labeltype>(r));
      }
    }
    mGraph.setEf(static_cast<size_t>(settings.checks));
  }

  Status validateQuery(const float* descriptor, int64_t dims) const override {
    if constexpr (kBinary) return checkZeroOne(descriptor, 1, dims, true);
    return Ok{};
  }

  Status query(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const override {
    try {
      std::vector<uint8_t> code(kBinary ? static_cast<size_t>(codeBytes(mDims, 8)) : 0);
      if constexpr (kBinary) packBits(descriptor, 1, mDims, 8, code.data());
      const void* point = kBinary ? static_cast<const void*>(code.data()) : static_cast<const void*>(descriptor);
      auto found = mGraph.searchKnn(point, static_cast<size_t>(k));  // max-heap: farthest on top
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

  bool searchesSets() const override { return true; }

  // A set of queries (a fragment's candidate frames) in one search: each row descends the upper
  // levels on its own, as a single query would, and the base layer is then searched once from all
  // their entry points (HNSW's best-first search, Malkov & Yashunin 2018, algorithm 2, with several
  // entry points) under the set's distance, the smallest over its rows. Every row's neighbourhood
  // is entered, so no row's nearest is lost to another's basin, and a node is measured once for
  // the set. Row r was inserted r-th, so its internal id is r.
  Status querySet(const float* descriptors, int64_t count, int k, int64_t* ids, float* squaredDistances,
                  int32_t* rows) const override {
    using hnswlib::tableint;
    using Scored = std::pair<float, tableint>;
    try {
      const size_t stride = kBinary ? static_cast<size_t>(codeBytes(mDims, 8)) : static_cast<size_t>(mDims) * sizeof(float);
      std::vector<uint8_t> codes(kBinary ? stride * static_cast<size_t>(count) : 0);
      if constexpr (kBinary) packBits(descriptors, count, mDims, 8, codes.data());
      const auto* base = kBinary ? codes.data() : reinterpret_cast<const unsigned char*>(descriptors);
      const auto rowOf = [&](int64_t q) { return static_cast<const void*>(base + static_cast<size_t>(q) * stride); };
      const hnswlib::DISTFUNC<float> distance = mGraph.fstdistfunc_;
      const void* param = mGraph.dist_func_param_;
      const auto setDistance = [&](tableint node) {
        const char* data = mGraph.getDataByInternalId(node);
        float best = distance(rowOf(0), data, param);
        for (int64_t q = 1; q < count; ++q) best = std::min(best, distance(rowOf(q), data, param));
        return best;
      };
      // The upper levels, row by row (greedy, as hnswlib's searchKnn).
      std::vector<tableint> entries;
      for (int64_t q = 0; q < count; ++q) {
        tableint current = mGraph.enterpoint_node_;
        float best = distance(rowOf(q), mGraph.getDataByInternalId(current), param);
        for (int level = mGraph.maxlevel_; level > 0; --level) {
          for (bool moved = true; moved;) {
            moved = false;
            hnswlib::linklistsizeint* links = mGraph.get_linklist(current, level);
            const tableint* neighbours = reinterpret_cast<const tableint*>(links + 1);
            for (int i = 0, size = mGraph.getListCount(links); i < size; ++i) {
              const float d = distance(rowOf(q), mGraph.getDataByInternalId(neighbours[i]), param);
              if (d < best) best = d, current = neighbours[i], moved = true;
            }
          }
        }
        if (std::find(entries.begin(), entries.end(), current) == entries.end()) entries.push_back(current);
      }
      // The base layer, once for the set: `kept` holds the ef best so far (farthest on top),
      // `frontier` the nodes still to expand (nearest on top).
      hnswlib::VisitedList* visitedList = mGraph.visited_list_pool_->getFreeVisitedList();
      struct Release {
        hnswlib::VisitedListPool* pool;
        hnswlib::VisitedList* list;
        ~Release() { pool->releaseVisitedList(list); }
      } release{mGraph.visited_list_pool_, visitedList};
      const auto tag = visitedList->curV;
      auto* visited = visitedList->mass;
      const size_t ef = std::max(mGraph.ef_, static_cast<size_t>(k));
      std::priority_queue<Scored> kept;
      std::priority_queue<Scored, std::vector<Scored>, std::greater<Scored>> frontier;
      auto offer = [&](tableint node) {
        visited[node] = tag;
        const float d = setDistance(node);
        if (kept.size() < ef || d < kept.top().first) {
          frontier.emplace(d, node);
          kept.emplace(d, node);
          if (kept.size() > ef) kept.pop();
        }
      };
      for (tableint e : entries) offer(e);
      while (!frontier.empty()) {
        const auto [d, node] = frontier.top();
        if (d > kept.top().first) break;
        frontier.pop();
        hnswlib::linklistsizeint* links = mGraph.get_linklist0(node);
        const tableint* neighbours = reinterpret_cast<const tableint*>(links + 1);
        for (int i = 0, size = mGraph.getListCount(links); i < size; ++i) {
          if (visited[neighbours[i]] != tag) offer(neighbours[i]);
        }
      }
      while (kept.size() > static_cast<size_t>(k)) kept.pop();
      if (static_cast<int>(kept.size()) < k)
        return invalidArgument("DescriptorIndex query: HNSW returned " + std::to_string(kept.size()) + " of " +
                               std::to_string(k) + " neighbours");
      for (int i = k - 1; i >= 0; --i) {
        squaredDistances[i] = kept.top().first;
        ids[i] = static_cast<int64_t>(mGraph.getExternalLabel(kept.top().second));
        kept.pop();
      }
      sortByDistanceThenId(k, ids, squaredDistances);
      for (int i = 0; i < k; ++i) {  // the lowest row reaching each result's distance
        const char* data = mGraph.getDataByInternalId(static_cast<tableint>(ids[i]));
        rows[i] = 0;
        for (int64_t q = 0; q < count; ++q) {
          if (distance(rowOf(q), data, param) == squaredDistances[i]) {
            rows[i] = static_cast<int32_t>(q);
            break;
          }
        }
      }
    } catch (const std::exception& e) {
      return invalidArgument(std::string("DescriptorIndex query: HNSW search failed: ") + e.what());
    }
    return Ok{};
  }

  // Level 0 (links, its own copy of the data, labels) plus the upper levels' links.
  int64_t memoryBytes() const override {
    int64_t bytes = static_cast<int64_t>(mGraph.max_elements_ * mGraph.size_data_per_element_);
    for (size_t i = 0; i < mGraph.cur_element_count; ++i) {
      bytes += static_cast<int64_t>(mGraph.size_links_per_element_) * mGraph.element_levels_[i];
    }
    return bytes;
  }

 private:
  int64_t mDims;
  Space mSpace;  // declared before the graph, which keeps a pointer to it
  hnswlib::HierarchicalNSW<float> mGraph;
};

}  // namespace

Result<std::unique_ptr<Backend>> buildHnsw(const float* data, int64_t rows, int64_t dims,
                                           const DescriptorIndexSettings& settings) {
  if (settings.trees < 2 || settings.trees > 1024)
    return invalidArgument("DescriptorIndex: settings.trees (HNSW M) must be in [2, 1024], got " + std::to_string(settings.trees));
  if (settings.checks < 1)
    return invalidArgument("DescriptorIndex: settings.checks (HNSW ef) must be >= 1, got " + std::to_string(settings.checks));
  if (rows > static_cast<int64_t>(std::numeric_limits<uint32_t>::max()))
    return invalidArgument("DescriptorIndex: HNSW needs rows <= UINT32_MAX");
  try {
    if (indexTakesBits(settings.kind)) {
      if (Status st = checkZeroOne(data, rows, dims, false); !st) return st.error();
      return std::unique_ptr<Backend>(std::make_unique<HnswBackend<HammingSpace, true>>(data, rows, dims, settings));
    }
    return std::unique_ptr<Backend>(std::make_unique<HnswBackend<EigenL2Space, false>>(data, rows, dims, settings));
  } catch (const std::exception& e) {
    return invalidArgument(std::string("DescriptorIndex: ") + descriptorIndexKindName(settings.kind) +
                           " build failed: " + e.what());
  }
}

}  // namespace brittle::search
