// FrequencyErrorCalibration: the bodies' frequency-error models, calibrated on the runtime's own
// fragments of a pack's objects against their solids in P2 tets. The models are those of the
// match errors (fitMatchErrors), so what is checked here is what the calibration adds: the samples
// are the runtime's fragments with sound indicators, the models are fitted to exactly them,
// checking helps where the Ritz values are furthest off, the same seeds give the same bits, and bad
// settings are typed errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "brittle/precompute/FrequencyErrorCalibration.h"
#include "brittle/precompute/MaterialLibrary.h"
#include "brittle/runtime/PolynomialModes.h"
#include "brittle/testing/BakeFixtures.h"

namespace brittle {
namespace {

const Pack& plate() {
  static const Pack pack = testing::makeGlassPlatePack(1500, 20).value();
  return pack;
}

FrequencyErrorCalibrationSettings small() {
  FrequencyErrorCalibrationSettings s;
  s.speedsMps = {30};
  s.seeds = 2;
  s.maxFragmentsPerImpact = 6;
  s.bins.bins = 3;
  return s;
}

TEST(FrequencyErrorCalibration, FitsTheRuntimesFragmentsAndRepeatsBitForBit) {
  auto made = calibrateFrequencyErrors(plate(), small());
  ASSERT_TRUE(made) << made.error().message;
  const FrequencyErrorCalibration& c = made.value();
  ASSERT_GE(c.samples.size(), 4u);
  std::vector<std::pair<double, double>> ritz, checked;
  for (const FrequencyErrorSample& x : c.samples) {
    EXPECT_EQ(x.object, "plate");
    EXPECT_GE(x.seed, 1001u);  // bench exact-modes' seeds (1, 2, ...) stay held back
    EXPECT_GE(x.ritzIndicator, 0.0);
    EXPECT_GE(x.ritzError, 0.0);
    EXPECT_GT(x.truthF1Hz, 0.0);
    ritz.emplace_back(x.ritzIndicator, x.ritzError);
    if (std::isfinite(x.checkError)) {
      EXPECT_GT(x.checkIndicator, 0.0);
      EXPECT_LT(x.checkIndicator, 1.0);
      EXPECT_LE(x.checkDof, small().checkMaxDof);
      checked.emplace_back(x.checkIndicator, x.checkError);
    }
    std::printf("seed %llu fragment %d: %lld DOF, Ritz %.3f (indicator %.3f), checked %.3f (gain %.3f), in P2 %.3f, truth f1 %.1f Hz\n",
                static_cast<unsigned long long>(x.seed), x.fragment, static_cast<long long>(x.checkDof), x.ritzError,
                x.ritzIndicator, x.checkError, x.checkIndicator, x.checkP2Error, x.truthF1Hz);
  }
  // The models are the samples' own fit.
  const MatchErrorModel expectedRitz = fitMatchErrors(ritz, small().bins).value();
  EXPECT_EQ(c.models.ritz.distance, expectedRitz.distance);
  EXPECT_EQ(c.models.ritz.medianError, expectedRitz.medianError);
  EXPECT_EQ(c.models.ritz.p90Error, expectedRitz.p90Error);
  ASSERT_FALSE(checked.empty());
  EXPECT_EQ(c.models.checked.samples, static_cast<int64_t>(checked.size()));
  EXPECT_TRUE(validateMatchErrorModel(c.models.ritz));
  EXPECT_TRUE(validateMatchErrorModel(c.models.checked));
  // Where the Ritz values are furthest off, the check brings them closer.
  const auto worst = std::max_element(c.samples.begin(), c.samples.end(),
                                      [](const auto& a, const auto& b) { return a.ritzError < b.ritzError; });
  ASSERT_TRUE(std::isfinite(worst->checkError));
  EXPECT_LT(worst->checkError, worst->ritzError);
  ASSERT_FALSE(c.models.checkedP2.empty());
  EXPECT_TRUE(validateMatchErrorModel(c.models.checkedP2));
  for (const FrequencyErrorSample& x : c.samples) {  // P2 removes the linear tets' locking: closer than P1 where both ran
    if (std::isfinite(x.checkP2Error) && x.checkError > 0.15) {
      EXPECT_LT(x.checkP2Error, x.checkError) << x.fragment;
    }
  }
  EXPECT_EQ(c.models.degree, small().degree);
  // The same pack and seeds: the same bits (without the P2 checks, to save the time).
  FrequencyErrorCalibrationSettings linearOnly = small();
  linearOnly.p2Checks = false;
  auto again = calibrateFrequencyErrors(plate(), linearOnly);
  ASSERT_TRUE(again);
  ASSERT_EQ(again.value().samples.size(), c.samples.size());
  for (size_t i = 0; i < c.samples.size(); ++i) {
    EXPECT_EQ(again.value().samples[i].ritzError, c.samples[i].ritzError);
    EXPECT_EQ(again.value().samples[i].ritzIndicator, c.samples[i].ritzIndicator);
    EXPECT_TRUE(again.value().samples[i].checkError == c.samples[i].checkError ||
                (std::isnan(again.value().samples[i].checkError) && std::isnan(c.samples[i].checkError)));
    EXPECT_TRUE(std::isnan(again.value().samples[i].checkP2Error));
  }
  EXPECT_TRUE(again.value().models.checkedP2.empty());
}

// A scene's own impacts (brittle size, calibrate-errors --scene): the objects are the scene's, hit
// by the sizing's draws (drawSceneImpacts: points × impactors × both speed ends), a dropped plate
// on its lowest node as well as a ball; the speeds in the settings are not used.
SceneObjectRange plateScene() {
  SceneObjectRange r;
  r.name = "plate";
  r.minSpeedMps = 20.0;
  r.maxSpeedMps = 40.0;
  SceneImpactor ball;
  ball.massKg = 0.1;
  ball.radiusM = 0.01;
  ball.material = materialPreset("steel").value();
  SceneImpactor ground = ball;  // the ground's material (steel), immovable and flat
  ground.massKg = ground.radiusM = std::numeric_limits<double>::infinity();
  r.impactors = {ball, ground};
  return r;
}

TEST(FrequencyErrorCalibration, ASceneBreaksItsObjectsWithItsOwnImpacts) {
  FrequencyErrorCalibrationSettings s = small();
  s.speedsMps = {-1.0};  // not read with a scene
  s.seeds = 1;
  s.maxFragmentsPerImpact = 1;
  s.p2Checks = false;
  s.scene = {plateScene()};
  auto made = calibrateFrequencyErrors(plate(), s);
  ASSERT_TRUE(made) << made.error().message;
  const FrequencyErrorCalibration& c = made.value();
  EXPECT_EQ(c.impacts, 4);  // 1 point × 2 impactors × 2 speeds
  ASSERT_GE(c.samples.size(), 2u);
  ASSERT_EQ(c.piecesPerObject.size(), 1u);  // the scene's one object, with every sample
  EXPECT_EQ(c.piecesPerObject[0].first, "plate");
  EXPECT_EQ(c.piecesPerObject[0].second, static_cast<int>(c.samples.size()));
  bool ends[2] = {false, false};
  for (const FrequencyErrorSample& x : c.samples) {
    EXPECT_EQ(x.object, "plate");
    ASSERT_TRUE(x.speedMps == 20.0 || x.speedMps == 40.0) << x.speedMps;
    ends[x.speedMps == 40.0] = true;
    EXPECT_GE(x.seed, s.firstSeed);
    EXPECT_LT(x.seed, s.firstSeed + 4);
    EXPECT_TRUE(std::isnan(x.checkP2Error));  // no P2 checks asked for
  }
  EXPECT_TRUE(ends[1]);
  EXPECT_EQ(c.models.ritz.samples, static_cast<int64_t>(c.samples.size()));
  EXPECT_TRUE(c.models.checkedP2.empty());
  // The scene's errors: an object the pack lacks, an object asked for outside the scene, a range
  // without an impactor.
  auto withScene = [&](auto change) {
    FrequencyErrorCalibrationSettings t = s;
    change(t);
    return calibrateFrequencyErrors(plate(), t);
  };
  auto vase = withScene([](auto& t) { t.scene[0].name = "vase"; });
  ASSERT_FALSE(vase);
  EXPECT_EQ(vase.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(vase.error().message.find("vase"), std::string::npos) << vase.error().message;
  EXPECT_EQ(withScene([](auto& t) { t.objects = {"plate", "brick"}; }).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(withScene([](auto& t) { t.scene[0].impactors.clear(); }).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(withScene([](auto& t) { t.scene[0].minSpeedMps = 0.0; }).error().code, ErrorCode::InvalidArgument);
}

TEST(FrequencyErrorCalibration, BadSettingsAreTypedErrors) {
  auto with = [](auto change) {
    FrequencyErrorCalibrationSettings s = small();
    change(s);
    return calibrateFrequencyErrors(plate(), s);
  };
  EXPECT_EQ(with([](auto& s) { s.speedsMps = {}; }).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(with([](auto& s) { s.speedsMps = {-1.0}; }).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(with([](auto& s) { s.seeds = 0; }).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(with([](auto& s) { s.degree = 2; }).error().code, ErrorCode::InvalidArgument);  // no degree two below it
  EXPECT_EQ(with([](auto& s) { s.degree = kMaxPolynomialModeDegree + 1; }).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(with([](auto& s) { s.objects = {"vase"}; }).error().code, ErrorCode::InvalidArgument);
  // An impact too soft to break anything leaves no fragment to calibrate on.
  auto soft = with([](auto& s) { s.speedsMps = {0.01}; });
  ASSERT_FALSE(soft);
  EXPECT_EQ(soft.error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(calibrateFrequencyErrors(Pack{}, small()).error().code, ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace brittle
