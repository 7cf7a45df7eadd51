#include "common/prepare_flags.h"

#include <algorithm>
#include <charconv>
#include <vector>

#include "common/error.h"

namespace endorecon {
namespace {

std::vector<std::string_view> Split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  std::size_t begin = 0;
  while (true) {
    const std::size_t end = text.find(separator, begin);
    parts.push_back(text.substr(begin, end == std::string_view::npos ? std::string_view::npos : end - begin));
    if (end == std::string_view::npos) return parts;
    begin = end + 1;
  }
}

// A whole non-negative decimal number (no sign, no spaces); false otherwise.
bool ParseCount(std::string_view text, int& value) {
  if (text.empty()) return false;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc() && end == text.data() + text.size() && value >= 0;
}

[[noreturn]] void Bad(std::string_view text, const std::string& expected) {
  std::string message = "'";  // appended piece by piece: GCC 12 warns (-Wrestrict) on "'" + std::string
  message.append(text).append("': expected ").append(expected);
  FailInvalid(message);
}

}  // namespace

std::vector<int> FrameRange::Of(int total) const {
  std::vector<int> frames;
  for (int frame = start; frame < (end < 0 ? total : std::min(end, total)); frame += step)
    frames.push_back(frame);
  return frames;
}

std::vector<int> FrameRange::PickedOf(int total, const std::string& prefix, const std::string& whose) const {
  std::vector<int> frames = Of(total);
  if (frames.empty()) {
    FailInvalid(prefix + "--frames " + ToString() + " picks none of " + whose + " " + std::to_string(total) +
                " frames (START:END:STEP counts them from 0, END exclusive)");
  }
  return frames;
}

std::string FrameRange::ToString() const {
  return std::to_string(start) + ":" + (end < 0 ? std::string() : std::to_string(end)) + ":" +
         std::to_string(step);
}

FrameRange ParseFrameRange(std::string_view text) {
  const std::string expected =
      "START:END:STEP (frame numbers from 0, END exclusive, each part optional, STEP > 0)";
  const auto parts = Split(text, ':');
  if (parts.size() > 3) Bad(text, expected);
  // Python's negative numbers count from the end, which the recording's or clip's length (not known
  // where this is parsed) would have to resolve; a number alone is a frame or a start to the reader.
  if (text.find('-') != std::string_view::npos)
    Bad(text, expected + "; numbers from the end (negative, as in Python) are not taken");
  if (parts.size() == 1 && !text.empty()) {
    int frame = 0;
    Bad(text, ParseCount(text, frame)
                  ? expected + ": " + std::string(text) + ": takes frame " + std::string(text) + " on, " +
                        std::string(text) + ":" + std::to_string(frame + 1) + " frame " + std::string(text) +
                        " alone"
                  : expected);
  }
  FrameRange range;
  if (!parts[0].empty() && !ParseCount(parts[0], range.start)) Bad(text, expected);
  if (parts.size() > 1 && !parts[1].empty() && !ParseCount(parts[1], range.end)) Bad(text, expected);
  if (parts.size() > 2 && !parts[2].empty() && (!ParseCount(parts[2], range.step) || range.step == 0))
    Bad(text, expected);
  if (range.end >= 0 && range.end <= range.start) Bad(text, expected + "; END must be above START");
  return range;
}

FrameSize ParseFrameSize(std::string_view text) {
  const std::string expected = "WxH with even, positive width and height (e.g. 640x512)";
  const auto parts = Split(text, 'x');
  FrameSize size;
  if (parts.size() != 2 || !ParseCount(parts[0], size.width) || !ParseCount(parts[1], size.height) ||
      size.width < 2 || size.height < 2 || size.width % 2 != 0 || size.height % 2 != 0) {
    Bad(text, expected);
  }
  // The largest frame a clip may have (the loaders' limit): a larger one would be made, then refused.
  if (double(size.width) * double(size.height) > kMostFramePixels) {
    Bad(text, "at most 16777216 pixels a frame (4096 x 4096), the largest a clip may have");
  }
  return size;
}

PixelRect ParsePixelRect(std::string_view text) {
  const std::string expected = "X,Y,W,H in pixels (x, y >= 0; width and height > 0)";
  const auto parts = Split(text, ',');
  PixelRect rect;
  if (parts.size() != 4 || !ParseCount(parts[0], rect.x) || !ParseCount(parts[1], rect.y) ||
      !ParseCount(parts[2], rect.width) || !ParseCount(parts[3], rect.height) || rect.width == 0 ||
      rect.height == 0) {
    Bad(text, expected);
  }
  return rect;
}

std::vector<std::string> PrepareFlags::Paths() const {
  std::vector<std::string> paths;
  for (const std::string* path : {&left, &right, &side_by_side, &top_bottom}) {
    if (!path->empty()) paths.push_back(*path);
  }
  paths.insert(paths.end(), calibration.begin(), calibration.end());
  for (const std::string* path : {&masks, &poses}) {
    if (!path->empty()) paths.push_back(*path);
  }
  return paths;
}

void CheckEyeSkips(bool two_sources, int skip_left, int skip_right) {
  if (skip_left < 0 || skip_right < 0) {
    FailInvalid("--skip-left and --skip-right count frames: 0 or more, found " +
                std::to_string(std::min(skip_left, skip_right)));
  }
  if ((skip_left > 0 || skip_right > 0) && !two_sources) {
    FailInvalid(
        "--skip-left and --skip-right pair two eyes' recordings (--left with --right); one recording of "
        "both eyes (--side-by-side, --top-bottom) holds each moment in one frame");
  }
}

void CheckPrepareFlags(const PrepareFlags& f) {
  const int forms = (!f.left.empty() || !f.right.empty()) + !f.side_by_side.empty() + !f.top_bottom.empty();
  if (forms != 1) {
    FailInvalid(
        "give the recording as --left VIDEO|DIR with --right VIDEO|DIR, or --side-by-side VIDEO, or "
        "--top-bottom VIDEO (exactly one of these)");
  }
  // One eye alone is a mono recording, which is not prepared: the way to it was said nowhere here
  // (found 2026-12-07).
  if (f.left.empty() != f.right.empty()) {
    FailInvalid(
        "--left and --right go together; a recording of one eye (mono) is not prepared: make it a DICOM "
        "recording (endorecon-worker to-dicom VIDEO -o rec.dcm) and reconstruct or submit rec.dcm");
  }
  if (f.rectified == !f.calibration.empty()) {
    FailInvalid(
        "give either --calibration FILE (an OpenCV stereo calibration, or two ROS camera_info YAMLs) "
        "or --rectified --focal PX --baseline B");
  }
  if (f.calibration.size() > 2) FailInvalid("--calibration takes one or two files");
  if (f.rectified && !(f.focal > 0 && f.baseline > 0)) {
    FailInvalid("--rectified needs --focal PX and --baseline B, both > 0");
  }
  if (!f.poses.empty() && f.estimate_poses) FailInvalid("give --poses FILE or --estimate-poses, not both");
  if (f.mask_tool != "white" && f.mask_tool != "black") {
    FailInvalid("--mask-tool must be white (255 = tool) or black (0 = tool), found '" + f.mask_tool + "'");
  }
  if (f.depth_paths != 0 && f.depth_paths != 3 && f.depth_paths != 8) {
    FailInvalid("--depth-paths must be 3 or 8, found " + std::to_string(f.depth_paths));
  }
  CheckEyeSkips(!f.left.empty(), f.skip_left, f.skip_right);
  if (!f.frames.empty()) ParseFrameRange(f.frames);
  if (!f.size.empty()) ParseFrameSize(f.size);
  for (const std::string& rect : f.exclude) ParsePixelRect(rect);
}

}  // namespace endorecon
