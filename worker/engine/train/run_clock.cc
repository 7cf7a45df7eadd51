#include "worker/engine/train/run_clock.h"

#include <algorithm>

namespace endorecon::train {

double RunProgress(int iteration, int iterations, double seconds, double budget_s) {
  double progress = iterations > 0 ? double(iteration) / iterations : 0.0;
  if (budget_s > 0) progress = std::max(progress, seconds / budget_s);
  return std::min(progress, 1.0);
}

RunClock::RunClock(int iterations, double budget_s, double seconds)
    : iterations_(iterations), budget_s_(budget_s), seconds_(seconds) {}

double RunClock::Progress(int iteration) {
  reached_ = std::max(reached_, RunProgress(iteration, iterations_, seconds_, budget_s_));
  return reached_;
}

bool RunClock::Finished(int iteration) const {
  return (iterations_ > 0 && iteration >= iterations_) || (budget_s_ > 0 && seconds_ >= budget_s_);
}

void RunClock::AddStep(double seconds, long long samples) {
  seconds_ += seconds;
  run_seconds_ += seconds;
  run_samples_ += double(samples);
  window_seconds_ += seconds;
  window_samples_ += double(samples);
}

double RunClock::SamplesPerSecond() const { return run_samples_ / std::max(run_seconds_, 1e-9); }

double RunClock::TakeWindowRate() {
  const double rate = window_samples_ / std::max(window_seconds_, 1e-9);
  window_samples_ = window_seconds_ = 0;
  return rate;
}

double RunClock::Eta(int iteration) const {
  double eta = iterations_ > 0 ? (iterations_ - iteration) * (seconds_ / std::max(1, iteration)) : 1e30;
  if (budget_s_ > 0) eta = std::min(eta, budget_s_ - seconds_);
  return std::max(0.0, eta);
}

}  // namespace endorecon::train
