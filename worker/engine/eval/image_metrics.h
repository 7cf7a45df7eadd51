// The appearance metrics of one rendered frame, over the whole frame and over tissue only.
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>

namespace endorecon::eval {

struct ImageMetrics {
  double psnr = 0, ssim = 0;                // every pixel
  double psnr_tissue = 0, ssim_tissue = 0;  // tool pixels left out (= the above without a mask)
  long tissue_pixels = 0;
};

// Psnr and Ssim of `rendered` (float RGB in [0, 1]) against `reference` (uint8 RGB), once over the
// whole frame and once with `tool_mask` (empty, or 1 = tool). Tissue numbers are NaN on an
// all-tool frame, SSIMs on a frame under kSsimLeastSide pixels wide or high. Throws InvalidArgument on bad
// sizes (see Psnr, Ssim).
ImageMetrics MeasureImage(std::span<const float> rendered, std::span<const std::uint8_t> reference,
                          std::span<const std::uint8_t> tool_mask, int width, int height);

// {"psnr", "ssim", "psnr_tissue", "ssim_tissue", "tissue_pixels"}; NaN serialises as null.
nlohmann::json ToJson(const ImageMetrics& metrics);

// Per-frame list and a Summary of each number over the frames (mean of per-frame PSNR, as
// EndoNeRF reports it): {"psnr": {mean, std, ...}, ..., "per_frame": [...]}.
nlohmann::json ToJson(std::span<const ImageMetrics> frames);

}  // namespace endorecon::eval
