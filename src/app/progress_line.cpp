#include "app/progress_line.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>

namespace lamina::app {

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
  const double eta = fraction > 1e-6 ? elapsed * (1.0 - fraction) / fraction : 0.0;
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
