// The server's check of a submitted DICOM recording against its job's options, from the stored
// blobs (server/recording_check.h).
#include "server/recording_check.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/dicom/recording_writer.h"
#include "common/dicom/study_context.h"
#include "common/error.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

// Under a relative data folder (the default, `endorecon-data`), as under an absolute one: the links
// to the blobs pointed nowhere from the temporary folder and no recording was checked (found
// 2026-12-07, a server started with --data-dir data).
TEST(RecordingCheckTest, AWindowPastTheEndIsRefusedUnderARelativeDataFolder) {
  testing::TempDir dir("recording-check");
  dicom::RecordingHeader header;
  header.study = dicom::NewStudyContext("P-1", "Doe^Jane", "", "");
  const std::vector<cv::Mat> frames(3, cv::Mat(24, 32, CV_8UC3, cv::Scalar(40, 90, 160)));
  dicom::WriteEndoscopicFrames(frames, {0, 0.1, 0.2}, false, header, dir / "rec.dcm");
  const std::filesystem::path before = std::filesystem::current_path();
  std::filesystem::current_path(dir.path());
  BlobStore blobs("data/blobs");
  v1::Manifest clip;
  auto* file = clip.add_files();
  file->set_path("rec.dcm");
  file->set_sha256(blobs.Put(testing::ReadBytes(dir / "rec.dcm")));
  v1::RecordingOptions options;
  options.set_frames("20:");
  const std::string refused = testing::ErrorFrom([&] { CheckRecording(clip, options, blobs); });
  options.set_frames("1:");
  EXPECT_NO_THROW(CheckRecording(clip, options, blobs));
  std::filesystem::current_path(before);
  EXPECT_NE(refused.find("rec.dcm: zero frames: the window 20::1 holds none of the recording's 3 frames"),
            std::string::npos)
      << refused;
}

}  // namespace
}  // namespace endorecon::server
