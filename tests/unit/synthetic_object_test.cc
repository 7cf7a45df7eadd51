// The object capture `synth --object` writes, read back as a user's NeRF-synthetic data would be:
// a centred rig (object box, near/far from the rig) with images composited onto white.
#include "worker/engine/scene/synthetic_object.h"

#include <gtest/gtest.h>

#include "tests/unit/temp_dir.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/scene_box.h"
#include "worker/engine/scene/view_geometry.h"

namespace endorecon::scene {
namespace {

TEST(SyntheticObjectTest, ReadsBackAsACentredRigOnWhite) {
  testing::TempDir dir("object");
  ObjectSynthOptions options;
  options.views = 6;
  options.width = options.height = 32;
  WriteSyntheticObject(options, dir.path());
  const Clip clip = LoadClip(dir.path());
  ASSERT_EQ(clip.frame_count(), 6);
  EXPECT_EQ(clip.width, 32);
  EXPECT_TRUE(clip.is_static);
  EXPECT_TRUE(clip.transparent);
  // Cameras 4 units out: the object within 2 of the origin, near 2, far 6 (NeRF's lego rig).
  EXPECT_NEAR(clip.object_radius, 2.0, 1e-9);
  EXPECT_NEAR(clip.near, 2.0, 1e-9);
  EXPECT_NEAR(clip.far, 6.0, 1e-9);
  const SceneBox box = ClipBox(clip);
  EXPECT_NEAR(box.max.x(), 2.2, 1e-9);
  EXPECT_NEAR(box.min.z(), -2.2, 1e-9);
  for (int f = 0; f < clip.frame_count(); ++f) {
    int white = 0;
    for (std::size_t i = 0; i < clip.rgb[f].size(); i += 3)
      white += clip.rgb[f][i] == 255 && clip.rgb[f][i + 1] == 255 && clip.rgb[f][i + 2] == 255;
    const int pixels = clip.width * clip.height;
    EXPECT_GT(white, pixels / 20) << "frame " << f << ": the background shows";
    EXPECT_LT(white, pixels * 4 / 5) << "frame " << f << ": the object fills the middle";
  }

  // Read onto black, the same pixels are black.
  LoadOptions black;
  black.alpha_background = {0, 0, 0};
  const Clip dark = LoadClip(dir.path(), black);
  EXPECT_EQ(dark.rgb[0][0], 0);
  EXPECT_EQ(clip.rgb[0][0], 255);
}

// With a backdrop: opaque images (nothing transparent, so "auto" would be black), and a pixel that
// misses the object shows the backdrop's colour along the loader's ray through its centre.
TEST(SyntheticObjectTest, ABackdropShowsItsColourAlongEachPixelsRay) {
  testing::TempDir dir("backdrop");
  ObjectSynthOptions options;
  options.views = 3;
  options.width = options.height = 32;
  options.backdrop = true;
  WriteSyntheticObject(options, dir.path());
  const Clip clip = LoadClip(dir.path());
  EXPECT_FALSE(clip.transparent);
  for (int f = 0; f < clip.frame_count(); ++f) {
    for (const int pixel : {0, 31, 32 * 31, 32 * 32 - 1}) {  // the corners miss the object
      double origin[3], direction[3], unit[3];
      PixelRay(clip.cameras[f].View(), pixel, origin, direction);
      UnitDirection(direction, unit);
      float rgb[3];
      BackdropColor(unit, rgb);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(clip.rgb[f][3 * pixel + c], 255 * rgb[c], 1.0) << "frame " << f << " pixel " << pixel;
      }
    }
  }
}

}  // namespace
}  // namespace endorecon::scene
