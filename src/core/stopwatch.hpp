#pragma once
// Wall-clock timing for the summary.json timings: one clock and the seconds since a start point.
#include <chrono>

#include "core/types.hpp"

namespace lamina {

using Clock = std::chrono::steady_clock;

/// Seconds of wall-clock time from start to now.
inline Real seconds_since(Clock::time_point start) { return std::chrono::duration<Real>(Clock::now() - start).count(); }

}  // namespace lamina
