#include "worker/engine/eval/image_metrics.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "worker/engine/eval/image_size.h"
#include "worker/engine/eval/psnr.h"
#include "worker/engine/eval/ssim.h"
#include "worker/engine/eval/summary.h"

namespace endorecon::eval {

ImageMetrics MeasureImage(std::span<const float> rendered, std::span<const std::uint8_t> reference,
                          std::span<const std::uint8_t> tool_mask, int width, int height) {
  CheckMaskSize(tool_mask.size(), width, height, "image metrics: tool mask");
  ImageMetrics m;
  // SSIM is not defined on a frame smaller than its window (a tiny clip, or a tiny clip's frame
  // rendered at a stride): NaN, written as null, rather than a failed job.
  const bool ssim_defined = width >= kSsimLeastSide && height >= kSsimLeastSide;
  const auto ssim = [&](std::span<const std::uint8_t> mask) {
    return ssim_defined ? Ssim(rendered, reference, mask, width, height) : std::nan("");
  };
  m.psnr = Psnr(rendered, reference, {}, width, height);
  m.ssim = ssim({});
  if (tool_mask.empty()) {
    m.psnr_tissue = m.psnr;
    m.ssim_tissue = m.ssim;
    m.tissue_pixels = static_cast<long>(width) * height;
    return m;
  }
  m.psnr_tissue = Psnr(rendered, reference, tool_mask, width, height);
  m.ssim_tissue = ssim(tool_mask);
  m.tissue_pixels = static_cast<long>(std::count(tool_mask.begin(), tool_mask.end(), 0));
  return m;
}

nlohmann::json ToJson(const ImageMetrics& metrics) {
  return {{"psnr", metrics.psnr},
          {"ssim", metrics.ssim},
          {"psnr_tissue", metrics.psnr_tissue},
          {"ssim_tissue", metrics.ssim_tissue},
          {"tissue_pixels", metrics.tissue_pixels}};
}

nlohmann::json ToJson(std::span<const ImageMetrics> frames) {
  nlohmann::json per_frame = nlohmann::json::array();
  for (const ImageMetrics& f : frames) per_frame.push_back(ToJson(f));
  return SummariseFrames(std::move(per_frame), {"psnr", "ssim", "psnr_tissue", "ssim_tissue"});
}

}  // namespace endorecon::eval
