#include "app/progress_line.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>

namespace lamina::app {

double RemainingTimeEstimate::update(double elapsed, double fraction) {
  if (fraction >= 1.0) return 0.0;
  const double horizon = 0.75 * elapsed;
  // the window starts at the latest sample at or before the horizon; older ones can no longer start it
  while (samples_.size() >= 2 && samples_[1].first <= horizon) samples_.pop_front();
  double estimate = fraction > 1e-6 ? elapsed * (1.0 - fraction) / fraction : 0.0;
  const auto [start, done] = samples_.front();
  if (start <= horizon && elapsed > start && fraction > done)
    estimate = (1.0 - fraction) * (elapsed - start) / (fraction - done);
  // samples at least 1 % of the elapsed time apart: a few dozen cover the window of any run
  if (elapsed - samples_.back().first >= 0.01 * elapsed) samples_.emplace_back(elapsed, fraction);
  return estimate;
}

ProgressLine::ProgressLine(bool quiet)
    : quiet_(quiet), terminal_(::isatty(STDERR_FILENO) == 1), start_(std::chrono::steady_clock::now()), last_(start_) {}

ProgressLine::~ProgressLine() { finish(); }

void ProgressLine::update(Real fraction, const std::string& status) {
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  const double since_last = std::chrono::duration<double>(now - last_).count();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (since_last < (terminal_ ? 0.2 : 5.0) && fraction < 1.0) return;
  last_ = now;
  const double eta = remaining_.update(elapsed, fraction);
  const std::string text = fmt::format("[{:5.1f}%] {}  elapsed {:.1f} s  ETA {:.1f} s", 100.0 * fraction, status, elapsed, eta);
  if (terminal_) {
    std::fprintf(stderr, "\r\033[K%s", text.c_str());
    open_line_ = true;
  } else {
    std::fprintf(stderr, "%s\n", text.c_str());
  }
  std::fflush(stderr);
}

void ProgressLine::note(const std::string& text) {
  if (quiet_) return;
  finish();
  std::fprintf(stderr, "lamina: note: %s\n", text.c_str());
  std::fflush(stderr);
}

void ProgressLine::finish() {
  if (open_line_) {
    std::fprintf(stderr, "\n");
    open_line_ = false;
  }
}

}  // namespace lamina::app
