#include "worker/engine/train/train_config.h"

#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "common/error.h"
#include "worker/engine/train/config_check.h"

namespace endorecon::train {
namespace {

// Every field set by hand to a value no preset has, written out and read back into a fresh
// configuration, then compared field by field: a key missing from the serialisation table (in either
// direction) leaves its field at the preset's value and fails here. The key list is written out too.
TEST(TrainConfigTest, JsonRoundTripKeepsEveryKey) {
  TrainConfig c;
  c.preset = "custom";
  c.iterations = 1234;
  c.rays_per_batch = 77;
  c.depth_samples = 5;
  c.stratified_samples = 6;
  c.depth_xi = 0.123;
  c.holdout = 5;
  c.nll_weight = 0.5f;
  c.nll_beta = 0.25f;
  c.rgb_l2_weight = 0.75f;
  c.depth_weight = 0.125f;
  c.variance_reg = 0.0625f;
  c.depth_loss = "huber";
  c.huber_delta = 0.03125f;
  c.variance_eps = 2e-6f;
  c.adam.lr = {{"grid", 0.5f}, {"color", 0.25f}};
  c.adam.default_lr = 0.015625f;
  c.adam.beta1 = 0.8f;
  c.adam.beta2 = 0.9f;
  c.adam.eps = 1e-7f;
  c.adam.final_lr_factor = 0.5f;
  c.adam.clip_norm = 3.0f;
  c.eval_coarse_samples = 11;
  c.eval_fine_samples = 13;
  c.eval_floor = 0.0625f;
  c.mc_passes = 3;
  c.uncertainty_lambda = 42.0f;
  c.adaptive_sampling = false;
  c.adaptive_warmup = 0.375;
  c.adaptive_ray_fraction = 0.125f;
  c.adaptive_refresh = 17;
  c.adaptive_map_stride = 3;
  c.adaptive_floor = 0.375f;
  c.depth_refine_every = 0.0625;
  c.depth_refine_fraction = 0.3125f;
  c.depth_refine_ema = 0.4375f;
  c.depth_refine_samples = 19;
  c.depth_refine_pixels = 2345;
  c.occupancy_resolution = 33;
  c.occupancy_every = 0.1875;
  c.occupancy_min_alpha = 0.0078125f;
  c.background = "learned";
  c.field.learned_background = true;
  c.field.trained_times = {0.125f, 0.875f};
  c.curve_interval_s = 4.5;
  c.curve_frames = 7;
  c.field.encoding = "frequency";
  c.field.frequencies = 6;
  c.field.grids.base_resolutions = {3, 5};
  c.field.grids.scales = {1.25, 1.75};
  c.field.grids.levels = 7;
  c.field.grids.features = 4;
  c.field.grids.log2_table = 12;
  c.field.grids.max_resolution = 99;
  c.field.blend_hidden = 9;
  c.field.deformation.enabled = false;
  c.field.deformation.resolution = 21;
  c.field.deformation.time_knots = 23;
  c.field.heads.color_time_frequencies = 3;
  c.field.heads.density_hidden = {7, 9};
  c.field.heads.color_hidden = {10};
  c.field.heads.geo_features = 8;
  c.field.heads.dropout = 0.15;
  c.field.heads.color_dropout = 0.35;

  const nlohmann::json json = ToJson(c);
  const std::set<std::string> expected_top = {"adam",
                                              "adaptive_floor",
                                              "adaptive_map_stride",
                                              "adaptive_ray_fraction",
                                              "adaptive_refresh",
                                              "adaptive_sampling",
                                              "adaptive_warmup",
                                              "background",
                                              "curve_frames",
                                              "curve_interval_s",
                                              "deformation_start",
                                              "depth_fill_sigma",
                                              "depth_loss",
                                              "depth_refine_ema",
                                              "depth_refine_every",
                                              "depth_refine_fraction",
                                              "depth_refine_pixels",
                                              "depth_refine_samples",
                                              "depth_samples",
                                              "depth_weight",
                                              "depth_xi",
                                              "eval_coarse_samples",
                                              "eval_fine_samples",
                                              "eval_floor",
                                              "exposure",
                                              "exposure_threshold",
                                              "field",
                                              "fit_depth_bounds",
                                              "holdout",
                                              "huber_delta",
                                              "iterations",
                                              "mc_passes",
                                              "nll_beta",
                                              "nll_weight",
                                              "occupancy_every",
                                              "occupancy_min_alpha",
                                              "occupancy_resolution",
                                              "outside_view",
                                              "outside_view_level",
                                              "preset",
                                              "rays_per_batch",
                                              "rgb_l2_weight",
                                              "still_threshold_px",
                                              "stratified_samples",
                                              "uncertainty_lambda",
                                              "variance_eps",
                                              "variance_reg"};
  std::set<std::string> top;
  for (const auto& [key, value] : json.items()) top.insert(key);
  EXPECT_EQ(top, expected_top);
  EXPECT_EQ(json.at("adam").size(), 7u);
  // Floats as the shortest decimals that read back as them: config.json showed 0.800000011920929.
  EXPECT_EQ(json.at("adam").at("beta1").get<double>(), 0.8);
  EXPECT_EQ(json.at("adam").at("eps").get<double>(), 1e-7);
  EXPECT_EQ(json.at("adam").at("lr").at("color").get<double>(), 0.25);
  // encoding, frequencies, grids, blend_hidden, deformation, heads, exposure_times, learned_background,
  // trained_times
  EXPECT_EQ(json.at("field").size(), 9u);
  EXPECT_EQ(json.at("field").at("grids").size(), 6u);
  EXPECT_EQ(json.at("field").at("deformation").size(), 3u);
  EXPECT_EQ(json.at("field").at("heads").size(), 6u);

  TrainConfig b = TrainConfig::Preset("cpu");
  ApplyJson(json, b);
  EXPECT_EQ(b.preset, "custom");
  EXPECT_EQ(b.iterations, 1234);
  EXPECT_EQ(b.rays_per_batch, 77);
  EXPECT_EQ(b.depth_samples, 5);
  EXPECT_EQ(b.stratified_samples, 6);
  EXPECT_EQ(b.depth_xi, 0.123);
  EXPECT_EQ(b.holdout, 5);
  EXPECT_EQ(b.nll_weight, 0.5f);
  EXPECT_EQ(b.nll_beta, 0.25f);
  EXPECT_EQ(b.rgb_l2_weight, 0.75f);
  EXPECT_EQ(b.depth_weight, 0.125f);
  EXPECT_EQ(b.variance_reg, 0.0625f);
  EXPECT_EQ(b.depth_loss, "huber");
  EXPECT_EQ(b.huber_delta, 0.03125f);
  EXPECT_EQ(b.variance_eps, 2e-6f);
  EXPECT_EQ(b.adam.lr.at("grid"), 0.5f);  // the preset's other rates stay (a map merges)
  EXPECT_EQ(b.adam.lr.at("color"), 0.25f);
  EXPECT_EQ(b.adam.default_lr, 0.015625f);
  EXPECT_EQ(b.adam.beta1, 0.8f);
  EXPECT_EQ(b.adam.beta2, 0.9f);
  EXPECT_EQ(b.adam.eps, 1e-7f);
  EXPECT_EQ(b.adam.final_lr_factor, 0.5f);
  EXPECT_EQ(b.adam.clip_norm, 3.0f);
  EXPECT_EQ(b.eval_coarse_samples, 11);
  EXPECT_EQ(b.eval_fine_samples, 13);
  EXPECT_EQ(b.eval_floor, 0.0625f);
  EXPECT_EQ(b.mc_passes, 3);
  EXPECT_EQ(b.uncertainty_lambda, 42.0f);
  EXPECT_EQ(b.adaptive_sampling, false);
  EXPECT_EQ(b.adaptive_warmup, 0.375);
  EXPECT_EQ(b.adaptive_ray_fraction, 0.125f);
  EXPECT_EQ(b.adaptive_refresh, 17);
  EXPECT_EQ(b.adaptive_map_stride, 3);
  EXPECT_EQ(b.adaptive_floor, 0.375f);
  EXPECT_EQ(b.depth_refine_every, 0.0625);
  EXPECT_EQ(b.depth_refine_fraction, 0.3125f);
  EXPECT_EQ(b.depth_refine_ema, 0.4375f);
  EXPECT_EQ(b.depth_refine_samples, 19);
  EXPECT_EQ(b.depth_refine_pixels, 2345);
  EXPECT_EQ(b.occupancy_resolution, 33);
  EXPECT_EQ(b.occupancy_every, 0.1875);
  EXPECT_EQ(b.occupancy_min_alpha, 0.0078125f);
  EXPECT_EQ(b.background, "learned");
  EXPECT_TRUE(b.field.learned_background);
  EXPECT_EQ(b.field.trained_times, (std::array<float, 2>{0.125f, 0.875f}));
  EXPECT_EQ(b.curve_interval_s, 4.5);
  EXPECT_EQ(b.curve_frames, 7);
  EXPECT_EQ(b.field.encoding, "frequency");
  EXPECT_EQ(b.field.frequencies, 6);
  EXPECT_EQ(b.field.grids.base_resolutions, (std::vector<int>{3, 5}));
  EXPECT_EQ(b.field.grids.scales, (std::vector<double>{1.25, 1.75}));
  EXPECT_EQ(b.field.grids.levels, 7);
  EXPECT_EQ(b.field.grids.features, 4);
  EXPECT_EQ(b.field.grids.log2_table, 12);
  EXPECT_EQ(b.field.grids.max_resolution, 99);
  EXPECT_EQ(b.field.blend_hidden, 9);
  EXPECT_EQ(b.field.deformation.enabled, false);
  EXPECT_EQ(b.field.deformation.resolution, 21);
  EXPECT_EQ(b.field.deformation.time_knots, 23);
  EXPECT_EQ(b.field.heads.density_hidden, (std::vector<int>{7, 9}));
  EXPECT_EQ(b.field.heads.color_hidden, (std::vector<int>{10}));
  EXPECT_EQ(b.field.heads.geo_features, 8);
  EXPECT_EQ(b.field.heads.dropout, 0.15);
  EXPECT_EQ(b.field.heads.color_dropout, 0.35);
  EXPECT_EQ(b.field.heads.color_time_frequencies, 3);
}

TEST(TrainConfigTest, ARateMapMergesIntoThePresets) {
  TrainConfig c = TrainConfig::Preset("cpu");
  const auto before = c.adam.lr;
  ApplyJson(nlohmann::json::parse(R"({"adam": {"lr": {"grid": 0.05, "exposure": 0.5}}})"), c);
  EXPECT_EQ(c.adam.lr.at("grid"), 0.05f);
  EXPECT_EQ(c.adam.lr.at("exposure"), 0.5f) << "a group the preset leaves at the default rate";
  for (const auto& [group, rate] : before) {
    if (group != "grid") {
      EXPECT_EQ(c.adam.lr.at(group), rate) << group << " kept";
    }
  }
  EXPECT_EQ(c.adam.lr.size(), before.size() + 1);
}

// The gpu preset is the cpu preset under its own name (measured on an H200: train_config.cc).
TEST(TrainConfigTest, TheGpuPresetIsTheCpuPresetUnderItsOwnName) {
  const TrainConfig gpu = TrainConfig::Preset("gpu");
  TrainConfig cpu = TrainConfig::Preset("cpu");
  EXPECT_EQ(gpu.preset, "gpu");
  cpu.preset = "gpu";
  EXPECT_EQ(ToJson(gpu), ToJson(cpu));
  try {
    TrainConfig::Preset("tpu");
    FAIL() << "accepted preset tpu";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cpu, gpu or paper"), std::string::npos) << e.what();
  }
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
  EXPECT_THROW(ApplyJson(nlohmann::json{{"background", "grey"}}, config), Error);
  EXPECT_THROW(ApplyJson(nlohmann::json{{"rays_per_batch", 0}}, config), Error);
  for (const auto& bad : {nlohmann::json(-1), nlohmann::json(51), nlohmann::json("wide")}) {
    TrainConfig fresh;
    EXPECT_THROW(ApplyJson(nlohmann::json{{"depth_fill_sigma", bad}}, fresh), Error) << bad.dump();
  }
  // The field's checks of its times, through a configuration, name the key and the configuration
  // (train_config_fuzz's contract; found by its replay).
  for (const auto& [key, bad] : {std::pair{"trained_times", nlohmann::json{0.8, 0.2}},
                                 std::pair{"exposure_times", nlohmann::json{0.5, 0.25}}}) {
    TrainConfig fresh;
    try {
      ApplyJson(nlohmann::json{{"field", {{key, bad}}}}, fresh);
      ADD_FAILURE() << key << " " << bad.dump() << " was accepted";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind("config: ", 0), 0u) << message;
      EXPECT_NE(message.find(key), std::string::npos) << message;
    }
  }
  EXPECT_THROW(TrainConfig::Preset("gpu-ultra"), Error);
  // Each names its key.
  for (const auto& bad :
       {nlohmann::json{{"depth_refine_pixels", -1}},
        nlohmann::json{{"field", {{"heads", {{"dropout", 1.0}}}}}},
        nlohmann::json{{"field", {{"heads", {{"color_dropout", 1.5}}}}}},
        nlohmann::json{{"field", {{"heads", {{"color_time_frequencies", 9}}}}}},
        nlohmann::json{{"exposure", "sometimes"}}, nlohmann::json{{"exposure_threshold", -0.1}},
        nlohmann::json{{"still_threshold_px", -1}}, nlohmann::json{{"fit_depth_bounds", "yes"}},
        nlohmann::json{{"deformation_start", "optical"}}, nlohmann::json{{"outside_view", "on"}},
        nlohmann::json{{"outside_view_level", 255}},
        nlohmann::json{{"field", {{"learned_background", true}}}},
        // Values that sized memory or made training meaningless, taken until 2026-12-05: a batch of
        // 1e9 rays held 7 GB before its first step; a negative rate or weight trained to 8 dB.
        nlohmann::json{{"rays_per_batch", 1000000000}}, nlohmann::json{{"depth_samples", 100000}},
        // ... and a count of evaluation samples ("eval samples must be at most 1024" until 2026-12-07).
        nlohmann::json{{"eval_fine_samples", 2000}}, nlohmann::json{{"eval_coarse_samples", 0}},
        nlohmann::json{{"stratified_samples", 0}}, nlohmann::json{{"mc_passes", 1000}},
        nlohmann::json{{"adam", {{"lr", {{"grid", -1}}}}}}, nlohmann::json{{"adam", {{"default_lr", -0.1}}}},
        nlohmann::json{{"adam", {{"beta2", 1.0}}}}, nlohmann::json{{"depth_weight", -100}},
        nlohmann::json{{"huber_delta", 0}},
        // A rate that threw the grid about (1e30 trained to garbage with a finite loss), a group the
        // field has not (a typo left the grid at the default rate), until 2026-12-05.
        nlohmann::json{{"adam", {{"lr", {{"grid", 1e30}}}}}}, nlohmann::json{{"adam", {{"default_lr", 2}}}},
        nlohmann::json{{"adam", {{"lr", {{"gird", 0.01}}}}}}}) {
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

// The field's keys are checked with the rest of the configuration, before a clip is loaded (until
// 2026-12-05 a bad table size failed after the clip had loaded, as "hash grid log2 table size must be
// in [4, 26]", naming neither the key nor the configuration), each naming its whole key.
TEST(TrainConfigTest, TheFieldsKeysAreCheckedNamingTheirWholeKey) {
  const std::vector<std::pair<std::string, nlohmann::json>> cases = {
      {"field.grids.log2_table", {{"field", {{"grids", {{"log2_table", 30}}}}}}},
      {"field.grids.features", {{"field", {{"grids", {{"features", 3}}}}}}},
      {"field.grids.levels", {{"field", {{"grids", {{"levels", 0}}}}}}},
      {"field.grids.scales[1]", {{"field", {{"grids", {{"scales", {1.5, 0.5, 1.4}}}}}}}},
      {"field.grids.base_resolutions and field.grids.scales",
       {{"field", {{"grids", {{"base_resolutions", {8, 16}}}}}}}},
      {"field.blend_hidden", {{"field", {{"blend_hidden", 0}}}}},
      {"field.deformation.resolution", {{"field", {{"deformation", {{"time_knots", 0}}}}}}},
      {"field.deformation:", {{"field", {{"deformation", {{"resolution", 1000}}}}}}},
      {"field.heads.density_hidden", {{"field", {{"heads", {{"density_hidden", std::vector<int>(9, 8)}}}}}}},
      {"field.heads.color_hidden[1]", {{"field", {{"heads", {{"color_hidden", {32, 0}}}}}}}},
      {"field.heads.geo_features", {{"field", {{"heads", {{"geo_features", -1}}}}}}},
      {"field.encoding", {{"field", {{"encoding", "fourier"}}}}},
      {"field.frequencies", {{"field", {{"encoding", "frequency"}, {"frequencies", 40}}}}},
  };
  for (const auto& [key, bad] : cases) {
    TrainConfig config;
    try {
      ApplyJson(bad, config);
      ADD_FAILURE() << bad.dump() << " was accepted";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << message;
      EXPECT_EQ(message.rfind("config: " + key, 0), 0u) << message;
    }
  }
  // A frequency encoding has no grids to check; a static scene's deformation is not built.
  TrainConfig config;
  ApplyJson(nlohmann::json{{"field", {{"encoding", "frequency"}, {"grids", {{"log2_table", 30}}}}}}, config);
  ApplyJson(nlohmann::json{{"field", {{"deformation", {{"enabled", false}, {"resolution", 0}}}}}}, config);
}

// A configuration each of whose values is in bounds but whose whole is not: a tenant's tables of
// 2^26 slots at 64 levels wrote 5.6 GB of results from a 64 x 48 clip, and heads of 8 x 1,024 units
// with 65,536 rays did not end one step in three minutes, past the budget, a cancel and SIGTERM
// (found 2026-12-06). The presets keep well inside every bound.
TEST(TrainConfigTest, AConfigurationsSizeAndWorkAreBoundedAsAWhole) {
  const std::vector<int> wide(8, 1024);
  const std::vector<std::pair<std::string, nlohmann::json>> cases = {
      {"config: field.grids: 3 grid(s) x 64 levels x 2^26 slots x 8 features",
       {{"field", {{"grids", {{"log2_table", 26}, {"features", 8}, {"levels", 64}}}}}}},
      {"config: a training step of rays_per_batch 65536",
       {{"rays_per_batch", 65536},
        {"field", {{"heads", {{"density_hidden", wide}, {"color_hidden", wide}}}}}}},
      {"config: an evaluated pixel of 1024 + 1024 samples",
       {{"eval_coarse_samples", 1024}, {"eval_fine_samples", 1024}, {"mc_passes", 64}}},
  };
  for (const auto& [start, bad] : cases) {
    try {
      CheckConfigJson(bad, "paper");
      ADD_FAILURE() << bad.dump() << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_EQ(std::string(e.what()).rfind(start, 0), 0u) << e.what();
    }
  }
  // With the cpu preset's 32-unit heads too: 2,048 samples in 65 passes took 55 s to evaluate a
  // 64 x 48 clip of 8 frames (found 2026-12-06).
  EXPECT_THROW(CheckConfigJson(cases[2].second, "cpu"), Error);
  for (const char* preset : {"cpu", "gpu", "paper"}) {
    const TrainConfig c = TrainConfig::Preset(preset);
    const double per_sample = field::SampleMultiplyAdds(c.field);
    EXPECT_LT(field::GridParamsBound(c.field.grids), field::kMostGridParams) << preset;
    EXPECT_LT(c.rays_per_batch * double(c.depth_samples + c.stratified_samples) * per_sample,
              kMostStepMultiplyAdds / 10)
        << preset;
    EXPECT_LT(double(c.eval_coarse_samples + c.eval_fine_samples) * (c.mc_passes + 1) * per_sample,
              kMostPixelMultiplyAdds / 10)
        << preset;
  }
  // The paper's heads: 128 inputs x 64 -> 17 and 31 x 64 -> 64 -> 4 multiply-adds a sample.
  EXPECT_DOUBLE_EQ(field::SampleMultiplyAdds(TrainConfig::Preset("paper").field),
                   128 * 64 + 64 * 17 + 31 * 64 + 64 * 64 + 64 * 4);
}

// The exposure's knot times (config.json of a run that models exposure): descending, repeated or
// not finite, refused naming the key and the knot.
TEST(TrainConfigTest, ExposureKnotTimesMustAscend) {
  for (const auto& times : {nlohmann::json{0.5, 0.2}, nlohmann::json{0.1, 0.1}, nlohmann::json{0.1, 1e39}}) {
    TrainConfig config;
    try {
      ApplyJson(nlohmann::json{{"field", {{"exposure_times", times}}}}, config);
      ADD_FAILURE() << times.dump() << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_NE(std::string(e.what()).find("exposure_times"), std::string::npos) << e.what();
    }
  }
  TrainConfig config;
  ApplyJson(nlohmann::json{{"field", {{"exposure_times", {0.0, 0.25, 1.0}}}}}, config);
  EXPECT_EQ(config.field.exposure_times, (std::vector<float>{0.0f, 0.25f, 1.0f}));
}

// Found by tests/fuzz/train_config_fuzz.cc: a number that does not fit its key's type was cast
// (undefined behaviour); it is refused, naming the key.
TEST(TrainConfigTest, NumbersThatDoNotFitTheirTypeAreRefused) {
  for (const auto& bad : {nlohmann::json{{"iterations", 4.8e39}}, nlohmann::json{{"iterations", 2.5}},
                          nlohmann::json{{"curve_frames", -4294967296.0}},
                          nlohmann::json{{"field", {{"heads", {{"density_hidden", {64, 1e20}}}}}}},
                          nlohmann::json{{"adam", {{"lr", {{"grid", 1e300}}}}}}}) {
    TrainConfig config;
    const std::string key = bad.flatten().begin().key();  // e.g. "/adam/lr/grid"
    const std::string top = key.substr(1, key.find('/', 1) - 1);
    try {
      ApplyJson(bad, config);
      ADD_FAILURE() << bad.dump() << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_NE(std::string(e.what()).find(top), std::string::npos) << e.what();
    }
  }
  TrainConfig whole;
  ApplyJson(nlohmann::json{{"iterations", 300.0}}, whole);  // a whole number written as a float is fine
  EXPECT_EQ(whole.iterations, 300);
}

}  // namespace
}  // namespace endorecon::train
