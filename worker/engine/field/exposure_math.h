// Per-sample math of the exposure module (exposure.h), shared by the CPU module and the CUDA kernels:
// a camera's gain changes from frame to frame (auto exposure, a flickering light source) while the
// tissue's colour does not, so the field's colour c is the tissue's and a sample at time t is seen as
// exp(a(t)) * c per channel, a(t) piecewise linear between knots at the training frames' times (one
// log-gain per channel per knot). A time on a knot (a training frame) gets that knot's gains; a time
// no frame was trained at (a held-out frame) the best guess the knots allow: between two knots their
// blend, outside them the end knot's, shrunk toward the mean log-gain by rho, the correlation of
// neighbouring knots' log-gains (ExposurePrior), so a drifting exposure is followed (rho near 1) and
// a flicker independent from frame to frame is predicted by its mean (rho near 0), which is closer to
// the held-out frame's gain than its neighbours' blend or the last frame's own. The gradients include the
// prior's (through every knot), so the module differentiates exactly.
#pragma once

#include <cmath>

#include "common/hd.h"

namespace endorecon::field {

// The knots around t: *k0 and *k1 = *k0 + 1 (both 0 with one knot) and the weight *w of k1. Knot
// times ascend; NaN reads as the first knot.
template <typename S>
ENDORECON_HD void ExposureKnots(const float* times, int knots, S t, int* k0, int* k1, S* w) {
  *w = S(0);
  *k0 = *k1 = 0;
  if (knots < 2 || !(t > S(times[0]))) return;
  if (t >= S(times[knots - 1])) {
    *k0 = *k1 = knots - 1;
    return;
  }
  int lo = 0, hi = knots - 1;  // times[lo] < t < times[hi]... or equal at lo
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    if (S(times[mid]) <= t) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  *k0 = lo;
  *k1 = hi;
  *w = (t - S(times[lo])) / (S(times[hi]) - S(times[lo]));
}

// The prior of times off the knots, from the log-gains: prior[0..3) the mean log-gain per channel,
// prior[3] rho in [0, 1] (the lag-1 correlation of the centred log-gains, knots in time order, the
// channels pooled; 1 while they are all equal, as at the start).
inline constexpr int kExposurePriorSize = 4;

template <typename S>
ENDORECON_HD void ExposurePrior(const S* params, int knots, S* prior) {
  for (int c = 0; c < 3; ++c) {
    S sum = 0;
    for (int k = 0; k < knots; ++k) sum += params[3 * k + c];
    prior[c] = sum / S(knots);
  }
  S lag = 0, var = 0;
  for (int k = 0; k < knots; ++k) {
    for (int c = 0; c < 3; ++c) {
      const S x = params[3 * k + c] - prior[c];
      var += x * x;
      if (k + 1 < knots) lag += x * (params[3 * (k + 1) + c] - prior[c]);
    }
  }
  const S rho = var > S(1e-12) ? lag / var : S(1);
  prior[3] = rho < S(0) ? S(0) : (rho > S(1) ? S(1) : rho);
}

// The log-gain of channel c at time t from the knots' blend (ExposureKnots): the knot's own on a knot,
// shrunk toward the mean at a time off the knots, between them or outside (`unseen` says which).
template <typename S>
ENDORECON_HD S ExposureLogGain(const S* params, const S* prior, const float* times, S t, int k0, int k1, S w,
                               int c, bool* unseen) {
  const S blend = (S(1) - w) * params[3 * k0 + c] + w * params[3 * k1 + c];
  *unseen = k1 != k0 ? w > S(0) : !(static_cast<float>(t) == times[k0]);  // knot times are floats
  return *unseen ? prior[c] + prior[3] * (blend - prior[c]) : blend;
}

// gain[c] = exp(a(t)) per channel; prior from ExposurePrior.
template <typename S>
ENDORECON_HD void ExposureGains(const S* params, const S* prior, const float* times, int knots, S t,
                                S* gain) {
  int k0, k1;
  S w;
  ExposureKnots(times, knots, t, &k0, &k1, &w);
  for (int c = 0; c < 3; ++c) {
    bool unseen;
    gain[c] = std::exp(ExposureLogGain(params, prior, times, t, k0, k1, w, c, &unseen));
  }
}

// rgb_out = gain(t) * rgb_in, per channel (rgb_out may be rgb_in); prior from ExposurePrior.
template <typename S>
ENDORECON_HD void ExposureSample(const S* params, const S* prior, const float* times, int knots, S t,
                                 const S* rgb_in, S* rgb_out) {
  S gain[3];
  ExposureGains(params, prior, times, knots, t, gain);
  for (int c = 0; c < 3; ++c) rgb_out[c] = gain[c] * rgb_in[c];
}

// From drgb_out = dL/d(rgb_out): WRITES dL/d(rgb_in) to drgb_in (when not null), adds dL/d(log-gain)
// of the two knots to dparams and, for a time off the knots, dL/d(prior) to dprior (4 values; chained
// to the log-gains by ExposurePriorBackward once the batch is done), through add(pointer, value)
// (PlainAdd on the CPU, atomic in kernels).
template <typename S, typename Add>
ENDORECON_HD void ExposureSampleBackward(const S* params, const S* prior, const float* times, int knots, S t,
                                         const S* rgb_in, const S* drgb_out, S* drgb_in, S* dparams,
                                         S* dprior, const Add& add) {
  int k0, k1;
  S w;
  ExposureKnots(times, knots, t, &k0, &k1, &w);
  for (int c = 0; c < 3; ++c) {
    bool unseen;
    const S log_gain = ExposureLogGain(params, prior, times, t, k0, k1, w, c, &unseen);
    const S gain = std::exp(log_gain);
    const S g = drgb_out[c] * rgb_in[c] * gain;  // dL/d(log-gain)
    if (drgb_in) drgb_in[c] = drgb_out[c] * gain;
    S d_blend = g;
    if (unseen) {
      const S blend = (S(1) - w) * params[3 * k0 + c] + w * params[3 * k1 + c];
      d_blend = prior[3] * g;
      add(dprior + c, (S(1) - prior[3]) * g);
      add(dprior + 3, (blend - prior[c]) * g);
    }
    add(dparams + 3 * k0 + c, (S(1) - w) * d_blend);
    if (k1 != k0) add(dparams + 3 * k1 + c, w * d_blend);
  }
}

// Adds to dparams what dL/d(prior) (dprior, 4 values) says of the log-gains: the means' share to
// every knot, and rho's through the centred log-gains (nothing where ExposurePrior clamped rho or
// found it undefined, i.e. where prior[3] is 0 or 1).
template <typename S>
ENDORECON_HD void ExposurePriorBackward(const S* params, int knots, const S* prior, const S* dprior,
                                        S* dparams) {
  for (int k = 0; k < knots; ++k) {
    for (int c = 0; c < 3; ++c) dparams[3 * k + c] += dprior[c] / S(knots);
  }
  const S rho = prior[3];
  if (!(rho > S(0) && rho < S(1)) || dprior[3] == S(0)) return;
  const auto x = [&](int k, int c) { return params[3 * k + c] - prior[c]; };
  S var = 0;
  for (int k = 0; k < knots; ++k) {
    for (int c = 0; c < 3; ++c) var += x(k, c) * x(k, c);
  }
  // d rho / d x_k = (x_{k-1} + x_{k+1} - 2 rho x_k) / var. The centring takes each channel's mean of
  // these out; as the centred values sum to 0, that mean is -(x_0 + x_{K-1}) / (K var).
  for (int c = 0; c < 3; ++c) {
    const S mean = -(x(0, c) + x(knots - 1, c)) / (S(knots) * var);
    for (int k = 0; k < knots; ++k) {
      const S dx =
          ((k > 0 ? x(k - 1, c) : S(0)) + (k + 1 < knots ? x(k + 1, c) : S(0)) - S(2) * rho * x(k, c)) / var;
      dparams[3 * k + c] += dprior[3] * (dx - mean);
    }
  }
}

}  // namespace endorecon::field
