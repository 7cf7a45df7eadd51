// Where the deformation starts: fitted to the optical flow back to time 0, it already carries each
// frame's surface points to where the reference frame saw them; without depth it lifts the pixels to
// the clip's typical depth; without a frame at time 0 it leaves the parameters alone and says why.
#include "worker/engine/train/flow_start.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "worker/engine/field/deformation.h"
#include "worker/engine/scene/scene_box.h"

namespace endorecon::train {
namespace {

constexpr int kW = 96, kH = 72, kFrames = 10;
constexpr double kDepth = 10, kFocal = 80;

// A texture without repeats at this size, continuous so a shifted frame is exact.
double Texture(double x, double y) {
  return 128 + 45 * std::sin(0.45 * x + 0.8 * std::sin(0.21 * y)) + 35 * std::cos(0.37 * y + 0.17 * x) +
         20 * std::sin(0.11 * x * y / 9 + 0.05 * y);
}

// How far frame f's texture has moved, pixels (right and down).
double ShiftX(int f) { return 0.45 * f; }
double ShiftY(int f) { return -0.3 * f; }

// A fixed camera over a plane at depth kDepth whose texture slides: frame f shows at pixel p what
// frame 0 showed at p - shift(f).
// Without depth, near and far put the clip's typical depth (their middle) at `typical_depth`.
scene::Clip SlidingPlane(bool with_depth, double typical_depth = kDepth, int width = kW, int height = kH) {
  scene::Clip clip;
  clip.source = "sliding plane";
  clip.width = width;
  clip.height = height;
  clip.near = typical_depth - 5;
  clip.far = typical_depth + 5;
  for (int f = 0; f < kFrames; ++f) {
    scene::Camera camera;
    camera.fx = camera.fy = kFocal;
    camera.cx = width / 2.0;
    camera.cy = height / 2.0;
    camera.width = width;
    camera.height = height;
    clip.cameras.push_back(camera);
    clip.times.push_back(float(f) / (kFrames - 1));
    std::vector<std::uint8_t> rgb(std::size_t(width) * height * 3);
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const double v = Texture(x - ShiftX(f), y - ShiftY(f));
        for (int c = 0; c < 3; ++c) rgb[(std::size_t(y) * width + x) * 3 + c] = std::uint8_t(std::lround(v));
      }
    }
    clip.rgb.push_back(rgb);
    if (with_depth) clip.depth.emplace_back(std::size_t(width) * height, float(kDepth));
  }
  return clip;
}

std::vector<int> AllFrames() {
  std::vector<int> frames;
  for (int f = 0; f < kFrames; ++f) frames.push_back(f);
  return frames;
}

field::DeformationConfig Grid() {
  field::DeformationConfig config;
  config.resolution = 8;
  config.time_knots = 3;
  return config;
}

// Inner pixels of every frame but the first: the mean distance (box units) of the fitted grid's
// canonical point from the true one, and of the pixel's point itself (no motion: the zero start).
struct StartError {
  double error = 0, motion = 0;
};

StartError MeasureStart(const scene::Clip& clip, const scene::SceneBox& box,
                        const field::Deformation<float>& deformation, const std::vector<float>& params) {
  StartError e;
  int count = 0;
  for (int f = 1; f < kFrames; ++f) {
    for (int y = 12; y < kH - 12; y += 4) {
      for (int x = 12; x < kW - 12; x += 4) {
        Eigen::Vector3d origin, direction, origin0, direction0;
        clip.cameras[f].Ray(x, y, origin, direction);
        clip.cameras[0].Ray(x - ShiftX(f), y - ShiftY(f), origin0, direction0);
        const Eigen::Vector3d pos = box.Normalise(origin + kDepth * direction);
        const Eigen::Vector3d truth = box.Normalise(origin0 + kDepth * direction0);
        const float p[3] = {float(pos.x()), float(pos.y()), float(pos.z())};
        float x0[3];
        field::DeformSample(deformation.layout(), params.data(), p, clip.times[f], x0);
        e.error += (Eigen::Vector3d(x0[0], x0[1], x0[2]) - truth).norm();
        e.motion += (pos - truth).norm();
        ++count;
      }
    }
  }
  e.error /= count;
  e.motion /= count;
  return e;
}

// The start fitted to every frame of `clip` on a zero grid, and how close it came.
struct Fitted {
  FlowStart start;
  StartError e;
};

Fitted FitAndMeasure(const scene::Clip& clip) {
  const scene::SceneBox box = scene::ClipBox(clip);
  const field::Deformation<float> deformation(Grid());
  std::vector<float> params(deformation.param_count(), 0.0f);
  Fitted fitted;
  fitted.start = FitDeformationToFlow(clip, AllFrames(), box, deformation.layout(), params.data());
  fitted.e = MeasureStart(clip, box, deformation, params);
  return fitted;
}

TEST(FlowStartTest, CarriesEachFramesSurfaceBackToWhereTimeZeroSawIt) {
  const auto [start, e] = FitAndMeasure(SlidingPlane(true));
  ASSERT_TRUE(start.skipped.empty()) << start.skipped;
  EXPECT_EQ(start.frames, kFrames - 1);
  EXPECT_GT(start.points, std::size_t(kFrames - 1) * 500);
  EXPECT_EQ(start.assumed_depth, 0);
  EXPECT_EQ(FlowStartJson(start).at("depth"), "priors");
  std::printf("flow start: mean error %.5f box units against mean motion %.5f\n", e.error, e.motion);
  EXPECT_LT(e.error, 0.05 * e.motion);
}

// A mono recording: the pixels lifted to the clip's typical depth. Where the surface lies there, the
// start is as close as with depth; where it lies a quarter nearer, its sideways motion starts a third
// too large (the two depths' ratio) and the grid, fitted at the typical depth, reaches the surface
// only through its smoothness: 0.47 of the motion off, still half the zero start's error.
TEST(FlowStartTest, WithoutDepthItLiftsThePixelsToTheTypicalDepth) {
  for (const double typical : {kDepth, kDepth * 4 / 3}) {
    const auto [start, e] = FitAndMeasure(SlidingPlane(false, typical));
    ASSERT_TRUE(start.skipped.empty()) << start.skipped;
    EXPECT_EQ(start.frames, kFrames - 1);
    EXPECT_DOUBLE_EQ(start.assumed_depth, typical);
    const nlohmann::json json = FlowStartJson(start);
    EXPECT_EQ(json.at("depth"), "assumed");
    EXPECT_DOUBLE_EQ(json.at("assumed_depth").get<double>(), typical);
    std::printf("typical depth %.2f (surface at %.2f): mean error %.5f box units against mean motion %.5f\n",
                typical, kDepth, e.error, e.motion);
    EXPECT_LT(e.error, (typical == kDepth ? 0.05 : 0.6) * e.motion);
  }
}

// A clip wider than the flow's images (here three times): a block of pixels the flow sees as one is
// left out when any pixel of it is tool, since the edge of a tool moves with the tool. A tool that
// covers one pixel of every 3 x 3 block leaves nothing to follow; a tool that covers none leaves
// the whole plane.
TEST(FlowStartTest, AFlowPixelWithAnyToolInItIsNotFollowed) {
  constexpr int kWide = 3 * 320;
  for (const bool sparse_tool : {false, true}) {
    scene::Clip clip = SlidingPlane(true, kDepth, kWide);
    for (int f = 0; f < kFrames; ++f) {
      std::vector<std::uint8_t> tool(std::size_t(kWide) * kH, 0);
      for (int y = 1; sparse_tool && y < kH; y += 3) {
        for (int x = 1; x < kWide; x += 3) tool[std::size_t(y) * kWide + x] = 1;
      }
      clip.tool_mask.push_back(tool);
    }
    const field::Deformation<float> deformation(Grid());
    std::vector<float> params(deformation.param_count(), 0.0f);
    const FlowStart start =
        FitDeformationToFlow(clip, AllFrames(), scene::ClipBox(clip), deformation.layout(), params.data());
    if (sparse_tool) {
      EXPECT_EQ(start.points, 0u);
      EXPECT_NE(start.skipped.find("no surface point"), std::string::npos) << start.skipped;
    } else {
      EXPECT_TRUE(start.skipped.empty()) << start.skipped;
      EXPECT_GT(start.points, std::size_t(kFrames - 1) * 500);
    }
  }
}

TEST(FlowStartTest, WithoutATrainingFrameAtTimeZeroItLeavesTheParametersAlone) {
  const scene::Clip clip = SlidingPlane(true);
  const field::Deformation<float> deformation(Grid());
  std::vector<float> params(deformation.param_count(), 0.25f);
  const FlowStart start =
      FitDeformationToFlow(clip, {2, 3, 4, 5}, scene::ClipBox(clip), deformation.layout(), params.data());
  EXPECT_NE(start.skipped.find("time 0"), std::string::npos) << start.skipped;
  for (float v : params) ASSERT_EQ(v, 0.25f);
}

// Frames under 12 pixels a side (a clip `synth` makes at 8 x 8) start from zero: OpenCV's DIS flow
// asserted on them and ended the run (found 2026-12-05).
TEST(FlowStartTest, FramesTooSmallForTheFlowStartFromZero) {
  const scene::Clip clip = SlidingPlane(true, kDepth, 8, 8);
  const field::Deformation<float> deformation(Grid());
  std::vector<float> params(deformation.param_count(), 0.25f);
  const FlowStart start =
      FitDeformationToFlow(clip, AllFrames(), scene::ClipBox(clip), deformation.layout(), params.data());
  EXPECT_NE(start.skipped.find("frames of 8x8 are too small for optical flow"), std::string::npos)
      << start.skipped;
  for (float v : params) ASSERT_EQ(v, 0.25f);
}

}  // namespace
}  // namespace endorecon::train
