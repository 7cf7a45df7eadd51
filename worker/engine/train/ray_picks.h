// Which (frame, pixel) a training ray comes from, as ENDORECON_HD functions over plain tables, so the
// CPU trainer and the CUDA kernels draw the same rays for a seed: by EndoNeRF's tool-mask importance
// (RaySampler) or in proportion to the uncertainty map's cell scores (UncertaintyMap).
#pragma once

#include <cstdint>

#include "common/hd.h"
#include "worker/engine/base/counter_rng.h"

namespace endorecon::train {

struct RayPick {
  int frame = 0;
  int pixel = 0;  // row-major index y * width + x
};

// The mask-importance tables: the frames rays may come from, each pixel's weight in [1, 2] (how often
// it is tool across the clip; null without masks) and each clip frame's tool mask (1 = tool; null
// without masks).
struct PickTables {
  const int* frames = nullptr;
  int frame_count = 0;
  int width = 0, height = 0;
  const float* occlusion = nullptr;
  const std::uint8_t* const* masks = nullptr;
};

// A pixel's weight: 0 on tool pixels, else its occlusion weight (1 without masks).
ENDORECON_HD float PixelWeight(const PickTables& t, int frame, int pixel) {
  if (t.occlusion == nullptr) return 1.0f;
  return t.masks[frame][pixel] ? 0.0f : t.occlusion[pixel];
}

// A pick that is a pure function of (seed, stream), by rejection against the bound 2: every frame in
// the table has a tissue pixel, so it ends.
ENDORECON_HD RayPick PickRay(const PickTables& t, std::uint64_t seed, std::uint64_t stream) {
  const base::CounterRng<double> uniform(seed, stream);
  const int pixels = t.width * t.height;
  RayPick pick;
  for (unsigned draw = 0;; draw += 3) {
    const int f = static_cast<int>(uniform(draw) * t.frame_count);
    pick.frame = t.frames[f < t.frame_count - 1 ? f : t.frame_count - 1];
    const int p = static_cast<int>(uniform(draw + 1) * pixels);
    pick.pixel = p < pixels - 1 ? p : pixels - 1;
    if (uniform(draw + 2) * 2.0 < PixelWeight(t, pick.frame, pick.pixel)) return pick;
  }
}

// The uncertainty map's tables: per cell its probe (pixel -1: no tissue) and the inclusive prefix sums
// of the usable scores; frames are cut into cells_x x cells_y cells of stride x stride pixels.
struct MapTables {
  const RayPick* probes = nullptr;
  const double* cumulative = nullptr;
  int cells = 0;
  double total = 0;
  int stride = 1, cells_x = 1, cells_y = 1;
};

// A pick in proportion to the cell scores, then a tissue pixel of the cell uniformly (the probe after
// 32 rejected draws); false when no cell has a positive score.
ENDORECON_HD bool PickFromMap(const MapTables& map, const PickTables& t, std::uint64_t seed,
                              std::uint64_t stream, RayPick* pick) {
  if (!(map.total > 0)) return false;
  const base::CounterRng<double> uniform(seed, stream);
  const double target = uniform(0) * map.total;
  int lo = 0, hi = map.cells;  // the first cell whose prefix sum exceeds target
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (map.cumulative[mid] > target) {
      hi = mid;
    } else {
      lo = mid + 1;
    }
  }
  const int cell = lo < map.cells - 1 ? lo : map.cells - 1;
  const RayPick probe = map.probes[cell];
  const int in_frame = cell % (map.cells_x * map.cells_y);
  const int x0 = (in_frame % map.cells_x) * map.stride, y0 = (in_frame / map.cells_x) * map.stride;
  const int x1 = x0 + map.stride < t.width ? x0 + map.stride : t.width;
  const int y1 = y0 + map.stride < t.height ? y0 + map.stride : t.height;
  const int w = x1 - x0, h = y1 - y0;
  for (unsigned draw = 1; draw < 1 + 2 * 32; draw += 2) {
    const int dx = static_cast<int>(uniform(draw) * w), dy = static_cast<int>(uniform(draw + 1) * h);
    const int pixel = (y0 + (dy < h - 1 ? dy : h - 1)) * t.width + x0 + (dx < w - 1 ? dx : w - 1);
    if (PixelWeight(t, probe.frame, pixel) > 0) {
      *pick = RayPick{probe.frame, pixel};
      return true;
    }
  }
  *pick = probe;
  return true;
}

}  // namespace endorecon::train
