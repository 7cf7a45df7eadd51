// The clock of a training run: how far along the run is (the schedule the learning-rate decay and
// every periodic round follow), when it ends, how fast it goes and how long is left. A run ends at its
// iteration cap (0: none) or when its training budget is spent, whichever comes first; with a budget
// the schedule runs on time. The training budget, in seconds of steps, may be revised as the run goes
// (the whole run's budget less what evaluation will need and what periodic work costs); the share
// of the run done never goes back.
#pragma once

#include <algorithm>

namespace endorecon::train {

// The share of a run done in [0, 1]: iteration / iterations (iterations 0: no cap), or
// seconds / budget_s when there is a budget and time is further along.
double RunProgress(int iteration, int iterations, double seconds, double budget_s);

class RunClock {
 public:
  // `seconds`: training time already spent (a resumed run's); budget_s 0: no budget.
  RunClock(int iterations, double budget_s, double seconds);

  double Progress(int iteration);
  void SetBudget(double budget_s) { budget_s_ = budget_s; }
  double budget() const { return budget_s_; }
  // True when no further step should run: the cap is reached or the budget spent.
  bool Finished(int iteration) const;
  // Accounts one step of `seconds` that processed `samples`.
  void AddStep(double seconds, long long samples);

  double seconds() const { return seconds_; }  // training time so far, earlier processes included
  // This process's samples per training second.
  double SamplesPerSecond() const;
  // Samples per second since the last call (the progress line's rate); starts a new window.
  double TakeWindowRate();
  // Seconds of training left at `iteration`: by the average step so far, within the budget.
  double Eta(int iteration) const;

 private:
  int iterations_;
  double budget_s_;
  double seconds_;
  double reached_ = 0;  // the largest share Progress returned
  double run_seconds_ = 0, run_samples_ = 0;
  double window_seconds_ = 0, window_samples_ = 0;
};

// A periodic event on any clock: Due(now) is true once `interval` has passed since it last was (or
// since `start`), and then waits another interval.
class Every {
 public:
  Every(double interval, double start) : interval_(interval), next_(start + interval) {}
  bool Due(double now) {
    if (now < next_) return false;
    next_ = now + interval_;
    return true;
  }

 private:
  double interval_;
  double next_;
};

// When the error-against-time curve takes its points, on the training clock (curve.svg's axis is
// log time). A point every `interval` (curve_interval_s) left a 20 s run 3 points, none between
// 0.03 s and 10 s (found 2026-12-06); so early on a point comes half the training time after the
// last (evenly on the log axis), never closer than `interval` / 8 nor than ten times what the last
// point cost (so points take a tenth of the time at most), and every `interval` once that is the
// shorter.
class CurveTimes {
 public:
  // The first point is due at `first` (negative: at the first step).
  CurveTimes(double interval, double first) : interval_(interval), next_(first) {}
  bool Due(double now) const { return now >= next_; }
  // A point was taken at `now`, costing `cost_s`.
  void Taken(double now, double cost_s) {
    next_ = now + std::min(interval_, std::max({0.5 * now, interval_ / 8, 10 * cost_s}));
  }

 private:
  double interval_;
  double next_;
};

}  // namespace endorecon::train
