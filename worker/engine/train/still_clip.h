// Whether a clip's tissue moves at all. A clip whose times differ but whose tissue stands still (a
// fixed scope on a still organ, a static phantom) trained a deformation for nothing: on a still
// synthetic clip at 20 s, 32.7 dB held out (37.3 against the noise-free truth) against 33.9 (41.4)
// with the deformation left out, and the flow start measured 0.03 px (found 2026-12-06;
// docs/benchmarks.md). FitToScene leaves the deformation out of such a clip.
//
// Tested where it can be told cheaply: the camera stays put (every training frame's pose the same;
// a moving camera's frames move whatever the tissue does), the frames have images. Each training
// frame's dense optical flow from the first in time, on frames averaged down to at most
// kStillFlowWidth pixels across, over pixels usable in both (no tool, not saturated); the clip is
// still when, in every frame, 95% of them move less than `threshold_px` clip pixels (the config's
// still_threshold_px). Camera noise reads as flow too: a still synthetic clip at synth's default
// noise measures 0.15 px, at twice it 0.29 px and at five times 0.6 px (moving clips 0.5-1.6 px), so
// a clip noisier than about twice synth's default keeps its deformation (the safe side; a real
// laparoscopic recording is less noisy than the default, docs/formats.md). Smoothing the flow
// (a 9 x 9 average, a blur of the frames) did not separate them: DIS's noise is smooth too. Frames are tried
// from the last in time back, and the first that moves ends the test (a moving clip costs one or
// two flows, a still one a flow per frame: 0.1 s for 42 frames of 160 x 128).
#pragma once

#include <string>
#include <vector>

#include "worker/engine/scene/clip.h"

namespace endorecon::train {

inline constexpr int kStillFlowWidth = 160;

struct Stillness {
  bool tested = false;  // false: `why` says why not
  bool still = false;
  double motion_px = 0;  // the largest frame's 95th-percentile flow, clip pixels (of the frames tried)
  int frames = 0;        // frames whose flow was measured
  std::string why;
};

Stillness MeasureStillness(const scene::Clip& clip, const std::vector<int>& frames, double threshold_px);

}  // namespace endorecon::train
