// Where a learned background starts: fitted to the training frames' borders, it already shows the
// backdrop of an object capture along rays the frames' corners see (closer than the grey it would
// otherwise start from).
#include "worker/engine/train/background_start.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "tests/unit/object_clip.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/field/background_math.h"
#include "worker/engine/scene/view_geometry.h"

namespace endorecon::train {
namespace {

TEST(BackgroundStartTest, TheBordersOfAnObjectCaptureGiveItsBackdrop) {
  testing::TempDir dir("backdrop-start");
  const scene::Clip clip = testing::ObjectClip(dir.path(), 10, 32, /*backdrop=*/true);
  std::vector<float> params(field::kBackgroundParams, 0.0f);
  FitBackgroundToBorders(clip, {0, 1, 2, 3, 4, 5, 6, 7}, params.data());
  // Frames 8 and 9 were not fitted: their corners look along other rays.
  double error = 0, grey_error = 0;
  int count = 0;
  for (const int f : {8, 9}) {
    for (const int pixel : {0, 31, 32 * 31, 32 * 32 - 1}) {
      double origin[3], d[3];
      scene::PixelRay(clip.cameras[f].View(), pixel, origin, d);
      float dir[3];
      scene::UnitDirection(d, dir);
      float rgb[3];
      field::BackgroundSample(params.data(), dir, rgb);
      for (int c = 0; c < 3; ++c) {
        const double truth = clip.rgb[f][3 * pixel + c] / 255.0;
        error += std::fabs(rgb[c] - truth);
        grey_error += std::fabs(0.5 - truth);
        ++count;
      }
    }
  }
  error /= count;
  grey_error /= count;
  EXPECT_LT(error, 0.04) << "grey would be " << grey_error;
  std::printf("border fit: mean error %.4f (grey %.4f)\n", error, grey_error);
  EXPECT_LT(error, grey_error / 3);
}

}  // namespace
}  // namespace endorecon::train
