// The progress line's remaining-time estimate (app/progress_line.hpp): the whole run's rate while the run
// is young or steady, the recent rate once it has changed.
#include <gtest/gtest.h>

#include "app/progress_line.hpp"

namespace {

using lamina::app::RemainingTimeEstimate;

TEST(RemainingTimeEstimate, SteadyRunIsTheLinearEstimate) {
  RemainingTimeEstimate estimate;
  for (double t = 1.0; t <= 20.0; t += 1.0) {
    const double fraction = 0.02 * t;  // 50 s in all
    EXPECT_NEAR(estimate.update(t, fraction), 50.0 - t, 1e-9) << "at t = " << t;
  }
}

TEST(RemainingTimeEstimate, RecentRateAfterTheRunSpeedsUp) {
  // 1 % per second for 10 s, then 3 % per second (a Newton run whose increments grow): the estimate
  // from the mean rate would stay far too long; the window's rate is exact once it lies past the change
  RemainingTimeEstimate estimate;
  auto fraction_at = [](double t) { return t <= 10.0 ? 0.01 * t : 0.1 + 0.03 * (t - 10.0); };
  double last = 0.0;
  for (double t = 0.5; t <= 25.0; t += 0.5) {
    last = estimate.update(t, fraction_at(t));
    if (t >= 14.0) {  // 3/4 of it lies past the change at 10 s
      EXPECT_NEAR(last, (1.0 - fraction_at(t)) / 0.03, 1e-9) << "at t = " << t;
    }
  }
  EXPECT_LT(last, 25.0 * (1.0 - fraction_at(25.0)) / fraction_at(25.0));  // below the mean-rate estimate
}

TEST(RemainingTimeEstimate, FinishedAndStalledRuns) {
  RemainingTimeEstimate estimate;
  EXPECT_EQ(estimate.update(1.0, 0.0), 0.0);    // nothing done yet: no estimate
  EXPECT_NEAR(estimate.update(2.0, 0.1), 9.0, 1e-9);   // the rate since t = 1 (the window start)
  EXPECT_NEAR(estimate.update(4.0, 0.1), 36.0, 1e-9);  // stalled over the window: the mean rate
  EXPECT_EQ(estimate.update(5.0, 1.0), 0.0);
}

}  // namespace
