#include "worker/engine/scene/camera_list.h"

#include "common/error.h"
#include "worker/engine/scene/camera_json.h"
#include "worker/engine/scene/json_file.h"

namespace endorecon::scene {

std::vector<CameraAtTime> ReadCameraList(const std::filesystem::path& path) {
  const nlohmann::json top = ReadJsonFile(path);
  const std::string file = path.string();
  if (!top.is_object() || !top.contains("frames") || !top["frames"].is_array() || top["frames"].empty()) {
    FailInvalid(file + ": expected an object with a non-empty \"frames\" list");
  }
  std::vector<CameraAtTime> cameras;
  for (std::size_t i = 0; i < top["frames"].size(); ++i) {
    const nlohmann::json& frame = top["frames"][i];
    const std::string where = file + " frame " + std::to_string(i);
    const auto w = FrameOrTopNumber(frame, top, "w", where, file);
    const auto h = FrameOrTopNumber(frame, top, "h", where, file);
    if (!w || !h || *w < 1 || *h < 1) FailInvalid(where + ": needs the image size \"w\" and \"h\" (>= 1)");
    CameraAtTime view;
    view.camera = CameraFromJson(frame, top, int(*w), int(*h), where, file);
    const double time = OptionalNumber(frame, "time", where).value_or(0.0);
    if (time < 0 || time > 1) FailInvalid(where + ": \"time\" must lie in [0, 1], found " + std::to_string(time));
    view.time = float(time);
    cameras.push_back(view);
  }
  return cameras;
}

}  // namespace endorecon::scene
