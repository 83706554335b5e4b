// One outcome protocol (issue #41, item 1): a branch's status is derived from its stop by one
// function, branch_status, read by Branch, ResponseCurve and Backbone alike; brief() is one line
// with the stop and the counts. Enumerated here: a branch converged exactly when it reached its
// range or its goal. Breaking branch_status by hand (e.g. counting StateBound as converged, as a
// curve cut by its state bound is not) fails the first test.
#include <string>

#include <gtest/gtest.h>

#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>
#include <wbm/solvers/response_curve.hpp>

using wbm::solvers::SolveStatus;
using wbm::solvers::StopReason;

TEST(Outcomes, ABranchConvergedExactlyWhenItReachedItsRangeOrGoal) {
  for (StopReason r : {StopReason::RangeReached, StopReason::StepBelowMinimum, StopReason::MaxPoints,
                       StopReason::InitialPointFailed, StopReason::StateBound, StopReason::Retraced,
                       StopReason::UndampedResonance, StopReason::DegenerateEvent, StopReason::TimeBudget,
                       StopReason::GoalReached}) {
    const bool reached = r == StopReason::RangeReached || r == StopReason::GoalReached;
    EXPECT_EQ(wbm::solvers::branch_status(r), reached ? SolveStatus::Converged : SolveStatus::PathEnded)
        << wbm::solvers::to_string(r);
    wbm::solvers::Branch b;
    b.stop = r;
    wbm::solvers::ResponseCurve c;
    c.stop = r;
    EXPECT_EQ(b.converged(), reached);
    EXPECT_EQ(c.converged(), reached);
    EXPECT_EQ(b.status(), c.status());
  }
}

TEST(Outcomes, BriefSaysTheStopAndTheCounts) {
  wbm::solvers::ResponseCurve c;
  c.stop = StopReason::StateBound;
  c.points.resize(3);
  c.folds.resize(2);
  c.rejected_steps = 1;
  c.wall_time_s = 0.25;
  EXPECT_EQ(c.brief(), "state bound exceeded: 3 points, 2 folds, 1 rejected steps, 0.25 s (stability 0 s)");
  c.events = 5;
  EXPECT_EQ(c.brief(), "state bound exceeded: 3 points, 2 folds, 5 events, 1 rejected steps, 0.25 s (stability 0 s)");
  wbm::solvers::Backbone b;
  b.stop = StopReason::RangeReached;
  b.levels.resize(4);
  b.kinks = 7;
  EXPECT_EQ(b.brief(), "range reached: 4 levels, 0 folds, 7 corners, 0 rejected steps, 0 s");
  wbm::solvers::WeightedResidualSolution s;
  s.report.status = SolveStatus::ResidualNotVerified;
  s.relative_residual = 2e-8;
  s.backward_error = 3e-9;
  s.residual_tolerance = 1e-9;
  EXPECT_EQ(s.brief().rfind("residual-not-verified: ‖G a − b + n(a)‖/‖b‖ = 2e-08, backward error 3e-09 (tolerance 1e-09); "
                            "Newton ", 0), 0u)
      << s.brief();
}
