// The model map's third term: the neighbouring training frames' residuals, relative to the camera
// noise's level at their brightness, seen where the frame's surface projects in each neighbour.
#include "worker/engine/eval/neighbour_evidence.h"

#include <gtest/gtest.h>

#include <vector>

#include "common/error.h"

namespace endorecon::eval {
namespace {

constexpr int kW = 12, kH = 8;

scene::Camera CameraAt(double x) {
  scene::Camera camera;
  camera.fx = camera.fy = 10;
  camera.cx = kW / 2.0;
  camera.cy = kH / 2.0;
  camera.width = kW;
  camera.height = kH;
  camera.c2w(0, 3) = x;
  return camera;
}

int Pixel(int u, int v) { return v * kW + u; }

TEST(ResidualEvidenceTest, TheNoiseOfABrightnessIsTakenOutAndTheToolMarked) {
  // Two brightness levels; the residual follows the noise (twice the RMSE where bright) except at
  // one dark pixel with three times its level's.
  std::vector<float> rgb, rmse;
  std::vector<std::uint8_t> tool(kW * kH, 0);
  for (int p = 0; p < kW * kH; ++p) {
    const bool bright = p % 2 == 0;
    rgb.insert(rgb.end(), 3, bright ? 0.8f : 0.2f);
    rmse.push_back((bright ? 0.02f : 0.01f) * (p == 7 ? 3.0f : 1.0f));
  }
  tool[10] = 1;
  const std::vector<float> evidence = ResidualEvidence(rgb, rmse, tool);
  EXPECT_NEAR(evidence[0], 1.0, 1e-5);  // a bright pixel at its level's median
  EXPECT_NEAR(evidence[1], 1.0, 1e-5);  // a dark one: alike, though its residual is a quarter
  EXPECT_NEAR(evidence[7], 9.0, 1e-4);  // the dark pixel with excess: 3^2 its level's
  EXPECT_EQ(evidence[10], -1.0f);       // the tool: no evidence
  EXPECT_THROW(ResidualEvidence(rgb, std::vector<float>(3), {}), Error);
}

TEST(NeighbourEvidenceTest, AStillCameraAveragesTheSamePixelWeightedByDistance) {
  const std::vector<scene::Camera> cameras(5, CameraAt(0));
  const std::vector<float> depth(kW * kH, 2.0f);
  std::vector<std::vector<float>> evidence(5);
  evidence[1].assign(kW * kH, 1.0f);  // frame 2's neighbours in training: 1 (distance 1) and 4 (distance 2)
  evidence[4].assign(kW * kH, 4.0f);
  evidence[1][Pixel(3, 2)] = -1.0f;  // frame 1's tool there: frame 4 alone speaks
  const std::vector<float> seen = NeighbourEvidence(cameras, 2, depth, evidence);
  EXPECT_NEAR(seen[Pixel(0, 0)], (1.0 * 1 + 0.5 * 4) / 1.5, 1e-6);
  EXPECT_NEAR(seen[Pixel(3, 2)], 4.0, 1e-6);
  // A frame past kNeighbourFrames is not a neighbour; a frame without evidence (held out) is none.
  evidence.assign(5, {});
  evidence[0].assign(kW * kH, 1.0f);
  const std::vector<float> none =
      NeighbourEvidence(std::vector<scene::Camera>(6, CameraAt(0)), 5, std::vector<float>(kW * kH, 2.0f),
                        {evidence[0], {}, {}, {}, {}, {}});
  EXPECT_EQ(none, std::vector<float>(kW * kH, 0.0f));
}

TEST(NeighbourEvidenceTest, AMovingCameraIsFollowedThroughTheRenderedDepth) {
  // Frame 1's camera sits one pixel's footprint to the right at depth 2 (fx = 10: 0.2): the surface
  // frame 0 sees at pixel u, frame 1 sees at u - 1.
  const std::vector<scene::Camera> cameras = {CameraAt(0), CameraAt(0.2)};
  std::vector<std::vector<float>> evidence(2);
  evidence[1].assign(kW * kH, 0.0f);
  evidence[1][Pixel(5, 3)] = 1.0f;
  std::vector<float> depth(kW * kH, 2.0f);
  const std::vector<float> seen = NeighbourEvidence(cameras, 0, depth, evidence);
  EXPECT_EQ(seen[Pixel(6, 3)], 1.0f);
  EXPECT_EQ(seen[Pixel(5, 3)], 0.0f);
  // Frame 0's first column projects left of frame 1's image: no neighbour sees it.
  EXPECT_EQ(seen[Pixel(0, 3)], 0.0f);
  // A neighbour whose image plane the surface touches sees it nowhere (no overflow), one behind whom
  // the surface lies sees it not at all.
  for (const double z : {-2.0 + 1e-13, -3.0}) {
    std::vector<scene::Camera> grazing = cameras;
    grazing[1].c2w(2, 3) = z;
    EXPECT_EQ(NeighbourEvidence(grazing, 0, depth, evidence), std::vector<float>(kW * kH, 0.0f)) << z;
  }
  // Where the depth is unknown the same pixel stands in.
  depth[Pixel(5, 3)] = 0.0f;
  EXPECT_EQ(NeighbourEvidence(cameras, 0, depth, evidence)[Pixel(5, 3)], 1.0f);
}

TEST(NeighbourEvidenceTest, SizesThatDisagreeAreRefused) {
  const std::vector<scene::Camera> cameras(3, CameraAt(0));
  const std::vector<float> depth(kW * kH, 1.0f);
  EXPECT_THROW(NeighbourEvidence(cameras, 3, depth, std::vector<std::vector<float>>(3)), Error);
  EXPECT_THROW(NeighbourEvidence(cameras, 0, depth, std::vector<std::vector<float>>(2)), Error);
  EXPECT_THROW(NeighbourEvidence(cameras, 0, std::vector<float>(5), std::vector<std::vector<float>>(3)),
               Error);
  std::vector<std::vector<float>> evidence(3);
  evidence[1].assign(7, 1.0f);
  EXPECT_THROW(NeighbourEvidence(cameras, 0, depth, evidence), Error);
}

}  // namespace
}  // namespace endorecon::eval
