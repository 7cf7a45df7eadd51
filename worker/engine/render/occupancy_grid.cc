#include "worker/engine/render/occupancy_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <istream>
#include <ostream>

#include "common/error.h"

namespace endorecon::render {
namespace {

// One cell of dilation along axis `axis` (a max filter of width 3), in place through a copy.
void DilateAxis(std::vector<std::uint8_t>& cells, int res, int axis) {
  const std::vector<std::uint8_t> in = cells;
  const std::size_t stride = axis == 0 ? 1 : axis == 1 ? std::size_t(res) : std::size_t(res) * res;
  tbb::parallel_for(0, res, [&](int z) {
    for (int y = 0; y < res; ++y) {
      for (int x = 0; x < res; ++x) {
        const std::size_t i = (std::size_t(z) * res + y) * res + x;
        const int at = axis == 0 ? x : axis == 1 ? y : z;
        std::uint8_t v = in[i];
        if (at > 0) v |= in[i - stride];
        if (at + 1 < res) v |= in[i + stride];
        cells[i] = v;
      }
    }
  });
}

}  // namespace

std::vector<float> OccupancyProbeTimes(bool dynamic) {
  if (!dynamic) return {0.0f};
  constexpr int kTimes = 8;
  std::vector<float> times(kTimes);
  for (int i = 0; i < kTimes; ++i) times[i] = float(i) / float(kTimes - 1);
  return times;
}

DensityProbe HostDensity(field::Field& field) {
  return [&field, log_var = std::vector<float>()](const field::SampleBatch& batch, float* sigma) mutable {
    log_var.resize(std::size_t(batch.n));
    field::FieldOutput out{sigma, log_var.data(), nullptr, nullptr};  // the density alone
    field.Infer(batch, out, /*dropout=*/false, 0);
  };
}

OccupancyGrid OccupancyGrid::Build(const DensityProbe& density, const std::vector<float>& times, int res,
                                   float min_alpha) {
  if (res < 1 || times.empty() || !(min_alpha > 0.0f && min_alpha < 1.0f)) {
    FailInvalid("occupancy grid: need a resolution >= 1, at least one time and min_alpha in (0, 1); got " +
                std::to_string(res) + ", " + std::to_string(times.size()) + " times, " +
                std::to_string(min_alpha));
  }
  OccupancyGrid grid;
  grid.res_ = res;
  const std::size_t cells = std::size_t(res) * res * res;
  grid.cells_.assign(cells, 0);
  // Densities are per box length and a cell is at most 1/res of it: alpha over one cell >= min_alpha
  // needs sigma >= -ln(1 - min_alpha) * res.
  const float min_sigma = -std::log1p(-min_alpha) * float(res);
  constexpr std::size_t kBatch = 1 << 16;
  std::vector<float> pos(3 * kBatch), time(kBatch), dir(3 * kBatch), sigma(kBatch);
  for (std::size_t i = 0; i < kBatch; ++i) {
    dir[3 * i] = dir[3 * i + 1] = 0.0f;
    dir[3 * i + 2] = 1.0f;  // density does not depend on the view direction
  }
  for (float t : times) {
    std::fill(time.begin(), time.end(), t);
    for (std::size_t first = 0; first < cells; first += kBatch) {
      const std::size_t n = std::min(kBatch, cells - first);
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t cell = first + i;
        pos[3 * i] = (float(cell % res) + 0.5f) / float(res);
        pos[3 * i + 1] = (float((cell / res) % res) + 0.5f) / float(res);
        pos[3 * i + 2] = (float(cell / (std::size_t(res) * res)) + 0.5f) / float(res);
      }
      density(field::SampleBatch{int(n), pos.data(), time.data(), dir.data()}, sigma.data());
      for (std::size_t i = 0; i < n; ++i) {
        // NaN counts as occupied: never skip what cannot be judged.
        if (!(sigma[i] < min_sigma)) grid.cells_[first + i] = 1;
      }
    }
  }
  for (int axis = 0; axis < 3; ++axis) DilateAxis(grid.cells_, res, axis);
  return grid;
}

double OccupancyGrid::occupied_fraction() const {
  if (cells_.empty()) return 1.0;
  return double(std::count(cells_.begin(), cells_.end(), std::uint8_t(1))) / double(cells_.size());
}

void OccupancyGrid::Span(const scene::SceneBox& box, const Eigen::Vector3d& origin,
                         const Eigen::Vector3d& direction, double near, double far, double* lo,
                         double* hi) const {
  if (empty()) {
    *lo = near;
    *hi = far;
    return;
  }
  RaySpan(cells_.data(), res_, box.Frame(), origin.data(), direction.data(), near, far, lo, hi);
}

void OccupancyGrid::Save(std::ostream& out) const {
  const std::int32_t res = res_;
  out.write(reinterpret_cast<const char*>(&res), sizeof(res));
  out.write(reinterpret_cast<const char*>(cells_.data()), std::streamsize(cells_.size()));
}

void OccupancyGrid::Load(std::istream& in) {
  std::int32_t res = 0;
  in.read(reinterpret_cast<char*>(&res), sizeof(res));
  if (!in || res < 0 || res > 1024) Fail(ErrorCode::kDataLoss, "checkpoint: bad occupancy grid header");
  std::vector<std::uint8_t> cells(std::size_t(res) * res * res);
  in.read(reinterpret_cast<char*>(cells.data()), std::streamsize(cells.size()));
  if (!in) Fail(ErrorCode::kDataLoss, "checkpoint: truncated inside the occupancy grid");
  res_ = res;
  cells_ = std::move(cells);
}

}  // namespace endorecon::render
