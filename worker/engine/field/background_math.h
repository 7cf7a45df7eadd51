// Per-ray math of the learned background (background.h), shared by the CPU module, the training step
// (train/step_math.h) and the CUDA kernels: what a ray sees past its samples as a function of its unit
// direction d alone (light from far away: a studio backdrop, a room, a sky),
//   bg_c(d) = sigmoid(sum_k p[3 k + c] Y_k(d)),   k < 16 real spherical harmonics up to band 3,
// 48 parameters. Band 3 resolves a backdrop's broad gradients and a bright window's lobe, not its
// edges; the sigmoid keeps every colour in (0, 1) as the colour head's.
#pragma once

#include "common/hd.h"
#include "worker/engine/field/activations.h"
#include "worker/engine/field/sh_encoding.h"

namespace endorecon::field {

inline constexpr int kBackgroundParams = 3 * kShDims;

// rgb = bg(dir); dir a unit vector.
template <typename S>
ENDORECON_HD void BackgroundSample(const S* params, const S* dir, S* rgb) {
  S sh[kShDims];
  ShEncode(dir, sh);
  for (int c = 0; c < 3; ++c) {
    S logit = 0;
    for (int k = 0; k < kShDims; ++k) logit += params[3 * k + c] * sh[k];
    rgb[c] = Sigmoid(logit);
  }
}

// From rgb = bg(dir) (BackgroundSample's output) and drgb = dL/d(rgb): adds dL/dparams through
// add(pointer, value) (PlainAdd on the CPU, atomic in kernels).
template <typename S, typename Add>
ENDORECON_HD void BackgroundSampleBackward(const S* dir, const S* rgb, const S* drgb, S* dparams,
                                           const Add& add) {
  S sh[kShDims];
  ShEncode(dir, sh);
  for (int c = 0; c < 3; ++c) {
    const S dlogit = drgb[c] * rgb[c] * (S(1) - rgb[c]);
    if (dlogit == S(0)) continue;
    for (int k = 0; k < kShDims; ++k) add(dparams + 3 * k + c, dlogit * sh[k]);
  }
}

}  // namespace endorecon::field
