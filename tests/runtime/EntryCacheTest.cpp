// EntryCache.h (private to the runtime): a database entry's connectivity and its basis at another
// Poisson ratio, built once and shared, with the bits of building them each time.
#include "EntryCache.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstring>
#include <vector>

#include <oneapi/tbb/parallel_for.h>

#include "brittle/testing/DatabaseFixtures.h"

namespace brittle::detail {
namespace {

int32_t outsideEntry(const FragmentDatabase& db) { return static_cast<int32_t>(db.entries.size()); }

template <class A, class B>
bool sameBits(const A& a, const B& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(*a.data()) * static_cast<size_t>(a.size())) == 0;
}

// A three-entry database with modes, baked once for the suite.
class EntryCacheTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto baked = bakeFragmentDatabase(testing::smallDatabaseSettings(3, true));
    ASSERT_TRUE(baked) << baked.error().message;
    sDatabase = new FragmentDatabase(std::move(baked).value());
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

}  // namespace
}  // namespace brittle::detail
