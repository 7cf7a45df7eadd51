// The results' evaluation plan: every frame full when that fits, else held-out frames full, training
// frames reduced (stride 2, then 4, then 8 on large frames) and as many promoted back to full as the time
// left allows; and the pacer that keeps a run to its deadline when the plan's prices prove low.
#include "worker/engine/eval/eval_plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

namespace endorecon::eval {
namespace {

constexpr int kPixels = 1000;
const RenderCost kCost{/*full=*/1e-3, /*plain=*/2e-4};  // a full frame 1 s, a plain pass 0.2 s

int Count(const EvalPlan& plan, FrameRender how) {
  return int(std::count(plan.frames.begin(), plan.frames.end(), how));
}

TEST(EvalPlan, EveryFrameFullWhenItFitsOrWithoutALimit) {
  for (double available : {0.0, 10.0, 50.0}) {
    const EvalPlan plan = PlanEvaluation(10, {4, 9}, kPixels, kCost, available);
    EXPECT_TRUE(plan.all_full()) << available;
    EXPECT_NEAR(plan.seconds, 10.0, 1e-9);
  }
  EXPECT_TRUE(PlanEvaluation(10, {4, 9}, kPixels, RenderCost{}, 1.0).all_full()) << "cost unknown";
}

TEST(EvalPlan, HeldOutFullTrainingReducedAndPromotedWithinTheTime) {
  // Reduced at stride 2: 0.2 + 1/4 = 0.45 s. Base: 2 full + 8 reduced = 5.6 s; 7 s promotes 2 frames.
  const EvalPlan plan = PlanEvaluation(10, {4, 9}, kPixels, kCost, 7.0);
  EXPECT_EQ(plan.stride, 2);
  EXPECT_EQ(plan.at(4), FrameRender::kFull);
  EXPECT_EQ(plan.at(9), FrameRender::kFull);
  EXPECT_EQ(Count(plan, FrameRender::kFull), 4);
  EXPECT_NEAR(plan.seconds, 5.6 + 2 * 0.55, 1e-9);
  EXPECT_LE(plan.seconds, 7.0);
  // The promoted ones spread out: not two neighbours at the start.
  std::vector<int> promoted;
  for (int f = 0; f < 10; ++f) {
    if (f != 4 && f != 9 && plan.at(f) == FrameRender::kFull) promoted.push_back(f);
  }
  ASSERT_EQ(promoted.size(), 2u);
  EXPECT_GE(promoted[1] - promoted[0], 3);
}

TEST(EvalPlan, StrideFourWhenTwoDoesNotFitAndHeldOutNeverReduced) {
  // Stride 4: 0.2 + 1/16 = 0.2625 s; base 2 + 8 * 0.2625 = 4.1 s.
  const EvalPlan plan = PlanEvaluation(10, {4, 9}, kPixels, kCost, 4.2);
  EXPECT_EQ(plan.stride, 4);
  EXPECT_EQ(Count(plan, FrameRender::kFull), 2);
  // Not even the held-out frames fit: they stay full, everything else is reduced.
  const EvalPlan late = PlanEvaluation(10, {4, 9}, kPixels, kCost, 0.5);
  EXPECT_EQ(late.stride, 4);
  EXPECT_EQ(late.at(4), FrameRender::kFull);
  EXPECT_EQ(late.at(9), FrameRender::kFull);
  EXPECT_EQ(Count(late, FrameRender::kReduced), 8);
  EXPECT_GT(late.seconds, 0.5);
}

// Large frames may go to stride 8 (its grid still holds kMinStridedPoints); small ones stop at 4.
TEST(EvalPlan, StrideEightOnlyOnFramesLargeEnoughForIt) {
  constexpr int kLarge = 640 * 512;
  const RenderCost cost{/*full=*/1e-3 / kLarge * kPixels, /*plain=*/2e-4 / kLarge * kPixels};  // as kCost
  // Stride 4 gives the 4.1 s of the test above, stride 8: 0.2 + 1/64 = 0.215625 s, base 3.725 s.
  const EvalPlan plan = PlanEvaluation(10, {4, 9}, kLarge, cost, 3.8);
  EXPECT_EQ(plan.stride, 8);
  EXPECT_NEAR(plan.seconds, 2 + 8 * 0.215625, 1e-9);
  EXPECT_EQ(PlanEvaluation(10, {4, 9}, kLarge, cost, 4.2).stride, 4);       // 4 fits: not coarser
  EXPECT_EQ(PlanEvaluation(10, {4, 9}, kLarge - 64, cost, 3.8).stride, 4);  // a grid too small for 8
  EXPECT_EQ(PlanEvaluation(10, {4, 9}, kPixels, kCost, 3.8).stride, 4);
}

// The leanest plan keeping held-out frames full: the price of PlanEvaluation's plan when no time is
// left, held-out frames full (4.1 s above: 2 full, 8 reduced at stride 4); on large frames stride 8.
TEST(EvalPlan, LeastSecondsAreTheLeanestPlansWithHeldOutFramesFull) {
  EXPECT_NEAR(LeastEvaluationSeconds(10, {4, 9}, kPixels, kCost), 2 + 8 * (0.2 + 1.0 / 16), 1e-9);
  EXPECT_NEAR(LeastEvaluationSeconds(10, {4, 9}, kPixels, kCost),
              PlanEvaluation(10, {4, 9}, kPixels, kCost, 1e-9).seconds, 1e-9);
  constexpr int kLarge = 640 * 512;
  const RenderCost cost{1e-3 / kLarge * kPixels, 2e-4 / kLarge * kPixels};  // as kCost per frame
  EXPECT_NEAR(LeastEvaluationSeconds(10, {4, 9}, kLarge, cost), 2 + 8 * 0.215625, 1e-9);
  EXPECT_EQ(LeastEvaluationSeconds(10, {4, 9}, kPixels, RenderCost{}), 0) << "cost unknown";
  EXPECT_NEAR(LeastEvaluationSeconds(10, {4, 9, 12}, kPixels, kCost), 2 + 8 * 0.2625, 1e-9)
      << "a held-out frame past the clip counts for nothing";
}

// The budget that leaves evaluation (and writing) its share, rounded up to 10 s.
TEST(EvalPlan, BudgetForAShareRoundsUpToTenSeconds) {
  EXPECT_EQ(BudgetForEvaluationShare(50, 1, 0.25), 210);
  EXPECT_EQ(BudgetForEvaluationShare(49, 1, 0.25), 200);
  EXPECT_EQ(BudgetForEvaluationShare(0.5, 0, 0.25), 10);
}

// Found by UndefinedBehaviorSanitizer (scripts/test --sanitize address): a run far behind its budget
// with a plain pass costing as much as a full one divided -4 s by a 1e-12 gain and cast -4e12 to int.
TEST(EvalPlan, FarBehindTimeWithNothingToGainPromotesNone) {
  const RenderCost flat{/*full=*/1e-3, /*plain=*/1e-3};
  const EvalPlan plan = PlanEvaluation(10, {4, 9}, kPixels, flat, 1e-3);
  EXPECT_EQ(plan.stride, 4);
  EXPECT_EQ(Count(plan, FrameRender::kFull), 2);
  EXPECT_EQ(Count(plan, FrameRender::kReduced), 8);
  const EvalPlan ahead = PlanEvaluation(10, {4, 9}, kPixels, flat, 1e15);
  EXPECT_TRUE(ahead.all_full());
}

// A budget too small for the clip's frames: held-out frames full would overrun, so with
// HeldOut::kMayReduce they are reduced as well, and promoted back to full as the time allows.
TEST(EvalPlan, HeldOutFramesReducedOnlyWhenAllowedAndTheyDoNotFitFull) {
  // Stride 4: reduced 0.2625 s, all ten 2.625 s; a held-out frame full costs 0.7375 s more.
  const EvalPlan none = PlanEvaluation(10, {4, 9}, kPixels, kCost, 0.5, HeldOut::kMayReduce);
  EXPECT_EQ(none.stride, 4);
  EXPECT_EQ(Count(none, FrameRender::kReduced), 10);
  EXPECT_NEAR(none.seconds, 2.625, 1e-9);
  const EvalPlan one = PlanEvaluation(10, {4, 9}, kPixels, kCost, 3.5, HeldOut::kMayReduce);
  EXPECT_EQ(Count(one, FrameRender::kFull), 1);
  EXPECT_EQ(one.at(4) == FrameRender::kFull || one.at(9) == FrameRender::kFull, true);
  EXPECT_NEAR(one.seconds, 2.625 + 0.7375, 1e-9);
  EXPECT_LE(one.seconds, 3.5);
  // Where the held-out frames fit full beside the rest reduced (4.1 s), they are full either way.
  for (HeldOut held_out : {HeldOut::kFull, HeldOut::kMayReduce}) {
    const EvalPlan fits = PlanEvaluation(10, {4, 9}, kPixels, kCost, 4.2, held_out);
    EXPECT_EQ(fits.at(4), FrameRender::kFull);
    EXPECT_EQ(fits.at(9), FrameRender::kFull);
  }
  // Without leave the held-out frames stay full and the plan overruns (as in the test above).
  EXPECT_EQ(PlanEvaluation(10, {4, 9}, kPixels, kCost, 0.5).at(4), FrameRender::kFull);
}

TEST(EvalPlan, FrameSecondsAddsThePlainPassAndTheStridedPasses) {
  EXPECT_DOUBLE_EQ(FrameSeconds(FrameRender::kFull, 2, kCost, kPixels), 1.0);
  EXPECT_DOUBLE_EQ(FrameSeconds(FrameRender::kReduced, 2, kCost, kPixels), 0.45);
}

// A training frame full, a reduced one, a held-out one: the pacer's plan below.
EvalPlan ThreeFrames() {
  EvalPlan plan;
  plan.frames = {FrameRender::kFull, FrameRender::kReduced, FrameRender::kFull};
  plan.stride = 2;
  plan.cost = kCost;
  return plan;
}

constexpr double kNoDeadline = std::numeric_limits<double>::infinity();

bool Is(FrameChoice choice, FrameRender how, int stride) {
  return choice.how == how && (how == FrameRender::kFull || choice.stride == stride);
}

TEST(FramePacer, KeepsThePlanWhileItFitsThenReducesThenCoarsens) {
  const EvalPlan plan = ThreeFrames();
  const FramePacer pacer(plan, {2}, kPixels, true);
  // Frame 0 and what follows it as planned (0.45 s + 1 s): full 2.45 s, reduced at 2 1.9 s, at 4 1.7125 s.
  EXPECT_TRUE(Is(pacer.Choose(0, kNoDeadline), FrameRender::kFull, 2));
  EXPECT_TRUE(Is(pacer.Choose(0, 2.5), FrameRender::kFull, 2));
  EXPECT_TRUE(Is(pacer.Choose(0, 2.0), FrameRender::kReduced, 2));
  EXPECT_TRUE(Is(pacer.Choose(0, 1.8), FrameRender::kReduced, 4));
  EXPECT_TRUE(Is(pacer.Choose(0, 0.1), FrameRender::kReduced, 4)) << "too late for any: the cheapest";
  // A reduced frame goes coarser (then 1 s for the held-out frame): 1.45 s at 2, 1.2625 s at 4.
  EXPECT_TRUE(Is(pacer.Choose(1, 1.5), FrameRender::kReduced, 2));
  EXPECT_TRUE(Is(pacer.Choose(1, 1.3), FrameRender::kReduced, 4));
  // The held-out frame, the last, is full while it fits (1 s), reduced only when it does not.
  EXPECT_TRUE(Is(pacer.Choose(2, 1.0), FrameRender::kFull, 2));
  EXPECT_TRUE(Is(pacer.Choose(2, 0.9), FrameRender::kReduced, 2));
  // Without a plain renderer nothing can be reduced.
  const FramePacer full_only(plan, {2}, kPixels, false);
  EXPECT_TRUE(Is(full_only.Choose(0, 0.1), FrameRender::kFull, 2));
}

TEST(FramePacer, FollowsThePaceOfTheFramesRendered) {
  const EvalPlan plan = ThreeFrames();
  FramePacer pacer(plan, {2}, kPixels, true);
  EXPECT_TRUE(Is(pacer.Choose(1, 1.6), FrameRender::kReduced, 2));  // priced 0.45 + 1 s
  // A reduced frame took twice its price: 0.9 + 1 s does not fit, 0.525 + 1 s does.
  pacer.Rendered({FrameRender::kReduced, 2}, 0.9);
  EXPECT_TRUE(Is(pacer.Choose(1, 1.6), FrameRender::kReduced, 4));
  // A full frame took half its price: 0.9 + 0.5 s fits.
  pacer.Rendered({FrameRender::kFull, 2}, 0.5);
  EXPECT_TRUE(Is(pacer.Choose(1, 1.6), FrameRender::kReduced, 2));
}

// Held-out frames come first: before one, the training frames after it count at their cheapest; a
// held-out frame planned reduced is full again when the frames run ahead of their prices.
TEST(FramePacer, HeldOutFramesGiveWayLastAndComeBackWhenTimeAllows) {
  EvalPlan plan;
  plan.frames = {FrameRender::kFull, FrameRender::kFull, FrameRender::kReduced};  // held out, two training
  plan.stride = 2;
  plan.cost = kCost;
  const FramePacer pacer(plan, {0}, kPixels, true);
  // 1 s for the held-out frame and 2 x 0.2625 s for the training frames at their cheapest: 1.525 s.
  EXPECT_TRUE(Is(pacer.Choose(0, 1.53), FrameRender::kFull, 2));
  EXPECT_TRUE(Is(pacer.Choose(0, 1.5), FrameRender::kReduced, 2));
  // Planned reduced, but there is time: full.
  plan.frames[0] = FrameRender::kReduced;
  const FramePacer ahead(plan, {0}, kPixels, true);
  EXPECT_TRUE(Is(ahead.Choose(0, 10.0), FrameRender::kFull, 2));
  EXPECT_TRUE(Is(ahead.Choose(0, kNoDeadline), FrameRender::kReduced, 2)) << "no deadline: the plan";
  // With the budget's tolerance a held-out frame runs full past the deadline by up to the slack;
  // training frames keep to the deadline itself.
  const FramePacer tolerant(plan, {0}, kPixels, true, 0.1);
  EXPECT_TRUE(Is(tolerant.Choose(0, 1.5), FrameRender::kFull, 2));
  EXPECT_TRUE(Is(tolerant.Choose(0, 1.4), FrameRender::kReduced, 2));
  EXPECT_TRUE(Is(tolerant.Choose(1, 0.2), FrameRender::kReduced, 4));
}

TEST(FramePacer, StrideEightOnlyOnLargeFrames) {
  constexpr int kLarge = 640 * 512;
  EvalPlan plan = ThreeFrames();
  plan.cost = RenderCost{1e-3 / kLarge * kPixels, 2e-4 / kLarge * kPixels};  // as kCost per frame
  plan.stride = 4;
  EXPECT_TRUE(Is(FramePacer(plan, {2}, kLarge, true).Choose(1, 1.22), FrameRender::kReduced, 8));
  EXPECT_TRUE(Is(FramePacer(plan, {2}, kLarge - 64, true).Choose(1, 1.22), FrameRender::kReduced, 4));
  EXPECT_EQ(UncertaintyStrides(kLarge), (std::vector<int>{2, 4, 8}));
  EXPECT_EQ(UncertaintyStrides(kPixels), (std::vector<int>{2, 4}));
}

}  // namespace
}  // namespace endorecon::eval
