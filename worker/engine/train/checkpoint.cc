#include "worker/engine/train/checkpoint.h"

#include <fstream>
#include <sstream>
#include <string>

#include "common/error.h"
#include "common/sealed_file.h"
#include "worker/engine/field/field_state.h"

namespace endorecon::train {
namespace {

// The last byte is the format version: 2 added the refined depth priors to the trainer state, 3 the
// checksum (common/sealed_file.h) and named field blocks.
constexpr char kCheckpointMagic[8] = {'E', 'N', 'D', 'O', 'C', 'K', 'P', '3'};
constexpr char kModelMagic[8] = {'E', 'N', 'D', 'O', 'M', 'D', 'L', '2'};

void WriteString(std::ostream& out, const std::string& s) {
  const std::uint64_t size = s.size();
  out.write(reinterpret_cast<const char*>(&size), sizeof(size));
  out.write(s.data(), std::streamsize(s.size()));
}

std::string ReadString(std::istream& in, const std::filesystem::path& path) {
  std::uint64_t size = 0;
  in.read(reinterpret_cast<char*>(&size), sizeof(size));
  if (!in || size > (std::uint64_t(1) << 30)) Fail(ErrorCode::kDataLoss, path.string() + ": corrupt header");
  // A length past the end of the file is refused before it is allocated (tests/fuzz/model_fuzz.cc:
  // a crafted file with a valid checksum made every read allocate up to a gigabyte).
  const auto here = in.tellg();
  in.seekg(0, std::ios::end);
  const auto end = in.tellg();
  in.seekg(here);
  if (here < 0 || end < here || size > std::uint64_t(end - here))
    Fail(ErrorCode::kDataLoss, path.string() + ": truncated header");
  std::string s(size, '\0');
  in.read(s.data(), std::streamsize(size));
  if (!in) Fail(ErrorCode::kDataLoss, path.string() + ": truncated header");
  return s;
}

TrainConfig ConfigFromString(const std::string& text, const std::filesystem::path& path) {
  TrainConfig config;
  try {
    const nlohmann::json json = nlohmann::json::parse(text);
    // A checkpoint of before 2026-12-06 laid its field and its scene box out without the stillness
    // test and the depth bounds' fit: resumed, it keeps them off, or its parameters would be read
    // into a field of another layout or a box of other bounds.
    if (json.is_object() && !json.contains("still_threshold_px")) config.still_threshold_px = 0;
    if (json.is_object() && !json.contains("fit_depth_bounds")) config.fit_depth_bounds = false;
    ApplyJson(json, config);
  } catch (const nlohmann::json::exception& e) {
    Fail(ErrorCode::kDataLoss, path.string() + ": its configuration does not parse: " + e.what());
  } catch (const Error& e) {
    Fail(e.code(), path.string() + ": its configuration: " + e.what());
  }
  return config;
}

// Runs `read`, naming the file in any error it throws (the field's and the trainer's own messages say
// only what was wrong).
template <typename Read>
auto NamingTheFile(const std::filesystem::path& path, Read&& read) {
  try {
    return read();
  } catch (const Error& e) {
    Fail(e.code(), path.string() + ": " + e.what());
  } catch (const nlohmann::json::exception& e) {
    Fail(ErrorCode::kDataLoss, path.string() + ": " + e.what());
  }
}

}  // namespace

nlohmann::json DeformationStartOf(const Trainer& trainer, const CheckpointExtras& extras) {
  return extras.deformation_start.is_null() ? FlowStartJson(trainer.deformation_start())
                                            : extras.deformation_start;
}

void WriteCheckpoint(const std::filesystem::path& path, const Trainer& trainer,
                     const CheckpointExtras& extras) {
  WriteSealedFile(
      path, kCheckpointMagic,
      [&](std::ostream& out) {
        WriteString(out, ToJson(trainer.config()).dump());
        WriteString(out, nlohmann::json{{"train_seconds", extras.train_seconds},
                                        {"curve", extras.curve},
                                        {"deformation_start", DeformationStartOf(trainer, extras)},
                                        {"frames", extras.frames.ToString()}}
                             .dump());
        trainer.Save(out);
      },
      "checkpoint");
}

TrainConfig ReadCheckpointConfig(const std::filesystem::path& path) {
  auto in = OpenSealedFile(path, kCheckpointMagic, "checkpoint");
  return ConfigFromString(ReadString(in, path), path);
}

CheckpointExtras ReadCheckpointState(const std::filesystem::path& path, Trainer& trainer,
                                     const FrameRange& frames) {
  auto in = OpenSealedFile(path, kCheckpointMagic, "checkpoint");
  return NamingTheFile(path, [&] {
    ReadString(in, path);
    const auto extras_json = nlohmann::json::parse(ReadString(in, path));
    CheckpointExtras extras;
    const auto saved = extras_json.find("frames");
    if (saved != extras_json.end() && saved->is_string())
      extras.frames = ParseFrameRange(saved->get<std::string>());
    if (extras.frames.ToString() != frames.ToString()) {
      const auto which = [](const FrameRange& range) {
        return range.SelectsAll() ? std::string("every frame of its clip")
                                  : "the clip's frames " + range.ToString();
      };
      FailInvalid("a checkpoint of " + which(extras.frames) + " (--frames), and this run takes " +
                  which(frames) + ": resume it " +
                  (extras.frames.SelectsAll() ? std::string("without --frames")
                                              : "with --frames " + extras.frames.ToString()));
    }
    trainer.Load(in);
    extras.train_seconds = extras_json.at("train_seconds").get<double>();
    extras.curve = extras_json.at("curve");
    extras.deformation_start = extras_json.value("deformation_start", nlohmann::json());
    return extras;
  });
}

int ReadCheckpointIteration(const std::filesystem::path& path) {
  auto in = OpenSealedFile(path, kCheckpointMagic, "checkpoint");
  return NamingTheFile(path, [&] {
    ReadString(in, path);
    ReadString(in, path);
    return Trainer::ReadIteration(in);
  });
}

void WriteModel(const std::filesystem::path& path, const TrainConfig& config, const scene::SceneBox& box,
                double near, double far, const field::Field& field) {
  WriteSealedFile(
      path, kModelMagic,
      [&](std::ostream& out) {
        WriteString(out, ToJson(config).dump());
        const nlohmann::json scene = {{"box_min", {box.min.x(), box.min.y(), box.min.z()}},
                                      {"box_max", {box.max.x(), box.max.y(), box.max.z()}},
                                      {"near", near},
                                      {"far", far}};
        WriteString(out, scene.dump());
        field::SaveFieldState(field, out);
      },
      "model");
}

Model ReadModel(const std::filesystem::path& path) {
  auto in = OpenSealedFile(path, kModelMagic, "model");
  Model model;
  model.config = ConfigFromString(ReadString(in, path), path);
  NamingTheFile(path, [&] {
    const auto scene = nlohmann::json::parse(ReadString(in, path));
    for (int k = 0; k < 3; ++k) {
      model.box.min[k] = scene.at("box_min").at(k).get<double>();
      model.box.max[k] = scene.at("box_max").at(k).get<double>();
    }
    model.near = scene.at("near").get<double>();
    model.far = scene.at("far").get<double>();
    model.field = std::make_unique<field::Field>(model.config.field, 0);
    field::LoadFieldState(*model.field, in);
    return 0;
  });
  return model;
}

}  // namespace endorecon::train
