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
// Wide rows (more than kMaxProjectedDims values: the 16³ voxel grids) are filed by kWideKeyDims
// principal components too, which the 4096² covariance would make slow to find and a query's
// 4096 × kWideKeyDims double products slow to use. So (WideProjection below):
//   - the directions come from kWideRounds rounds of subspace iteration on an evenly spaced sample
//     (in float, every sum in a fixed order; the start a splitmix64 stream, no draw), made
//     orthonormal in double and rounded to float: any orthonormal directions give valid bounds,
//     the leading ones tight bounds;
//   - a key sums the float directions' rows of the values where the row differs from a reference
//     of ±1 (a clamped distance differs in ~800 of 4 096), in float over blocks of kWideBlock values
//     and the blocks in double; the residual comes from the norms, not a second pass. Each row
//     keeps the bounds of its rounding: its key lies within e of the exact projection, and its
//     residual r in [lo, hi], both for the whole key and for its first kWidePrefixDims values.
//   - A query's lower bound on a row's distance is (√d̂ − e_q − e_x)² + gap², gap the distance
//     between the two residual intervals. The lists probed are those whose centroids' first
//     kWideListDims values are nearest. Their rows are bounded from their keys' first
//     kWidePrefixDims values (a quarter of the bytes) and the k smallest bounds' rows measured
//     exactly. Every row whose bound is within the k-th best exact distance is then bounded again
//     from its whole key (its other values and rounding bounds in one record, fetched ahead), and
//     those still within are measured in the order of their bounds, nearest first, until the next
//     bound passes the k-th best. At 10⁵ clamped distances (40 lists probed) a query bounds 4 080
//     rows by their first values, 48 by their whole keys and measures 7 (6.4 of them within the
//     final k-th best, so no order measures fewer); the upper bounds' admission above would
//     measure hundreds, since a 4 096-value row's residual is not small.
//
// Same bits with SSE2 and AVX: both forms keep eight float lanes, lane l summing (a − b)² over the
// values l, l + 8, ..., and add the lanes in one fixed order at the end (Simd.h). So the probed
// lists, and so the answer, do not depend on the CPU.
#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <array>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "IndexBackends.h"
#include "brittle/core/Random.h"
#include "brittle/core/Simd.h"

namespace brittle::search {
namespace {

constexpr int kLanes = 8;
constexpr int64_t kSamplePerList = 32;  // k-means rows per centroid (FAISS trains on up to 256)
constexpr int kIterations = 12;
// Rows wider than kKeyDims values are compared by their first kKeyDims principal components and the
// norm of the rest, up to kMaxProjectedDims values (the moment descriptors); wider rows (the voxel
// grids, whose covariance would be 4096²) are compared whole.
constexpr int64_t kKeyDims = InvertedFileKeys::kKeyDims;
constexpr int64_t kMaxProjectedDims = InvertedFileKeys::kMaxProjectedDims;
constexpr int64_t kPrincipalSample = 8192;  // rows the principal directions are made from, evenly spaced
// Wide rows: 64 of 4096 directions keep 94 % of the clamped distances' variance; a key's first 16
// values are scanned first (a quarter of its bytes).
constexpr int64_t kWideKeyDims = InvertedFileKeys::kWideKeyDims;
constexpr int64_t kWidePrefixDims = InvertedFileKeys::kWidePrefixDims;
constexpr int64_t kWideRestDims = kWideKeyDims - kWidePrefixDims;
// A wide row's record for its second bound: its key's other values, then its WideRest's error, low
// and high, so that a row reached at random costs one fetch (apart, they were four cache misses).
constexpr int64_t kWideRecord = kWideRestDims + 8;
constexpr int64_t kWideRecordError = kWideRestDims, kWideRecordLow = kWideRestDims + 1, kWideRecordHigh = kWideRestDims + 2;
constexpr int64_t kWideListDims = InvertedFileKeys::kWideListDims;  // wide rows: a centroid's first values, which choose the lists probed
constexpr int64_t kWideSample = 2048;       // wide rows: sample of the subspace iteration, at most
constexpr int64_t kWideSampleValues = int64_t{1} << 23;  // ... this many values (32 MB a copy: 64³ grids get 32 rows)
constexpr int kWideRounds = 4;              // wide rows: rounds of subspace iteration
constexpr int64_t kWideBlock = 64;          // wide rows: values summed in float before a double sum
constexpr size_t kRecordsAhead = 8;         // wide rows: second-bound records fetched ahead of their bound
constexpr int kInsertedProbes = 8;          // lists probed up to which they are chosen by insertion, not selection
constexpr int64_t kWideNextPrefetch = 256;  // wide rows: values of the next row to measure fetched ahead
// Bounds of a wide key's rounding, relative to the row's norm (see WideProjection::key): a block's
// float sum is within γ₆₄ ≈ 3.8e-6 of exact (Cauchy–Schwarz over ‖b_i‖ = 1), √64 coordinates give
// 3.1e-5, the float basis's departure from orthonormal (≤ 64 ulp) adds 4e-6 of ‖x‖² to r²: each
// taken about three times over.
constexpr double kWideKeyError = 1e-4;
constexpr double kWideResidualError = 3e-5;

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

// best ← the `probes` smallest of distances[0, lists) by (distance, index), in that order. A few
// (the moments' 4 of ~256) by insertion into a sorted list; more (the wide rows' 40 of 1 024,
// where the insertions took 23k cycles a query) by selection: a distance ≥ 0 (finite: the query
// and the centroids are) orders as its bits, so each centroid is one integer key. Measured at 10⁵:
// the moments' query 5.6 µs by insertion, 6.7 by selection; the clamped distances' 61–67 → 59 µs
// by selection. Both give the same lists (ivfNearestLists).
void nearestLists(const float* distances, int lists, int probes, bool insertion, std::vector<int32_t>& best,
                  std::vector<uint64_t>& order) {
  const auto kept = static_cast<size_t>(std::min(probes, lists));
  if (insertion) {
    const auto before = [&](int32_t a, int32_t b) { return distances[a] != distances[b] ? distances[a] < distances[b] : a < b; };
    best.clear();
    for (int32_t c = 0; c < lists; ++c) {
      if (best.size() == kept && !before(c, best.back())) continue;
      best.insert(std::upper_bound(best.begin(), best.end(), c, before), c);
      if (best.size() > kept) best.pop_back();
    }
    return;
  }
  order.resize(static_cast<size_t>(lists));
  for (int32_t c = 0; c < lists; ++c) {
    const float d = distances[c];
    order[static_cast<size_t>(c)] = uint64_t{std::bit_cast<uint32_t>(d > 0.0f ? d : 0.0f)} << 32 | static_cast<uint32_t>(c);
  }
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(kept) - 1, order.end());
  std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(kept));
  best.resize(kept);
  for (size_t i = 0; i < kept; ++i) best[i] = static_cast<int32_t>(order[i] & 0xffffffffu);
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

// A wide row's rounding bounds beside its key: the key lies within `error` of the exact
// projection, and the norm of what it leaves out within [low, high].
struct WideRest {
  float error = 0.0f;
  float low = 0.0f;
  float high = 0.0f;
  float prefixLow = 0.0f;   // the same for the norm outside the key's first kWidePrefixDims values
  float prefixHigh = 0.0f;
};

// Each scanned wide row's lower bound on its squared distance, from its key distance d̂ (in
// `lower` on entry): (√d̂ − e)² + gap², e = e_q + e_x, gap the distance between the residuals'
// intervals. (√d̂ − e)² ≥ d̂(1 − e) − e (as √d̂ ≤ (d̂ + 1)/2), which keeps the loop free of roots;
// the float sums' rounding is a relative δ. Eight rows to an AVX register where `lanes` is Wide,
// else four to an SSE2 one, each lane the scalar tail's operations (max as std::max's a < b ? b : a):
// the same bits either way (InvertedFileWideBoundsHoldForEveryRow).
template <int L>
[[gnu::always_inline]] inline void wideLowerBoundsInLanes(float qError, float qLow, float qHigh, const float* errors,
                                                          const float* lows, const float* highs, int64_t count,
                                                          float* lower) {
  constexpr float kDelta = 1e-3f;
  // (References in and out: a 256-bit value passed or returned by value changes the ABI outside AVX.)
  const auto bound = [&](const auto& d, const auto& error, const auto& low, const auto& high, auto& out) {
    using T = std::remove_cvref_t<decltype(d)>;
    const T zero{};
    const T e = qError + error;
    T key = d * (1.0f - e) - e;
    const T below = qLow - high, above = low - qHigh;
    T gap = below < above ? above : below;
    gap = gap < zero ? zero : gap;
    key = key < zero ? zero : key;
    out = (key + gap * gap) * (1.0f - kDelta);
  };
  using V = VectorOf<float, L>;
  int64_t i = 0;
  for (; i + L <= count; i += L) {
    V d, error, low, high;
    loadLanes<L>(lower + i, d);
    loadLanes<L>(errors + i, error);
    loadLanes<L>(lows + i, low);
    loadLanes<L>(highs + i, high);
    V out;
    bound(d, error, low, high, out);
    std::memcpy(lower + i, &out, sizeof out);
  }
  for (; i < count; ++i) bound(lower[i], errors[i], lows[i], highs[i], lower[i]);
}
BRITTLE_TARGET_AVX void wideLowerBoundsWide(float qError, float qLow, float qHigh, const float* errors, const float* lows,
                                            const float* highs, int64_t count, float* lower) {
  wideLowerBoundsInLanes<8>(qError, qLow, qHigh, errors, lows, highs, count, lower);
}
void wideLowerBounds(Lanes lanes, float qError, float qLow, float qHigh, const float* errors, const float* lows,
                     const float* highs, int64_t count, float* lower) {
  if (count >= 8 && lanes == Lanes::Wide) {
    wideLowerBoundsWide(qError, qLow, qHigh, errors, lows, highs, count, lower);
  } else {
    wideLowerBoundsInLanes<4>(qError, qLow, qHigh, errors, lows, highs, count, lower);
  }
}

// out[i] = Σ_j weights[j]·rows[index[j]·kWideKeyDims + i] for the kWideKeyDims values i, each a float
// sum over j in order, one lane per i: the same bits in either form (no fused multiply-add).
template <int L>
[[gnu::always_inline]] inline void weightedRowSumBy(const float* rows, const int32_t* index, const float* weights,
                                                    int64_t count, float* out) {
  using V = VectorOf<float, L>;
  constexpr int kRegisters = static_cast<int>(kWideKeyDims) / L;
  V sums[kRegisters] = {};
  for (int64_t j = 0; j < count; ++j) {
    const float* row = rows + static_cast<int64_t>(index[j]) * kWideKeyDims;
    const V weight = V{} + weights[j];
    for (int r = 0; r < kRegisters; ++r) {
      V value;
      loadLanes<L>(row + r * L, value);
      sums[r] += value * weight;
    }
  }
  for (int r = 0; r < kRegisters; ++r) std::memcpy(out + r * L, &sums[r], sizeof sums[r]);
}
BRITTLE_TARGET_AVX void weightedRowSumWide(const float* rows, const int32_t* index, const float* weights, int64_t count,
                                           float* out) {
  weightedRowSumBy<8>(rows, index, weights, count, out);
}
void weightedRowSumNarrow(const float* rows, const int32_t* index, const float* weights, int64_t count, float* out) {
  weightedRowSumBy<4>(rows, index, weights, count, out);
}
void weightedRowSum(const float* rows, const int32_t* index, const float* weights, int64_t count, float* out) {
  if (widestLanes() == Lanes::Wide) {
    weightedRowSumWide(rows, index, weights, count, out);
  } else {
    weightedRowSumNarrow(rows, index, weights, count, out);
  }
}

// The wide rows' projection (see the file comment): kWideKeyDims directions in float, value by
// value; the centre they are measured from; and a reference row of ±1 (the sign of the centre),
// which a clamped distance equals in most of its values (3 300 of 4 096 on 10⁴ fragments): a key
// sums the directions of the other values only.
class WideProjection {
 public:
  WideProjection() = default;

  // The leading directions of an evenly spaced sample of the rows, by subspace iteration in
  // float (their precision only decides how tight the bounds are, not whether they hold), made
  // orthonormal in double.
  WideProjection(const float* data, int64_t rows, int64_t dims) : mDims(dims) {
    constexpr int64_t m = kWideKeyDims;
    const int64_t n = dims, samples = std::min({rows, kWideSample, std::max<int64_t>(1, kWideSampleValues / dims)});
    std::vector<double> mean(static_cast<size_t>(n), 0.0);
    for (int64_t s = 0; s < samples; ++s) {
      const float* row = data + (s * rows / samples) * n;
      for (int64_t c = 0; c < n; ++c) mean[static_cast<size_t>(c)] += row[c];
    }
    for (double& v : mean) v /= static_cast<double>(samples);
    std::vector<float> x(static_cast<size_t>(samples * n)), across(static_cast<size_t>(n * samples));
    for (int64_t s = 0; s < samples; ++s) {
      const float* row = data + (s * rows / samples) * n;
      for (int64_t c = 0; c < n; ++c) {
        const auto value = static_cast<float>(row[c] - mean[static_cast<size_t>(c)]);
        x[static_cast<size_t>(s * n + c)] = value;
        across[static_cast<size_t>(c * samples + s)] = value;
      }
    }
    std::vector<int32_t> order(static_cast<size_t>(std::max(n, samples)));
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int32_t>(i);
    // V (n × m) from a fixed stream, then rounds of V ← orthonormal(Xᵀ X V).
    std::vector<float> v(static_cast<size_t>(n * m)), y(static_cast<size_t>(samples * m));
    SplitMix64 stream(0x1f2e3d4c5b6a7988ull);
    for (float& value : v) value = static_cast<float>(nearNormal(stream.next()));
    orthonormalise(v, n);
    for (int round = 0; round < kWideRounds; ++round) {
      for (int64_t s = 0; s < samples; ++s) weightedRowSum(v.data(), order.data(), x.data() + s * n, n, y.data() + s * m);
      for (int64_t c = 0; c < n; ++c) weightedRowSum(y.data(), order.data(), across.data() + c * samples, samples, v.data() + c * m);
      orthonormalise(v, n);
    }
    // Rayleigh–Ritz: the directions of V ordered by the sample's variance along them, largest first.
    for (int64_t s = 0; s < samples; ++s) weightedRowSum(v.data(), order.data(), x.data() + s * n, n, y.data() + s * m);
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(m, m);
    for (int64_t s = 0; s < samples; ++s) {
      const Eigen::VectorXd ys = Eigen::Map<const Eigen::VectorXf>(y.data() + s * m, m).cast<double>();
      for (int64_t j = 0; j < m; ++j) gram.col(j) += ys[j] * ys;  // element by element, in sample order
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(gram);
    if (solver.info() != Eigen::Success) throw std::runtime_error("the wide rows' principal directions did not converge");
    const Eigen::MatrixXd turn = solver.eigenvectors().rowwise().reverse();
    std::vector<double> turned(static_cast<size_t>(n * m));
    for (int64_t c = 0; c < n; ++c) {
      for (int64_t i = 0; i < m; ++i) {
        double sum = 0.0;
        for (int64_t j = 0; j < m; ++j) sum += static_cast<double>(v[static_cast<size_t>(c * m + j)]) * turn(j, i);
        turned[static_cast<size_t>(c * m + i)] = sum;
      }
    }
    orthonormalise(turned, n);
    mAcross.assign(turned.begin(), turned.end());  // rounded to float
    mCentre.resize(static_cast<size_t>(n));
    mReference.resize(static_cast<size_t>(n));
    double apart = 0.0;
    for (int64_t c = 0; c < n; ++c) {
      mCentre[static_cast<size_t>(c)] = static_cast<float>(mean[static_cast<size_t>(c)]);
      mReference[static_cast<size_t>(c)] = mCentre[static_cast<size_t>(c)] >= 0.0f ? 1.0f : -1.0f;
      const double gap = static_cast<double>(mReference[static_cast<size_t>(c)]) - mCentre[static_cast<size_t>(c)];
      apart += gap * gap;
      for (int64_t i = 0; i < m; ++i) mOffset[static_cast<size_t>(i)] += static_cast<double>(mAcross[static_cast<size_t>(c * m + i)]) * gap;
    }
    mReferenceApart = std::sqrt(apart);
  }

  // `key` (kWideKeyDims floats) of `row` and its rounding bounds: Σ_c b_c (x_c − z_c), the float
  // basis's rows b_c of the values c where the row differs from the reference z, summed in float
  // over blocks of kWideBlock values and the blocks in double, plus the reference's key Σ_c b_c
  // (z_c − centre_c) in double; the residual from ‖x − centre‖² − ‖key‖².
  WideRest key(const float* row, float* key) const {
    constexpr int64_t m = kWideKeyDims;
    std::array<double, m> sums{};
    std::array<int32_t, kWideBlock> columns;
    std::array<float, kWideBlock> differences;
    std::array<float, m> block;
    for (int64_t begin = 0; begin < mDims; begin += kWideBlock) {
      const int64_t end = std::min(mDims, begin + kWideBlock);
      int64_t count = 0;
      for (int64_t c = begin; c < end; ++c) {  // branch-free: most values equal the reference
        const float difference = row[c] - mReference[static_cast<size_t>(c)];
        columns[static_cast<size_t>(count)] = static_cast<int32_t>(c);
        differences[static_cast<size_t>(count)] = difference;
        count += difference != 0.0f;
      }
      if (count == 0) continue;
      weightedRowSum(mAcross.data(), columns.data(), differences.data(), count, block.data());
      for (int64_t i = 0; i < m; ++i) sums[static_cast<size_t>(i)] += block[static_cast<size_t>(i)];
    }
    const double centred = exactSquaredL2(row, mCentre.data(), mDims);  // ‖x − centre‖², in double lanes
    double kept = 0.0, prefix = 0.0;
    for (int64_t i = 0; i < m; ++i) {
      const double coordinate = sums[static_cast<size_t>(i)] + mOffset[static_cast<size_t>(i)];
      key[i] = static_cast<float>(coordinate);
      kept += coordinate * coordinate;
      if (i + 1 == kWidePrefixDims) prefix = kept;
    }
    // ‖x − z‖ ≤ ‖x − centre‖ + ‖centre − z‖ bounds the sums' rounding (file comment).
    const double error = kWideKeyError * (std::sqrt(centred) + mReferenceApart);
    const double rest = std::max(centred - kept, 0.0), beyondPrefix = std::max(centred - prefix, 0.0);
    const double slack = error * (2.0 * std::sqrt(centred) + error) + kWideResidualError * centred;
    return {static_cast<float>(error), static_cast<float>(std::sqrt(std::max(rest - slack, 0.0))),
            static_cast<float>(std::sqrt(rest + slack)), static_cast<float>(std::sqrt(std::max(beyondPrefix - slack, 0.0))),
            static_cast<float>(std::sqrt(beyondPrefix + slack))};
  }

  int64_t bytes() const {
    return static_cast<int64_t>((mAcross.size() + mCentre.size() + mReference.size()) * sizeof(float) + sizeof mOffset);
  }
  void addToDigest(Fingerprint& digest) const {
    digest.add(mDims), digest.add(mAcross), digest.add(mCentre), digest.add(mReference);
    digest.addBytes(mOffset.data(), sizeof mOffset);
    digest.add(mReferenceApart);
  }

 private:
  // The columns of v (n × m, row-major) made orthonormal in order, by Gram–Schmidt in double done
  // twice. A column that vanishes (fewer distinct samples than directions) is replaced by the
  // next unit vector that does not: the bounds need an orthonormal basis, not a principal one.
  template <class T>
  static void orthonormalise(std::vector<T>& values, int64_t n) {
    constexpr int64_t m = kWideKeyDims;
    Eigen::MatrixXd v(n, m);
    for (int64_t c = 0; c < n; ++c) {
      for (int64_t j = 0; j < m; ++j) v(c, j) = static_cast<double>(values[static_cast<size_t>(c * m + j)]);
    }
    int64_t unit = 0;
    for (int64_t j = 0; j < m; ++j) {
      for (;;) {
        const double before = v.col(j).squaredNorm();
        for (int pass = 0; pass < 2; ++pass) {
          for (int64_t i = 0; i < j; ++i) v.col(j) -= v.col(i).dot(v.col(j)) * v.col(i);
        }
        const double norm = v.col(j).squaredNorm();
        if (norm > 1e-20 * before && norm > 0.0) {
          v.col(j) /= std::sqrt(norm);
          break;
        }
        if (unit >= n) throw std::runtime_error("no orthonormal basis for the wide rows");
        v.col(j) = Eigen::VectorXd::Unit(n, unit++);
      }
    }
    for (int64_t c = 0; c < n; ++c) {
      for (int64_t j = 0; j < m; ++j) values[static_cast<size_t>(c * m + j)] = static_cast<T>(v(c, j));
    }
  }

  int64_t mDims = 0;
  std::vector<float> mAcross;                   // mDims rows of kWideKeyDims: value c's coordinates along the directions
  std::vector<float> mCentre;                   // the sample's mean row, rounded to float
  std::vector<float> mReference;                // z: ±1, the centre's sign
  std::array<double, kWideKeyDims> mOffset{};   // the reference's key, Σ_c b_c (z_c − centre_c), in double
  double mReferenceApart = 0.0;                 // ‖z − centre‖
};

class IvfBackend final : public Backend {
 public:
  IvfBackend(const float* data, int64_t rows, int64_t dims, int lists, int probes)
      : mData(data), mDims(dims), mWide(dims > kMaxProjectedDims),
        mKeyDims(mWide ? kWideKeyDims : dims > kKeyDims ? kKeyDims : dims), mStride(paddedDims(mKeyDims)),
        mLists(lists), mProbes(probes) {
    if (mWide) {
      mProjection = WideProjection(data, rows, dims);
    } else if (mKeyDims < mDims) {
      principalDirections(rows);
    }
    std::vector<float> keys(static_cast<size_t>(rows * mStride), 0.0f);
    std::vector<KeyRest> rests(mWide ? 0 : static_cast<size_t>(rows));
    std::vector<WideRest> wideRests(mWide ? static_cast<size_t>(rows) : 0);
    std::vector<double> centred;
    for (int64_t r = 0; r < rows; ++r) {
      if (mWide) {
        wideRests[static_cast<size_t>(r)] = mProjection.key(mData + r * mDims, keys.data() + r * mStride);
      } else {
        rests[static_cast<size_t>(r)] = makeKey(mData + r * mDims, keys.data() + r * mStride, centred);
      }
    }
    train(keys, rows);
    file(keys, rests, wideRests, rows);
    if (mWide) mCentroids = std::vector<float>();  // a query reads their first values only (mCentroidPrefix)
  }

  Status query(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const override {
    try {
      if (mWide) {
        queryWide(descriptor, k, ids, squaredDistances);
        return Ok{};
      }
      // Scratch kept by the index (ScratchPool): a query allocates nothing once one as large has run.
      const auto lease = mScratch.lease();
      Scratch& w = *lease;
      w.query.resize(static_cast<size_t>(mStride));
      const KeyRest q = makeKey(descriptor, w.query.data(), w.centred);
      w.toCentroids.resize(static_cast<size_t>(mLists));
      distances(w.query.data(), mCentroids.data(), mLists, mStride, w.toCentroids.data());
      const int64_t rows = probe(w.toCentroids, k, w.probed, w.order);

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

  // Every row's first and second lower bounds for `descriptor` (by row id), by queryWide's own
  // firstBounds and secondBound, in the given lanes: for the tests (ivfWideBounds).
  void wideBounds(Lanes lanes, const float* descriptor, std::vector<float>& first, std::vector<float>& second) const {
    std::vector<float> key(static_cast<size_t>(mStride), 0.0f);
    const WideRest q = mProjection.key(descriptor, key.data());
    const auto rows = static_cast<int64_t>(mIds.size());
    std::vector<float> prefix(static_cast<size_t>(rows)), lower(static_cast<size_t>(rows));
    firstBounds(lanes, key.data(), q, 0, rows, prefix.data(), lower.data());
    first.assign(static_cast<size_t>(rows), 0.0f);
    second.assign(static_cast<size_t>(rows), 0.0f);
    for (int64_t at = 0; at < rows; ++at) {
      const auto id = static_cast<size_t>(mIds[static_cast<size_t>(at)]);
      first[id] = lower[static_cast<size_t>(at)];
      second[id] = secondBound(lanes, key.data(), q, at, prefix[static_cast<size_t>(at)]);
    }
  }

  Status addToDigest(Fingerprint& digest) const override {
    digest.add(mDims, mWide, mKeyDims, mStride, mLists, mProbes);
    digest.add(mBasis), digest.add(mBasisAcross), digest.add(mMean), digest.add(mCentroids), digest.add(mRows);
    digest.add(mResiduals), digest.add(mNorms), digest.add(mCentroidPrefix), digest.add(mWidePrefix), digest.add(mWideRecords);
    digest.add(mWideErrors), digest.add(mWidePrefixLows), digest.add(mWidePrefixHighs), digest.add(mIds), digest.add(mOffsets);
    mProjection.addToDigest(digest);
    return Ok{};
  }

  int64_t memoryBytes() const override {
    return mProjection.bytes() +
           static_cast<int64_t>((mCentroids.size() + mCentroidPrefix.size() + mRows.size() + mResiduals.size() + mNorms.size() + mWidePrefix.size() +
                                 mWideRecords.size() + mWideErrors.size() +
                                 mWidePrefixLows.size() + mWidePrefixHighs.size()) * sizeof(float) +
                                (mBasis.size() + mBasisAcross.size() + mMean.size()) * sizeof(double) +
                                mIds.size() * sizeof(int32_t) + mOffsets.size() * sizeof(int64_t));
  }

 private:
  struct Ranked {
    float distance;
    int64_t id;
  };
  struct Scratch {
    std::vector<float> query, toCentroids, lower, upper, heap, prefix;  // prefix: wide rows' key-prefix distances
    std::vector<double> centred;
    std::vector<int32_t> probed, scanned;
    std::vector<uint64_t> order;
    std::vector<Ranked> ranked;
    std::vector<std::pair<float, int64_t>> smallest;
  };
  static bool before(const Ranked& a, const Ranked& b) { return a.distance != b.distance ? a.distance < b.distance : a.id < b.id; }

  // A wide row's query (see the file comment). Each probed row's lower bound from its key's first
  // kWidePrefixDims values (a quarter of its bytes); the exact distances of the k smallest; then
  // for every row whose bound is within the k-th best exact distance, the bound from its whole key,
  // and the rows still within measured nearest bound first, the k-th best tightening as better
  // rows are found.
  void queryWide(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const {
    const auto lease = mScratch.lease();
    Scratch& w = *lease;
    w.query.assign(static_cast<size_t>(mStride), 0.0f);
    const WideRest q = mProjection.key(descriptor, w.query.data());
    w.toCentroids.resize(static_cast<size_t>(mLists));
    distances(w.query.data(), mCentroidPrefix.data(), mLists, kWideListDims, w.toCentroids.data());
    const int64_t rows = probe(w.toCentroids, k, w.probed, w.order);
    w.lower.resize(static_cast<size_t>(rows));
    w.prefix.resize(static_cast<size_t>(rows));
    w.scanned.resize(static_cast<size_t>(rows));
    float* const lower = w.lower.data();
    float* const prefixDistance = w.prefix.data();
    int64_t n = 0;
    for (int32_t list : w.probed) {
      const int64_t begin = mOffsets[static_cast<size_t>(list)], count = listSize(list);
      firstBounds(widestLanes(), w.query.data(), q, begin, count, prefixDistance + n, lower + n);
      for (int64_t i = 0; i < count; ++i) w.scanned[static_cast<size_t>(n + i)] = static_cast<int32_t>(begin + i);
      n += count;
    }
    std::vector<std::pair<float, int64_t>>& smallest = w.smallest;  // a max-heap by (bound, position)
    smallest.clear();
    for (int64_t i = 0; i < rows; ++i) {
      if (static_cast<int>(smallest.size()) == k && !(lower[i] < smallest.front().first)) continue;
      smallest.emplace_back(lower[i], i);
      std::push_heap(smallest.begin(), smallest.end());
      if (static_cast<int>(smallest.size()) > k) {
        std::pop_heap(smallest.begin(), smallest.end());
        smallest.pop_back();
      }
    }
    std::vector<Ranked>& best = w.ranked;  // a max-heap of the k best by (distance, id)
    best.clear();
    for (const auto& [bound, i] : smallest) {
      const int64_t at = w.scanned[static_cast<size_t>(i)];
      best.push_back({exactWide(descriptor, at), mIds[static_cast<size_t>(at)]});
      std::push_heap(best.begin(), best.end(), before);
      lower[i] = std::numeric_limits<float>::infinity();  // measured
    }
    // The rows still within the k-th best by their first values: their rest keys fetched, then
    // their bounds from the whole key, and those within measured in the order of their bounds, so
    // that the nearest rows come first and the k-th best is tight before the rest are reached.
    std::vector<std::pair<float, int64_t>>& candidates = w.smallest;  // (bound, position), reused
    candidates.clear();
    forEachWithin(lower, rows, best.front().distance, [&](int64_t i) { candidates.emplace_back(0.0f, i); });
    const auto recordOf = [&](size_t c) { return mWideRecords.data() + w.scanned[static_cast<size_t>(candidates[c].second)] * kWideRecord; };
    for (size_t c = 0; c < std::min(candidates.size(), kRecordsAhead); ++c) prefetchBytes(recordOf(c), recordOf(c) + kWideRecord);
    size_t kept = 0;
    for (size_t c = 0; c < candidates.size(); ++c) {
      if (c + kRecordsAhead < candidates.size()) prefetchBytes(recordOf(c + kRecordsAhead), recordOf(c + kRecordsAhead) + kWideRecord);
      const int64_t i = candidates[c].second;
      const int64_t at = w.scanned[static_cast<size_t>(i)];
      const float whole = secondBound(widestLanes(), w.query.data(), q, at, prefixDistance[i]);
      if (whole > best.front().distance) continue;
      candidates[kept++] = {whole, i};
    }
    candidates.resize(kept);
    std::sort(candidates.begin(), candidates.end());
    for (size_t c = 0; c < candidates.size(); ++c) {
      if (candidates[c].first > best.front().distance) break;  // and so are all after it
      const int64_t at = w.scanned[static_cast<size_t>(candidates[c].second)];
      if (c + 1 < candidates.size()) prefetchWide(w.scanned[static_cast<size_t>(candidates[c + 1].second)]);
      const Ranked candidate{exactWide(descriptor, at), mIds[static_cast<size_t>(at)]};
      if (!before(candidate, best.front())) continue;
      std::pop_heap(best.begin(), best.end(), before);
      best.back() = candidate;
      std::push_heap(best.begin(), best.end(), before);
    }
    std::sort_heap(best.begin(), best.end(), before);
    for (int r = 0; r < k; ++r) {
      ids[r] = best[static_cast<size_t>(r)].id;
      squaredDistances[r] = best[static_cast<size_t>(r)].distance;
    }
  }
  // The first bounds of the `count` rows filed from `begin`: their keys' first values' distances
  // to the query's key into `prefix`, and the bounds from them into `lower`.
  void firstBounds(Lanes lanes, const float* key, const WideRest& q, int64_t begin, int64_t count, float* prefix,
                   float* lower) const {
    ivfSquaredDistances(lanes, key, mWidePrefix.data() + begin * kWidePrefixDims, count, kWidePrefixDims, prefix);
    std::copy_n(prefix, count, lower);
    wideLowerBounds(lanes, q.error, q.prefixLow, q.prefixHigh, mWideErrors.data() + begin, mWidePrefixLows.data() + begin,
                    mWidePrefixHighs.data() + begin, count, lower);
  }
  // The second bound of the row filed at `at`, from its whole key: its first values' distance
  // `prefix` (firstBounds') plus its record's rest, and the record's rounding bounds.
  float secondBound(Lanes lanes, const float* key, const WideRest& q, int64_t at, float prefix) const {
    const float* record = mWideRecords.data() + at * kWideRecord;
    float whole = 0.0f;
    ivfSquaredDistances(lanes, key + kWidePrefixDims, record, 1, kWideRestDims, &whole);
    whole += prefix;
    wideLowerBounds(lanes, q.error, q.low, q.high, record + kWideRecordError, record + kWideRecordLow, record + kWideRecordHigh, 1,
                    &whole);
    return whole;
  }

  // Brute force's distance to the row filed at `at`.
  float exactWide(const float* descriptor, int64_t at) const {
    return exactSquaredL2(descriptor, mData + static_cast<int64_t>(mIds[static_cast<size_t>(at)]) * mDims, mDims);
  }
  // The start of that row, asked for while another is measured.
  void prefetchWide(int64_t at) const {
    const float* row = mData + static_cast<int64_t>(mIds[static_cast<size_t>(at)]) * mDims;
    prefetchBytes(row, row + kWideNextPrefetch);
  }

  // A row's key into `key` (mStride floats, zero padded): with a projection, its coordinates along
  // the first mKeyDims principal directions of the centred data, in double, with the norms of the
  // rest and of the whole; without, the row itself.
  // `centred` is scratch (the query's own lease).
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
  int64_t probe(const std::vector<float>& toCentroids, int k, std::vector<int32_t>& best, std::vector<uint64_t>& order) const {
    nearestLists(toCentroids.data(), mLists, mProbes, mProbes <= kInsertedProbes, best, order);
    int64_t held = 0;
    for (int32_t list : best) held += listSize(list);
    if (held >= k) return held;
    nearestLists(toCentroids.data(), mLists, mLists, false, best, order);  // every list, nearest first
    size_t taken = 0;
    for (held = 0; taken < best.size() && held < k; ++taken) held += listSize(best[taken]);
    best.resize(taken);
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
  void file(const std::vector<float>& keys, const std::vector<KeyRest>& rests, const std::vector<WideRest>& wideRests,
            int64_t rows) {
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
    const size_t kept = mWide ? 0 : static_cast<size_t>(rows), wide = mWide ? static_cast<size_t>(rows) : 0;
    mResiduals.resize(kept);
    mNorms.resize(kept);
    mWideErrors.resize(wide);
    mWidePrefixLows.resize(wide);
    mWidePrefixHighs.resize(wide);
    mWidePrefix.resize(wide * kWidePrefixDims);
    mCentroidPrefix.resize(mWide ? static_cast<size_t>(mLists * kWideListDims) : 0);
    for (int64_t c = 0; mWide && c < mLists; ++c) {
      std::copy_n(mCentroids.data() + c * mStride, kWideListDims, mCentroidPrefix.data() + c * kWideListDims);
    }
    mWideRecords.assign(wide * kWideRecord, 0.0f);
    mRows.resize(mWide ? 0 : static_cast<size_t>(rows * mStride));
    for (int64_t r = 0; r < rows; ++r) {
      const int64_t at = next[static_cast<size_t>(listOf[static_cast<size_t>(r)])]++;
      mIds[static_cast<size_t>(at)] = static_cast<int32_t>(r);
      if (mWide) {
        mWideErrors[static_cast<size_t>(at)] = wideRests[static_cast<size_t>(r)].error;
        mWidePrefixLows[static_cast<size_t>(at)] = wideRests[static_cast<size_t>(r)].prefixLow;
        mWidePrefixHighs[static_cast<size_t>(at)] = wideRests[static_cast<size_t>(r)].prefixHigh;
        const float* key = keys.data() + r * mStride;
        std::copy_n(key, kWidePrefixDims, mWidePrefix.data() + at * kWidePrefixDims);
        float* record = mWideRecords.data() + at * kWideRecord;
        std::copy_n(key + kWidePrefixDims, kWideRestDims, record);
        record[kWideRecordError] = wideRests[static_cast<size_t>(r)].error;
        record[kWideRecordLow] = wideRests[static_cast<size_t>(r)].low;
        record[kWideRecordHigh] = wideRests[static_cast<size_t>(r)].high;
        continue;
      }
      mResiduals[static_cast<size_t>(at)] = rests[static_cast<size_t>(r)].residual;
      mNorms[static_cast<size_t>(at)] = rests[static_cast<size_t>(r)].norm;
      std::copy_n(keys.data() + r * mStride, mStride, mRows.data() + at * mStride);
    }
  }

  const float* mData;  // DescriptorIndex's copy, for the exact distances
  int64_t mDims;
  bool mWide;  // more than kMaxProjectedDims values: keyed by WideProjection
  int64_t mKeyDims, mStride;
  int mLists, mProbes;
  std::vector<double> mBasis;      // with a projection: mKeyDims directions of mDims values
  std::vector<double> mBasisAcross;  // the same, value by value: mDims rows of the mKeyDims directions' values
  std::vector<double> mMean;       // with a projection: the sample's mean row
  mutable ScratchPool<Scratch> mScratch;  // a query's working memory, kept for the next
  std::vector<float> mCentroids;   // mLists × mStride keys
  std::vector<float> mRows;        // the rows' keys, padded, list after list
  std::vector<float> mResiduals;   // each filed row's norm outside its key (0 without a projection)
  std::vector<float> mNorms;       // each filed row's centred norm (0 without a projection)
  WideProjection mProjection;      // wide rows: their directions
  std::vector<float> mCentroidPrefix;  // wide rows: each centroid's first kWideListDims values
  std::vector<float> mWidePrefix;   // wide rows: their keys' first kWidePrefixDims values, list after list
  std::vector<float> mWideRecords;  // wide rows: each filed row's record (kWideRecord floats), list after list
  std::vector<float> mWideErrors, mWidePrefixLows, mWidePrefixHighs;  // wide rows: each filed row's WideRest for the first bound
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

void ivfWeightedRowSum(Lanes lanes, const float* rows, const int32_t* index, const float* weights, int64_t count, float* out) {
  if (lanes == Lanes::Wide) {
    weightedRowSumWide(rows, index, weights, count, out);
  } else {
    weightedRowSumNarrow(rows, index, weights, count, out);
  }
}

void ivfNearestLists(const float* distances, int lists, int probes, bool insertion, std::vector<int32_t>& best) {
  std::vector<uint64_t> order;
  nearestLists(distances, lists, probes, insertion, best, order);
}

Status ivfWideBounds(Lanes lanes, const float* data, int64_t rows, int64_t dims, int lists, const float* query,
                     std::vector<float>& first, std::vector<float>& second) {
  if (dims <= kMaxProjectedDims) return invalidArgument("ivfWideBounds: rows of more than 128 values are wide");
  try {
    IvfBackend(data, rows, dims, lists, lists).wideBounds(lanes, query, first, second);
  } catch (const std::exception& e) {
    return invalidArgument(std::string("ivfWideBounds: ") + e.what());
  }
  return Ok{};
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
