#include "brittle/core/JsonChecks.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>

namespace brittle {
namespace {

TEST(JsonChecksTest, FindsTheFirstUnknownKey) {
  const auto doc = nlohmann::json::parse(R"({"mesh": "a.off", "matrial": "concrete", "zz": 1})");
  EXPECT_EQ(findUnknownKey(doc, {"mesh", "material", "zz"}), "matrial");
  EXPECT_EQ(findUnknownKey(doc, std::set<std::string>{"mesh", "matrial", "zz"}), std::nullopt);
  const char* const keys[] = {"mesh", "material"};
  EXPECT_EQ(findUnknownKey(doc, keys), "matrial");
}

TEST(JsonChecksTest, UnknownKeysAreParseErrorsNamingTheKey) {
  const auto doc = nlohmann::json::parse(R"({"seed": 1, "colour": "red"})");
  const Status st = checkKnownKeys(doc, {"seed"}, "manifest m.json, object 0");
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().code, ErrorCode::ParseError);
  EXPECT_EQ(st.error().message, "manifest m.json, object 0: unknown key \"colour\"");
  EXPECT_TRUE(checkKnownKeys(doc, {"seed", "colour"}, "m"));
}

}  // namespace
}  // namespace brittle
