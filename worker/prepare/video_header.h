// What a video file's container announces of its video stream, read with libavformat (the FFmpeg
// that OpenCV decodes with). OpenCV's frame count of a container that stores no count (Matroska,
// WebM) is its duration times the rate, and that duration runs from time zero: a clip cut from a
// longer recording with its timestamps kept (starting at 10 s, say) announced the frames before its
// start and was refused as truncated (found 2026-12-06).
#pragma once

#include <filesystem>

namespace endorecon::prepare {

struct VideoHeader {
  // The frames the container announces: its stored count, else (duration - first timestamp) x
  // average rate; -1 when it says neither (or the file does not open).
  int frames = -1;
};

VideoHeader ReadVideoHeader(const std::filesystem::path& file);

}  // namespace endorecon::prepare
