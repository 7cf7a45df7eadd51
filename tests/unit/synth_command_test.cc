// `endorecon-worker synth` as a user calls it: --backdrop belongs to --object captures; alone it is
// refused with a message naming both, before anything is written. --noise scales the camera noise and
// cannot be given with --no-noise.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/error.h"
#include "tests/unit/temp_dir.h"
#include "worker/runtime/commands.h"

namespace endorecon::worker {
namespace {

// Parses `args` (after the program name) and runs the synth command; the error's text, or "".
std::string RunSynth(std::vector<std::string> args) {
  CLI::App app;
  const Command run = AddSynthCommand(app);
  args.insert(args.begin(), "endorecon-worker");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  app.parse(int(argv.size()), argv.data());
  try {
    run();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(SynthCommandTest, ABackdropNeedsAnObjectAndWritesNothingWithoutOne) {
  testing::TempDir dir("synth-command");
  const auto out = dir.path() / "clip";
  const std::string message = RunSynth({"synth", out.string(), "--backdrop"});
  EXPECT_NE(message.find("--backdrop needs --object"), std::string::npos) << message;
  EXPECT_FALSE(std::filesystem::exists(out));

  EXPECT_EQ(RunSynth({"synth", out.string(), "--object", "--backdrop", "--frames", "2", "--width", "16",
                      "--height", "16"}),
            "");
  const auto written = nlohmann::json::parse(std::ifstream(out / "synth.json"));
  EXPECT_TRUE(written.at("backdrop").get<bool>());
  EXPECT_TRUE(std::filesystem::exists(out / "transforms.json"));
}

// A recording too small for its checkerboard to be found by calibrate is refused before anything is
// written (64 x 48 was written, and calibrate found the board in 0 of 24 views).
TEST(SynthCommandTest, ARecordingTooSmallForItsCheckerboardIsRefused) {
  testing::TempDir dir("synth-command");
  const auto out = dir.path() / "clip";
  const std::string message =
      RunSynth({"synth", out.string(), "--recording", "--width", "64", "--height", "48"});
  EXPECT_NE(message.find("frames of 64x48 are too small for the recording's checkerboard"), std::string::npos)
      << message;
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(SynthCommandTest, NoiseIsScaledAndRecordedAndRefusedOutOfRange) {
  testing::TempDir dir("synth-command");
  const auto out = dir.path() / "clip";
  const std::vector<std::string> small = {"--frames", "2", "--width", "16", "--height", "12"};
  const auto with = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {"synth", out.string()});
    args.insert(args.end(), small.begin(), small.end());
    return args;
  };
  EXPECT_EQ(RunSynth(with({"--noise", "0.25"})), "");
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(std::ifstream(out / "synth.json")).at("noise").get<double>(), 0.25);
  EXPECT_EQ(RunSynth(with({"--no-noise"})), "");
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(std::ifstream(out / "synth.json")).at("noise").get<double>(), 0);
  EXPECT_THROW(RunSynth(with({"--noise", "0.5", "--no-noise"})), CLI::ExcludesError);
  EXPECT_THROW(RunSynth(with({"--noise", "-1"})), CLI::ValidationError);
}

}  // namespace
}  // namespace endorecon::worker
