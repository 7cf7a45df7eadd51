// How a recording's frames are laid out (mono, or which stereo layout) and how its endoscope is
// placed in the clip made from it: the words of a job's recording options. Apart from reading the
// recording (recording.h), so that the server checks a job's options without OpenCV.
#pragma once

#include <string>

namespace endorecon::dicom {

enum class StereoLayout { kMono, kSideBySide, kTopBottom, kTwoSeries };

// "" or "mono", "side-by-side", "top-bottom", "series". Throws InvalidArgument naming the value.
StereoLayout ParseStereoLayout(const std::string& text);
std::string StereoLayoutName(StereoLayout layout);

// How the endoscope is placed in the clip made from a recording: moving (its motion estimated from
// the frames: a mono recording's turns, worker/prepare/camera_rotation.h; a stereo recording's
// poses, worker/prepare/pose_estimator.h) or fixed (one pose for every frame).
enum class Endoscope { kMoving, kFixed };

// "" or "moving", "fixed". Throws InvalidArgument naming the value.
Endoscope ParseEndoscope(const std::string& text);
std::string EndoscopeName(Endoscope endoscope);

}  // namespace endorecon::dicom
