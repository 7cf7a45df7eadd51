// Checkpoints and models that are not what they claim: each a clear error naming the file, never a
// crash or a silently wrong model.
#include "worker/engine/train/checkpoint.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include "common/error.h"
#include "common/sha256.h"
#include "tests/unit/small_clip_fixture.h"

namespace endorecon::train {
namespace {

namespace fs = std::filesystem;

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

class CheckpointTest : public testing::SmallClipTest {
 protected:
  void SetUp() override {
    config_ = SmallConfig();
    trainer_ = std::make_unique<Trainer>(*clip_, config_, AllFrames(), 3);
    for (int i = 0; i < 3; ++i) trainer_->Step();
    path_ = dir_->path() /
            (std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + ".bin");
    WriteCheckpoint(path_, *trainer_, {});
    bytes_ = ReadBytes(path_);
  }

  // The error ReadCheckpointState throws for the file now at path_.
  Error Read() {
    Trainer fresh(*clip_, config_, AllFrames(), 3);
    try {
      ReadCheckpointState(path_, fresh);
    } catch (const Error& e) {
      return e;
    }
    ADD_FAILURE() << "read a broken checkpoint";
    return Error(ErrorCode::kInternal, "");
  }

  void ExpectNamed(const Error& e, ErrorCode code, const std::string& words) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_NE(std::string(e.what()).find(path_.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }

  TrainConfig config_;
  std::unique_ptr<Trainer> trainer_;
  fs::path path_;
  std::string bytes_;
};

TEST_F(CheckpointTest, AnIntactCheckpointResumesAtItsIteration) {
  Trainer fresh(*clip_, config_, AllFrames(), 3);
  const CheckpointExtras extras = ReadCheckpointState(path_, fresh);
  EXPECT_EQ(fresh.iteration(), 3);
  // How the first run's deformation started travels with it (the resumed trainer fits nothing).
  EXPECT_EQ(extras.deformation_start.value("from", ""), "optical flow") << extras.deformation_start.dump();
  EXPECT_EQ(ToJson(ReadCheckpointConfig(path_)), ToJson(config_));
}

TEST_F(CheckpointTest, ItsIterationIsReadWithoutATrainer) {
  EXPECT_EQ(ReadCheckpointIteration(path_), 3);
  WriteBytes(path_, bytes_.substr(0, bytes_.size() / 2));
  EXPECT_THROW(ReadCheckpointIteration(path_), Error);
}

TEST_F(CheckpointTest, ATruncatedCheckpointIsDataLoss) {
  for (std::size_t keep : {std::size_t{4}, std::size_t{60}, bytes_.size() / 2, bytes_.size() - 1}) {
    WriteBytes(path_, bytes_.substr(0, keep));
    const Error e = Read();
    EXPECT_NE(std::string(e.what()).find(path_.string()), std::string::npos) << keep << ": " << e.what();
    EXPECT_TRUE(e.code() == ErrorCode::kDataLoss || (keep < 8 && e.code() == ErrorCode::kInvalidArgument))
        << keep << ": " << e.what();
  }
}

TEST_F(CheckpointTest, AnotherFileIsNoCheckpoint) {
  WriteBytes(path_, "PNGXXXXX" + bytes_.substr(8));
  ExpectNamed(Read(), ErrorCode::kInvalidArgument, "is not an endorecon checkpoint file");
}

TEST_F(CheckpointTest, AnotherFormatVersionIsNamed) {
  std::string old = bytes_;
  old[7] = '2';
  WriteBytes(path_, old);
  ExpectNamed(Read(), ErrorCode::kInvalidArgument, "format 2; this build reads format 3");
}

TEST_F(CheckpointTest, EveryFlippedByteIsFound) {
  for (std::size_t at : {std::size_t{8}, std::size_t{40}, bytes_.size() / 3, bytes_.size() / 2,
                         bytes_.size() - 70, bytes_.size() - 1}) {
    std::string flipped = bytes_;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x10);
    WriteBytes(path_, flipped);
    ExpectNamed(Read(), ErrorCode::kDataLoss, "corrupt");
  }
}

// A checkpoint says which of its clip folder's frames it trained on (--frames); one of other frames is
// refused before its state is read: of as many frames it resumed on them without a word (found
// 2026-12-06).
TEST_F(CheckpointTest, ACheckpointOfOtherFramesIsRefusedNamingThem) {
  CheckpointExtras extras;
  extras.frames = ParseFrameRange("1:9:3");
  WriteCheckpoint(path_, *trainer_, extras);
  Trainer fresh(*clip_, config_, AllFrames(), 3);
  EXPECT_EQ(ReadCheckpointState(path_, fresh, ParseFrameRange("1:9:3")).frames.ToString(), "1:9:3");
  try {
    Trainer other(*clip_, config_, AllFrames(), 3);
    ReadCheckpointState(path_, other, ParseFrameRange("0:9:3"));
    FAIL() << "resumed a checkpoint of other frames";
  } catch (const Error& e) {
    ExpectNamed(
        e, ErrorCode::kInvalidArgument,
        "a checkpoint of the clip's frames 1:9:3 (--frames), and this run takes the clip's frames 0:9:3: "
        "resume it with --frames 1:9:3");
  }
  WriteCheckpoint(path_, *trainer_, {});  // every frame: resumed by a run of every frame only
  EXPECT_NO_THROW(ReadCheckpointState(path_, fresh));
  ExpectNamed(
      [&] {
        try {
          ReadCheckpointState(path_, fresh, ParseFrameRange("::2"));
        } catch (const Error& e) {
          return e;
        }
        return Error(ErrorCode::kInternal, "");
      }(),
      ErrorCode::kInvalidArgument,
      "a checkpoint of every frame of its clip (--frames), and this run takes the clip's frames 0::2: resume "
      "it "
      "without --frames");
}

TEST_F(CheckpointTest, AFieldOfAnotherShapeIsNamed) {
  TrainConfig other = config_;
  other.field.heads.color_hidden = {8};
  Trainer small(*clip_, other, AllFrames(), 3);
  try {
    ReadCheckpointState(path_, small);
    FAIL() << "loaded a field of another shape";
  } catch (const Error& e) {
    ExpectNamed(e, ErrorCode::kDataLoss, "'color'");
  }
}

// Found by tests/fuzz/checkpoint_fuzz.cc: a sealed checkpoint whose configuration has a key this build
// does not know said "config: unknown key" without naming the file.
TEST_F(CheckpointTest, AConfigurationThisBuildCannotUseIsNamed) {
  std::string body = bytes_.substr(0, bytes_.size() - 64);
  const auto at = body.find("\"deformation\"");  // the field's, not deformation_start
  ASSERT_NE(at, std::string::npos);
  body.replace(at + 1, 11, "dJformation");  // same length: the body stays well formed
  WriteBytes(path_, body + Sha256Hex(body));
  try {
    ReadCheckpointConfig(path_);
    FAIL() << "read a configuration with an unknown key";
  } catch (const Error& e) {
    ExpectNamed(e, ErrorCode::kInvalidArgument, "unknown key /field/dJformation");
  }
}

// A checkpoint of before 2026-12-06 (its configuration without the two keys) resumes with the
// stillness test and the depth bounds' fit off: its field and box were laid out without them.
TEST_F(CheckpointTest, ACheckpointOfBeforeTheStillnessTestAndTheBoundsFitKeepsThemOff) {
  EXPECT_EQ(ReadCheckpointConfig(path_).still_threshold_px, config_.still_threshold_px);
  EXPECT_TRUE(ReadCheckpointConfig(path_).fit_depth_bounds);
  std::string body = bytes_.substr(0, bytes_.size() - 64);
  for (const std::string key : {"\"still_threshold_px\":0.25,", "\"fit_depth_bounds\":true,"}) {
    const auto at = body.find(key);
    ASSERT_NE(at, std::string::npos) << key;
    body.replace(at, key.size(), std::string(key.size(), ' '));  // the same length: framing kept
  }
  WriteBytes(path_, body + Sha256Hex(body));
  const TrainConfig old = ReadCheckpointConfig(path_);
  EXPECT_EQ(old.still_threshold_px, 0);
  EXPECT_FALSE(old.fit_depth_bounds);
}

TEST_F(CheckpointTest, AModelWithAFlippedByteIsFound) {
  const fs::path model = dir_->path() / "model.bin";
  WriteModel(model, config_, trainer_->box(), clip_->near, clip_->far, trainer_->field());
  EXPECT_NO_THROW(ReadModel(model));
  std::string bytes = ReadBytes(model);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 1);
  WriteBytes(model, bytes);
  try {
    ReadModel(model);
    FAIL() << "read a corrupt model";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kDataLoss);
    EXPECT_NE(std::string(e.what()).find(model.string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace endorecon::train
