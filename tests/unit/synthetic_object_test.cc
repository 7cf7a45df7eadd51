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

// The capture made in memory (for the GPU tests' bundle) is what its files load as, byte for byte:
// on transparency (composited onto white) and in front of a backdrop (opaque RGB).
TEST(SyntheticObjectTest, TheCaptureMadeInMemoryIsTheCaptureItsFilesLoadAs) {
  for (const bool backdrop : {false, true}) {
    testing::TempDir dir("object-memory");
    ObjectSynthOptions options;
    options.views = 5;
    options.width = 24;
    options.height = 20;
    options.backdrop = backdrop;
    WriteSyntheticObject(options, dir.path());
    const Clip files = LoadClip(dir.path());
    const Clip memory = MakeSyntheticObject(options);
    ASSERT_EQ(memory.frame_count(), files.frame_count()) << backdrop;
    EXPECT_EQ(memory.width, files.width);
    EXPECT_EQ(memory.height, files.height);
    EXPECT_EQ(memory.rgb, files.rgb) << backdrop;
    EXPECT_EQ(memory.times, files.times);
    EXPECT_EQ(memory.is_static, files.is_static);
    EXPECT_EQ(memory.transparent, files.transparent);
    EXPECT_EQ(memory.transparent, !backdrop);
    EXPECT_EQ(memory.near, files.near);
    EXPECT_EQ(memory.far, files.far);
    EXPECT_EQ(memory.object_radius, files.object_radius);
    for (int f = 0; f < files.frame_count(); ++f) {
      EXPECT_EQ(memory.cameras[f].c2w, files.cameras[f].c2w) << f;
      EXPECT_EQ(memory.cameras[f].fx, files.cameras[f].fx);
      EXPECT_EQ(memory.cameras[f].fy, files.cameras[f].fy);
      EXPECT_EQ(memory.cameras[f].cx, files.cameras[f].cx);
      EXPECT_EQ(memory.cameras[f].cy, files.cameras[f].cy);
    }
  }
}

}  // namespace
}  // namespace endorecon::scene
