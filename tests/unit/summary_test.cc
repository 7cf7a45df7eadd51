#include "worker/engine/eval/summary.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <vector>

namespace endorecon::eval {
namespace {

TEST(Summary, UndefinedValuesAreLeftOut) {
  const std::vector<double> values = {1, 2, 3, std::nan(""), std::numeric_limits<double>::infinity()};
  const Summary s = Summarise(values);
  EXPECT_EQ(s.count, 3);
  EXPECT_DOUBLE_EQ(s.mean, 2.0);
  EXPECT_NEAR(s.std, std::sqrt(2.0 / 3.0), 1e-12);
  EXPECT_EQ(s.min, 1.0);
  EXPECT_EQ(s.max, 3.0);
}

TEST(Summary, NothingDefinedSerialisesAsNull) {
  const std::vector<double> values = {std::nan("")};
  const Summary s = Summarise(values);
  EXPECT_EQ(s.count, 0);
  EXPECT_TRUE(std::isnan(s.mean));
  const nlohmann::json j = nlohmann::json::parse(ToJson(s).dump());
  EXPECT_TRUE(j["mean"].is_null());
  EXPECT_EQ(j["count"].get<int>(), 0);
}

TEST(Summary, FramesAreSummarisedByKey) {
  nlohmann::json per_frame = nlohmann::json::array();
  per_frame.push_back({{"a", 1.0}, {"b", 4.0}});
  per_frame.push_back({{"a", 3.0}, {"b", nullptr}});
  per_frame.push_back({{"a", std::nan("")}});
  const nlohmann::json j = SummariseFrames(per_frame, {"a", "b"});
  EXPECT_DOUBLE_EQ(j["a"]["mean"].get<double>(), 2.0);
  EXPECT_EQ(j["a"]["count"].get<int>(), 2);
  EXPECT_DOUBLE_EQ(j["b"]["mean"].get<double>(), 4.0);
  EXPECT_EQ(j["b"]["count"].get<int>(), 1);
  EXPECT_EQ(j["per_frame"].dump(), per_frame.dump());
}

}  // namespace
}  // namespace endorecon::eval
