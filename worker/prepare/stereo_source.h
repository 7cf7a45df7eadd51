// The two eyes of a stereo recording, frame by frame: two frame sources (one per eye), or one
// whose frames hold both eyes side by side (left eye in the left half) or top-bottom (left eye on
// top). Checks what pairing needs: equal sizes, lengths and frame rates, pairs in step, even widths
// or heights to split.
#pragma once

#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "worker/prepare/frame_source.h"

namespace endorecon::prepare {

enum class StereoLayout { kTwoSources, kSideBySide, kTopBottom };

struct RecordingInput {
  StereoLayout layout = StereoLayout::kTwoSources;
  std::filesystem::path left, right;  // kTwoSources: a video or a folder per eye
  std::filesystem::path combined;     // kSideBySide, kTopBottom: one video or folder
  // kTwoSources: the first frames of one eye's recording, dropped so that the pairs begin at one
  // moment (its recording began that many frames before the other's: eye_sync.h). With either,
  // the eyes' recordings may end apart too: the pairs end with the shorter, said.
  int skip_left = 0, skip_right = 0;
};

struct StereoFrame {
  cv::Mat left, right;  // 8-bit BGR, each eye's own pixels
  double time_s = 0;
  int index = 0;  // 0-based position in the recording
};

class StereoSource {
 public:
  // Whether two folders of different lengths are refused at once, or read as far as the shorter
  // (the eyes' timing check reads their start first: a lag is what usually makes them differ).
  enum class UnequalLengths { kRefused, kRead };
  // Opens the sources (OpenFrameSource's errors), and throws FailInvalid naming the file when the
  // eyes differ in size, frame rate or (two folders, kRefused) length, a skip leaves an eye no frame,
  // or a combined frame cannot be split in equal halves.
  explicit StereoSource(const RecordingInput& input, UnequalLengths unequal = UnequalLengths::kRefused);

  cv::Size eye_size() const { return eye_size_; }
  // The recording's announced frame count (-1: unknown); the lower of two sources'.
  int announced_frames() const;
  // The file(s), for messages.
  std::string name() const;
  // Throws FailInvalid naming both when two folders of exact counts differ in length and the eyes
  // were not cut apart (what the constructor does with UnequalLengths::kRefused).
  void RequireEqualLengths() const;
  // Two sources whose first frames are skipped (RecordingInput::skip_left, skip_right): cut apart at
  // their start, they may end apart too.
  bool cut_apart() const { return skips_[0] > 0 || skips_[1] > 0; }

  // The next pair; false after the last. Throws the sources' errors, and FailInvalid naming both
  // when one eye's recording ends before the other's (a video may go on by kTrailingFrames, left out
  // with a warning) or their frames' times are out of step.
  bool Next(StereoFrame& frame);
  bool Skip();
  // The frames of the left eye's file, its skip included, where they are known before it is read (a
  // folder's); -1 otherwise.
  int left_file_frames() const { return first_->count_is_exact() ? first_->announced_frames() : -1; }
  // After the last pair: the frames the left eye's recording held after its skip (its masks' count),
  // or -1 where the right eye's ended first and the left's went on (eyes cut apart).
  int left_eye_frames() const { return left_frames_; }

 private:
  bool Ended(bool first, bool second, int index);
  void CheckPairedByOrder(UnequalLengths unequal);
  static void SkipFirst(FrameSource& eye, int frames, const char* flag);

  StereoLayout layout_;
  std::unique_ptr<FrameSource> first_, second_;  // second_ only for two sources
  cv::Size eye_size_;
  double frame_period_s_ = 0;  // two videos': one frame's time at their rate; 0: not two videos
  double rate_ratio_ = 1;      // two videos': the right eye's rate over the left's
  int skips_[2] = {0, 0};      // two sources: the first frames skipped of first_, second_
  static constexpr int kTrailingFrames = 2;  // a longer video's frames past the shorter's, tolerated
  int next_ = 0;
  int left_frames_ = -1;
};

}  // namespace endorecon::prepare
