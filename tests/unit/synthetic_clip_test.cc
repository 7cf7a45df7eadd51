#include "worker/engine/scene/synthetic_clip.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_scene.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

SynthOptions Small() {
  SynthOptions options;
  options.frames = 12;
  options.width = 64;
  options.height = 48;
  options.seed = 7;
  return options;
}

std::vector<fs::path> AllFiles(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(fs::relative(entry.path(), dir));
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(SyntheticClipTest, IsDeterministicForASeed) {
  TempDir a("synth"), b("synth"), c("synth");
  SynthOptions options = Small();
  options.stereo = true;
  WriteSyntheticClip(options, a.path());
  WriteSyntheticClip(options, b.path());
  const std::vector<fs::path> files = AllFiles(a.path());
  ASSERT_EQ(files, AllFiles(b.path()));
  EXPECT_EQ(files.size(), 2 + 1 + 6u * 12);  // poses, stereo.json, synth.json; six files per frame
  for (const fs::path& file : files) {
    EXPECT_EQ(testing::ReadBytes(a / file.string()), testing::ReadBytes(b / file.string())) << file;
  }
  options.seed = 8;
  WriteSyntheticClip(options, c.path());
  EXPECT_NE(testing::ReadBytes(a / "images/000003.png"), testing::ReadBytes(c / "images/000003.png"));
}

TEST(SyntheticClipTest, LoadsAsAValidEndoNerfClip) {
  TempDir dir("synth");
  WriteSyntheticClip(Small(), dir.path());
  const Clip clip = LoadClip(dir.path());
  ASSERT_EQ(clip.frame_count(), 12);
  EXPECT_EQ(clip.width, 64);
  EXPECT_EQ(clip.height, 48);
  EXPECT_EQ(clip.near, 40);
  EXPECT_EQ(clip.far, 130);
  EXPECT_FALSE(clip.is_static);
  EXPECT_FLOAT_EQ(clip.times[3], 3.f / 11);
  for (const Camera& camera : clip.cameras) {
    EXPECT_TRUE(camera.c2w.isApprox(Eigen::Matrix<double, 3, 4>::Identity())) << camera.c2w;
    EXPECT_NEAR(camera.fx, 64 * 569.46820041 / 640, 1e-9);
    EXPECT_EQ(camera.cx, 32);
    EXPECT_EQ(camera.cy, 24);
  }
  EXPECT_TRUE(clip.has_depth());
  EXPECT_TRUE(clip.has_masks());
  EXPECT_FALSE(clip.has_stereo());
  EXPECT_EQ(clip.gt_rgb.size(), 12u);
  EXPECT_EQ(clip.gt_depth.size(), 12u);
  // The tissue deforms: ground-truth depth changes between the first and the middle frame.
  double change = 0;
  for (std::size_t i = 0; i < clip.gt_depth[0].size(); ++i) {
    change = std::max(change, std::abs(double{clip.gt_depth[0][i]} - clip.gt_depth[6][i]));
  }
  EXPECT_GT(change, 0.5);
}

TEST(SyntheticClipTest, ToolMaskCoversTheToolAndNothingElse) {
  TempDir dir("synth");
  SynthOptions options = Small();
  options.noise = 0;  // the seen tissue is then exactly the tool-free truth
  WriteSyntheticClip(options, dir.path());
  const Clip clip = LoadClip(dir.path());
  for (int f = 0; f < clip.frame_count(); ++f) {
    std::size_t tool = 0, tool_differs = 0;
    for (std::size_t p = 0; p < clip.tool_mask[f].size(); ++p) {
      const bool differs = !std::equal(&clip.rgb[f][3 * p], &clip.rgb[f][3 * p + 3], &clip.gt_rgb[f][3 * p]);
      if (clip.tool_mask[f][p] == 0) {
        ASSERT_FALSE(differs) << "frame " << f << " pixel " << p << " differs from the tool-free image";
        continue;
      }
      ++tool;
      tool_differs += differs;
      // The tool is in front of the tissue (holes aside).
      if (clip.depth[f][p] > 0) {
        EXPECT_LT(clip.depth[f][p], clip.gt_depth[f][p] - 2) << "frame " << f;
      }
    }
    EXPECT_GT(tool, clip.tool_mask[f].size() / 50) << "frame " << f;
    EXPECT_LT(tool, clip.tool_mask[f].size() / 3) << "frame " << f;
    EXPECT_GT(tool_differs, tool * 95 / 100) << "frame " << f;
  }
}

TEST(SyntheticClipTest, DepthIsNoisyTruthWithinBounds) {
  TempDir dir("synth");
  WriteSyntheticClip(Small(), dir.path());
  const Clip clip = LoadClip(dir.path());
  std::size_t holes = 0, compared = 0, exact = 0;
  double sum = 0;
  for (int f = 0; f < clip.frame_count(); ++f) {
    for (std::size_t p = 0; p < clip.depth[f].size(); ++p) {
      const double truth = clip.gt_depth[f][p];
      ASSERT_GT(truth, clip.near);
      ASSERT_LT(truth, clip.far);
      if (clip.depth[f][p] == 0) {
        ++holes;
        continue;
      }
      if (clip.tool_mask[f][p]) continue;
      // Noise is clamped at 3 sigma, sigma = 0.25 + 0.5 (z / 90)^2; then rounded.
      const double sigma = 0.25 + 0.5 * (truth / 90) * (truth / 90);
      const double error = clip.depth[f][p] - truth;
      ASSERT_LE(std::abs(error), 3 * sigma + 0.5) << "frame " << f << " pixel " << p;
      sum += error;
      exact += std::abs(error) <= 0.5;
      ++compared;
    }
  }
  const std::size_t pixels = clip.depth.size() * clip.depth[0].size();
  EXPECT_GT(holes, 0u);
  EXPECT_LT(holes, pixels / 5);
  EXPECT_NEAR(sum / compared, 0, 0.1);  // zero-mean noise
  EXPECT_LT(exact, compared * 9 / 10);  // ... that is really there
}

TEST(SyntheticClipTest, RaysMeetTheTissueExactly) {
  const SynthOptions options = Small();
  const SyntheticScene scene(options);
  const Camera camera = scene.LeftCamera();
  for (double t : {0.0, 0.37, 1.0}) {
    const SyntheticScene::State state = scene.At(t);
    for (int v = 0; v < options.height; v += 5) {
      for (int u = 0; u < options.width; u += 5) {
        Eigen::Vector3d origin, direction;
        camera.Ray(u, v, origin, direction);
        const SceneHit hit = scene.Trace(state, origin, direction);
        double dx, dy;
        const double s = hit.tissue_depth;
        EXPECT_NEAR(scene.TissueDepth(state, s * direction.x(), s * direction.y(), &dx, &dy), s, 1e-9);
        // One crossing only: the residual s - D grows along the ray (the slope bound).
        EXPECT_LT(dx * direction.x() + dy * direction.y(), 1);
      }
    }
  }
}

TEST(SyntheticClipTest, NoToolAndNoDepthLeaveTheirFoldersOut) {
  TempDir dir("synth");
  SynthOptions options = Small();
  options.tool = false;
  options.depth = false;
  options.noise = 0;
  WriteSyntheticClip(options, dir.path());
  EXPECT_FALSE(fs::exists(dir / "masks"));
  EXPECT_FALSE(fs::exists(dir / "depth"));
  const Clip clip = LoadClip(dir.path());
  EXPECT_FALSE(clip.has_masks());
  EXPECT_FALSE(clip.has_depth());
  EXPECT_EQ(clip.rgb, clip.gt_rgb);
  EXPECT_EQ(clip.gt_depth.size(), 12u);
}

TEST(SyntheticClipTest, StaticSceneDoesNotMove) {
  TempDir dir("synth");
  SynthOptions options = Small();
  options.static_scene = true;
  WriteSyntheticClip(options, dir.path());
  const Clip clip = LoadClip(dir.path());
  EXPECT_FLOAT_EQ(clip.times.back(), 1.f);
  for (int f = 1; f < clip.frame_count(); ++f) {
    EXPECT_EQ(clip.gt_rgb[f], clip.gt_rgb[0]) << f;  // the seen images differ by their noise only
    EXPECT_NE(clip.rgb[f], clip.rgb[0]) << f;
    EXPECT_EQ(clip.gt_depth[f], clip.gt_depth[0]) << f;
    EXPECT_EQ(clip.tool_mask[f], clip.tool_mask[0]) << f;
  }
}

// The camera noise's standard deviation in 255ths, at stored truth levels 60-95 (dark) and 160-200
// (bright), over all frames and channels; and the share of values it changed.
struct NoiseLevels {
  double dark = 0, bright = 0, changed = 0;
};

NoiseLevels MeasureNoise(const Clip& clip) {
  double dark_sum2 = 0, bright_sum2 = 0, differ = 0, values = 0;
  long dark = 0, bright = 0;
  for (int f = 0; f < clip.frame_count(); ++f) {
    for (std::size_t i = 0; i < clip.rgb[f].size(); ++i) {
      const double truth = clip.gt_rgb[f][i], seen = clip.rgb[f][i], d = seen - truth;
      differ += d != 0;
      ++values;
      if (truth > 60 && truth < 95) dark_sum2 += d * d, ++dark;
      if (truth > 160 && truth < 200) bright_sum2 += d * d, ++bright;
    }
  }
  EXPECT_GT(dark, 1000);
  EXPECT_GT(bright, 1000);
  return {std::sqrt(dark_sum2 / double(std::max(dark, 1L))),
          std::sqrt(bright_sum2 / double(std::max(bright, 1L))), differ / values};
}

TEST(SyntheticClipTest, CameraNoiseIsSignalDependentStrongerInTheDarkAndLeavesTheTruthClean) {
  TempDir dir("synth");
  SynthOptions options = Small();
  options.tool = false;  // every pixel tissue: images/ = gt/images + noise
  WriteSyntheticClip(options, dir.path());
  const Clip clip = LoadClip(dir.path());
  // A standard deviation that falls from dark to bright as the model says (about 3.3 levels at 0.3,
  // 2.5 at 0.7, 255ths).
  const NoiseLevels noise = MeasureNoise(clip);
  EXPECT_NEAR(noise.dark, 3.3, 0.8);
  EXPECT_NEAR(noise.bright, 2.5, 0.6);
  EXPECT_GT(noise.dark, noise.bright);
  EXPECT_GT(noise.changed, 0.5) << "most values carry noise";
  // The same seed gives the same noise; a scale of 0.5 about half of it; --no-noise gives the truth.
  TempDir again("synth-again");
  WriteSyntheticClip(options, again.path());
  EXPECT_EQ(LoadClip(again.path()).rgb, clip.rgb);
  options.noise = 0.5;
  TempDir half("synth-half");
  WriteSyntheticClip(options, half.path());
  const Clip half_clip = LoadClip(half.path());
  const NoiseLevels halved = MeasureNoise(half_clip);
  EXPECT_NEAR(halved.dark / noise.dark, 0.5, 0.1);  // rounding to levels adds a little
  EXPECT_NEAR(halved.bright / noise.bright, 0.5, 0.1);
  EXPECT_EQ(half_clip.gt_rgb, clip.gt_rgb);
  options.noise = 0;
  TempDir clean("synth-clean");
  WriteSyntheticClip(options, clean.path());
  const Clip clean_clip = LoadClip(clean.path());
  EXPECT_EQ(clean_clip.rgb, clean_clip.gt_rgb);
  EXPECT_EQ(clean_clip.gt_rgb, clip.gt_rgb);
}

TEST(SyntheticClipTest, StiffSceneIsThinDarkAndSaturated) {
  TempDir dir("synth");
  SynthOptions options = Small();
  options.stiff = true;
  WriteSyntheticClip(options, dir.path());
  const Clip clip = LoadClip(dir.path());
  EXPECT_LT(clip.far - clip.near, 8);
  std::size_t dark = 0, saturated = 0, pixels = 0;
  for (int f = 0; f < clip.frame_count(); ++f) {
    for (float z : clip.gt_depth[f]) {
      ASSERT_GT(z, clip.near);
      ASSERT_LT(z, clip.far);
    }
    for (std::size_t p = 0; p < clip.gt_rgb[f].size(); p += 3, ++pixels) {
      const std::uint8_t* rgb = &clip.gt_rgb[f][p];
      dark += std::max({rgb[0], rgb[1], rgb[2]}) < 40;
      saturated += std::min({rgb[0], rgb[1], rgb[2]}) == 255;
    }
  }
  EXPECT_GT(dark, pixels / 3);
  EXPECT_GT(saturated, pixels / 100);
}

TEST(SyntheticClipTest, StereoRightEyeIsShiftedByTheBaseline) {
  TempDir dir("synth");
  SynthOptions options = Small();
  options.stereo = true;
  WriteSyntheticClip(options, dir.path());
  const Clip clip = LoadClip(dir.path());
  ASSERT_TRUE(clip.has_stereo());
  EXPECT_TRUE(clip.right_cameras[0].c2w.col(3).isApprox(Eigen::Vector3d(5, 0, 0)));
  EXPECT_NE(clip.right_rgb[0], clip.rgb[0]);
  // A far-away point seen by the right eye appears shifted left: the views overlap but differ.
  std::size_t equal = 0;
  for (std::size_t i = 0; i < clip.rgb[0].size(); ++i) equal += clip.right_rgb[0][i] == clip.rgb[0][i];
  EXPECT_LT(equal, clip.rgb[0].size() / 2);
}

TEST(SyntheticClipTest, MovingEndoscopeFollowsItsPath) {
  TempDir dir("synth");
  SynthOptions options = Small();
  options.moving = true;
  WriteSyntheticClip(options, dir.path());
  const Clip clip = LoadClip(dir.path());
  const SyntheticScene scene(options);
  for (int f : {0, 5, 11}) {
    EXPECT_TRUE(clip.cameras[f].c2w.isApprox(scene.LeftPose(FrameTime(options, f)), 1e-12)) << f;
  }
  EXPECT_GT((clip.cameras[11].c2w.col(3) - clip.cameras[0].c2w.col(3)).norm(), 10);
  // Rays from the moved camera meet the tissue: the hit lies on the surface z = -D(x, y).
  const SyntheticScene::State state = scene.At(FrameTime(options, 11));
  for (int v = 0; v < options.height; v += 7) {
    for (int u = 0; u < options.width; u += 7) {
      Eigen::Vector3d origin, direction;
      clip.cameras[11].Ray(u, v, origin, direction);
      const SceneHit hit = scene.TraceAlong(state, origin, direction);
      const Eigen::Vector3d point = origin + hit.tissue_depth * direction;
      double dx, dy;
      EXPECT_NEAR(-point.z(), scene.TissueDepth(state, point.x(), point.y(), &dx, &dy), 1e-6);
    }
  }
}

// The raw left eye is the ideal left camera seen through the calibration's lens model: a pixel of
// the ideal frame, projected with K1 and D1, finds the same colour in the raw frame.
TEST(SyntheticClipTest, RecordingMatchesItsCalibration) {
  TempDir dir("synth");
  SynthOptions options = Small();
  options.width = 160;
  options.height = 128;
  options.frames = 2;
  options.recording = true;
  options.checkerboard_views = 2;
  WriteSyntheticClip(options, dir.path());
  for (const char* file :
       {"recording/calibration.yaml", "recording/poses.json", "recording/left/000001.png",
        "recording/right/000001.png", "recording/masks/000001.png", "recording/checkerboard/left/000001.png",
        "recording/checkerboard/right/000001.png"}) {
    EXPECT_TRUE(fs::exists(dir / file)) << file;
  }
  const cv::Mat ideal = cv::imread((dir / "gt/images/000000.png").string());
  const cv::Mat raw = cv::imread((dir / "recording/left/000000.png").string());
  cv::FileStorage calibration((dir / "recording/calibration.yaml").string(), cv::FileStorage::READ);
  cv::Mat k, d;
  calibration["K1"] >> k;
  calibration["D1"] >> d;
  EXPECT_EQ(static_cast<int>(calibration["image_width"]), 160);
  const double f = SyntheticScene(options).LeftCamera().fx;
  std::vector<cv::Point3d> rays;
  std::vector<cv::Point2i> pixels;
  for (int v = 20; v < 108; v += 4) {
    for (int u = 20; u < 140; u += 4) {
      rays.emplace_back((u - 79.5) / f, (v - 63.5) / f, 1);  // OpenCV pixel centres
      pixels.emplace_back(u, v);
    }
  }
  std::vector<cv::Point2d> projected;
  cv::projectPoints(rays, cv::Vec3d(), cv::Vec3d(), k, d, projected);
  double difference = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    cv::Mat sample;
    cv::getRectSubPix(raw, cv::Size(1, 1), cv::Point2f(projected[i]), sample);
    difference += cv::norm(cv::Vec3d(sample.at<cv::Vec3b>(0, 0)) - cv::Vec3d(ideal.at<cv::Vec3b>(pixels[i])),
                           cv::NORM_L1) /
                  3;
  }
  EXPECT_LT(difference / rays.size(), 8) << "mean difference per channel";
  const nlohmann::json poses = nlohmann::json::parse(testing::ReadBytes(dir / "recording/poses.json"));
  EXPECT_EQ(poses["poses"].size(), 2u);
  EXPECT_EQ(poses["convention"], "opencv");
}

TEST(SyntheticClipTest, ReplacesAnEarlierSyntheticClipOnly) {
  TempDir dir("synth");
  SynthOptions options = Small();
  WriteSyntheticClip(options, dir.path());
  options.frames = 5;
  options.tool = false;
  WriteSyntheticClip(options, dir.path());
  EXPECT_FALSE(fs::exists(dir / "masks"));
  EXPECT_EQ(LoadClip(dir.path()).frame_count(), 5);

  TempDir foreign("synth");
  testing::WriteBytes(foreign / "notes.txt", "keep me");
  const std::string message = testing::ErrorFrom([&] { WriteSyntheticClip(options, foreign.path()); });
  EXPECT_NE(message.find("exists and is not empty"), std::string::npos) << message;
  EXPECT_TRUE(fs::exists(foreign / "notes.txt"));
}

// Mean absolute difference of two 8-bit images, in levels.
double MeanDifference(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += std::abs(int(a[i]) - int(b[i]));
  return sum / double(a.size());
}

double Mean(const std::vector<std::uint8_t>& image) {
  double sum = 0;
  for (std::uint8_t v : image) sum += v;
  return sum / double(image.size());
}

TEST(SyntheticClipTest, ATextureGivesTheTissueItsColours) {
  TempDir dir("synth");
  SynthOptions options = Small();
  options.tool = false;
  options.noise = 0;
  options.texture_width = 4;
  options.texture_height = 2;
  for (int i = 0; i < 8; ++i) options.texture.insert(options.texture.end(), {40, 160, 60});  // green
  options.texture_source = "test";
  WriteSyntheticClip(options, dir.path());
  const Clip clip = LoadClip(dir.path());
  int green = 0;
  const auto& rgb = clip.gt_rgb[0];
  for (std::size_t i = 0; i < rgb.size(); i += 3) green += rgb[i + 1] > rgb[i] && rgb[i + 1] > rgb[i + 2];
  EXPECT_GT(green, clip.width * clip.height * 9 / 10) << "green tissue, but for saturated highlights";

  options.texture.pop_back();
  const std::string message = testing::ErrorFrom([&] { WriteSyntheticClip(options, dir.path()); });
  EXPECT_NE(message.find("the texture must be at least 2 x 2 RGB pixels"), std::string::npos) << message;
}

TEST(SyntheticClipTest, MotionPushAndFlickerChangeWhatTheyShould) {
  SynthOptions options = Small();
  options.noise = 0;
  TempDir calm("synth"), lively("synth"), pushed("synth"), flickering("synth");
  WriteSyntheticClip(options, calm.path());
  SynthOptions more = options;
  more.motion = 3;
  WriteSyntheticClip(more, lively.path());
  SynthOptions push = options;
  push.push = true;
  WriteSyntheticClip(push, pushed.path());
  SynthOptions flicker = options;
  flicker.flicker = 0.2;
  WriteSyntheticClip(flicker, flickering.path());
  const Clip a = LoadClip(calm.path()), b = LoadClip(lively.path()), c = LoadClip(pushed.path()),
             d = LoadClip(flickering.path());
  // Frame to frame, the lively tissue changes more.
  double calm_change = 0, lively_change = 0;
  for (int f = 1; f < a.frame_count(); ++f) {
    calm_change += MeanDifference(a.gt_rgb[f], a.gt_rgb[f - 1]);
    lively_change += MeanDifference(b.gt_rgb[f], b.gt_rgb[f - 1]);
  }
  EXPECT_GT(lively_change, 1.5 * calm_change);
  // The push only deepens the tissue, somewhere in every frame, by about its 3.5 units (a ray meets the
  // sloped surface a little aside of where it would have, so a z-depth may grow a little more).
  for (int f = 0; f < a.frame_count(); ++f) {
    float deepest = 0;
    for (std::size_t i = 0; i < a.gt_depth[f].size(); ++i) {
      const float deeper = c.gt_depth[f][i] - a.gt_depth[f][i];
      EXPECT_GT(deeper, -1e-3f);
      deepest = std::max(deepest, deeper);
    }
    EXPECT_GT(deepest, 1.0f) << f;
    EXPECT_LT(deepest, 4.5f) << f;
  }
  // Flicker scales each frame's light (truth included) by 1 +- 0.2; geometry stays.
  double spread = 0;
  for (int f = 0; f < a.frame_count(); ++f) {
    const double ratio = Mean(d.gt_rgb[f]) / Mean(a.gt_rgb[f]);
    EXPECT_GT(ratio, 0.75) << f;
    EXPECT_LT(ratio, 1.25) << f;
    spread = std::max(spread, std::abs(ratio - 1));
    EXPECT_EQ(d.gt_depth[f], a.gt_depth[f]);
  }
  EXPECT_GT(spread, 0.05);
}

TEST(SyntheticClipTest, RejectsBadOptions) {
  TempDir dir("synth");
  SynthOptions options = Small();
  options.frames = 0;
  const std::string message = testing::ErrorFrom([&] { WriteSyntheticClip(options, dir / "out"); });
  EXPECT_NE(message.find("must be positive (got 0 frames of 64x48)"), std::string::npos) << message;
}

}  // namespace
}  // namespace endorecon::scene
