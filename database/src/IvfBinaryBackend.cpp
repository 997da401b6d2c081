// IvfBinaryBackend.cpp — an inverted file over 0/1 descriptors (the occupancy voxels): lists of
// rows scanned by a short key in wide registers, the rows the key cannot rule out ranked by their
// whole codes.
//
// Why it exists: at 10⁵ occupancy grids the graph over their codes (hnsw-binary) needs ef 48 for
// recall 0.99, 35–45 µs a query. The walk is long, not its steps: the nearest grid has thousands
// close behind it, and each hop waits on memory for a node's links and then its neighbours' codes.
// An inverted file reads a few lists of rows that lie next to each other instead, which the
// hardware prefetcher streams (the moment descriptors' `ivf` answers the same way,
// IvfBackend.cpp).
//
// Codes. A row's code holds its varying columns only (VaryingColumns: 1 106 of 4 096 on 10⁵ grids).
// Its key holds the kKeyBits columns of those whose values are most evenly split between 0 and 1
// over the indexed rows (the fewer of the two counts, largest first; ties by lower column): 256
// bits, one AVX2 register. The key's columns are a subset of the code's, so a key's Hamming distance
// is a lower bound of the code's. The columns left out of the key are those that a few rows set,
// and they add a few bits at most to a near pair's distance.
//
// Build (deterministic: no random draw, no threads, ties by lower index):
//   - Lists by k-majority (Lloyd's k-means under the Hamming distance, a centroid bit the majority
//     of its rows' bits, 0 on a tie), over the codes of up to kMajoritySamplePerList·lists rows spaced
//     evenly, started from evenly spaced ones, for kMajorityIterations rounds; a centroid without rows keeps
//     its place. Every row is then filed under its nearest centroid, in row order.
//   - A list's keys lie in blocks of eight rows, word by word (word w of rows 0–7, then word w + 1),
//     so that one AVX-512 register (two AVX2 ones) holds one word of eight rows, and the popcount of
//     its XOR with the query's word adds to eight distances at once.
// Query: the `checks` lists whose centroids' keys are nearest the query's (ties by lower index) are
// probed, or more, in that order, while they hold fewer than k rows. Every probed row's key distance
// is computed first, list after list. Then the first k rows whose key is no farther than the k-th
// smallest block's least are ranked by their codes, which sets a bound (the k-th best code distance),
// and every other row whose key is within the bound is ranked too, while the bound tightens. A key's
// distance is a lower bound of its code's, so no row left out can be among the k nearest: within the
// probed lists the answer is exact, and the lists probed decide the recall. (Ranking the nearest key
// first ranks 45 codes a query at 10⁵ where ranking list by list ranked 64.) Distances returned
// are whole rows' Hamming distances (the left-out columns' share added), which are the 0/1 vectors'
// squared L2 distances, as brute force's.
//
// The same answer on any CPU: every popcount form (AVX-512 VPOPCNTDQ, AVX2 look-ups, popcnt, portable)
// counts the same integers.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "IndexBackends.h"

namespace brittle::search {
namespace {

constexpr int kKeyWords = 4;  // 256 key bits
constexpr int kKeyBits = 64 * kKeyWords;
constexpr int kBlock = 8;     // rows a block of keys
constexpr int64_t kMajoritySamplePerList = 32;  // as the float lists' k-means (IvfBackend.cpp)
constexpr int kMajorityIterations = 10;
constexpr uint32_t kFar = std::numeric_limits<uint32_t>::max();  // a key distance never admitted

// out[8b + l] ← the key distance of `query` to lane l of block b, for each of `blocks` blocks, and
// least[b] ← the smallest of block b's eight.
void keyDistancesPortable(const uint64_t* query, const uint64_t* keys, int64_t blocks, uint32_t* out, uint32_t* least) {
  for (int64_t b = 0; b < blocks; ++b) {
    const uint64_t* block = keys + b * kKeyWords * kBlock;
    for (int l = 0; l < kBlock; ++l) {
      uint32_t sum = 0;
      for (int w = 0; w < kKeyWords; ++w) sum += static_cast<uint32_t>(__builtin_popcountll(block[w * kBlock + l] ^ query[w]));
      out[b * kBlock + l] = sum;
    }
    least[b] = *std::min_element(out + b * kBlock, out + (b + 1) * kBlock);
  }
}

#if defined(__x86_64__)
__attribute__((target("popcnt"))) void keyDistancesPopcnt(const uint64_t* query, const uint64_t* keys, int64_t blocks,
                                                          uint32_t* out, uint32_t* least) {
  for (int64_t b = 0; b < blocks; ++b) {
    const uint64_t* block = keys + b * kKeyWords * kBlock;
    for (int l = 0; l < kBlock; ++l) {
      uint64_t sum = 0;
      for (int w = 0; w < kKeyWords; ++w) sum += static_cast<uint64_t>(_mm_popcnt_u64(block[w * kBlock + l] ^ query[w]));
      out[b * kBlock + l] = static_cast<uint32_t>(sum);
    }
    least[b] = *std::min_element(out + b * kBlock, out + (b + 1) * kBlock);
  }
}

// Four rows a register: each byte's count from two 4-bit look-ups, summed per 8 bytes (one row's
// word) by psadbw (Mula, Kurz & Lemire 2018).
__attribute__((target("avx2"))) void keyDistancesAvx2(const uint64_t* query, const uint64_t* keys, int64_t blocks,
                                                      uint32_t* out, uint32_t* least) {
  const __m256i table = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4,  //
                                         0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i low = _mm256_set1_epi8(0x0f);
  __m256i q[kKeyWords];
  for (int w = 0; w < kKeyWords; ++w) q[w] = _mm256_set1_epi64x(static_cast<long long>(query[w]));
  for (int64_t b = 0; b < blocks; ++b) {
    const uint64_t* block = keys + b * kKeyWords * kBlock;
    for (int half = 0; half < 2; ++half) {
      __m256i counts = _mm256_setzero_si256();
      for (int w = 0; w < kKeyWords; ++w) {
        const __m256i d = _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(block + w * kBlock + 4 * half)), q[w]);
        counts = _mm256_add_epi8(counts, _mm256_add_epi8(_mm256_shuffle_epi8(table, _mm256_and_si256(d, low)),
                                                         _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(d, 4), low))));
      }
      // A byte holds at most 4 words × 8 bits = 32: no overflow before the sums.
      alignas(32) uint64_t lanes[4];
      _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), _mm256_sad_epu8(counts, _mm256_setzero_si256()));
      for (int l = 0; l < 4; ++l) out[b * kBlock + 4 * half + l] = static_cast<uint32_t>(lanes[l]);
    }
    least[b] = *std::min_element(out + b * kBlock, out + (b + 1) * kBlock);
  }
}

__attribute__((target("avx512f,avx512vpopcntdq"))) void keyDistancesAvx512(const uint64_t* query, const uint64_t* keys,
                                                                           int64_t blocks, uint32_t* out, uint32_t* least) {
  __m512i q[kKeyWords];
  for (int w = 0; w < kKeyWords; ++w) q[w] = _mm512_set1_epi64(static_cast<long long>(query[w]));
  for (int64_t b = 0; b < blocks; ++b) {
    const uint64_t* block = keys + b * kKeyWords * kBlock;
    __m512i sums = _mm512_popcnt_epi64(_mm512_xor_si512(_mm512_loadu_si512(block), q[0]));
    for (int w = 1; w < kKeyWords; ++w)
      sums = _mm512_add_epi64(sums, _mm512_popcnt_epi64(_mm512_xor_si512(_mm512_loadu_si512(block + w * kBlock), q[w])));
    const __m256i narrow = _mm512_mask_cvtepi64_epi32(_mm256_setzero_si256(), 0xff, sums);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + b * kBlock), narrow);
    __m128i m = _mm_min_epu32(_mm256_castsi256_si128(narrow), _mm256_extracti128_si256(narrow, 1));
    m = _mm_min_epu32(m, _mm_shuffle_epi32(m, 0x4e));
    m = _mm_min_epu32(m, _mm_shuffle_epi32(m, 0xb1));
    least[b] = static_cast<uint32_t>(_mm_cvtsi128_si32(m));
  }
}
#endif

// out ← (d[c] << 16 | c) for each list c whose distance d[c] is at most `last`, in order of c;
// returns how many. Without a branch per list: which pass is not predictable.
size_t listsWithinPortable(const uint32_t* d, int begin, int end, uint32_t last, int32_t* out) {
  size_t n = 0;
  for (int c = begin; c < end; ++c) {
    out[n] = static_cast<int32_t>(d[c] << 16 | static_cast<uint32_t>(c));
    n += d[c] <= last ? 1 : 0;
  }
  return n;
}

#if defined(__x86_64__)
__attribute__((target("avx512f"))) size_t listsWithinAvx512(const uint32_t* d, int lists, uint32_t last, int32_t* out) {
  const __m512i bound = _mm512_set1_epi32(static_cast<int>(last)), step = _mm512_set1_epi32(16);
  __m512i index = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  size_t n = 0;
  int c = 0;
  for (; c + 16 <= lists; c += 16, index = _mm512_add_epi32(index, step)) {
    const __m512i v = _mm512_loadu_si512(d + c);
    const __mmask16 within = _mm512_cmple_epu32_mask(v, bound);
    // Compressed in a register and stored whole (a compressing store to memory is microcoded on
    // AMD Zen 4): lanes past the kept ones land below out + c + 16, which is within the lists.
    _mm512_storeu_si512(out + n, _mm512_maskz_compress_epi32(within, _mm512_or_si512(_mm512_maskz_slli_epi32(0xffff, v, 16), index)));
    n += static_cast<size_t>(__builtin_popcount(within));
  }
  return n + listsWithinPortable(d, c, lists, last, out + n);
}
#endif

size_t listsWithin(Popcount form, const uint32_t* d, int lists, uint32_t last, int32_t* out) {
#if defined(__x86_64__)
  if (form == Popcount::Avx512) return listsWithinAvx512(d, lists, last, out);
#endif
  (void)form;
  return listsWithinPortable(d, 0, lists, last, out);
}

using KeyDistances = void (*)(const uint64_t*, const uint64_t*, int64_t, uint32_t*, uint32_t*);

KeyDistances keyDistancesFor(Popcount form) {
  switch (form) {
#if defined(__x86_64__)
    case Popcount::Avx512: return &keyDistancesAvx512;
    case Popcount::Avx2: return &keyDistancesAvx2;
    case Popcount::Popcnt: return &keyDistancesPopcnt;
#endif
    default: return &keyDistancesPortable;
  }
}

int64_t blocksOf(int64_t rows) { return (rows + kBlock - 1) / kBlock; }

class IvfBinaryBackend final : public Backend {
 public:
  IvfBinaryBackend(const float* data, int64_t rows, int64_t dims, int lists, int probes)
      : mVarying(data, rows, dims),
        mWords(mVarying.words()),
        mLists(lists),
        mProbes(probes),
        mForm(fastestPopcount()),
        mKeyDistances(keyDistancesFor(mForm)) {
    std::vector<uint64_t> codes(static_cast<size_t>(rows) * mWords), full(mVarying.fullWords());
    for (int64_t r = 0; r < rows; ++r) (void)mVarying.code(data + r * dims, full.data(), codes.data() + r * mWords);
    chooseKeyColumns(codes, rows);
    const std::vector<uint64_t> centroids = kMajority(codes, rows);
    fileRows(codes, rows, centroids);
  }

  Status validateQuery(const float* descriptor, int64_t dims) const override { return checkZeroOne(descriptor, 1, dims, true); }
  bool validatesFiniteValues() const override { return true; }

  Status query(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const override {
    try {
      const auto lease = mScratch.lease();
      Scratch& x = *lease;
      x.probed.clear();
      x.best.clear();
      x.full.resize(mVarying.fullWords());
      x.code.resize(mWords);
      const int outside = mVarying.code(descriptor, x.full.data(), x.code.data());
      std::array<uint64_t, kKeyWords> key{};
      keyOf(x.code.data(), key.data());
      x.distances.resize(static_cast<size_t>(blocksOf(mLists) * kBlock));
      x.least.resize(static_cast<size_t>(blocksOf(mLists)));
      mKeyDistances(key.data(), mCentroidKeys.data(), blocksOf(mLists), x.distances.data(), x.least.data());
      orderLists(x, mProbes);

      // The lists probed: the first mProbes, or more while they hold fewer than k rows; each one's
      // slots in the scratch from `at` on.
      int64_t rows = 0, slots = 0;
      for (int i = 0; i < mLists && (i < mProbes || rows < k); ++i) {
        if (i == static_cast<int>(x.order.size())) orderLists(x, mLists);
        const auto c = static_cast<size_t>(x.order[static_cast<size_t>(i)]);
        x.probed.push_back({c, slots});
        rows += mListRows[c];
        slots += blocksOf(mListRows[c]) * kBlock;
      }

      // Pass 1: every probed row's key distance, list after list, the next list's keys asked of
      // the cache while one is scanned. A list's padding lanes get the largest distance, so that
      // they are never admitted, and a block's least is its rows' alone.
      x.rowKeys.resize(static_cast<size_t>(slots));
      x.least.resize(static_cast<size_t>(slots / kBlock));
      x.blockSlot.resize(x.least.size());
      const auto keysOf = [&](size_t list) { return mKeys.data() + mListStart[list] * kKeyWords; };
      const auto prefetchKeys = [&](size_t list) {
        prefetchBytes(keysOf(list), keysOf(list) + blocksOf(mListRows[list]) * kBlock * kKeyWords);
      };
      prefetchKeys(x.probed.front().list);
      for (size_t p = 0; p < x.probed.size(); ++p) {
        if (p + 1 < x.probed.size()) prefetchKeys(x.probed[p + 1].list);
        const Probed& l = x.probed[p];
        const int64_t count = mListRows[l.list], blocks = blocksOf(count);
        uint32_t* rowKeys = x.rowKeys.data() + l.at;
        mKeyDistances(key.data(), keysOf(l.list), blocks, rowKeys, x.least.data() + l.at / kBlock);
        for (int64_t b = 0; b < blocks; ++b) x.blockSlot[static_cast<size_t>(l.at / kBlock + b)] = mListStart[l.list] + b * kBlock;
        if (count % kBlock != 0) {
          std::fill(rowKeys + count, rowKeys + blocks * kBlock, kFar);
          x.least[static_cast<size_t>(l.at / kBlock + blocks - 1)] = *std::min_element(rowKeys + (blocks - 1) * kBlock, rowKeys + count);
        }
      }

      // Pass 2: the first k rows (in slot order) whose key distance is at most the k-th smallest
      // block's least, which are at least k rows. None is measured in vain: the k nearest rows'
      // keys are no farther than the k-th best code distance, so neither is that least.
      uint32_t first = kFar;
      if (k == 1) {
        first = *std::min_element(x.least.begin(), x.least.end());
      } else if (static_cast<size_t>(k) <= x.least.size()) {
        x.smallest = x.least;
        std::nth_element(x.smallest.begin(), x.smallest.begin() + (k - 1), x.smallest.end());
        first = x.smallest[static_cast<size_t>(k - 1)];
      }
      uint32_t bound = kFar;  // the k-th best distance, once k are found
      admit(x, first, k);
      measure(x, k, bound);
      // Pass 3: the rows the bound admits that pass 2 did not measure (their keys are now kFar),
      // while it tightens.
      admit(x, bound, std::numeric_limits<int64_t>::max());
      measure(x, k, bound);
      for (int i = 0; i < k; ++i) {
        ids[i] = x.best[static_cast<size_t>(i)].second;
        squaredDistances[i] = static_cast<float>(x.best[static_cast<size_t>(i)].first + static_cast<uint32_t>(outside));  // exact: < 2^24
      }
    } catch (const std::exception& e) {
      return invalidArgument(std::string("DescriptorIndex query: ivf-binary search failed: ") + e.what());
    }
    return Ok{};
  }

  // (mForm and mKeyDistances, the CPU's instructions, change no answer: left out.)
  Status addToDigest(Fingerprint& digest) const override {
    mVarying.addToDigest(digest);
    digest.add(static_cast<uint64_t>(mWords), mLists, mProbes);
    digest.add(mKeyMask), digest.add(mCentroidKeys), digest.add(mListStart), digest.add(mListRows), digest.add(mKeys);
    digest.add(mCodes), digest.add(mIds);
    return Ok{};
  }

  int64_t memoryBytes() const override {
    return static_cast<int64_t>((mCodes.size() + mKeys.size() + mCentroidKeys.size()) * 8 + mIds.size() * 8 +
                                (mListStart.size() + mListRows.size() + mKeyMask.size()) * 8) +
           mVarying.memoryBytes();
  }

 private:
  struct Probed {
    size_t list;
    int64_t at;  // its first slot in the scratch's rowKeys (a multiple of kBlock)
  };
  struct Scratch {
    std::vector<uint64_t> full, code;
    std::vector<uint32_t> distances, rowKeys, least;  // least: of each probed block (of the centroids' at first)
    std::vector<uint32_t> smallest;                   // k > 1: the blocks' least, partly sorted
    std::vector<int32_t> order, gathered;  // lists in probing order; those within the threshold
    std::vector<Probed> probed;
    std::vector<int64_t> blockSlot;  // each probed block's first slot in the index
    std::vector<int32_t> blocks;     // probed blocks that a bound admits
    std::vector<std::pair<uint32_t, int64_t>> best;  // the k best (distance, id) so far, ascending
    std::vector<std::pair<int64_t, int64_t>> admitted;  // (scratch slot, index slot) of rows to measure
  };

  // x.admitted ← the probed rows whose key distance is at most `high`, in slot order, at most
  // `most` of them, their codes asked of the cache before any is compared. For many, blocks are
  // picked without branches: which pass is not predictable. (kFar is never admitted: padding, or a
  // row measured already.)
  void admit(Scratch& x, uint32_t high, int64_t most) const {
    high = std::min(high, kFar - 1);
    x.admitted.clear();
    const auto admitBlock = [&](size_t b) {
      for (size_t j = b * kBlock; j < (b + 1) * kBlock && static_cast<int64_t>(x.admitted.size()) < most; ++j) {
        if (x.rowKeys[j] > high) continue;
        const int64_t slot = x.blockSlot[b] + static_cast<int64_t>(j - b * kBlock);
        x.admitted.emplace_back(static_cast<int64_t>(j), slot);
        prefetchBytes(mCodes.data() + slot * mWords, mCodes.data() + (slot + 1) * mWords);
      }
    };
    if (most < kBlock) {  // a few rows (pass 2): blocks in order until they are found
      for (size_t b = 0; b < x.least.size() && static_cast<int64_t>(x.admitted.size()) < most; ++b) {
        if (x.least[b] <= high) admitBlock(b);
      }
      return;
    }
    x.blocks.resize(x.least.size());
    size_t n = 0;
    for (size_t b = 0; b < x.least.size(); ++b) {
      x.blocks[n] = static_cast<int32_t>(b);
      n += x.least[b] <= high ? 1 : 0;
    }
    for (size_t i = 0; i < n && static_cast<int64_t>(x.admitted.size()) < most; ++i) admitBlock(static_cast<size_t>(x.blocks[i]));
  }

  // The admitted rows whose key is still within the bound ranked by their codes into x.best, each
  // key then set to kFar (a row is measured once); the bound becomes the k-th best distance once k
  // are found.
  void measure(Scratch& x, int k, uint32_t& bound) const {
    for (const auto& [at, slot] : x.admitted) {
      const uint32_t key = x.rowKeys[static_cast<size_t>(at)];
      x.rowKeys[static_cast<size_t>(at)] = kFar;
      if (key > bound) continue;  // the bound has tightened since
      const auto d = static_cast<uint32_t>(hammingDistance(mForm, reinterpret_cast<const uint8_t*>(x.code.data()),
                                                           reinterpret_cast<const uint8_t*>(mCodes.data() + slot * mWords), mWords));
      if (d > bound) continue;  // before its id is read (a cold load)
      const std::pair<uint32_t, int64_t> found{d, mIds[static_cast<size_t>(slot)]};
      if (static_cast<int>(x.best.size()) == k) {
        if (!(found < x.best.back())) continue;
        x.best.pop_back();
      }
      x.best.push_back(found);
      for (size_t b = x.best.size() - 1; b > 0 && found < x.best[b - 1]; --b) std::swap(x.best[b], x.best[b - 1]);
      if (static_cast<int>(x.best.size()) == k) bound = x.best.back().first;
    }
  }

  // x.order ← at least the `wanted` lists nearest the query (x.distances: their centroids' key
  // distances), ordered by (distance, index). The lists up to the wanted one's distance are
  // gathered in index order (a count of each distance finds it), then placed by the same counts:
  // ~wanted lists moved instead of all of them sorted.
  void orderLists(Scratch& x, int wanted) const {
    // Four tables, so that runs of one distance do not wait on each other's increments (counts
    // below 2^16: lists are).
    std::array<std::array<uint16_t, kKeyBits + 1>, 4> count{};
    const uint32_t* d = x.distances.data();
    int c = 0;
    for (; c + 4 <= mLists; c += 4) {
      ++count[0][d[c]], ++count[1][d[c + 1]], ++count[2][d[c + 2]], ++count[3][d[c + 3]];
    }
    for (; c < mLists; ++c) ++count[0][d[c]];
    uint32_t last = 0;
    for (int32_t sum = 0; last < kKeyBits; ++last) {
      sum += count[0][last] + count[1][last] + count[2][last] + count[3][last];
      if (sum >= wanted) break;
    }
    // The lists within `last`, in index order, then placed by distance from the counts (a
    // counting sort: stable, so (distance, index) order).
    x.gathered.resize(static_cast<size_t>(mLists));
    const size_t n = listsWithin(mForm, d, mLists, last, x.gathered.data());
    std::array<int32_t, kKeyBits + 1> at{};
    for (uint32_t v = 1, sum = 0; v <= last; ++v) {
      sum += count[0][v - 1] + count[1][v - 1] + count[2][v - 1] + count[3][v - 1];
      at[v] = static_cast<int32_t>(sum);
    }
    x.order.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const auto g = static_cast<uint32_t>(x.gathered[i]);
      x.order[static_cast<size_t>(at[g >> 16]++)] = static_cast<int32_t>(g & 0xffff);
    }
  }

  // The kKeyBits code positions whose column is most evenly split over the rows.
  void chooseKeyColumns(const std::vector<uint64_t>& codes, int64_t rows) {
    const size_t bits = mVarying.columns().size();
    std::vector<int64_t> ones(bits, 0);
    for (int64_t r = 0; r < rows; ++r) {
      const uint64_t* code = codes.data() + r * mWords;
      for (size_t w = 0; w < mWords; ++w) {
        for (uint64_t word = code[w]; word != 0; word &= word - 1) ++ones[w * 64 + static_cast<size_t>(__builtin_ctzll(word))];
      }
    }
    std::vector<int32_t> order(bits);
    for (size_t b = 0; b < bits; ++b) order[b] = static_cast<int32_t>(b);
    const auto minority = [&](int32_t b) { return std::min(ones[static_cast<size_t>(b)], rows - ones[static_cast<size_t>(b)]); };
    std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return minority(a) > minority(b); });
    order.resize(std::min<size_t>(bits, kKeyBits));
    mKeyMask.assign(mWords, 0);
    for (int32_t b : order) mKeyMask[static_cast<size_t>(b) / 64] |= uint64_t{1} << (b % 64);
  }

  // The key: the code's bits at the key's positions, in ascending order.
  void keyOf(const uint64_t* code, uint64_t* key) const { gatherBits(code, mKeyMask.data(), mWords, key, kKeyWords); }

  // Key words into a block layout: row `slot` of `keys` (blocks of kBlock rows, word by word).
  static void storeKey(const uint64_t* key, int64_t slot, std::vector<uint64_t>& keys) {
    const int64_t block = slot / kBlock, lane = slot % kBlock;
    for (int w = 0; w < kKeyWords; ++w) keys[static_cast<size_t>((block * kKeyWords + w) * kBlock + lane)] = key[w];
  }

  // The nearest of `count` codes (ties by lower index) to `code`.
  int nearest(const uint64_t* code, const std::vector<uint64_t>& centroids) const {
    int best = 0;
    float bestDistance = std::numeric_limits<float>::infinity();
    for (int c = 0; c < mLists; ++c) {
      const float d = hammingDistance(mForm, reinterpret_cast<const uint8_t*>(code),
                                      reinterpret_cast<const uint8_t*>(centroids.data() + static_cast<size_t>(c) * mWords), mWords);
      if (d < bestDistance) bestDistance = d, best = c;
    }
    return best;
  }

  std::vector<uint64_t> kMajority(const std::vector<uint64_t>& codes, int64_t rows) const {
    const int64_t samples = std::min<int64_t>(rows, kMajoritySamplePerList * mLists);
    std::vector<int64_t> sample(static_cast<size_t>(samples));
    for (int64_t i = 0; i < samples; ++i) sample[static_cast<size_t>(i)] = i * rows / samples;
    std::vector<uint64_t> centroids(static_cast<size_t>(mLists) * mWords);
    for (int c = 0; c < mLists; ++c) {
      const int64_t r = sample[static_cast<size_t>(static_cast<int64_t>(c) * samples / mLists)];
      std::copy_n(codes.data() + r * mWords, mWords, centroids.data() + static_cast<size_t>(c) * mWords);
    }
    const size_t bits = mWords * 64;
    std::vector<int32_t> counts(static_cast<size_t>(mLists) * bits), sizes(static_cast<size_t>(mLists));
    for (int iteration = 0; iteration < kMajorityIterations; ++iteration) {
      std::fill(counts.begin(), counts.end(), 0);
      std::fill(sizes.begin(), sizes.end(), 0);
      for (int64_t r : sample) {
        const uint64_t* code = codes.data() + r * mWords;
        const auto c = static_cast<size_t>(nearest(code, centroids));
        ++sizes[c];
        for (size_t w = 0; w < mWords; ++w) {
          for (uint64_t word = code[w]; word != 0; word &= word - 1) ++counts[c * bits + w * 64 + static_cast<size_t>(__builtin_ctzll(word))];
        }
      }
      for (size_t c = 0; c < static_cast<size_t>(mLists); ++c) {
        if (sizes[c] == 0) continue;  // keeps its place
        uint64_t* centroid = centroids.data() + c * mWords;
        std::fill_n(centroid, mWords, uint64_t{0});
        for (size_t b = 0; b < bits; ++b) {
          if (2 * counts[c * bits + b] > sizes[c]) centroid[b / 64] |= uint64_t{1} << (b % 64);
        }
      }
    }
    return centroids;
  }

  void fileRows(const std::vector<uint64_t>& codes, int64_t rows, const std::vector<uint64_t>& centroids) {
    std::vector<int32_t> list(static_cast<size_t>(rows));
    mListRows.assign(static_cast<size_t>(mLists), 0);
    for (int64_t r = 0; r < rows; ++r) {
      list[static_cast<size_t>(r)] = nearest(codes.data() + r * mWords, centroids);
      ++mListRows[static_cast<size_t>(list[static_cast<size_t>(r)])];
    }
    // Each list starts on a block; its rows in row order.
    mListStart.assign(static_cast<size_t>(mLists), 0);
    int64_t slots = 0;
    for (size_t c = 0; c < mListRows.size(); ++c) {
      mListStart[c] = slots;
      slots += blocksOf(mListRows[c]) * kBlock;
    }
    mKeys.assign(static_cast<size_t>(slots * kKeyWords), 0);
    mCodes.assign(static_cast<size_t>(slots) * mWords, 0);
    mIds.assign(static_cast<size_t>(slots), -1);
    std::vector<int64_t> next = mListStart;
    std::array<uint64_t, kKeyWords> key{};
    for (int64_t r = 0; r < rows; ++r) {
      const int64_t slot = next[static_cast<size_t>(list[static_cast<size_t>(r)])]++;
      keyOf(codes.data() + r * mWords, key.data());
      storeKey(key.data(), slot, mKeys);
      std::copy_n(codes.data() + r * mWords, mWords, mCodes.data() + slot * mWords);
      mIds[static_cast<size_t>(slot)] = r;
    }
    mCentroidKeys.assign(static_cast<size_t>(blocksOf(mLists) * kBlock * kKeyWords), 0);
    for (int c = 0; c < mLists; ++c) {
      keyOf(centroids.data() + static_cast<size_t>(c) * mWords, key.data());
      storeKey(key.data(), c, mCentroidKeys);
    }
  }

  VaryingColumns mVarying;
  size_t mWords;  // 8-byte words per code
  int mLists, mProbes;
  Popcount mForm;
  KeyDistances mKeyDistances;
  std::vector<uint64_t> mKeyMask;       // the key's positions in a code
  std::vector<uint64_t> mCentroidKeys;  // the lists' centroids' keys, in blocks
  std::vector<int64_t> mListStart;      // each list's first slot (a multiple of kBlock)
  std::vector<int64_t> mListRows;
  std::vector<uint64_t> mKeys;   // every slot's key, in blocks
  std::vector<uint64_t> mCodes;  // every slot's code
  std::vector<int64_t> mIds;     // every slot's row (-1: padding)
  mutable ScratchPool<Scratch> mScratch;
};

}  // namespace

void ivfBinaryKeyDistances(Popcount form, const uint64_t* query, const uint64_t* keys, int64_t blocks, uint32_t* out,
                           uint32_t* least) {
  keyDistancesFor(form)(query, keys, blocks, out, least);
}

Result<std::unique_ptr<Backend>> buildIvfBinary(const float* data, int64_t rows, int64_t dims,
                                                const DescriptorIndexSettings& settings) {
  if (Status st = checkZeroOne(data, rows, dims, false); !st) return st.error();
  // Lists below 2^16: a query orders them by (distance << 16 | list) (orderLists).
  if (Status st = checkInvertedFileSettings(settings, rows, 65535, "ivf-binary"); !st) return st.error();
  try {
    return std::unique_ptr<Backend>(std::make_unique<IvfBinaryBackend>(data, rows, dims, settings.trees, settings.checks));
  } catch (const std::exception& e) {
    return invalidArgument(std::string("DescriptorIndex: ivf-binary build failed: ") + e.what());
  }
}

}  // namespace brittle::search
