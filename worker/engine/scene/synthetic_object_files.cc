// WriteSyntheticObject (synthetic_object.h): the views RenderSyntheticObject makes, as PNG files and
// transforms.json. Apart from the rendering so that a capture made in memory links no image codec.
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "worker/engine/scene/synthetic_files.h"
#include "worker/engine/scene/synthetic_object.h"

namespace endorecon::scene {

void WriteSyntheticObject(const ObjectSynthOptions& options, const std::filesystem::path& dir) {
  const SyntheticObjectViews views = RenderSyntheticObject(options);
  ClearSyntheticFolder(dir);
  std::filesystem::create_directories(dir / "images");
  nlohmann::json transforms = SyntheticObjectTransforms(views);
  for (int view = 0; view < options.views; ++view) {
    const int type = views.channels == 3 ? CV_8UC3 : CV_8UC4;
    // OpenCV writes BGR(A): the rendered RGB(A) bytes converted, not copied.
    const cv::Mat rendered(views.height, views.width, type,
                           const_cast<std::uint8_t*>(views.images[view].data()));
    cv::Mat image;
    cv::cvtColor(rendered, image, views.channels == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_RGBA2BGRA);
    const std::string name = "r_" + FrameName(view);
    WritePng(dir / "images" / (name + ".png"), image);
    transforms["frames"][view]["file_path"] = "./images/" + name;
  }
  WriteText(dir / "transforms.json", transforms.dump(2));
  const nlohmann::json written = {{"object", true},         {"views", options.views},
                                  {"width", options.width}, {"height", options.height},
                                  {"seed", options.seed},   {"backdrop", options.backdrop}};
  WriteText(dir / "synth.json", written.dump(2) + "\n");
}

}  // namespace endorecon::scene
