#include "worker/prepare/clip_writer.h"

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "common/error.h"
#include "common/npy.h"

namespace endorecon::prepare {
namespace {

namespace fs = std::filesystem;

void WriteImage(const fs::path& path, const cv::Mat& image) {
  bool written = false;
  try {
    written = cv::imwrite(path.string(), image);
  } catch (const cv::Exception&) {
  }
  if (!written) Fail(ErrorCode::kUnavailable, "cannot write " + path.string());
}

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream file(path, std::ios::trunc);
  file << text;
  file.close();
  if (!file) Fail(ErrorCode::kUnavailable, "cannot write " + path.string());
}

// OpenCV camera axes (x right, y down, z forward) to OpenGL's (x right, y up, z back).
cv::Matx44d ToOpenGl(const cv::Matx44d& pose) {
  return pose * cv::Matx44d(1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1);
}

}  // namespace

std::string ClipFrameName(int index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d", index);
  return name;
}

ClipWriter::ClipWriter(fs::path dir, ClipLayout layout, const RectifiedCamera& camera, bool masks)
    : dir_(std::move(dir)), layout_(layout), camera_(camera), masks_(masks) {
  for (const char* sub : {"images", "images_right", "depth"}) fs::create_directories(dir_ / sub);
  if (masks_) fs::create_directories(dir_ / "masks");
}

void ClipWriter::Write(int index, const PreparedFrame& frame) const {
  const std::string name = ClipFrameName(index);
  WriteImage(dir_ / "images" / (name + ".png"), frame.left);
  WriteImage(dir_ / "images_right" / (name + ".png"), frame.right);
  CV_Assert(frame.depth.type() == CV_32F && frame.depth.isContinuous());
  WriteNpyFloat32(dir_ / "depth" / (name + ".npy"), frame.depth.ptr<float>(),
                  {static_cast<std::size_t>(frame.depth.rows), static_cast<std::size_t>(frame.depth.cols)});
  if (masks_) {
    // transforms.json follows nerfstudio: 0 = excluded.
    WriteImage(dir_ / "masks" / (name + ".png"),
               layout_ == ClipLayout::kEndoNerf ? frame.excluded : 255 - frame.excluded);
  }
}

void ClipWriter::Finish(const std::vector<FramePlacement>& placements, double near, double far) const {
  const int w = camera_.size.width, h = camera_.size.height;
  WriteText(dir_ / "stereo.json", nlohmann::json{{"baseline", camera_.baseline}}.dump() + "\n");
  if (layout_ == ClipLayout::kEndoNerf) {
    // LLFF rows: the OpenGL pose's columns in [down, right, back] order, then (H, W, f), near, far.
    const double hwf[3] = {static_cast<double>(h), static_cast<double>(w), camera_.focal};
    std::vector<double> rows;
    for (const FramePlacement& placement : placements) {
      const cv::Matx44d gl = ToOpenGl(placement.pose);
      for (int r = 0; r < 3; ++r)
        rows.insert(rows.end(), {0.0 - gl(r, 1), gl(r, 0), gl(r, 2), gl(r, 3), hwf[r]});
      rows.insert(rows.end(), {near, far});
    }
    WriteNpyFloat64(dir_ / "poses_bounds.npy", rows.data(), {placements.size(), 17});
    return;
  }
  const double t0 = placements.front().time_s, span = placements.back().time_s - t0;
  nlohmann::json frames = nlohmann::json::array();
  for (std::size_t i = 0; i < placements.size(); ++i) {
    const cv::Matx44d gl = ToOpenGl(placements[i].pose);
    nlohmann::json matrix = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) matrix.push_back({gl(r, 0), gl(r, 1), gl(r, 2), gl(r, 3)});
    const std::string name = ClipFrameName(static_cast<int>(i));
    nlohmann::json frame = {{"file_path", "images/" + name + ".png"},
                            {"depth_file_path", "depth/" + name + ".npy"},
                            {"transform_matrix", matrix},
                            {"time", span > 0 ? (placements[i].time_s - t0) / span : 0.0}};
    if (masks_) frame["mask_path"] = "masks/" + name + ".png";
    frames.push_back(frame);
  }
  const nlohmann::json top = {{"fl_x", camera_.focal},
                              {"fl_y", camera_.focal},
                              {"cx", w / 2.0},
                              {"cy", h / 2.0},
                              {"w", w},
                              {"h", h},
                              {"near", near},
                              {"far", far},
                              {"frames", frames}};
  WriteText(dir_ / "transforms.json", top.dump(1) + "\n");
}

}  // namespace endorecon::prepare
