// The scene reader: the default scenes load, and every kind of bad input is a typed error that
// names the key.
#include "brittle/player/Scene.h"

#include <gtest/gtest.h>

#include <cmath>

#include "brittle/testing/Fixtures.h"

namespace brittle {
namespace {

const char* kMinimal = R"({"duration": 1, "time_step": 0.01,
  "objects": [{"asset": "brick", "position": [0, 0, 1]}]})";

Error parseError(const std::string& json) {
  auto s = parseScene(json, "t.json");
  EXPECT_FALSE(s) << json;
  return s ? Error{ErrorCode::Cancelled, ""} : s.error();
}

TEST(SceneTest, DefaultScenesLoad) {
  for (const char* name : {"plate-drop", "ball-through-pane", "brick-stack", "vase-drop"}) {
    auto s = loadScene(testing::sourceDir() / "assets" / "scenes" / (std::string(name) + ".json"));
    ASSERT_TRUE(s) << name << ": " << s.error().message;
    EXPECT_EQ(s.value().name, name);
    EXPECT_TRUE(s.value().floor.has_value());
    EXPECT_FALSE(s.value().objects.empty());
  }
}

TEST(SceneTest, MinimalSceneGetsTheDefaults) {
  auto s = parseScene(kMinimal, "t.json");
  ASSERT_TRUE(s) << s.error().message;
  const Scene& scene = s.value();
  EXPECT_EQ(scene.gravityMps2, Eigen::Vector3d(0, 0, -9.81));
  EXPECT_EQ(scene.substeps, 1);
  EXPECT_EQ(scene.seed, 1u);
  EXPECT_FALSE(scene.floor);
  ASSERT_EQ(scene.objects.size(), 1u);
  EXPECT_EQ(scene.objects[0].name, "brick");
  EXPECT_FALSE(scene.objects[0].isStatic);
  EXPECT_TRUE(scene.objects[0].rotation.isApprox(Eigen::Quaterniond::Identity()));
}

TEST(SceneTest, RotationsAsAxisAngleOrQuaternionAgree) {
  auto a = parseScene(R"({"duration": 1, "time_step": 0.01, "objects": [{"asset": "b", "position": [0, 0, 0],
    "rotation": {"axis": [0, 0, 2], "angle_deg": 90}}]})");
  auto q = parseScene(R"({"duration": 1, "time_step": 0.01, "objects": [{"asset": "b", "position": [0, 0, 0],
    "rotation": {"quaternion": [0.7071067811865476, 0, 0, 0.7071067811865476]}}]})");
  ASSERT_TRUE(a && q);
  EXPECT_TRUE(a.value().objects[0].rotation.isApprox(q.value().objects[0].rotation, 1e-12));
  const Eigen::Vector3d x = a.value().objects[0].rotation * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x.y(), 1.0, 1e-12);
}

TEST(SceneTest, MissingFileIsFileNotFound) {
  auto s = loadScene(testing::sourceDir() / "assets" / "scenes" / "no-such-scene.json");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::FileNotFound);
}

TEST(SceneTest, BadJsonIsParseError) {
  EXPECT_EQ(parseError("{\"duration\": 1,").code, ErrorCode::ParseError);
  EXPECT_EQ(parseError("[1, 2]").code, ErrorCode::ParseError);
  // A number beyond double's range (found by fuzz_play_scene_json).
  EXPECT_EQ(parseError(R"({"duration": 1, "time_step": 1e999, "objects": []})").code, ErrorCode::ParseError);
}

TEST(SceneTest, UnknownKeysAreRefusedByName) {
  Error e = parseError(R"({"duration": 1, "time_step": 0.01, "objects": [{"asset": "b", "posiiton": [0, 0, 0]}]})");
  EXPECT_EQ(e.code, ErrorCode::ParseError);
  EXPECT_NE(e.message.find("objects[0].posiiton"), std::string::npos) << e.message;
  e = parseError(R"({"duration": 1, "time_step": 0.01, "gravitation": [0, 0, -9.81], "objects": []})");
  EXPECT_NE(e.message.find("gravitation"), std::string::npos) << e.message;
  e = parseError(R"({"duration": 1, "time_step": 0.01, "objects": [], "impactors": [{"shape": "sphere", "radius": 0.1,
    "half_extents": [1, 1, 1], "mass": 1, "position": [0, 0, 0]}]})");
  EXPECT_NE(e.message.find("impactors[0].half_extents"), std::string::npos) << e.message;
}

TEST(SceneTest, MissingAndMistypedKeysAreParseErrorsNamingTheKey) {
  Error e = parseError(R"({"time_step": 0.01, "objects": []})");
  EXPECT_EQ(e.code, ErrorCode::ParseError);
  EXPECT_NE(e.message.find("duration"), std::string::npos) << e.message;
  e = parseError(R"({"duration": "long", "time_step": 0.01, "objects": []})");
  EXPECT_EQ(e.code, ErrorCode::ParseError);
  EXPECT_NE(e.message.find("duration"), std::string::npos) << e.message;
  e = parseError(R"({"duration": 1, "time_step": 0.01, "objects": [{"asset": "b", "position": [0, 0]}]})");
  EXPECT_EQ(e.code, ErrorCode::ParseError);
  EXPECT_NE(e.message.find("objects[0].position"), std::string::npos) << e.message;
  e = parseError(R"({"duration": 1, "time_step": 0.01, "objects": [], "impactors": [{"shape": "cone", "mass": 1,
    "position": [0, 0, 0]}]})");
  EXPECT_NE(e.message.find("impactors[0].shape"), std::string::npos) << e.message;
  e = parseError(R"({"duration": 1, "time_step": 0.01, "objects": [{"asset": "b", "position": [0, 0, 0],
    "rotation": {"axis": [1, 0, 0], "angle_deg": 5, "quaternion": [1, 0, 0, 0]}}]})");
  EXPECT_EQ(e.code, ErrorCode::ParseError);
}

TEST(SceneTest, OutOfRangeValuesAreInvalidArgumentNamingTheKey) {
  struct Case {
    const char* json;
    const char* key;
  };
  const Case cases[] = {
      {R"({"duration": -1, "time_step": 0.01, "objects": [{"asset": "b", "position": [0, 0, 0]}]})", "duration"},
      {R"({"duration": 1, "time_step": 0, "objects": [{"asset": "b", "position": [0, 0, 0]}]})", "time_step"},
      {R"({"duration": 1, "time_step": 2, "objects": [{"asset": "b", "position": [0, 0, 0]}]})", "time_step"},
      {R"({"duration": 500, "time_step": 0.001, "objects": [{"asset": "b", "position": [0, 0, 0]}]})", "duration"},
      {R"({"duration": 1, "time_step": 0.01, "substeps": 0, "objects": [{"asset": "b", "position": [0, 0, 0]}]})", "substeps"},
      {R"({"duration": 1, "time_step": 0.01, "objects": [{"asset": "b", "position": [0, 0, 0],
         "rotation": {"axis": [0, 0, 0], "angle_deg": 5}}]})", "objects[0].rotation.axis"},
      {R"({"duration": 1, "time_step": 0.01, "objects": [], "impactors": [{"shape": "sphere", "radius": 0.1,
         "mass": -2, "position": [0, 0, 0]}]})", "impactors[0].mass"},
      {R"({"duration": 1, "time_step": 0.01, "objects": [], "impactors": [{"shape": "box",
         "half_extents": [1, 0, 1], "mass": 2, "position": [0, 0, 0]}]})", "impactors[0].half_extents"},
      {R"({"duration": 1, "time_step": 0.01, "objects": []})", "objects"},
  };
  for (const Case& c : cases) {
    const Error e = parseError(c.json);
    EXPECT_EQ(e.code, ErrorCode::InvalidArgument) << c.json << "\n" << e.message;
    EXPECT_NE(e.message.find(c.key), std::string::npos) << e.message;
  }
}

TEST(SceneTest, UnknownMaterialIsTyped) {
  Error e = parseError(R"({"duration": 1, "time_step": 0.01, "floor": {"material": "cheese"}, "objects": [{"asset": "b",
    "position": [0, 0, 0]}]})");
  EXPECT_EQ(e.code, ErrorCode::UnknownMaterial);
  EXPECT_NE(e.message.find("floor.material"), std::string::npos) << e.message;
}

}  // namespace
}  // namespace brittle
