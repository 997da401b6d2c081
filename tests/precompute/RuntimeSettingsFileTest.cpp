// The runtime settings file `brittle size` writes and play/impact --settings read.
#include "brittle/precompute/RuntimeSettingsFile.h"

#include <gtest/gtest.h>

#include <fstream>

#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

TEST(RuntimeSettingsFile, WritesAndReadsBackEveryKey) {
  FractureSettings s;
  s.descriptor = DescriptorKind::VoxelImproved;
  s.debrisVolumeFraction = 0.004;
  s.contactSpreadFraction = 0.12;
  s.exactModesMaxTets = 321;
  s.exactModeCount = 12;
  s.exactModesDelayS = 0.4;
  s.polynomialModeDegree = 3;
  s.meshRatioMaxDof = 2345;
  s.meshRatioDelayS = 0.125;
  s.meshRatioLateMaxDof = 6789;
  s.meshRatioLateDelayS = 0.75;
  s.frequencyErrorTarget = 0.2;
  s.meshRatioEscalationDelayS = 3.5;
  s.meshRatioElement = ElementOrder::P2;
  s.crack.endAtCracks = true;
  s.modeCount = 15;
  const auto dir = testing::makeTempDir("runtime-settings");
  std::ofstream(dir / "s.json") << runtimeSettingsJson(s);
  auto back = loadRuntimeSettings(dir / "s.json");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back.value().descriptor, DescriptorKind::VoxelImproved);
  EXPECT_EQ(back.value().debrisVolumeFraction, 0.004);
  EXPECT_EQ(back.value().contactSpreadFraction, 0.12);
  EXPECT_EQ(back.value().exactModesMaxTets, 321);
  EXPECT_EQ(back.value().exactModeCount, 12);
  EXPECT_EQ(back.value().exactModesDelayS, 0.4);
  EXPECT_EQ(back.value().polynomialModeDegree, 3);
  EXPECT_EQ(back.value().meshRatioMaxDof, 2345);
  EXPECT_EQ(back.value().meshRatioDelayS, 0.125);
  EXPECT_EQ(back.value().meshRatioLateMaxDof, 6789);
  EXPECT_EQ(back.value().meshRatioLateDelayS, 0.75);
  EXPECT_EQ(back.value().frequencyErrorTarget, 0.2);
  EXPECT_EQ(back.value().meshRatioEscalationDelayS, 3.5);
  EXPECT_EQ(back.value().meshRatioElement, ElementOrder::P2);
  EXPECT_TRUE(back.value().crack.endAtCracks);
  EXPECT_EQ(back.value().modeCount, 15);
}

TEST(RuntimeSettingsFile, MissingKeysKeepTheBase) {
  FractureSettings base;
  base.modeCount = 7;
  base.pulseSteps = 33;
  auto r = parseRuntimeSettings(R"({ "debris_volume_fraction": 0.2 })", "t", base);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r.value().debrisVolumeFraction, 0.2);
  EXPECT_EQ(r.value().modeCount, 7);
  EXPECT_EQ(r.value().pulseSteps, 33);
  EXPECT_EQ(r.value().descriptor, base.descriptor);
}

TEST(RuntimeSettingsFile, BadFilesGiveTypedErrors) {
  auto code = [](const char* json) {
    auto r = parseRuntimeSettings(json, "t");
    return r ? std::string("ok") : std::string(errorCodeName(r.error().code));
  };
  EXPECT_EQ(code("{"), "parse_error");
  EXPECT_EQ(code("[]"), "parse_error");
  EXPECT_EQ(code(R"({ "debris": 0.1 })"), "parse_error");                  // unknown key (a typo)
  EXPECT_EQ(code(R"({ "descriptor": "fourier" })"), "parse_error");        // unknown descriptor
  EXPECT_EQ(code(R"({ "descriptor": 3 })"), "parse_error");
  EXPECT_EQ(code(R"({ "modes": 2.5 })"), "parse_error");
  EXPECT_EQ(code(R"({ "modes": -1 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "modes": 1e12 })"), "parse_error");                  // not an integer in JSON
  EXPECT_EQ(code(R"({ "modes": 99999999999 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "debris_volume_fraction": 1.0 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "debris_volume_fraction": "a" })"), "parse_error");
  EXPECT_EQ(code(R"({ "contact_spread_fraction": 1.0 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "contact_spread_fraction": -0.1 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "contact_spread_fraction": [0.1] })"), "parse_error");
  EXPECT_EQ(code(R"({ "contact_spread_fraction": 0 })"), "ok");
  EXPECT_EQ(code(R"({ "exact_mode_count": 0 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "frequency_error_target": -0.1 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "frequency_error_target": "high" })"), "parse_error");
  EXPECT_EQ(code(R"({ "mesh_ratio_escalation_delay_s": -1 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "mesh_ratio_late_delay_s": -1 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "mesh_ratio_delay_s": -1 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "exact_modes_delay_s": -1 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "exact_modes_delay_s": 0 })"), "ok");
  EXPECT_EQ(code(R"({ "exact_modes_max_tets": 0 })"), "ok");
  EXPECT_EQ(code(R"({ "polynomial_mode_degree": 6 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "polynomial_mode_degree": -1 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "polynomial_mode_degree": 0 })"), "ok");
  EXPECT_EQ(code(R"({ "mesh_ratio_max_dof": -1 })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "mesh_ratio_max_dof": 0 })"), "ok");
  EXPECT_EQ(code(R"({ "mesh_ratio_element": "p3" })"), "invalid_argument");
  EXPECT_EQ(code(R"({ "mesh_ratio_element": 2 })"), "parse_error");
  EXPECT_EQ(code(R"({ "mesh_ratio_element": "p2" })"), "ok");
  EXPECT_EQ(code(R"({ "end_at_cracks": 1 })"), "parse_error");  // a boolean, not a number
  EXPECT_EQ(code(R"({ "end_at_cracks": "yes" })"), "parse_error");
  EXPECT_EQ(code(R"({ "end_at_cracks": false })"), "ok");
  auto missing = loadRuntimeSettings("no-such-settings.json");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::FileNotFound);
}

}  // namespace
}  // namespace brittle
