// Which files make a clip, by the rules of its layout (docs/formats.md, "Clip layouts"), found
// without decoding any of them: shared by the worker's loaders (worker/engine/scene/clip_loader.h),
// which then read the pixels and the cameras, and the CLI, which checks a clip before its upload so
// that a missing mask or a path out of the clip is refused before the upload, not after it.
#pragma once

#include <cstddef>
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace endorecon {

struct NpyArray;

// The image file extensions the loaders read (lower case): .png .jpg .jpeg .bmp .tif .tiff.
const std::vector<std::string>& ImageExtensions();

// Whether the extension of `path` (any case) is one of `extensions` (lower case, with the dot).
bool HasExtension(const std::filesystem::path& path, const std::vector<std::string>& extensions);

// Whether file name `a` comes before `b` with the digit runs compared as numbers ("2.png" before
// "10.png"; zero-padded names keep their string order).
bool NaturalLess(std::string_view a, std::string_view b);

// Regular files in `dir`, in NaturalLess order of their names, whose extension (any case) is one of `extensions`; hidden files
// are skipped. Throws FailInvalid when `dir` is not a folder, or names an entry with one of the
// extensions that is no regular file (a broken link, a folder, a pipe).
std::vector<std::filesystem::path> ListFiles(const std::filesystem::path& dir,
                                             const std::vector<std::string>& extensions);

// The files of one frame; an empty path means the clip has no such file (for every frame).
struct FrameFiles {
  std::filesystem::path image;
  std::filesystem::path depth, tool_mask, eval_mask, right_image;
};

enum class ClipLayout { kEndoNerf, kTransforms };

// transforms.json present: kTransforms; else poses_bounds.npy present: kEndoNerf; else nothing.
std::optional<ClipLayout> FindClipLayout(const std::filesystem::path& dir);

// EndoNeRF layout. The rows of poses_bounds.npy (`path`), which must be an N x 17 array of finite
// values with N > 0; throws FailInvalid naming the file and the shape found, or the row and column
// of a NaN or infinity.
constexpr std::size_t kPoseColumns = 17;
std::size_t PoseRowCount(const NpyArray& poses, const std::filesystem::path& path);

// EndoNeRF layout: images/ (required) and the optional depth/, masks/, gt_masks/ and images_right/,
// each holding exactly `rows` files, paired by their sorted order. Throws FailInvalid naming the
// folder, its count and the first file that pairs with no image; files paired with images of other
// names are warned of.
std::vector<FrameFiles> ListEndoNerfFrames(const std::filesystem::path& dir, std::size_t rows);

// transforms.json layout: the files each of top["frames"] names (file_path, depth_file_path,
// mask_path), resolved inside `dir` (an extension may be left out). Throws FailInvalid naming the
// frame for no frames, a path that leaves the clip's folder, or a file that does not exist.
std::vector<FrameFiles> ListTransformsFrames(const std::filesystem::path& dir, const nlohmann::json& top);

// The frames' files of the clip in `dir`, whichever its layout (reads poses_bounds.npy or
// transforms.json for them). Throws FailInvalid when `dir` is no clip, or as the functions above.
std::vector<FrameFiles> ListClipFrames(const std::filesystem::path& dir);

// A clip's ground truth, its gt/ folder `gt_dir` (either layout): gt/images/ (required) and gt/depth/
// (.npy, optional), `frames` files each, paired by their sorted order (FrameFiles' image and depth).
// Throws FailInvalid naming the folder whose count differs.
std::vector<FrameFiles> ListGroundTruthFrames(const std::filesystem::path& gt_dir, std::size_t frames);

// Every file the loaders read of the clip in `dir`, once each: its layout's file, stereo.json (EndoNeRF
// layout, when present), each frame's files and gt/'s, as `dir` / relative path. What the CLI uploads of a
// clip folder: a file no loader reads (notes, a video, a spreadsheet beside the frames) stays on the
// user's machine. Throws as ListClipFrames and ListGroundTruthFrames.
std::vector<std::filesystem::path> ListClipFiles(const std::filesystem::path& dir);

}  // namespace endorecon
