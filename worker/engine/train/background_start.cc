// GCC 12 reports a false "maybe uninitialized" inside its own AVX-512 intrinsics when Eigen's
// products are inlined here (as in field/mlp.cc); silenced for this file.
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include "worker/engine/train/background_start.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "worker/engine/field/background_math.h"
#include "worker/engine/scene/view_geometry.h"

namespace endorecon::train {

void FitBackgroundToBorders(const scene::Clip& clip, const std::vector<int>& frames, float* params) {
  constexpr int kDims = field::kShDims;
  const int w = clip.width, h = clip.height;
  std::vector<int> ring;
  for (int u = 0; u < w; ++u) ring.insert(ring.end(), {u, (h - 1) * w + u});
  for (int v = 1; v + 1 < h; ++v) ring.insert(ring.end(), {v * w, v * w + w - 1});
  // One row per border pixel: its rays' SH features and the logits of its colour.
  const Eigen::Index rows = Eigen::Index(frames.size() * ring.size());
  Eigen::MatrixXd features(rows, kDims), logits(rows, 3);
  Eigen::Index row = 0;
  for (const int f : frames) {
    const scene::PinholeView view = clip.cameras[f].View();
    for (const int pixel : ring) {
      double origin[3], direction[3], d[3];
      scene::PixelRay(view, pixel, origin, direction);
      scene::UnitDirection(direction, d);
      double sh[kDims];
      field::ShEncode(d, sh);
      for (int k = 0; k < kDims; ++k) features(row, k) = sh[k];
      for (int c = 0; c < 3; ++c) {
        const double colour = std::clamp(clip.rgb[f][3 * std::size_t(pixel) + c] / 255.0, 0.02, 0.98);
        logits(row, c) = std::log(colour / (1 - colour));
      }
      ++row;
    }
  }
  // Least squares, reweighted three times so border pixels the backdrop does not explain (the object
  // reaching the frame's edge) count as an L1 fit would count them: weight 1 / max(|residual|, 0.1).
  // The ridge keeps bands no border ray constrains (directions never seen) near zero.
  Eigen::VectorXd weights = Eigen::VectorXd::Ones(rows);
  Eigen::MatrixXd fit = Eigen::MatrixXd::Zero(kDims, 3);
  for (int round = 0; round < 4; ++round) {
    const Eigen::MatrixXd weighted = features.array().colwise() * weights.array();
    Eigen::MatrixXd normal = weighted.transpose() * features;
    const double ridge = 1e-3 * std::max(normal.trace() / kDims, 1e-12);
    normal.diagonal().array() += ridge;
    fit = normal.ldlt().solve(weighted.transpose() * logits);
    const Eigen::VectorXd residual = (features * fit - logits).cwiseAbs().rowwise().maxCoeff();
    weights = residual.cwiseMax(0.1).cwiseInverse();
  }
  for (int k = 0; k < kDims; ++k) {
    for (int c = 0; c < 3; ++c) params[3 * k + c] = static_cast<float>(fit(k, c));
  }
}

}  // namespace endorecon::train
