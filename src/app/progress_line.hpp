#pragma once
// Progress of a long run on stderr: one updating line on a terminal (fraction, status, elapsed,
// ETA), plain periodic lines otherwise, nothing when quiet.
#include <chrono>
#include <deque>
#include <string>
#include <utility>

#include "core/types.hpp"

namespace lamina::app {

/// Remaining time of a run from its (elapsed seconds, fraction done) samples: the rate over the last
/// quarter of the run or more (from the latest sample at or before 3/4 of the elapsed time), so that a
/// run whose steps get cheaper or dearer (Newton increments that grow, ADR increments of changing cost)
/// is not judged by its start; the whole run's mean rate until such a sample exists, and for a run of
/// constant rate.
class RemainingTimeEstimate {
 public:
  /// Records the sample and returns the estimated seconds to fraction 1 (0 once it is reached).
  double update(double elapsed, double fraction);

 private:
  std::deque<std::pair<double, double>> samples_{{0.0, 0.0}};  // (elapsed, fraction), oldest first
};

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
  RemainingTimeEstimate remaining_;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace lamina::app
