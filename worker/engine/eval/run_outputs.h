// The files that describe a whole run beside its per-frame results: metrics.json and curve.svg (the
// error-against-run-time curve). Every write is checked and fails naming the file (file_write.h).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

namespace endorecon::eval {

// `metrics` as indented JSON at `path`.
void WriteMetrics(const std::filesystem::path& path, const nlohmann::json& metrics);

// The curve's points ({"seconds", "train_psnr", optional "heldout_psnr"}) as held-out and training
// PSNR against seconds on a log axis (curve_plot.h).
void WriteCurve(const std::filesystem::path& path, const nlohmann::json& curve);

}  // namespace endorecon::eval
