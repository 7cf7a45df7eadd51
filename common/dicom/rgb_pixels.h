// Colour frames as DICOM pixel data: RGB, interleaved (Planar Configuration 0), frame after frame.
#pragma once

#include <dcmtk/config/osconfig.h>
#include <dcmtk/ofstd/oftypes.h>

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace endorecon::dicom {

// `frames`: 8-bit BGR (OpenCV's order). Throws InvalidArgument naming `where` and the frame when a
// frame differs from the first in size or type, or there is none.
std::vector<Uint8> InterleavedRgb(const std::vector<cv::Mat>& frames, const std::string& where);

}  // namespace endorecon::dicom
