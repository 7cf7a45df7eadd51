// fuzz_seed_maker OUT: writes the starting inputs of every harness into OUT/<harness>/ (replacing
// what was there): valid files made by the project's own writers, and a few near misses. Seeds are
// made, not committed, so they follow the formats as the code changes.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "common/dicom/recording_writer.h"
#include "common/npy.h"
#include "common/sha256.h"
#include "endorecon/v1/files.pb.h"
#include "tests/fuzz/fuzz_input.h"
#include "tests/fuzz/tiny_run.h"
#include "worker/engine/train/checkpoint.h"
#include "worker/engine/train/trainer.h"
#include "worker/prepare/stereo_calibration.h"

namespace {

namespace fs = std::filesystem;
using namespace endorecon;
using nlohmann::json;

std::string ReadAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class Seeds {
 public:
  Seeds(const fs::path& root, const std::string& harness) : dir_(root / harness) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void Add(const std::string& bytes) {
    std::ofstream(dir_ / ("seed-" + std::to_string(count_++)), std::ios::binary) << bytes;
  }
  void Add(const json& value) { Add(value.dump()); }

 private:
  fs::path dir_;
  int count_ = 0;
};

std::string Npy(const std::vector<double>& values, const std::vector<std::size_t>& shape, bool float64) {
  const fs::path path = fuzz::ScratchDir() / "seed.npy";
  if (float64) {
    WriteNpyFloat64(path, values.data(), shape);
  } else {
    const std::vector<float> floats(values.begin(), values.end());
    WriteNpyFloat32(path, floats.data(), shape);
  }
  return ReadAll(path);
}

// A version 2.0 file with a '|u1' array, which WriteNpy never makes.
std::string NpyVersion2() {
  std::string header = "{'descr': '|u1', 'fortran_order': False, 'shape': (2, 3), }";
  header.append(64 - (12 + header.size() + 1) % 64, ' ');
  header += '\n';
  std::string file("\x93NUMPY\x02\x00", 8);
  const auto length = static_cast<std::uint32_t>(header.size());
  for (int i = 0; i < 4; ++i) file += static_cast<char>((length >> (8 * i)) & 0xff);
  return file + header + std::string("\x01\x02\x03\x04\x05\x06", 6);
}

std::vector<double> PoseRows(int rows, double h, double w, double f) {
  std::vector<double> values;
  for (int i = 0; i < rows; ++i) {
    // LLFF's [down, right, back] columns of an identity camera, then (H, W, f), near and far.
    const double row[17] = {0, 1, 0, 0.1 * i, h, -1, 0, 0, 0, w, 0, 0, 1, 0, f, 0.5, 20.0};
    values.insert(values.end(), row, row + 17);
  }
  return values;
}

void NpySeeds(const fs::path& root) {
  Seeds seeds(root, "npy_fuzz");
  seeds.Add(Npy({1, 2, 3, 4, 5, 6}, {2, 3}, false));
  seeds.Add(Npy({0.5, -1e30, 3}, {3}, true));
  seeds.Add(Npy({7}, {}, true));
  seeds.Add(Npy({}, {0, 4}, false));
  seeds.Add(Npy({1, 2, 3, 4, 5, 6, 7, 8}, {2, 2, 2}, false));
  seeds.Add(NpyVersion2());
}

void PosesSeeds(const fs::path& root) {
  // Two rows for the two 4x3 images tests/fuzz/poses_bounds_fuzz.cc puts beside the file.
  Seeds seeds(root, "poses_bounds_fuzz");
  seeds.Add(Npy(PoseRows(2, 3, 4, 5), {2, 17}, true));
  seeds.Add(Npy(PoseRows(2, 6, 8, 10), {2, 17}, false));  // images at half the file's size
  seeds.Add(Npy(PoseRows(1, 3, 4, 5), {1, 17}, true));
  seeds.Add(Npy(PoseRows(2, 3, 4, 5), {34}, true));
}

json Frame(const std::string& file, json extra = json::object()) {
  json frame = {{"file_path", file},
                {"transform_matrix", {{1, 0, 0, 0.1}, {0, 1, 0, 0}, {0, 0, 1, 2}, {0, 0, 0, 1}}}};
  frame.update(extra);
  return frame;
}

void TransformsSeeds(const fs::path& root) {
  // The files tests/fuzz/transforms_fuzz.cc puts beside transforms.json.
  Seeds seeds(root, "transforms_fuzz");
  seeds.Add(json{{"fl_x", 20}, {"frames", {Frame("images/a.png"), Frame("images/b.jpg")}}});
  seeds.Add(json{
      {"camera_angle_x", 0.9},
      {"w", 4},
      {"h", 3},
      {"near", 0.1},
      {"far", 9},
      {"frames",
       {Frame("images/a", {{"time", 0.0}, {"depth_file_path", "depth.npy"}, {"mask_path", "mask"}}),
        Frame("images/b.jpg", {{"time", 2.5}, {"depth_file_path", "depth.npy"}, {"mask_path", "mask"}})}}});
  seeds.Add(json{{"fl_x", 20},
                 {"fl_y", 21},
                 {"cx", 2},
                 {"cy", 1.5},
                 {"k1", 0.1},
                 {"depth_unit_scale_factor", 0.001},
                 {"frames", {Frame("images/a.png", {{"depth_file_path", "depth.png"}, {"fl_x", 19}})}}});
  seeds.Add(json{{"frames", json::array()}});
}

void CameraListSeeds(const fs::path& root) {
  Seeds seeds(root, "camera_list_fuzz");
  seeds.Add(json{{"w", 16}, {"h", 12}, {"fl_x", 20}, {"frames", {Frame("", {{"time", 0.5}})}}});
  seeds.Add(json{{"camera_angle_x", 1.2},
                 {"frames",
                  {Frame("", {{"w", 640}, {"h", 512}, {"time", 0}}),
                   Frame("", {{"w", 640}, {"h", 512}, {"cx", 300}, {"camera_angle_y", 1.0}, {"time", 1}})}}});
}

void ConfigSeeds(const fs::path& root) {
  Seeds seeds(root, "train_config_fuzz");
  seeds.Add(train::ToJson(train::TrainConfig::Preset("cpu")));
  seeds.Add(train::ToJson(train::TrainConfig::Preset("paper")));
  seeds.Add(json::object());
  seeds.Add(json{{"iterations", 200}, {"field", {{"grids", {{"levels", 4}, {"scales", {1.5, 1.5, 1.5}}}}}}});
  seeds.Add(json{{"adam", {{"lr", {{"grid", 0.01}}}}}, {"depth_loss", "huber"}, {"holdout", 0}});
}

void ImageSeeds(const fs::path& root) {
  Seeds seeds(root, "image_decode_fuzz");
  const auto encode = [&](const cv::Mat& image, const std::string& extension) {
    std::vector<std::uint8_t> bytes;
    cv::imencode(extension, image, bytes);
    seeds.Add(std::string(bytes.begin(), bytes.end()));
  };
  cv::Mat mask(3, 4, CV_8UC1, cv::Scalar(0));
  mask.at<std::uint8_t>(1, 2) = 255;
  for (const char* extension : {".png", ".bmp", ".tiff"}) {
    encode(cv::Mat(3, 4, CV_8UC3, cv::Scalar(10, 20, 30)), extension);
    encode(mask, extension);
  }
  encode(cv::Mat(3, 4, CV_8UC3, cv::Scalar(10, 20, 30)), ".jpg");
  encode(cv::Mat(3, 4, CV_8UC4, cv::Scalar(10, 20, 30, 255)), ".png");
  encode(cv::Mat(3, 4, CV_16UC1, cv::Scalar(1200)), ".png");
  encode(cv::Mat(3, 4, CV_16UC3, cv::Scalar(1200, 40000, 7)), ".png");
  encode(cv::Mat(3, 4, CV_32FC1, cv::Scalar(2.5)), ".tiff");
}

// A sealed file in both modes of tests/fuzz/sealed_input.h.
void AddSealed(Seeds& seeds, const std::string& file) {
  seeds.Add(std::string(1, '\0') + file);
  seeds.Add(std::string(1, '\1') + file.substr(0, file.size() - 64));
}

void RunSeeds(const fs::path& root) {
  const scene::Clip clip = fuzz::TinyClip(fuzz::ScratchDir() / "tiny_clip");
  train::Trainer trainer(clip, fuzz::TinyConfig(), {0, 1}, 1);
  trainer.Step();
  const fs::path checkpoint = fuzz::ScratchDir() / "checkpoint.bin";
  train::CheckpointExtras extras;
  extras.train_seconds = 1.5;
  extras.curve = json::array({json{{"seconds", 1.0}, {"psnr", 20.0}}});
  train::WriteCheckpoint(checkpoint, trainer, extras);
  Seeds checkpoints(root, "checkpoint_fuzz");
  AddSealed(checkpoints, ReadAll(checkpoint));

  const fs::path model = fuzz::ScratchDir() / "model.bin";
  train::WriteModel(model, trainer.config(), trainer.box(), 0.5, 20, trainer.field());
  Seeds models(root, "model_fuzz");
  AddSealed(models, ReadAll(model));
}

v1::FileEntry Entry(const std::string& path, const std::string& content) {
  v1::FileEntry entry;
  entry.set_path(path);
  entry.set_size(static_cast<std::int64_t>(content.size()));
  entry.set_sha256(Sha256Hex(content));
  return entry;
}

// Length-prefixed messages (tests/fuzz/message_stream.h).
template <typename Message>
std::string Stream(const std::vector<Message>& messages) {
  std::string bytes;
  for (const auto& message : messages) {
    const std::string serialized = message.SerializeAsString();
    bytes += static_cast<char>(serialized.size() & 0xff);
    bytes += static_cast<char>(serialized.size() >> 8);
    bytes += serialized;
  }
  return bytes;
}

void ManifestSeeds(const fs::path& root) {
  Seeds seeds(root, "manifest_fuzz");
  v1::Manifest manifest;
  *manifest.add_files() = Entry("summary.json", "{}");
  *manifest.add_files() = Entry("eval/frame.png", "a frame");
  *manifest.add_files() = Entry("images/000000.png", std::string(100, 'x'));
  seeds.Add(manifest.SerializeAsString());
  manifest.mutable_files(1)->set_path("../outside");
  seeds.Add(manifest.SerializeAsString());
}

void UploadSeeds(const fs::path& root) {
  Seeds seeds(root, "upload_stream_fuzz");
  const std::string a = "poses and bounds", b = std::string(300, 'b');
  std::vector<v1::UploadRequest> stream(1);
  *stream[0].mutable_manifest()->add_files() = Entry("poses_bounds.npy", a);
  *stream[0].mutable_manifest()->add_files() = Entry("images/000000.png", b);
  const auto chunk = [](const std::string& path, std::int64_t offset, const std::string& data) {
    v1::UploadRequest request;
    request.mutable_chunk()->set_path(path);
    request.mutable_chunk()->set_offset(offset);
    request.mutable_chunk()->set_data(data);
    return request;
  };
  stream.push_back(chunk("poses_bounds.npy", 0, a));
  stream.push_back(chunk("images/000000.png", 0, b.substr(0, 100)));
  stream.push_back(chunk("images/000000.png", 100, b.substr(100)));
  seeds.Add(Stream(stream));
  stream[3] = chunk("images/000000.png", 50, b.substr(50));  // overlaps what was sent
  seeds.Add(Stream(stream));
  stream.resize(3);  // cut short
  seeds.Add(Stream(stream));
}

void DownloadSeeds(const fs::path& root) {
  Seeds seeds(root, "download_stream_fuzz");
  const std::string a = "report", b = std::string(200, 'r');
  std::vector<v1::FileChunk> stream(3);
  *stream[0].mutable_file() = Entry("report.html", a);
  stream[0].set_data(a);
  *stream[1].mutable_file() = Entry("eval/frames/000.png", b);
  stream[1].set_data(b.substr(0, 120));
  stream[2].set_offset(120);
  stream[2].set_data(b.substr(120));
  seeds.Add(Stream(stream));
  stream[2].set_data("not what was promised");
  seeds.Add(Stream(stream));
}

void TokenSeeds(const fs::path& root) {
  const std::string token = "endorecon.0123456789abcdef." + std::string(64, 'a');
  Seeds files(root, "token_file_fuzz");
  files.Add(token + "\n");
  files.Add("  " + token + " \r\n");
  files.Add(token + " " + token);
  Seeds store(root, "token_store_fuzz");
  store.Add(token + "\nradiology");
  store.Add(std::string("endorecon.xyz.123\n-tenant"));
  store.Add("Bearer " + token);
}

void DicomSeeds(const fs::path& root) {
  Seeds seeds(root, "dicom_recording_fuzz");
  dicom::RecordingHeader header;
  header.study = dicom::NewStudyContext("P-1", "Doe^Jane", "", "");
  std::vector<cv::Mat> frames;
  for (int f = 0; f < 2; ++f) frames.emplace_back(6, 8, CV_8UC3, cv::Scalar(40 * f, 90, 200));
  for (const bool jpeg : {false, true}) {
    const fs::path file = fuzz::ScratchDir() / "seed.dcm";
    dicom::WriteEndoscopicFrames(frames, {0.0, 0.04}, jpeg, header, file);
    seeds.Add(ReadAll(file));
  }
}

void PoseFileSeeds(const fs::path& root) {
  // The first byte picks the format (tests/fuzz/pose_file_fuzz.cc): even JSON, odd CSV.
  Seeds seeds(root, "pose_file_fuzz");
  const json identity = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
  const json moved = {{0, -1, 0, 1.5}, {1, 0, 0, 0}, {0, 0, 1, -2}};
  seeds.Add(std::string(1, '\0') + json{{"convention", "opencv"}, {"poses", {identity, moved}}}.dump());
  seeds.Add(std::string(1, '\0') + json{{"convention", "opengl"}, {"poses", {identity}}}.dump());
  seeds.Add(std::string("\1# frame, 3x4\n1,0,0,0,0,1,0,0,0,0,1,0\n\n0,-1,0,1.5,1,0,0,0,0,0,1,-2\n"));
  seeds.Add(std::string("\1") + "1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1\n");
}

void CalibrationSeeds(const fs::path& root) {
  // The first byte picks the form (tests/fuzz/stereo_calibration_fuzz.cc): 0 OpenCV YAML, 1 OpenCV
  // XML, 2 and 3 a ROS camera_info of one eye.
  Seeds seeds(root, "stereo_calibration_fuzz");
  prepare::StereoCalibration calibration;
  calibration.image_size = {640, 512};
  calibration.k1 = calibration.k2 = cv::Matx33d(500, 0, 320, 0, 500, 256, 0, 0, 1);
  calibration.d1 = cv::Mat::zeros(1, 5, CV_64F);
  calibration.d2 = (cv::Mat_<double>(1, 5) << 0.1, -0.05, 0.001, 0, 0.01);
  calibration.r = cv::Matx33d::eye();
  calibration.t = {-5, 0, 0.1};
  for (const char* extension : {".yaml", ".xml"}) {
    const fs::path file = fuzz::ScratchDir() / (std::string("seed") + extension);
    prepare::WriteStereoCalibration(file, calibration, {{"rms_reprojection_error_px", 0.3}});
    seeds.Add(std::string(1, extension == std::string(".yaml") ? '\0' : '\1') + ReadAll(file));
  }
  const std::string ros = R"(image_width: 640
image_height: 512
camera_matrix: {rows: 3, cols: 3, data: [510, 0, 321, 0, 505, 250, 0, 0, 1]}
distortion_model: rational_polynomial
distortion_coefficients: {rows: 1, cols: 8, data: [0.1, -0.2, 0, 0, 0.01, 0, 0, 0]}
rectification_matrix: {rows: 3, cols: 3, data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}
projection_matrix: {rows: 3, cols: 4, data: [500, 0, 320, 0, 0, 500, 256, 0, 0, 0, 1, 0]}
)";
  seeds.Add("\2" + ros);
  seeds.Add("\3" + ros);
}

void QuotaSeeds(const fs::path& root) {
  Seeds seeds(root, "quotas_fuzz");
  seeds.Add(
      json{{"radiology", {{"max_jobs", 20}, {"max_bytes", 500000000000}}}, {"research", {{"max_jobs", 2}}}});
  seeds.Add(json::object());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seed_maker OUT\n");
    return 2;
  }
  const fs::path root = argv[1];
  NpySeeds(root);
  PosesSeeds(root);
  TransformsSeeds(root);
  CameraListSeeds(root);
  ConfigSeeds(root);
  ImageSeeds(root);
  RunSeeds(root);
  ManifestSeeds(root);
  UploadSeeds(root);
  DownloadSeeds(root);
  TokenSeeds(root);
  QuotaSeeds(root);
  DicomSeeds(root);
  PoseFileSeeds(root);
  CalibrationSeeds(root);
  std::printf("fuzz seeds written to %s\n", root.c_str());
  return 0;
}
