// EntryCache.h (private to the runtime): a database entry's connectivity and its basis at another
// Poisson ratio, built once and shared, with the bits of building them each time; and the entries
// of a pack read on demand (EntryReading::OnDemand), read as they are asked for.
#include "EntryCache.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstring>
#include <filesystem>
#include <vector>

#include <oneapi/tbb/parallel_for.h>

#include "brittle/database/Pack.h"
#include "brittle/testing/DatabaseFixtures.h"

namespace brittle::detail {
namespace {

int32_t outsideEntry(const FragmentDatabase& db) { return static_cast<int32_t>(db.entries.size()); }

template <class A, class B>
bool sameBits(const A& a, const B& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(*a.data()) * static_cast<size_t>(a.size())) == 0;
}

// A three-entry database with modes, baked once for the suite, and a pack of it.
class EntryCacheTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto baked = bakeFragmentDatabase(testing::smallDatabaseSettings(3, true));
    ASSERT_TRUE(baked) << baked.error().message;
    sDatabase = new FragmentDatabase(std::move(baked).value());
    Pack pack;
    pack.database = *sDatabase;
    ASSERT_TRUE(writePack(pack, packPath()));
  }
  static std::filesystem::path packPath() {
    static const std::filesystem::path path = testing::makeTempDir("entry-cache") / "db.h5";
    return path;
  }
  static void TearDownTestSuite() {
    delete sDatabase;
    sDatabase = nullptr;
  }
  void SetUp() override { ASSERT_NE(sDatabase, nullptr); }
  static inline FragmentDatabase* sDatabase = nullptr;
  static inline const FragmentDatabase kNone;  // read only if the bake failed, before SetUp stops the test
  const FragmentDatabase& db = sDatabase ? *sDatabase : kNone;
  const double nu = db.referenceMaterial.poissonRatio + 0.05;  // another ν than the database's
};

TEST_F(EntryCacheTest, BuildsEachEntrysDataOnceWithTheBitsOfBuildingItEachTime) {
  ASSERT_GE(db.entries.size(), 2u);
  EntryCache cache(db);
  EXPECT_EQ(cache.built(), 0);

  // Asked for from many tasks at once: one build per (entry) and per (entry, ν), one object each.
  std::vector<std::shared_ptr<const Result<TetTopology>>> topologies(64);
  std::vector<std::shared_ptr<const Result<EntryAtPoisson>>> bases(64);
  tbb::parallel_for(0, 64, [&](int i) {
    topologies[static_cast<size_t>(i)] = cache.topology(i % 2);
    bases[static_cast<size_t>(i)] = cache.atPoisson(i % 2, nu);
  });
  for (size_t i = 2; i < 64; ++i) {
    EXPECT_EQ(topologies[i], topologies[i % 2]);
    EXPECT_EQ(bases[i], bases[i % 2]);
  }
  EXPECT_EQ(cache.built(), 4);
  for (int32_t e : {0, 1}) {
    SCOPED_TRACE(e);
    const FragmentEntry& entry = db.entries[static_cast<size_t>(e)];
    const Result<TetTopology>& topology = *cache.topology(e);
    ASSERT_TRUE(topology) << topology.error().message;
    const TetTopology direct = buildTetTopology(entry.asset.tetMesh).value();
    EXPECT_EQ(topology.value().edges, direct.edges);
    EXPECT_EQ(topology.value().neighbours, direct.neighbours);
    EXPECT_TRUE(sameBits(topology.value().tetVolumesM3, direct.tetVolumesM3));
    const Result<EntryAtPoisson>& basis = *cache.atPoisson(e, nu);
    ASSERT_TRUE(basis) << basis.error().message;
    const EntryAtPoisson own = entryAtPoisson(entry, db.referenceMaterial, nu).value();
    EXPECT_EQ(basis.value().poissonRatio, nu);
    EXPECT_TRUE(sameBits(basis.value().modal.modes, own.modal.modes));
    EXPECT_TRUE(sameBits(basis.value().modal.eigenvaluesRad2PerS2, own.modal.eigenvaluesRad2PerS2));
    EXPECT_TRUE(sameBits(basis.value().stressModes, own.stressModes));
  }
  EXPECT_EQ(cache.built(), 4);  // the checks above were served from the cache
  // Another ν is another basis.
  ASSERT_TRUE(*cache.atPoisson(0, nu + 0.05));
  EXPECT_NE(cache.atPoisson(0, nu + 0.05), bases[0]);
  EXPECT_EQ(cache.built(), 5);

  // Placing an entry through the cache is instantiateEntry's placement, bit for bit, at ν₀ (no
  // basis read) and at another ν (the cached basis); it builds nothing new for a basis it has.
  CanonicalFrame frame;
  frame.rotation = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, -1.0, 0.2).normalized()).toRotationMatrix();
  frame.translationM = Eigen::Vector3d(0.2, -0.1, 0.7);
  frame.scalePerM = 1.0 / 0.08;
  Material other = db.referenceMaterial;
  other.name = "other-nu";
  other.poissonRatio = nu;
  for (const Material& target : {db.referenceMaterial, other}) {
    SCOPED_TRACE(target.name);
    auto placed = cache.place(1, target, frame);
    auto direct = instantiateEntry(db.entries[1], db.referenceMaterial, target, frame);
    ASSERT_TRUE(placed && direct);
    EXPECT_TRUE(sameBits(placed.value().modal.modes, direct.value().modal.modes));
    EXPECT_TRUE(sameBits(placed.value().stressModes, direct.value().stressModes));
    EXPECT_TRUE(sameBits(placed.value().tetMesh.nodes, direct.value().tetMesh.nodes));
  }
  EXPECT_EQ(cache.built(), 5);
  EXPECT_EQ(cache.place(outsideEntry(db), other, frame).error().code, ErrorCode::InvalidArgument);

  // Typed errors, kept as the slot's answer: an entry out of range, a ν no material can have.
  const auto outside = static_cast<int32_t>(db.entries.size());
  EXPECT_EQ(cache.topology(outside)->error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(cache.atPoisson(-1, nu)->error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(cache.atPoisson(0, 0.5)->error().code, ErrorCode::InvalidMaterial);
  EXPECT_EQ(cache.atPoisson(0, 0.5), cache.atPoisson(0, 0.5));
}

// Bounded, the cache drops the least recently asked-for entry: what a worker still holds stays
// valid, and an entry asked for again is built again, to the same bits.
TEST_F(EntryCacheTest, KeepsTheMostRecentlyUsedEntriesUpToItsCapacity) {
  ASSERT_EQ(db.entries.size(), 3u);
  EntryCache cache(db, 2);
  const auto first = cache.atPoisson(0, nu);
  ASSERT_TRUE(*first);
  (void)cache.atPoisson(1, nu);
  (void)cache.atPoisson(0, nu);  // 0 is now more recent than 1
  EXPECT_EQ(cache.built(), 2);
  (void)cache.atPoisson(2, nu);  // drops 1, the least recent
  EXPECT_EQ(cache.built(), 3);
  EXPECT_EQ(cache.held(), 2u);
  EXPECT_EQ(cache.atPoisson(0, nu), first);  // kept: the same object, nothing built
  EXPECT_EQ(cache.built(), 3);
  const auto again = cache.atPoisson(1, nu);  // dropped: built again (and 2 dropped)
  EXPECT_EQ(cache.built(), 4);
  const EntryAtPoisson own = entryAtPoisson(db.entries[1], db.referenceMaterial, nu).value();
  ASSERT_TRUE(*again);
  EXPECT_TRUE(sameBits(again->value().modal.modes, own.modal.modes));
  EXPECT_TRUE(sameBits(again->value().stressModes, own.stressModes));
  // A value dropped while held lives on with its holder.
  for (int32_t e : {2, 1, 2}) (void)cache.atPoisson(e, nu);  // 2 built again, dropping 0
  EXPECT_EQ(cache.built(), 5);
  EXPECT_EQ(cache.held(), 2u);
  EXPECT_TRUE(sameBits(first->value().modal.modes, entryAtPoisson(db.entries[0], db.referenceMaterial, nu).value().modal.modes));
  // Topologies are kept under the same bound, separately.
  for (int32_t e : {0, 1, 2}) ASSERT_TRUE(*cache.topology(e));
  EXPECT_EQ(cache.held(), 4u);
}

// A pack read on demand holds every entry's small fields and no arrays; each entry read from it
// equals the whole read's, bit for bit, and so does everything the cache derives from it.
TEST_F(EntryCacheTest, EntriesReadOnDemandAreTheEntriesOfAWholeRead) {
  auto whole = readPack(packPath());
  auto lazy = readPack(packPath(), EntryReading::OnDemand);
  ASSERT_TRUE(whole && lazy);
  const FragmentDatabase& a = whole.value().database;
  const FragmentDatabase& b = lazy.value().database;
  EXPECT_EQ(a.entrySource, nullptr);
  ASSERT_NE(b.entrySource, nullptr);
  ASSERT_EQ(a.entries.size(), b.entries.size());
  EXPECT_TRUE(a.hasPhysics());
  EXPECT_TRUE(b.hasPhysics());
  for (DescriptorKind kind : kAllDescriptorKinds) {  // read when an index is built over them
    EXPECT_EQ(b.descriptorsOf(kind).size(), 0);
    auto read = b.entrySource->descriptors(kind);
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read.value(), a.descriptorsOf(kind));
  }
  for (size_t i = 0; i < a.entries.size(); ++i) {
    SCOPED_TRACE(i);
    const FragmentEntry& w = a.entries[i];
    const FragmentEntry& skeleton = b.entries[i];
    EXPECT_EQ(skeleton.asset.name, w.asset.name);
    EXPECT_TRUE(sameBits(skeleton.asset.modal.frequenciesHz, w.asset.modal.frequenciesHz));
    EXPECT_EQ(skeleton.asset.massProperties.massKg, w.asset.massProperties.massKg);
    EXPECT_EQ(skeleton.asset.tetMesh.tets.rows(), 0);  // the arrays stay in the file
    EXPECT_EQ(skeleton.asset.stressModes.size(), 0);
    EXPECT_EQ(b.entrySource->tetCount(static_cast<int64_t>(i)), w.asset.tetMesh.tets.rows());
    auto read = b.entrySource->load(static_cast<int64_t>(i));
    ASSERT_TRUE(read) << read.error().message;
    const FragmentEntry& e = read.value();
    EXPECT_EQ(e.asset.name, w.asset.name);
    EXPECT_EQ(e.asset.elementOrder, w.asset.elementOrder);
    EXPECT_TRUE(sameBits(e.asset.tetMesh.nodes, w.asset.tetMesh.nodes));
    EXPECT_EQ(e.asset.tetMesh.tets, w.asset.tetMesh.tets);
    EXPECT_EQ(e.asset.surfaceFaces, w.asset.surfaceFaces);
    EXPECT_TRUE(sameBits(e.asset.modal.modes, w.asset.modal.modes));
    EXPECT_TRUE(sameBits(e.asset.modal.eigenvaluesRad2PerS2, w.asset.modal.eigenvaluesRad2PerS2));
    EXPECT_TRUE(sameBits(e.asset.stressModes, w.asset.stressModes));
    EXPECT_EQ(e.asset.eliminationOrder, w.asset.eliminationOrder);
    EXPECT_TRUE(sameBits(e.surface.vertices, w.surface.vertices));
    EXPECT_EQ(e.surface.faces, w.surface.faces);
    EXPECT_EQ(e.seed, w.seed);
    EXPECT_EQ(e.baseShape, w.baseShape);
  }
  // Read from many workers at once (HDF5 serialises its calls): the same bits every time.
  std::vector<Result<FragmentEntry>> reads(48, makeError(ErrorCode::InvalidArgument, "not read"));
  tbb::parallel_for(0, 48, [&](int k) { reads[static_cast<size_t>(k)] = b.entrySource->load(k % 3); });
  for (size_t k = 0; k < reads.size(); ++k) {
    ASSERT_TRUE(reads[k]) << reads[k].error().message;
    EXPECT_TRUE(sameBits(reads[k].value().asset.stressModes, a.entries[k % 3].asset.stressModes));
    EXPECT_TRUE(sameBits(reads[k].value().surface.vertices, a.entries[k % 3].surface.vertices));
  }
  EXPECT_EQ(b.entrySource->load(-1).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(b.entrySource->load(static_cast<int64_t>(b.entries.size())).error().code, ErrorCode::InvalidArgument);

  // The cache reads each entry once while it keeps it, and places it to the bits of the whole read.
  EntryCache fromWhole(a), onDemand(b, 2);
  CanonicalFrame frame;
  frame.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 0.2, -0.4).normalized()).toRotationMatrix();
  frame.scalePerM = 1.0 / 0.05;
  Material other = a.referenceMaterial;
  other.name = "other-nu";
  other.poissonRatio = nu;
  for (int32_t entry : {0, 1, 0, 2, 0}) {
    auto expected = fromWhole.place(entry, other, frame);
    auto placed = onDemand.place(entry, other, frame);
    ASSERT_TRUE(expected && placed) << (placed ? expected.error().message : placed.error().message);
    EXPECT_TRUE(sameBits(placed.value().modal.modes, expected.value().modal.modes));
    EXPECT_TRUE(sameBits(placed.value().stressModes, expected.value().stressModes));
    EXPECT_TRUE(sameBits(placed.value().tetMesh.nodes, expected.value().tetMesh.nodes));
    EXPECT_EQ(onDemand.topology(entry)->value().edges, fromWhole.topology(entry)->value().edges);
  }
  EXPECT_EQ(onDemand.entriesRead(), 3);  // 0 kept throughout (the most recent), 1 dropped for 2
  EXPECT_EQ(onDemand.entriesHeld(), 2u);
  EXPECT_EQ(fromWhole.entriesRead(), 0);
  EXPECT_EQ(onDemand.place(3, other, frame).error().code, ErrorCode::InvalidArgument);

  // Such a database is not all in memory: writing it is refused, and nothing is written.
  const auto copy = packPath().parent_path() / "rewritten.h5";
  auto written = writePack(lazy.value(), copy);
  ASSERT_FALSE(written);
  EXPECT_EQ(written.error().code, ErrorCode::InvalidArgument);
  EXPECT_FALSE(std::filesystem::exists(copy));
}

// Entries' arrays are stored in small chunks (PackWriter.cpp), so one entry's bytes can be damaged
// alone: a whole read refuses the pack, a read on demand finds it when that entry is read, as a
// typed error of that entry, and reads the others.
TEST_F(EntryCacheTest, ADamagedEntryIsAnErrorWhenItIsReadAndOnlyThen) {
  const auto path = packPath().parent_path() / "damaged.h5";
  std::filesystem::copy_file(packPath(), path, std::filesystem::copy_options::overwrite_existing);
  const uint64_t chunk = testing::chunkRows(path, "/database/entries/stress_modes");
  EXPECT_GT(chunk, 0u);
  EXPECT_LE(chunk * sizeof(double), 32u * 1024u);  // a small entry spans a few chunks
  const auto first = testing::stressChunkInsideEntry(db, 1, chunk);
  ASSERT_TRUE(first) << "entry 1 spans no whole chunk";
  ASSERT_TRUE(testing::damageChunk(path, "/database/entries/stress_modes", *first));
  auto whole = readPack(path);
  ASSERT_FALSE(whole);
  EXPECT_EQ(whole.error().code, ErrorCode::PackCorrupt);
  auto lazy = readPack(path, EntryReading::OnDemand);
  ASSERT_TRUE(lazy) << lazy.error().message;
  const FragmentDatabase& damaged = lazy.value().database;
  EXPECT_TRUE(damaged.entrySource->load(0));
  EXPECT_TRUE(damaged.entrySource->load(2));
  auto bad = damaged.entrySource->load(1);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().code, ErrorCode::PackCorrupt);
  EXPECT_NE(bad.error().message.find("/database/entries/stress_modes"), std::string::npos) << bad.error().message;
  EntryCache cache(damaged);
  EXPECT_EQ(cache.place(1, damaged.referenceMaterial, CanonicalFrame{}).error().code, ErrorCode::PackCorrupt);
  EXPECT_EQ(cache.topology(1)->error().code, ErrorCode::PackCorrupt);
  EXPECT_TRUE(cache.place(0, damaged.referenceMaterial, CanonicalFrame{}));
}

}  // namespace
}  // namespace brittle::detail
