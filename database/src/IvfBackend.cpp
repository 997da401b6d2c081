// IvfBackend.cpp — an inverted file over float descriptors: k-means lists scanned in registers,
// the nearest candidates ranked exactly.
//
// Why it exists: at 10⁵ moment descriptors (28 floats) a graph query is bound by memory latency.
// Each hop of hnswlib's walk reads a node's links and then its row, about 50 ns a node, and a
// query visits hundreds of them. An inverted file instead reads a few lists of rows that lie next to
// each other, which the hardware prefetcher streams, and compares them in SIMD registers.
//
// Keys. A row of more than kKeyDims values (up to kMaxProjectedDims: the moment descriptors) is
// filed by its key, its coordinates along the first kKeyDims principal directions of the centred
// data (a PCA of up to kPrincipalSample evenly spaced rows, in double), plus two numbers: the norm
// of what the key leaves out (its residual r) and the centred row's norm. The moment descriptors
// keep 99.99 % of their variance in 16 directions, so a list holds half the bytes. Other rows are
// filed whole (their key is the row, r = 0).
//
// Build (deterministic: no random draw, every sum in a fixed order):
//   - Lloyd's k-means over the keys with `trees` centroids, on up to kSamplePerList·trees rows
//     spaced evenly through the data, started from evenly spaced sample rows, for kIterations
//     rounds. A row goes to its nearest centroid, ties to the lower index. A centroid becomes its
//     rows' mean, summed in double in row order; a centroid without rows keeps its place.
//   - Every row's key is then filed under its nearest centroid, padded with zeros to a multiple of
//     8 floats, so that one AVX register (two SSE2 ones) takes 8 values at a time.
// Query: the `checks` lists with the nearest centroids (ties by lower index) are scanned, or more
// lists, in centroid order, when those hold fewer than k rows. A row's distance is its key
// distance d̂ plus its residual part, which lies between (r_q − r_x)² and (r_q + r_x)². With the
// float sums' rounding (δ) and the keys' (η) added, that gives each row a lower and an upper bound.
// Rows whose lower bound is within the k-th smallest upper bound, and only those, get brute
// force's own distance (exactSquaredL2), and the k best are returned by (distance, id). The
// bounds are made in one pass, four rows to a register, beside each list's smallest upper bound,
// so that most lists and rows cost one compare in the k-th bound's pass and a quarter of one in
// the admission's. So within the probed lists the answer is exact; the lists probed decide the
// recall.
//
// Same bits with SSE2 and AVX: both forms keep eight float lanes, lane l summing (a − b)² over the
// values l, l + 8, ..., and add the lanes in one fixed order at the end (Simd.h). So the probed
// lists, and so the answer, do not depend on the CPU.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "IndexBackends.h"
#include "brittle/core/Simd.h"

namespace brittle::search {
namespace {

constexpr int kLanes = 8;
constexpr int64_t kSamplePerList = 32;  // k-means rows per centroid (FAISS trains on up to 256)
constexpr int kIterations = 12;
// Rows wider than kKeyDims values are compared by their first kKeyDims principal components and the
// norm of the rest, up to kMaxProjectedDims values (the moment descriptors); wider rows (the voxel
// grids, whose covariance would be 4096²) are compared whole.
constexpr int64_t kKeyDims = 16;
constexpr int64_t kMaxProjectedDims = 128;
constexpr int64_t kPrincipalSample = 8192;  // rows the principal directions are made from, evenly spaced

int64_t paddedDims(int64_t dims) { return (dims + kLanes - 1) / kLanes * kLanes; }

using V4 = VectorOf<float, 4>;

// The squared distances of four rows from their eight lanes, each row's four pair sums in `s`
// (lane l + lane l + 4): the rows' ((s0 + s1) + (s2 + s3)), the four at once after a transpose.
[[gnu::always_inline]] inline V4 addLanes(V4 s0, V4 s1, V4 s2, V4 s3) {
  const V4 t0 = __builtin_shufflevector(s0, s1, 0, 4, 1, 5), t1 = __builtin_shufflevector(s2, s3, 0, 4, 1, 5);
  const V4 t2 = __builtin_shufflevector(s0, s1, 2, 6, 3, 7), t3 = __builtin_shufflevector(s2, s3, 2, 6, 3, 7);
  const V4 c0 = __builtin_shufflevector(t0, t1, 0, 1, 4, 5), c1 = __builtin_shufflevector(t0, t1, 2, 3, 6, 7);
  const V4 c2 = __builtin_shufflevector(t2, t3, 0, 1, 4, 5), c3 = __builtin_shufflevector(t2, t3, 2, 3, 6, 7);
  return (c0 + c1) + (c2 + c3);
}

// out[i] ← the squared distance of `query` to each of `count` consecutive padded rows (`stride`
// floats each), four rows at a time. Lane l of a row sums (a − b)² over the values l, l + 8, ...;
// each form below keeps those eight lanes, in two SSE2 registers or one AVX register.
template <class Row>
[[gnu::always_inline]] inline void distancesBy4(const float* query, const float* rows, int64_t count, int64_t stride,
                                                 float* out, Row row) {
  const V4 zero{};
  int64_t i = 0;
  for (; i + 4 <= count; i += 4, rows += 4 * stride) {
    const V4 d = addLanes(row(query, rows, stride), row(query, rows + stride, stride), row(query, rows + 2 * stride, stride),
                          row(query, rows + 3 * stride, stride));
    std::memcpy(out + i, &d, sizeof d);
  }
  for (; i < count; ++i, rows += stride) {  // the last rows, one at a time, with the same sums
    const V4 d = addLanes(row(query, rows, stride), zero, zero, zero);
    out[i] = d[0];
  }
}

// One row's pair sums (lane l + lane l + 4) with SSE2.
[[gnu::always_inline]] inline V4 pairSumsNarrow(const float* query, const float* row, int64_t stride) {
  V4 lo{}, hi{};
  for (int64_t c = 0; c < stride; c += kLanes) {
    V4 a0, a1, b0, b1;
    loadLanes<4>(query + c, a0);
    loadLanes<4>(query + c + 4, a1);
    loadLanes<4>(row + c, b0);
    loadLanes<4>(row + c + 4, b1);
    const V4 d0 = a0 - b0, d1 = a1 - b1;
    lo += d0 * d0;
    hi += d1 * d1;
  }
  return lo + hi;
}

void distancesNarrow(const float* query, const float* rows, int64_t count, int64_t stride, float* out) {
  if (stride == 2 * kLanes) {  // the keys of moment rows (and rows of 9 to 16 values): the loop unrolled
    distancesBy4(query, rows, count, stride, out, [](const float* q, const float* row, int64_t) {
      return pairSumsNarrow(q, row, 2 * kLanes);
    });
  } else if (stride == 4 * kLanes) {  // rows of 25 to 32 values filed whole
    distancesBy4(query, rows, count, stride, out, [](const float* q, const float* row, int64_t) {
      return pairSumsNarrow(q, row, 4 * kLanes);
    });
  } else {
    distancesBy4(query, rows, count, stride, out, pairSumsNarrow);
  }
}

// The same sums with the eight lanes in one AVX register.
BRITTLE_TARGET_AVX void distancesWide(const float* query, const float* rows, int64_t count, int64_t stride, float* out) {
  using V8 = VectorOf<float, 8>;
  const auto pairSums = [](const float* q, const float* row, int64_t n) BRITTLE_TARGET_AVX {
    V8 acc{};
    for (int64_t c = 0; c < n; c += kLanes) {
      V8 a, b;
      loadLanes<8>(q + c, a);
      loadLanes<8>(row + c, b);
      const V8 d = a - b;
      acc += d * d;
    }
    return V4(__builtin_shufflevector(acc, acc, 0, 1, 2, 3) + __builtin_shufflevector(acc, acc, 4, 5, 6, 7));
  };
  if (stride == 2 * kLanes) {  // the same unrolled loops as distancesNarrow's
    distancesBy4(query, rows, count, stride, out,
                 [&](const float* q, const float* row, int64_t) BRITTLE_TARGET_AVX { return pairSums(q, row, 2 * kLanes); });
  } else if (stride == 4 * kLanes) {
    distancesBy4(query, rows, count, stride, out,
                 [&](const float* q, const float* row, int64_t) BRITTLE_TARGET_AVX { return pairSums(q, row, 4 * kLanes); });
  } else {
    distancesBy4(query, rows, count, stride, out, pairSums);
  }
}

void distances(const float* query, const float* rows, int64_t count, int64_t stride, float* out) {
  ivfSquaredDistances(widestLanes(), query, rows, count, stride, out);
}

// One row copied into `padded` (stride floats, zeros after dims).
void pad(const float* row, int64_t dims, int64_t stride, float* padded) {
  std::copy(row, row + dims, padded);
  std::fill(padded + dims, padded + stride, 0.0f);
}

// The index of the smallest value, the lower index on ties.
int64_t nearest(const float* d, int64_t count) {
  int64_t best = 0;
  for (int64_t i = 1; i < count; ++i) {
    if (d[i] < d[best]) best = i;
  }
  return best;
}

// Each scanned row's bounds on its squared distance, from its key distance d̂ (in `lower` on entry):
// d̂ plus its residual part, which lies between (r_q − r_x)² and (r_q + r_x)², widened by a
// relative `delta` for the float sums and by eta = etaScale(‖q‖ + ‖x‖)² for the keys' rounding.
// Four rows to a register, each lane doing the scalar tail's operations, so every row's bounds
// are the same bits either way. Returns the smallest upper bound (+inf for none, NaNs left out).
struct KeyRest {
  float residual = 0.0f;  // the norm of what the key leaves out
  float norm = 0.0f;      // the centred row's norm
};
float bounds(KeyRest q, const float* residuals, const float* norms, int64_t count, float delta, float etaScale,
             float* lower, float* upper) {
  // One formula for a float and for four in a register (a scalar operand is broadcast).
  const auto both = [&](auto d, auto xr, auto xn, auto& low, auto& up) {
    const auto sum = q.residual + xr, gap = q.residual - xr, wholes = q.norm + xn;
    const auto eta = etaScale * wholes * wholes;
    up = (d + sum * sum) * (1.0f + delta) + eta;
    low = (d + gap * gap) * (1.0f - delta) - eta;
  };
  constexpr float kNone = std::numeric_limits<float>::infinity();
  V4 least{kNone, kNone, kNone, kNone};
  int64_t i = 0;
  for (; i + 4 <= count; i += 4) {
    V4 d, xr, xn, low, up;
    loadLanes<4>(lower + i, d);
    loadLanes<4>(residuals + i, xr);
    loadLanes<4>(norms + i, xn);
    both(d, xr, xn, low, up);
    std::memcpy(upper + i, &up, sizeof up);
    std::memcpy(lower + i, &low, sizeof low);
    least = up < least ? up : least;
  }
  float smallest = std::min(std::min(least[0], least[1]), std::min(least[2], least[3]));
  for (; i < count; ++i) {
    both(lower[i], residuals[i], norms[i], lower[i], upper[i]);
    if (upper[i] < smallest) smallest = upper[i];
  }
  return smallest;
}

// Calls visit(i) for each i < count with values[i] ≤ limit (or NaN), in order; four values to a
// compare, since few pass.
template <class Visit>
void forEachWithin(const float* values, int64_t count, float limit, Visit visit) {
  int64_t i = 0;
  for (; i + 4 <= count; i += 4) {
    V4 v;
    loadLanes<4>(values + i, v);
    const auto over = v > limit;
    uint64_t low = 0, high = 0;
    std::memcpy(&low, &over, sizeof low);
    std::memcpy(&high, reinterpret_cast<const char*>(&over) + sizeof low, sizeof high);
    if ((low & high) == ~uint64_t{0}) continue;  // all four over the limit
    for (int64_t j = i; j < i + 4; ++j) {
      if (!(values[j] > limit)) visit(j);
    }
  }
  for (; i < count; ++i) {
    if (!(values[i] > limit)) visit(i);
  }
}

class IvfBackend final : public Backend {
 public:
  IvfBackend(const float* data, int64_t rows, int64_t dims, int lists, int probes)
      : mData(data), mDims(dims), mKeyDims(dims > kKeyDims && dims <= kMaxProjectedDims ? kKeyDims : dims),
        mStride(paddedDims(mKeyDims)), mLists(lists), mProbes(probes) {
    if (mKeyDims < mDims) principalDirections(rows);
    std::vector<float> keys(static_cast<size_t>(rows * mStride));
    std::vector<KeyRest> rests(static_cast<size_t>(rows));
    std::vector<double> centred;
    for (int64_t r = 0; r < rows; ++r) {
      rests[static_cast<size_t>(r)] = makeKey(mData + r * mDims, keys.data() + r * mStride, centred);
    }
    train(keys, rows);
    file(keys, rests, rows);
  }

  Status query(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const override {
    try {
      // Scratch kept per thread: a query allocates nothing once its thread has run one as large.
      // (Its address is taken once: in a shared library each thread_local access is a call.)
      Scratch& w = scratch();
      w.query.resize(static_cast<size_t>(mStride));
      const KeyRest q = makeKey(descriptor, w.query.data(), w.centred);
      w.toCentroids.resize(static_cast<size_t>(mLists));
      distances(w.query.data(), mCentroids.data(), mLists, mStride, w.toCentroids.data());
      const int64_t rows = probe(w.toCentroids, k, w.probed);

      // Each probed row's key distance d̂, list after list, and the k-th smallest upper bound of the
      // rows' distances (a max-heap of k). A row's distance is d̂ plus its residual part, which lies
      // between (qr − xr)² and (qr + xr)² (the triangle inequality in the discarded directions).
      // Float rounding of the sums is covered by a relative δ. The keys' own rounding moves a key
      // distance's root by at most 2⁻²⁴(‖q‖ + ‖x‖) (the centred norms), so its square by less than
      // η = 1e-6(‖q‖ + ‖x‖)², eight times that. Without a projection, xr = qr = η = 0.
      constexpr float kDelta = 1e-3f;
      const float etaScale = mKeyDims < mDims ? 1e-6f : 0.0f;
      w.lower.resize(static_cast<size_t>(rows));
      w.upper.resize(static_cast<size_t>(rows));
      float* const lower = w.lower.data();
      float* const upper = w.upper.data();
      std::vector<float>& heap = w.heap;
      heap.clear();
      float kth = std::numeric_limits<float>::infinity();  // the heap's top once it holds k
      int64_t n = 0;
      for (int32_t list : w.probed) {
        const int64_t begin = mOffsets[static_cast<size_t>(list)], count = listSize(list);
        distances(w.query.data(), mRows.data() + begin * mStride, count, mStride, lower + n);
        const float least =
            bounds(q, mResiduals.data() + begin, mNorms.data() + begin, count, kDelta, etaScale, lower + n, upper + n);
        for (int64_t i = n; i < n + count && (static_cast<int>(heap.size()) < k || least < kth); ++i) {
          const bool full = static_cast<int>(heap.size()) == k;
          if (full && !(upper[i] < kth)) continue;  // most rows: one compare, kept in a register
          if (full) {
            std::pop_heap(heap.begin(), heap.end());
            heap.pop_back();
          }
          heap.push_back(upper[i]);
          std::push_heap(heap.begin(), heap.end());
          kth = heap.front();
        }  // (a list none of whose rows can enter, by its smallest upper bound, is not walked)
        n += count;
      }
      // Rows whose lower bound is within the k-th upper bound can be among the k nearest: those,
      // and only those, get their exact distance.
      const float admit = heap.front();
      std::vector<Ranked>& ranked = w.ranked;
      ranked.clear();
      n = 0;
      for (int32_t list : w.probed) {
        const int64_t begin = mOffsets[static_cast<size_t>(list)], count = listSize(list);
        forEachWithin(lower + n, count, admit, [&](int64_t i) {
          const int64_t id = mIds[static_cast<size_t>(begin + i)];
          ranked.push_back({exactSquaredL2(descriptor, mData + id * mDims, mDims), id});
        });
        n += count;
      }
      std::partial_sort(ranked.begin(), ranked.begin() + k, ranked.end(), [](const Ranked& a, const Ranked& b) {
        return a.distance != b.distance ? a.distance < b.distance : a.id < b.id;
      });
      for (int r = 0; r < k; ++r) {
        ids[r] = ranked[static_cast<size_t>(r)].id;
        squaredDistances[r] = ranked[static_cast<size_t>(r)].distance;
      }
    } catch (const std::exception& e) {
      return invalidArgument(std::string("DescriptorIndex query: IVF search failed: ") + e.what());
    }
    return Ok{};
  }

  int64_t memoryBytes() const override {
    return static_cast<int64_t>((mCentroids.size() + mRows.size() + mResiduals.size() + mNorms.size()) * sizeof(float) +
                                (mBasis.size() + mBasisAcross.size() + mMean.size()) * sizeof(double) +
                                mIds.size() * sizeof(int32_t) + mOffsets.size() * sizeof(int64_t));
  }

 private:
  struct Ranked {
    float distance;
    int64_t id;
  };
  struct Scratch {
    std::vector<float> query, toCentroids, lower, upper, heap;
    std::vector<double> centred;
    std::vector<int32_t> probed;
    std::vector<Ranked> ranked;
  };
  [[gnu::noinline]] static Scratch& scratch() {
    thread_local Scratch perThread;
    return perThread;
  }

  // A row's key into `key` (mStride floats, zero padded): with a projection, its coordinates along
  // the first mKeyDims principal directions of the centred data, in double, with the norms of the
  // rest and of the whole; without, the row itself.
  // `centred` is scratch (the query's own, so that a query touches one thread_local).
  KeyRest makeKey(const float* row, float* key, std::vector<double>& centred) const {
    if (mBasis.empty()) {
      pad(row, mDims, mStride, key);
      return {};
    }
    centred.resize(static_cast<size_t>(mDims));
    double whole = 0.0;
    for (int64_t c = 0; c < mDims; ++c) {
      centred[static_cast<size_t>(c)] = static_cast<double>(row[c]) - mMean[static_cast<size_t>(c)];
      whole += centred[static_cast<size_t>(c)] * centred[static_cast<size_t>(c)];
    }
    // The coordinates c = B·x, summed over the values in order, kKeyDims independent sums (each in
    // its own lane, so any vector width gives the same bits); then the rest x − Bᵀc, value by value.
    std::array<double, kKeyDims> coordinates{};
    for (int64_t c = 0; c < mDims; ++c) {
      const double* across = mBasisAcross.data() + c * kKeyDims;
      const double value = centred[static_cast<size_t>(c)];
      for (int64_t i = 0; i < kKeyDims; ++i) coordinates[static_cast<size_t>(i)] += across[i] * value;
    }
    std::fill(key, key + mStride, 0.0f);
    for (int64_t i = 0; i < kKeyDims; ++i) {
      const double coordinate = coordinates[static_cast<size_t>(i)];
      key[i] = static_cast<float>(coordinate);
      const double* direction = mBasis.data() + i * mDims;
      for (int64_t c = 0; c < mDims; ++c) centred[static_cast<size_t>(c)] -= coordinate * direction[c];
    }
    double rest = 0.0;
    for (double v : centred) rest += v * v;
    return {static_cast<float>(std::sqrt(rest)), static_cast<float>(std::sqrt(whole))};
  }

  // The first mKeyDims principal axes of an evenly spaced sample of the rows (principalAxes).
  void principalDirections(int64_t rows) {
    const int64_t sample = std::min(rows, kPrincipalSample);
    Eigen::MatrixXd points(mDims, sample);
    for (int64_t i = 0; i < sample; ++i) {
      const float* row = mData + (i * rows / sample) * mDims;
      for (int64_t c = 0; c < mDims; ++c) points(c, i) = row[c];
    }
    const PrincipalAxes principal = principalAxes(points);
    mBasis.resize(static_cast<size_t>(mKeyDims * mDims));
    for (int64_t i = 0; i < mKeyDims; ++i) {
      for (int64_t c = 0; c < mDims; ++c) mBasis[static_cast<size_t>(i * mDims + c)] = principal.axes(c, i);
    }
    mBasisAcross.resize(static_cast<size_t>(mDims * kKeyDims));
    for (int64_t c = 0; c < mDims; ++c) {
      for (int64_t i = 0; i < kKeyDims; ++i) mBasisAcross[static_cast<size_t>(c * kKeyDims + i)] = principal.axes(c, i);
    }
    const Eigen::VectorXd& mean = principal.mean;
    mMean.assign(mean.data(), mean.data() + mDims);
  }

  // The lists to scan: the mProbes nearest centroids, ties by lower index, and more in centroid
  // order while they hold fewer than k rows. Returns the rows they hold.
  int64_t probe(const std::vector<float>& toCentroids, int k, std::vector<int32_t>& best) const {
    best.clear();  // sorted by (distance, index), at most mProbes
    const auto before = [&](int32_t a, int32_t b) {
      const float da = toCentroids[static_cast<size_t>(a)], db = toCentroids[static_cast<size_t>(b)];
      return da != db ? da < db : a < b;
    };
    for (int32_t c = 0; c < mLists; ++c) {
      if (static_cast<int>(best.size()) == mProbes && !before(c, best.back())) continue;
      best.insert(std::upper_bound(best.begin(), best.end(), c, before), c);
      if (static_cast<int>(best.size()) > mProbes) best.pop_back();
    }
    int64_t held = 0;
    for (int32_t list : best) held += listSize(list);
    if (held >= k) return held;
    std::vector<int32_t> all(static_cast<size_t>(mLists));
    for (int32_t c = 0; c < mLists; ++c) all[static_cast<size_t>(c)] = c;
    std::sort(all.begin(), all.end(), before);
    best.clear();
    held = 0;
    for (int32_t list : all) {
      if (held >= k) break;
      best.push_back(list);
      held += listSize(list);
    }
    return held;
  }

  int64_t listSize(int32_t list) const {
    return mOffsets[static_cast<size_t>(list) + 1] - mOffsets[static_cast<size_t>(list)];
  }

  // Lloyd's k-means over the keys of an evenly spaced sample (see the file comment).
  void train(const std::vector<float>& keys, int64_t rows) {
    const int64_t sample = std::min(rows, kSamplePerList * mLists);
    const auto point = [&](int64_t i) { return keys.data() + (i * rows / sample) * mStride; };
    mCentroids.resize(static_cast<size_t>(mLists) * static_cast<size_t>(mStride));
    for (int64_t c = 0; c < mLists; ++c) std::copy_n(point(c * sample / mLists), mStride, mCentroids.data() + c * mStride);
    std::vector<float> d(static_cast<size_t>(mLists));
    std::vector<double> sums(mCentroids.size());
    std::vector<int64_t> counts(static_cast<size_t>(mLists));
    for (int iteration = 0; iteration < kIterations; ++iteration) {
      std::fill(sums.begin(), sums.end(), 0.0);
      std::fill(counts.begin(), counts.end(), 0);
      for (int64_t i = 0; i < sample; ++i) {
        const float* p = point(i);
        distances(p, mCentroids.data(), mLists, mStride, d.data());
        const int64_t c = nearest(d.data(), mLists);
        ++counts[static_cast<size_t>(c)];
        for (int64_t v = 0; v < mStride; ++v) sums[static_cast<size_t>(c * mStride + v)] += p[v];
      }
      for (int64_t c = 0; c < mLists; ++c) {
        if (counts[static_cast<size_t>(c)] == 0) continue;
        for (int64_t v = 0; v < mStride; ++v) {
          mCentroids[static_cast<size_t>(c * mStride + v)] =
              static_cast<float>(sums[static_cast<size_t>(c * mStride + v)] / static_cast<double>(counts[static_cast<size_t>(c)]));
        }
      }
    }
  }

  // Every row's key under its nearest centroid, lists in centroid order, rows in id order within each.
  void file(const std::vector<float>& keys, const std::vector<KeyRest>& rests, int64_t rows) {
    std::vector<int32_t> listOf(static_cast<size_t>(rows));
    std::vector<float> d(static_cast<size_t>(mLists));
    mOffsets.assign(static_cast<size_t>(mLists) + 1, 0);
    for (int64_t r = 0; r < rows; ++r) {
      distances(keys.data() + r * mStride, mCentroids.data(), mLists, mStride, d.data());
      listOf[static_cast<size_t>(r)] = static_cast<int32_t>(nearest(d.data(), mLists));
      ++mOffsets[static_cast<size_t>(listOf[static_cast<size_t>(r)]) + 1];
    }
    for (int64_t c = 0; c < mLists; ++c) mOffsets[static_cast<size_t>(c) + 1] += mOffsets[static_cast<size_t>(c)];
    std::vector<int64_t> next(mOffsets.begin(), mOffsets.end() - 1);
    mIds.resize(static_cast<size_t>(rows));
    mResiduals.resize(static_cast<size_t>(rows));
    mNorms.resize(static_cast<size_t>(rows));
    mRows.resize(static_cast<size_t>(rows * mStride));
    for (int64_t r = 0; r < rows; ++r) {
      const int64_t at = next[static_cast<size_t>(listOf[static_cast<size_t>(r)])]++;
      mIds[static_cast<size_t>(at)] = static_cast<int32_t>(r);
      mResiduals[static_cast<size_t>(at)] = rests[static_cast<size_t>(r)].residual;
      mNorms[static_cast<size_t>(at)] = rests[static_cast<size_t>(r)].norm;
      std::copy_n(keys.data() + r * mStride, mStride, mRows.data() + at * mStride);
    }
  }

  const float* mData;  // DescriptorIndex's copy, for the exact distances
  int64_t mDims, mKeyDims, mStride;
  int mLists, mProbes;
  std::vector<double> mBasis;      // with a projection: mKeyDims directions of mDims values
  std::vector<double> mBasisAcross;  // the same, value by value: mDims rows of the mKeyDims directions' values
  std::vector<double> mMean;       // with a projection: the sample's mean row
  std::vector<float> mCentroids;   // mLists × mStride keys
  std::vector<float> mRows;        // the rows' keys, padded, list after list
  std::vector<float> mResiduals;   // each filed row's norm outside its key (0 without a projection)
  std::vector<float> mNorms;       // each filed row's centred norm (0 without a projection)
  std::vector<int32_t> mIds;       // each filed row's id
  std::vector<int64_t> mOffsets;   // list c is filed rows [mOffsets[c], mOffsets[c + 1])
};

}  // namespace

void ivfSquaredDistances(Lanes lanes, const float* query, const float* rows, int64_t count, int64_t stride, float* out) {
  if (lanes == Lanes::Wide) {
    distancesWide(query, rows, count, stride, out);
  } else {
    distancesNarrow(query, rows, count, stride, out);
  }
}

Status checkInvertedFileSettings(const DescriptorIndexSettings& settings, int64_t rows, int64_t maxLists, const char* what) {
  const int64_t most = std::min(rows, maxLists);
  if (settings.trees < 1 || settings.trees > most)
    return invalidArgument(std::string("DescriptorIndex: settings.trees (") + what + " lists) must be in [1, " +
                           (most < rows ? "min(rows = " + std::to_string(rows) + ", " + std::to_string(maxLists) + ")"
                                        : "rows = " + std::to_string(rows)) +
                           "], got " + std::to_string(settings.trees));
  if (settings.checks < 1 || settings.checks > settings.trees)
    return invalidArgument(std::string("DescriptorIndex: settings.checks (") + what + " lists probed) must be in [1, trees], got " +
                           std::to_string(settings.checks));
  return Ok{};
}

Result<std::unique_ptr<Backend>> buildIvf(const float* data, int64_t rows, int64_t dims,
                                          const DescriptorIndexSettings& settings) {
  if (rows > std::numeric_limits<int32_t>::max()) return invalidArgument("DescriptorIndex: ivf needs rows <= INT32_MAX");
  if (Status st = checkInvertedFileSettings(settings, rows, std::numeric_limits<int64_t>::max(), "IVF"); !st) return st.error();
  try {
    return std::unique_ptr<Backend>(std::make_unique<IvfBackend>(data, rows, dims, settings.trees, settings.checks));
  } catch (const std::exception& e) {
    return invalidArgument(std::string("DescriptorIndex: ivf build failed: ") + e.what());
  }
}

}  // namespace brittle::search
