// The part of an endoscope's frames outside its round view: the black corners (or sides) a scope's
// circular field of view leaves in a rectangular frame. It is not tissue: trained, it would teach the
// field black walls; scored, it would lift every PSNR with pixels any render gets right.
//
// A pixel is outside the view when its brightest channel is at most `max_level` (of 255) in every
// frame and it reaches the frame's edge through such pixels (4-neighbours): a dark region inside the
// view (a cavity, a shadow) is tissue and stays. On the real laparoscopic video in ../shared/data/real/
// 16.3% of the frame is outside at level 8 (15.1% at 2, 17.0% at 32: the rim is sharp); the synthetic
// clips have none at any level up to 24, the stiff clip's near-black tissue included (camera noise
// and shading lift every pixel above it in some frame).
#pragma once

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "worker/engine/scene/clip.h"

namespace endorecon::scene {

// H*W, 1 outside the view; empty when no pixel is, when more than three quarters of the frame would
// be (a frame dark nearly everywhere has no view to keep), or when the clip has no frame.
std::vector<std::uint8_t> OutsideViewMask(const Clip& clip, int max_level);
// The same over frames not yet a clip: 8-bit, 3 channels (either order), one size; throws
// InvalidArgument otherwise.
std::vector<std::uint8_t> OutsideViewMask(const std::vector<cv::Mat>& frames, int max_level);

// The pixels of a frame a render covers: all but those outside the view.
int RenderedPixels(const Clip& clip);

// Marks the mask's pixels as not tissue in every frame: in the tool masks (made, all tissue but
// these, when the clip had none) and in the evaluation masks when the clip has them; and keeps it as
// clip.outside_view.
void ExcludeFromFrames(Clip& clip, const std::vector<std::uint8_t>& mask);

}  // namespace endorecon::scene
