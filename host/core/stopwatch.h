// Wall-clock seconds for the timings that reports print; steady_clock, so a clock change
// never makes a stage take negative time. Timings only go to reports: no result reads them.
#pragma once

#include <chrono>

namespace uvpress {

class Stopwatch {
 public:
  // Seconds since the start (construction or the last restart() or lap()).
  double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  // seconds(), then start again: consecutive laps add up to the whole.
  double lap() {
    const auto now = Clock::now();
    const double s = std::chrono::duration<double>(now - start_).count();
    start_ = now;
    return s;
  }
  void restart() { start_ = Clock::now(); }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_ = Clock::now();
};

}  // namespace uvpress
