// Decoding one image file from outside (a clip's frames, a recording's image folder, frames for
// `to-dicom`): the single path by which untrusted image bytes reach OpenCV.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>

namespace endorecon::scene {

// The file's pixels as OpenCV stores them (IMREAD_UNCHANGED: 8- or 16-bit, 1, 3 or 4 channels,
// BGR order). Only PNG, JPEG, BMP and TIFF files, told by their first bytes, reach OpenCV: it picks
// a decoder by content, and some of the decoders it carries abort the process on a broken file
// (tests/fuzz/image_decode_fuzz.cc: GDCM's DICOM reader asserts on a broken DICOM named .png); a
// PNG must be whole (common/image_bytes.h).
// Throws FailInvalid naming the file when it is missing, of another format, unreadable or truncated,
// and Error(kResourceExhausted) when its header declares more pixels than OpenCV decodes (2^30).
cv::Mat DecodeImageFile(const std::filesystem::path& path);

// An 8- or 16-bit grey, BGR or BGRA image as 8-bit BGR (16-bit scaled by 1/257).
cv::Mat ToBgr8(const cv::Mat& image);

// DecodeImageFile, then ToBgr8; also throws FailInvalid naming the file for another depth or a
// two-channel image.
cv::Mat DecodeImageFileAsBgr8(const std::filesystem::path& path);

}  // namespace endorecon::scene
