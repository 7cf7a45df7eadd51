#include "worker/prepare/options_from_flags.h"

namespace endorecon::prepare {

PrepareOptions OptionsFromFlags(const PrepareFlags& f, const std::filesystem::path& base) {
  CheckPrepareFlags(f);
  const auto path = [&](const std::string& p) {
    return p.empty() || base.empty() ? std::filesystem::path(p) : base / p;
  };
  PrepareOptions o;
  if (!f.side_by_side.empty()) {
    o.recording = {StereoLayout::kSideBySide, {}, {}, path(f.side_by_side)};
  } else if (!f.top_bottom.empty()) {
    o.recording = {StereoLayout::kTopBottom, {}, {}, path(f.top_bottom)};
  } else {
    o.recording = {StereoLayout::kTwoSources, path(f.left), path(f.right), {}, f.skip_left, f.skip_right};
  }
  for (const std::string& file : f.calibration) o.calibration.push_back(path(file));
  o.rectified = f.rectified;
  o.focal = f.focal;
  o.baseline = f.baseline;
  o.masks = path(f.masks);
  o.masks_tool_black = f.mask_tool == "black";
  for (const std::string& rect : f.exclude) o.exclude.push_back(ParsePixelRect(rect));
  if (!f.frames.empty()) o.frames = ParseFrameRange(f.frames);
  if (!f.size.empty()) o.size = ParseFrameSize(f.size);
  o.poses = path(f.poses);
  o.estimate_poses = f.estimate_poses;
  o.depth.refine = f.depth_refine;
  o.depth.eight_paths = f.depth_paths == 8 || (f.depth_paths == 0 && f.estimate_poses);
  return o;
}

}  // namespace endorecon::prepare
