#include "worker/prepare/stereo_source.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "common/error.h"

namespace endorecon::prepare {
namespace {

std::string SizeText(cv::Size size) { return std::to_string(size.width) + "x" + std::to_string(size.height); }

}  // namespace

StereoSource::StereoSource(const RecordingInput& input, UnequalLengths unequal) : layout_(input.layout) {
  if (layout_ == StereoLayout::kTwoSources) {
    // One eye given twice has no disparity: it prepared a clip of 29% depth coverage without a word
    // (found 2026-12-05).
    std::error_code error;
    if (std::filesystem::equivalent(input.left, input.right, error) && !error) {
      FailInvalid(input.right.string() + ": the right eye is the left eye's recording (" +
                  input.left.string() + "); give each eye's own");
    }
    first_ = OpenFrameSource(input.left);
    second_ = OpenFrameSource(input.right);
    eye_size_ = first_->frame_size();
    if (second_->frame_size() != eye_size_) {
      FailInvalid(second_->name() + ": frames of " + SizeText(second_->frame_size()) + " differ from " +
                  first_->name() + "'s " + SizeText(eye_size_) + " (both eyes must have one size)");
    }
    skips_[0] = input.skip_left;
    skips_[1] = input.skip_right;
    CheckPairedByOrder(unequal);
    SkipFirst(*first_, input.skip_left, "--skip-left");
    SkipFirst(*second_, input.skip_right, "--skip-right");
    return;
  }
  first_ = OpenFrameSource(input.combined);
  const cv::Size whole = first_->frame_size();
  if (layout_ == StereoLayout::kSideBySide) {
    if (whole.width % 2 != 0) {
      FailInvalid(first_->name() + " frame 0: a side-by-side frame must have an even width, found " +
                  SizeText(whole));
    }
    eye_size_ = {whole.width / 2, whole.height};
  } else {
    if (whole.height % 2 != 0) {
      FailInvalid(first_->name() + " frame 0: a top-bottom frame must have an even height, found " +
                  SizeText(whole));
    }
    eye_size_ = {whole.width, whole.height / 2};
  }
}

// The eyes' frames are paired by their order: two recordings of other rates or lengths would pair
// frames of different moments, and the disparities between them are motion, not depth (a 25 and a
// 30 fps eye prepared a clip without a word; found 2026-12-06). Checked before any frame is
// prepared, where the headers say; Next checks each pair's times as it goes.
void StereoSource::CheckPairedByOrder(UnequalLengths unequal) {
  const double a = first_->frame_rate(), b = second_->frame_rate();
  if (a > 0 && b > 0 && std::abs(a - b) > 0.01 * std::max(a, b)) {
    FailInvalid(
        fmt::format("{}: {:.4g} frames per second while {} has {:.4g}: the eyes' frames are paired "
                    "by their order, so both recordings must have one frame rate (were they "
                    "recorded together?)",
                    second_->name(), b, first_->name(), a));
  }
  // Times are compared only between two videos: a folder's are its order at a nominal 25 fps. The
  // right eye's are scaled by the rates' ratio: one synchronised rig's eyes labelled 30 and 29.97 fps
  // drift apart by a frame every 33 s (a 52 s recording was refused at its end; found 2026-12-06).
  frame_period_s_ = a > 0 && b > 0 ? 1 / a : 0;
  rate_ratio_ = a > 0 && b > 0 ? b / a : 1;
  // Two folders' counts are exact: compared before any frame is prepared. A video's header count may
  // be an estimate (from its duration; a start time of 0.5 s read as 15 frames more), so two videos'
  // lengths are compared as they end (Ended).
  if (unequal == UnequalLengths::kRefused) RequireEqualLengths();
}

void StereoSource::RequireEqualLengths() const {
  if (!second_ || cut_apart() || !first_->count_is_exact() || !second_->count_is_exact()) return;
  if (const int m = first_->announced_frames(), n = second_->announced_frames(); m != n) {
    FailInvalid(fmt::format(
        "{}: {} frames while {} has {} (both eyes' recordings must have the same length; if one eye's "
        "began earlier, pass --skip-left or --skip-right with the frames it began before the other: the "
        "eyes' motion did not tell how many)",
        second_->name(), n, first_->name(), m));
  }
}

// Drops `eye`'s first `frames` (`flag`: skip_left, skip_right); a recording of no more frames is
// refused (a video's count is known only once read: the eyes' timing check says when none is left).
void StereoSource::SkipFirst(FrameSource& eye, int frames, const char* flag) {
  if (frames == 0) return;
  if (const int skipped = SkipFrames(eye, frames); skipped < frames) {
    FailInvalid(fmt::format("{}: it ends after {} frame(s), before the {} to skip ({} {})", eye.name(),
                            skipped, frames, flag, frames));
  }
  if (eye.count_is_exact() && eye.announced_frames() <= frames) {
    FailInvalid(fmt::format("{}: it holds {} frame(s): none is left after the {} skipped ({} {})", eye.name(),
                            eye.announced_frames(), frames, flag, frames));
  }
}

int StereoSource::announced_frames() const {
  const auto less = [](int count, int skipped) { return count < 0 ? count : std::max(0, count - skipped); };
  const int first = less(first_->announced_frames(), skips_[0]);
  if (!second_) return first;
  const int second = less(second_->announced_frames(), skips_[1]);
  return first < 0 ? second : second < 0 ? first : std::min(first, second);
}

std::string StereoSource::name() const {
  return second_ ? first_->name() + " + " + second_->name() : first_->name();
}

bool StereoSource::Ended(bool first, bool second, int index) {
  if (!first) left_frames_ = index;
  if (first == second) return !first;
  FrameSource& ended = first ? *second_ : *first_;
  FrameSource& going = first ? *first_ : *second_;
  // Eyes cut apart at their start may end apart too: the pairs end with the shorter.
  if (cut_apart()) {
    // With no pair at all the eyes' timing check refuses the skip instead.
    if (index > 0) {
      spdlog::warn("{}: its frames after the {} paired with {} are left out (the eyes' recordings end apart)",
                   going.name(), index, ended.name());
    }
    return true;
  }
  // A video a frame or two longer than the other (a trailing frame one eye's file kept) ends the
  // pairs with the shorter, said; two folders are exact (refused before any frame).
  if (!(ended.count_is_exact() && going.count_is_exact())) {
    int extra = 1;  // the going eye's frame `index` was read already
    while (extra <= kTrailingFrames && going.Skip()) ++extra;
    if (extra <= kTrailingFrames) {
      if (first) left_frames_ = index + extra;
      spdlog::warn("{}: {} frame(s) after the {} of {} left out: the eyes are paired up to the shorter",
                   going.name(), extra, index, ended.name());
      return true;
    }
  }
  FailInvalid(ended.name() + " frame " + std::to_string(index) + ": it ends after " + std::to_string(index) +
              " frames while " + going.name() + " goes on (both eyes' recordings must have the same length)");
}

bool StereoSource::Next(StereoFrame& frame) {
  const int index = next_;
  if (second_) {
    SourceFrame left, right;
    const bool a = first_->Next(left), b = second_->Next(right);
    if (Ended(a, b, index)) return false;
    // Pairs out of step by more than a frame and a half (a variable-rate eye, say; timestamps
    // jitter by less).
    // Eyes cut apart are expected that many frames apart in their own times.
    const double expected_s = (skips_[0] - skips_[1]) * frame_period_s_;
    if (frame_period_s_ > 0 &&
        std::abs(left.time_s - right.time_s * rate_ratio_ - expected_s) > 1.5 * frame_period_s_) {
      FailInvalid(
          fmt::format("{} frame {}: at {:.3f} s while {}'s frame {} is at {:.3f} s: the eyes are out of "
                      "step (the frames are paired by their order; is one of them of a variable "
                      "frame rate, or cut?)",
                      second_->name(), index, right.time_s, first_->name(), index, left.time_s));
    }
    frame.left = std::move(left.image);
    frame.right = std::move(right.image);
    frame.time_s = left.time_s;
  } else {
    SourceFrame both;
    if (!first_->Next(both)) {
      left_frames_ = index;
      return false;
    }
    const cv::Rect first_half(0, 0, eye_size_.width, eye_size_.height);
    const cv::Rect second_half = layout_ == StereoLayout::kSideBySide
                                     ? cv::Rect(eye_size_.width, 0, eye_size_.width, eye_size_.height)
                                     : cv::Rect(0, eye_size_.height, eye_size_.width, eye_size_.height);
    frame.left = both.image(first_half).clone();
    frame.right = both.image(second_half).clone();
    frame.time_s = both.time_s;
  }
  frame.index = index;
  ++next_;
  return true;
}

bool StereoSource::Skip() {
  const int index = next_;
  const bool a = first_->Skip();
  if (!second_ && !a) left_frames_ = index;
  if (second_ ? Ended(a, second_->Skip(), index) : !a) return false;
  ++next_;
  return true;
}

}  // namespace endorecon::prepare
