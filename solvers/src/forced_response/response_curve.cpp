#include <wbm/solvers/response_curve.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <wbm/contact/friction.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/spectral/layout.hpp>

#include "point_stability.hpp"

namespace wbm::solvers {

ForcedResponseFamily::ForcedResponseFamily(const WeightedResidual& base, ContinuationParameter parameter)
    : base_(&base), parameter_(parameter), base_amplitude_(base.forcing().amplitude) {
  if (parameter_ == ContinuationParameter::Amplitude && base_amplitude_ == 0.0) {
    throw std::invalid_argument("ForcedResponseFamily: amplitude continuation needs a base problem with F != 0");
  }
  if (parameter_ == ContinuationParameter::FrictionCoefficient) {
    cache_lambda_ = common_friction_coefficient(base.contacts());
    cache_.emplace(base.at_frequency(base.frequency_hz()));  // G factorized once, kept for every μ
  }
}

double ForcedResponseFamily::load(double lambda) const {
  return parameter_ == ContinuationParameter::Amplitude ? lambda / base_amplitude_ : 1.0;
}

const WeightedResidual& ForcedResponseFamily::at(double lambda) const {
  if (parameter_ == ContinuationParameter::Amplitude) return *base_;
  if (parameter_ == ContinuationParameter::FrictionCoefficient) {
    if (cache_lambda_ != lambda) {
      cache_->set_friction_coefficient(lambda);
      cache_lambda_ = lambda;
    }
    return *cache_;
  }
  if (!cache_ || cache_lambda_ != lambda) {
    cache_.emplace(base_->at_frequency(lambda));
    cache_lambda_ = lambda;
  }
  return *cache_;
}

// A predictor can overshoot to a frequency ≤ 0 (or non-finite) on a steep branch: no problem
// exists there, so the residual is NaN and the corrector fails, and the step is halved, instead
// of at_frequency throwing out of the continuation.
bool ForcedResponseFamily::defined(double lambda) const {
  switch (parameter_) {
    case ContinuationParameter::Frequency: return lambda > 0.0 && std::isfinite(lambda);
    case ContinuationParameter::FrictionCoefficient: return lambda >= 0.0 && std::isfinite(lambda);
    case ContinuationParameter::Amplitude: break;
  }
  return true;
}

Eigen::VectorXd ForcedResponseFamily::residual(const Eigen::VectorXd& x, double lambda) const {
  if (!defined(lambda)) return Eigen::VectorXd::Constant(x.size(), NAN);
  if (base_->rigid()) return at(lambda).signorini_residual(x, load(lambda));
  return at(lambda).contact_residual(x, load(lambda));
}

LowRankLinearization ForcedResponseFamily::linearize(const Eigen::VectorXd& x, double lambda) const {
  if (!defined(lambda)) {
    LowRankLinearization l{Eigen::VectorXd::Constant(x.size(), NAN), {}, Eigen::VectorXd::Constant(x.size(), NAN)};
    l.jacobian.capacitance = Eigen::MatrixXd::Constant(x.size(), x.size(), NAN);  // dense form
    return l;
  }
  const WeightedResidual& wr = at(lambda);
  LowRankLinearization l;
  if (wr.rigid()) {  // the Signorini conditions on the impulses
    l.residual = wr.signorini_residual(x, load(lambda));
    l.jacobian = wr.signorini_jacobian(x, load(lambda));
    l.parameter_derivative = parameter_ == ContinuationParameter::Frequency
                                 ? wr.signorini_frequency_derivative(x, load(lambda))
                                 : Eigen::VectorXd(wr.signorini_load_derivative(x, load(lambda)) / base_amplitude_);
    return l;
  }
  l.residual = wr.contact_residual(x, load(lambda));
  l.jacobian = wr.contact_jacobian_low_rank(x);
  if (parameter_ == ContinuationParameter::Frequency) {
    l.parameter_derivative = wr.contact_residual_frequency_derivative(x);
  } else if (parameter_ == ContinuationParameter::FrictionCoefficient) {
    l.parameter_derivative = wr.contact_residual_friction_derivative(x);
  } else {
    l.parameter_derivative = -wr.contact_unknowns(wr.linear_response()) / (wr.residual_scale() * base_amplitude_);
  }
  return l;
}

namespace {
// Every contact a rigid stop (friction laws are rigid too, and hysteretic).
bool rigid_stops_only(const WeightedResidual& wr) {
  if (!wr.rigid()) return false;
  return std::none_of(wr.contacts().begin(), wr.contacts().end(),
                      [](const ContactPoint& c) { return c.law->hysteretic(); });
}
}  // namespace

SignoriniResponseFamily::SignoriniResponseFamily(const ForcedResponseFamily& family)
    : PiecewiseResponseFamily(family) {
  if (!rigid_stops_only(family.base())) {
    throw std::invalid_argument("SignoriniResponseFamily: the problem's contacts must all be rigid stops "
                                "(contact::RigidStop) without friction; continue it with ForcedResponseFamily");
  }
}

ActiveSet SignoriniResponseFamily::active_set(const Eigen::VectorXd& x, double lambda) const {
  return family_->at(lambda).signorini_active_set(x, family_->load(lambda));
}

Eigen::VectorXd SignoriniResponseFamily::residual(const Eigen::VectorXd& x, double lambda, const ActiveSet& piece) const {
  if (!family_->defined(lambda)) return Eigen::VectorXd::Constant(x.size(), NAN);
  return family_->at(lambda).signorini_residual(x, family_->load(lambda), &piece);
}

LowRankLinearization SignoriniResponseFamily::linearize(const Eigen::VectorXd& x, double lambda,
                                                        const ActiveSet& piece) const {
  if (!family_->defined(lambda)) return family_->linearize(x, lambda);  // NaN
  const WeightedResidual& wr = family_->at(lambda);
  const double s = family_->load(lambda);
  LowRankLinearization l;
  l.residual = wr.signorini_residual(x, s, &piece);
  l.jacobian = wr.signorini_jacobian(x, s, &piece);
  l.parameter_derivative = family_->parameter() == ContinuationParameter::Frequency
                               ? wr.signorini_frequency_derivative(x, s, &piece)
                               : Eigen::VectorXd(wr.signorini_load_derivative(x, s, &piece) / wr.forcing().amplitude);
  return l;
}

Eigen::VectorXd SignoriniResponseFamily::events(const Eigen::VectorXd& x, double lambda, const ActiveSet& piece) const {
  if (!family_->defined(lambda)) return Eigen::VectorXd::Constant(x.size(), NAN);
  return family_->at(lambda).signorini_events(x, family_->load(lambda), piece);
}
}  // namespace wbm::solvers

namespace wbm::solvers {

namespace {

// A branch that left the range did so on its last step, beyond the end by less than one step:
// that point is replaced by the continuation's landing on the end itself (Newton at fixed λ on
// that step, PseudoArclengthOptions::land_on), so that the curve stops on the range as asked.
// Skipped when a fold lies on that step (the landing could lie on the other sheet); if the
// landing did not converge, the overshooting point is kept and the message says so.
void replace_last_by_landing(Branch& branch, const ResponseCurveOptions& o) {
  if (branch.stop != StopReason::RangeReached || branch.points.size() < 2) return;
  const size_t n = branch.points.size();
  BranchPoint& last = branch.points[n - 1];
  if (!(last.parameter > o.parameter_max || last.parameter < o.parameter_min)) return;
  const double end = last.parameter > o.parameter_max ? o.parameter_max : o.parameter_min;
  for (const Fold& f : branch.folds) {
    if (f.after + 2 >= n) return;
  }
  const BranchPoint* landing = nullptr;
  for (const auto& l : branch.landings) {
    if (l.parameter == end && l.arclength >= branch.points[n - 2].arclength) landing = &l;
  }
  if (landing == nullptr) {
    branch.message += "; landing on the range end " + format_number(end) + " did not converge: the last point lies beyond it";
    return;
  }
  last.x = landing->x;
  last.parameter = end;
  last.residual_norm = landing->residual_norm;
  last.corrector_iterations = landing->corrector_iterations;
  branch.message = "landed on the range end λ = " + format_number(end);
}

// The M = 2^J Fourier basis ends on cos πMτ without its sine: C u̇ never reaches it, so when
// (M/2) f nears a natural frequency f_k it resonates undamped, driven by the contact forces, and
// the branch follows that resonance (hundreds of gaps, thousands of points). Such a point is
// recognized by the top function's coefficient dominating the contact displacement: the branch
// is cut before the first point where |x_top| > kTopShare · max_k |x_k| (a genuine response
// decays with the harmonic: well below 1 % there), and the message names the mode.
constexpr double kTopShare = 0.5;

void cut_at_undamped_top_resonance(const WeightedResidual& base, Branch& branch, bool frequency) {
  const int m = base.dimension();
  if (!base.trial().is_fourier() || m % 2 == 1) return;
  const auto nc = static_cast<Eigen::Index>(base.contacts().size());
  for (size_t i = 0; i < branch.points.size(); ++i) {
    const Eigen::MatrixXd x = spectral::as_coefficients(branch.points[i].x, nc);  // n_c × M
    const double top = x.col(m - 1).cwiseAbs().maxCoeff(), all = x.cwiseAbs().maxCoeff();
    if (!(top > kTopShare * all)) continue;
    const double f = frequency ? branch.points[i].parameter : base.frequency_hz();
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(base.system().stiffness),
                                                                        Eigen::MatrixXd(base.system().mass),
                                                                        Eigen::EigenvaluesOnly);
    const double f_top = 0.5 * m * f;
    Eigen::Index k = 0;
    (eig.eigenvalues().cwiseMax(0.0).cwiseSqrt() / (2.0 * std::numbers::pi) - Eigen::VectorXd::Constant(eig.eigenvalues().size(), f_top))
        .cwiseAbs()
        .minCoeff(&k);
    const double f_k = std::sqrt(std::max(0.0, eig.eigenvalues()(k))) / (2.0 * std::numbers::pi);
    branch.points.resize(std::max<size_t>(i, 1));
    std::erase_if(branch.folds, [&](const Fold& fold) { return fold.after + 1 >= branch.points.size(); });
    branch.stop = StopReason::UndampedResonance;
    branch.message = "at f = " + format_number(f) + " Hz the top Fourier function cos(pi M tau) (harmonic M/2 = " +
                     std::to_string(m / 2) + ", " + format_number(f_top) + " Hz) carries " +
                     format_number(100.0 * top / all) + " % of the contact displacement: it resonates with mode " +
                     std::to_string(k + 1) + " (" + format_number(f_k) +
                     " Hz) without damping (it has no sine partner); use harmonics = H (2H + 1 functions, "
                     "every harmonic damped) or another M; branch cut there";
    return;
  }
}

// StickSlipEvents::OnStall: one part of a branch with Jenkins elements ended where its way of
// crossing the stick/slip switches cannot go on: the nonsmooth corrector stalled at a kink (a step
// below minimum above the rounding floor), or the pieces cycled around a switching point where
// many samples' surfaces meet (a degenerate event). The branch goes on from its last point with
// the other `system` (JenkinsResponseFamily or the family itself), in the direction its last
// tangent took, and the parts are joined: the new part's first point is the old last (dropped),
// its folds' indices are shifted, the counts add up, and the stop and message are the new part's,
// after what ended the old one. Returns whether the new part added a point.
template <class System>
bool continue_branch(const System& system, PseudoArclengthOptions pa, Branch& branch, const char* how) {
  const BranchPoint last = branch.points.back();
  const auto n = last.x.size();
  pa.direction = last.tangent(n) < 0.0 ? -1 : 1;
  pa.max_points = std::max(1, pa.max_points - static_cast<int>(branch.points.size()) + 1);
  const size_t offset = branch.points.size() - 1;
  if (pa.on_point) {
    pa.on_point = [on = pa.on_point, offset](size_t index, const BranchPoint& p) {
      if (index > 0) on(offset + index, p);
    };
  }
  Branch more = pseudo_arclength(system, last.x, last.parameter, pa);
  const std::string ended = branch.message;
  for (size_t i = 1; i < more.points.size(); ++i) {
    more.points[i].arclength += last.arclength;
    branch.points.push_back(std::move(more.points[i]));
  }
  for (Fold f : more.folds) {
    f.after += offset;
    branch.folds.push_back(std::move(f));
  }
  for (auto& l : more.landings) {
    l.arclength += last.arclength;
    branch.landings.push_back(std::move(l));
  }
  branch.stop = more.stop;
  branch.message = more.message + " (continued " + how + " from λ = " + format_number(last.parameter) + ", where " +
                   ended + ")";
  branch.rejected_steps += more.rejected_steps;
  branch.kinks += more.kinks;
  branch.events += more.events;
  branch.switches += more.switches;
  branch.corrector_iterations += more.corrector_iterations;
  branch.wall_time_s += more.wall_time_s;
  branch.stalled_residual = more.stalled_residual;
  branch.rounding_floor = more.rounding_floor;
  return more.points.size() > 1;
}


}  // namespace

void ResponseCurveOptions::validate() const {
  const std::string field = "ResponseCurveOptions.";
  if (threads < 0) {
    throw std::invalid_argument(field + "threads = " + std::to_string(threads) +
                                ": must be >= 0 (0: oneTBB's default, one per core this process may use; 1: serial)");
  }
  if (samples < 8) {
    throw std::invalid_argument(field + "samples = " + std::to_string(samples) +
                                ": must be >= 8 (P samples per period of max/min and of the monodromy steps; e.g. 512)");
  }
  if (!(max_parameter_step >= 0.0) || !std::isfinite(max_parameter_step)) {
    throw std::invalid_argument(field + "max_parameter_step = " + format_number(max_parameter_step) +
                                ": must be finite and >= 0 (0: no cap on |Δλ| per step)");
  }
  if (!(max_state >= 0.0) || !std::isfinite(max_state)) {
    throw std::invalid_argument(field + "max_state = " + format_number(max_state) +
                                ": must be finite and >= 0 (0: no bound on the contact unknowns)");
  }
  if (!(parameter_min < parameter_max) || !std::isfinite(parameter_min) || !std::isfinite(parameter_max)) {
    throw std::invalid_argument(field + "parameter_min = " + format_number(parameter_min) + ", parameter_max = " +
                                format_number(parameter_max) + ": need finite parameter_min < parameter_max (the "
                                "range of λ; for a frequency, in Hz)");
  }
  if (!(min_step > 0.0 && min_step <= initial_step && initial_step <= max_step && std::isfinite(max_step))) {
    throw std::invalid_argument(field + "min_step = " + format_number(min_step) + ", initial_step = " +
                                format_number(initial_step) + ", max_step = " + format_number(max_step) +
                                ": need 0 < min_step <= initial_step <= max_step (scaled arclength; defaults 1e-7, "
                                "5e-3, 2e-2)");
  }
  if (max_points < 1) {
    throw std::invalid_argument(field + "max_points = " + std::to_string(max_points) + ": must be >= 1 (e.g. 5000)");
  }
  if (max_corrector_iterations < 1) {
    throw std::invalid_argument(field + "max_corrector_iterations = " + std::to_string(max_corrector_iterations) +
                                ": must be >= 1 (e.g. 8)");
  }
  if (!(corrector_tolerance > 0.0) || !std::isfinite(corrector_tolerance)) {
    throw std::invalid_argument(field + "corrector_tolerance = " + format_number(corrector_tolerance) +
                                ": must be finite and > 0 (e.g. 1e-9)");
  }
  if (direction != 1 && direction != -1) {
    throw std::invalid_argument(field + "direction = " + std::to_string(direction) + ": must be +1 or -1");
  }
}

ResponseCurve trace_response(const WeightedResidual& base, const ResponseCurveOptions& o) {
  const bool rigid = base.rigid();
  if (rigid && o.stability && !rigid_stops_only(base)) {
    throw std::invalid_argument("trace_response: stability = true with exact Coulomb friction: the monodromy "
                                "matrix of its rigid-plastic orbit is not computed; set "
                                "ResponseCurveOptions::stability = false, or use a stiff Jenkins element "
                                "(contact::JenkinsLaw), whose stability is computed");
  }
  if (rigid && o.stability) {
    require_fixed_obstacles(base.contacts(), "trace_response with rigid stops and stability = true (the exact orbit "
                            "with impacts is shot against fixed stops)", "set ResponseCurveOptions::stability = false");
  }
  if (base.contact_unknowns(base.linear_response()).size() == 0) {
    throw std::invalid_argument("trace_response: the problem has no contact; its response is linear "
                                "(use frequency_response)");
  }
  o.validate();  // after the refusals of the problem itself, which say more than the options
  const bool frequency = o.parameter == ContinuationParameter::Frequency;
  const bool friction = o.parameter == ContinuationParameter::FrictionCoefficient;
  const double lambda0 = frequency  ? base.frequency_hz()
                         : friction ? common_friction_coefficient(base.contacts())
                                    : base.forcing().amplitude;
  if (friction && o.parameter_min < 0.0) {
    throw std::invalid_argument("trace_response: parameter_min = " + format_number(o.parameter_min) +
                                " for a friction coefficient: must be >= 0 (no friction below mu = 0)");
  }
  if (!(lambda0 >= o.parameter_min && lambda0 <= o.parameter_max)) {
    throw std::invalid_argument("trace_response: the start " + std::to_string(lambda0) + " lies outside [" +
                                std::to_string(o.parameter_min) + ", " + std::to_string(o.parameter_max) +
                                "]; start the base problem inside the range");
  }
  const int dof = o.observed_dof >= 0 ? o.observed_dof : base.forcing().dof;
  if (dof >= base.dofs()) {
    throw std::invalid_argument("trace_response: observed_dof = " + std::to_string(dof) + " outside [0, " +
                                std::to_string(base.dofs()) + ")");
  }
  for (int k : o.keep_dofs) {
    if (k < 0 || k >= base.dofs()) {
      throw std::invalid_argument("trace_response: keep_dofs has DOF " + std::to_string(k) + " outside [0, " +
                                  std::to_string(base.dofs()) + ")");
    }
  }
  const ForcedResponseFamily family(base, o.parameter);
  // The start, with load stepping if needed.
  const WeightedResidualSolution start = base.solve();
  ResponseCurve curve;
  if (!start.report.converged()) {
    curve.message = "start: " + start.report.message;
    return curve;
  }
  // The unknowns: the contact coefficients x (penalty laws) or the impulses λ (rigid stops).
  const Eigen::VectorXd x0 = rigid ? spectral::stacked(start.contact_force_samples)
                                   : base.contact_unknowns(spectral::stacked(start.coefficients));
  PseudoArclengthOptions pa;
  pa.parameter_min = o.parameter_min;
  pa.parameter_max = o.parameter_max;
  pa.parameter_scale = std::abs(lambda0) > 0.0 ? std::abs(lambda0) : 1.0;
  // μ may start at 0 or far below the end of its range (0.05 → 2): scaled by the range's largest
  // |μ|, so that the steps are fractions of the range asked for.
  if (friction) pa.parameter_scale = std::max(std::abs(o.parameter_min), std::abs(o.parameter_max));
  // λ in newtons: scaled so that c λ is compared with s_r, as the residual is.
  pa.state_scale = rigid ? base.residual_scale() / base.force_compliance() : base.residual_scale();
  // Rigid stops alone: pieces and events (SignoriniResponseFamily). With friction the branch has
  // a corner at every change of the active instants, restarted there.
  const bool pieces = rigid_stops_only(base);
  pa.corner_restart = rigid && !pieces;
  pa.direction = o.direction;
  pa.initial_step = o.initial_step;
  pa.min_step = o.min_step;
  pa.max_step = o.max_step;
  pa.max_parameter_step = o.max_parameter_step;
  pa.max_state = o.max_state;
  pa.max_points = o.max_points;
  pa.max_corrector_iterations = o.max_corrector_iterations;
  pa.corrector_tolerance = o.corrector_tolerance;
  pa.initial_newton.tolerance = o.corrector_tolerance;
  pa.on_point = o.on_point;
  // Penalty laws and Jenkins elements: each accepted point's multipliers start on a worker while
  // the continuation goes on (point_stability.hpp; the same multipliers as computed afterwards).
  // A point's frequency: λ in a frequency continuation, else the base problem's.
  const auto frequency_at = [frequency, f0 = base.frequency_hz()](double parameter) {
    return frequency ? parameter : f0;
  };
  std::optional<detail::PointStability> penalty_stability;
  if (o.stability && !rigid) {
    penalty_stability.emplace(base, o.samples, friction, o.threads);
    if (penalty_stability->pipelined()) {
      pa.on_point = [user = o.on_point, ps = &*penalty_stability, frequency_at](size_t index, const BranchPoint& p) {
        ps->queue(p.parameter, frequency_at(p.parameter), p.x);
        if (user) user(index, p);
      };
    }
  }
  // The ends of the range are landed on by the continuation (an end the branch starts on is
  // landed on at its first step, and not again).
  pa.land_on = {o.parameter_min, o.parameter_max};
  const bool jenkins = !rigid && std::any_of(base.contacts().begin(), base.contacts().end(), [](const ContactPoint& c) {
    return dynamic_cast<const contact::JenkinsLaw*>(c.law.get()) != nullptr;
  });
  Branch branch = pieces ? pseudo_arclength(SignoriniResponseFamily(family), x0, lambda0, pa)
                  : jenkins && o.stick_slip_events == StickSlipEvents::Always
                      ? pseudo_arclength(JenkinsResponseFamily(family), x0, lambda0, pa)
                      : pseudo_arclength(family, x0, lambda0, pa);
  if (jenkins && o.stick_slip_events == StickSlipEvents::OnStall) {
    // The parts alternate: the nonsmooth corrector until it stalls, then events until the pieces
    // cycle, and so on, while each part adds a point (at most kParts parts).
    constexpr int kParts = 16;
    bool on_events = false;
    for (int part = 1; part < kParts && !branch.points.empty(); ++part) {
      const bool stalled = !on_events && branch.stop == StopReason::StepBelowMinimum &&
                           !std::isfinite(branch.stalled_residual);
      const bool cycled = on_events && branch.stop == StopReason::DegenerateEvent;
      if (!stalled && !cycled) break;
      on_events = !on_events;
      const bool moved = on_events ? continue_branch(JenkinsResponseFamily(family), pa, branch, "on stick/slip events")
                                   : continue_branch(family, pa, branch, "by the nonsmooth corrector");
      if (!moved) break;
    }
  }
  // Rigid stops never drive the top function: it vanishes at every impulse instant.
  if (!rigid) cut_at_undamped_top_resonance(base, branch, frequency);
  replace_last_by_landing(branch, o);
  curve.folds = branch.folds;
  curve.stop = branch.stop;
  curve.message = branch.message;
  curve.stalled_residual = branch.stalled_residual;
  const bool hysteretic = std::any_of(base.contacts().begin(), base.contacts().end(),
                                      [](const ContactPoint& c) { return c.law->hysteretic(); });
  if (branch.stop == StopReason::StepBelowMinimum && !std::isfinite(branch.stalled_residual) && !rigid &&
      hysteretic) {
    // A Jenkins element's force has no f(u) to average over a cell; the cell-average advice below
    // does not apply to it. bench_friction's damper in DB6:DB6, M = 64, stops at 5.98 Hz with
    // Q = 128 samples and crosses its resonance with Q = 256 (tests/solvers/test_circulant_blocks.cpp).
    curve.message += "; a hysteretic law (the Jenkins element) sampled at midpoints has a kink wherever a sample "
                     "switches between stick and slip, and the cell average does not apply to it (it has no f(u)): "
                     "raise the samples per period (WeightedResidualOptions::time_samples; scene: [basis] "
                     "time_samples, e.g. 4M)";
    if (o.stick_slip_events == StickSlipEvents::Never) {
      curve.message += ", or cross the switches as events (ResponseCurveOptions::stick_slip_events = OnStall; scene: "
                       "[analysis] stick_slip_events = \"on-stall\")";
    }
  } else if (branch.stop == StopReason::StepBelowMinimum && !std::isfinite(branch.stalled_residual) && !rigid &&
             base.contact_quadrature() == ContactQuadrature::Midpoint) {
    // Sampled at midpoints, a law with a corner (a linear penalty k (u − g)₊) makes the residual
    // nonsmooth wherever a sample crosses the gap: the cell average is C¹ there (issue #35).
    curve.message += "; a contact law with a corner sampled at midpoints (WeightedResidualOptions::contact_quadrature "
                     "= Midpoint) has a kink wherever a sample crosses the gap: use CellAverage (scene: [basis] "
                     "contact_quadrature = \"cell-average\"; Python: contact_quadrature=\"cell-average\"), "
                     "or more harmonics";
  }
  if (branch.stop == StopReason::StateBound) {
    curve.message += " (a contact coefficient exceeds max_state = " + format_number(o.max_state) + " × s_r, s_r = " +
                     format_number(base.residual_scale()) + " m: a runaway branch? raise max_state, or 0 for no bound)";
  }
  curve.rejected_steps = branch.rejected_steps;
  curve.kinks = branch.kinks;
  curve.events = branch.events;
  curve.switches = branch.switches;
  curve.corrector_iterations = branch.corrector_iterations;
  curve.wall_time_s = branch.wall_time_s;
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(o.samples, 0.0, 1.0 - 1.0 / o.samples);
  const auto& contacts = base.contacts();
  const auto nc = static_cast<int>(contacts.size());
  int observed_contact = -1;  // the observed DOF's index among the contacts, if it is one
  for (int c = 0; c < nc; ++c) {
    if (contacts[c].terms() == std::vector<std::pair<int, double>>{{dof, 1.0}}) observed_contact = c;
  }
  const Eigen::MatrixXd q = base.trial().values(tau, 0);  // P × M
  // The contact displacements relative to the counter-surfaces (ContactPoint::obstacle), P × n_c,
  // at the instants `at`: what the laws and the monodromy matrix see.
  const bool moving = any_moving_obstacle(contacts);
  auto relative = [&](Eigen::MatrixXd uc, const Eigen::VectorXd& at) {
    if (moving) uc -= obstacle_samples(contacts, at).transpose();
    return uc;
  };
  // The response at one state x of the branch (a point, or a fold's interpolated state).
  // Rigid stops with stability: each point's trial coefficients (n × M), for its exact orbit.
  std::vector<Eigen::MatrixXd> rigid_coefficients;
  auto response_at = [&](double parameter, const Eigen::VectorXd& x, int corrector_iterations,
                         Eigen::MatrixXd* coefficients = nullptr) {
    ResponsePoint r;
    r.parameter = parameter;
    r.frequency_hz = frequency_at(parameter);
    r.amplitude_n = family.load(parameter) * base.forcing().amplitude;
    r.contact_unknowns = x;
    Eigen::VectorXd u;
    auto keep = [&](const WeightedResidual& wr, const Eigen::VectorXd& a) {
      if (o.keep_dofs.empty()) return;
      const Eigen::MatrixXd all = spectral::as_coefficients(a, wr.dofs());
      r.kept_coefficients.resize(static_cast<Eigen::Index>(o.keep_dofs.size()), all.cols());
      for (size_t i = 0; i < o.keep_dofs.size(); ++i) r.kept_coefficients.row(static_cast<Eigen::Index>(i)) = all.row(o.keep_dofs[i]);
    };
    if (rigid) {  // the impulses: expand at this point
      const WeightedResidual& wr = family.at(parameter);
      const Eigen::VectorXd a = wr.expand_forces(x, family.load(parameter));
      keep(wr, a);
      if (coefficients != nullptr) *coefficients = spectral::as_coefficients(a, wr.dofs());
      r.max_contact_force = x.maxCoeff();
      u = evaluate_trial(wr.trial(), spectral::as_coefficients(a, wr.dofs()), dof, tau, r.frequency_hz);
      r.max_displacement = u.maxCoeff();
      r.min_displacement = u.minCoeff();
      r.amplitude = 0.5 * (r.max_displacement - r.min_displacement);
      r.corrector_iterations = corrector_iterations;
      return r;
    }
    if (!base.harmonics().empty()) {
      r.dropped_harmonics_residual = family.at(parameter).dropped_harmonics_residual(x, family.load(parameter));
    }
    const Eigen::MatrixXd uc = q * spectral::as_coefficients(x, nc).transpose();  // P × n_c
    const Eigen::MatrixXd ur = relative(uc, tau);                                 // what the laws see
    // The laws at this point (in a continuation in μ, its Jenkins elements at μ = λ).
    const auto& laws = friction ? family.at(parameter).contacts() : contacts;
    for (int c = 0; c < nc; ++c) {
      if (laws[c].law->hysteretic()) {  // the periodic loop over the P samples; |f| (friction)
        Eigen::VectorXd f(ur.rows()), k(ur.rows()), sensitivity(ur.rows());
        Eigen::VectorXi anchor(ur.rows());
        evaluate_contact_period(laws, c, ur.transpose(), f, k, anchor, sensitivity);
        r.max_contact_force = std::max(r.max_contact_force, f.cwiseAbs().maxCoeff());
        continue;
      }
      for (Eigen::Index k = 0; k < ur.rows(); ++k) {
        r.max_contact_force = std::max(r.max_contact_force, laws[c].law->force(ur(k, c)));
      }
    }
    if (observed_contact >= 0 && o.keep_dofs.empty()) {
      u = uc.col(observed_contact);
    } else {  // a DOF away from the contacts, or kept DOFs: expand (one more factorization of G at this point)
      const WeightedResidual& wr = family.at(parameter);
      Eigen::VectorXd a = wr.expand(x);
      a += (family.load(parameter) - 1.0) * wr.linear_response();  // expand() is at load 1
      keep(wr, a);
      u = observed_contact >= 0 ? Eigen::VectorXd(uc.col(observed_contact))
                                : evaluate_trial(wr.trial(), spectral::as_coefficients(a, wr.dofs()), dof, tau, r.frequency_hz);
    }
    r.max_displacement = u.maxCoeff();
    r.min_displacement = u.minCoeff();
    r.amplitude = 0.5 * (r.max_displacement - r.min_displacement);
    r.corrector_iterations = corrector_iterations;
    return r;
  };
  if (rigid && o.stability) rigid_coefficients.resize(branch.points.size());
  for (size_t i = 0; i < branch.points.size(); ++i) {
    const BranchPoint& p = branch.points[i];
    curve.points.push_back(response_at(p.parameter, p.x, p.corrector_iterations,
                                       rigid_coefficients.empty() ? nullptr : &rigid_coefficients[i]));
  }
  for (const auto& fold : branch.folds) curve.fold_points.push_back(response_at(fold.parameter, fold.x, 0));
  if (o.stability) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<FloquetResult> results;
    // Per point what the curve keeps of its exact orbit (not the orbit and monodromy: 2n × 2n each).
    struct Exact {
      bool available = false;
      std::string message;
      double distance = std::numeric_limits<double>::quiet_NaN();
      int impacts = 0;
    };
    std::vector<Exact> exact(rigid ? curve.points.size() : 0);
    if (rigid) {
      // The exact orbit near each point, by shooting, and its saltation monodromy
      // (impact_stability), on oneTBB's workers (at most `threads`, in a task arena), one point a
      // task; the flow is set up per point (its frequency and load). Each point's computation does
      // not depend on the others, so the results are the same for any thread count. An exception
      // in any task cancels the others and is rethrown here.
      results.resize(curve.points.size());
      std::vector<double> seconds(curve.points.size(), 0.0);
      auto impact_stability_of = [&](size_t i) {
        const auto ti = std::chrono::steady_clock::now();
        const ResponsePoint& r = curve.points[i];
        HarmonicForcing forcing = base.forcing();
        const double load = family.load(r.parameter);
        forcing.frequency_hz = r.frequency_hz;
        forcing.amplitude *= load;
        for (auto& more : forcing.more) more.amplitude *= load;
        ImpactStability s = impact_stability(base.system(), forcing, contacts, base.trial(), rigid_coefficients[i],
                                             o.samples, o.impact_stability);
        exact[i] = {s.available, std::move(s.message), s.distance, s.impacts};
        results[i] = std::move(s.floquet);
        results[i].monodromy.resize(0, 0);  // the multipliers suffice
        rigid_coefficients[i].resize(0, 0);
        seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - ti).count();
      };
      const int workers = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
      tbb::task_arena arena(std::max(1, workers));
      arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, results.size(), 1), [&](const tbb::blocked_range<size_t>& range) {
          for (size_t i = range.begin(); i != range.end(); ++i) impact_stability_of(i);
        });
      });
      for (double s : seconds) curve.stability_work_s += s;
    } else {
      results = penalty_stability->results(curve.points);
      curve.stability_work_s = penalty_stability->work_s;
      curve.stability_points_beside = penalty_stability->taken;
    }
    const FloquetResult* previous = nullptr;  // the last point with a verdict
    for (size_t i = 0; i < results.size(); ++i) {
      ResponsePoint& r = curve.points[i];
      const FloquetResult& fl = results[i];
      if (rigid) {
        r.shooting_distance = exact[i].distance;
        r.impacts = exact[i].impacts;
        if (!exact[i].available) {
          r.stability_available = false;
          r.stability_message = exact[i].message;
          r.stability_settled = false;
          r.stable = false;
          ++curve.unavailable_points;
          continue;
        }
      }
      r.stability_settled = fl.settled();
      if (!r.stability_settled) ++curve.unsettled_points;
      r.monodromy_steps = fl.steps;
      r.max_multiplier_error = fl.multiplier_errors.size() > 0 ? fl.multiplier_errors.maxCoeff() : 0.0;
      r.max_multiplier = fl.max_modulus;
      r.stable = fl.stable();
      if (fl.multipliers.size() > 0) r.leading_multiplier = fl.multipliers(0);
      if (previous != nullptr) r.crossing = classify_crossing(*previous, fl);
      previous = &fl;
    }
    curve.stability_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  // A fold of the truncated weighted-residual system and the Floquet crossing of its orbit need
  // not fall on the same step: on the stiff stop at H = 32 the crossing comes 4 points after the
  // fold. A crossing within kFoldWindow points on either side confirms it.
  constexpr size_t kFoldWindow = 4;
  for (const auto& fold : curve.folds) {
    bool crossing = false;
    // points[i].crossing is about the step (i − 1, i); the fold lies on the step (after, after + 1).
    const size_t first = fold.after >= kFoldWindow ? fold.after - kFoldWindow + 1 : 1;
    for (size_t i = first; o.stability && i < std::min(curve.points.size(), fold.after + kFoldWindow + 2); ++i) {
      crossing = crossing || curve.points[i].crossing == Bifurcation::Fold;
    }
    curve.fold_confirmed.push_back(crossing);
  }
  return curve;
}

}  // namespace wbm::solvers
