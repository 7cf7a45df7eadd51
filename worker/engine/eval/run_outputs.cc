#include "worker/engine/eval/run_outputs.h"

#include <cmath>
#include <vector>

#include "common/file_write.h"
#include "worker/engine/eval/curve_plot.h"

namespace endorecon::eval {

void WriteMetrics(const std::filesystem::path& path, const nlohmann::json& metrics) {
  WriteFile(path, metrics.dump(2), "metrics");
}

void WriteCurve(const std::filesystem::path& path, const nlohmann::json& curve) {
  std::vector<CurveSeries> series(2);
  series[0].label = "held-out PSNR (tissue)";
  series[1].label = "training PSNR (batch)";
  series[1].dashed = true;
  for (const auto& point : curve) {
    const double seconds = point.at("seconds").get<double>();
    series[0].seconds.push_back(seconds);
    series[0].psnr.push_back(point.contains("heldout_psnr") ? point.at("heldout_psnr").get<double>() : NAN);
    series[1].seconds.push_back(seconds);
    series[1].psnr.push_back(point.at("train_psnr").get<double>());
  }
  WriteCurveSvg(path, series);
}

}  // namespace endorecon::eval
