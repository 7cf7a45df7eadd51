// The third and fourth terms of the model map (model_uncertainty.h) where the clip's frames are known.
// The third: where the model does not fit the training frames near a time, it is likely wrong at that
// time too. The model's own errors persist from frame to frame at a surface point (a hash collision, a
// fold the deformation misses) and keep their sign, while the camera's noise does not; so the
// neighbours' signed residuals are averaged before they are squared, which cancels the noise where the
// squares would add it up, and the square is taken relative to the noise's level at the pixel's
// brightness. With the squares averaged instead, the model map ranked the demo clip's held-out
// noise-free error at Spearman 0.50-0.53; with the residuals averaged 0.55-0.58, and the real-texture
// clip's 0.36 against 0.43 (docs/benchmarks.md, "The neighbours' residuals, averaged with their
// signs"). The fourth compares the frame's own render with the nearest training frames' images: the
// render minus a neighbour's image is the render's own error, plus how the scene changes between the
// frames, plus the neighbour's noise; averaged over the neighbours and a pixel's surroundings the noise
// shrinks, and the render's error and the motion, where the model is most often wrong, are left. It
// ranked the demo clip's held-out noise-free error at 0.61-0.64 with it against 0.56-0.60 without
// (docs/benchmarks.md, "The render against its neighbours' images").
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "worker/engine/scene/camera.h"

namespace endorecon::eval {

// How far, in frames, the neighbours reach on either side.
inline constexpr int kNeighbourFrames = 4;

// One training frame's evidence: its signed residual against its image per channel (rendered colour
// clamped to [0, 1] minus the image's / 255; 3 values a pixel), NaN on its tool, where training does
// not look. rgb holds 3 values per pixel, image 3 (uint8) and tool_mask (or empty) one. Throws
// InvalidArgument when the lengths disagree.
std::vector<float> ResidualEvidence(std::span<const float> rgb, std::span<const std::uint8_t> image,
                                    std::span<const std::uint8_t> tool_mask);

// Frame f's view of its neighbours' evidence: per pixel, the squared length of the mean weighted by
// 1 / |g - f| over the frames g != f within kNeighbourFrames of f whose evidence is given (evidence[g]
// not empty) of their residuals at the pixel where the surface f sees there (f's rendered depth)
// projects in g's camera (the same pixel where the depth is not finite and positive), relative to
// its median at f's rendered brightness (RelativeToBrightnessMedian, rgb and tool_mask f's); a
// neighbour that sees it outside its image or on its tool adds nothing; 0 where none sees it. Tissue
// that moves between frames is not followed: the neighbours are a few frames away. Throws
// InvalidArgument when the cameras, the colours, the depth and the evidence disagree in size.
std::vector<float> NeighbourEvidence(std::span<const scene::Camera> cameras, int f,
                                     std::span<const float> rgb, std::span<const float> depth,
                                     std::span<const std::uint8_t> tool_mask,
                                     const std::vector<std::vector<float>>& evidence);

// How far, in frames, the disagreement's neighbours reach on either side, and the σ in pixels of the
// Gaussian it is averaged over.
inline constexpr int kDisagreementFrames = 2;
inline constexpr double kDisagreementBlurPixels = 1.0;

// A frame's image as the disagreement reads it: 3 values a pixel, and its tool mask (1 = tool; empty:
// none); an empty image for a frame that is not a neighbour (a held-out frame).
struct NeighbourImage {
  std::span<const std::uint8_t> rgb;
  std::span<const std::uint8_t> tool_mask;
};

// Frame f's disagreement with its neighbouring training frames' images: per pixel, f's rendered colour
// (clamped to [0, 1]) minus the image's / 255 at the pixel where the surface f sees projects in g
// (as NeighbourEvidence's), averaged with weights 1 / |g - f| over the frames g != f within
// kDisagreementFrames whose image is given, g's tool left out; the sums and their weights blurred by a
// Gaussian of kDisagreementBlurPixels (so pixels no neighbour sees do not pull their surroundings to
// 0), and the squared length of the mean taken. 0 where no neighbour sees the pixel. images holds one
// entry per camera. Throws InvalidArgument when the cameras, colours, depth and images disagree in size.
std::vector<float> NeighbourDisagreement(std::span<const scene::Camera> cameras, int f,
                                         std::span<const float> rgb, std::span<const float> depth,
                                         std::span<const NeighbourImage> images);

}  // namespace endorecon::eval
