// The runtime's hot path allocates nothing after warm-up: an impact that does not break its body,
// reported into a reused ImpactResult, makes no heap allocation once the World's buffers have grown;
// one that breaks it allocates only what it hands over (per fragment, not per element), and with a
// database and the host's clock, per piece its search and the sources of its bodies.
//
// Allocations are counted by interposing the C allocator (operator new, Eigen and the standard
// containers all end in malloc), so this test has an executable of its own. Under AddressSanitizer,
// which owns the allocator, the interposer is left out and the test is skipped.
#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstddef>

#include "brittle/precompute/FragmentDatabaseBake.h"
#include "brittle/runtime/World.h"
#include "brittle/testing/BakeFixtures.h"
#include "brittle/testing/DatabaseFixtures.h"

#if defined(__SANITIZE_ADDRESS__)
#define BRITTLE_COUNT_ALLOCATIONS 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define BRITTLE_COUNT_ALLOCATIONS 0
#endif
#endif
#ifndef BRITTLE_COUNT_ALLOCATIONS
#define BRITTLE_COUNT_ALLOCATIONS 1
#endif

namespace {
std::atomic<long> gAllocations{0};
}

#if BRITTLE_COUNT_ALLOCATIONS && defined(__linux__)
#include <sys/prctl.h>

#include <cstring>
namespace {
// Whether the calling thread's allocations are the impact's: not those of the World's background
// threads (named "brittle-bg", BackgroundThreads.h), which start building the fragments' bodies as
// soon as a breaking impact hands them over, beside the end of that impact. Asked once a thread
// (a thread-local of this executable: no allocation to read it).
bool counted() {
  static thread_local int role = -1;
  if (role < 0) {
    char name[16] = {};
    prctl(PR_GET_NAME, name, 0, 0, 0);
    role = std::strcmp(name, "brittle-bg") == 0 ? 0 : 1;
  }
  return role == 1;
}
}  // namespace
#else
namespace {
bool counted() { return true; }
}  // namespace
#endif

#if BRITTLE_COUNT_ALLOCATIONS
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);
void __libc_free(void*);

void* malloc(size_t n) {
  if (counted()) gAllocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(n);
}
void* calloc(size_t count, size_t n) {
  if (counted()) gAllocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(count, n);
}
void* realloc(void* p, size_t n) {
  if (counted()) gAllocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, n);
}
void* memalign(size_t alignment, size_t n) {
  if (counted()) gAllocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(size_t alignment, size_t n) {
  if (counted()) gAllocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** p, size_t alignment, size_t n) {
  if (counted()) gAllocations.fetch_add(1, std::memory_order_relaxed);
  *p = __libc_memalign(alignment, n);
  return *p ? 0 : ENOMEM;
}
void free(void* p) { __libc_free(p); }
}
#endif

namespace brittle {
namespace {

class HotPathAllocationTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!BRITTLE_COUNT_ALLOCATIONS) return;  // every test skips: no bake
    auto plate = testing::makeGlassPlatePack(1500, 20);
    ASSERT_TRUE(plate) << plate.error().message;
    sPack = new Pack(std::move(plate).value());
    // The same plate in P2: its corner stresses as nodal means, the scan's equal-point groups and
    // crack growth's node memo (CornerStressMeans, StressBounds::groupUniform, StressField::nodeMemo).
    auto quadratic = testing::makeGlassPlatePack(1500, 20, 0.3, ElementOrder::P2);
    ASSERT_TRUE(quadratic) << quadratic.error().message;
    sPackP2 = new Pack(std::move(quadratic).value());
  }
  static void TearDownTestSuite() {
    delete sPack;
    delete sPackP2;
  }
  static Pack* sPack;
  static Pack* sPackP2;

  // A 100 g steel ball of 2 cm radius on the plate's top face, near its centre.
  static ImpactDesc ballOnThePlate() {
    ImpactDesc hit;
    hit.pointWorld = Eigen::Vector3d(0.16, 0.13, 0.01);
    hit.impactorMassKg = 0.1;
    hit.impactorRadiusM = 0.02;
    return hit;
  }

  // A plate placed in `world` and broken by `hit` (its object set here) once the world's
  // background work is done, so that none of it runs beside the count: the impact's allocations,
  // or −1 if it failed or did not break the plate.
  static long countedBreak(World& world, ImpactDesc& hit, ImpactResult& result) {
    auto id = world.addObject({.asset = "plate"});
    if (!id) return -1;
    hit.object = id.value();
    if (!world.waitUntilPrepared()) return -1;
    const long before = gAllocations.load();
    const Status st = world.impact(hit, result);
    const long made = gAllocations.load() - before;
    EXPECT_TRUE(st) << st.error().message;
    return st && result.broken ? made : -1;
  }

  // Impacts below the breaking speed, at different points, speeds and impactors (load patches of
  // different sizes): one round warms up, the next must not allocate.
  static std::vector<ImpactDesc> impacts(ObjectId id) {
    std::vector<ImpactDesc> out;
    const double speeds[] = {0.2, 0.6, 0.05};
    const double radii[] = {0.02, 0.005, 0.05};
    for (int i = 0; i < 3; ++i) {
      ImpactDesc d;
      d.object = id;
      d.pointWorld = Eigen::Vector3d(0.03 * i - 0.02, 0.01 * i, 0.005);
      d.normalWorld = Eigen::Vector3d::UnitZ();
      d.speedMps = speeds[i];
      d.impactorMassKg = 0.1;
      d.impactorRadiusM = radii[i];
      out.push_back(d);
    }
    return out;
  }

  static void expectNoAllocationAfterWarmUp(const WorldSettings& settings, const Pack* pack = nullptr) {
    if (!BRITTLE_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
    auto world = World::create(pack ? *pack : *sPack, settings);
    ASSERT_TRUE(world) << world.error().message;
    auto id = world.value().addObject({.asset = "plate"});
    ASSERT_TRUE(id) << id.error().message;
    const auto descs = impacts(id.value());
    ImpactResult result;
    for (const ImpactDesc& d : descs) {  // warm-up
      ASSERT_TRUE(world.value().impact(d, result));
      ASSERT_FALSE(result.broken) << "the hot-path impacts must not break the plate";
      ASSERT_GT(result.peakPrincipalStressPa, 0.0);
    }
    // The allocations counted are the process's: the placement's background work (the plate's
    // tet moments, at idle priority on the World's background threads) must be done first.
    ASSERT_TRUE(world.value().waitUntilPrepared());
    const double warmPeak = result.peakPrincipalStressPa;
    long counted = 0;
    bool ok = true, broken = false;
    for (int round = 0; round < 2; ++round) {
      for (const ImpactDesc& d : descs) {
        const long before = gAllocations.load();
        const Status st = world.value().impact(d, result);
        counted += gAllocations.load() - before;
        ok = ok && st.ok();
        broken = broken || result.broken;
      }
    }
    EXPECT_TRUE(ok);
    EXPECT_FALSE(broken);
    EXPECT_EQ(counted, 0) << "heap allocations in 6 warm impacts";
    EXPECT_EQ(result.peakPrincipalStressPa, warmPeak) << "a reused result gives the same answer";
    // The counter is live: the allocating form of impact is seen.
    const long before = gAllocations.load();
    auto fresh = world.value().impact(descs.back());
    ASSERT_TRUE(fresh);
    EXPECT_GT(gAllocations.load() - before, 0);
    EXPECT_EQ(fresh.value().peakPrincipalStressPa, warmPeak);
  }
};
Pack* HotPathAllocationTest::sPack = nullptr;
Pack* HotPathAllocationTest::sPackP2 = nullptr;

TEST_F(HotPathAllocationTest, DefaultSettingsAllocateNothingAfterWarmUp) { expectNoAllocationAfterWarmUp({}); }

TEST_F(HotPathAllocationTest, AQuadraticPlateAllocatesNothingAfterWarmUp) { expectNoAllocationAfterWarmUp({}, sPackP2); }

TEST_F(HotPathAllocationTest, WithoutStaticCorrectionOrPruningAllocateNothingEither) {
  WorldSettings s;
  s.fracture.staticCorrection = false;
  s.fracture.pruneStresses = false;
  expectNoAllocationAfterWarmUp(s);
}

TEST_F(HotPathAllocationTest, ReportingTheUncorrectedPeakAllocatesNothing) {
  WorldSettings s;
  s.fracture.reportUncorrectedPeak = true;
  s.fracture.modeCount = 12;
  expectNoAllocationAfterWarmUp(s);
}

// A breaking impact grows its cracks, labels its nodes and builds its surfaces in the World's
// buffers: what it allocates is what it hands over (World.h): per fragment, its surface's two
// arrays and its reason text. The fracture state's two arrays reuse the storage of those the
// reused result held (CrackWorkspace::recycle). Fragments here stay surfaces (no
// database, no exact path), so no body is made on the workers while allocations are counted.
// On the P1 plate and on its P2 twin (nodal means, equal-point groups, the node memo), with cracks
// crossing each other and ending at each other (CrackSettings::endAtCracks).
TEST_F(HotPathAllocationTest, BreakingImpactsAllocateOnlyWhatTheyHandOver) {
  if (!BRITTLE_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
  for (const auto& [pack, endAtCracks] : {std::pair{sPack, false}, std::pair{sPackP2, false}, std::pair{sPack, true}, std::pair{sPackP2, true}}) {
    SCOPED_TRACE(::testing::Message() << elementOrderName(pack->objects[0].elementOrder) << (endAtCracks ? ", cracks end at cracks" : ""));
    WorldSettings settings;
    settings.prepareInBackground = false;  // nothing runs on the workers meanwhile
    settings.fracture.matchFragments = false;
    settings.fracture.crack.endAtCracks = endAtCracks;
    auto world = World::create(*pack, settings);
    ASSERT_TRUE(world) << world.error().message;
    ImpactDesc hit;
    hit.pointWorld = Eigen::Vector3d(0.16, 0.13, 0.01);  // on the top face, near its centre
    hit.speedMps = 60.0;
    hit.impactorMassKg = 0.1;
    hit.impactorRadiusM = 0.02;
    ImpactResult result;
    long counted = 0;
    size_t fragments = 0, elements = 0;
    // Round 0 warms up with a harder hit, which cuts more elements and makes more fragments than the
    // counted rounds (each round's crack seed differs), so no workspace grows after it.
    for (int round = 0; round < 3; ++round) {
      hit.speedMps = round == 0 ? 120.0 : 60.0;
      auto id = world.value().addObject({.asset = "plate"});
      ASSERT_TRUE(id) << id.error().message;
      hit.object = id.value();
      const long before = gAllocations.load();
      const Status st = world.value().impact(hit, result);
      const long made = gAllocations.load() - before;
      ASSERT_TRUE(st) << st.error().message;
      ASSERT_TRUE(result.broken) << "the impact must break the plate";
      ASSERT_GE(result.fragments.size(), 2u);
      if (round == 0) continue;
      counted += made;
      fragments += result.fragments.size();
      elements += result.fracture.cutElements.size();
      // Exactly what is handed over: each fragment's non-empty surface arrays, and its reason where
      // the text is longer than a string holds in place (a looser 3 a fragment hid one vector a
      // breaking impact, the crack field's modal coordinates, until stop 86).
      long handed = 0;
      for (const FragmentResult& f : result.fragments) {
        handed += (f.surface.vertices.size() > 0 ? 1 : 0) + (f.surface.faces.size() > 0 ? 1 : 0) +
                  (f.reason.capacity() > std::string().capacity() ? 1 : 0);
      }
      EXPECT_LE(made, handed) << result.fragments.size() << " fragments, " << result.fracture.cutElements.size() << " cut elements";
    }
    EXPECT_GT(counted, 0) << "the surfaces handed over are allocated: the counter is live";
    EXPECT_GT(elements, fragments) << "more elements are cut than fragments made: the bound is not trivial";
    // The result's list holds the declared capacity from its first break, so a later break with
    // more fragments than any before does not grow it.
    EXPECT_GE(result.fragments.capacity(), static_cast<size_t>(settings.maxFragmentsPerImpact));
  }
}

// With the exact path on, the pieces it takes are handed over as BodySources, and everything the
// path does (cutting the piece's solid out of its parent, its modal analysis) runs on the workers
// when the World makes the body. So the impact itself still allocates per fragment, a few blocks
// each, not per element of the pieces it cuts out.
TEST_F(HotPathAllocationTest, TheExactPathCutsNothingInTheImpact) {
  if (!BRITTLE_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
  WorldSettings settings;
  settings.prepareInBackground = false;  // no factorisations queued behind the new bodies
  settings.fracture.exactModesMaxTets = 400;
  settings.fracture.exactModesMaxDof = 0;
  settings.fracture.exactModesBudgetDof = 0;
  auto world = World::create(*sPack, settings);
  ASSERT_TRUE(world) << world.error().message;
  ImpactDesc hit = ballOnThePlate();
  ImpactResult result;
  int exact = 0;
  for (int round = 0; round < 3; ++round) {
    hit.speedMps = round == 0 ? 120.0 : 60.0;
    const long made = countedBreak(world.value(), hit, result);  // the last round's bodies made first
    ASSERT_GE(made, 0) << "the impact must break the plate";
    if (round == 0) continue;
    int taken = 0;
    for (const FragmentResult& f : result.fragments) taken += f.path == FragmentPath::ExactModes;
    exact += taken;
    // What a surface hands over (as above), and per exact piece its BodySource (the source, its
    // task and the piece's name); the parent's labels and cuts, shared by the pieces, once.
    EXPECT_LE(made, 2 + 3 * static_cast<long>(result.fragments.size()) + 4 * taken + 3)
        << result.fragments.size() << " fragments, " << taken << " on the exact path";
  }
  EXPECT_GT(exact, 0) << "some pieces take the exact path";
}

// A host's breaks are timed (ImpactDesc::timeS, as the player's), with a database: each matched
// piece and each exact-path piece (its match first, its own analysis from exactModesDelayS) is
// searched in the impact (FragmentMatcher::match: its canonical frames, descriptors and the index's
// query, about 20 blocks a piece, since the database's API returns its matches) and handed over as
// a BodySource with its later versions (the checks, the analysis), all made on the background
// threads. Measured: 58–60 blocks a piece. The bound is per piece, not per element: an allocation
// per cut element or per triangle (thousands here) would break it.
TEST_F(HotPathAllocationTest, TimedBreaksWithADatabaseAllocatePerPieceOnly) {
  if (!BRITTLE_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are not counted under AddressSanitizer";
  Pack pack = *sPack;
  auto database = bakeFragmentDatabase(testing::shippedShapesDatabase({"box", "plate", "wedge"}, 12, 400, 12));
  ASSERT_TRUE(database) << database.error().message;
  pack.database = std::move(database).value();
  WorldSettings settings;
  settings.prepareInBackground = false;  // no factorisations queued behind the new bodies
  auto world = World::create(std::move(pack), settings);
  ASSERT_TRUE(world) << world.error().message;
  ImpactDesc hit = ballOnThePlate();
  ImpactResult result;
  int matched = 0;
  for (int round = 0; round < 4; ++round) {
    hit.speedMps = round == 0 ? 120.0 : 60.0;
    hit.timeS = 10.0 * round;  // the host's clock
    const long made = countedBreak(world.value(), hit, result);
    ASSERT_GE(made, 0) << "the impact must break the plate";
    if (round == 0) continue;
    int pieces = 0, versions = 0;
    for (const FragmentResult& f : result.fragments) {
      matched += f.path == FragmentPath::Matched;
      if (f.path == FragmentPath::Matched || f.path == FragmentPath::ExactModes) {
        ++pieces;
        versions += std::isfinite(f.lateCheckDueS) + std::isfinite(f.checkDueS) + std::isfinite(f.escalationDueS) +
                    std::isfinite(f.exactDueS);
      }
    }
    EXPECT_LE(made, 3 * static_cast<long>(result.fragments.size()) + 64 * pieces + 16)
        << result.fragments.size() << " fragments, " << pieces << " pieces with bodies, " << versions << " later versions";
    EXPECT_GT(static_cast<long>(result.fracture.cutElements.size()), 64 * pieces) << "the bound is below one a cut element";
    EXPECT_GT(versions, pieces) << "the pieces have later versions: the breaks are timed";
  }
  EXPECT_GT(matched, 0) << "some pieces are matched";
}

}  // namespace
}  // namespace brittle
