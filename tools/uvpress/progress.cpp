#include "progress.h"

#include <chrono>
#include <cmath>
#include <unistd.h>

namespace uvpress::cli {

namespace {

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

constexpr double kRedraw = 0.2;       // s between terminal redraws
constexpr double kFirstLine = 5.0;    // s a stage runs before a plain line is printed
constexpr double kLineInterval = 15;  // s between plain lines

}  // namespace

ProgressDisplay::ProgressDisplay(bool verbose) : ProgressDisplay(verbose, isatty(2), stderr, steady_seconds) {}

ProgressDisplay::ProgressDisplay(bool verbose, bool tty, std::FILE* out, Clock clock)
    : verbose_(verbose), tty_(tty), out_(out), clock_(clock ? std::move(clock) : Clock(steady_seconds)) {}

ProgressDisplay::~ProgressDisplay() { finish(); }

std::string ProgressDisplay::time_left(double elapsed, size_t done, size_t total) {
  if (done == 0 || done >= total || elapsed < 1.0) return "";
  const double left = elapsed * double(total - done) / double(done);
  char buf[48];
  if (left < 90) std::snprintf(buf, sizeof buf, "about %.0f s left", std::max(1.0, std::round(left)));
  else if (left < 5400) std::snprintf(buf, sizeof buf, "about %.0f min left", std::round(left / 60));
  else std::snprintf(buf, sizeof buf, "about %.1f h left", left / 3600);
  return buf;
}

void ProgressDisplay::operator()(const std::string& stage, size_t done, size_t total) {
  const double now = clock_();
  if (stage != stage_) {
    finish();
    stage_ = stage, start_ = now, last_ = now, end_ = -1;
  }
  done_ = done, total_ = total;
  if (done >= total) end_ = now;  // the stage's work ends here, whatever runs before the next
  const double elapsed = now - start_;
  const std::string left = time_left(elapsed, done, total);
  if (tty_) {
    if (now - last_ < kRedraw && done < total && drawn_) return;
    last_ = now;
    constexpr int kBar = 20;
    const int filled = total ? int(double(kBar) * double(done) / double(total)) : kBar;
    std::string bar(size_t(filled), '#');
    bar.append(size_t(kBar - filled), '.');
    // \r and a clear-to-end-of-line: a shorter line leaves nothing of the longer one.
    std::fprintf(out_, "\r%s [%s] %zu/%zu%s%s\033[K", stage.c_str(), bar.c_str(), done, total, left.empty() ? "" : ", ",
                 left.c_str());
    std::fflush(out_);
    drawn_ = true;
    return;
  }
  // Plain lines: only for a stage that has run a while, then at intervals.
  if (elapsed < kFirstLine || (drawn_ && now - last_ < kLineInterval)) return;
  last_ = now;
  std::fprintf(out_, "%s: %zu/%zu (%.0f%%)%s%s\n", stage.c_str(), done, total, total ? 100.0 * double(done) / double(total) : 100.0,
               left.empty() ? "" : ", ", left.c_str());
  std::fflush(out_);
  drawn_ = true;
}

void ProgressDisplay::finish() {
  if (stage_.empty()) return;
  if (tty_ && drawn_) std::fputc('\n', out_);
  if (verbose_) std::fprintf(out_, "%s: done in %.1f s\n", stage_.c_str(), (end_ >= start_ ? end_ : clock_()) - start_);
  std::fflush(out_);
  stage_.clear();
  drawn_ = false;
}

}  // namespace uvpress::cli
