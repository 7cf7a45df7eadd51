// The model map's third term: the neighbouring training frames' signed residuals, averaged where the
// frame's surface projects in each neighbour, squared, relative to the camera noise's level at the
// frame's brightness. And its fourth: the frame's render against the nearest training frames' images,
// averaged over the neighbours and a Gaussian, squared.
#include "worker/engine/eval/neighbour_evidence.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
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

// Evidence of n pixels whose residual is (r, 0, 0), the same in every pixel.
std::vector<float> Residuals(float r) {
  std::vector<float> residual(3 * kW * kH, 0.0f);
  for (int p = 0; p < kW * kH; ++p) residual[3 * p] = r;
  return residual;
}

void SetResidual(std::vector<float>& evidence, int pixel, float r) { evidence[3 * pixel] = r; }

// A frame's render: one grey everywhere (one brightness bin), and no tool.
const std::vector<float> kGrey(3 * kW * kH, 0.5f);
const std::vector<std::uint8_t> kNoTool;

TEST(ResidualEvidenceTest, TheSignedResidualPerChannelWithTheToolMarked) {
  const std::vector<float> rgb = {0.5f, 1.2f, -0.1f, 0.2f, 0.2f, 0.2f};
  const std::vector<std::uint8_t> image = {102, 255, 0, 0, 0, 0}, tool = {0, 1};
  const std::vector<float> evidence = ResidualEvidence(rgb, image, tool);
  ASSERT_EQ(evidence.size(), 6u);
  EXPECT_NEAR(evidence[0], 0.5 - 0.4, 1e-6);  // rendered minus observed
  EXPECT_EQ(evidence[1], 0.0f);               // the render clamped to [0, 1] first
  EXPECT_EQ(evidence[2], 0.0f);
  for (int c = 3; c < 6; ++c) EXPECT_TRUE(std::isnan(evidence[c]));  // the tool: no evidence
  EXPECT_THROW(ResidualEvidence(rgb, std::vector<std::uint8_t>(3), {}), Error);
  EXPECT_THROW(ResidualEvidence(rgb, image, std::vector<std::uint8_t>(3)), Error);
}

TEST(NeighbourEvidenceTest, AStillCameraAveragesTheResidualsBeforeSquaringThem) {
  const std::vector<scene::Camera> cameras(5, CameraAt(0));
  const std::vector<float> depth(kW * kH, 2.0f);
  // Frame 2's neighbours in training: 1 (distance 1) and 4 (distance 2); both 0.01 too bright.
  std::vector<std::vector<float>> evidence(5);
  evidence[1] = Residuals(0.01f);
  evidence[4] = Residuals(0.01f);
  SetResidual(evidence[4], Pixel(1, 1), -0.02f);  // noise: (1 * 0.01 + 0.5 * -0.02) / 1.5 = 0
  SetResidual(evidence[1], Pixel(2, 1), 0.03f);   // the model's own error, in both: 3 times the rest
  SetResidual(evidence[4], Pixel(2, 1), 0.03f);
  evidence[1][3 * Pixel(3, 2)] = std::numeric_limits<float>::quiet_NaN();  // frame 1's tool: frame 4 alone
  SetResidual(evidence[4], Pixel(3, 2), 0.02f);
  const std::vector<float> seen = NeighbourEvidence(cameras, 2, kGrey, depth, kNoTool, evidence);
  // Relative to the frame's median at its brightness, 0.01^2.
  EXPECT_NEAR(seen[Pixel(0, 0)], 1.0, 1e-5);
  EXPECT_NEAR(seen[Pixel(1, 1)], 0.0, 1e-5);
  EXPECT_NEAR(seen[Pixel(2, 1)], 9.0, 1e-4);
  EXPECT_NEAR(seen[Pixel(3, 2)], 4.0, 1e-4);
  // A frame past kNeighbourFrames is not a neighbour; a frame without evidence (held out) is none.
  const std::vector<float> none =
      NeighbourEvidence(std::vector<scene::Camera>(6, CameraAt(0)), 5, kGrey,
                        std::vector<float>(kW * kH, 2.0f), kNoTool, {Residuals(0.01f), {}, {}, {}, {}, {}});
  EXPECT_EQ(none, std::vector<float>(kW * kH, 0.0f));
}

TEST(NeighbourEvidenceTest, AMovingCameraIsFollowedThroughTheRenderedDepth) {
  // Frame 1's camera sits one pixel's footprint to the right at depth 2 (fx = 10: 0.2): the surface
  // frame 0 sees at pixel u, frame 1 sees at u - 1.
  const std::vector<scene::Camera> cameras = {CameraAt(0), CameraAt(0.2)};
  std::vector<std::vector<float>> evidence(2);
  evidence[1] = Residuals(0.01f);
  SetResidual(evidence[1], Pixel(5, 3), 0.03f);
  std::vector<float> depth(kW * kH, 2.0f);
  const std::vector<float> seen = NeighbourEvidence(cameras, 0, kGrey, depth, kNoTool, evidence);
  EXPECT_NEAR(seen[Pixel(6, 3)], 9.0, 1e-4);
  EXPECT_NEAR(seen[Pixel(5, 3)], 1.0, 1e-5);
  // Frame 0's first column projects left of frame 1's image: no neighbour sees it.
  EXPECT_EQ(seen[Pixel(0, 3)], 0.0f);
  // A neighbour whose image plane the surface touches sees it nowhere (no overflow), one behind whom
  // the surface lies sees it not at all.
  for (const double z : {-2.0 + 1e-13, -3.0}) {
    std::vector<scene::Camera> grazing = cameras;
    grazing[1].c2w(2, 3) = z;
    EXPECT_EQ(NeighbourEvidence(grazing, 0, kGrey, depth, kNoTool, evidence),
              std::vector<float>(kW * kH, 0.0f))
        << z;
  }
  // Where the depth is unknown the same pixel stands in.
  depth[Pixel(5, 3)] = 0.0f;
  EXPECT_NEAR(NeighbourEvidence(cameras, 0, kGrey, depth, kNoTool, evidence)[Pixel(5, 3)], 9.0, 1e-4);
}

TEST(NeighbourEvidenceTest, SizesThatDisagreeAreRefused) {
  const std::vector<scene::Camera> cameras(3, CameraAt(0));
  const std::vector<float> depth(kW * kH, 1.0f);
  const std::vector<std::vector<float>> none(3);
  EXPECT_THROW(NeighbourEvidence(cameras, 3, kGrey, depth, kNoTool, none), Error);
  EXPECT_THROW(NeighbourEvidence(cameras, 0, kGrey, depth, kNoTool, std::vector<std::vector<float>>(2)),
               Error);
  EXPECT_THROW(NeighbourEvidence(cameras, 0, kGrey, std::vector<float>(5), kNoTool, none), Error);
  EXPECT_THROW(NeighbourEvidence(cameras, 0, std::vector<float>(5), depth, kNoTool, none), Error);
  EXPECT_THROW(NeighbourEvidence(cameras, 0, kGrey, depth, std::vector<std::uint8_t>(5), none), Error);
  std::vector<std::vector<float>> evidence(3);
  evidence[1].assign(kW * kH, 1.0f);  // one value a pixel where three are due
  EXPECT_THROW(NeighbourEvidence(cameras, 0, kGrey, depth, kNoTool, evidence), Error);
}

// An image of one grey level (0-255) everywhere.
std::vector<std::uint8_t> GreyImage(std::uint8_t level) {
  return std::vector<std::uint8_t>(3 * kW * kH, level);
}

// The weight of the centre pixel in the 2-D Gaussian of kDisagreementBlurPixels = 1 that OpenCV builds
// for doubles (9 taps): 1 / (sum over |x| <= 4 of exp(-x^2 / 2)), squared.
constexpr double kCentre = 0.398942 * 0.398942;

TEST(NeighbourDisagreementTest, TheNeighboursDifferencesAreAveragedThenBlurredThenSquared) {
  const std::vector<scene::Camera> cameras(7, CameraAt(0));
  const std::vector<float> depth(kW * kH, 2.0f);
  // Frame 3's render is 0.5 grey. Its training neighbours: 2 (weight 1) sees 0.4 everywhere, 5 (weight
  // 1/2) 0.6; 1 and 4 are held out (no image), 0 and 6 too far to count.
  const std::vector<std::uint8_t> grey = GreyImage(102), bright = GreyImage(153);  // 0.4 and 0.6
  std::vector<NeighbourImage> images(7);
  images[0] = {bright};
  images[6] = {bright};
  images[2] = {grey};
  images[5] = {bright};
  const std::vector<float> seen = NeighbourDisagreement(cameras, 3, kGrey, depth, images);
  const double mean = (1.0 * 0.1 + 0.5 * -0.1) / 1.5;
  for (int p = 0; p < kW * kH; ++p) ASSERT_NEAR(seen[p], 3 * mean * mean, 1e-6) << p;
  // One pixel of frame 2 brighter in red by 0.2, frame 5 as frame 2 elsewhere: the blur keeps kCentre
  // of the spot at its pixel.
  std::vector<std::uint8_t> spot = grey;
  spot[3 * Pixel(6, 4)] = 153;
  images[2] = {spot};
  images[5] = {grey};
  const std::vector<float> spotted = NeighbourDisagreement(cameras, 3, kGrey, depth, images);
  const double red = 0.1 - kCentre * 0.2 / 1.5;
  EXPECT_NEAR(spotted[Pixel(6, 4)], red * red + 2 * 0.1 * 0.1, 1e-5);
  EXPECT_NEAR(spotted[Pixel(0, 0)], 3 * 0.1 * 0.1, 1e-5);  // beyond the blur's reach: unchanged
}

TEST(NeighbourDisagreementTest, ANeighboursToolIsLeftOutWithoutPullingItsSurroundingsToZero) {
  const std::vector<scene::Camera> cameras(2, CameraAt(0));
  const std::vector<float> depth(kW * kH, 2.0f);
  const std::vector<std::uint8_t> grey = GreyImage(102);
  std::vector<std::uint8_t> tool(kW * kH, 0);
  for (int v = 0; v < kH; ++v) {
    for (int u = 0; u < kW / 2; ++u) tool[Pixel(u, v)] = 1;
  }
  std::vector<NeighbourImage> images(2);
  images[1] = {grey, tool};
  const std::vector<float> seen = NeighbourDisagreement(cameras, 0, kGrey, depth, images);
  // The right half and the tool's pixels within the blur's reach read the right half's 0.1 per
  // channel; the tool's pixels beyond it (more than 4 columns in) have no neighbour: 0.
  EXPECT_NEAR(seen[Pixel(kW - 1, 3)], 0.03, 1e-6);
  EXPECT_NEAR(seen[Pixel(kW / 2 - 1, 3)], 0.03, 1e-6);
  EXPECT_EQ(seen[Pixel(0, 3)], 0.0f);
}

TEST(NeighbourDisagreementTest, AMovingCameraIsFollowedAndSizesThatDisagreeAreRefused) {
  // As NeighbourEvidence's: frame 0's pixel u is frame 1's u - 1.
  const std::vector<scene::Camera> cameras = {CameraAt(0), CameraAt(0.2)};
  const std::vector<float> depth(kW * kH, 2.0f);
  std::vector<std::uint8_t> column = GreyImage(128);           // 0.502: about the render
  for (int v = 0; v < kH; ++v) column[3 * Pixel(5, v)] = 255;  // red in frame 1's column 5
  std::vector<NeighbourImage> images(2);
  images[1] = {column};
  const std::vector<float> seen = NeighbourDisagreement(cameras, 0, kGrey, depth, images);
  EXPECT_GT(seen[Pixel(6, 3)], 10 * seen[Pixel(4, 3)]);  // frame 0's column 6 is frame 1's 5
  EXPECT_THROW(NeighbourDisagreement(cameras, 0, kGrey, depth, std::vector<NeighbourImage>(1)), Error);
  EXPECT_THROW(NeighbourDisagreement(cameras, 2, kGrey, depth, images), Error);
  EXPECT_THROW(NeighbourDisagreement(cameras, 0, kGrey, std::vector<float>(5), images), Error);
  const std::vector<std::uint8_t> small(5);
  images[1] = {small};
  EXPECT_THROW(NeighbourDisagreement(cameras, 0, kGrey, depth, images), Error);
  images[1] = {column, small};
  EXPECT_THROW(NeighbourDisagreement(cameras, 0, kGrey, depth, images), Error);
}

}  // namespace
}  // namespace endorecon::eval
