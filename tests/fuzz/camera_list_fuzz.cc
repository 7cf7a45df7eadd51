// Camera lists for `endorecon-worker render --cameras` (scene::ReadCameraList, through the file).
// An accepted list has at least one camera, each of a positive size at a time in [0, 1].
#include "tests/fuzz/fuzz_input.h"
#include "worker/engine/scene/camera_list.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  const auto path = fuzz::WriteInput("cameras.json", fuzz::Bytes(data, size));
  std::vector<scene::CameraAtTime> cameras;
  if (!fuzz::Accepts([&] { cameras = scene::ReadCameraList(path); }, {ErrorCode::kInvalidArgument},
                     path.string())) {
    return 0;
  }
  if (cameras.empty()) fuzz::Broken("accepted an empty list");
  for (const auto& view : cameras) {
    if (view.camera.width < 1 || view.camera.height < 1 || !(view.time >= 0 && view.time <= 1))
      fuzz::Broken("accepted a camera without a size or a time outside [0, 1]");
  }
  return 0;
}
