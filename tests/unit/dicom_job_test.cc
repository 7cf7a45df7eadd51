// A clip folder is used as it is (--frames may pick some of its frames): the options that thin or
// scale a recording's frames are refused for it, naming them, where they were once ignored without a
// word.
#include "worker/runtime/dicom_job.h"

#include <gtest/gtest.h>

#include <string>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::worker {
namespace {

TEST(DicomJobTest, RecordingOptionsOnAClipFolderAreRefused) {
  testing::TempDir dir("dicom-job");
  testing::WriteBytes(dir / "poses_bounds.npy", "not DICOM");
  EXPECT_FALSE(PrepareRecording(dir.path(), {}, dir / "clip").has_value()) << "no options: the folder as it is";
  v1::RecordingOptions options;
  options.set_fps(5);
  options.set_size("320x180");
  const std::string message =
      testing::ErrorFrom([&] { PrepareRecording(dir.path(), options, dir / "clip"); });
  EXPECT_NE(message.find("--fps, --size apply to a DICOM recording"), std::string::npos) << message;
  EXPECT_NE(message.find("is a clip folder"), std::string::npos) << message;

  v1::RecordingOptions frames;
  frames.set_frames("2:8:3");
  const auto none = PrepareRecording(dir.path(), frames, dir / "clip");
  EXPECT_FALSE(none.has_value());
  EXPECT_EQ(ClipFolderFrames(none, frames).ToString(), "2:8:3") << "a clip folder's frames, picked";
}

}  // namespace
}  // namespace endorecon::worker
