#include "worker/engine/scene/camera_list.h"

#include <fmt/format.h>

#include <optional>
#include <string>

#include "common/error.h"
#include "common/json_file.h"
#include "worker/engine/scene/camera_json.h"
#include "worker/engine/scene/clip_checks.h"
#include "worker/engine/scene/load_options.h"

namespace endorecon::scene {

std::vector<CameraAtTime> ReadCameraList(const std::filesystem::path& path) {
  const nlohmann::json top = ReadJsonFile(path);
  const std::string file = path.string();
  if (!top.is_object() || !top.contains("frames") || !top["frames"].is_array() || top["frames"].empty()) {
    FailInvalid(file + ": expected an object with a non-empty \"frames\" list");
  }
  std::vector<CameraAtTime> cameras;
  // Every view has a time (its own, or the list's top-level "time") or none does (a static scene's
  // views, all at t = 0): a list timing only some put the rest at t = 0 without a word.
  std::optional<std::size_t> timed, untimed;
  for (std::size_t i = 0; i < top["frames"].size(); ++i) {
    const nlohmann::json& frame = top["frames"][i];
    const std::string where = file + " frame " + std::to_string(i);
    const auto w = FrameOrTopNumber(frame, top, "w", where, file);
    const auto h = FrameOrTopNumber(frame, top, "h", where, file);
    if (!w || !h || *w < 1 || *h < 1) FailInvalid(where + ": needs the image size \"w\" and \"h\" (>= 1)");
    // The clips' limit holds for views too (a larger view would not fit in memory to render).
    const std::size_t limit = LoadOptions{}.max_pixels_per_frame;
    if (*w > double(limit) || *h > double(limit)) {
      Fail(ErrorCode::kInvalidArgument,
           where + ": \"w\" x \"h\" exceed the limit of " + std::to_string(limit) + " pixels per frame");
    }
    CheckFrameLimit(int(*w), int(*h), limit, where + ": \"w\" x \"h\"");
    CameraAtTime view;
    view.camera = CameraFromJson(frame, top, int(*w), int(*h), where, file);
    const std::optional<double> given = FrameOrTopNumber(frame, top, "time", where, file);
    (given ? timed : untimed) = (given ? timed : untimed).value_or(i);
    if (timed && untimed) {
      FailInvalid(file + ": frame " + std::to_string(*timed) + " has a \"time\" and frame " +
                  std::to_string(*untimed) +
                  " has none: give every view its time (or one top-level "
                  "\"time\" for all), or none for a static scene");
    }
    const double time = given.value_or(0.0);
    // {:g}: std::to_string printed 1e300 as its 301 digits (found 2026-12-07).
    if (time < 0 || time > 1)
      FailInvalid(fmt::format("{}: \"time\" must lie in [0, 1], found {:g}", where, time));
    view.time = float(time);
    cameras.push_back(view);
  }
  return cameras;
}

}  // namespace endorecon::scene
