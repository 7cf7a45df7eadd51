// A clip folder checked before its upload, as far as that needs no decoding: what the worker's loader
// would refuse after the upload and a wait in the queue is refused here, at once.
#pragma once

#include <filesystem>

namespace endorecon::client {

// The layout's files are all there and paired frame by frame (common/clip_files.h: a missing mask, an
// extra depth map, a path out of the clip), every image is a PNG, JPEG, BMP or TIFF by its bytes and
// a PNG is whole (common/image_bytes.h), and every .npy depth map reads; gt/'s files alike; and an
// EndoNeRF clip's pose rows hold cameras, poses and depth bounds the loader takes (common/pose_rows.h).
// Throws Error (kInvalidArgument) naming the file and saying that nothing was uploaded. Pixels,
// transforms.json's cameras and sizes are the worker's to check.
void CheckClipBeforeUpload(const std::filesystem::path& dir);

}  // namespace endorecon::client
