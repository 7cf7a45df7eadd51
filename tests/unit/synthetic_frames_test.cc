// The synthetic clip made in memory is the clip its files load as, byte for byte.
#include "worker/engine/scene/synthetic_frames.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace endorecon::scene {
namespace {

void ExpectSameCameras(const std::vector<Camera>& made, const std::vector<Camera>& loaded) {
  ASSERT_EQ(made.size(), loaded.size());
  for (std::size_t i = 0; i < made.size(); ++i) {
    EXPECT_EQ(made[i].width, loaded[i].width);
    EXPECT_EQ(made[i].height, loaded[i].height);
    EXPECT_EQ(made[i].fx, loaded[i].fx);
    EXPECT_EQ(made[i].fy, loaded[i].fy);
    EXPECT_EQ(made[i].cx, loaded[i].cx);
    EXPECT_EQ(made[i].cy, loaded[i].cy);
    EXPECT_TRUE(made[i].c2w == loaded[i].c2w) << "camera " << i << "\n"
                                              << made[i].c2w << "\n"
                                              << loaded[i].c2w;
  }
}

TEST(SyntheticFrames, TheClipMadeInMemoryIsTheClipItsFilesLoadAs) {
  SynthOptions options;
  options.frames = 5;
  options.width = 40;
  options.height = 32;
  options.seed = 7;
  options.moving = true;
  options.stereo = true;
  options.flicker = 0.1;
  testing::TempDir dir("synthetic-frames");
  WriteSyntheticClip(options, dir.path() / "clip");
  const Clip loaded = LoadClip(dir.path() / "clip");
  const Clip made = MakeSyntheticClip(options);

  EXPECT_EQ(made.width, loaded.width);
  EXPECT_EQ(made.height, loaded.height);
  EXPECT_EQ(made.near, loaded.near);
  EXPECT_EQ(made.far, loaded.far);
  EXPECT_EQ(made.times, loaded.times);
  EXPECT_EQ(made.is_static, loaded.is_static);
  ExpectSameCameras(made.cameras, loaded.cameras);
  ExpectSameCameras(made.right_cameras, loaded.right_cameras);
  EXPECT_TRUE(made.rgb == loaded.rgb);
  EXPECT_TRUE(made.gt_rgb == loaded.gt_rgb);
  EXPECT_TRUE(made.right_rgb == loaded.right_rgb);
  EXPECT_TRUE(made.depth == loaded.depth);
  EXPECT_TRUE(made.tool_mask == loaded.tool_mask);
  EXPECT_TRUE(made.gt_depth == loaded.gt_depth);
  EXPECT_TRUE(made.eval_mask.empty() && loaded.eval_mask.empty());
  // Not a copy of one frame: the frames differ (the tissue moves, the camera too).
  EXPECT_FALSE(made.rgb[0] == made.rgb[4]);
}

TEST(SyntheticFrames, LeavesOutWhatTheOptionsLeaveOutAndRefusesBadOptions) {
  SynthOptions options;
  options.frames = 2;
  options.width = 16;
  options.height = 12;
  options.tool = false;
  options.depth = false;
  const Clip clip = MakeSyntheticClip(options);
  EXPECT_FALSE(clip.has_masks());
  EXPECT_FALSE(clip.has_depth());
  EXPECT_FALSE(clip.has_stereo());
  EXPECT_EQ(clip.rgb[0].size(), 16u * 12u * 3u);
  options.noise = -1;
  EXPECT_THROW(MakeSyntheticClip(options), Error);
  options.noise = 1;
  options.frames = 0;
  EXPECT_THROW(MakeSyntheticClip(options), Error);
}

}  // namespace
}  // namespace endorecon::scene
