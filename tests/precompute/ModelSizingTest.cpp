#include "brittle/precompute/ModelSizing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include "brittle/database/Pack.h"
#include "brittle/precompute/BakeManifest.h"
#include "brittle/precompute/FrequencyErrorCalibration.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/testing/DatabaseFixtures.h"
#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

std::filesystem::path writeText(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir / name) << text;
  return dir / name;
}

// The sizing scenes' two objects: a 12 mm glass tile (thin: P1 locks in bending) and a chunky block.
void writeTileAndBlock(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  testing::writeOff(testing::makeBoxSurface(0.1, 0.1, 0.012), dir / "tile.off");
  testing::writeOff(testing::makeBoxSurface(0.2, 0.1, 0.06), dir / "block.off");
}

Result<SceneRequirements> parse(const std::string& text) {
  static const auto dir = testing::makeTempDir("requirements");
  return loadSceneRequirements(writeText(dir, "scene.json", text));
}

// A scene sizing kept small: the ladder given, one point per impactor, one timing, a coarse reference.
ModelSizingSettings quickScene(std::vector<int> ladder, int referenceSteps = 30) {
  ModelSizingSettings s;
  s.modeLadder = std::move(ladder);
  s.points = 1;
  s.timingRepeats = 1;
  s.referenceStepsPerContact = referenceSteps;
  return s;
}

TEST(SceneRequirementsTest, ReadsSpheresTheGroundAndTheTarget) {
  auto r = parse(R"({ "peak_stress_error": 0.1, "refracture": false, "objects": [
      { "name": "plate", "speeds_mps": [2, 10], "impactors": [ { "mass_kg": 0.1, "radius_m": 0.02 } ] },
      { "name": "brick", "speeds_mps": [3, 3], "impactors": [ { "ground": true }, { "mass_kg": 1, "radius_m": 0.05, "material": "stone" } ] } ] })");
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_DOUBLE_EQ(r.value().peakStressError, 0.1);
  EXPECT_FALSE(r.value().refracture);
  ASSERT_EQ(r.value().objects.size(), 2u);
  EXPECT_EQ(r.value().objects[0].impactors[0].material.name, "steel");  // the default impactor
  EXPECT_DOUBLE_EQ(r.value().objects[0].maxSpeedMps, 10.0);
  EXPECT_TRUE(r.value().objects[1].impactors[0].ground());
  EXPECT_TRUE(std::isinf(r.value().objects[1].impactors[0].radiusM));
  EXPECT_EQ(r.value().objects[1].impactors[1].material.name, "stone");
}

TEST(SceneRequirementsTest, BadFilesGiveTypedErrors) {
  const std::string sphere = R"({ "mass_kg": 0.1, "radius_m": 0.02 })";
  auto object = [&](const std::string& speeds, const std::string& impactor) {
    return R"({ "objects": [ { "name": "plate", "speeds_mps": )" + speeds + R"(, "impactors": [ )" + impactor + " ] } ] }";
  };
  for (const std::string& text : {std::string("{"), std::string(R"({ "objects": [] })"),
                                  std::string(R"({ "peak_stress_error": 1.5, "objects": [] })"),
                                  std::string(R"({ "colour": 1, "objects": [] })"), object("[0, 5]", sphere),
                                  object("[5, 2]", sphere), object("[2]", sphere), object("[2, 5]", "{}"),
                                  object("[2, 5]", R"({ "mass_kg": -1, "radius_m": 0.02 })"),
                                  object("[2, 5]", R"({ "ground": true, "mass_kg": 1 })"),
                                  object("[2, 5]", R"({ "mass_kg": "heavy", "radius_m": 0.02 })"),
                                  std::string(R"({ "objects": [ { "name": "a", "speeds_mps": [1, 2], "impactors": [ { "ground": true } ] },
                                                    { "name": "a", "speeds_mps": [1, 2], "impactors": [ { "ground": true } ] } ] })")}) {
    auto r = parse(text);
    ASSERT_FALSE(r) << text;
    EXPECT_EQ(r.error().code, ErrorCode::ParseError) << text << ": " << r.error().message;
  }
  auto unknown = parse(object("[2, 5]", R"({ "mass_kg": 0.1, "radius_m": 0.02, "material": "unobtainium" })"));
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().code, ErrorCode::UnknownMaterial);
  auto missing = loadSceneRequirements("no-such-scene.json");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::FileNotFound);
}

class ModelSizingTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ObjectBakeSettings b;
    b.name = "plate";
    b.material = materialPreset("glass").value();
    b.tetMesh.targetTets = 1500;
    b.modal.modeCount = 40;
    auto asset = bakeSurface(testing::makeBoxSurface(0.12, 0.12, 0.012), b);
    ASSERT_TRUE(asset) << asset.error().message;
    sAsset = new ObjectAsset(std::move(asset).value());
  }
  static void TearDownTestSuite() {
    delete sAsset;
    sAsset = nullptr;
  }
  static SceneObjectRange ballRange() {
    SceneObjectRange r;
    r.name = "plate";
    r.minSpeedMps = 2.0;
    r.maxSpeedMps = 8.0;
    SceneImpactor ball;
    ball.massKg = 0.05;
    ball.radiusM = 0.01;
    ball.material = materialPreset("steel").value();
    r.impactors.push_back(ball);
    return r;
  }
  static ModelSizingSettings quick() {
    ModelSizingSettings s;
    s.modeLadder = {40, 5, 20, 10};  // any order
    s.points = 2;
    s.timingRepeats = 1;
    s.referenceStepsPerContact = 40;
    return s;
  }
  static inline ObjectAsset* sAsset = nullptr;
};

TEST_F(ModelSizingTest, PicksTheSmallestCountThatMeetsTheTarget) {
  const Material glass = materialPreset("glass").value();
  auto loose = sizeObjectModes(*sAsset, glass, ballRange(), 0.30, quick());
  ASSERT_TRUE(loose) << loose.error().message;
  const auto& trials = loose.value().trials;
  ASSERT_EQ(trials.size(), 4u);
  EXPECT_EQ(loose.value().impacts, 4);  // 2 points × 1 impactor × 2 speeds
  EXPECT_GT(loose.value().referenceS, 0.0);
  for (size_t i = 0; i < trials.size(); ++i) {
    EXPECT_EQ(trials[i].modes, std::vector<int>({5, 10, 20, 40})[i]);
    EXPECT_TRUE(std::isfinite(trials[i].worstError) && trials[i].worstError >= 0.0);
    EXPECT_GT(trials[i].medianImpactMs, 0.0);
  }
  // The full basis with the static correction is close to the reference on its own mesh.
  EXPECT_LT(trials.back().worstError, 0.15);
  ASSERT_TRUE(loose.value().targetMet);
  for (const auto& t : trials) {
    if (t.modes < loose.value().chosenModes) {
      EXPECT_GT(t.worstError, 0.30) << t.modes;
    }
    if (t.modes == loose.value().chosenModes) {
      EXPECT_LE(t.worstError, 0.30);
    }
  }
  // The same seed gives the same errors; a target nothing meets keeps the largest count.
  auto strict = sizeObjectModes(*sAsset, glass, ballRange(), 1e-9, quick());
  ASSERT_TRUE(strict);
  EXPECT_FALSE(strict.value().targetMet);
  EXPECT_EQ(strict.value().chosenModes, 40);
  for (size_t i = 0; i < trials.size(); ++i) EXPECT_EQ(strict.value().trials[i].worstError, trials[i].worstError);
}

TEST_F(ModelSizingTest, ACountInsideAClusterOfEqualFrequenciesKeepsTheWholeCluster) {
  // The square tile's modes come in pairs of nearly equal frequencies (its two in-plane axes):
  // a count that keeps one of a pair is raised past the pair, and 0 keeps counts as given.
  const Eigen::VectorXd& hz = sAsset->modal.frequenciesHz;
  const double gap = ModelSizingSettings{}.modeClusterGap;
  auto close = [&](int j) { return hz[j] - hz[j - 1] < gap * hz[j - 1]; };  // modes j − 1 and j are one cluster
  int inside = 0;  // the first count that keeps one of a pair without the other
  for (int k = 2; k + 1 < hz.size() && inside == 0; ++k) {
    if (close(k)) inside = k;
  }
  ASSERT_GT(inside, 0) << "the tile has no pair of equal frequencies: the test shows nothing";
  const Material glass = materialPreset("glass").value();
  ModelSizingSettings s = quick();
  s.points = 1;
  s.modeLadder = {inside, 40};
  auto r = sizeObjectModes(*sAsset, glass, ballRange(), 0.3, s);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r.value().trials.size(), 2u);
  // Raised to the end of the cluster: every mode from `inside` up to the count is close to the one
  // before it, and the first mode left out is not.
  const int raised = r.value().trials.front().modes;
  std::printf("tile: a count of %d keeps %.1f Hz without %.1f Hz; raised to %d\n", inside, hz[inside - 1], hz[inside], raised);
  ASSERT_GT(raised, inside);
  ASSERT_LT(raised, 40);
  for (int j = inside; j < raised; ++j) EXPECT_TRUE(close(j)) << j;
  EXPECT_FALSE(close(raised));
  s.modeClusterGap = 0.0;
  auto given = sizeObjectModes(*sAsset, glass, ballRange(), 0.3, s);
  ASSERT_TRUE(given) << given.error().message;
  ASSERT_EQ(given.value().trials.size(), 2u);
  EXPECT_EQ(given.value().trials.front().modes, inside);
  s.modeClusterGap = -0.1;
  auto bad = sizeObjectModes(*sAsset, glass, ballRange(), 0.3, s);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().code, ErrorCode::InvalidArgument);
}

TEST_F(ModelSizingTest, TheGroundMeetsTheBodyAtACorner) {
  // Flat on flat has no Hertz contact: ground impacts must land on corners, never on a face.
  SceneObjectRange drop = ballRange();
  drop.impactors[0].massKg = std::numeric_limits<double>::infinity();
  drop.impactors[0].radiusM = std::numeric_limits<double>::infinity();
  ModelSizingSettings s = quick();
  s.points = 3;
  auto r = sizeObjectModes(*sAsset, materialPreset("glass").value(), drop, 0.3, s);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r.value().impacts, 6);
  for (const auto& t : r.value().trials) EXPECT_TRUE(std::isfinite(t.worstError)) << t.modes;
}

TEST_F(ModelSizingTest, RefusesBadSettings) {
  const Material glass = materialPreset("glass").value();
  ModelSizingSettings s = quick();
  s.modeLadder = {60, 80};  // more than the asset holds
  auto tooMany = sizeObjectModes(*sAsset, glass, ballRange(), 0.1, s);
  ASSERT_FALSE(tooMany);
  EXPECT_EQ(tooMany.error().code, ErrorCode::InvalidArgument);
  SceneObjectRange none = ballRange();
  none.impactors.clear();
  auto noImpactor = sizeObjectModes(*sAsset, glass, none, 0.1, quick());
  ASSERT_FALSE(noImpactor);
  EXPECT_EQ(noImpactor.error().code, ErrorCode::InvalidArgument);
}

TEST_F(ModelSizingTest, FragmentsGiveTheDebrisThresholdAndTheSearch) {
  const Material glass = materialPreset("glass").value();
  SceneObjectRange range = ballRange();
  range.maxSpeedMps = 40.0;  // breaks the plate at both points
  ModelSizingSettings s = quick();
  s.fragmentsPerImpact = 6;
  auto fragments = sceneFragments(*sAsset, glass, range, 20, s);
  ASSERT_TRUE(fragments) << fragments.error().message;
  ASSERT_GE(fragments.value().size(), 4u);
  int broke = 0;
  for (const FragmentRecord& f : fragments.value()) {
    EXPECT_EQ(f.object, "plate");
    EXPECT_GT(f.volumeFraction, 0.0);
    EXPECT_LT(f.volumeFraction, 1.0);
    EXPECT_GT(f.frequenciesHz[0], 0.0);
    EXPECT_LE(f.frequenciesHz[0], f.frequenciesHz[1]);
    EXPECT_LE(f.frequenciesHz[1], f.frequenciesHz[2]);
    broke += f.brokeAgain ? 1 : 0;
  }
  // Deterministic: the same seed gives the same fragments and the same outcomes.
  auto again = sceneFragments(*sAsset, glass, range, 20, s);
  ASSERT_TRUE(again);
  ASSERT_EQ(again.value().size(), fragments.value().size());
  for (size_t i = 0; i < again.value().size(); ++i) {
    EXPECT_EQ(again.value()[i].volumeFraction, fragments.value()[i].volumeFraction);
    EXPECT_EQ(again.value()[i].brokeAgain, fragments.value()[i].brokeAgain);
  }

  // Debris: half the smallest fraction that broke again; nothing that broke lies below it.
  const DebrisSizing debris = chooseDebrisThreshold("plate", fragments.value());
  EXPECT_EQ(debris.fragments, static_cast<int>(fragments.value().size()));
  EXPECT_EQ(debris.brokeAgain, broke);
  if (broke > 0) {
    EXPECT_DOUBLE_EQ(debris.debrisVolumeFraction, std::clamp(0.5 * debris.smallestBrokenFraction, 0.001, 0.5));
    for (const FragmentRecord& f : fragments.value()) {
      if (f.brokeAgain) {
        EXPECT_GE(f.volumeFraction, 2.0 * debris.debrisVolumeFraction - 1e-15);
      }
    }
  } else {
    EXPECT_EQ(debris.debrisVolumeFraction, 0.5);
  }
  FragmentRecord big;
  big.object = "x";
  big.volumeFraction = 0.3;
  big.brokeAgain = true;
  FragmentRecord small = big;
  small.volumeFraction = 0.01;
  small.brokeAgain = false;
  EXPECT_DOUBLE_EQ(chooseDebrisThreshold("x", {big, small}).debrisVolumeFraction, 0.15);
  EXPECT_DOUBLE_EQ(chooseDebrisThreshold("x", {small}).debrisVolumeFraction, 0.5);

  // Search: every kind × precision of its stored index is tried; the cheapest that meets the
  // target (fewest bytes compared, not the measured time) is chosen, else the most accurate.
  auto database = bakeFragmentDatabase(testing::shippedShapesDatabase({"box", "plate", "wedge", "blob"}, 12, 400, 6));
  ASSERT_TRUE(database) << database.error().message;
  ASSERT_EQ(database.value().entries.size(), 12u);
  s.searchPrecision = {0.25, 4.0, 0.0};
  auto loose = chooseSearch(database.value(), fragments.value(), {glass}, 100.0, s);
  ASSERT_TRUE(loose) << loose.error().message;
  EXPECT_TRUE(loose.value().targetMet);
  // Per kind: the stored index at ¼ and 4× its checks, then brute force; a precision that lands
  // on an index already tried is not tried again (the one-list inverted files, the moments' and the
  // occupancy voxels', probe their one list at any precision).
  using Kind = DescriptorIndexSettings::Kind;
  size_t expectedTrials = 0;
  for (DescriptorKind kind : kAllDescriptorKinds) {
    const DescriptorIndexSettings& stored = database.value().indexSettings[static_cast<size_t>(kind)];
    std::vector<const SearchTrial*> ofKind;
    for (const SearchTrial& t : loose.value().trials)
      if (t.kind == kind) ofKind.push_back(&t);
    SCOPED_TRACE(descriptorKindName(kind));
    if (stored.kind == Kind::Ivf || stored.kind == Kind::IvfBinary) {
      ASSERT_EQ(stored.trees, 1);
      ASSERT_EQ(ofKind.size(), 2u);
      EXPECT_EQ(ofKind[0]->index.checks, 1);
    } else {
      ASSERT_EQ(ofKind.size(), 3u);
      EXPECT_EQ(ofKind[0]->index.checks, std::max(1, static_cast<int>(std::lround(0.25 * stored.checks))));
      EXPECT_EQ(ofKind[1]->index.checks, 4 * stored.checks);
      EXPECT_EQ(ofKind[1]->index.trees, stored.trees);
    }
    EXPECT_EQ(ofKind[0]->index.kind, stored.kind);
    EXPECT_EQ(ofKind.back()->precision, 0.0);
    EXPECT_EQ(ofKind.back()->index.kind, Kind::BruteForce);
    expectedTrials += ofKind.size();
  }
  EXPECT_EQ(loose.value().trials.size(), expectedTrials);
  for (const SearchTrial& t : loose.value().trials) {
    EXPECT_GT(t.matched, 0);
    EXPECT_GT(t.medianMatchMs, 0.0);
    // Brute force reads every row in floats. Nothing reads more rows, but a keyed graph
    // (hnsw-principal, hnsw-pooled) also reads its keys: at 12 entries it is dearer than the scan.
    const double exact = 12.0 * 4.0 * static_cast<double>(descriptorSize(t.kind, database.value().descriptorSettings));
    if (t.index.kind == Kind::BruteForce) {
      EXPECT_EQ(t.bytesCompared, exact);
    }
    const bool keyed = t.index.kind == Kind::HnswPrincipal || t.index.kind == Kind::HnswPooled;
    EXPECT_LE(t.bytesCompared, exact + (keyed ? 12.0 * 4.0 * 512.0 : 0.0));
    EXPECT_GT(t.bytesCompared, 0.0);
    // One (distance, error) pair per matched fragment, the error that the trial's median is of.
    ASSERT_EQ(t.distanceErrors.size(), static_cast<size_t>(t.matched));
    std::vector<double> errors;
    for (const auto& [distance, error] : t.distanceErrors) errors.push_back(error);
    std::sort(errors.begin(), errors.end());
    const size_t n = errors.size();
    EXPECT_DOUBLE_EQ(t.medianFrequencyError, n % 2 ? errors[n / 2] : 0.5 * (errors[n / 2 - 1] + errors[n / 2]));
  }
  // What the sized pack's model of the chosen kind is fitted to: the chosen trial's pairs.
  const SearchTrial& chosen = *std::find_if(loose.value().trials.begin(), loose.value().trials.end(), [&](const SearchTrial& t) {
    return t.kind == loose.value().kind && t.precision == loose.value().precision;
  });
  EXPECT_EQ(loose.value().distanceErrors, chosen.distanceErrors);
  EXPECT_EQ(loose.value().index.kind, chosen.index.kind);
  EXPECT_EQ(loose.value().index.checks, chosen.index.checks);
  for (const SearchTrial& t : loose.value().trials) {  // (every trial meets a 100× target)
    EXPECT_GE(t.bytesCompared, chosen.bytesCompared);
  }
  // The same choice on a second run, whatever the clock read.
  auto rerun = chooseSearch(database.value(), fragments.value(), {glass}, 100.0, s);
  ASSERT_TRUE(rerun);
  EXPECT_EQ(rerun.value().kind, loose.value().kind);
  EXPECT_EQ(rerun.value().precision, loose.value().precision);
  auto strict = chooseSearch(database.value(), fragments.value(), {glass}, 1e-9, s);
  ASSERT_TRUE(strict);
  EXPECT_FALSE(strict.value().targetMet);
  for (const SearchTrial& t : strict.value().trials) EXPECT_GE(t.medianFrequencyError, strict.value().medianFrequencyError);
  // The sized pack keeps the stored index's kind at the chosen precision, or brute force.
  EXPECT_EQ(strict.value().index.kind, strict.value().precision > 0.0
                                            ? database.value().indexSettings[static_cast<size_t>(strict.value().kind)].kind
                                            : Kind::BruteForce);
  ModelSizingSettings bad = s;
  bad.searchPrecision = {1.0, -0.5};
  EXPECT_EQ(chooseSearch(database.value(), fragments.value(), {glass}, 0.2, bad).error().code, ErrorCode::InvalidArgument);
  bad.searchPrecision = {};
  EXPECT_EQ(chooseSearch(database.value(), fragments.value(), {glass}, 0.2, bad).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(chooseSearch(database.value(), {}, {glass}, 0.2, s).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(chooseSearch(database.value(), fragments.value(), {}, 0.2, s).error().code, ErrorCode::InvalidArgument);
}

// The search's cost model (searchBytesCompared) at the sizes it decides between: each kind's
// stored default index at 10⁵ entries reads more with precision and far less than brute force,
// and the occupancy graph's walk is ef × M codes of 512 bytes.
TEST(SearchSizingTest, BytesComparedGrowWithPrecisionAndStayBelowTheExactSearch) {
  constexpr int64_t kRows = 100000;
  const std::pair<DescriptorKind, int64_t> kinds[] = {
      {DescriptorKind::Moment, 30}, {DescriptorKind::Voxel, 4096}, {DescriptorKind::VoxelImproved, 4096}};
  for (const auto& [kind, cols] : kinds) {
    SCOPED_TRACE(descriptorKindName(kind));
    const DescriptorIndexSettings stored = defaultIndexSettings(kind, kRows);
    const double exact = searchBytesCompared(indexAtPrecision(stored, 0.0), kRows, cols);
    EXPECT_EQ(exact, 4.0 * kRows * cols);
    double previous = 0.0;
    for (double precision : {0.25, 1.0, 4.0}) {
      const DescriptorIndexSettings index = indexAtPrecision(stored, precision);
      EXPECT_EQ(index.kind, stored.kind);
      EXPECT_EQ(index.trees, stored.trees);
      const double bytes = searchBytesCompared(index, kRows, cols);
      EXPECT_GT(bytes, previous);
      EXPECT_LT(bytes, 0.05 * exact);
      previous = bytes;
    }
  }
  DescriptorIndexSettings binary{.kind = DescriptorIndexSettings::Kind::HnswBinary, .trees = 16, .checks = 32};
  EXPECT_EQ(searchBytesCompared(binary, kRows, 4096), 32.0 * 16.0 * 512.0);
  EXPECT_EQ(searchBytesCompared(binary, 100, 4096), 100.0 * 512.0);  // the walk cannot read more rows than there are
  // The occupancy voxels' stored inverted file: 32-byte keys of the centroids and the probed rows.
  const DescriptorIndexSettings bits = defaultIndexSettings(DescriptorKind::Voxel, kRows);
  ASSERT_EQ(bits.kind, DescriptorIndexSettings::Kind::IvfBinary);
  EXPECT_EQ(searchBytesCompared(bits, kRows, 4096), 32.0 * (bits.trees + bits.checks * std::ceil(double(kRows) / bits.trees)) + 512.0);
  EXPECT_EQ(indexAtPrecision(bits, 1000.0).checks, bits.trees);
  // An inverted file probes at most its lists; the exact kinds have no precision to scale.
  const DescriptorIndexSettings ivf = sizedInvertedFile(kRows);
  EXPECT_EQ(indexAtPrecision(ivf, 1000.0).checks, ivf.trees);
  EXPECT_EQ(indexAtPrecision(ivf, 1e-6).checks, 1);
  const DescriptorIndexSettings flat{.kind = DescriptorIndexSettings::Kind::FaissBinaryFlat};
  EXPECT_EQ(indexAtPrecision(flat, 4.0).kind, DescriptorIndexSettings::Kind::FaissBinaryFlat);
  EXPECT_EQ(describeIndexSettings(indexAtPrecision(binary, 0.25)), "hnsw-binary:16:8");
  EXPECT_EQ(describeIndexSettings(indexAtPrecision(binary, 0.0)), "brute-force");
}

TEST(SceneSizingTest, BakesOnlyWhatTheSceneUsesAndReportsTheSavings) {
  const auto dir = testing::makeTempDir("scene-sizing");
  writeTileAndBlock(dir / "meshes");
  const auto manifestPath = writeText(dir, "manifest.json", R"({ "objects": [
      { "name": "tile", "mesh": "meshes/tile.off", "material": "glass", "tets": 800, "modes": 10 },
      { "name": "block", "mesh": "meshes/block.off", "material": "concrete", "tets": 800, "modes": 10 } ] })");
  auto manifest = loadBakeManifest(manifestPath);
  ASSERT_TRUE(manifest) << manifest.error().message;
  auto requirements = parse(R"({ "peak_stress_error": 0.3, "refracture": false, "objects": [
      { "name": "tile", "speeds_mps": [2, 6], "impactors": [ { "mass_kg": 0.05, "radius_m": 0.01 } ] } ] })");
  ASSERT_TRUE(requirements);
  ModelSizingSettings s = quickScene({5, 10, 30});
  const auto out = dir / "out" / "sized.h5";
  std::filesystem::create_directories(out.parent_path());
  auto report = sizeScene(manifest.value(), std::nullopt, requirements.value(), {out, {}}, s);
  ASSERT_TRUE(report) << report.error().message;
  const auto& r = report.value();
  ASSERT_EQ(r.objects.size(), 1u);
  EXPECT_EQ(r.skippedObjects, std::vector<std::string>({"block"}));
  EXPECT_GT(r.maximumPackBytes, r.sizedPackBytes);
  EXPECT_GT(r.maximumBakeS, 0.0);
  EXPECT_GT(r.sizedBakeS, 0.0);
  EXPECT_FALSE(std::filesystem::exists(out.string() + ".maximum.h5"));  // measured, then removed
  // The tile's fragments were sized too (no database: no search).
  ASSERT_EQ(r.debris.size(), 1u);
  EXPECT_EQ(r.debris[0].object, "tile");
  EXPECT_EQ(r.debrisVolumeFraction, r.debris[0].debrisVolumeFraction);
  EXPECT_FALSE(r.search);
  auto sized = readPack(out);
  ASSERT_TRUE(sized) << sized.error().message;
  ASSERT_EQ(sized.value().objects.size(), 1u);
  EXPECT_EQ(sized.value().objects[0].name, "tile");
  EXPECT_EQ(sized.value().objects[0].modal.eigenvaluesRad2PerS2.size(), r.objects[0].chosenModes);
  EXPECT_EQ(static_cast<int64_t>(std::filesystem::file_size(out)), r.sizedPackBytes);

  // The sized manifest bakes the same objects from another directory.
  const auto sizedManifest = dir / "out" / "sized.json";
  ASSERT_TRUE(writeSizedManifest(manifestPath, r, sizedManifest));
  auto again = loadBakeManifest(sizedManifest);
  ASSERT_TRUE(again) << again.error().message;
  ASSERT_EQ(again.value().size(), 1u);
  EXPECT_EQ(again.value()[0].modal.modeCount, r.objects[0].chosenModes);
  EXPECT_TRUE(std::filesystem::exists(again.value()[0].meshPath));

  // A scene object the manifest lacks is named in a typed error.
  SceneRequirements unknown = requirements.value();
  unknown.objects[0].name = "vase";
  auto missing = sizeScene(manifest.value(), std::nullopt, unknown, {dir / "out" / "never.h5", {}}, s);
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(missing.error().message.find("vase"), std::string::npos);
  EXPECT_NE(missing.error().message.find("tile, block"), std::string::npos);
}

// A scene that refractures keeps the database, and its bodies' frequency errors are calibrated at
// the scene's own impacts (FrequencyErrorCalibration.h): the sized pack holds exactly the models a
// calibration of it at those impacts makes. A scene whose impacts break nothing off gets none, and
// says why, instead of failing.
TEST(SceneSizingTest, CalibratesTheBodiesFrequencyErrorsAtTheScenesImpacts) {
  const auto dir = testing::makeTempDir("scene-sizing-errors");
  writeTileAndBlock(dir / "meshes");
  const auto manifestPath = writeText(dir, "manifest.json", R"({ "objects": [
      { "name": "tile", "mesh": "meshes/tile.off", "material": "glass", "tets": 800, "modes": 10 } ] })");
  auto manifest = loadBakeManifest(manifestPath);
  ASSERT_TRUE(manifest) << manifest.error().message;
  auto requirements = parse(R"({ "peak_stress_error": 0.5, "refracture": true, "objects": [
      { "name": "tile", "speeds_mps": [20, 40], "impactors": [ { "mass_kg": 0.05, "radius_m": 0.01 } ] } ] })");
  ASSERT_TRUE(requirements);
  ModelSizingSettings s = quickScene({5, 10});
  s.elementOrders = {ElementOrder::P1};
  s.fragmentsPerImpact = 3;
  s.searchPrecision = {0.0};
  s.frequencyErrorPoints = 1;
  s.frequencyErrorPiecesPerImpact = 3;
  const DatabaseBakeSettings database = testing::shippedShapesDatabase({"box", "plate"}, 8, 300, 6);
  const auto out = dir / "sized.h5";
  auto report = sizeScene(manifest.value(), database, requirements.value(), {out, {}}, s);
  ASSERT_TRUE(report) << report.error().message;
  ASSERT_TRUE(report.value().frequencyErrors);
  const FrequencyErrorSizing& f = *report.value().frequencyErrors;
  ASSERT_TRUE(f.calibrated) << f.note;
  EXPECT_EQ(f.impacts, 2);  // 1 point × 1 impactor × 2 speeds
  ASSERT_EQ(f.piecesPerObject.size(), 1u);
  EXPECT_EQ(f.piecesPerObject[0].first, "tile");
  EXPECT_GT(f.piecesPerObject[0].second, 0);
  EXPECT_GT(f.seconds, 0.0);
  auto sized = readPack(out);
  ASSERT_TRUE(sized) << sized.error().message;
  const FrequencyErrorModels stored = sized.value().database.frequencyErrors;
  EXPECT_EQ(stored.degree, 5);
  EXPECT_EQ(stored.ritz.samples, f.piecesPerObject[0].second);
  EXPECT_EQ(static_cast<int>(stored.ritz.distance.size()), f.ritzBins);
  EXPECT_EQ(static_cast<int>(stored.checkedP2.distance.size()), f.checkedP2Bins);
  FrequencyErrorCalibrationSettings again;
  again.scene = requirements.value().objects;
  again.seeds = s.frequencyErrorPoints;
  again.maxFragmentsPerImpact = s.frequencyErrorPiecesPerImpact;
  auto recalibrated = calibrateFrequencyErrors(sized.value(), again);
  ASSERT_TRUE(recalibrated) << recalibrated.error().message;
  EXPECT_EQ(recalibrated.value().models.ritz.medianError, stored.ritz.medianError);
  EXPECT_EQ(recalibrated.value().models.ritz.p90Error, stored.ritz.p90Error);
  EXPECT_EQ(recalibrated.value().models.checked.distance, stored.checked.distance);

  // Too soft to break: the sizing succeeds, the pack predicts nothing, and the report says why.
  SceneRequirements soft = requirements.value();
  soft.objects[0].minSpeedMps = 0.01;
  soft.objects[0].maxSpeedMps = 0.02;
  const auto softOut = dir / "soft.h5";
  auto softReport = sizeScene(manifest.value(), database, soft, {softOut, {}}, s);
  ASSERT_TRUE(softReport) << softReport.error().message;
  ASSERT_TRUE(softReport.value().frequencyErrors);
  EXPECT_FALSE(softReport.value().frequencyErrors->calibrated);
  EXPECT_NE(softReport.value().frequencyErrors->note.find("no piece"), std::string::npos) << softReport.value().frequencyErrors->note;
  EXPECT_EQ(softReport.value().frequencyErrors->impacts, 2);  // made, and counted
  auto softPack = readPack(softOut);
  ASSERT_TRUE(softPack) << softPack.error().message;
  EXPECT_TRUE(softPack.value().database.frequencyErrors.ritz.empty());
}

// The element order is one more knob (ModelSizingSettings::elementOrders): each object is sized in
// P1 and in P2 on the same tets, and the cheaper order that meets both targets is kept. The thin
// tile's P1 tets lock in bending, far outside a 40 % frequency target, so it is P2; the chunky
// block's P1 first mode is within it, and P1 reads fewer values per impact, so it stays P1.
TEST(SceneSizingTest, KeepsTheCheaperElementOrderThatMeetsBothTargets) {
  const auto dir = testing::makeTempDir("scene-sizing-elements");
  writeTileAndBlock(dir);
  const auto manifestPath = writeText(dir, "manifest.json", R"({ "objects": [
      { "name": "tile", "mesh": "tile.off", "material": "glass", "tets": 500, "modes": 10 },
      { "name": "block", "mesh": "block.off", "material": "concrete", "tets": 400, "modes": 10 } ] })");
  auto manifest = loadBakeManifest(manifestPath);
  ASSERT_TRUE(manifest) << manifest.error().message;
  auto requirements = parse(R"({ "peak_stress_error": 0.5, "refracture": false, "objects": [
      { "name": "tile", "speeds_mps": [3, 3], "impactors": [ { "mass_kg": 0.05, "radius_m": 0.01 } ] },
      { "name": "block", "speeds_mps": [3, 3], "impactors": [ { "mass_kg": 0.05, "radius_m": 0.01 } ] } ] })");
  ASSERT_TRUE(requirements);
  ModelSizingSettings s = quickScene({5, 10}, 20);
  s.fragmentsPerImpact = 2;
  s.elementOrders = {ElementOrder::P1, ElementOrder::P2};
  s.frequencyErrorTarget = 0.4;
  auto report = sizeScene(manifest.value(), std::nullopt, requirements.value(), {dir / "sized.h5", {}}, s);
  ASSERT_TRUE(report) << report.error().message;
  const auto& r = report.value();
  ASSERT_EQ(r.objects.size(), 2u);
  EXPECT_EQ(r.frequencyTargetError, 0.4);
  for (const ObjectSizing& o : r.objects) {
    ASSERT_EQ(o.elementTrials.size(), 2u) << o.object;
    const ElementTrial &p1 = o.elementTrials[0], &p2 = o.elementTrials[1];
    EXPECT_EQ(p1.elementOrder, ElementOrder::P1);
    EXPECT_EQ(p2.frequencyError, 0.0);
    EXPECT_GT(p1.firstFrequencyHz, p2.firstFrequencyHz) << o.object;  // P1 is stiffer on the same tets
    EXPECT_LT(p1.impactValues, p2.impactValues) << o.object;         // and cheaper
    // The 50 % stress target is met in both orders here, so the frequency target decides.
    EXPECT_EQ(p1.targetMet, p1.frequencyError <= 0.4) << o.object;
    EXPECT_TRUE(p2.targetMet) << o.object;
  }
  EXPECT_GT(r.objects[0].elementTrials[0].frequencyError, 0.4);  // the tile locks (measured 1.03)
  EXPECT_EQ(r.objects[0].elementOrder, ElementOrder::P2);
  EXPECT_LT(r.objects[1].elementTrials[0].frequencyError, 0.4);  // the block does not (measured 0.25)
  EXPECT_EQ(r.objects[1].elementOrder, ElementOrder::P1);
  auto sized = readPack(dir / "sized.h5");
  ASSERT_TRUE(sized) << sized.error().message;
  EXPECT_EQ(sized.value().objects[0].elementOrder, ElementOrder::P2);
  EXPECT_EQ(sized.value().objects[1].elementOrder, ElementOrder::P1);
  ASSERT_TRUE(writeSizedManifest(manifestPath, r, dir / "sized.json"));
  auto again = loadBakeManifest(dir / "sized.json");
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_EQ(again.value()[0].elementOrder, ElementOrder::P2);
  EXPECT_EQ(again.value()[1].elementOrder, ElementOrder::P1);

  // Bad order lists are refused before anything is baked.
  s.elementOrders = {ElementOrder::P1, ElementOrder::P1};
  auto twice = sizeScene(manifest.value(), std::nullopt, requirements.value(), {dir / "never.h5", {}}, s);
  ASSERT_FALSE(twice);
  EXPECT_EQ(twice.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(twice.error().message.find("twice"), std::string::npos);
  s.elementOrders = {ElementOrder::P1, ElementOrder::P2};
  s.frequencyErrorTarget = 0.0;
  auto badTarget = sizeScene(manifest.value(), std::nullopt, requirements.value(), {dir / "never.h5", {}}, s);
  ASSERT_FALSE(badTarget);
  EXPECT_EQ(badTarget.error().code, ErrorCode::InvalidArgument);
  EXPECT_FALSE(std::filesystem::exists(dir / "never.h5"));
}

}  // namespace
}  // namespace brittle
