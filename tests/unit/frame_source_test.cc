// The recordings `prepare` reads: folders of images and video files (made here with OpenCV's
// VideoWriter), their sizes, times and lengths, the damaged ones, and the real laparoscopic video.
#include "worker/prepare/frame_source.h"

#include <gtest/gtest.h>

extern "C" {
#include <libavformat/avformat.h>
}

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::testing {
namespace {

namespace fs = std::filesystem;

// Smooth gradients that differ per frame (JPEG keeps them close).
cv::Mat Frame(int i, cv::Size size = {64, 48}) {
  cv::Mat frame(size, CV_8UC3);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      frame.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<std::uint8_t>(2 * x + 45 * i), static_cast<std::uint8_t>(3 * y),
                    static_cast<std::uint8_t>(100 + i));
    }
  }
  return frame;
}

// A Motion-JPEG AVI of `frames` frames at 25 fps, written by OpenCV's own encoder.
fs::path WriteVideo(const fs::path& path, int frames, cv::Size size = {64, 48}) {
  cv::VideoWriter writer(path.string(), cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                         size);
  EXPECT_TRUE(writer.isOpened());
  for (int i = 0; i < frames; ++i) writer.write(Frame(i, size));
  return path;
}

// A Matroska file of `frames` Motion-JPEG frames at 25 fps whose timestamps start at `start_ms`, as a
// clip cut from a longer recording with its timestamps kept: muxed with libavformat (OpenCV's writer
// always starts at zero).
fs::path WriteMatroska(const fs::path& path, int frames, int start_ms) {
  AVFormatContext* out = nullptr;
  EXPECT_GE(avformat_alloc_output_context2(&out, nullptr, "matroska", path.c_str()), 0);
  AVStream* stream = avformat_new_stream(out, nullptr);
  stream->time_base = {1, 1000};
  stream->avg_frame_rate = {25, 1};
  stream->codecpar->codec_type = AVMEDIA_TYPE_VIDEO;
  stream->codecpar->codec_id = AV_CODEC_ID_MJPEG;
  stream->codecpar->width = 64;
  stream->codecpar->height = 48;
  EXPECT_GE(avio_open(&out->pb, path.c_str(), AVIO_FLAG_WRITE), 0);
  EXPECT_GE(avformat_write_header(out, nullptr), 0);
  AVPacket* packet = av_packet_alloc();
  for (int i = 0; i < frames; ++i) {
    std::vector<std::uint8_t> jpeg;
    cv::imencode(".jpg", Frame(i), jpeg);
    EXPECT_GE(av_new_packet(packet, static_cast<int>(jpeg.size())), 0);
    std::copy(jpeg.begin(), jpeg.end(), packet->data);
    packet->pts = packet->dts = av_rescale_q(start_ms + 40 * i, {1, 1000}, stream->time_base);
    packet->duration = av_rescale_q(40, {1, 1000}, stream->time_base);
    packet->flags |= AV_PKT_FLAG_KEY;
    packet->stream_index = stream->index;
    EXPECT_GE(av_interleaved_write_frame(out, packet), 0);
  }
  av_packet_free(&packet);
  EXPECT_GE(av_write_trailer(out), 0);
  avio_closep(&out->pb);
  avformat_free_context(out);
  return path;
}

TEST(FrameSourceTest, ReadsAFolderInNameOrder) {
  TempDir dir("frames");
  for (int i = 0; i < 3; ++i) WriteImage(dir / cv::format("f%d.png", 2 - i), Frame(i));
  cv::Mat grey16(48, 64, CV_16UC1, cv::Scalar(65535));
  WriteImage(dir / "f3.png", grey16);
  auto source = prepare::OpenFrameSource(dir.path());
  EXPECT_EQ(source->announced_frames(), 4);
  EXPECT_EQ(source->frame_size(), cv::Size(64, 48));
  prepare::SourceFrame frame;
  ASSERT_TRUE(source->Next(frame));
  EXPECT_EQ(cv::norm(frame.image, Frame(2), cv::NORM_INF), 0) << "f0.png first";
  EXPECT_TRUE(source->Skip());
  ASSERT_TRUE(source->Next(frame));
  EXPECT_EQ(frame.index, 2);
  EXPECT_DOUBLE_EQ(frame.time_s, 2 * prepare::kImageFolderFramePeriod);
  ASSERT_TRUE(source->Next(frame));
  EXPECT_EQ(frame.image.type(), CV_8UC3) << "16-bit grey becomes 8-bit colour";
  EXPECT_EQ(frame.image.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 255, 255));
  EXPECT_FALSE(source->Next(frame));
}

TEST(FrameSourceTest, FolderFramesOfAnotherSizeOrUnreadableAreNamed) {
  TempDir dir("frames");
  WriteImage(dir / "a.png", Frame(0));
  WriteImage(dir / "b.png", Frame(1, {32, 48}));
  auto source = prepare::OpenFrameSource(dir.path());
  prepare::SourceFrame frame;
  ASSERT_TRUE(source->Next(frame));
  std::string message = ErrorFrom([&] { source->Next(frame); });
  EXPECT_NE(message.find("b.png: size 32x48 differs from the recording's 64x48"), std::string::npos)
      << message;
  fs::remove(dir / "b.png");
  // A broken DICOM named .png (OpenCV would hand it to GDCM, which aborts the process) and a PNG
  // cut short: both refused naming the file and the frame.
  WriteBytes(dir / "c.png", std::string(128, '\0') + "DICM" + std::string(64, 'x'));
  source = prepare::OpenFrameSource(dir.path());
  ASSERT_TRUE(source->Next(frame));
  message = ErrorFrom([&] { source->Next(frame); });
  EXPECT_NE(message.find("c.png: not a PNG, JPEG, BMP or TIFF image (frame 1)"), std::string::npos)
      << message;
  std::vector<std::uint8_t> png;
  cv::imencode(".png", Frame(2), png);
  WriteBytes(dir / "c.png", std::string(png.begin(), png.begin() + png.size() / 2));
  source = prepare::OpenFrameSource(dir.path());
  ASSERT_TRUE(source->Next(frame));
  message = ErrorFrom([&] { source->Next(frame); });
  EXPECT_NE(message.find("c.png: a truncated PNG"), std::string::npos) << message;
  EXPECT_NE(message.find("(frame 1)"), std::string::npos) << message;
}

TEST(FrameSourceTest, ReadsAVideoWithItsTimes) {
  TempDir dir("video");
  auto source = prepare::OpenFrameSource(WriteVideo(dir / "v.avi", 10));
  EXPECT_EQ(source->announced_frames(), 10);
  EXPECT_EQ(source->frame_size(), cv::Size(64, 48));
  prepare::SourceFrame frame;
  int frames = 0;
  while (source->Next(frame)) {
    EXPECT_EQ(frame.index, frames);
    EXPECT_NEAR(frame.time_s, frames / 25.0, 1e-6);
    EXPECT_LT(cv::norm(frame.image, Frame(frames), cv::NORM_L1) / frame.image.total(), 25)
        << "JPEG-close, another frame is not";
    ++frames;
  }
  EXPECT_EQ(frames, 10);
}

TEST(FrameSourceTest, TruncatedOrUnreadableVideosAreNamed) {
  TempDir dir("video");
  const fs::path video = WriteVideo(dir / "v.avi", 40);
  const std::string bytes = ReadBytes(video);
  WriteBytes(dir / "cut.avi", bytes.substr(0, bytes.size() / 2));
  const std::string message = ErrorFrom([&] {
    auto source = prepare::OpenFrameSource(dir / "cut.avi");
    while (source->Skip()) {
    }
  });
  EXPECT_NE(message.find("cut.avi"), std::string::npos) << message;
  EXPECT_NE(message.find("of the 40 frames its header announces (truncated or damaged)"), std::string::npos)
      << message;

  WriteBytes(dir / "noise.mp4", std::string(5000, 'x'));
  const std::string unreadable = ErrorFrom([&] { prepare::OpenFrameSource(dir / "noise.mp4"); });
  EXPECT_NE(unreadable.find("noise.mp4: cannot open it as a video"), std::string::npos) << unreadable;
  ErrorFrom([&] { prepare::OpenFrameSource(dir / "missing.mp4"); }, ErrorCode::kNotFound);
}

// A Matroska clip whose timestamps start at 10 s announced the 250 frames of (10 s + its 4 s) x 25 fps
// and was refused as truncated after its 100 (found 2026-12-06); cut short, it still is.
TEST(FrameSourceTest, AVideoWhoseTimestampsStartLateIsCountedFromItsStart) {
  TempDir dir("late");
  const fs::path video = WriteMatroska(dir / "late.mkv", 100, 10000);
  auto source = prepare::OpenFrameSource(video);
  EXPECT_EQ(source->announced_frames(), 100);
  prepare::SourceFrame frame;
  int frames = 0;
  while (source->Next(frame)) {
    if (frames == 1) {
      EXPECT_NEAR(frame.time_s, 0.04, 1e-3) << "since the clip's first frame";
    }
    ++frames;
  }
  EXPECT_EQ(frames, 100);

  const std::string bytes = ReadBytes(video);
  WriteBytes(dir / "cut.mkv", bytes.substr(0, bytes.size() / 2));
  const std::string message = ErrorFrom([&] {
    auto cut = prepare::OpenFrameSource(dir / "cut.mkv");
    while (cut->Skip()) {
    }
  });
  EXPECT_NE(message.find("of the 100 frames its header announces (truncated or damaged)"), std::string::npos)
      << message;
}

// Real H.264 from a laparoscope (1280x720, 25 fps): what FFmpeg says of it matches what it decodes.
TEST(FrameSourceTest, ReadsTheRealLaparoscopicVideo) {
  const fs::path video = fs::path(ENDORECON_SHARED_DIR) / "data/real/laparoscopy_mono/endo.mp4";
  if (!fs::exists(video)) GTEST_SKIP() << "the real video is not here: " << video;
  auto source = prepare::OpenFrameSource(video);
  EXPECT_EQ(source->frame_size(), cv::Size(1280, 720));
  EXPECT_EQ(source->announced_frames(), 250);
  prepare::SourceFrame frame;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(source->Next(frame));
    EXPECT_NEAR(frame.time_s, i * 0.04, 1e-3);
  }
  EXPECT_EQ(frame.image.type(), CV_8UC3);
}

}  // namespace
}  // namespace endorecon::testing
