#include "common/clip_files.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "common/error.h"
#include "common/job_bounds.h"
#include "common/json_file.h"
#include "common/npy.h"

namespace endorecon {
namespace {

// What column `column` of a poses_bounds.npy row holds: the 3x5 matrix [R | t | (H, W, f)] row by
// row, then near and far.
std::string PoseColumnName(std::size_t column) {
  if (column == 15) return "near";
  if (column == 16) return "far";
  const std::size_t r = column / 5, c = column % 5;
  if (c < 3) return "R[" + std::to_string(r) + "][" + std::to_string(c) + "]";
  if (c == 3) return "t[" + std::to_string(r) + "]";
  return r == 0 ? "H" : r == 1 ? "W" : "focal length";
}

namespace fs = std::filesystem;
using nlohmann::json;

std::string Lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// Where a per-frame folder and the folder it is paired with (images/) part ways, by file name (stem):
// the first file there without one here, or the first here without one there; empty when the names
// match. `folder` is the other folder's name before its files' ("images/", "depth/").
std::string FirstUnpaired(const std::vector<fs::path>& files, const std::vector<fs::path>& images,
                          const std::string& folder = "images/") {
  std::set<std::string> stems, image_stems;
  for (const auto& f : files) stems.insert(f.stem().string());
  for (const auto& f : images) image_stems.insert(f.stem().string());
  for (const auto& image : images) {
    if (!stems.count(image.stem().string()))
      return "no file named " + image.stem().string() + ".* for " + folder + image.filename().string();
  }
  for (const auto& f : files) {
    if (!image_stems.count(f.stem().string())) return f.filename().string() + " names no file in " + folder;
  }
  return "";
}

// The first gap in files named by numbers of one width ("no 000005.* between 000004 and 000006");
// empty when the names are not such numbers or run without a gap.
std::string FirstGap(const std::vector<fs::path>& files) {
  std::vector<long long> numbers;
  std::size_t width = 0;
  for (const auto& f : files) {
    const std::string stem = f.stem().string();
    if (stem.empty() || stem.size() > 15 || (width != 0 && stem.size() != width) ||
        !std::all_of(stem.begin(), stem.end(), [](unsigned char c) { return std::isdigit(c); }))
      return "";
    width = stem.size();
    numbers.push_back(std::stoll(stem));
  }
  std::sort(numbers.begin(), numbers.end());
  const auto named = [width](long long n) { return fmt::format("{:0{}}", n, width); };
  for (std::size_t i = 1; i < numbers.size(); ++i) {
    if (numbers[i] > numbers[i - 1] + 1) {
      return "no " + named(numbers[i - 1] + 1) + ".* between " + named(numbers[i - 1]) + " and " +
             named(numbers[i]);
    }
  }
  return "";
}

// The files of an optional folder: none when absent, otherwise exactly `count`, paired with
// `images` (when given) by their sorted order.
std::vector<fs::path> ListFolder(const fs::path& dir, const std::vector<std::string>& extensions,
                                 std::size_t count, bool required, const std::vector<fs::path>& images = {},
                                 const std::string& missing = "") {
  if (!required && !fs::exists(dir)) return {};
  std::vector<fs::path> files = ListFiles(dir, extensions);
  if (files.size() != count) {
    const std::string unpaired = !missing.empty() ? missing
                                 : images.empty() ? ""
                                                  : FirstUnpaired(files, images);
    FailInvalid(dir.string() + ": holds " + std::to_string(files.size()) +
                " files but poses_bounds.npy has " + std::to_string(count) +
                " rows (the counts of images, depth maps, masks and poses must be equal)" +
                (unpaired.empty() ? "" : "; " + unpaired));
  }
  // Files are paired with images by their sorted order: names that part ways (000004 beside image
  // 000003) usually mean a file is missing and another is extra.
  for (std::size_t i = 0; i < images.size() && i < files.size(); ++i) {
    if (files[i].stem() != images[i].stem()) {
      spdlog::warn("{}: {} is paired with images/{} by their sorted order, though their names differ ({})",
                   dir.string(), files[i].filename().string(), images[i].filename().string(),
                   FirstUnpaired(files, images));
      break;
    }
  }
  return files;
}

fs::path ResolveFile(const fs::path& dir, const json& frame, const char* key, const std::string& where) {
  const json& value = frame[key];
  if (!value.is_string()) FailInvalid(where + ": \"" + key + "\" must be a string, found " + value.dump());
  // A clip is its folder: a path that leaves it (absolute, or up through "..") is refused, so a clip
  // uploaded to the service cannot make a worker read its own files (or another job's).
  if (value.get<std::string>().empty()) FailInvalid(where + ": \"" + key + "\" is empty");
  // No file name holds a NUL (the system's calls end the name there) or another control character:
  // the message cut at it, saying where but not what (found 2026-12-06).
  if (const std::string& text = value.get<std::string>(); PrintableText(text, text.size()) != text) {
    FailInvalid(where + ": \"" + key + "\" " + value.dump() +
                " holds a control character (a NUL, a line break, an escape) or bytes of no UTF-8 text");
  }
  const fs::path relative = fs::path(value.get<std::string>()).lexically_normal();
  if (relative.is_absolute() || relative.has_root_name() || *relative.begin() == "..") {
    FailInvalid(where + ": " + key + " \"" + value.get<std::string>() +
                "\" leaves the clip's folder; paths must be relative and stay inside it");
  }
  const fs::path path = dir / relative;
  std::error_code error;
  if (fs::is_regular_file(path, error)) return path;
  if (fs::exists(path, error))
    FailInvalid(where + ": " + key + " " + path.string() + " is not a regular file");
  for (const char* extension : {".png", ".jpg", ".jpeg", ".npy"}) {
    fs::path candidate = path;
    candidate += extension;
    if (fs::is_regular_file(candidate, error)) return candidate;
  }
  FailInvalid(where + ": " + key + " " + path.string() +
              " does not exist (also tried adding .png, .jpg, .jpeg, .npy)");
}

}  // namespace

const std::vector<std::string>& ImageExtensions() {
  static const std::vector<std::string> extensions = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff"};
  return extensions;
}

bool HasExtension(const fs::path& path, const std::vector<std::string>& extensions) {
  const std::string extension = Lower(path.extension().string());
  return std::find(extensions.begin(), extensions.end(), extension) != extensions.end();
}

bool NaturalLess(std::string_view a, std::string_view b) {
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (digit(a[i]) && digit(b[j])) {
      std::size_t ei = i, ej = j;
      while (ei < a.size() && digit(a[ei])) ++ei;
      while (ej < b.size() && digit(b[ej])) ++ej;
      // Compared as numbers of any length: leading zeros aside, the longer run is the larger number.
      std::string_view x = a.substr(i, ei - i), y = b.substr(j, ej - j);
      x.remove_prefix(std::min(x.find_first_not_of('0'), x.size()));
      y.remove_prefix(std::min(y.find_first_not_of('0'), y.size()));
      if (x.size() != y.size()) return x.size() < y.size();
      if (x != y) return x < y;
      i = ei;
      j = ej;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  if ((i < a.size()) != (j < b.size())) return j < b.size();
  return a < b;  // equal as numbers ("01", "1"): by their characters, so the order is total
}

std::vector<fs::path> ListFiles(const fs::path& dir, const std::vector<std::string>& extensions) {
  if (!fs::is_directory(dir)) FailInvalid(dir.string() + ": folder does not exist");
  std::vector<fs::path> files;
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename().string().starts_with(".") || !HasExtension(entry.path(), extensions))
      continue;
    // A frame's name that is no readable file (a broken or looping link, a folder, a pipe) is named,
    // not skipped: skipped, it would show only as a frame count that disagrees.
    if (!entry.is_regular_file(error)) {
      FailInvalid(entry.path().string() + ": not a regular file (" +
                  (error ? error.message() : std::string("a folder, a broken link, a pipe or a device")) +
                  ")");
    }
    files.push_back(entry.path());
  }
  // Numbers in names as numbers: FFmpeg's `%d.png` names 0.png ... 15.png, whose string order put
  // 10-15 before 2 and scrambled time without a word (found 2026-12-05).
  std::sort(files.begin(), files.end(), [](const fs::path& a, const fs::path& b) {
    return NaturalLess(a.filename().string(), b.filename().string());
  });
  return files;
}

std::optional<ClipLayout> FindClipLayout(const fs::path& dir) {
  if (fs::exists(dir / "transforms.json")) return ClipLayout::kTransforms;
  if (fs::exists(dir / "poses_bounds.npy")) return ClipLayout::kEndoNerf;
  return std::nullopt;
}

std::size_t PoseRowCount(const NpyArray& poses, const fs::path& path) {
  if (poses.shape.size() != 2 || poses.shape[1] != kPoseColumns) {
    std::string shape;
    for (std::size_t dim : poses.shape) shape += (shape.empty() ? "" : ", ") + std::to_string(dim);
    FailInvalid(path.string() + ": expected an array of shape (N, 17), found (" + shape + ")");
  }
  if (poses.shape[0] == 0) FailInvalid(path.string() + ": zero frames (the array has no rows)");
  // Here, not only in the loader's camera checks, so that the CLI refuses a NaN before the upload.
  for (std::size_t at = 0; at < poses.data.size(); ++at) {
    if (std::isfinite(poses.data[at])) continue;
    const std::size_t row = at / kPoseColumns, column = at % kPoseColumns;
    FailInvalid(path.string() + " row " + std::to_string(row) + ": column " + std::to_string(column) + " (" +
                PoseColumnName(column) + ") is " + (std::isnan(poses.data[at]) ? "NaN" : "infinite") +
                "; every value must be finite");
  }
  return poses.shape[0];
}

std::vector<FrameFiles> ListEndoNerfFrames(const fs::path& dir, std::size_t rows) {
  std::vector<std::string> depth_extensions = ImageExtensions();
  depth_extensions.push_back(".npy");
  const std::vector<fs::path> images = [&] {
    const std::vector<fs::path> found = ListFiles(dir / "images", ImageExtensions());
    if (found.size() == rows) return found;
    // Which frame is missing, said from another per-frame folder with a file for every row, or from a
    // gap in numbered names (it said only the counts; found 2026-12-07).
    std::string missing = FirstGap(found);
    for (const char* other : {"depth", "masks", "gt_masks", "images_right"}) {
      if (!missing.empty() || !fs::exists(dir / other)) continue;
      const std::vector<fs::path> files = ListFiles(dir / other, depth_extensions);
      if (files.size() == rows) missing = FirstUnpaired(found, files, std::string(other) + "/");
    }
    return ListFolder(dir / "images", ImageExtensions(), rows, true, {}, missing);
  }();
  const std::vector<fs::path> depths = ListFolder(dir / "depth", depth_extensions, rows, false, images);
  const std::vector<fs::path> masks = ListFolder(dir / "masks", ImageExtensions(), rows, false, images);
  const std::vector<fs::path> eval_masks =
      ListFolder(dir / "gt_masks", ImageExtensions(), rows, false, images);
  const std::vector<fs::path> rights =
      ListFolder(dir / "images_right", ImageExtensions(), rows, false, images);

  std::vector<FrameFiles> frames(rows);
  for (std::size_t i = 0; i < rows; ++i) {
    frames[i].image = images[i];
    if (!depths.empty()) frames[i].depth = depths[i];
    if (!masks.empty()) frames[i].tool_mask = masks[i];
    if (!eval_masks.empty()) frames[i].eval_mask = eval_masks[i];
    if (!rights.empty()) frames[i].right_image = rights[i];
  }
  return frames;
}

std::vector<FrameFiles> ListTransformsFrames(const fs::path& dir, const json& top) {
  const std::string file = (dir / "transforms.json").string();
  if (!top.is_object() || !top.contains("frames") || !top["frames"].is_array()) {
    FailInvalid(file + ": expected an object with a \"frames\" array");
  }
  const json& frames = top["frames"];
  if (frames.empty()) FailInvalid(file + ": zero frames (\"frames\" is empty)");
  std::vector<FrameFiles> files(frames.size());
  // One image for many frames trained them as one frame at many times, and let a few kB of upload
  // decode into gigabytes (3,000 frames of one 1024 x 1024 PNG; found 2026-12-05).
  std::map<fs::path, std::size_t> frame_of_image;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::string where = file + " frame " + std::to_string(i);
    const json& frame = frames[i];
    if (!frame.is_object())
      FailInvalid(where + ": not an object (a frame is {\"file_path\": ..., \"transform_matrix\": ...})");
    if (!frame.contains("file_path")) FailInvalid(where + ": no \"file_path\"");
    files[i].image = ResolveFile(dir, frame, "file_path", where);
    const auto [first, added] = frame_of_image.emplace(files[i].image.lexically_normal(), i);
    if (!added) {
      FailInvalid(where + ": its file_path " + files[i].image.string() + " is frame " +
                  std::to_string(first->second) + "'s too; every frame needs an image of its own");
    }
    if (frame.contains("depth_file_path")) files[i].depth = ResolveFile(dir, frame, "depth_file_path", where);
    if (frame.contains("mask_path")) files[i].tool_mask = ResolveFile(dir, frame, "mask_path", where);
  }
  return files;
}

std::vector<FrameFiles> ListClipFrames(const fs::path& dir) {
  const std::optional<ClipLayout> layout = FindClipLayout(dir);
  if (!layout) {
    FailInvalid(dir.string() +
                ": not a clip: found neither transforms.json (transforms.json layout) nor poses_bounds.npy "
                "(EndoNeRF layout)");
  }
  if (*layout == ClipLayout::kTransforms) {
    if (fs::exists(dir / "poses_bounds.npy")) {
      spdlog::warn(
          "{}: holds both transforms.json and poses_bounds.npy; transforms.json is read, "
          "poses_bounds.npy left aside (remove the one that does not describe the frames)",
          dir.string());
    }
    return ListTransformsFrames(dir, ReadJsonFile(dir / "transforms.json"));
  }
  const fs::path poses = dir / "poses_bounds.npy";
  if (!fs::exists(poses)) FailInvalid(poses.string() + ": file does not exist");
  return ListEndoNerfFrames(dir, PoseRowCount(ReadNpy(poses), poses));
}

std::vector<FrameFiles> ListGroundTruthFrames(const fs::path& gt_dir, std::size_t frames) {
  const auto count_of = [frames](const fs::path& folder, const std::vector<fs::path>& files) {
    if (files.size() != frames) {
      FailInvalid(folder.string() + ": holds " + std::to_string(files.size()) + " files but the clip has " +
                  std::to_string(frames) + " frames");
    }
  };
  const std::vector<fs::path> images = ListFiles(gt_dir / "images", ImageExtensions());
  count_of(gt_dir / "images", images);
  std::vector<fs::path> depths;
  if (fs::exists(gt_dir / "depth")) {
    depths = ListFiles(gt_dir / "depth", {".npy"});
    count_of(gt_dir / "depth", depths);
  }
  std::vector<FrameFiles> truth(frames);
  for (std::size_t i = 0; i < frames; ++i) {
    truth[i].image = images[i];
    if (!depths.empty()) truth[i].depth = depths[i];
  }
  return truth;
}

std::vector<fs::path> ListClipFiles(const fs::path& dir) {
  const std::vector<FrameFiles> frames = ListClipFrames(dir);
  std::vector<fs::path> files;
  if (FindClipLayout(dir) == ClipLayout::kTransforms) {
    files.push_back(dir / "transforms.json");
  } else {
    files.push_back(dir / "poses_bounds.npy");
    if (fs::exists(dir / "stereo.json")) files.push_back(dir / "stereo.json");
  }
  // Once each: frames of a transforms.json may share a mask or a depth map (one mask for a tool that
  // stays put), which a manifest listing twice is refused for.
  std::set<fs::path> listed;
  const auto add = [&](const FrameFiles& frame) {
    for (const fs::path* file :
         {&frame.image, &frame.depth, &frame.tool_mask, &frame.eval_mask, &frame.right_image})
      if (!file->empty() && listed.insert(file->lexically_normal()).second) files.push_back(*file);
  };
  for (const FrameFiles& frame : frames) add(frame);
  if (fs::is_directory(dir / "gt")) {
    for (const FrameFiles& frame : ListGroundTruthFrames(dir / "gt", frames.size())) add(frame);
  }
  return files;
}

}  // namespace endorecon
