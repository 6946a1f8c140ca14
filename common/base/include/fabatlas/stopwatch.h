// fabatlas/stopwatch.h — the wall time of a step, in seconds, on the
// monotonic clock (std::chrono::steady_clock): the one timer of the
// libraries' summaries (seconds fields) and statistics.
//
//   const Stopwatch watch;
//   Solve();
//   summary.seconds = watch.Seconds();
#pragma once

#include <chrono>

namespace fabatlas {

class Stopwatch {
 public:
  using Clock = std::chrono::steady_clock;

  // Started now.
  Stopwatch() : start_(Clock::now()) {}

  // Seconds since the start (or the last Restart).
  double Seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  // Starts again now.
  void Restart() { start_ = Clock::now(); }

 private:
  Clock::time_point start_;
};

}  // namespace fabatlas
