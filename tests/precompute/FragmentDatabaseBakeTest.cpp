// Baking the fragment database: contents, reproducibility, and the pack schema v2 round trip.
#include "brittle/precompute/FragmentDatabaseBake.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <fstream>
#include <set>

#include "brittle/database/FragmentMatcher.h"
#include "brittle/database/Pack.h"
#include "brittle/precompute/MeshValidation.h"
#include "brittle/precompute/TetMeshQuality.h"
#include "brittle/testing/AssetChecks.h"
#include "brittle/testing/DatabaseFixtures.h"

namespace brittle {
namespace {

class FragmentDatabaseBakeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ASSERT_GE(testing::shippedBaseShapes().size(), 6u);
    auto db = bakeFragmentDatabase(testing::smallDatabaseSettings(8, true));
    ASSERT_TRUE(db) << db.error().message;
    physical = new FragmentDatabase(std::move(db).value());
  }
  static void TearDownTestSuite() { delete physical; }
  static inline FragmentDatabase* physical = nullptr;
  std::filesystem::path dir = testing::makeTempDir("fragdb");
};

TEST_F(FragmentDatabaseBakeTest, EveryEntryIsACanonicalClosedUnitVolumeFragmentWithModes) {
  const FragmentDatabase& db = *physical;
  ASSERT_EQ(db.entries.size(), 8u);
  EXPECT_TRUE(db.hasPhysics());
  std::set<std::string> shapes;
  for (const FragmentEntry& e : db.entries) {
    SCOPED_TRACE(e.asset.name);
    shapes.insert(e.baseShape);
    EXPECT_TRUE(validateSurfaceMesh(e.surface)) << "closed, manifold, outward";
    const MassProperties surface = computeSurfaceMassProperties(e.surface, 1.0);
    EXPECT_NEAR(surface.volumeM3, 1.0, 1e-9);
    EXPECT_LT(surface.centerOfMassM.norm(), 1e-9);
    // Principal axes, ascending, unless two principal moments are within the ambiguity gap (the
    // frame is then chosen inside that plane by higher-order moments).
    const Eigen::Matrix3d& c = surface.secondMomentM5;
    const auto frames = computeCanonicalFrames(e.surface);
    ASSERT_TRUE(frames);
    if (!frames.value().degenerateLowerPair && !frames.value().degenerateUpperPair) {
      EXPECT_LT(std::abs(c(0, 1)) + std::abs(c(0, 2)) + std::abs(c(1, 2)), 1e-9 * c.trace());
      EXPECT_LE(c(0, 0), c(1, 1) * (1 + 1e-9));
      EXPECT_LE(c(1, 1), c(2, 2) * (1 + 1e-9));
    }
    // The tet mesh fills the same solid (the surface is approximated within Mesh_3's tolerance).
    EXPECT_NEAR(e.asset.massProperties.volumeM3, 1.0, 0.08);  // 400 tets on curved fragments
    EXPECT_EQ(e.asset.modal.frequenciesHz.size(), 6);
    EXPECT_LT(e.asset.modal.residuals.maxCoeff(), 1e-8);
    EXPECT_GT(e.asset.modal.frequenciesHz(0), 0.0);
    EXPECT_GT(e.baseVolumeFraction, 0.0);
    EXPECT_LT(e.baseVolumeFraction, 1.0);
    EXPECT_TRUE(e.cut == "voronoi" || e.cut == "planes") << e.cut;
  }
  EXPECT_GE(shapes.size(), 6u) << "entries cycle over the base shapes";
  for (DescriptorKind kind : kAllDescriptorKinds) {
    EXPECT_EQ(db.descriptorsOf(kind).rows(), 8);
    EXPECT_EQ(db.descriptorsOf(kind).cols(), descriptorSize(kind, db.descriptorSettings));
  }
}

TEST_F(FragmentDatabaseBakeTest, SameSeedSameDatabaseForAnyThreadCount) {
  DatabaseBakeSettings s = testing::smallDatabaseSettings(12, false);
  s.threads = 1;
  auto one = bakeFragmentDatabase(s);
  s.threads = 2;
  auto two = bakeFragmentDatabase(s);
  s.seed = 8;
  auto other = bakeFragmentDatabase(s);
  ASSERT_TRUE(one && two && other);
  for (size_t i = 0; i < 12; ++i) {
    EXPECT_EQ(one.value().entries[i].surface.vertices, two.value().entries[i].surface.vertices);
    EXPECT_EQ(one.value().entries[i].seed, two.value().entries[i].seed);
  }
  for (DescriptorKind kind : kAllDescriptorKinds) {
    EXPECT_EQ(one.value().descriptorsOf(kind), two.value().descriptorsOf(kind));
    EXPECT_NE(one.value().descriptorsOf(kind), other.value().descriptorsOf(kind));
  }
}

TEST_F(FragmentDatabaseBakeTest, PackRoundTripIsBitExact) {
  Pack pack;
  pack.database = *physical;
  // One kind stores an HNSW index (M in `trees`, ef in `checks`): it must come back as such.
  DescriptorIndexSettings& hnsw = pack.database.indexSettings[static_cast<size_t>(DescriptorKind::VoxelImproved)];
  hnsw.kind = DescriptorIndexSettings::Kind::Hnsw;
  hnsw.trees = 12;
  hnsw.checks = 40;
  const auto path = dir / "db.h5";
  ASSERT_TRUE(writePack(pack, path));
  auto read = readPack(path);
  ASSERT_TRUE(read) << read.error().message;
  const FragmentDatabase& a = pack.database;
  const FragmentDatabase& b = read.value().database;
  EXPECT_EQ(a.referenceMaterial, b.referenceMaterial);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.descriptorSettings.moment.maxOrder, b.descriptorSettings.moment.maxOrder);
  EXPECT_EQ(a.descriptorSettings.voxel.resolution, b.descriptorSettings.voxel.resolution);
  EXPECT_EQ(a.descriptorSettings.voxelImproved.clampVoxels, b.descriptorSettings.voxelImproved.clampVoxels);
  ASSERT_EQ(a.entries.size(), b.entries.size());
  for (size_t i = 0; i < a.entries.size(); ++i) {
    testing::expectSameBakedData(a.entries[i].asset, b.entries[i].asset);
    EXPECT_EQ(a.entries[i].surface.vertices, b.entries[i].surface.vertices);
    EXPECT_EQ(a.entries[i].surface.faces, b.entries[i].surface.faces);
    EXPECT_EQ(a.entries[i].baseShape, b.entries[i].baseShape);
    EXPECT_EQ(a.entries[i].cut, b.entries[i].cut);
    EXPECT_EQ(a.entries[i].seed, b.entries[i].seed);
  }
  for (DescriptorKind kind : kAllDescriptorKinds) {
    EXPECT_EQ(a.descriptorsOf(kind), b.descriptorsOf(kind));
    EXPECT_EQ(a.indexSettings[static_cast<size_t>(kind)].checks, b.indexSettings[static_cast<size_t>(kind)].checks);
    EXPECT_EQ(a.indexSettings[static_cast<size_t>(kind)].trees, b.indexSettings[static_cast<size_t>(kind)].trees);
    EXPECT_EQ(a.indexSettings[static_cast<size_t>(kind)].kind, b.indexSettings[static_cast<size_t>(kind)].kind);
  }
  // And the matcher builds that index from the pack.
  FragmentMatcherSettings ms;
  ms.enabled = {false, false, true};
  auto matcher = FragmentMatcher::build(b, ms);
  ASSERT_TRUE(matcher) << matcher.error().message;
  EXPECT_EQ(matcher.value().index(DescriptorKind::VoxelImproved)->settings().kind, DescriptorIndexSettings::Kind::Hnsw);
}

// The bytes of the pack holding just this database (writePack is deterministic).
std::string packBytes(const FragmentDatabase& db, const std::filesystem::path& path) {
  Pack pack;
  pack.database = db;
  EXPECT_TRUE(writePack(pack, path));
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

size_t chunkFiles(const std::filesystem::path& directory) {
  size_t n = 0;
  for (const auto& f : std::filesystem::directory_iterator(directory)) n += f.path().extension() == ".h5";
  return n;
}

// Stops the bake once `after` entries are done.
class StopAfter final : public ProgressSink {
 public:
  explicit StopAfter(int after) : mAfter(after) {}
  void report(std::string_view stage, double) override { mDone += stage == "fragment database"; }
  bool wasInterrupted() override { return mDone >= mAfter; }

 private:
  int mAfter;
  int mDone = 0;
};

TEST_F(FragmentDatabaseBakeTest, CheckpointedBakeEqualsTheUninterruptedOne) {
  DatabaseCheckpointSettings c;
  c.directory = dir / "chunks";
  c.chunkEntries = 3;  // 3 + 3 + 2
  DatabaseCheckpointReport report;
  auto db = bakeFragmentDatabase(testing::smallDatabaseSettings(8, true), c, nullptr, &report);
  ASSERT_TRUE(db) << db.error().message;
  EXPECT_EQ(report.chunksBaked, 3);
  EXPECT_EQ(report.entriesBaked, 8);
  EXPECT_EQ(chunkFiles(c.directory), 3u);
  EXPECT_TRUE(std::filesystem::exists(c.directory / "bake.json"));
  testing::expectSameDatabase(db.value(), *physical);  // bake timings aside, so not the bytes
}

TEST_F(FragmentDatabaseBakeTest, InterruptedBakeResumesFromItsFinishedChunks) {
  DatabaseBakeSettings s = testing::smallDatabaseSettings(12, false);
  s.threads = 1;
  const std::string reference = packBytes(bakeFragmentDatabase(s).value(), dir / "reference.h5");
  DatabaseCheckpointSettings c;
  c.directory = dir / "chunks";
  c.chunkEntries = 4;
  StopAfter stop(6);  // in the second chunk
  auto cancelled = bakeFragmentDatabase(s, c, &stop);
  ASSERT_FALSE(cancelled);
  EXPECT_EQ(cancelled.error().code, ErrorCode::Cancelled);
  EXPECT_EQ(chunkFiles(c.directory), 1u);  // the first chunk, whole; nothing of the second

  c.resume = true;
  DatabaseCheckpointReport report;
  auto resumed = bakeFragmentDatabase(s, c, nullptr, &report);
  ASSERT_TRUE(resumed) << resumed.error().message;
  EXPECT_EQ(report.chunksReused, 1);
  EXPECT_EQ(report.entriesReused, 4);
  EXPECT_EQ(report.entriesBaked, 8);
  EXPECT_TRUE(packBytes(resumed.value(), dir / "resumed.h5") == reference);

  // Resuming a finished bake bakes nothing.
  auto again = bakeFragmentDatabase(s, c, nullptr, &report);
  ASSERT_TRUE(again);
  EXPECT_EQ(report.entriesReused, 12);
  EXPECT_EQ(report.entriesBaked, 0);
}

TEST_F(FragmentDatabaseBakeTest, CheckpointsRefuseOtherSettingsAndRebakeDamagedChunks) {
  DatabaseBakeSettings s = testing::smallDatabaseSettings(6, false);
  DatabaseCheckpointSettings c;
  c.directory = dir / "chunks";
  c.chunkEntries = 2;
  auto first = bakeFragmentDatabase(s, c);
  ASSERT_TRUE(first);
  const std::string reference = packBytes(first.value(), dir / "reference.h5");

  c.resume = true;
  DatabaseBakeSettings other = s;
  other.seed = 99;
  EXPECT_EQ(bakeFragmentDatabase(other, c).error().code, ErrorCode::InvalidArgument);
  other = s;
  other.modeCount = 7;
  EXPECT_EQ(bakeFragmentDatabase(other, c).error().code, ErrorCode::InvalidArgument);

  // A damaged chunk (one flipped byte in its middle) is baked again, and only it.
  const auto chunk = fragmentDatabaseChunkPath(s, c, 1);
  {
    std::fstream f(chunk, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(0, std::ios::end);
    const auto size = static_cast<std::streamoff>(f.tellg());
    f.seekg(size / 2);
    char byte = 0;
    f.read(&byte, 1);
    byte = static_cast<char>(byte ^ 0x5a);
    f.seekp(size / 2);
    f.write(&byte, 1);
  }
  EXPECT_FALSE(assembleFragmentDatabase(s, c));
  DatabaseCheckpointReport report;
  auto repaired = bakeFragmentDatabase(s, c, nullptr, &report);
  ASSERT_TRUE(repaired) << repaired.error().message;
  EXPECT_EQ(report.chunksBaked, 1);
  EXPECT_EQ(report.chunksReused, 2);
  EXPECT_TRUE(packBytes(repaired.value(), dir / "repaired.h5") == reference);

  // A missing chunk names itself; afresh (no resume) removes the old chunks first.
  std::filesystem::remove(fragmentDatabaseChunkPath(s, c, 2));
  auto incomplete = assembleFragmentDatabase(s, c);
  ASSERT_FALSE(incomplete);
  EXPECT_EQ(incomplete.error().code, ErrorCode::FileNotFound);
  EXPECT_NE(incomplete.error().message.find("chunk 2"), std::string::npos) << incomplete.error().message;
  c.resume = false;
  ASSERT_TRUE(prepareFragmentDatabaseCheckpoints(other, c));
  EXPECT_EQ(chunkFiles(c.directory), 0u);

  // Bad checkpoint settings.
  DatabaseCheckpointSettings bad = c;
  bad.chunkEntries = 0;
  EXPECT_EQ(bakeFragmentDatabase(s, bad).error().code, ErrorCode::InvalidArgument);
  bad = c;
  bad.rank = 2;
  bad.ranks = 2;
  EXPECT_EQ(bakeFragmentDatabase(s, bad).error().code, ErrorCode::InvalidArgument);
  bad = c;
  bad.directory.clear();
  EXPECT_EQ(bakeFragmentDatabase(s, bad).error().code, ErrorCode::InvalidArgument);
  DatabaseBakeSettings oneKind = s;
  oneKind.kinds = {true, false, false};
  EXPECT_EQ(bakeFragmentDatabase(oneKind, c).error().code, ErrorCode::InvalidArgument);
}

// Ranks bake disjoint chunks into one directory; any rank's chunks plus the others' assemble into
// the single-process database.
TEST_F(FragmentDatabaseBakeTest, RanksBakeDisjointChunksThatAssembleIntoTheSameDatabase) {
  DatabaseBakeSettings s = testing::smallDatabaseSettings(7, false);
  const std::string reference = packBytes(bakeFragmentDatabase(s).value(), dir / "reference.h5");
  DatabaseCheckpointSettings c;
  c.directory = dir / "chunks";
  c.chunkEntries = 2;  // chunks 0..3
  c.ranks = 3;
  int64_t baked = 0;
  for (int rank = 0; rank < 3; ++rank) {
    c.rank = rank;
    ASSERT_TRUE(prepareFragmentDatabaseCheckpoints(s, c));
    c.resume = true;  // the other ranks' chunks stay
    auto report = bakeFragmentDatabaseChunks(s, c);
    ASSERT_TRUE(report) << report.error().message;
    EXPECT_EQ(report.value().chunksBaked, rank == 0 ? 2 : 1);  // chunks {0, 3}, {1}, {2}
    baked += report.value().entriesBaked;
  }
  EXPECT_EQ(baked, 7);
  auto db = assembleFragmentDatabase(s, c);
  ASSERT_TRUE(db) << db.error().message;
  EXPECT_TRUE(packBytes(db.value(), dir / "assembled.h5") == reference);
}

// A real pack (8 entries with tets, modes and stress modes) damaged in many places: every flipped
// byte and every truncation gives a typed pack error or, where the byte is unused by HDF5, the
// same database; never a crash, a hang, an exception or a half-read pack.
TEST_F(FragmentDatabaseBakeTest, FlippedBytesAndTruncationsGiveTypedErrorsOrTheSameDatabase) {
  const std::string bytes = packBytes(*physical, dir / "whole.h5");
  ASSERT_GT(bytes.size(), 10000u);
  const std::set<ErrorCode> packErrors = {ErrorCode::PackIoError, ErrorCode::PackFormatMismatch,
                                          ErrorCode::PackVersionMismatch, ErrorCode::PackCorrupt,
                                          ErrorCode::PackShapeMismatch};
  const auto damaged = dir / "damaged.h5";
  auto write = [&](const std::string& content) {
    std::ofstream out(damaged, std::ios::binary | std::ios::trunc);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
  };
  int typed = 0, unchanged = 0;
  constexpr int kFlips = 200;
  for (int k = 0; k < kFlips; ++k) {
    std::string copy = bytes;
    const size_t at = (static_cast<size_t>(k) * copy.size()) / kFlips + static_cast<size_t>(k % 13);
    copy[at] = static_cast<char>(copy[at] ^ (1 << (k % 8)));
    write(copy);
    auto read = readPack(damaged);
    if (read) {
      ++unchanged;
      SCOPED_TRACE("flip at " + std::to_string(at));
      testing::expectSameDatabase(read.value().database, *physical);
    } else {
      ++typed;
      EXPECT_TRUE(packErrors.count(read.error().code)) << "flip at " << at << ": " << read.error().message;
    }
  }
  for (int k = 0; k < 64; ++k) {
    const size_t length = (static_cast<size_t>(k) * bytes.size()) / 64;
    write(bytes.substr(0, length));
    auto read = readPack(damaged);
    ASSERT_FALSE(read) << "truncated to " << length << " of " << bytes.size() << " bytes";
    EXPECT_TRUE(packErrors.count(read.error().code)) << length << ": " << read.error().message;
  }
  std::printf("[ damaged  ] %d flips: %d typed errors, %d unused bytes (same database); 64 truncations refused\n",
              kFlips, typed, unchanged);
  EXPECT_GT(typed, kFlips / 2);  // the checksums cover the data, most of the file
}

// A writer killed between its temporary file and the rename leaves the file behind; the next
// write of that pack removes it (its pid is gone) and keeps a live writer's.
TEST_F(FragmentDatabaseBakeTest, StaleTemporaryFilesOfKilledWritersAreRemoved) {
  const auto target = dir / "db.h5";
  char host[256] = {};
  ASSERT_EQ(::gethostname(host, sizeof host - 1), 0);
  std::string h(host);
  std::replace(h.begin(), h.end(), '-', '_');
  pid_t gone = 0;
  for (pid_t pid = 4000000; pid > 300000; pid -= 7919) {
    if (::kill(pid, 0) != 0 && errno == ESRCH) {
      gone = pid;
      break;
    }
  }
  ASSERT_GT(gone, 0);
  const auto stale = dir / ("db.h5.tmp-" + h + "-" + std::to_string(gone) + "-0");
  const auto live = dir / ("db.h5.tmp-" + h + "-" + std::to_string(::getppid()) + "-0");
  const auto other = dir / "other.h5.tmp-x-1-0";
  for (const auto& p : {stale, live, other}) std::ofstream(p) << "partial";
  Pack pack;
  pack.database = *physical;
  ASSERT_TRUE(writePack(pack, target));
  EXPECT_FALSE(std::filesystem::exists(stale));
  EXPECT_TRUE(std::filesystem::exists(live));
  EXPECT_TRUE(std::filesystem::exists(other));
  EXPECT_TRUE(readPack(target));
}

TEST_F(FragmentDatabaseBakeTest, DamagedDatabaseGivesTypedErrors) {
  Pack pack;
  pack.database = *physical;
  const auto path = dir / "db.h5";
  ASSERT_TRUE(writePack(pack, path));
  // A descriptor matrix of the wrong width.
  {
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    ASSERT_GE(H5Ldelete(f, "/database/descriptors/moment", H5P_DEFAULT), 0);
    H5Fclose(f);
  }
  auto read = readPack(path);
  ASSERT_FALSE(read);
  EXPECT_EQ(read.error().code, ErrorCode::PackShapeMismatch);
  EXPECT_NE(read.error().message.find("/database/descriptors/moment"), std::string::npos) << read.error().message;

  // The writer refuses an inconsistent database instead of writing it.
  pack.database.descriptors[0].conservativeResize(3, Eigen::NoChange);
  auto status = writePack(pack, dir / "bad.h5");
  ASSERT_FALSE(status);
  EXPECT_EQ(status.error().code, ErrorCode::InvalidArgument);
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.h5"));
}

TEST_F(FragmentDatabaseBakeTest, ManifestDatabaseSectionAndErrors) {
  std::ofstream(dir / "m.json") << R"({"database": {"shapes": ")" +
                                       (testing::sourceDir() / "assets/shapes/base-shapes.json").string() +
                                       R"(", "only": ["box", "sphere"], "entries": 5, "seed": 3, "tets": 300, "modes": 4,)"
                                       R"( "runtime_fraction": 0.25, "element": "p2"}})";
  auto s = loadDatabaseManifest(dir / "m.json");
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_TRUE(s.value().has_value());
  EXPECT_EQ(s.value()->shapes.size(), 2u);
  EXPECT_EQ(s.value()->entryCount, 5);
  EXPECT_EQ(s.value()->modeCount, 4);
  EXPECT_EQ(s.value()->runtimeFragments.fraction, 0.25);
  EXPECT_EQ(s.value()->elementOrder, ElementOrder::P2);
  std::ofstream(dir / "element.json") << R"({"database": {"shapes": "x.json", "element": "p3"}})";
  auto element = loadDatabaseManifest(dir / "element.json");
  ASSERT_FALSE(element);
  EXPECT_EQ(element.error().code, ErrorCode::ParseError);
  EXPECT_NE(element.error().message.find("\"element\""), std::string::npos) << element.error().message;
  std::ofstream(dir / "fraction.json") << R"({"database": {"shapes": "x.json", "runtime_fraction": 2}})";
  EXPECT_EQ(loadDatabaseManifest(dir / "fraction.json").error().code, ErrorCode::ParseError);
  std::ofstream(dir / "bad.json") << R"({"database": {"shapes": "x.json", "entries": -3}})";
  EXPECT_EQ(loadDatabaseManifest(dir / "bad.json").error().code, ErrorCode::ParseError);
  std::ofstream(dir / "unknown.json") << R"({"database": {"shapes": "x.json", "entires": 3}})";
  auto unknown = loadDatabaseManifest(dir / "unknown.json");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("entires"), std::string::npos);
  std::ofstream(dir / "none.json") << R"({"objects": []})";
  EXPECT_FALSE(loadDatabaseManifest(dir / "none.json").value().has_value());
  DatabaseBakeSettings empty = testing::smallDatabaseSettings(3, false);
  empty.shapes.clear();
  EXPECT_EQ(bakeFragmentDatabase(empty).error().code, ErrorCode::InvalidArgument);
}

// Entry 8 587 of a seed-1, 300-tet database: Mesh_3 (CGAL 5.5, this build) refines the wedge
// piece's canonical surface without end. Found by `brittle bake-db --entries 10000 --tets 300
// --modes 12`, which sat on it for over ten minutes. With a time limit the run is given up and the
// entry meshed finer (bakeFragmentEntry), as a piece that splits is: the bake goes on.
TEST(FragmentDatabaseEntry, APieceMesh3RefinesWithoutEndIsGivenUpAndMeshedFiner) {
  DatabaseBakeSettings s;  // bake-db's defaults
  s.shapes = testing::shippedBaseShapes();
  s.tetMesh.targetTets = 300;
  s.modeCount = 12;
  s.tetMesh.runTimeLimitS = 5.0;  // the normal runs take ≤ 1 s, also under the sanitizers; the stalled one all of it
  const int64_t i = 8587;
  const auto& shape = s.shapes[static_cast<size_t>(i) % s.shapes.size()];
  ASSERT_EQ(shape.name, "wedge");
  auto base = makeBaseShape(shape);
  ASSERT_TRUE(base) << base.error().message;
  auto fragment = generateFragment(base.value(), s.fragments, fragmentEntrySeed(1, i));
  ASSERT_TRUE(fragment) << fragment.error().message;
  const auto dir = testing::makeTempDir("mesh3-stall");
  const auto cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir);  // where Mesh_3 would dump its complex on an error
  std::array<Descriptor, kDescriptorKindCount> row;
  auto entry = bakeFragmentEntry(fragment.value(), "wedge-8587", s, row);
  std::filesystem::current_path(cwd);
  ASSERT_TRUE(entry) << entry.error().message;
  EXPECT_GT(entry.value().asset.tetMesh.tets.rows(), 450);  // meshed at 600 tets: the 300-tet run was given up
  EXPECT_EQ(countFaceConnectedComponents(entry.value().asset.tetMesh), 1);
  EXPECT_EQ(entry.value().asset.modal.frequenciesHz.size(), 12);
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

}  // namespace
}  // namespace brittle
