// A recording a user has as a video becomes a DICOM recording (`endorecon-worker to-dicom VIDEO`):
// every frame, at the video's own rate unless --fps says otherwise, as H.264 Video Endoscopic or
// multi-frame VL Endoscopic; the reader gets the same frames and times back.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "common/dicom/recording.h"
#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

// 12 frames of 64 x 48 at 10 frames/s, each a different grey ramp, as an MJPEG AVI.
std::filesystem::path WriteVideo(const TempDir& dir) {
  const std::filesystem::path video = dir / "clip.avi";
  cv::VideoWriter writer(video.string(), cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'),
                         10, cv::Size(64, 48));
  for (int f = 0; f < 12; ++f) {
    cv::Mat frame(48, 64, CV_8UC3);
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 64; ++x)
        frame.at<cv::Vec3b>(y, x) = cv::Vec3b::all(cv::saturate_cast<uchar>(2 * x + 8 * f));
    writer.write(frame);
  }
  return video;
}

int ToDicom(const TempDir& dir, std::vector<std::string> args) {
  args.insert(args.begin(), {BuiltBinary("worker/runtime/endorecon-worker"), "to-dicom"});
  Process process(args, dir / "to-dicom.log");
  const int code = process.Wait();
  EXPECT_EQ(code, 0) << process.Log();
  return code;
}

TEST(VideoToDicomTest, EveryFrameOfAVideoAtItsOwnRate) {
  TempDir dir("video-to-dicom");
  const auto video = WriteVideo(dir);
  ASSERT_EQ(ToDicom(dir, {video.string(), "-o", (dir / "h264.dcm").string()}), 0);
  const dicom::Recording h264 = dicom::ReadRecording(dir / "h264.dcm", {});
  ASSERT_EQ(h264.left.size(), 12u);
  EXPECT_EQ(h264.left[0].size(), cv::Size(64, 48));
  EXPECT_NEAR(h264.times_s.back(), 1.1, 1e-6);
  // Lossy, but the ramps are where they were: frame 11 is 88 levels brighter than frame 0.
  EXPECT_NEAR(cv::mean(h264.left[11])[0] - cv::mean(h264.left[0])[0], 88, 4);

  ASSERT_EQ(ToDicom(dir, {video.string(), "-o", (dir / "vl.dcm").string(), "--format", "vl", "--fps", "4"}),
            0);
  const dicom::Recording vl = dicom::ReadRecording(dir / "vl.dcm", {});
  ASSERT_EQ(vl.left.size(), 12u);
  EXPECT_NEAR(vl.times_s.back(), 11 / 4.0, 1e-6);
}

TEST(VideoToDicomTest, WhatCannotBeReadIsNamed) {
  TempDir dir("video-to-dicom-bad");
  WriteBytes(dir / "broken.mp4", std::string(5000, 'x'));
  Process process({BuiltBinary("worker/runtime/endorecon-worker"), "to-dicom", (dir / "broken.mp4").string(),
                   "-o", (dir / "out.dcm").string()},
                  dir / "to-dicom.log");
  EXPECT_NE(process.Wait(), 0);
  EXPECT_NE(process.Log().find("broken.mp4"), std::string::npos) << process.Log();
  EXPECT_FALSE(std::filesystem::exists(dir / "out.dcm"));
}

// A video that ends early leaves no half-made MP4 beside the output (found 2026-12-05), and -o naming
// a folder is a usage error that says so.
TEST(VideoToDicomTest, AFailedWriteLeavesNothingAndAFolderIsNoOutput) {
  TempDir dir("video-to-dicom-left");
  std::filesystem::create_directories(dir / "frames");
  cv::imwrite((dir / "frames" / "a.png").string(), cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(90)));
  cv::imwrite((dir / "frames" / "b.png").string(), cv::Mat(40, 64, CV_8UC3, cv::Scalar::all(90)));
  Process mixed({BuiltBinary("worker/runtime/endorecon-worker"), "to-dicom", (dir / "frames").string(), "-o",
                 (dir / "out.dcm").string()},
                dir / "mixed.log");
  EXPECT_NE(mixed.Wait(), 0) << mixed.Log();
  EXPECT_FALSE(std::filesystem::exists(dir / "out.dcm.mp4"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out.dcm"));
  Process folder({BuiltBinary("worker/runtime/endorecon-worker"), "to-dicom", (dir / "frames").string(), "-o",
                  dir.path().string()},
                 dir / "folder.log");
  EXPECT_EQ(folder.Wait(), 2) << folder.Log();
  EXPECT_NE(folder.Log().find(": a folder; -o names the DICOM file to write"), std::string::npos)
      << folder.Log();
}

// `to-dicom same.mp4 -o same.mp4` wrote the DICOM file over the only copy of the video (found
// 2026-12-07): refused, and the video is as it was.
TEST(VideoToDicomTest, TheVideoItselfIsNoOutput) {
  TempDir dir("video-to-dicom-same");
  const auto video = WriteVideo(dir);
  const std::string before = ReadBytes(video);
  Process same(
      {BuiltBinary("worker/runtime/endorecon-worker"), "to-dicom", video.string(), "-o", video.string()},
      dir / "same.log");
  EXPECT_EQ(same.Wait(), 2) << same.Log();
  EXPECT_NE(same.Log().find("is the video it would be made from"), std::string::npos) << same.Log();
  EXPECT_EQ(ReadBytes(video), before);
}

// Frames of odd size become H.264 of the even size above, padded, and read back whole: FFmpeg cut
// them to the size below while the header kept the odd one, a file endorecon could not read.
TEST(VideoToDicomTest, OddSizedFramesArePaddedToEvenOnes) {
  TempDir dir("video-to-dicom-odd");
  std::filesystem::create_directories(dir / "odd");
  for (const char* name : {"a.png", "b.png", "c.png"})
    cv::imwrite((dir / "odd" / name).string(), cv::Mat(47, 63, CV_8UC3, cv::Scalar(40, 120, 200)));
  ASSERT_EQ(ToDicom(dir, {(dir / "odd").string(), "-o", (dir / "odd.dcm").string()}), 0);
  const dicom::Recording odd = dicom::ReadRecording(dir / "odd.dcm", {});
  ASSERT_EQ(odd.left.size(), 3u);
  EXPECT_EQ(odd.left[0].size(), cv::Size(64, 48));
  EXPECT_NEAR(cv::mean(odd.left[2])[2], 200, 4);  // the padding repeats the edge: no dark border
  // The size said is the size written (it said 63x47).
  EXPECT_NE(ReadBytes(dir / "to-dicom.log").find("(3 frames of 64x48 at"), std::string::npos)
      << ReadBytes(dir / "to-dicom.log");
}

// The flags added on 2026-12-05 refuse their bad forms before any work: a Series Number out of DICOM's
// range for to-dicom, no views for calibrate (an OpenCV assertion before).
TEST(VideoToDicomTest, NewFlagsRefuseTheirBadForms) {
  TempDir dir("video-to-dicom-flags");
  const std::string worker = BuiltBinary("worker/runtime/endorecon-worker");
  Process series(
      {worker, "to-dicom", WriteVideo(dir).string(), "-o", (dir / "x.dcm").string(), "--series-number", "-1"},
      dir / "series.log");
  EXPECT_EQ(series.Wait(), 2) << series.Log();
  EXPECT_NE(series.Log().find("--series-number"), std::string::npos) << series.Log();
  EXPECT_FALSE(std::filesystem::exists(dir / "x.dcm"));
  Process views({worker, "calibrate", "-o", (dir / "c.yaml").string(), "--left", dir.path().string(),
                 "--right", dir.path().string(), "--square", "4", "--max-views", "0"},
                dir / "views.log");
  EXPECT_EQ(views.Wait(), 2) << views.Log();
  EXPECT_NE(views.Log().find("--max-views"), std::string::npos) << views.Log();
  // A clip or results folder that is not there is the user's input too: exit 2, as documented (it
  // was 1; found 2026-12-05).
  Process missing({worker, "reconstruct", (dir / "nope").string(), "-o", (dir / "out").string()},
                  dir / "missing.log");
  EXPECT_EQ(missing.Wait(), 2) << missing.Log();
  EXPECT_NE(missing.Log().find("nope"), std::string::npos) << missing.Log();
}

// `reconstruct REC.dcm -o OUT` makes its clip in OUT.clip: a folder of the user's there is refused,
// not deleted (found 2026-12-05: it was removed without a word).
TEST(VideoToDicomTest, AReconstructionKeepsAForeignFolderWhereItsClipWouldGo) {
  TempDir dir("video-to-dicom-clip");
  ASSERT_EQ(ToDicom(dir, {WriteVideo(dir).string(), "-o", (dir / "rec.dcm").string()}), 0);
  std::filesystem::create_directories(dir / "out.clip");
  WriteBytes(dir / "out.clip" / "mine.txt", "keep");
  Process reconstruct({BuiltBinary("worker/runtime/endorecon-worker"), "reconstruct",
                       (dir / "rec.dcm").string(), "-o", (dir / "out").string(), "--iterations", "5"},
                      dir / "reconstruct.log");
  EXPECT_EQ(reconstruct.Wait(), 2) << reconstruct.Log();
  EXPECT_NE(reconstruct.Log().find("out.clip: exists and is not a clip an earlier run made"),
            std::string::npos)
      << reconstruct.Log();
  EXPECT_EQ(ReadBytes(dir / "out.clip" / "mine.txt"), "keep");
}

}  // namespace
}  // namespace endorecon::testing
