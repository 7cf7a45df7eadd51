// The third term of the model map (model_uncertainty.h) where the clip's frames are known: where the
// model does not fit the training frames near a time, it is likely wrong at that time too. The
// model's own errors persist from frame to frame at a surface point (a hash collision, a fold the
// deformation misses), while the camera's noise does not; a neighbouring frame's residual against
// its image carries both, so each is taken relative to the noise's level at its brightness and
// several neighbours are averaged. It lifts the model map's ranking of the noise-free error (Spearman)
// from 0.49 to 0.54 on the demo clip's held-out frames and from 0.52 to 0.59 on the real-texture
// clip's training frames; that clip's held-out frames, whose exposure flickers unpredictably, rank
// lower (0.44 to 0.39) unless their exposure is fitted first (0.49 to 0.59; docs/benchmarks.md,
// "The neighbours' residuals").
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "worker/engine/scene/camera.h"

namespace endorecon::eval {

// How far, in frames, the neighbours reach on either side.
inline constexpr int kNeighbourFrames = 4;

// One training frame's evidence: its per-pixel squared RMSE against its image (eval::PixelRmse)
// divided by the frame's median at the pixel's rendered brightness (RelativeToBrightnessMedian);
// tool pixels, where training does not look, are marked -1 (no evidence). rgb holds 3 values per
// pixel, pixel_rmse and tool_mask (or empty) one. Throws InvalidArgument when the lengths disagree.
std::vector<float> ResidualEvidence(std::span<const float> rgb, std::span<const float> pixel_rmse,
                                    std::span<const std::uint8_t> tool_mask);

// Frame f's view of its neighbours' evidence: per pixel, the mean weighted by 1 / |g - f| over the
// frames g != f within kNeighbourFrames of f whose evidence is given (evidence[g] not empty) of
// their evidence at the pixel where the surface f sees there (f's rendered depth) projects in g's
// camera (the same pixel where the depth is not finite and positive); a neighbour that sees it
// outside its image or on its tool adds nothing; 0 where none sees it. Tissue that moves between
// frames is not followed: the neighbours are a few frames away. Throws InvalidArgument when the
// cameras, the depth and the evidence disagree in size.
std::vector<float> NeighbourEvidence(std::span<const scene::Camera> cameras, int f,
                                     std::span<const float> depth,
                                     const std::vector<std::vector<float>>& evidence);

}  // namespace endorecon::eval
