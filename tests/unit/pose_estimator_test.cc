// Poses of a moving endoscope estimated from its own stereo frames, against the synthetic path.
// Issue 16's targets are 1% of the trajectory's length in translation and 0.5 degrees in rotation;
// the rotation target is met, the translation one is not yet: on this path (19 units in 12
// frames, the light moving with the endoscope) the worst frame is 2-4% off (docs/benchmarks.md,
// "Pose estimation"), so this test holds the estimator to 5%.
#include "worker/prepare/pose_estimator.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "tests/unit/synthetic_recording_fixture.h"
#include "worker/engine/scene/clip_loader.h"

namespace endorecon::testing {
namespace {

Eigen::Matrix4d Homogeneous(const Eigen::Matrix<double, 3, 4>& pose) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topRows<3>() = pose;
  return m;
}

TEST(PoseEstimatorTest, FollowsTheMovingSyntheticEndoscope) {
  TempDir dir("poses");
  scene::SynthOptions synth = RecordingOptions(320, 256, 12);
  synth.moving = true;
  synth.static_scene = true;
  scene::WriteSyntheticClip(synth, dir / "synth");
  prepare::PrepareOptions options = RecordingPrepareOptions(dir / "synth", dir / "clip");
  options.estimate_poses = true;
  options.depth.eight_paths = true;  // what --estimate-poses chooses by default
  const prepare::PrepareSummary summary = prepare::PrepareClip(options);
  EXPECT_EQ(summary.layout, "transforms");
  EXPECT_TRUE(summary.dropped.empty());
  EXPECT_LT(summary.pose_reprojection.rms, 1.0);

  const nlohmann::json report = ReadJson(dir / "clip/prepare.json");
  EXPECT_TRUE(report["poses"]["reprojection_error_px"].contains("rms"));
  const scene::Clip clip = scene::LoadClip(dir / "clip");
  ASSERT_EQ(clip.frame_count(), 12);
  EXPECT_FALSE(clip.is_static);
  const scene::SyntheticScene scene(synth);
  const Eigen::Matrix4d first = Homogeneous(TruthCamera(scene, synth, report, 0).c2w);
  double length = 0, worst_translation = 0, worst_degrees = 0;
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (int f = 0; f < clip.frame_count(); ++f) {
    const Eigen::Matrix4d truth = first.inverse() * Homogeneous(TruthCamera(scene, synth, report, f).c2w);
    const Eigen::Matrix4d estimate = Homogeneous(clip.cameras[f].c2w);
    length += (truth.topRightCorner<3, 1>() - previous).norm();
    previous = truth.topRightCorner<3, 1>();
    worst_translation =
        std::max(worst_translation, (estimate.topRightCorner<3, 1>() - truth.topRightCorner<3, 1>()).norm());
    const Eigen::Matrix3d difference =
        estimate.topLeftCorner<3, 3>().transpose() * truth.topLeftCorner<3, 3>();
    worst_degrees = std::max(worst_degrees, Eigen::AngleAxisd(difference).angle() * 180 / M_PI);
  }
  EXPECT_GT(length, 10) << "the synthetic endoscope should move";
  EXPECT_LE(worst_translation, 0.05 * length) << "trajectory length " << length;
  EXPECT_LE(worst_degrees, 0.5);
}

}  // namespace
}  // namespace endorecon::testing
