// Where the deformation starts: fitted to the optical flow back to time 0, it already carries each
// frame's surface points to where the reference frame saw them; without depth or without a frame at
// time 0 it leaves the parameters alone and says why.
#include "worker/engine/train/flow_start.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
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
scene::Clip SlidingPlane(bool with_depth) {
  scene::Clip clip;
  clip.source = "sliding plane";
  clip.width = kW;
  clip.height = kH;
  clip.near = 5;
  clip.far = 15;
  for (int f = 0; f < kFrames; ++f) {
    scene::Camera camera;
    camera.fx = camera.fy = kFocal;
    camera.cx = kW / 2.0;
    camera.cy = kH / 2.0;
    camera.width = kW;
    camera.height = kH;
    clip.cameras.push_back(camera);
    clip.times.push_back(float(f) / (kFrames - 1));
    std::vector<std::uint8_t> rgb(std::size_t(kW) * kH * 3);
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        const double v = Texture(x - ShiftX(f), y - ShiftY(f));
        for (int c = 0; c < 3; ++c) rgb[(std::size_t(y) * kW + x) * 3 + c] = std::uint8_t(std::lround(v));
      }
    }
    clip.rgb.push_back(rgb);
    if (with_depth) clip.depth.emplace_back(std::size_t(kW) * kH, float(kDepth));
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

TEST(FlowStartTest, CarriesEachFramesSurfaceBackToWhereTimeZeroSawIt) {
  const scene::Clip clip = SlidingPlane(true);
  const scene::SceneBox box = scene::ClipBox(clip);
  const field::Deformation<float> deformation(Grid());
  std::vector<float> params(deformation.param_count(), 0.0f);
  const FlowStart start = FitDeformationToFlow(clip, AllFrames(), box, deformation.layout(), params.data());
  ASSERT_TRUE(start.skipped.empty()) << start.skipped;
  EXPECT_EQ(start.frames, kFrames - 1);
  EXPECT_GT(start.points, std::size_t(kFrames - 1) * 500);

  // Inner pixels of every frame: the fitted grid against the true canonical point, and against no
  // motion (the start without the fit).
  double error = 0, motion = 0;
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
        error += (Eigen::Vector3d(x0[0], x0[1], x0[2]) - truth).norm();
        motion += (pos - truth).norm();
        ++count;
      }
    }
  }
  error /= count;
  motion /= count;
  std::printf("flow start: mean error %.5f box units against mean motion %.5f (%d points)\n", error, motion,
              count);
  EXPECT_LT(error, 0.05 * motion);
}

TEST(FlowStartTest, WithoutDepthItLeavesTheParametersAlone) {
  const scene::Clip clip = SlidingPlane(false);
  const field::Deformation<float> deformation(Grid());
  std::vector<float> params(deformation.param_count(), 0.25f);
  const FlowStart start =
      FitDeformationToFlow(clip, AllFrames(), scene::ClipBox(clip), deformation.layout(), params.data());
  EXPECT_EQ(start.skipped, "the clip has no depth");
  for (float v : params) ASSERT_EQ(v, 0.25f);
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

}  // namespace
}  // namespace endorecon::train
