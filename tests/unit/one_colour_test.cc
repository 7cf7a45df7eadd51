// The one-colour yardstick (eval/one_colour.h) in closed form, and a run that learns nothing saying so.
#include "worker/engine/eval/one_colour.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <sstream>
#include <vector>

#include "common/json_file.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/base/psnr_from_mse.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace endorecon {
namespace {

// Half the pixels at 0 and half at 1 in every channel: each channel's variance about its mean (0.5)
// is 0.25, so the yardstick is -10 log10(0.25) = 6.02 dB; one colour everywhere is capped.
TEST(OneColourTest, TheYardstickIsTheImagesVarianceAboutItsMeanColour) {
  std::vector<std::uint8_t> halves(2 * 10 * 3, 0);
  std::fill(halves.begin() + 30, halves.end(), 255);
  EXPECT_NEAR(eval::OneColourPsnr(halves), -10 * std::log10(0.25), 1e-9);
  const std::vector<std::uint8_t> flat(12 * 3, 77);
  EXPECT_EQ(eval::OneColourPsnr(flat), base::kPsnrCapDb);
  EXPECT_TRUE(std::isnan(eval::OneColourPsnr({})));
}

// A learning rate of 1 without momentum's damping trained to 3.2 dB, its depth all at the near plane,
// and the run ended as any other (found 2026-12-07): metrics.json holds the yardstick, and the log
// says the reconstruction learnt nothing, as metrics.json's warnings do.
TEST(OneColourTest, ARunThatLearnsNothingSaysSo) {
  testing::TempDir dir("one-colour");
  scene::SynthOptions synth;
  synth.frames = 4;
  synth.width = 40;
  synth.height = 32;
  scene::WriteSyntheticClip(synth, dir / "clip");
  ReconstructOptions options;
  options.clip_dir = (dir / "clip").string();
  options.out_dir = (dir / "out").string();
  options.iterations = 40;
  options.config = {
      {"rays_per_batch", 256},
      {"mc_passes", 0},
      {"eval_coarse_samples", 8},
      {"eval_fine_samples", 8},
      {"adam",
       {{"lr", {{"grid", 1}, {"blend", 1}, {"deform", 1}, {"density", 1}, {"color", 1}, {"background", 1}}},
        {"beta1", 0},
        {"beta2", 0}}}};
  std::ostringstream log;
  const auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  spdlog::default_logger()->sinks().push_back(sink);
  Reconstruct(options, {});
  spdlog::default_logger()->sinks().pop_back();
  const auto metrics = ReadJsonFile(dir / "out" / "metrics.json");
  const double yardstick = metrics.at("train").at("image").at("psnr_one_colour").get<double>();
  const double trained = metrics.at("train").at("image").at("psnr").at("mean").get<double>();
  EXPECT_LT(trained, yardstick + eval::kLeastGainOverOneColourDb);
  EXPECT_NE(log.str().find("the reconstruction learnt nothing of the scene"), std::string::npos) << log.str();
  // Not in the worker's log alone: in metrics.json, which the report page and `endorecon status` show.
  ASSERT_TRUE(metrics.contains("warnings")) << metrics.dump();
  EXPECT_NE(metrics.at("warnings").dump().find("the reconstruction learnt nothing of the scene"),
            std::string::npos);
}

}  // namespace
}  // namespace endorecon
