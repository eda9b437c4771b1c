#pragma once
// Progress of a long run on stderr: one updating line on a terminal (fraction, status, elapsed,
// ETA), plain periodic lines otherwise, nothing when quiet.
#include <chrono>
#include <string>

#include "core/types.hpp"

namespace lamina::app {

class ProgressLine {
 public:
  explicit ProgressLine(bool quiet);
  ~ProgressLine();
  void update(Real fraction, const std::string& status);
  void finish();
  /// One line of its own below the progress line (an event of the run), unless quiet.
  void note(const std::string& text);

 private:
  bool quiet_, terminal_, open_line_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace lamina::app
