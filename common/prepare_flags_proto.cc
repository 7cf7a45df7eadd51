#include "common/prepare_flags_proto.h"

#include "common/error.h"

namespace endorecon {

v1::PrepareOptions PrepareFlagsToProto(const PrepareFlags& f) {
  v1::PrepareOptions o;
  o.set_left(f.left);
  o.set_right(f.right);
  o.set_side_by_side(f.side_by_side);
  o.set_top_bottom(f.top_bottom);
  for (const std::string& file : f.calibration) o.add_calibration(file);
  o.set_rectified(f.rectified);
  o.set_focal(f.focal);
  o.set_baseline(f.baseline);
  o.set_masks(f.masks);
  o.set_mask_tool(f.mask_tool);
  for (const std::string& rect : f.exclude) o.add_exclude(rect);
  o.set_frames(f.frames);
  o.set_size(f.size);
  o.set_poses(f.poses);
  o.set_estimate_poses(f.estimate_poses);
  o.set_depth_refine(f.depth_refine);
  o.set_depth_paths(f.depth_paths);
  o.set_skip_left(f.skip_left);
  o.set_skip_right(f.skip_right);
  return o;
}

PrepareFlags PrepareFlagsFromProto(const v1::PrepareOptions& o) {
  PrepareFlags f;
  f.left = o.left();
  f.right = o.right();
  f.side_by_side = o.side_by_side();
  f.top_bottom = o.top_bottom();
  f.calibration.assign(o.calibration().begin(), o.calibration().end());
  f.rectified = o.rectified();
  f.focal = o.focal();
  f.baseline = o.baseline();
  f.masks = o.masks();
  if (!o.mask_tool().empty()) f.mask_tool = o.mask_tool();
  f.exclude.assign(o.exclude().begin(), o.exclude().end());
  f.frames = o.frames();
  f.size = o.size();
  f.poses = o.poses();
  f.estimate_poses = o.estimate_poses();
  f.depth_refine = o.depth_refine();
  f.depth_paths = o.depth_paths();
  f.skip_left = o.skip_left();
  f.skip_right = o.skip_right();
  return f;
}

void CheckPrepareOptions(const v1::PrepareOptions& options, const v1::Manifest& recording) {
  const PrepareFlags flags = PrepareFlagsFromProto(options);
  CheckPrepareFlags(flags);
  for (const std::string& path : flags.Paths()) {
    bool found = false;
    for (const v1::FileEntry& file : recording.files()) {
      found = found || file.path() == path || file.path().rfind(path + "/", 0) == 0;
    }
    if (!found) FailInvalid("prepare: '" + path + "' is not a file (or folder) of the uploaded recording");
  }
}

}  // namespace endorecon
