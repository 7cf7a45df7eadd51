#include "worker/engine/eval/image_metrics.h"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <vector>

#include "worker/engine/eval/image_size.h"
#include "worker/engine/eval/psnr.h"
#include "worker/engine/eval/ssim.h"
#include "worker/engine/eval/summary.h"

namespace endorecon::eval {

ImageMetrics MeasureImage(std::span<const float> rendered, std::span<const std::uint8_t> reference,
                          std::span<const std::uint8_t> tool_mask, int width, int height) {
  CheckMaskSize(tool_mask.size(), width, height, "image metrics: tool mask");
  ImageMetrics m;
  m.psnr = Psnr(rendered, reference, {}, width, height);
  m.ssim = Ssim(rendered, reference, {}, width, height);
  if (tool_mask.empty()) {
    m.psnr_tissue = m.psnr;
    m.ssim_tissue = m.ssim;
    m.tissue_pixels = static_cast<long>(width) * height;
    return m;
  }
  m.psnr_tissue = Psnr(rendered, reference, tool_mask, width, height);
  m.ssim_tissue = Ssim(rendered, reference, tool_mask, width, height);
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
  std::vector<double> psnr, ssim, psnr_tissue, ssim_tissue;
  nlohmann::json per_frame = nlohmann::json::array();
  for (const ImageMetrics& f : frames) {
    psnr.push_back(f.psnr);
    ssim.push_back(f.ssim);
    psnr_tissue.push_back(f.psnr_tissue);
    ssim_tissue.push_back(f.ssim_tissue);
    per_frame.push_back(ToJson(f));
  }
  return {{"psnr", ToJson(Summarise(psnr))},
          {"ssim", ToJson(Summarise(ssim))},
          {"psnr_tissue", ToJson(Summarise(psnr_tissue))},
          {"ssim_tissue", ToJson(Summarise(ssim_tissue))},
          {"per_frame", std::move(per_frame)}};
}

}  // namespace endorecon::eval
