// The parallel loops the field's modules run over a batch: fixed splits (they depend on the batch size
// only, never on the thread count) and per-task partial gradients added in task order, so a fixed
// seed gives bit-equal results on any number of threads.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <vector>

namespace endorecon::field {

// Rows of the heads' and the blend's tiles: a tile's activations stay in L1/L2 between layers.
inline constexpr int kTileRows = 512;
// Rows of one task of a module's loop: a grid walks its levels over a task, so a level's table is
// pulled into L2 once and reused by ~16k lookups; a task's partial gradient serves 4 tiles.
inline constexpr int kTaskRows = 2048;

// Every buffer starts on a cache line, so the vector kernels (Eigen's GEMMs) take the same path
// whatever addresses the allocator hands out: a fixed seed on one thread gives bit-equal results.
template <typename S>
using AlignedVector = std::vector<S, Eigen::aligned_allocator<S>>;

template <typename S>
void GrowTo(AlignedVector<S>& v, std::size_t size) {
  if (v.size() < size) v.resize(size);
}

inline int TaskCount(int n, int task_rows) { return (n + task_rows - 1) / task_rows; }

// Calls fn(task, row0, rows) for the tasks of `task_rows` rows that cover [0, n), in parallel.
template <typename Fn>
void ParallelTasks(int n, int task_rows, Fn&& fn) {
  const int tasks = TaskCount(n, task_rows);
  if (tasks == 1) return fn(0, 0, n);  // the field's segments and tiles: no task to hand out
  tbb::parallel_for(tbb::blocked_range<int>(0, tasks, 1), [&](const tbb::blocked_range<int>& r) {
    for (int t = r.begin(); t != r.end(); ++t) fn(t, t * task_rows, std::min(task_rows, n - t * task_rows));
  });
}

// fn(i) for every row i of a batch of n (a std::size_t), in parallel tasks of kTaskRows rows.
template <typename Fn>
void ParallelRows(int n, Fn&& fn) {
  ParallelTasks(n, kTaskRows, [&](int, int row0, int rows) {
    for (int i = row0; i < row0 + rows; ++i) fn(static_cast<std::size_t>(i));
  });
}

// Calls fn(offset, rows) for the tiles of kTileRows rows of a task of `rows` rows, in order.
template <typename Fn>
void ForTiles(int rows, Fn&& fn) {
  for (int t = 0; t < rows; t += kTileRows) fn(t, std::min(kTileRows, rows - t));
}

// One zeroed partial gradient block per task, added into the module's gradient in task order.
template <typename S>
class TaskPartials {
 public:
  // Makes `tasks` zeroed blocks of `size` values.
  void Reset(int tasks, std::size_t size) {
    size_ = size;
    tasks_ = tasks;
    GrowTo(values_, static_cast<std::size_t>(tasks) * size);
    std::fill_n(values_.begin(), static_cast<std::size_t>(tasks) * size, S(0));
  }
  S* task(int t) { return values_.data() + static_cast<std::size_t>(t) * size_; }

  // dst[i] += sum over tasks, in task order, for every i (in parallel over i).
  void AddTo(S* dst) const {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, size_, 1024), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        S sum = dst[i];
        for (int t = 0; t < tasks_; ++t) sum += values_[static_cast<std::size_t>(t) * size_ + i];
        dst[i] = sum;
      }
    });
  }

 private:
  AlignedVector<S> values_;
  std::size_t size_ = 0;
  int tasks_ = 0;
};

}  // namespace endorecon::field
