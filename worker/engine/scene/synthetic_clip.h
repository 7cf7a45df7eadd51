// Synthetic clips with known truth, written in the EndoNeRF layout (docs/formats.md):
//   images/NNNNNN.png        observed frames (RGB, tool drawn)
//   depth/NNNNNN.png         stereo-like 8-bit depth of what is seen, clip units (0 = hole)  [depth]
//   masks/NNNNNN.png         255 where the tool is visible, 0 elsewhere                      [tool]
//   poses_bounds.npy         N rows: the endoscope's camera-to-world (the identity once loaded unless
//                            moving), near, far
//   images_right/, stereo.json  the right eye, shifted by the baseline along x             [stereo]
//   recording/               the raw stereo recording and its calibration (synthetic_recording.h) [recording]
//   gt/images/NNNNNN.png     the same frames without the tool
//   gt/depth/NNNNNN.npy      float32 z-depth of the tissue (no tool), clip units
//   synth.json               the options used (and the mark of a synthetic clip folder)
#pragma once

#include <filesystem>

#include "worker/engine/scene/synthetic_scene.h"

namespace endorecon::scene {

// Renders and writes the clip. Identical options give byte-identical files. Depth PNGs are the
// observed z-depth plus zero-mean noise (sigma = 0.25 + 0.5 (z/90)^2, clamped at 3 sigma), rounded,
// with holes (0) at strong specular highlights and at a few random discs per frame.
// `out` is created if needed; an existing non-empty folder must hold an earlier synthetic clip
// (synth.json), whose files are replaced. Throws FailInvalid for bad options or a foreign
// non-empty folder, Error(kUnavailable) when a file cannot be written.
void WriteSyntheticClip(const SynthOptions& options, const std::filesystem::path& out);

}  // namespace endorecon::scene
