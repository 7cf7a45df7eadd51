// Holes in a frame's depth prior filled from their surroundings before training. Stereo matching
// fails on specular highlights (and a synthetic clip's prior has holes there, as a real one's has),
// so the depth loss never sees the tissue under a highlight; a highlight that moves over still tissue
// is then free to become a floater in front of it (docs/benchmarks.md, "Where the demo clip's depth
// error sits": 4-9 units in front over 50-90 pixels as soon as the deformation is given more
// freedom). The tissue under a highlight continues its surroundings, so each hole pixel takes the
// Gaussian-weighted mean of the measured depths around it (normalised convolution), where they
// weigh enough; holes next to the tool, where the depth jumps from tool to tissue, stay holes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace endorecon::train {

struct FilledDepth {
  std::vector<float> depth;  // width * height: the prior with the holes it could fill filled
  std::size_t filled = 0;    // hole pixels filled
  std::size_t left = 0;      // hole pixels left (too far from a measurement, or by the tool)
};

// depth: width * height, 0 (or not finite, or negative) where nothing was measured; tool_mask: empty or
// width * height, nonzero on the tool. A hole pixel is filled with sum(g * d) / sum(g) over the measured
// pixels d (g a Gaussian of `sigma` pixels) when sum(g) is at least 5% of the Gaussian's whole weight and
// it is more than 3 pixels from the tool; measured pixels are kept as they are. sigma 0 fills nothing.
// Throws InvalidArgument when the sizes disagree or sigma is negative.
FilledDepth FillDepthHoles(std::span<const float> depth, std::span<const std::uint8_t> tool_mask, int width,
                           int height, double sigma);

}  // namespace endorecon::train
