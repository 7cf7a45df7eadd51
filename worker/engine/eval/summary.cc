#include "worker/engine/eval/summary.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <vector>

namespace endorecon::eval {

Summary Summarise(std::span<const double> values) {
  Summary s;
  double sum = 0;
  s.min = std::numeric_limits<double>::infinity();
  s.max = -std::numeric_limits<double>::infinity();
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    sum += v;
    s.min = std::min(s.min, v);
    s.max = std::max(s.max, v);
    ++s.count;
  }
  if (s.count == 0) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan, nan, 0};
  }
  s.mean = sum / s.count;
  double squares = 0;
  for (double v : values) {
    if (std::isfinite(v)) squares += (v - s.mean) * (v - s.mean);
  }
  s.std = std::sqrt(squares / s.count);
  return s;
}

nlohmann::json ToJson(const Summary& summary) {
  return {{"mean", summary.mean},
          {"std", summary.std},
          {"min", summary.min},
          {"max", summary.max},
          {"count", summary.count}};
}

nlohmann::json SummariseFrames(nlohmann::json per_frame, std::initializer_list<const char*> keys) {
  nlohmann::json out = nlohmann::json::object();
  for (const char* key : keys) {
    std::vector<double> values;
    for (const nlohmann::json& frame : per_frame) {
      const auto it = frame.find(key);
      values.push_back(it != frame.end() && it->is_number() ? it->get<double>()
                                                            : std::numeric_limits<double>::quiet_NaN());
    }
    out[key] = ToJson(Summarise(values));
  }
  out["per_frame"] = std::move(per_frame);
  return out;
}

}  // namespace endorecon::eval
