#include "worker/engine/eval/evaluation_mask.h"

namespace endorecon::eval {

const std::vector<std::uint8_t>& EvaluationMask(const scene::Clip& clip, int frame) {
  static const std::vector<std::uint8_t> kNone;
  if (!clip.eval_mask.empty()) return clip.eval_mask[frame];
  if (!clip.tool_mask.empty()) return clip.tool_mask[frame];
  return kNone;
}

}  // namespace endorecon::eval
