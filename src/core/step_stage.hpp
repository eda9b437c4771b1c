#pragma once
// StepStage: one named stage of a solver's step (as NairnMPM's tasks). A solver's step is an ordered
// list of them, so the algorithm reads in one screen and a variant is another list; run_stages times each.
#include <functional>
#include <vector>

#include "core/stopwatch.hpp"
#include "core/types.hpp"

namespace lamina {

struct StepStage {
  const char* name;            // timing key: summary.json timing.stage_<name>_s
  std::function<void()> run;
};

/// Runs the stages in order, adding each one's wall time to seconds[k] (sized like stages).
inline void run_stages(const std::vector<StepStage>& stages, std::vector<Real>& seconds) {
  for (std::size_t k = 0; k < stages.size(); ++k) {
    const auto start = Clock::now();
    stages[k].run();
    seconds[k] += seconds_since(start);
  }
}

}  // namespace lamina
