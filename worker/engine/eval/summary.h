// Aggregates of one metric over the frames of a clip, as metrics.json reports them.
#pragma once

#include <initializer_list>
#include <nlohmann/json_fwd.hpp>
#include <span>

namespace endorecon::eval {

struct Summary {
  double mean = 0, std = 0, min = 0, max = 0;  // NaN when count == 0
  int count = 0;                               // how many values were defined (finite)
};

// Mean, population standard deviation (divides by count, as numpy's default), min and max of the
// finite values; NaN and Inf mark a metric undefined on that frame (e.g. PSNR of an all-tool frame)
// and are left out, so `count` says how many frames the numbers rest on.
Summary Summarise(std::span<const double> values);

// {"mean", "std", "min", "max", "count"}; undefined numbers serialise as null.
nlohmann::json ToJson(const Summary& summary);

// Per-frame metrics objects and their summaries side by side: {"<key>": ToJson(Summary of
// per_frame[i][key]) for each key, "per_frame": per_frame}. A key that is missing, null or not a
// number on a frame counts as undefined there.
nlohmann::json SummariseFrames(nlohmann::json per_frame, std::initializer_list<const char*> keys);

}  // namespace endorecon::eval
