// The viewer's script reader (ViewerScript.h): every action, ordering, typed errors.
#include "brittle/viewer/ViewerScript.h"

#include <gtest/gtest.h>

namespace brittle {
namespace {

std::string codeOf(const char* json) {
  auto r = parseViewerScript(json, "t");
  return r ? "ok" : std::string(errorCodeName(r.error().code));
}

TEST(ViewerScript, ReadsEveryActionInFrameOrder) {
  auto s = parseViewerScript(R"({ "events": [
      { "frame": 40, "action": "screenshot", "file": "a.png" },
      { "frame": 10, "action": "throw", "from": [0, -1, 0.5], "to": [0, 0, 0.5], "speed": 12, "radius": 0.03,
        "mass": 0.4, "material": "stone" },
      { "frame": 40, "action": "camera", "yaw_deg": 30, "distance": 1.5 },
      { "frame": 50, "action": "pause" }, { "frame": 50, "action": "step" }, { "frame": 50, "action": "resume" },
      { "frame": 60, "action": "quit" } ] })", "t");
  ASSERT_TRUE(s) << s.error().message;
  const auto& e = s.value().events;
  ASSERT_EQ(e.size(), 7u);
  EXPECT_EQ(e[0].action, ScriptAction::Throw);
  EXPECT_EQ(e[0].frame, 10);
  EXPECT_EQ(e[0].from, Eigen::Vector3d(0, -1, 0.5));
  EXPECT_EQ(e[0].speedMps, 12.0);
  EXPECT_EQ(e[0].radiusM, 0.03);
  EXPECT_EQ(e[0].massKg, 0.4);
  EXPECT_EQ(e[0].material, "stone");
  EXPECT_EQ(e[1].action, ScriptAction::Screenshot);  // file order within a frame
  EXPECT_EQ(e[1].file, "a.png");
  EXPECT_EQ(e[2].action, ScriptAction::Camera);
  EXPECT_EQ(*e[2].yawDeg, 30.0);
  EXPECT_FALSE(e[2].pitchDeg);
  EXPECT_EQ(*e[2].distanceM, 1.5);
  EXPECT_EQ(e[3].action, ScriptAction::Pause);
  EXPECT_EQ(e[4].action, ScriptAction::Step);
  EXPECT_EQ(e[5].action, ScriptAction::Resume);
  EXPECT_EQ(e[6].action, ScriptAction::Quit);
  // Defaults of a throw.
  auto d = parseViewerScript(R"({ "events": [ { "frame": 0, "action": "throw", "from": [0, 0, 1], "to": [0, 0, 0] } ] })");
  ASSERT_TRUE(d);
  EXPECT_EQ(d.value().events[0].radiusM, 0.02);
  EXPECT_EQ(d.value().events[0].massKg, 0.2);
  EXPECT_EQ(d.value().events[0].material, "steel");
}

TEST(ViewerScript, BadScriptsGiveTypedErrors) {
  EXPECT_EQ(codeOf("{"), "parse_error");
  EXPECT_EQ(codeOf("[]"), "parse_error");
  EXPECT_EQ(codeOf(R"({ "event": [] })"), "parse_error");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "dance" } ] })"), "parse_error");
  EXPECT_EQ(codeOf(R"({ "events": [ { "action": "quit" } ] })"), "parse_error");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1.5, "action": "quit" } ] })"), "parse_error");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": -1, "action": "quit" } ] })"), "invalid_argument");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "quit", "file": "x" } ] })"), "parse_error");  // unknown key
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "throw", "from": [0, 0, 1] } ] })"), "parse_error");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "throw", "from": [0, 0], "to": [0, 0, 0] } ] })"), "parse_error");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "throw", "from": [0, 0, 1], "to": [0, 0, 1] } ] })"),
            "invalid_argument");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "throw", "from": [0, 0, 1], "to": [0, 0, 0], "speed": 0 } ] })"),
            "invalid_argument");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "throw", "from": [0, 0, 1], "to": [0, 0, 0], "mass": -1 } ] })"),
            "invalid_argument");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "throw", "from": [0, 0, 1], "to": [0, 0, 0], "material": "cheese" } ] })"),
            "unknown_material");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "screenshot" } ] })"), "parse_error");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "screenshot", "file": "" } ] })"), "invalid_argument");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "camera", "pitch_deg": 90 } ] })"), "invalid_argument");
  EXPECT_EQ(codeOf(R"({ "events": [ { "frame": 1, "action": "camera", "distance": 0 } ] })"), "invalid_argument");
  EXPECT_EQ(codeOf(R"({ "events": [] })"), "ok");
  auto missing = loadViewerScript("no-such-script.json");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::FileNotFound);
}

}  // namespace
}  // namespace brittle
