#include "client/clip_cut.h"

#include <nlohmann/json.hpp>
#include <vector>

#include "client/staging_folder.h"
#include "common/clip_files.h"
#include "common/error.h"
#include "common/file_write.h"
#include "common/json_file.h"
#include "common/npy.h"
#include "common/pose_rows.h"

namespace endorecon::client {
namespace fs = std::filesystem;

StagedClipCut::StagedClipCut(const fs::path& clip, const FrameRange& frames)
    : clip_(fs::absolute(clip).lexically_normal()), given_(clip.string()) {
  while (given_.size() > 1 && given_.back() == '/') given_.pop_back();
  if (!clip_.has_filename()) clip_ = clip_.parent_path();  // "clips/c12/"
  const std::vector<FrameFiles> all = ListClipFrames(clip_);
  total_ = all.size();
  const std::vector<int> picked = frames.PickedOf(static_cast<int>(total_), "", clip.string() + "'s");
  picked_ = picked.size();
  dir_ = MakeStagingFolder("clip");
  // Each file once: frames of a transforms.json may share a mask.
  const auto link = [&](const fs::path& file) {
    if (file.empty()) return;
    const fs::path target = dir_ / file.lexically_normal().lexically_relative(clip_);
    if (fs::exists(fs::symlink_status(target))) return;
    fs::create_directories(target.parent_path());
    fs::create_symlink(file, target);
  };
  for (const int frame : picked) {
    const FrameFiles& files = all[static_cast<std::size_t>(frame)];
    for (const fs::path* file :
         {&files.image, &files.depth, &files.tool_mask, &files.eval_mask, &files.right_image})
      link(*file);
  }
  if (FindClipLayout(clip_) == ClipLayout::kTransforms) {
    nlohmann::json top = ReadJsonFile(clip_ / "transforms.json");
    nlohmann::json cut = nlohmann::json::array();
    for (const int frame : picked) cut.push_back(top["frames"][static_cast<std::size_t>(frame)]);
    top["frames"] = std::move(cut);
    WriteFile(dir_ / "transforms.json", top.dump(2) + "\n", "the cut clip's transforms.json");
  } else {
    const fs::path poses = clip_ / "poses_bounds.npy";
    const NpyArray rows = ReadNpy(poses);
    PoseRowsOf(rows, poses);  // every row, as a local run of the same frames checks them
    std::vector<double> cut;
    for (const int frame : picked) {
      const auto row = rows.data.begin() + static_cast<std::ptrdiff_t>(frame * kPoseColumns);
      cut.insert(cut.end(), row, row + static_cast<std::ptrdiff_t>(kPoseColumns));
    }
    WriteNpyFloat64(dir_ / "poses_bounds.npy", cut.data(), {picked.size(), kPoseColumns});
    if (fs::exists(clip_ / "stereo.json")) link(clip_ / "stereo.json");
  }
  if (fs::is_directory(clip_ / "gt")) {
    const std::vector<FrameFiles> truth = ListGroundTruthFrames(clip_ / "gt", total_);
    for (const int frame : picked) {
      link(truth[static_cast<std::size_t>(frame)].image);
      link(truth[static_cast<std::size_t>(frame)].depth);
    }
  }
}

StagedClipCut::~StagedClipCut() {
  std::error_code ignored;
  fs::remove_all(dir_, ignored);
}

std::string StagedClipCut::InClip(std::string text) const {
  const std::string staged = dir_.string(), own = given_;
  for (auto at = text.find(staged); at != std::string::npos; at = text.find(staged, at + own.size()))
    text.replace(at, staged.size(), own);
  return text;
}

}  // namespace endorecon::client
