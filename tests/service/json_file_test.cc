// common/json_file: JSON texts and files parsed with their errors named, nesting bounded.
#include "common/json_file.h"

#include <gtest/gtest.h>

#include <string>

#include "common/error.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

TEST(JsonFileTest, ATextIsParsedOrRefusedNamingWhatItIs) {
  EXPECT_EQ(ParseJson(R"({"a": [1, 2]})", "config")["a"][1], 2);
  const std::string message = testing::ErrorFrom([] { ParseJson("{\"a\": ", "--config c.json"); });
  EXPECT_NE(message.find("--config c.json: not valid JSON"), std::string::npos) << message;
}

// 60,000 nested arrays in a 120 kB --config crashed the reconstruction (a recursive walk; found
// 2026-12-05).
TEST(JsonFileTest, NestingDeeperThanItsBoundIsRefused) {
  const auto nested = [](int depth) { return std::string(depth, '[') + std::string(depth, ']'); };
  EXPECT_NO_THROW(ParseJson(nested(kMostJsonDepth), "config"));
  std::string message = testing::ErrorFrom([&] { ParseJson(nested(kMostJsonDepth + 1), "config"); });
  EXPECT_NE(message.find("config: nested deeper than 64 levels"), std::string::npos) << message;
  testing::TempDir dir("json-file");
  testing::WriteBytes(dir / "deep.json", "{\"adam\": " + nested(100000) + "}");
  message = testing::ErrorFrom([&] { ReadJsonFile(dir / "deep.json"); });
  EXPECT_NE(message.find("deep.json: nested deeper than 64 levels"), std::string::npos) << message;
}

}  // namespace
}  // namespace endorecon
