// The Floquet multipliers of trace_response's points, computed while the continuation goes on
// (point_stability.hpp).
#include "point_stability.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdint>
#include <map>

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/spectral/layout.hpp>

namespace wbm::solvers::detail {

namespace {

bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() != b.size()) return false;
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    if (!same_bits(a(i), b(i))) return false;
  }
  return true;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

PointStability::PointStability(const WeightedResidual& base, int samples, bool friction, int threads)
    : base_(base), friction_(friction), nc_(static_cast<int>(base.contacts().size())),
      arena_(std::max(1, threads > 0 ? threads : tbb::info::default_concurrency())) {
  tau_ = Eigen::VectorXd::LinSpaced(samples, 0.0, 1.0 - 1.0 / samples);
  q_ = base.trial().values(tau_, 0);
  // The modes of a classical C are set up once for the branch; the points read the multipliers
  // only. In a continuation in μ each point's Jenkins elements differ: each has its own analysis.
  if (!friction_) analysis_.emplace(base.system(), base.contacts(), FloquetOptions{.monodromy = false});
  // One slot of the arena is kept for the thread that joins it (results()): a worker takes the
  // queued points only when there are two or more.
  pipelined_ = arena_.max_concurrency() >= 2;
  group_ = std::make_unique<tbb::task_group>();
}

PointStability::~PointStability() {
  if (!group_) return;
  try {
    arena_.execute([&] {
      group_->cancel();
      group_->wait();
    });
  } catch (...) {  // a point's exception after a continuation that threw: the first one stands
  }
}

FloquetResult PointStability::compute(double parameter, double frequency_hz, const Eigen::VectorXd& x) const {
  const auto& contacts = base_.contacts();
  const bool moving = any_moving_obstacle(contacts);
  // The contact displacements relative to the counter-surfaces, P × n_c: what the laws and the
  // monodromy matrix see.
  auto relative = [&](Eigen::MatrixXd uc, const Eigen::VectorXd& at) {
    if (moving) uc -= obstacle_samples(contacts, at).transpose();
    return uc;
  };
  std::optional<FloquetAnalysis> own;
  if (friction_) {
    own.emplace(base_.system(), with_friction_coefficient(contacts, parameter), FloquetOptions{.monodromy = false});
  }
  const FloquetAnalysis& analysis = friction_ ? *own : *analysis_;
  Eigen::MatrixXd uc = relative(q_ * spectral::as_coefficients(x, nc_).transpose(), tau_);
  // A contact stiff against its mass needs more steps (floquet.hpp): the orbit is evaluated there
  // from the trial functions, rather than interpolated between the P samples.
  const Eigen::Index resolved = analysis.resolved_steps(uc.transpose(), frequency_hz);
  if (resolved > uc.rows()) {
    const double last = 1.0 - 1.0 / static_cast<double>(resolved);
    const Eigen::VectorXd fine = Eigen::VectorXd::LinSpaced(resolved, 0.0, last);
    uc = relative(base_.trial().values(fine, 0) * spectral::as_coefficients(x, nc_).transpose(), fine);
  }
  FloquetResult fl = analysis(uc.transpose(), frequency_hz);
  // Refine where the error estimate could overturn the verdict (near a collision of two
  // multipliers, or |μ| near 1), at most twice, ×4 steps each time.
  for (int refinement = 0; refinement < 2 && !fl.settled(); ++refinement) {
    const int steps = 4 * fl.steps;
    const Eigen::VectorXd fine = Eigen::VectorXd::LinSpaced(steps, 0.0, 1.0 - 1.0 / steps);
    const Eigen::MatrixXd ucf =
        relative(base_.trial().values(fine, 0) * spectral::as_coefficients(x, nc_).transpose(), fine);
    fl = analysis(ucf.transpose(), frequency_hz);
  }
  return fl;
}

void PointStability::run(Queued& q) const {
  const auto t0 = std::chrono::steady_clock::now();
  q.result = compute(q.parameter, q.frequency_hz, q.x);
  q.seconds = seconds_since(t0);
}

void PointStability::queue(double parameter, double frequency_hz, const Eigen::VectorXd& x) {
  if (!pipelined_) return;
  Queued& slot = queued_.emplace_back();
  slot.parameter = parameter;
  slot.frequency_hz = frequency_hz;
  slot.x = x;
  Queued* at = &slot;
  arena_.enqueue(group_->defer([this, at] { run(*at); }));
}

std::vector<FloquetResult> PointStability::results(const std::vector<ResponsePoint>& points) {
  if (pipelined_) arena_.execute([&] { group_->wait(); });  // rethrows a point's exception
  std::multimap<std::uint64_t, Queued*> by_parameter;
  for (Queued& q : queued_) by_parameter.emplace(std::bit_cast<std::uint64_t>(q.parameter), &q);
  std::vector<FloquetResult> out(points.size());
  std::vector<size_t> missing;
  taken = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const ResponsePoint& r = points[i];
    Queued* found = nullptr;
    const auto [first, last] = by_parameter.equal_range(std::bit_cast<std::uint64_t>(r.parameter));
    for (auto it = first; it != last && found == nullptr; ++it) {
      Queued& q = *it->second;
      if (!q.taken && same_bits(q.frequency_hz, r.frequency_hz) && same_bits(q.x, r.contact_unknowns)) found = &q;
    }
    if (found == nullptr) {
      missing.push_back(i);
      continue;
    }
    found->taken = true;
    ++taken;
    out[i] = std::move(found->result);
  }
  work_s = 0.0;
  for (const Queued& q : queued_) work_s += q.seconds;
  // The others on the arena's threads, one point a task: the refined points cost up to 16 times
  // more, and oneTBB's work stealing balances them. An exception in any task cancels the others
  // and is rethrown here.
  std::vector<double> seconds(missing.size(), 0.0);
  arena_.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, missing.size(), 1), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t j = range.begin(); j != range.end(); ++j) {
        const auto t0 = std::chrono::steady_clock::now();
        const ResponsePoint& r = points[missing[j]];
        out[missing[j]] = compute(r.parameter, r.frequency_hz, r.contact_unknowns);
        seconds[j] = seconds_since(t0);
      }
    });
  });
  for (double s : seconds) work_s += s;
  queued_.clear();
  return out;
}

}  // namespace wbm::solvers::detail
