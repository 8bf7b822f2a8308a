// Progress of the long stages on stderr, one form for every command that has them
// (reparam, demo, eval):
// - on a terminal, one line redrawn at most five times a second:
//   "triangles (layout 0) [#########...........] 450/1000, about 1 min left";
// - otherwise (a log file, a Slurm job's output) a plain line once a stage has run 5 s and
//   every 15 s after, so that short runs stay quiet and long ones show they are alive;
// - with -v, every stage also ends with "<stage>: done in 12.3 s".
// The time left is the stage's elapsed time scaled by the work left (uniform work items);
// it is shown from the first finished item once the stage has run a second.
#pragma once

#include <cstddef>
#include <cstdio>
#include <functional>
#include <string>

namespace uvpress::cli {

class ProgressDisplay {
 public:
  using Clock = std::function<double()>;  // seconds, monotonic
  // tty: draw the redrawn line (default: whether stderr is a terminal); clock: for tests.
  explicit ProgressDisplay(bool verbose);
  ProgressDisplay(bool verbose, bool tty, std::FILE* out, Clock clock);
  ~ProgressDisplay();
  // The pipeline's progress callback: `done` of `total` items of `stage`.
  void operator()(const std::string& stage, size_t done, size_t total);
  // Ends the current stage's line (called by the next stage and the destructor).
  void finish();

  // "about 40 s left", "about 3 min left"; "" when it cannot be estimated yet.
  static std::string time_left(double elapsed, size_t done, size_t total);

 private:
  bool verbose_, tty_;
  std::FILE* out_;
  Clock clock_;
  std::string stage_;
  double start_ = 0, last_ = -1e9, end_ = -1;  // end_: when done reached total
  bool drawn_ = false;
  size_t done_ = 0, total_ = 0;
};

}  // namespace uvpress::cli
