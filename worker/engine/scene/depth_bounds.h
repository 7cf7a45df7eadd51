// A clip's depth bounds (near, far) brought to where its depth priors say the surface is. The bounds
// set the scene box, the samplers' range and the grids' cells; the priors are measured. Bounds far
// looser than the priors (near 0 and far 1000 around tissue at 60-105) spread the samples and the
// cells over empty space: depth came out 400 units off and the training slowed fourfold, without a
// word. Bounds that cut the priors off (near 84 and far 86 around the same tissue) leave the surface
// out of reach of every ray (found 2026-12-06).
//
// The priors' range is their 0.5th to 99.5th percentile, widened by a quarter of its span each way
// (at least a twentieth of the highest; not below half the lowest). Bounds spanning more than twice that
// range, or leaving more than a quarter of the priors outside them, become that range. Left as they are: a
// clip without depth, an object capture (its box is the object's), and priors mostly outside [near / 2, 2
// far], which are more likely in other units than the poses (CheckClipGeometry warns of those), and
// clips of fewer than 16 priors (read at every 61st pixel, or denser in a small clip, to about 400).
#pragma once

#include <string>

#include "worker/engine/scene/clip.h"

namespace endorecon::scene {

// Changes clip.near and clip.far as above and returns why (logged as a warning; FitToScene records
// it in left_out); empty when they stay.
std::string FitBoundsToPriors(Clip& clip);

}  // namespace endorecon::scene
