// IndexBackends.h — the approximate and library backends behind DescriptorIndex (private).
//
// DescriptorIndex validates the data, the settings it shares between backends and every query,
// keeps the row-major float copy of the data and runs brute force itself. Everything else is a
// Backend: FLANN (FlannBackend.cpp), hnswlib (HnswBackend.cpp), the inverted files (IvfBackend.cpp,
// IvfBinaryBackend.cpp) and FAISS (FaissBackend.cpp). A
// backend answers the k nearest rows of one query, nearest first, ties by lower id, with squared L2
// distances, and never runs threads of its own (queries are called from the World's workers).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <algorithm>
#include <array>
#include <atomic>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "brittle/core/Fingerprint.h"
#include "brittle/core/Result.h"
#include "brittle/core/Simd.h"
#include "brittle/database/DescriptorIndex.h"

namespace brittle::search {

/// A query's working memory kept for the next query: a few slots, each taken and returned by one
/// atomic exchange, so that concurrent queries each get their own and a query on a warm index makes
/// no allocation. (A thread_local scratch cost __tls_get_addr in a shared library.) The user resets
/// what a lease holds; its vectors keep their capacity.
template <class T>
class ScratchPool {
 public:
  class Lease {
   public:
    Lease(ScratchPool& pool, T* held) : mPool(pool), mHeld(held) {}
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    ~Lease() { mPool.give(mHeld); }
    T& operator*() const { return *mHeld; }

   private:
    ScratchPool& mPool;
    T* mHeld;
  };

  ScratchPool() = default;
  ScratchPool(const ScratchPool&) = delete;
  ScratchPool& operator=(const ScratchPool&) = delete;
  ~ScratchPool() {
    for (auto& slot : mSlots) delete slot.load(std::memory_order_acquire);
  }
  /// Throws std::bad_alloc when no slot holds one and none can be made.
  Lease lease() {
    for (auto& slot : mSlots) {
      if (T* held = slot.exchange(nullptr, std::memory_order_acquire)) return Lease(*this, held);
    }
    return Lease(*this, new T());
  }

 private:
  void give(T* held) {
    for (auto& slot : mSlots) {
      T* empty = nullptr;
      if (slot.compare_exchange_strong(empty, held, std::memory_order_release, std::memory_order_relaxed)) return;
    }
    delete held;
  }
  std::array<std::atomic<T*>, 4> mSlots{};
};

class Backend {
 public:
  virtual ~Backend() = default;
  /// Checks what the backend needs of one query beyond finite values (binary codes need 0 or 1).
  virtual Status validateQuery(const float* /*descriptor*/, int64_t /*dims*/) const { return Ok{}; }
  /// Whether a query that passes validateQuery() has finite values too (0/1 values do), so that
  /// DescriptorIndex need not check them again.
  virtual bool validatesFiniteValues() const { return false; }
  virtual Status query(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const = 0;
  /// Whether querySet() searches a set of queries in one pass (DescriptorIndex::queryNearestOfSet
  /// merges per-row answers otherwise).
  virtual bool searchesSets() const { return false; }
  /// The k nearest rows to a set of `count` validated queries (distance: the smallest over the
  /// set), with the lowest query row reaching each; ordered as query().
  virtual Status querySet(const float* /*descriptors*/, int64_t /*count*/, int /*k*/, int64_t* /*ids*/,
                          float* /*squaredDistances*/, int32_t* /*rows*/) const {
    return makeError(ErrorCode::InvalidArgument, "DescriptorIndex: this backend does not search sets");
  }
  /// Bytes held beyond DescriptorIndex's own copy of the data.
  virtual int64_t memoryBytes() const = 0;
  /// Adds what the build made (lists, keys, directions, graph links, trees; not the choices of
  /// the CPU's instructions, which change no answer) to a digest, so that two builds can be
  /// compared across processes (DescriptorIndex::digest). Errors: InvalidArgument when a library
  /// cannot write its index out.
  virtual Status addToDigest(Fingerprint& digest) const = 0;
};

/// `data` is DescriptorIndex's copy (rows × dims, finite, validated); it stays at this address for
/// the backend's lifetime. Errors: InvalidArgument for settings the backend cannot take or a
/// failure inside the library (the message says which).
Result<std::unique_ptr<Backend>> buildFlann(const float* data, int64_t rows, int64_t dims,
                                            const DescriptorIndexSettings& settings);
Result<std::unique_ptr<Backend>> buildHnsw(const float* data, int64_t rows, int64_t dims,
                                           const DescriptorIndexSettings& settings);
Result<std::unique_ptr<Backend>> buildIvf(const float* data, int64_t rows, int64_t dims,
                                          const DescriptorIndexSettings& settings);
Result<std::unique_ptr<Backend>> buildIvfBinary(const float* data, int64_t rows, int64_t dims,
                                                const DescriptorIndexSettings& settings);
Result<std::unique_ptr<Backend>> buildFaiss(const float* data, int64_t rows, int64_t dims,
                                            const DescriptorIndexSettings& settings);

/// An inverted file's settings: `trees` lists in [1, min(rows, maxLists)], `checks` probed in
/// [1, trees]; else InvalidArgument naming the kind (`what`: "IVF", "ivf-binary").
Status checkInvertedFileSettings(const DescriptorIndexSettings& settings, int64_t rows, int64_t maxLists, const char* what);

namespace detail {
// The squared distance in eight double lanes, lane l summing the values c ≡ l (mod 8) in order,
// the lanes added in one fixed order: L doubles to a register, 8 / L registers.
template <int L>
[[gnu::always_inline]] inline double squaredL2InLanes(const float* a, const float* b, int64_t dims) {
  using Doubles = VectorOf<double, L>;
  using Floats = VectorOf<float, L>;
  constexpr int kRegisters = 8 / L;
  Doubles sums[kRegisters] = {};
  int64_t c = 0;
  for (; c + 8 <= dims; c += 8) {
    for (int r = 0; r < kRegisters; ++r) {
      Floats x, y;
      loadLanes<L>(a + c + r * L, x);
      loadLanes<L>(b + c + r * L, y);
      const Doubles d = __builtin_convertvector(x, Doubles) - __builtin_convertvector(y, Doubles);
      sums[r] += d * d;
    }
  }
  double lanes[8];
  std::memcpy(lanes, sums, sizeof lanes);
  for (int i = 0; i < 8 && c + i < dims; ++i) {  // c is a multiple of 8: value c + i is lane i's
    const double d = static_cast<double>(a[c + i]) - static_cast<double>(b[c + i]);
    lanes[i] += d * d;
  }
  return ((lanes[0] + lanes[1]) + (lanes[2] + lanes[3])) + ((lanes[4] + lanes[5]) + (lanes[6] + lanes[7]));
}
BRITTLE_TARGET_AVX inline double squaredL2Wide(const float* a, const float* b, int64_t dims) {
  return squaredL2InLanes<4>(a, b, dims);
}
inline double squaredL2Narrow(const float* a, const float* b, int64_t dims) { return squaredL2InLanes<2>(a, b, dims); }
}  // namespace detail

/// The squared L2 distance of two rows of `dims` floats, accumulated in double: brute force's
/// distance, which re-ranking backends reproduce exactly. Eight lanes, not one running sum: a
/// 4096-value row took 5 µs as one chain of dependent additions, which the inverted file's exact
/// step paid per admitted row; the lanes are the same bits with SSE2 and AVX (Simd.h).
inline float exactSquaredL2(const float* a, const float* b, int64_t dims) {
  return static_cast<float>(widestLanes() == Lanes::Wide ? detail::squaredL2Wide(a, b, dims)
                                                         : detail::squaredL2Narrow(a, b, dims));
}

/// The inverted file's float distances (IvfBackend.cpp): out[i] ← the squared distance of `query` to
/// each of `count` consecutive rows of `stride` floats, stride a multiple of 8 (rows padded with
/// zeros). The same bits with either lanes: eight lanes, added in one fixed order.
void ivfSquaredDistances(Lanes lanes, const float* query, const float* rows, int64_t count, int64_t stride, float* out);
/// The inverted file's wide-row kernel (IvfBackend.cpp): out[i] ← Σ_j weights[j]·rows[index[j]·64 + i]
/// for i < 64, each a float sum over j in order: the same bits with either lanes.
void ivfWeightedRowSum(Lanes lanes, const float* rows, const int32_t* index, const float* weights, int64_t count, float* out);
/// The inverted file's choice of lists (IvfBackend.cpp): best ← the `probes` smallest `distances`
/// (of `lists`, each ≥ 0) by (distance, index), in that order, by insertion or by selection.
void ivfNearestLists(const float* distances, int lists, int probes, bool insertion, std::vector<int32_t>& best);
/// The wide rows' lower bounds (IvfBackend.cpp), for the tests: an inverted file of `lists` lists
/// built over `data` (rows of dims > 128 values), and each row's first bound (its key's first
/// values) and second bound (its whole key) on its squared distance to `query`, by row id, the
/// key distances in the given lanes.
Status ivfWideBounds(Lanes lanes, const float* data, int64_t rows, int64_t dims, int lists, const float* query,
                     std::vector<float>& first, std::vector<float>& second);

/// The principal axes of `points` (a column per sample): their mean, and the covariance's
/// eigenvectors as columns, the largest eigenvalue's first. In double, the covariance summed in
/// column order, solved by Eigen's symmetric solver: the same in any process (hnsw-principal's and
/// ivf's keys). Throws std::runtime_error when the solver fails.
struct PrincipalAxes {
  Eigen::VectorXd mean;
  Eigen::MatrixXd axes;
};
PrincipalAxes principalAxes(const Eigen::MatrixXd& points);

/// Orders the k results by (distance, id), whatever order a backend found them in.
void sortByDistanceThenId(int k, int64_t* ids, float* distances);

// Binary codes of 0/1 descriptors (the occupancy voxel kind): one bit per value, least significant
// first, each row padded with zero bits to a whole number of `wordBytes`. Their Hamming distance is
// exactly the squared L2 distance of the 0/1 vectors.
/// Every value 0 or 1, else InvalidArgument naming the first other one (its row, for data).
Status checkZeroOne(const float* values, int64_t rows, int64_t dims, bool isQuery);
int64_t codeBytes(int64_t dims, int64_t wordBytes);

/// How a Hamming distance counts its bits (HnswBackend.cpp): a word at a time (portable C++ or the
/// popcnt instruction), 32 bytes at a time (AVX2 look-ups) or 64 (AVX-512 VPOPCNTDQ). Every form
/// gives the same integer; the graphs use the fastest the CPU runs.
enum class Popcount { Portable, Popcnt, Avx2, Avx512 };
bool cpuRuns(Popcount form);
/// The fastest form this CPU runs; Popcnt at most in a process kept to 128-bit lanes (Simd.h).
Popcount fastestPopcount();
/// The Hamming distance of two codes of `words` 8-byte words (any alignment), as a float (exact).
float hammingDistance(Popcount form, const uint8_t* a, const uint8_t* b, size_t words);
void packBits(const float* values, int64_t rows, int64_t dims, int64_t wordBytes, uint8_t* codes);

/// ivf-binary's key distances (IvfBinaryBackend.cpp): 256-bit keys in blocks of eight, word by word
/// (word w of the block's 8 keys at [32b + 8w, 32b + 8w + 8)). out[8b + l] ← the Hamming distance of
/// `query` (4 words) to key l of block b; least[b] ← the block's smallest. The same integers in
/// every form.
void ivfBinaryKeyDistances(Popcount form, const uint64_t* query, const uint64_t* keys, int64_t blocks, uint32_t* out,
                           uint32_t* least);

/// out ← the bits of `in` (`words` 8-byte words) where `mask` has a 1, in ascending order, packed
/// from bit 0 (out has room for them all; its bits past them are 0). BMI2's pext where it runs
/// fast (not on AMD CPUs before Zen 3, which microcode it), else a loop over the mask's bits: the
/// same bits either way.
void gatherBits(const uint64_t* in, const uint64_t* mask, size_t words, uint64_t* out, size_t outWords);

/// The columns of indexed 0/1 rows that do not hold one value in every row, and codes over them
/// (hnsw-binary, ivf-binary). A column with one value in every indexed row adds the same 0 or 1 to
/// a query's distance from each of them, so it changes no ranking: the codes leave it out, and a
/// query counts it once (`code`'s return), so that distances stay the whole rows' Hamming
/// distances. On 10⁴ occupancy grids (16³) 929 of 4 096 columns vary, on 10⁵ 1 106.
class VaryingColumns {
 public:
  VaryingColumns() = default;
  /// Over `rows` validated 0/1 rows of `dims` values.
  VaryingColumns(const float* data, int64_t rows, int64_t dims);
  const std::vector<int32_t>& columns() const { return mColumns; }
  /// 8-byte words of a code over the varying columns (at least one).
  size_t words() const { return std::max<size_t>(1, (mColumns.size() + 63) / 64); }
  /// 8-byte words of a whole row's code (packBits).
  size_t fullWords() const { return mConstant.size(); }
  /// One row of dims 0/1 values to its code (words() words), through `full` (fullWords() words of
  /// scratch); returns how many left-out columns differ from the indexed rows' value there.
  int code(const float* row, uint64_t* full, uint64_t* code) const;
  int64_t memoryBytes() const { return static_cast<int64_t>(mColumns.size() * 4 + 3 * mConstant.size() * 8); }
  void addToDigest(Fingerprint& digest) const { digest.add(mDims), digest.add(mColumns), digest.add(mConstant), digest.add(mOutside), digest.add(mInside); }

 private:
  int64_t mDims = 0;
  std::vector<int32_t> mColumns;    // ascending
  std::vector<uint64_t> mConstant;  // the first row's full code: the left-out columns' value
  std::vector<uint64_t> mOutside;   // the left-out columns, as a full code's mask
  std::vector<uint64_t> mInside;    // the varying columns, as a full code's mask
};

}  // namespace brittle::search
