// Empty-space skipping (issue 3 §6): which cells of the field's unit box may hold density at some
// time of the clip, so samplers spend their stratified samples only where something can be.
//
// Built from the field itself: the density at every cell centre at a set of times; a cell is
// occupied where that density would make a sample one cell long at least min_alpha opaque; then the
// occupied set is dilated by one cell in every direction, so a thin surface passing between two
// probes still marks the cells around it (behind a surface the density the field never had to lower
// is occupied too). A ray's occupied span is the part of [near, far] from its first to its last
// occupied cell, with a cell's margin; the stratified samples go there instead of over [near, far].
// What is skipped had alpha below min_alpha per cell length at every probed time, so the rendered
// colour, depth and opacity change by at most that much per skipped cell. Held-out frames and novel
// views can use it: it is a property of the trained field, not of any frame's depth prior.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <vector>

#include "common/hd.h"
#include "worker/engine/field/field.h"
#include "worker/engine/scene/scene_box.h"
#include "worker/engine/scene/view_geometry.h"

namespace endorecon::render {

// Cell of a point in [0, 1)^3 normalised box coordinates at `res` cells per axis; -1 outside.
ENDORECON_HD int OccupancyCell(const float* pos, int res) {
  int index = 0;
  for (int c = 2; c >= 0; --c) {
    const float x = pos[c];
    if (!(x >= 0.0f && x < 1.0f)) return -1;
    const int i = static_cast<int>(x * static_cast<float>(res));
    index = index * res + (i < res ? i : res - 1);
  }
  return index;
}

// [*lo, *hi]: the part of [near, far] whose points start + s * step (normalised box coordinates per
// unit z-depth s, as RayPoints) lie in occupied cells, widened by one marching step each way. Marches
// in steps of at most half a cell. When no point is occupied the whole [near, far] is returned: the
// grid is only ever trusted to shorten a ray, never to empty it.
ENDORECON_HD void OccupiedSpan(const std::uint8_t* occupied, int res, const double* start, const double* step,
                               double near, double far, double* lo, double* hi) {
  double fastest = 0;
  for (int c = 0; c < 3; ++c)
    fastest = step[c] > fastest ? step[c] : (-step[c] > fastest ? -step[c] : fastest);
  const double ds = fastest > 0 ? 0.5 / (res * fastest) : (far - near);
  double first = -1, last = -1;
  for (double s = near; s <= far + 0.5 * ds; s += ds) {
    const double z = s < far ? s : far;
    const float p[3] = {static_cast<float>(start[0] + z * step[0]),
                        static_cast<float>(start[1] + z * step[1]),
                        static_cast<float>(start[2] + z * step[2])};
    const int cell = OccupancyCell(p, res);
    if (cell < 0 || !occupied[cell]) continue;
    if (first < 0) first = z;
    last = z;
  }
  if (first < 0) {
    *lo = near;
    *hi = far;
    return;
  }
  *lo = first - ds > near ? first - ds : near;
  *hi = last + ds < far ? last + ds : far;
}

// OccupiedSpan of the ray origin + s * direction (scene units, direction with unit z-depth) in the box.
ENDORECON_HD void RaySpan(const std::uint8_t* occupied, int res, const scene::BoxFrame& box,
                          const double* origin, const double* direction, double near, double far, double* lo,
                          double* hi) {
  double start[3], step[3];
  for (int c = 0; c < 3; ++c) {
    start[c] = (origin[c] - box.min[c]) * box.inv_size[c];
    step[c] = direction[c] * box.inv_size[c];
  }
  OccupiedSpan(occupied, res, start, step, near, far, lo, hi);
}

// The times a grid is probed at: one for a static field, else 8 evenly spaced over [0, 1]. They need
// not land on the deformation's time knots (12 in the cpu preset): between probes the one-cell
// dilation covers the motion (measured with 8 and 12 knots, docs/benchmarks.md "Twelve time knots").
std::vector<float> OccupancyProbeTimes(bool dynamic);

// The field's density (sigma, n) at a batch of points in host memory, wherever the field's
// parameters live (the host field, or a GPU's copy through the trainer's step backend).
using DensityProbe = std::function<void(const field::SampleBatch& batch, float* sigma)>;

// The host field's density (the field must outlive the probe).
DensityProbe HostDensity(field::Field& field);

class OccupancyGrid {
 public:
  OccupancyGrid() = default;  // empty: every span is the whole ray

  // Probes the density at every cell centre of a res^3 grid at each of `times` (a static field needs
  // one). Throws Error(kInvalidArgument) for res < 1, an empty time list or min_alpha outside (0, 1).
  static OccupancyGrid Build(const DensityProbe& density, const std::vector<float>& times, int res,
                             float min_alpha);
  static OccupancyGrid Build(field::Field& field, const std::vector<float>& times, int res, float min_alpha) {
    return Build(HostDensity(field), times, res, min_alpha);
  }

  bool empty() const { return res_ == 0; }
  int resolution() const { return res_; }
  const std::uint8_t* cells() const { return cells_.data(); }  // res^3, x fastest; 1 = occupied
  double occupied_fraction() const;

  // OccupiedSpan of the ray origin + s * direction (scene units, direction with unit z-depth, as
  // scene::Camera::Ray gives) in `box`; [near, far] itself for an empty grid.
  void Span(const scene::SceneBox& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
            double near, double far, double* lo, double* hi) const;

  void Save(std::ostream& out) const;
  void Load(std::istream& in);  // Error(kDataLoss) for a truncated or inconsistent stream

 private:
  int res_ = 0;
  std::vector<std::uint8_t> cells_;
};

}  // namespace endorecon::render
