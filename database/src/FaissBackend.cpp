// FaissBackend.cpp — FAISS (Debian's libfaiss-dev 1.7.3) as the standard baselines beside the
// project's own indexes: HNSW and IVF on floats, flat and HNSW on binary codes.
//
// Reproducible builds. FAISS parallelises add() and k-means with OpenMP; several threads add graph
// links in an order that depends on timing. Builds therefore run on one OpenMP thread, with the
// graph's level draw and the k-means sampling seeded from the settings, which gives the same index
// in any process. Queries also run on one OpenMP thread: a team of threads per single query costs
// more than the query (measured 220 µs against 73 µs at 2·10⁴ entries on two cores), and the caller
// (the World's workers) owns the parallelism. omp_set_num_threads changes the calling thread's own
// setting only, and a guard restores it.
//
// Binary codes (IndexBackends.h): the binary kinds take descriptors whose every value is 0 or 1 (the
// occupancy voxel kind), packed one bit per value with zero padding to a whole byte, and answer in
// the same units as the other backends. Any other value is an InvalidArgument, at build and query.
//
// Debian builds FAISS for generic x86-64: distances run through its scalar reference loops and
// popcount through libgcc, so these are baselines of the library as packaged, not of FAISS at its
// best on this CPU. Queries allocate (FAISS's result heaps and visited tables), as FLANN's do.
#include <cstdint>
#include <exception>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <faiss/IndexBinaryFlat.h>
#include <faiss/IndexBinaryHNSW.h>
#include <faiss/IndexFlat.h>
#include <faiss/IndexHNSW.h>
#include <faiss/IndexIVFFlat.h>
#include <faiss/impl/io.h>
#include <faiss/index_io.h>
#include <omp.h>

#include "IndexBackends.h"

namespace brittle::search {
namespace {

using Kind = DescriptorIndexSettings::Kind;
using FaissId = faiss::Index::idx_t;
static_assert(sizeof(FaissId) == sizeof(int64_t), "FAISS labels are written in place into int64_t ids");

class OneOpenMpThread {
 public:
  OneOpenMpThread() : mPrevious(omp_get_max_threads()) { omp_set_num_threads(1); }
  ~OneOpenMpThread() { omp_set_num_threads(mPrevious); }
  OneOpenMpThread(const OneOpenMpThread&) = delete;
  OneOpenMpThread& operator=(const OneOpenMpThread&) = delete;

 private:
  int mPrevious;
};

class FloatBackend final : public Backend {
 public:
  explicit FloatBackend(std::unique_ptr<faiss::Index> index) : mIndex(std::move(index)) {}

  Status query(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const override {
    try {
      OneOpenMpThread one;
      mIndex->search(1, descriptor, k, squaredDistances, reinterpret_cast<FaissId*>(ids));
    } catch (const std::exception& e) {
      return invalidArgument(std::string("DescriptorIndex query: FAISS search failed: ") + e.what());
    }
    for (int i = 0; i < k; ++i) {  // IVF leaves -1 where its probed lists hold fewer than k rows
      if (ids[i] < 0) return invalidArgument("DescriptorIndex query: FAISS found " + std::to_string(i) + " of " +
                                             std::to_string(k) + " neighbours (probe more lists)");
    }
    sortByDistanceThenId(k, ids, squaredDistances);
    return Ok{};
  }

  int64_t memoryBytes() const override {
    if (const auto* hnsw = dynamic_cast<const faiss::IndexHNSW*>(mIndex.get())) {
      const auto* flat = dynamic_cast<const faiss::IndexFlatCodes*>(hnsw->storage);
      return graphBytes(hnsw->hnsw) + (flat ? static_cast<int64_t>(flat->codes.size()) : 0);
    }
    const auto* ivf = dynamic_cast<const faiss::IndexIVF*>(mIndex.get());
    int64_t bytes = static_cast<int64_t>(ivf->nlist) * ivf->d * static_cast<int64_t>(sizeof(float));
    for (size_t list = 0; list < ivf->nlist; ++list) {
      bytes += static_cast<int64_t>(ivf->invlists->list_size(list) * (ivf->code_size + sizeof(FaissId)));
    }
    return bytes;
  }

  // FAISS's own serialisation, into memory.
  Status addToDigest(Fingerprint& digest) const override {
    try {
      faiss::VectorIOWriter writer;
      faiss::write_index(mIndex.get(), &writer);
      digest.add(writer.data);
    } catch (const std::exception& e) {
      return invalidArgument(std::string("DescriptorIndex digest: FAISS could not write its index: ") + e.what());
    }
    return Ok{};
  }

  static int64_t graphBytes(const faiss::HNSW& g) {
    return static_cast<int64_t>(g.neighbors.size() * sizeof(faiss::HNSW::storage_idx_t) +
                                g.levels.size() * sizeof(int) + g.offsets.size() * sizeof(size_t));
  }

 private:
  std::unique_ptr<faiss::Index> mIndex;
};

class BinaryBackend final : public Backend {
 public:
  BinaryBackend(std::unique_ptr<faiss::IndexBinary> index, int64_t dims) : mIndex(std::move(index)), mDims(dims) {}

  Status validateQuery(const float* descriptor, int64_t dims) const override { return checkZeroOne(descriptor, 1, dims, true); }
  bool validatesFiniteValues() const override { return true; }

  Status query(const float* descriptor, int k, int64_t* ids, float* squaredDistances) const override {
    std::vector<uint8_t> code(static_cast<size_t>(codeBytes(mDims, 1)));
    packBits(descriptor, 1, mDims, 1, code.data());
    std::vector<int32_t> hamming(static_cast<size_t>(k));
    try {
      OneOpenMpThread one;
      mIndex->search(1, code.data(), k, hamming.data(), reinterpret_cast<FaissId*>(ids));
    } catch (const std::exception& e) {
      return invalidArgument(std::string("DescriptorIndex query: FAISS search failed: ") + e.what());
    }
    for (int i = 0; i < k; ++i) {
      if (ids[i] < 0) return invalidArgument("DescriptorIndex query: FAISS found " + std::to_string(i) + " of " +
                                             std::to_string(k) + " neighbours");
      squaredDistances[i] = static_cast<float>(hamming[static_cast<size_t>(i)]);  // exact below 2^24
    }
    sortByDistanceThenId(k, ids, squaredDistances);
    return Ok{};
  }

  Status addToDigest(Fingerprint& digest) const override {
    try {
      faiss::VectorIOWriter writer;
      faiss::write_index_binary(mIndex.get(), &writer);
      digest.add(mDims);
      digest.add(writer.data);
    } catch (const std::exception& e) {
      return invalidArgument(std::string("DescriptorIndex digest: FAISS could not write its index: ") + e.what());
    }
    return Ok{};
  }

  int64_t memoryBytes() const override {
    if (const auto* flat = dynamic_cast<const faiss::IndexBinaryFlat*>(mIndex.get()))
      return static_cast<int64_t>(flat->xb.size());
    const auto* hnsw = dynamic_cast<const faiss::IndexBinaryHNSW*>(mIndex.get());
    const auto* storage = dynamic_cast<const faiss::IndexBinaryFlat*>(hnsw->storage);
    return FloatBackend::graphBytes(hnsw->hnsw) + (storage ? static_cast<int64_t>(storage->xb.size()) : 0);
  }

 private:
  std::unique_ptr<faiss::IndexBinary> mIndex;
  int64_t mDims;
};

Status checkGraphSettings(const DescriptorIndexSettings& s) {
  if (s.trees < 2 || s.trees > 1024)
    return invalidArgument("DescriptorIndex: settings.trees (FAISS HNSW M) must be in [2, 1024], got " + std::to_string(s.trees));
  if (s.checks < 1)
    return invalidArgument("DescriptorIndex: settings.checks (FAISS HNSW efSearch) must be >= 1, got " + std::to_string(s.checks));
  return Ok{};
}

void seedGraph(faiss::HNSW& graph, const DescriptorIndexSettings& s) {
  graph.efConstruction = 200;  // as the hnswlib backend
  graph.efSearch = s.checks;
  graph.rng = faiss::RandomGenerator(static_cast<int64_t>(s.seed & 0x7fffffffffffffffull));
}

Result<std::unique_ptr<Backend>> buildFloat(const float* data, int64_t rows, int64_t dims, const DescriptorIndexSettings& s) {
  const auto d = static_cast<faiss::Index::idx_t>(dims);
  if (s.kind == Kind::FaissHnsw) {
    if (Status st = checkGraphSettings(s); !st) return st.error();
    auto index = std::make_unique<faiss::IndexHNSWFlat>(d, s.trees);
    seedGraph(index->hnsw, s);
    index->add(rows, data);
    return std::unique_ptr<Backend>(std::make_unique<FloatBackend>(std::move(index)));
  }
  if (s.trees < 1 || s.trees > rows)
    return invalidArgument("DescriptorIndex: settings.trees (FAISS IVF lists) must be in [1, rows = " +
                           std::to_string(rows) + "], got " + std::to_string(s.trees));
  if (s.checks < 1 || s.checks > s.trees)
    return invalidArgument("DescriptorIndex: settings.checks (FAISS IVF lists probed) must be in [1, trees], got " +
                           std::to_string(s.checks));
  auto quantizer = std::make_unique<faiss::IndexFlatL2>(d);
  auto index = std::make_unique<faiss::IndexIVFFlat>(quantizer.get(), d, static_cast<size_t>(s.trees), faiss::METRIC_L2);
  quantizer.release();
  index->own_fields = true;
  index->cp.seed = static_cast<int>(s.seed & 0x7fffffff);
  index->cp.min_points_per_centroid = 1;  // fewer than 39 rows a list is allowed (FAISS would warn)
  index->train(rows, data);
  index->add(rows, data);
  index->nprobe = static_cast<size_t>(s.checks);
  return std::unique_ptr<Backend>(std::make_unique<FloatBackend>(std::move(index)));
}

Result<std::unique_ptr<Backend>> buildBinary(const float* data, int64_t rows, int64_t dims, const DescriptorIndexSettings& s) {
  if (Status st = checkZeroOne(data, rows, dims, false); !st) return st.error();
  std::vector<uint8_t> codes(static_cast<size_t>(rows * codeBytes(dims, 1)));
  packBits(data, rows, dims, 1, codes.data());
  const auto bits = static_cast<int>(8 * codeBytes(dims, 1));
  std::unique_ptr<faiss::IndexBinary> index;
  if (s.kind == Kind::FaissBinaryHnsw) {
    if (Status st = checkGraphSettings(s); !st) return st.error();
    auto graph = std::make_unique<faiss::IndexBinaryHNSW>(bits, s.trees);
    seedGraph(graph->hnsw, s);
    index = std::move(graph);
  } else {
    index = std::make_unique<faiss::IndexBinaryFlat>(bits);
  }
  index->add(rows, codes.data());
  return std::unique_ptr<Backend>(std::make_unique<BinaryBackend>(std::move(index), dims));
}

}  // namespace

Result<std::unique_ptr<Backend>> buildFaiss(const float* data, int64_t rows, int64_t dims,
                                            const DescriptorIndexSettings& settings) {
  if (rows > std::numeric_limits<int32_t>::max() || dims > std::numeric_limits<int32_t>::max() - 7)
    return invalidArgument("DescriptorIndex: FAISS backends need rows and dims <= INT32_MAX");
  try {
    OneOpenMpThread one;
    return indexTakesBits(settings.kind) ? buildBinary(data, rows, dims, settings) : buildFloat(data, rows, dims, settings);
  } catch (const std::exception& e) {
    return invalidArgument(std::string("DescriptorIndex: ") + descriptorIndexKindName(settings.kind) +
                           " build failed: " + e.what());
  }
}

}  // namespace brittle::search
