#pragma once
// Private to wbm_solvers: the Floquet multipliers of trace_response's points for penalty laws and
// Jenkins elements (rigid stops go through impact_stability, in response_curve.cpp).
//
// The continuation runs on one thread. While it goes on, each accepted point's multipliers are
// computed on a oneTBB worker of this unit's task arena (queue(), called from the continuation's
// on_point), so that on a machine with two cores the stability costs the branch little more than
// the last points' monodromy matrices (issue #39). A point's computation does not depend on any
// other, nor on the thread that runs it: a queued result is used only for a final point whose
// parameter, frequency and unknowns are the queued ones bit for bit, and every other final point
// (the landed end that replaces the last one) is computed afterwards, in parallel. So the
// multipliers are the same as those of computing every point after the continuation, for any
// thread count.

#include <cstddef>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/weighted_residual.hpp>

namespace wbm::solvers::detail {

class PointStability {
 public:
  /// base: the curve's problem (penalty laws or Jenkins elements; not rigid stops); samples: P
  /// (ResponseCurveOptions::samples); friction: a continuation in the friction coefficient (each
  /// point then sets up its own FloquetAnalysis at μ = λ); threads: ResponseCurveOptions::threads
  /// (0: oneTBB's default concurrency). With one thread queue() does nothing and results()
  /// computes every point. Throws what FloquetAnalysis's constructor throws.
  PointStability(const WeightedResidual& base, int samples, bool friction, int threads);
  /// Cancels the points not started and waits for those running (a continuation that threw).
  ~PointStability();
  PointStability(const PointStability&) = delete;
  PointStability& operator=(const PointStability&) = delete;

  /// True when points are computed during the continuation (at least two threads).
  [[nodiscard]] bool pipelined() const noexcept { return pipelined_; }
  /// From the continuation's thread: the multipliers of the point (λ, f [Hz], its contact
  /// unknowns x, ResponsePoint::contact_unknowns) start on the arena's worker. Does not throw
  /// (but std::bad_alloc); a computation that throws is rethrown by results().
  void queue(double parameter, double frequency_hz, const Eigen::VectorXd& x);
  /// The multipliers of each point (FloquetResult, monodromy not kept), in the points' order:
  /// the queued ones where parameter, frequency_hz and contact_unknowns match bit for bit, the
  /// others computed now on the arena's threads. Rethrows the first exception of any point.
  /// Also sets work_s.
  [[nodiscard]] std::vector<FloquetResult> results(const std::vector<ResponsePoint>& points);
  /// Thread time summed over the points computed (queued or not) [s], after results().
  double work_s = 0.0;
  /// Final points whose queued result results() took, after results().
  int taken = 0;

 private:
  struct Queued {
    double parameter = 0.0, frequency_hz = 0.0;
    Eigen::VectorXd x;
    FloquetResult result;
    double seconds = 0.0;
    bool taken = false;
  };
  [[nodiscard]] FloquetResult compute(double parameter, double frequency_hz, const Eigen::VectorXd& x) const;
  void run(Queued& q) const;

  const WeightedResidual& base_;
  bool friction_ = false;
  bool pipelined_ = false;
  int nc_ = 0;
  Eigen::VectorXd tau_;  // P instants τ_k = k / P
  Eigen::MatrixXd q_;    // the trial functions at τ_k, P × M
  std::optional<FloquetAnalysis> analysis_;  // the branch's, when not in μ
  tbb::task_arena arena_;
  std::deque<Queued> queued_;  // the worker writes into elements; push_back moves none of them
  std::unique_ptr<tbb::task_group> group_;
};

}  // namespace wbm::solvers::detail
