#include "worker/engine/train/checkpoint.h"

#include <fstream>
#include <sstream>
#include <string>

#include "common/error.h"

namespace endorecon::train {
namespace {

// The last byte is the format version: 2 added the refined depth priors to the trainer state.
constexpr char kCheckpointMagic[8] = {'E', 'N', 'D', 'O', 'C', 'K', 'P', '2'};
constexpr char kModelMagic[8] = {'E', 'N', 'D', 'O', 'M', 'D', 'L', '1'};

void WriteString(std::ostream& out, const std::string& s) {
  const std::uint64_t size = s.size();
  out.write(reinterpret_cast<const char*>(&size), sizeof(size));
  out.write(s.data(), std::streamsize(s.size()));
}

std::string ReadString(std::istream& in, const std::filesystem::path& path) {
  std::uint64_t size = 0;
  in.read(reinterpret_cast<char*>(&size), sizeof(size));
  if (!in || size > (std::uint64_t(1) << 30)) Fail(ErrorCode::kDataLoss, path.string() + ": corrupt header");
  std::string s(size, '\0');
  in.read(s.data(), std::streamsize(size));
  if (!in) Fail(ErrorCode::kDataLoss, path.string() + ": truncated header");
  return s;
}

template <typename Body>
void WriteAtomically(const std::filesystem::path& path, Body&& body) {
  std::filesystem::create_directories(path.parent_path());
  const std::filesystem::path temp = path.string() + ".tmp";
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) Fail(ErrorCode::kUnavailable, "cannot write " + temp.string());
    body(out);
    out.flush();
    if (!out) Fail(ErrorCode::kUnavailable, "cannot write " + temp.string() + " (disk full?)");
  }
  std::filesystem::rename(temp, path);
}

std::ifstream OpenWithMagic(const std::filesystem::path& path, const char (&magic)[8], const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail(ErrorCode::kNotFound, "cannot read " + path.string());
  char found[8] = {};
  in.read(found, 8);
  if (!in || !std::equal(found, found + 7, magic)) {
    FailInvalid(path.string() + " is not an endorecon " + what + " file");
  }
  if (found[7] != magic[7]) {
    FailInvalid(path.string() + ": an endorecon " + what + " of format " + std::string(1, found[7]) +
                "; this build reads format " + std::string(1, magic[7]));
  }
  return in;
}

TrainConfig ConfigFromString(const std::string& text) {
  TrainConfig config;
  ApplyJson(nlohmann::json::parse(text), config);
  return config;
}

}  // namespace

void WriteCheckpoint(const std::filesystem::path& path, const Trainer& trainer,
                     const CheckpointExtras& extras) {
  WriteAtomically(path, [&](std::ofstream& out) {
    out.write(kCheckpointMagic, 8);
    WriteString(out, ToJson(trainer.config()).dump());
    WriteString(out, nlohmann::json{{"train_seconds", extras.train_seconds}, {"curve", extras.curve}}.dump());
    trainer.Save(out);
  });
}

TrainConfig ReadCheckpointConfig(const std::filesystem::path& path) {
  auto in = OpenWithMagic(path, kCheckpointMagic, "checkpoint");
  return ConfigFromString(ReadString(in, path));
}

CheckpointExtras ReadCheckpointState(const std::filesystem::path& path, Trainer& trainer) {
  auto in = OpenWithMagic(path, kCheckpointMagic, "checkpoint");
  ReadString(in, path);
  const auto extras_json = nlohmann::json::parse(ReadString(in, path));
  trainer.Load(in);
  CheckpointExtras extras;
  extras.train_seconds = extras_json.at("train_seconds").get<double>();
  extras.curve = extras_json.at("curve");
  return extras;
}

void WriteModel(const std::filesystem::path& path, const TrainConfig& config, const scene::SceneBox& box,
                double near, double far, const field::Field& field) {
  WriteAtomically(path, [&](std::ofstream& out) {
    out.write(kModelMagic, 8);
    WriteString(out, ToJson(config).dump());
    const nlohmann::json scene = {{"box_min", {box.min.x(), box.min.y(), box.min.z()}},
                                  {"box_max", {box.max.x(), box.max.y(), box.max.z()}},
                                  {"near", near},
                                  {"far", far}};
    WriteString(out, scene.dump());
    field.Save(out);
  });
}

Model ReadModel(const std::filesystem::path& path) {
  auto in = OpenWithMagic(path, kModelMagic, "model");
  Model model;
  model.config = ConfigFromString(ReadString(in, path));
  const auto scene = nlohmann::json::parse(ReadString(in, path));
  for (int k = 0; k < 3; ++k) {
    model.box.min[k] = scene.at("box_min").at(k).get<double>();
    model.box.max[k] = scene.at("box_max").at(k).get<double>();
  }
  model.near = scene.at("near").get<double>();
  model.far = scene.at("far").get<double>();
  model.field = std::make_unique<field::Field>(model.config.field, 0);
  model.field->Load(in);
  return model;
}

}  // namespace endorecon::train
