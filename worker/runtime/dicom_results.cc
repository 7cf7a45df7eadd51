#include "worker/runtime/dicom_results.h"

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "endorecon_version.h"
#include "common/dicom/result_instances.h"
#include "common/dicom/uid.h"
#include "common/error.h"
#include "common/npy.h"
#include "worker/engine/eval/exports.h"

namespace endorecon::worker {
namespace fs = std::filesystem;
namespace {

int CountFrames(const fs::path& folder, const std::string& extension) {
  int count = 0;
  while (fs::exists(folder / eval::FrameFileName(count, extension))) ++count;
  if (count == 0)
    FailInvalid(folder.string() + ": no result frames (" + eval::FrameFileName(0, extension) + ")");
  return count;
}

std::vector<float> ReadFloats(const fs::path& path, int width, int height) {
  if (!fs::exists(path)) FailInvalid(path.string() + ": missing");
  const NpyArray array = ReadNpy(path);
  if (array.shape.size() != 2 || array.shape[0] != static_cast<std::size_t>(height) ||
      array.shape[1] != static_cast<std::size_t>(width)) {
    FailInvalid(path.string() + ": expected shape (" + std::to_string(height) + ", " + std::to_string(width) +
                ")");
  }
  return std::vector<float>(array.data.begin(), array.data.end());
}

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) FailInvalid(path.string() + ": missing");
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

std::vector<fs::path> WriteDicomResults(const fs::path& results_dir, const DicomResultSettings& settings) {
  const int count = CountFrames(results_dir / "rgb", ".png");
  std::vector<cv::Mat> rgb;
  for (int f = 0; f < count; ++f) {
    const fs::path path = results_dir / "rgb" / eval::FrameFileName(f, ".png");
    rgb.push_back(cv::imread(path.string(), cv::IMREAD_COLOR));
    if (rgb.back().empty()) FailInvalid(path.string() + ": not a readable image");
  }
  const int width = rgb[0].cols, height = rgb[0].rows;
  std::vector<std::vector<float>> depth, uncertainty, model_map;
  for (int f = 0; f < count; ++f) {
    depth.push_back(ReadFloats(results_dir / "depth" / eval::FrameFileName(f, ".npy"), width, height));
  }
  const bool uncertain = fs::exists(results_dir / "uncertainty" / eval::FrameFileName(0, ".npy"));
  for (int f = 0; uncertain && f < count; ++f) {
    uncertainty.push_back(
        ReadFloats(results_dir / "uncertainty" / eval::FrameFileName(f, ".npy"), width, height));
  }
  // The model map, written beside the uncertainty (results from before it have none).
  const bool mapped =
      uncertain && fs::exists(results_dir / "uncertainty" / eval::FrameFileName(0, "_model.npy"));
  for (int f = 0; mapped && f < count; ++f) {
    model_map.push_back(
        ReadFloats(results_dir / "uncertainty" / eval::FrameFileName(f, "_model.npy"), width, height));
  }

  dicom::SeriesHeader header;
  header.study = settings.study;
  header.uid_root = settings.uid_root;
  header.frame_times_s =
      static_cast<int>(settings.times_s.size()) == count ? settings.times_s : std::vector<double>{};
  header.frame_of_reference_uid = dicom::NewUid(settings.uid_root);
  const std::string method =
      "endorecon " ENDORECON_VERSION ", Endo-NeRF++ (uncertainty-aware hash-grid NeRF) reconstruction of " +
      (settings.source_summary.empty() ? std::string("a clip") : settings.source_summary);
  const fs::path out = results_dir / "dicom";
  fs::remove_all(out);
  std::vector<fs::path> written;
  const auto next = [&](int number, const std::string& description, const std::string& what) {
    header.series_number = number;
    header.series_description = description;
    header.derivation_description = what + "; " + method;
  };
  next(901, "endorecon rendered frames", "Frames rendered from the reconstruction at every input time");
  WriteColorFrames(written.emplace_back(out / "rendered.dcm"), header, rgb);
  next(902, "endorecon depth", "Rendered z-depth along the optical axis at every input time");
  WriteScalarFrames(written.emplace_back(out / "depth.dcm"), header, depth, width, height,
                    {"MM",
                     "Depth: z-depth along the optical axis in the clip's length unit, nominally millimetres "
                     "(a mono recording has no absolute scale); 0 = no depth."});
  if (uncertain) {
    next(903, "endorecon uncertainty", "Total (aleatoric + epistemic) uncertainty at every input time");
    WriteScalarFrames(written.emplace_back(out / "uncertainty.dcm"), header, uncertainty, width, height,
                      {"US",
                       "Total uncertainty: the ray score of the aleatoric plus epistemic variances "
                       "(docs/formats.md, Uncertainty values); unitless, larger is less certain."});
  }
  if (mapped) {
    next(905, "endorecon model map", "Where the reconstruction is likely wrong at every input time");
    WriteScalarFrames(
        written.emplace_back(out / "model_map.dcm"), header, model_map, width, height,
        {"US",
         "Model map: where the reconstruction itself is likely wrong, apart from the camera's "
         "noise (docs/formats.md, results layout); unitless, relative within a frame, larger is "
         "more likely wrong."});
  }
  next(904, "endorecon tissue surface",
       "Tissue surface of the canonical frame (t = 0) triangulated on the pixel grid");
  WriteStlMesh(written.emplace_back(out / "mesh.dcm"), header, ReadBytes(results_dir / "mesh.stl"), "mm");
  return written;
}

}  // namespace endorecon::worker
