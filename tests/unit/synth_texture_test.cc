// The picture `synth --texture` takes: an image as it is, or the centre of a real recording's frame.
#include "worker/runtime/synth_texture.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::worker {
namespace {

namespace fs = std::filesystem;

TEST(SynthTextureTest, AnImageIsTakenAsItIs) {
  testing::TempDir dir("texture");
  cv::imwrite((dir.path() / "tissue.png").string(), cv::Mat(3, 4, CV_8UC3, cv::Scalar(10, 20, 200)));
  scene::SynthOptions options;
  LoadSynthTexture((dir.path() / "tissue.png").string(), -1, options);
  EXPECT_EQ(options.texture_width, 4);
  EXPECT_EQ(options.texture_height, 3);
  ASSERT_EQ(options.texture.size(), 36u);
  EXPECT_EQ(options.texture[0], 200);  // RGB order
  EXPECT_EQ(options.texture_source, (dir.path() / "tissue.png").string());
}

TEST(SynthTextureTest, AFrameOfTheRealRecordingIsCroppedToItsCentre) {
  const fs::path video = fs::path(ENDORECON_SHARED_DIR) / "data/real/laparoscopy_mono/endo.mp4";
  if (!fs::exists(video)) GTEST_SKIP() << "the real video is not here: " << video;
  scene::SynthOptions options;
  LoadSynthTexture(video.string(), -1, options);  // 250 frames of 1280 x 720: frame 125, 503 px (0.7 x 720, rounded down)
  EXPECT_EQ(options.texture_width, 503);
  EXPECT_EQ(options.texture_height, 503);
  EXPECT_EQ(options.texture.size(), 503u * 503 * 3);
  EXPECT_NE(options.texture_source.find("frame 125"), std::string::npos) << options.texture_source;
  // The centre of a laparoscopic view is lit tissue, not the black outside the scope's circle.
  double sum = 0;
  for (std::uint8_t v : options.texture) sum += v;
  EXPECT_GT(sum / double(options.texture.size()), 40.0);

  const std::string message = testing::ErrorFrom([&] { LoadSynthTexture(video.string(), 400, options); });
  EXPECT_NE(message.find("has no frame 400"), std::string::npos) << message;
}

}  // namespace
}  // namespace endorecon::worker
