// Empty-space skipping: the ray span through a hand-made grid, and a grid built from a trained field
// that skips space yet keeps every true tissue surface point, so frames render as without it.
#include "worker/engine/render/occupancy_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "common/error.h"
#include "tests/unit/small_clip_fixture.h"
#include "worker/engine/eval/psnr.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/train/trainer.h"

namespace endorecon::render {
namespace {

TEST(OccupiedSpan, BracketsTheOccupiedCellsWithAMarginAndNeverEmptiesARay) {
  constexpr int kRes = 4;
  std::uint8_t cells[kRes * kRes * kRes] = {};
  const float inside[3] = {0.6f, 0.3f, 0.55f};
  cells[OccupancyCell(inside, kRes)] = 1;  // cell (2, 1, 2): z in [0.5, 0.75)
  // Along +z through x = 0.6, y = 0.3, from z = 0 (s = 0) to z = 1 (s = 1).
  const double start[3] = {0.6, 0.3, 0.0}, step[3] = {0.0, 0.0, 1.0};
  double lo = 0, hi = 0;
  OccupiedSpan(cells, kRes, start, step, 0.0, 1.0, &lo, &hi);
  const double ds = 0.5 / kRes;  // the march step: half a cell
  EXPECT_GE(lo, 0.5 - 2 * ds);
  EXPECT_LE(lo, 0.5);
  EXPECT_GE(hi, 0.75 - ds);
  EXPECT_LE(hi, 0.75 + 2 * ds);
  // A ray that misses every occupied cell keeps its whole range.
  const double elsewhere[3] = {0.1, 0.9, 0.0};
  OccupiedSpan(cells, kRes, elsewhere, step, 0.2, 0.9, &lo, &hi);
  EXPECT_EQ(lo, 0.2);
  EXPECT_EQ(hi, 0.9);
}

TEST(OccupancyCell, OutsideTheUnitBoxIsNoCell) {
  const float points[][3] = {{-0.01f, 0.5f, 0.5f}, {0.5f, 1.0f, 0.5f}, {0.5f, 0.5f, NAN}};
  for (const auto& p : points) EXPECT_EQ(OccupancyCell(p, 8), -1);
  const float corner[3] = {0.0f, 0.0f, 0.999f};
  EXPECT_EQ(OccupancyCell(corner, 8), 7 * 64);
}

TEST(OccupancyGrid, RejectsBadSettings) {
  field::Field field(field::FieldConfig::Cpu(), 1);
  EXPECT_THROW(OccupancyGrid::Build(field, {0.0f}, 0, 0.01f), Error);
  EXPECT_THROW(OccupancyGrid::Build(field, {}, 8, 0.01f), Error);
  EXPECT_THROW(OccupancyGrid::Build(field, {0.0f}, 8, 1.0f), Error);
}

class OccupancyGridTest : public testing::SmallClipTest {};

TEST_F(OccupancyGridTest, TrainedFieldSkipsSpaceKeepsEveryTissuePointAndRendersTheSame) {
  // The trainer rebuilds its grid every tenth of the run and samples only the occupied spans.
  train::TrainConfig config = SmallConfig();
  train::Trainer trainer(*clip_, config, AllFrames(), 5);
  for (int i = 0; i < 400; ++i) trainer.Step();
  trainer.RebuildOccupancy();
  const OccupancyGrid& grid = trainer.occupancy();
  ASSERT_EQ(grid.resolution(), config.occupancy_resolution);
  // Some of the rays' range is skipped (the box's corners outside every frustum are never trained,
  // so the occupied fraction of the box says little; the rays' spans say what is saved).
  double kept = 0;
  int rays = 0;
  for (int y = 0; y < clip_->height; ++y) {
    for (int x = 0; x < clip_->width; ++x) {
      Eigen::Vector3d origin, direction;
      clip_->cameras[0].Ray(x, y, origin, direction);
      double lo = 0, hi = 0;
      grid.Span(trainer.box(), origin, direction, clip_->near, clip_->far, &lo, &hi);
      kept += (hi - lo) / (clip_->far - clip_->near);
      ++rays;
    }
  }
  EXPECT_LT(kept / rays, 0.99) << "nothing skipped";

  // Every ground-truth tissue point of every frame lies in an occupied cell.
  const scene::SceneBox& box = trainer.box();
  int tissue = 0, missed = 0;
  for (int f = 0; f < clip_->frame_count(); ++f) {
    for (int y = 0; y < clip_->height; ++y) {
      for (int x = 0; x < clip_->width; ++x) {
        Eigen::Vector3d origin, direction;
        clip_->cameras[f].Ray(x, y, origin, direction);
        const Eigen::Vector3d p =
            box.Normalise(origin + double(clip_->gt_depth[f][y * clip_->width + x]) * direction);
        const float q[3] = {float(p.x()), float(p.y()), float(p.z())};
        ++tissue;
        missed += !grid.cells()[OccupancyCell(q, grid.resolution())];
      }
    }
  }
  EXPECT_EQ(missed, 0) << "of " << tissue << " tissue points";

  // The trainer skipped the same space, so frames render at least as well with the grid as without.
  FrameRenderSettings settings;
  settings.near = clip_->near;
  settings.far = clip_->far;
  FrameRenderer plain(trainer.field(), box, settings), skipping(trainer.field(), box, settings);
  skipping.SetOccupancy(&grid);
  for (int f : {0, 3, 7}) {
    const auto a = plain.Render(clip_->cameras[f], clip_->times[f]);
    const auto b = skipping.Render(clip_->cameras[f], clip_->times[f]);
    const auto& tool = clip_->tool_mask[f];
    const double without = eval::Psnr(a.rgb, clip_->rgb[f], tool, clip_->width, clip_->height);
    const double with = eval::Psnr(b.rgb, clip_->rgb[f], tool, clip_->width, clip_->height);
    EXPECT_GT(with, without - 0.3) << "frame " << f;
  }

  std::stringstream state;
  grid.Save(state);
  OccupancyGrid copy;
  copy.Load(state);
  const int res = grid.resolution();
  ASSERT_EQ(copy.resolution(), res);
  EXPECT_TRUE(std::equal(copy.cells(), copy.cells() + res * res * res, grid.cells()));
}

}  // namespace
}  // namespace endorecon::render
