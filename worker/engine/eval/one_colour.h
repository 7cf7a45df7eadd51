// The yardstick of a reconstruction that learnt nothing: the PSNR each frame would get from its own
// mean colour alone. A run whose training frames score no better finished without a word (a learning
// rate of 1 trained to 3.2 dB, its depth all at the near plane; found 2026-12-07): the run says so.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "worker/engine/scene/clip.h"

namespace endorecon::eval {

// PSNR (peak 1, every channel of every pixel) of `image` (uint8 RGB) against its own mean colour.
double OneColourPsnr(std::span<const std::uint8_t> image);

// The mean of OneColourPsnr over `frames` of `clip`; NaN for no frame.
double MeanOneColourPsnr(const scene::Clip& clip, const std::vector<int>& frames);

// A reconstruction whose training frames' mean PSNR is within this of the yardstick learnt nothing
// a single colour would not have.
inline constexpr double kLeastGainOverOneColourDb = 1.0;

}  // namespace endorecon::eval
