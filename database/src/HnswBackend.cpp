// HnswBackend.cpp — hnswlib's hierarchical navigable small-world graph (Debian's libhnswlib-dev),
// over float descriptors (squared L2) or over the binary codes of 0/1 descriptors (Hamming).
#include <cstddef>
#include <cstdint>
#include <algorithm>
#include <array>
#include <tuple>
#include <cmath>
#include <cstring>
#include <vector>
#include <exception>
#include <limits>
#include <memory>
#include <queue>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Core>
#if defined(__x86_64__)
#include <immintrin.h>
#endif
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

// Hamming distance between two codes of `words` 64-bit words, in four forms that give the same
// integer (hammingDistance, IndexBackends.h). hnswlib keeps each code 4-byte aligned only, so every
// form loads unaligned. The widest the CPU runs is chosen once, when the space is made
// (fastestPopcount); the distance is most of a graph walk's time over 4 096-bit grids.
template <bool kPopcnt>
float hammingWords(const void* a, const void* b, const void* param) {
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

#if defined(__x86_64__)
// 32 bytes a step: each byte's count from two 4-bit look-ups (pshufb), summed per 8 bytes by psadbw
// (Mula, Kurz & Lemire 2018). The tail words by the loop above.
__attribute__((target("avx2"))) float hammingAvx2(const void* a, const void* b, const void* param) {
  const size_t words = *static_cast<const size_t*>(param);
  const auto* x = static_cast<const unsigned char*>(a);
  const auto* y = static_cast<const unsigned char*>(b);
  const __m256i table = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4,  //
                                         0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i low = _mm256_set1_epi8(0x0f);
  __m256i sums = _mm256_setzero_si256();
  size_t i = 0;
  for (; i + 4 <= words; i += 4) {
    const __m256i d = _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(x + 8 * i)),
                                       _mm256_loadu_si256(reinterpret_cast<const __m256i*>(y + 8 * i)));
    const __m256i counts = _mm256_add_epi8(_mm256_shuffle_epi8(table, _mm256_and_si256(d, low)),
                                           _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(d, 4), low)));
    sums = _mm256_add_epi64(sums, _mm256_sad_epu8(counts, _mm256_setzero_si256()));
  }
  const uint64_t sum = static_cast<uint64_t>(_mm256_extract_epi64(sums, 0)) + static_cast<uint64_t>(_mm256_extract_epi64(sums, 1)) +
                       static_cast<uint64_t>(_mm256_extract_epi64(sums, 2)) + static_cast<uint64_t>(_mm256_extract_epi64(sums, 3));
  const size_t rest = words - i;
  return static_cast<float>(sum) + hammingWords<false>(x + 8 * i, y + 8 * i, &rest);  // exact: integers below 2^24
}

// 64 bytes a step, a popcount per 64-bit lane (AVX-512 VPOPCNTDQ); the tail words masked in.
__attribute__((target("avx512f,avx512vpopcntdq"))) float hammingAvx512(const void* a, const void* b, const void* param) {
  const size_t words = *static_cast<const size_t*>(param);
  const auto* x = static_cast<const unsigned char*>(a);
  const auto* y = static_cast<const unsigned char*>(b);
  __m512i sums = _mm512_setzero_si512();
  size_t i = 0;
  for (; i + 8 <= words; i += 8) {
    const __m512i d = _mm512_xor_si512(_mm512_loadu_si512(x + 8 * i), _mm512_loadu_si512(y + 8 * i));
    sums = _mm512_add_epi64(sums, _mm512_popcnt_epi64(d));
  }
  if (i < words) {
    const auto tail = static_cast<__mmask8>((1u << (words - i)) - 1u);
    const __m512i d = _mm512_xor_si512(_mm512_maskz_loadu_epi64(tail, x + 8 * i), _mm512_maskz_loadu_epi64(tail, y + 8 * i));
    sums = _mm512_add_epi64(sums, _mm512_popcnt_epi64(d));
  }
  alignas(64) uint64_t lanes[8];  // (GCC 12's _mm512_reduce_add_epi64 warns of an undefined register)
  _mm512_store_si512(lanes, sums);
  uint64_t sum = 0;
  for (uint64_t lane : lanes) sum += lane;
  return static_cast<float>(sum);
}
#endif

hnswlib::DISTFUNC<float> hammingFunction(Popcount form) {
  switch (form) {
#if defined(__x86_64__)
    case Popcount::Avx512: return &hammingAvx512;
    case Popcount::Avx2: return &hammingAvx2;
    case Popcount::Popcnt: return &hammingWords<true>;
#endif
    default: return &hammingWords<false>;
  }
}

}  // namespace

bool cpuRuns(Popcount form) {
#if defined(__x86_64__)
  switch (form) {
    case Popcount::Avx512: return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vpopcntdq");
    case Popcount::Avx2: return __builtin_cpu_supports("avx2");
    case Popcount::Popcnt: return __builtin_cpu_supports("popcnt");
    case Popcount::Portable: return true;
  }
#endif
  return form == Popcount::Portable;
}

Popcount fastestPopcount() {
  static const Popcount form = [] {
    // A process kept to the 128-bit forms (BRITTLE_SIMD=sse2, Simd.h) runs as on a CPU without AVX.
    if (widestLanes() == Lanes::Narrow) return cpuRuns(Popcount::Popcnt) ? Popcount::Popcnt : Popcount::Portable;
    for (Popcount f : {Popcount::Avx512, Popcount::Avx2, Popcount::Popcnt}) {
      if (cpuRuns(f)) return f;
    }
    return Popcount::Portable;
  }();
  return form;
}

float hammingDistance(Popcount form, const uint8_t* a, const uint8_t* b, size_t words) {
  return hammingFunction(form)(a, b, &words);
}

namespace {

class HammingSpace : public hnswlib::SpaceInterface<float> {
 public:
  explicit HammingSpace(size_t words) : mWords(words) {}
  size_t get_data_size() override { return mWords * 8; }
  hnswlib::DISTFUNC<float> get_dist_func() override { return hammingFunction(fastestPopcount()); }
  void* get_dist_func_param() override { return &mWords; }

 private:
  size_t mWords;
};

// A node found for a set of queries: its distance to the set, the node, and the lowest row of the
// set at that distance. Ordered by (distance, node); a node appears once, so the row never decides.
using Scored = std::tuple<float, hnswlib::tableint, int32_t>;

// What every graph's query reports when it found fewer than k neighbours.
Error tooFewNeighbours(size_t found, int k) {
  return makeError(ErrorCode::InvalidArgument, "DescriptorIndex query: HNSW returned " + std::to_string(found) + " of " +
                                                   std::to_string(k) + " neighbours");
}

// hnswlib's graph in memory: every node's data and level-0 links, and its upper-level links.
int64_t graphBytes(const hnswlib::HierarchicalNSW<float>& graph) {
  auto bytes = static_cast<int64_t>(graph.max_elements_ * graph.size_data_per_element_);
  for (size_t i = 0; i < graph.cur_element_count; ++i) {
    bytes += static_cast<int64_t>(graph.size_links_per_element_) * graph.element_levels_[i];
  }
  return bytes;
}

// hnswlib's graph into a digest: its counts and entry point, and every node's label, data and
// links at each of its levels (each list's count and the links it holds: hnswlib mallocs the
// lists, so the slots past a list's count are whatever the heap held).
void addGraphToDigest(const hnswlib::HierarchicalNSW<float>& graph, Fingerprint& digest) {
  const size_t count = graph.cur_element_count;
  digest.add(static_cast<uint64_t>(count), static_cast<int64_t>(graph.maxlevel_), static_cast<int64_t>(graph.enterpoint_node_));
  const auto addLinks = [&](hnswlib::linklistsizeint* list) {  // (getListCount takes a non-const pointer; it only reads)
    const unsigned short links = graph.getListCount(list);
    digest.add(links);
    digest.addBytes(list + 1, sizeof(hnswlib::tableint) * links);
  };
  for (size_t i = 0; i < count; ++i) {
    const auto id = static_cast<hnswlib::tableint>(i);
    digest.add(static_cast<uint64_t>(graph.getExternalLabel(id)), static_cast<int64_t>(graph.element_levels_[i]));
    digest.addBytes(graph.getDataByInternalId(id), graph.data_size_);
    addLinks(graph.get_linklist0(id));
    for (int level = 1; level <= graph.element_levels_[i]; ++level) addLinks(graph.get_linklist(id, level));
  }
}

// The `ef` nearest nodes of `graph` to a set of `count` queries (`stride` bytes apart from `base`),
// nearest first, ties by lower id, each with the lowest row at its distance: a fragment's
// candidate frames in one search. Each row descends
// the upper levels on its own, as a single query would, and level 0 is then searched once from all
// their entry points (HNSW's best-first search, Malkov & Yashunin 2018, algorithm 2, with several
// entry points) under the set's distance, the smallest over its rows. A node is measured once for
// the set; the price is that the rows share one beam (docs/results/fragment-database.md).
// `offsets`, when given: a constant per row added to its distances (what its code leaves out).
std::vector<Scored> walkSet(const hnswlib::HierarchicalNSW<float>& graph, const unsigned char* base, int64_t count,
                            size_t stride, size_t ef, const float* offsets = nullptr) {
  using hnswlib::tableint;
  const auto rowOf = [&](int64_t q) { return static_cast<const void*>(base + static_cast<size_t>(q) * stride); };
  const hnswlib::DISTFUNC<float> distance = graph.fstdistfunc_;
  const void* param = graph.dist_func_param_;
  const auto scored = [&](tableint node) {  // the set's distance, from the lowest row reaching it
    const char* data = graph.getDataByInternalId(node);
    Scored best{distance(rowOf(0), data, param) + (offsets ? offsets[0] : 0.0f), node, 0};
    for (int64_t q = 1; q < count; ++q) {
      const float d = distance(rowOf(q), data, param) + (offsets ? offsets[q] : 0.0f);
      if (d < std::get<0>(best)) best = {d, node, static_cast<int32_t>(q)};
    }
    return best;
  };
  // The upper levels, row by row (greedy, as hnswlib's searchKnn).
  std::vector<tableint> entries;
  for (int64_t q = 0; q < count; ++q) {
    tableint current = graph.enterpoint_node_;
    float best = distance(rowOf(q), graph.getDataByInternalId(current), param);
    for (int level = graph.maxlevel_; level > 0; --level) {
      for (bool moved = true; moved;) {
        moved = false;
        hnswlib::linklistsizeint* links = graph.get_linklist(current, level);
        const auto* neighbours = reinterpret_cast<const tableint*>(links + 1);
        for (int i = 0, size = graph.getListCount(links); i < size; ++i) {
          const float d = distance(rowOf(q), graph.getDataByInternalId(neighbours[i]), param);
          if (d < best) best = d, current = neighbours[i], moved = true;
        }
      }
    }
    if (std::find(entries.begin(), entries.end(), current) == entries.end()) entries.push_back(current);
  }
  // Level 0, once for the set: `kept` holds the ef best so far (farthest on top), `frontier` the
  // nodes still to expand (nearest on top).
  hnswlib::VisitedList* visitedList = graph.visited_list_pool_->getFreeVisitedList();
  struct Release {
    hnswlib::VisitedListPool* pool;
    hnswlib::VisitedList* list;
    ~Release() { pool->releaseVisitedList(list); }
  } release{graph.visited_list_pool_, visitedList};
  const auto tag = visitedList->curV;
  auto* visited = visitedList->mass;
  std::priority_queue<Scored> kept;
  std::priority_queue<Scored, std::vector<Scored>, std::greater<Scored>> frontier;
  auto offer = [&](tableint node) {
    visited[node] = tag;
    const Scored found = scored(node);
    if (kept.size() < ef || std::get<0>(found) < std::get<0>(kept.top())) {
      frontier.push(found);
      kept.push(found);
      if (kept.size() > ef) kept.pop();
    }
  };
  for (tableint e : entries) offer(e);
  std::vector<tableint> fresh;
  fresh.reserve(graph.maxM0_);
  while (!frontier.empty()) {
    const auto [d, node, row] = frontier.top();
    if (d > std::get<0>(kept.top())) break;
    frontier.pop();
    hnswlib::linklistsizeint* links = graph.get_linklist0(node);
    const auto* neighbours = reinterpret_cast<const tableint*>(links + 1);
    // The unvisited neighbours' rows are asked of the cache first, then measured in the same order:
    // their reads overlap instead of each waiting for the one before. At 10⁵ occupancy grids (51 MB
    // of codes) this took a set query from 78 to 50 µs (docs/results/fragment-database.md).
    const int size = graph.getListCount(links);
    fresh.clear();
    for (int i = 0; i < size; ++i) {
      if (visited[neighbours[i]] == tag) continue;
      fresh.push_back(neighbours[i]);
      const char* data = graph.getDataByInternalId(neighbours[i]);
      prefetchBytes(data, data + graph.data_size_);
    }
    for (tableint n : fresh) offer(n);
  }
  std::vector<Scored> out(kept.size());
  for (size_t i = out.size(); i-- > 0; kept.pop()) out[i] = kept.top();
  return out;  // ascending (distance, id): the max-heap popped farthest first, ties higher id first
}

// Float rows are inserted as they are; 0/1 rows as the binary codes (8-byte words) of their
// varying columns only (VaryingColumns): the same graph and answers as over whole rows, with the
// left-out columns' share added back to the distances returned. On 9 000 occupancy grids (16³):
// 120-byte codes instead of 512 (docs/results/fragment-database.md).
template <typename Space, bool kBinary>
class HnswBackend final : public Backend {
 public:
  HnswBackend(const float* data, int64_t rows, int64_t dims, const DescriptorIndexSettings& settings)
      : mDims(dims),
        mVarying(kBinary ? VaryingColumns(data, rows, dims) : VaryingColumns()),
        mWords(mVarying.words()),
        mSpace(kBinary ? mWords : static_cast<size_t>(dims)),
        mGraph(&mSpace, static_cast<size_t>(rows), static_cast<size_t>(settings.trees), size_t{200},
               static_cast<size_t>(settings.seed)) {
    // Rows inserted in order with a seeded level draw: the same graph in any process.
    std::vector<uint64_t> full(kBinary ? mVarying.fullWords() : 0), code(kBinary ? mWords : 0);
    for (int64_t r = 0; r < rows; ++r) {
      if constexpr (kBinary) {
        (void)mVarying.code(data + r * dims, full.data(), code.data());
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
  bool validatesFiniteValues() const override { return kBinary; }

  // One query is a set of one row: walkSet's level-0 search is hnswlib's searchKnn, node for node
  // where no two distances tie (DescriptorIndex.GraphWalkIsHnswlibsSearch; on ties the walk expands
  // the lower id first), with the neighbours' rows prefetched, which hnswlib does only in its SSE
  // build (off here, see above).
  Status query(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const override {
    std::vector<int32_t> rows(static_cast<size_t>(k));
    return querySet(descriptor, 1, k, ids, squaredDistances, rows.data());
  }

  bool searchesSets() const override { return true; }

  // A set of queries (a fragment's candidate frames) in one walk (walkSet); row r was inserted
  // r-th, so its internal id is r.
  Status querySet(const float* descriptors, int64_t count, int k, int64_t* ids, float* squaredDistances,
                  int32_t* rows) const override {
    try {
      const size_t stride = kBinary ? mWords * 8 : static_cast<size_t>(mDims) * sizeof(float);
      std::vector<uint64_t> codes(kBinary ? mWords * static_cast<size_t>(count) : 0);
      std::vector<float> offsets(kBinary ? static_cast<size_t>(count) : 0);
      if constexpr (kBinary) {
        std::vector<uint64_t> full(mVarying.fullWords());
        for (int64_t q = 0; q < count; ++q) {
          offsets[static_cast<size_t>(q)] =
              static_cast<float>(mVarying.code(descriptors + q * mDims, full.data(), codes.data() + static_cast<size_t>(q) * mWords));
        }
      }
      const auto* base = kBinary ? reinterpret_cast<const unsigned char*>(codes.data()) : reinterpret_cast<const unsigned char*>(descriptors);
      const std::vector<Scored> kept = walkSet(mGraph, base, count, stride, std::max(mGraph.ef_, static_cast<size_t>(k)),
                                               kBinary ? offsets.data() : nullptr);
      if (static_cast<int>(kept.size()) < k) return tooFewNeighbours(kept.size(), k);
      for (int i = 0; i < k; ++i) {
        const auto& [distance, node, row] = kept[static_cast<size_t>(i)];
        squaredDistances[i] = distance;
        ids[i] = static_cast<int64_t>(mGraph.getExternalLabel(node));
        rows[i] = row;
      }
    } catch (const std::exception& e) {
      return invalidArgument(std::string("DescriptorIndex query: HNSW search failed: ") + e.what());
    }
    return Ok{};
  }

  // Level 0 (links, its own copy of the data, labels) plus the upper levels' links.
  int64_t memoryBytes() const override { return graphBytes(mGraph) + mVarying.memoryBytes(); }
  Status addToDigest(Fingerprint& digest) const override {
    digest.add(mDims, static_cast<uint64_t>(mWords));
    mVarying.addToDigest(digest);
    addGraphToDigest(mGraph, digest);
    return Ok{};
  }

 private:
  int64_t mDims;
  VaryingColumns mVarying;  // 0/1 rows: the columns in the codes
  size_t mWords;            // 0/1 rows: 8-byte words per code
  Space mSpace;  // declared before the graph, which keeps a pointer to it
  hnswlib::HierarchicalNSW<float> mGraph;
};

// HnswPooled and HnswPrincipal: the graph over a short key per row, with the ef rows whose keys
// are nearest then ranked by their exact squared distance (as brute force computes it; for rows of
// 0/1 values, the Hamming distance of their bit codes, the same number), and the k best returned.
// Both keys start from the grid's block sums (a cubic grid of R³ values summed over 8 × 8 × 8 blocks
// of (R/8)³ cells, 512 values, scaled by 1/√cells):
//   - HnswPooled keys a row by those 512 sums;
//   - HnswPrincipal by their projection on the first kPrincipalDims principal directions of the
//     indexed rows' sums (a PCA of a sample of them, made when the index is built): 64 values, so a
//     step of the walk reads 256 bytes instead of 2 KiB.
// Each key is an orthonormal projection of the row (the blocks' indicators over √cells, then the
// principal directions), so by Cauchy–Schwarz the keys' squared distance is a lower bound of the
// rows' own: a near row has a near key. Blocks of 4³ (64 values) were tried first: on 10⁴
// fragments' grids their recall stopped at 0.70 (occupancy) and 0.96 (clamped distance) at ef 64
// (docs/results/fragment-database.md); the principal key keeps 64 numbers made from all 512. A skip
// of the candidates whose key alone proves them out of the k best was tried with it and dropped:
// on those grids a query measured a median of 32 of its 32 candidates (a mean of 30.9), since 64
// of 512 directions leave the bound loose.
class PooledHnswBackend final : public Backend {
 public:
  static constexpr int kBlocksPerAxis = 8, kBlocks = kBlocksPerAxis * kBlocksPerAxis * kBlocksPerAxis;
  static constexpr int kPrincipalDims = 64;
  static constexpr int64_t kPrincipalSample = 4096;  // rows the PCA is made from, evenly spaced

  PooledHnswBackend(const float* data, int64_t rows, int64_t dims, int64_t side, bool binary, bool principal,
                    const DescriptorIndexSettings& settings)
      : mData(data), mDims(dims), mSide(side), mBinary(binary), mWordsPerCode(static_cast<size_t>(codeBytes(dims, 8) / 8)),
        mKeyDims(principal ? kPrincipalDims : kBlocks), mKeySpace(mKeyDims), mCodeSpace(mWordsPerCode),
        mGraph(&mKeySpace, static_cast<size_t>(rows), static_cast<size_t>(settings.trees), size_t{200},
               static_cast<size_t>(settings.seed)) {
    mHamming = mCodeSpace.get_dist_func();
    if (mBinary) {
      mCodes.resize(static_cast<size_t>(rows) * mWordsPerCode * 8);
      packBits(data, rows, dims, 8, mCodes.data());
    }
    if (principal) principalDirections(rows);
    std::vector<float> key(mKeyDims);
    for (int64_t r = 0; r < rows; ++r) {  // in order, with a seeded level draw: the same graph in any process
      makeKey(data + r * dims, key.data());
      mGraph.addPoint(key.data(), static_cast<hnswlib::labeltype>(r));
    }
    mGraph.setEf(static_cast<size_t>(settings.checks));
  }

  Status validateQuery(const float* descriptor, int64_t dims) const override {
    if (mBinary) return checkZeroOne(descriptor, 1, dims, true);  // ranked by its bit code
    return Ok{};
  }

  Status query(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const override {
    std::vector<int32_t> rows(static_cast<size_t>(k));
    return querySet(descriptor, 1, k, ids, squaredDistances, rows.data());
  }

  bool searchesSets() const override { return true; }

  Status querySet(const float* descriptors, int64_t count, int k, int64_t* ids, float* squaredDistances,
                  int32_t* rows) const override {
    try {
      std::vector<float> keys(static_cast<size_t>(count) * mKeyDims);
      for (int64_t q = 0; q < count; ++q) makeKey(descriptors + q * mDims, keys.data() + q * mKeyDims);
      const std::vector<Scored> candidates =
          walkSet(mGraph, reinterpret_cast<const unsigned char*>(keys.data()), count, mKeyDims * sizeof(float),
                  std::max(mGraph.ef_, static_cast<size_t>(k)));
      if (static_cast<int>(candidates.size()) < k) return tooFewNeighbours(candidates.size(), k);
      rank(descriptors, count, candidates, k, ids, squaredDistances, rows);
    } catch (const std::exception& e) {
      return invalidArgument(std::string("DescriptorIndex query: HNSW search failed: ") + e.what());
    }
    return Ok{};
  }

  int64_t memoryBytes() const override {
    return graphBytes(mGraph) + static_cast<int64_t>(mCodes.size() + (mBasis.size() + mMean.size()) * sizeof(float));
  }
  Status addToDigest(Fingerprint& digest) const override {
    digest.add(mDims, mSide, mBinary, static_cast<uint64_t>(mWordsPerCode), mKeyDims);
    digest.add(mCodes), digest.add(mBasis), digest.add(mMean);
    addGraphToDigest(mGraph, digest);
    return Ok{};
  }

 private:
  // The block sums of one row, each over √cells: a block's cells are b consecutive values of a
  // line, summed line by line into the block's slot (no division per value).
  void pool(const float* row, float* sums) const {
    const int64_t b = mSide / kBlocksPerAxis;
    std::fill(sums, sums + kBlocks, 0.0f);
    for (int64_t z = 0; z < mSide; ++z) {
      for (int64_t y = 0; y < mSide; ++y) {
        const float* line = row + (z * mSide + y) * mSide;
        float* out = sums + ((z / b) * kBlocksPerAxis + y / b) * kBlocksPerAxis;
        for (int64_t xb = 0; xb < kBlocksPerAxis; ++xb, line += b) {
          float sum = 0.0f;
          for (int64_t x = 0; x < b; ++x) sum += line[x];
          out[xb] += sum;
        }
      }
    }
    const float scale = 1.0f / std::sqrt(static_cast<float>(b * b * b));
    for (int i = 0; i < kBlocks; ++i) sums[i] *= scale;
  }

  // A row's key into `key`. The projection adds the directions' columns one block at a time, each
  // key value summed in block order: the same bits wherever the buffers lie, as the graph's build
  // needs, and 64 independent sums that the compiler keeps in registers.
  void makeKey(const float* row, float* key) const {
    if (mBasis.empty()) {
      pool(row, key);
      return;
    }
    std::array<float, kBlocks> sums;
    pool(row, sums.data());
    std::array<float, kPrincipalDims> out{};
    for (int j = 0; j < kBlocks; ++j) {
      const float c = sums[static_cast<size_t>(j)] - mMean[static_cast<size_t>(j)];
      const float* direction = mBasis.data() + static_cast<size_t>(j) * kPrincipalDims;  // column j
      for (int i = 0; i < kPrincipalDims; ++i) out[static_cast<size_t>(i)] += direction[i] * c;
    }
    std::copy(out.begin(), out.end(), key);
  }

  // The first kPrincipalDims eigenvectors of the block sums' covariance over an evenly spaced
  // sample of the rows (all of them up to kPrincipalSample), in double, summed in row order and
  // solved by Eigen's symmetric solver: the same directions in any process.
  void principalDirections(int64_t rows) {
    const int64_t sample = std::min(rows, kPrincipalSample);
    Eigen::MatrixXd sums(kBlocks, sample);
    std::array<float, kBlocks> one;
    for (int64_t i = 0; i < sample; ++i) {
      pool(mData + (i * rows / sample) * mDims, one.data());
      for (int j = 0; j < kBlocks; ++j) sums(j, i) = one[static_cast<size_t>(j)];
    }
    const PrincipalAxes principal = principalAxes(sums);
    // The first kPrincipalDims axes, stored transposed (a column per block).
    mBasis.resize(static_cast<size_t>(kBlocks) * kPrincipalDims);
    for (int i = 0; i < kPrincipalDims; ++i) {
      for (int j = 0; j < kBlocks; ++j) mBasis[static_cast<size_t>(j) * kPrincipalDims + i] = static_cast<float>(principal.axes(j, i));
    }
    const Eigen::VectorXd& mean = principal.mean;
    mMean.resize(kBlocks);
    for (int j = 0; j < kBlocks; ++j) mMean[j] = static_cast<float>(mean[j]);
  }

  // The candidates by their exact distance to the set (the smallest over its rows; the lowest row
  // reaching it), the k best by (distance, id).
  void rank(const float* descriptors, int64_t count, const std::vector<Scored>& candidates, int k, int64_t* ids,
            float* squaredDistances, int32_t* rows) const {
    std::vector<uint8_t> queryCodes(mBinary ? static_cast<size_t>(count) * mWordsPerCode * 8 : 0);
    if (mBinary) packBits(descriptors, count, mDims, 8, queryCodes.data());
    struct Ranked {
      float distance;
      int64_t id;
      int32_t row;
    };
    std::vector<Ranked> ranked;
    ranked.reserve(candidates.size());
    // Float rows: a float pass first (Eigen's SIMD), then the exact distance only for candidates
    // that can still be among the k best. Over n values the float sum of squares is within
    // δ = 1e-3 of the exact one (n·ε ≈ 2.4e-4 for 16³), so if T is the k-th smallest float
    // distance, the exact k-th is at most T(1 + δ), and every member of the exact k best has a
    // float distance of at most T(1 + δ)²: those, and only those, are measured exactly.
    std::vector<float> approx(mBinary ? 0 : candidates.size());
    float admit = std::numeric_limits<float>::infinity();
    if (!mBinary) {
      for (size_t i = 0; i < candidates.size(); ++i) {
        const Eigen::Map<const Eigen::VectorXf> row(mData + static_cast<int64_t>(mGraph.getExternalLabel(std::get<1>(candidates[i]))) * mDims, mDims);
        float best = std::numeric_limits<float>::infinity();
        for (int64_t q = 0; q < count; ++q) {
          best = std::min(best, (Eigen::Map<const Eigen::VectorXf>(descriptors + q * mDims, mDims) - row).squaredNorm());
        }
        approx[i] = best;
      }
      std::vector<float> sorted(approx);
      std::nth_element(sorted.begin(), sorted.begin() + (k - 1), sorted.end());
      constexpr double kDelta = 1e-3;
      admit = static_cast<float>(static_cast<double>(sorted[static_cast<size_t>(k - 1)]) * (1.0 + kDelta) * (1.0 + kDelta)) +
              std::numeric_limits<float>::min();
    }
    for (size_t i = 0; i < candidates.size(); ++i) {
      if (!mBinary && approx[i] > admit) continue;
      const auto id = static_cast<int64_t>(mGraph.getExternalLabel(std::get<1>(candidates[i])));
      Ranked best{std::numeric_limits<float>::infinity(), id, 0};
      for (int64_t q = 0; q < count; ++q) {
        const float d = mBinary ? mHamming(queryCodes.data() + static_cast<size_t>(q) * mWordsPerCode * 8,
                                                              mCodes.data() + static_cast<size_t>(id) * mWordsPerCode * 8,
                                                              &mWordsPerCode)
                                : exactSquaredL2(descriptors + q * mDims, mData + id * mDims, mDims);
        if (d < best.distance) best.distance = d, best.row = static_cast<int32_t>(q);
      }
      ranked.push_back(best);
    }
    std::partial_sort(ranked.begin(), ranked.begin() + k, ranked.end(), [](const Ranked& a, const Ranked& b) {
      return a.distance != b.distance ? a.distance < b.distance : a.id < b.id;
    });
    for (int i = 0; i < k; ++i) {
      ids[i] = ranked[static_cast<size_t>(i)].id;
      squaredDistances[i] = ranked[static_cast<size_t>(i)].distance;
      rows[i] = ranked[static_cast<size_t>(i)].row;
    }
  }

  const float* mData;  // DescriptorIndex's copy
  int64_t mDims, mSide;
  bool mBinary;
  size_t mWordsPerCode;
  int mKeyDims;
  std::vector<uint8_t> mCodes;   // rows of 0/1 values: their bit codes, for the ranking
  std::vector<float> mBasis;     // principal key: kBlocks columns of kPrincipalDims (the directions, transposed)
  std::vector<float> mMean;      // principal key: the sample's mean block sums
  EigenL2Space mKeySpace;        // declared before the graph, which keeps a pointer to it
  HammingSpace mCodeSpace;
  hnswlib::DISTFUNC<float> mHamming;  // mCodeSpace's distance, chosen once
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
    if (settings.kind == DescriptorIndexSettings::Kind::HnswPooled || settings.kind == DescriptorIndexSettings::Kind::HnswPrincipal) {
      const auto side = static_cast<int64_t>(std::llround(std::cbrt(static_cast<double>(dims))));
      if (side * side * side != dims || side % PooledHnswBackend::kBlocksPerAxis != 0)
        return invalidArgument(std::string("DescriptorIndex: ") + descriptorIndexKindName(settings.kind) + " needs a cubic grid whose side is a multiple of 8 (R^3 values), got " +
                               std::to_string(dims) + " values");
      const bool binary = checkZeroOne(data, rows, dims, false).ok();
      const bool principal = settings.kind == DescriptorIndexSettings::Kind::HnswPrincipal;
      return std::unique_ptr<Backend>(std::make_unique<PooledHnswBackend>(data, rows, dims, side, binary, principal, settings));
    }
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
