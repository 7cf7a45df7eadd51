// WriteSyntheticObject (synthetic_object.h): the views RenderSyntheticObject makes, as PNG files and
// transforms.json. Apart from the rendering so that a capture made in memory links no image codec.
#include <nlohmann/json.hpp>
#include <string>

#include "worker/engine/scene/synthetic_files.h"
#include "worker/engine/scene/synthetic_object.h"

namespace endorecon::scene {

void WriteSyntheticObject(const ObjectSynthOptions& options, const std::filesystem::path& dir) {
  const SyntheticObjectViews views = RenderSyntheticObject(options);
  ClearSyntheticFolder(dir);
  std::filesystem::create_directories(dir / "images");
  nlohmann::json transforms = SyntheticObjectTransforms(views);
  for (int view = 0; view < options.views; ++view) {
    const std::string name = "r_" + FrameName(view);
    WriteRgbPng(dir / "images" / (name + ".png"), views.images[view].data(), views.width, views.height,
                views.channels);
    transforms["frames"][view]["file_path"] = "./images/" + name;
  }
  WriteText(dir / "transforms.json", transforms.dump(2));
  const nlohmann::json written = {{"object", true},         {"views", options.views},
                                  {"width", options.width}, {"height", options.height},
                                  {"seed", options.seed},   {"backdrop", options.backdrop}};
  WriteText(dir / "synth.json", written.dump(2) + "\n");
}

}  // namespace endorecon::scene
