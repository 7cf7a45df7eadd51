#include "worker/engine/train/train_config.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "common/error.h"

namespace endorecon::train {
namespace {

TEST(TrainConfigTest, JsonRoundTripKeepsEveryKey) {
  TrainConfig config = TrainConfig::Preset("paper");
  config.depth_xi = 0.123;
  config.field.heads.color_hidden = {7, 9};
  config.adam.lr["grid"] = 0.5f;
  TrainConfig back = TrainConfig::Preset("cpu");
  ApplyJson(ToJson(config), back);
  EXPECT_EQ(ToJson(back), ToJson(config));
}

TEST(TrainConfigTest, EmptyObjectChangesNothing) {
  TrainConfig config = TrainConfig::Preset("cpu");
  ApplyJson(nlohmann::json::object(), config);
  EXPECT_EQ(ToJson(config), ToJson(TrainConfig::Preset("cpu")));
}

TEST(TrainConfigTest, UnknownKeyIsNamed) {
  TrainConfig config;
  try {
    ApplyJson(nlohmann::json{{"iterations", 5}, {"field", {{"grids", {{"levelz", 3}}}}}}, config);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("levelz"), std::string::npos) << e.what();
  }
}

TEST(TrainConfigTest, BadValuesAreRejected) {
  TrainConfig config;
  EXPECT_THROW(ApplyJson(nlohmann::json{{"iterations", "many"}}, config), Error);
  EXPECT_THROW(ApplyJson(nlohmann::json{{"depth_loss", "l3"}}, config), Error);
  EXPECT_THROW(ApplyJson(nlohmann::json{{"rays_per_batch", 0}}, config), Error);
  EXPECT_THROW(TrainConfig::Preset("gpu-ultra"), Error);
  // Each names its key.
  for (const auto& bad : {nlohmann::json{{"depth_refine_pixels", -1}},
                          nlohmann::json{{"field", {{"heads", {{"dropout", 1.0}}}}}},
                          nlohmann::json{{"field", {{"heads", {{"color_dropout", 1.5}}}}}}}) {
    TrainConfig fresh;
    const std::string key = bad.flatten().begin().key();  // "/field/heads/dropout"
    const std::string leaf = key.substr(key.rfind('/') + 1);
    try {
      ApplyJson(bad, fresh);
      ADD_FAILURE() << bad.dump() << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(leaf), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace endorecon::train
