// The progress display every long command shares (tools/uvpress/progress.h): a redrawn
// bar on a terminal, plain lines at intervals elsewhere, and an estimate of the time left.
#include <catch2/catch.hpp>

#include "progress.h"

#include <cstdio>
#include <string>

using uvpress::cli::ProgressDisplay;

namespace {

// What the display wrote to a temporary file.
std::string contents(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string s;
  for (int c; (c = std::fgetc(f)) != EOF;) s += char(c);
  return s;
}

size_t count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
  return n;
}

}  // namespace

TEST_CASE("progress: the time left scales the elapsed time by the work left", "[cli][progress]") {
  CHECK(ProgressDisplay::time_left(10, 25, 100) == "about 30 s left");
  CHECK(ProgressDisplay::time_left(60, 10, 100) == "about 9 min left");
  CHECK(ProgressDisplay::time_left(3600, 1, 4) == "about 3.0 h left");
  CHECK(ProgressDisplay::time_left(0.5, 50, 100).empty());  // too early to tell
  CHECK(ProgressDisplay::time_left(10, 0, 100).empty());    // nothing finished yet
  CHECK(ProgressDisplay::time_left(10, 100, 100).empty());  // nothing left
}

TEST_CASE("progress: plain lines only for a stage that runs, at intervals, -v says when each stage is done", "[cli][progress]") {
  double now = 0;
  std::FILE* f = std::tmpfile();
  REQUIRE(f);
  {
    ProgressDisplay p(/*verbose=*/false, /*tty=*/false, f, [&] { return now; });
    p("short", 0, 10);
    for (int k = 1; k <= 10; ++k) now += 0.3, p("short", size_t(k), 10);  // 3 s: quiet
    p("long", 0, 100);
    for (int k = 1; k <= 100; ++k) now += 0.5, p("long", size_t(k), 100);  // 50 s
  }
  const std::string plain = contents(f);
  std::fclose(f);
  INFO(plain);
  CHECK(plain.find("short") == std::string::npos);
  CHECK(plain.find('\r') == std::string::npos);
  // At 5 s, then every 15 s: 5, 20, 35, 50 s.
  CHECK(count(plain, "long: ") == 4);
  CHECK(plain.find("long: 10/100 (10%), about 45 s left\n") != std::string::npos);

  f = std::tmpfile();
  now = 0;
  {
    ProgressDisplay p(/*verbose=*/true, /*tty=*/true, f, [&] { return now; });
    for (int k = 0; k <= 40; ++k) now += 0.05, p("bar", size_t(k), 40);  // 2 s at 20 calls a second
    p("next", 0, 1);
  }
  const std::string tty = contents(f);
  std::fclose(f);
  INFO(tty);
  // Redrawn at most five times a second (plus the first and the last draw).
  CHECK(count(tty, "\rbar [") <= 2 * 5 + 2);
  CHECK(count(tty, "\rbar [") >= 5);
  CHECK(tty.find("\rbar [####################] 40/40") != std::string::npos);
  CHECK(tty.find("bar: done in 2.") != std::string::npos);
  CHECK(tty.find("next: done in 0.0 s") != std::string::npos);
}
