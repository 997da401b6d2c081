// Runtime fracture as the database's second source: base shapes broken by the World, reproducibly.
#include "brittle/precompute/RuntimeFragments.h"

#include <gtest/gtest.h>

#include "brittle/database/Pack.h"
#include "brittle/descriptors/MassProperties.h"
#include "brittle/precompute/MeshValidation.h"
#include "brittle/testing/DatabaseFixtures.h"

namespace brittle {
namespace {

DatabaseBakeSettings runtimeSettings(int64_t entries, double fraction) {
  DatabaseBakeSettings s = testing::smallDatabaseSettings(entries, false);
  s.shapes = selectBaseShapes(s.shapes, {"box", "rod", "blob"}).value();
  s.runtimeFragments.fraction = fraction;
  s.runtimeFragments.targetTets = 1000;
  s.runtimeFragments.modeCount = 12;
  return s;
}

TEST(RuntimeFragments, EntriesAreClosedPiecesOfTheBaseShapesAndReproducible) {
  DatabaseBakeSettings s = runtimeSettings(6, 1.0);
  s.threads = 1;
  auto one = bakeFragmentDatabase(s);
  ASSERT_TRUE(one) << one.error().message;
  s.threads = 2;
  auto two = bakeFragmentDatabase(s);
  ASSERT_TRUE(two) << two.error().message;
  ASSERT_EQ(one.value().entries.size(), 6u);
  for (size_t i = 0; i < 6; ++i) {
    const FragmentEntry& e = one.value().entries[i];
    SCOPED_TRACE(e.asset.name);
    EXPECT_EQ(e.cut.rfind("runtime: ", 0), 0u) << e.cut;
    EXPECT_TRUE(validateSurfaceMesh(e.surface)) << "closed, manifold, outward";
    EXPECT_NEAR(computeSurfaceMassProperties(e.surface, 1.0).volumeM3, 1.0, 1e-9);
    // Not debris (≥ 1 % of the body) and a proper piece (the body broke).
    EXPECT_GE(e.baseVolumeFraction, 0.01 * 0.95);
    EXPECT_LT(e.baseVolumeFraction, 1.0);
    EXPECT_EQ(e.surface.vertices, two.value().entries[i].surface.vertices) << "any thread count, same entry";
  }
  EXPECT_EQ(one.value().descriptorsOf(DescriptorKind::Moment), two.value().descriptorsOf(DescriptorKind::Moment));
}

TEST(RuntimeFragments, FractionPicksAboutThatShareOfEntries) {
  int picked = 0;
  for (int64_t i = 0; i < 20000; ++i) picked += isRuntimeFragmentEntry(fragmentEntrySeed(3, i), 0.3) ? 1 : 0;
  EXPECT_NEAR(picked / 20000.0, 0.3, 0.015);
  EXPECT_FALSE(isRuntimeFragmentEntry(fragmentEntrySeed(3, 0), 0.0));
  EXPECT_TRUE(isRuntimeFragmentEntry(fragmentEntrySeed(3, 0), 1.0));

  // A mixed database has both kinds of entries.
  auto mixed = bakeFragmentDatabase(runtimeSettings(8, 0.5));
  ASSERT_TRUE(mixed) << mixed.error().message;
  int runtime = 0;
  for (const FragmentEntry& e : mixed.value().entries) runtime += e.cut.rfind("runtime: ", 0) == 0 ? 1 : 0;
  EXPECT_GT(runtime, 0);
  EXPECT_LT(runtime, 8);
}

TEST(RuntimeFragments, PiecesOfAnObjectsOwnMeshInQuadraticTets) {
  // A database of the brick's own pieces (a mesh base shape, assets/shapes/default-objects.json),
  // broken off by the runtime, with P2 entries: each entry is a closed piece of the brick whose
  // tets are the ones the runtime cut it out with (they enclose its surface's unit volume), its
  // elements are quadratic, its modes solve, and it survives the pack. The same tets as P1 are
  // stiffer (P1 locks in bending), so their first mode is higher.
  DatabaseBakeSettings s = testing::brickPiecesDatabase(2);
  ASSERT_EQ(s.shapes.size(), 1u);
  auto db = bakeFragmentDatabase(s);
  ASSERT_TRUE(db) << db.error().message;
  ASSERT_EQ(db.value().entries.size(), 2u);
  for (const FragmentEntry& e : db.value().entries) {
    SCOPED_TRACE(e.asset.name);
    EXPECT_EQ(e.baseShape, "brick");
    EXPECT_EQ(e.cut.rfind("runtime: ", 0), 0u) << e.cut;
    EXPECT_TRUE(validateSurfaceMesh(e.surface));
    EXPECT_GT(e.baseVolumeFraction, 0.0);
    EXPECT_LT(e.baseVolumeFraction, 1.0);
    EXPECT_EQ(e.asset.elementOrder, ElementOrder::P2);
    EXPECT_EQ(e.asset.modal.modes.rows(), 3 * femNodeCount(e.asset.tetMesh, ElementOrder::P2));
    EXPECT_EQ(e.asset.stressModes.rows(), 6 * 4 * e.asset.tetMesh.tets.rows());
    EXPECT_LT(e.asset.modal.residuals.maxCoeff(), 1e-8);
    EXPECT_NEAR(e.asset.massProperties.volumeM3, 1.0, 1e-9) << "the runtime's own tets of the unit-volume piece";
    std::array<Descriptor, kDescriptorKindCount> unused;
    DatabaseBakeSettings p1 = s;
    p1.elementOrder = ElementOrder::P1;
    auto linear = bakeFragmentEntry(e.surface, e.asset.name, p1, unused, nullptr, &e.asset.tetMesh);
    ASSERT_TRUE(linear) << linear.error().message;
    EXPECT_EQ(linear.value().asset.tetMesh.tets, e.asset.tetMesh.tets) << "the same tets";
    EXPECT_NEAR(linear.value().asset.massProperties.volumeM3, 1.0, 1e-9);
    EXPECT_GT(linear.value().asset.modal.frequenciesHz[0], e.asset.modal.frequenciesHz[0] * 1.001);
  }
  Pack pack;
  pack.database = db.value();
  const auto path = testing::makeTempDir("runtime-p2") / "db.h5";
  ASSERT_TRUE(writePack(pack, path));
  auto back = readPack(path);
  ASSERT_TRUE(back) << back.error().message;
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back.value().database.entries[i].asset.elementOrder, ElementOrder::P2);
    EXPECT_EQ(back.value().database.entries[i].asset.modal.modes, db.value().entries[i].asset.modal.modes);
  }
}

TEST(RuntimeFragments, BadSettingsGiveTypedErrors) {
  for (auto bad : {-0.1, 1.5}) {
    DatabaseBakeSettings s = runtimeSettings(2, bad);
    auto db = bakeFragmentDatabase(s);
    ASSERT_FALSE(db);
    EXPECT_EQ(db.error().code, ErrorCode::InvalidArgument);
  }
  RuntimeFragmentSettings r;
  r.minSpeedMps = 50.0;
  r.maxSpeedMps = 10.0;
  EXPECT_EQ(validateRuntimeFragmentSettings(r).error().code, ErrorCode::InvalidArgument);
  r = {};
  r.targetTets = 10;
  EXPECT_EQ(validateRuntimeFragmentSettings(r).error().code, ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle
