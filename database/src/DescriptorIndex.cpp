// DescriptorIndex.cpp — validation, brute force, and the dispatch to the library backends
// (IndexBackends.h).
#include "brittle/database/DescriptorIndex.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>

#include <stdexcept>

#include <Eigen/Eigenvalues>
#if defined(__SSE2__)
#include <emmintrin.h>
#if defined(__x86_64__)
#include <cpuid.h>
#include <immintrin.h>
#endif
#endif

#include "IndexBackends.h"
#include "brittle/core/Simd.h"

namespace brittle {

namespace search {

// k is small, so insertion sort.
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

namespace {

// Where a per-value check must start: the first block of values (eight to an AVX register, four
// to an SSE2 one) not all of which pass `test`, or the last values short of a block. The checks of a
// 4096-value voxel query then cost a compare per block instead of a branch per value; the scalar
// check from there finds and names the value. Without SSE2, 0: every value is checked one by one.
enum class BlockTest { Finite, ZeroOrOne };
#if defined(__x86_64__)
BRITTLE_TARGET_AVX int64_t leadingWideBlocksPassing(const float* values, int64_t count, BlockTest test) {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  int64_t c = 0;
  if (test == BlockTest::Finite) {
    // v · 0 = 0: finite (an ordered compare: NaN fails)
    while (c + 8 <= count && _mm256_movemask_ps(_mm256_cmp_ps(_mm256_mul_ps(_mm256_loadu_ps(values + c), zero), zero, _CMP_EQ_OQ)) == 0xff) c += 8;
  } else {
    while (c + 8 <= count) {
      const __m256 v = _mm256_loadu_ps(values + c);
      if (_mm256_movemask_ps(_mm256_or_ps(_mm256_cmp_ps(v, zero, _CMP_EQ_OQ), _mm256_cmp_ps(v, one, _CMP_EQ_OQ))) != 0xff) break;
      c += 8;
    }
  }
  return c;
}
#endif
int64_t leadingBlocksPassing([[maybe_unused]] const float* values, [[maybe_unused]] int64_t count,
                             [[maybe_unused]] BlockTest test) {
  int64_t c = 0;
#if defined(__x86_64__)
  if (widestLanes() == Lanes::Wide) c = leadingWideBlocksPassing(values, count, test);
#endif
#if defined(__SSE2__)
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
  const auto passes = [&](__m128 v) {
    const __m128 lanes = test == BlockTest::Finite ? _mm_cmpeq_ps(_mm_mul_ps(v, zero), zero)  // v · 0 = 0: finite
                                                   : _mm_or_ps(_mm_cmpeq_ps(v, zero), _mm_cmpeq_ps(v, one));
    return _mm_movemask_ps(lanes) == 0xF;
  };
  while (c + 4 <= count && passes(_mm_loadu_ps(values + c))) c += 4;
#endif
  return c;
}

}  // namespace

Status checkZeroOne(const float* values, int64_t rows, int64_t dims, bool isQuery) {
  for (int64_t r = 0; r < rows; ++r) {
    const float* row = values + r * dims;
    for (int64_t c = leadingBlocksPassing(row, dims, BlockTest::ZeroOrOne); c < dims; ++c) {
      const float v = row[c];
      if (v != 0.0f && v != 1.0f) {
        return invalidArgument(std::string("DescriptorIndex") + (isQuery ? " query" : "") +
                               ": binary indexes take 0/1 descriptors (the voxel kind); " +
                               (isQuery ? std::string() : "row " + std::to_string(r) + ", ") + "column " +
                               std::to_string(c) + " is " + std::to_string(v));
      }
    }
  }
  return Ok{};
}

int64_t codeBytes(int64_t dims, int64_t wordBytes) { return (dims + 8 * wordBytes - 1) / (8 * wordBytes) * wordBytes; }

#if defined(__x86_64__)
namespace {
// code[i] ← the bits (value ≠ 0) of values [8i, 8i + 8), for the whole bytes of `dims`; returns
// where they end. The same bits as the loops in packBits.
BRITTLE_TARGET_AVX int64_t packWideBytes(const float* row, int64_t dims, uint8_t* code) {
  const __m256 zero = _mm256_setzero_ps();
  int64_t c = 0;
  for (; c + 8 <= dims; c += 8) code[c / 8] = static_cast<uint8_t>(_mm256_movemask_ps(_mm256_cmp_ps(_mm256_loadu_ps(row + c), zero, _CMP_NEQ_UQ)));
  return c;
}
}  // namespace
#endif

void packBits(const float* values, int64_t rows, int64_t dims, int64_t wordBytes, uint8_t* codes) {
  const int64_t bytes = codeBytes(dims, wordBytes);
  std::fill(codes, codes + rows * bytes, uint8_t{0});
  for (int64_t r = 0; r < rows; ++r) {
    const float* row = values + r * dims;
    uint8_t* code = codes + r * bytes;
    int64_t c = 0;
#if defined(__x86_64__)
    if (widestLanes() == Lanes::Wide) c = packWideBytes(row, dims, code);
#endif
#if defined(__SSE2__)
    // A byte from eight compares' signs (the same test as below: value ≠ 0).
    const __m128 zero = _mm_setzero_ps();
    for (; c + 8 <= dims; c += 8) {
      const int low = _mm_movemask_ps(_mm_cmpneq_ps(_mm_loadu_ps(row + c), zero));
      const int high = _mm_movemask_ps(_mm_cmpneq_ps(_mm_loadu_ps(row + c + 4), zero));
      code[c / 8] = static_cast<uint8_t>(low | (high << 4));
    }
#endif
    for (; c < dims; ++c) {
      if (row[c] != 0.0f) code[c / 8] |= static_cast<uint8_t>(1u << (c % 8));
    }
  }
}

namespace {

bool pextRunsFast() {
#if defined(__x86_64__)
  static const bool fast = [] {
    if (!__builtin_cpu_supports("bmi2")) return false;
    if (!__builtin_cpu_is("amd")) return true;
    unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
    if (!__get_cpuid(1, &eax, &ebx, &ecx, &edx)) return false;
    const unsigned family = ((eax >> 8) & 0xfu) + ((eax >> 20) & 0xffu);
    return family >= 0x19;  // Zen 3 and later run pext in hardware
  }();
  return fast;
#else
  return false;
#endif
}

#if defined(__x86_64__)
__attribute__((target("bmi2,popcnt"))) void gatherBitsPext(const uint64_t* in, const uint64_t* mask, size_t words, uint64_t* out) {
  size_t at = 0;
  for (size_t w = 0; w < words; ++w) {
    if (mask[w] == 0) continue;
    const uint64_t bits = _pext_u64(in[w], mask[w]);
    const auto count = static_cast<size_t>(_mm_popcnt_u64(mask[w]));
    out[at / 64] |= bits << (at % 64);
    if (at % 64 + count > 64) out[at / 64 + 1] |= bits >> (64 - at % 64);
    at += count;
  }
}
#endif

}  // namespace

void gatherBits(const uint64_t* in, const uint64_t* mask, size_t words, uint64_t* out, size_t outWords) {
  std::fill(out, out + outWords, uint64_t{0});
#if defined(__x86_64__)
  if (pextRunsFast()) return gatherBitsPext(in, mask, words, out);
#endif
  size_t at = 0;
  for (size_t w = 0; w < words; ++w) {
    for (uint64_t m = mask[w]; m != 0; m &= m - 1, ++at) {
      out[at / 64] |= ((in[w] >> __builtin_ctzll(m)) & 1u) << (at % 64);
    }
  }
}

VaryingColumns::VaryingColumns(const float* data, int64_t rows, int64_t dims)
    : mDims(dims), mConstant(static_cast<size_t>(codeBytes(dims, 8) / 8), 0), mOutside(mConstant.size(), ~uint64_t{0}) {
  // A column varies where some row's code differs from the first's.
  std::vector<uint64_t> code(mConstant.size()), differ(mConstant.size(), 0);
  if (rows > 0) packBits(data, 1, dims, 8, reinterpret_cast<uint8_t*>(mConstant.data()));
  for (int64_t r = 1; r < rows; ++r) {
    packBits(data + r * dims, 1, dims, 8, reinterpret_cast<uint8_t*>(code.data()));
    for (size_t w = 0; w < code.size(); ++w) differ[w] |= code[w] ^ mConstant[w];
  }
  for (size_t j = 0; j < differ.size() * 64; ++j) {
    if ((differ[j / 64] >> (j % 64)) & 1u) mColumns.push_back(static_cast<int32_t>(j));
  }
  mInside = differ;
  for (size_t w = 0; w < differ.size(); ++w) mOutside[w] = ~differ[w];
}

namespace {
// The bits where a and b differ within `mask`: one popcnt instruction a word where the CPU has it,
// else libgcc's loop. The same count either way.
#if defined(__x86_64__)
__attribute__((target("popcnt"))) int maskedDifferencesPopcnt(const uint64_t* a, const uint64_t* b, const uint64_t* mask, size_t words) {
  int64_t count = 0;
  for (size_t w = 0; w < words; ++w) count += _mm_popcnt_u64((a[w] ^ b[w]) & mask[w]);
  return static_cast<int>(count);
}
#endif
int maskedDifferences(const uint64_t* a, const uint64_t* b, const uint64_t* mask, size_t words) {
#if defined(__x86_64__)
  if (fastestPopcount() != Popcount::Portable) return maskedDifferencesPopcnt(a, b, mask, words);
#endif
  int count = 0;
  for (size_t w = 0; w < words; ++w) count += __builtin_popcountll((a[w] ^ b[w]) & mask[w]);
  return count;
}
}  // namespace

int VaryingColumns::code(const float* row, uint64_t* full, uint64_t* code) const {
  packBits(row, 1, mDims, 8, reinterpret_cast<uint8_t*>(full));
  gatherBits(full, mInside.data(), mInside.size(), code, words());
  return maskedDifferences(full, mConstant.data(), mOutside.data(), mOutside.size());
}

PrincipalAxes principalAxes(const Eigen::MatrixXd& points) {
  const Eigen::Index n = points.rows(), samples = points.cols();
  PrincipalAxes out;
  out.mean = points.rowwise().sum() / static_cast<double>(samples);
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < samples; ++i) {
    const Eigen::VectorXd c = points.col(i) - out.mean;
    for (Eigen::Index j = 0; j < n; ++j) covariance.col(j) += c[j] * c;  // element by element, in sample order
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(covariance);
  if (solver.info() != Eigen::Success) throw std::runtime_error("the principal directions did not converge");
  out.axes = solver.eigenvectors().rowwise().reverse();  // eigenvalues ascending: reversed, largest first
  return out;
}

}  // namespace search

DescriptorIndex::DescriptorIndex(DescriptorIndex&&) noexcept = default;
DescriptorIndex& DescriptorIndex::operator=(DescriptorIndex&&) noexcept = default;
DescriptorIndex::~DescriptorIndex() = default;

const char* descriptorIndexKindName(DescriptorIndexSettings::Kind kind) {
  switch (kind) {
    case DescriptorIndexSettings::Kind::BruteForce: return "brute-force";
    case DescriptorIndexSettings::Kind::KdForest: return "kd-forest";
    case DescriptorIndexSettings::Kind::Autotuned: return "autotuned";
    case DescriptorIndexSettings::Kind::Hnsw: return "hnsw";
    case DescriptorIndexSettings::Kind::HnswBinary: return "hnsw-binary";
    case DescriptorIndexSettings::Kind::HnswPooled: return "hnsw-pooled";
    case DescriptorIndexSettings::Kind::HnswPrincipal: return "hnsw-principal";
    case DescriptorIndexSettings::Kind::Ivf: return "ivf";
    case DescriptorIndexSettings::Kind::IvfBinary: return "ivf-binary";
    case DescriptorIndexSettings::Kind::FaissHnsw: return "faiss-hnsw";
    case DescriptorIndexSettings::Kind::FaissIvf: return "faiss-ivf";
    case DescriptorIndexSettings::Kind::FaissBinaryFlat: return "faiss-binary-flat";
    case DescriptorIndexSettings::Kind::FaissBinaryHnsw: return "faiss-binary-hnsw";
  }
  return "unknown";
}

Result<DescriptorIndexSettings::Kind> parseDescriptorIndexKind(std::string_view name) {
  using Kind = DescriptorIndexSettings::Kind;
  std::string names;
  for (Kind kind : kAllDescriptorIndexKinds) {
    if (name == descriptorIndexKindName(kind)) return kind;
    names += std::string(names.empty() ? "" : ", ") + descriptorIndexKindName(kind);
  }
  return makeError(ErrorCode::InvalidArgument, "unknown index backend '" + std::string(name) + "' (expected one of " + names + ")");
}

std::string describeIndexSettings(const DescriptorIndexSettings& settings) {
  using Kind = DescriptorIndexSettings::Kind;
  const std::string name = descriptorIndexKindName(settings.kind);
  if (settings.kind == Kind::BruteForce || settings.kind == Kind::FaissBinaryFlat) return name;
  if (settings.kind == Kind::Autotuned) {
    char precision[32];
    std::snprintf(precision, sizeof precision, ":%g", static_cast<double>(settings.targetPrecision));
    return name + precision;
  }
  return name + ":" + std::to_string(settings.trees) + ":" + std::to_string(settings.checks);
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
  for (int64_t r = 0; r < rows; ++r) {
    for (int64_t c = 0; c < dims; ++c) {
      if (!std::isfinite(data[r * dims + c]))
        return invalidArgument("DescriptorIndex: non-finite value in data at row " + std::to_string(r) +
                       ", column " + std::to_string(c));
    }
  }

  DescriptorIndex result;
  result.mSettings = settings;
  result.mRows = rows;
  result.mDims = dims;
  try {
    result.mData.assign(data, data + rows * dims);
  } catch (const std::bad_alloc&) {
    return invalidArgument("DescriptorIndex: no memory for " + std::to_string(rows) + " x " + std::to_string(dims) + " floats");
  }
  // mData's buffer never moves after this point (a moved std::vector keeps its buffer), so a
  // backend may keep pointers into it.
  Result<std::unique_ptr<search::Backend>> backend = std::unique_ptr<search::Backend>();
  switch (settings.kind) {
    case Kind::BruteForce: break;
    case Kind::KdForest:
    case Kind::Autotuned: backend = search::buildFlann(result.mData.data(), rows, dims, settings); break;
    case Kind::Hnsw:
    case Kind::HnswBinary:
    case Kind::HnswPooled:
    case Kind::HnswPrincipal: backend = search::buildHnsw(result.mData.data(), rows, dims, settings); break;
    case Kind::Ivf: backend = search::buildIvf(result.mData.data(), rows, dims, settings); break;
    case Kind::IvfBinary: backend = search::buildIvfBinary(result.mData.data(), rows, dims, settings); break;
    case Kind::FaissHnsw:
    case Kind::FaissIvf:
    case Kind::FaissBinaryFlat:
    case Kind::FaissBinaryHnsw: backend = search::buildFaiss(result.mData.data(), rows, dims, settings); break;
  }
  if (!backend) return backend.error();
  result.mBackend = std::move(backend).value();
  return result;
}

int64_t DescriptorIndex::memoryBytes() const {
  return static_cast<int64_t>(mData.size() * sizeof(float)) + (mBackend ? mBackend->memoryBytes() : 0);
}

Result<uint64_t> DescriptorIndex::digest() const {
  Fingerprint f;
  f.add(std::string(descriptorIndexKindName(mSettings.kind)));
  f.add(mSettings.trees, mSettings.checks, mSettings.targetPrecision, mSettings.seed, mRows, mDims);
  f.add(mData);
  if (mBackend) {
    if (Status st = mBackend->addToDigest(f); !st) return st.error();
  }
  return f.value();
}

Status DescriptorIndex::validateQuery(const float* descriptor, int k, int64_t queryRow,
                                      bool batch) const {
  if (descriptor == nullptr) return invalidArgument("DescriptorIndex query: descriptor is null");
  if (k < 1) return invalidArgument("DescriptorIndex query: k must be >= 1, got " + std::to_string(k));
  if (k > mRows)
    return invalidArgument("DescriptorIndex query: k = " + std::to_string(k) + " exceeds the " +
                   std::to_string(mRows) + " entries");
  // A backend's own check that implies finite values runs first: when it passes, the finite check
  // is not repeated; when it fails, the finite check names a non-finite value first, as always.
  if (mBackend && mBackend->validatesFiniteValues() && mBackend->validateQuery(descriptor, mDims)) return Ok{};
  for (int64_t c = search::leadingBlocksPassing(descriptor, mDims, search::BlockTest::Finite); c < mDims; ++c) {
    if (!std::isfinite(descriptor[c]))
      return invalidArgument("DescriptorIndex query: non-finite value " +
                     (batch ? "at query row " + std::to_string(queryRow) + ", " : std::string("at ")) +
                     "column " + std::to_string(c));
  }
  return mBackend ? mBackend->validateQuery(descriptor, mDims) : Status(Ok{});
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
  if (mBackend) return mBackend->query(descriptor, k, ids, squaredDistances);
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

Status DescriptorIndex::queryNearestOfSet(const float* descriptors, int64_t count, int k, int64_t* ids,
                                          float* squaredDistances, int32_t* rows, bool eachRow) const {
  if (descriptors == nullptr) return invalidArgument("DescriptorIndex queryNearestOfSet: descriptors is null");
  if (ids == nullptr || squaredDistances == nullptr || rows == nullptr)
    return invalidArgument("DescriptorIndex queryNearestOfSet: ids, squaredDistances or rows is null");
  if (count < 1)
    return invalidArgument("DescriptorIndex queryNearestOfSet: count must be >= 1, got " + std::to_string(count));
  for (int64_t q = 0; q < count; ++q) {
    if (Status valid = validateQuery(descriptors + q * mDims, k, q, true); !valid) return valid;
  }
  if (!eachRow && mBackend && mBackend->searchesSets()) return mBackend->querySet(descriptors, count, k, ids, squaredDistances, rows);
  // Each row's k nearest, merged: the best distance per entry, ordered by (distance, id); a stable
  // sort keeps rows in order, so an entry's first hit is from the lowest row reaching it.
  struct Hit {
    float distance;
    int64_t id;
    int32_t row;
  };
  std::vector<int64_t> rowIds(static_cast<size_t>(k));
  std::vector<float> rowDistances(static_cast<size_t>(k));
  std::vector<Hit> hits;
  hits.reserve(static_cast<size_t>(count * k));
  for (int64_t q = 0; q < count; ++q) {
    if (Status st = queryBackend(descriptors + q * mDims, k, rowIds.data(), rowDistances.data()); !st) return st;
    for (int j = 0; j < k; ++j) hits.push_back({rowDistances[static_cast<size_t>(j)], rowIds[static_cast<size_t>(j)], static_cast<int32_t>(q)});
  }
  std::stable_sort(hits.begin(), hits.end(), [](const Hit& a, const Hit& b) {
    return a.distance != b.distance ? a.distance < b.distance : a.id < b.id;
  });
  int filled = 0;
  for (const Hit& h : hits) {
    if (filled == k) break;
    if (std::find(ids, ids + filled, h.id) != ids + filled) continue;
    ids[filled] = h.id;
    squaredDistances[filled] = h.distance;
    rows[filled] = h.row;
    ++filled;
  }
  return Ok{};  // row 0 alone holds k distinct entries
}

void DescriptorIndex::queryBruteForce(const float* descriptor, int k, int64_t* ids,
                                      float* squaredDistances) const {
  // Keeps the best k so far, sorted by (distance, id), in the caller's arrays. Rows are scanned
  // in increasing id, so a later row only displaces a kept one on a strictly smaller distance:
  // that is what makes ties go to the lower id.
  int filled = 0;
  for (int64_t r = 0; r < mRows; ++r) {
    // Double accumulation: the reference should not lose digits to rounding.
    const float d = search::exactSquaredL2(mData.data() + r * mDims, descriptor, mDims);
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

}  // namespace brittle
