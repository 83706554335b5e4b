// WeightedResidual, rigid stops: the collocation instants, the Delassus operator D = V H W, the
// Signorini conditions as a semismooth system (primal-dual active set) and their penalty homotopy
// (weighted_residual_impl.hpp).
#include "weighted_residual_impl.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/signorini.hpp>

namespace wbm::solvers {


Eigen::MatrixXd WeightedResidual::Impl::kinematic(const Eigen::MatrixXd& y) const {
  const Collocation& col = *collocation;
  if (!col.any_coulomb) return per_contact(col.trial_values, y);
  Eigen::MatrixXd out(y.rows(), y.cols());
  for (int c = 0; c < nc; ++c) {
    const Eigen::MatrixXd& t = col.coulomb[static_cast<size_t>(c)] != 0 ? col.increments : col.trial_values;
    const Eigen::MatrixXd y_c = y(Eigen::seq(c, Eigen::last, nc), Eigen::all);
    out(Eigen::seq(c, Eigen::last, nc), Eigen::all) = t * y_c;
  }
  return out;
}


// Fourier:Fourier, H commuting with shifts: D (and a stuck row) from H W's first block column
// (the impulses at τ_0), O(n_c² M²) instead of the O(n_c² M³) products of the general path. The
// impulses are uniform (midpoints or k/M), V's rows sit at τ_{k+1} and the increments' at τ_{k+1}
// and τ_k, so the response at row j to the impulse at k depends on j − k mod M only:
//   D(j·n_c + c, k·n_c + d) = D(((j − k) mod M)·n_c + c, d).
// This holds with the top function cos πMτ as well (its values at k/M are (−1)^k, at the
// midpoints 0). The same numbers as the general path to rounding (tests: both paths against
// the full system's impulse responses, with and without friction rows).
void WeightedResidual::Impl::set_delassus_circulant(Eigen::MatrixXd& v_hw0) {
  const Collocation& col = *collocation;
  const Eigen::Index size = static_cast<Eigen::Index>(nc) * m;
  Eigen::MatrixXd w0 = Eigen::MatrixXd::Zero(size, nc);  // (W ⊗ I) at the impulses of τ_0
  for (int l = 0; l < m; ++l) {
    for (int d = 0; d < nc; ++d) w0(static_cast<Eigen::Index>(l) * nc + d, d) = col.weights(l, 0);
  }
  const Eigen::MatrixXd hw0 = compliance_times(w0);
  const Eigen::MatrixXd d0 = kinematic(hw0);
  delassus.resize(size, size);
  for (int k = 0; k < m; ++k) {
    const Eigen::Index shift = static_cast<Eigen::Index>(k) * nc;
    for (int d = 0; d < nc; ++d) {
      auto column = delassus.col(shift + d);
      column.segment(shift, size - shift) = d0.col(d).head(size - shift);
      column.head(shift) = d0.col(d).tail(shift);
    }
  }
  if (col.any_coulomb) v_hw0 = per_contact(col.trial_values, hw0);
}


void WeightedResidual::Impl::set_delassus(bool set_force_compliance) {
  const Collocation& col = *collocation;
  const Eigen::Index size = static_cast<Eigen::Index>(nc) * m;
  // Fourier:Fourier: V (H W)'s first block column, for the stuck rows (friction only).
  Eigen::MatrixXd v_hw0;
  const bool circulant = commutes_with_shifts();
  Eigen::MatrixXd hw;  // H (W ⊗ I_{n_c}), the general path
  if (circulant) {
    set_delassus_circulant(v_hw0);
  } else if (nc == 1) {
    hw = compliance_times(col.weights);
  } else {
    // Column j·n_c + d of H (W ⊗ I) is Σ_b H(:, b·n_c + d) W(b, j): one dense (n_c·M × M)(M × M)
    // product per contact, O(n_c² M³) in all, instead of H times the n_c·M square W ⊗ I, which
    // is zero but for a 1/n_c share (on the 24 stops of the blade at M = 25, 41 % of a
    // continuation's time was that product).
    hw.resize(size, size);
    for (int d = 0; d < nc; ++d) {
      const auto cols = Eigen::seq(d, Eigen::last, nc);
      hw(Eigen::all, cols) = Eigen::MatrixXd(dense_h()(Eigen::all, cols)) * col.weights;
    }
  }
  if (!circulant) delassus = kinematic(hw);
  u_lin = kinematic(x_lin);
  if (set_force_compliance) {
    // c over the stops' rows, c_f over the friction rows; with one kind only both are the mean over
    // every row, evaluated on the diagonal expression as before friction existed (a contiguous
    // copy would be summed in another order: rigid-stop results would move by rounding).
    std::vector<Eigen::Index> stops, friction;
    for (Eigen::Index i = 0; i < delassus.rows(); ++i) {
      (col.coulomb[static_cast<size_t>(i % nc)] != 0 ? friction : stops).push_back(i);
    }
    if (stops.empty() || friction.empty()) {
      force_compliance = delassus.diagonal().cwiseAbs().mean();
      if (!(force_compliance > 0.0) || !std::isfinite(force_compliance)) force_compliance = 1.0;
      friction_compliance = force_compliance;
    } else {
      const Eigen::VectorXd d = delassus.diagonal().cwiseAbs();
      force_compliance = Eigen::VectorXd(d(stops)).mean();
      if (!(force_compliance > 0.0) || !std::isfinite(force_compliance)) force_compliance = 1.0;
      friction_compliance = Eigen::VectorXd(d(friction)).mean();
      if (!(friction_compliance > 0.0) || !std::isfinite(friction_compliance)) friction_compliance = force_compliance;
    }
  }
  if (!col.any_coulomb) return;
  // The row that replaces a stuck contact's first: its position u_c(τ_1) (row c of
  // V(τ_{k+1}) H W and of V x_lin).
  stuck_rows = Eigen::MatrixXd::Zero(nc, size);
  stuck_lin = Eigen::VectorXd::Zero(nc);
  stuck_row_of.clear();
  stuck_contact.clear();
  for (int c = 0; c < nc; ++c) {
    if (col.coulomb[static_cast<size_t>(c)] == 0) continue;
    const auto rows_c = Eigen::seq(c, Eigen::last, nc);
    const Eigen::VectorXd x_c = x_lin(rows_c);
    const auto e = static_cast<Eigen::Index>(stuck_row_of.size());
    if (circulant) {  // u_c(τ_1) per impulse k·n_c + d: row ((0 − k) mod M)·n_c + c of V H W's first block column
      for (int k = 0; k < m; ++k) {
        const Eigen::Index from = static_cast<Eigen::Index>((m - k) % m) * nc + c;
        stuck_rows.row(e).segment(static_cast<Eigen::Index>(k) * nc, nc) = v_hw0.row(from);
      }
    } else {
      stuck_rows.row(e) = col.trial_values.row(0) * Eigen::MatrixXd(hw(rows_c, Eigen::all));
    }
    stuck_lin(e) = col.trial_values.row(0).dot(x_c);
    stuck_row_of.push_back(c);
    stuck_contact.push_back(c);
  }
  stuck_rows.conservativeResize(static_cast<Eigen::Index>(stuck_row_of.size()), Eigen::NoChange);
  stuck_lin.conservativeResize(stuck_rows.rows());
}


void WeightedResidual::Impl::require_piece(const char* what, const ActiveSet* piece) const {
  if (piece == nullptr) return;
  if (collocation->any_coulomb) {
    throw std::logic_error(std::string("WeightedResidual::") + what + ": a piece (active set) is defined for rigid "
                           "stops without friction; a friction row has three branches (stick, slip either way): "
                           "call it without a piece");
  }
  if (piece->size() != static_cast<size_t>(nc) * static_cast<size_t>(m)) {
    throw std::invalid_argument(std::string("WeightedResidual::") + what + ": the piece has length " +
                                std::to_string(piece->size()) + ", expected n_c*M = " + std::to_string(nc * m) +
                                " (one entry per impulse, ordering k*n_c + c; from signorini_active_set)");
  }
}

Eigen::VectorXd WeightedResidual::Impl::signorini(const Eigen::VectorXd& lambda, double load, std::vector<int>* gap_rows,
                                                  std::vector<int>* pinned, const ActiveSet* piece,
                                                  std::vector<CoupledSlip>* coupled) const {
  require_factorized();
  const Collocation& col = *collocation;
  // The slips Δ (friction rows), and the stops' gaps in one expression, as before friction existed
  // (forming g0 − u from a stored u rounds differently in the last bits: rigid-stop results would
  // move by rounding). Each only when that kind of contact is present.
  // (Eigen forms the product first in both, so one product serves both bit for bit.)
  const Eigen::VectorXd d_lambda = delassus * lambda;
  Eigen::VectorXd u, gap;
  if (col.any_coulomb) u = load * u_lin - d_lambda;
  if (col.any_coulomb && col.slip_offsets.size() > 0) u -= col.slip_offsets;  // relative to the counter-surface
  if (std::find(col.coulomb.begin(), col.coulomb.end(), 0) != col.coulomb.end()) gap = col.gaps - (load * u_lin - d_lambda);
  Eigen::VectorXd phi(lambda.size());
  if (gap_rows != nullptr) gap_rows->clear();
  if (pinned != nullptr) pinned->clear();
  if (coupled != nullptr) coupled->clear();
  std::vector<char> slips(static_cast<size_t>(nc), 0);
  for (Eigen::Index i = 0; i < phi.size(); ++i) {
    const auto c = static_cast<size_t>(i % nc);
    bool d_branch = false;
    if (col.coulomb[c] != 0) {
      const auto cp = friction_row(lambda(i), u(i), slip_force(lambda, i));
      phi(i) = cp.value;
      d_branch = cp.stick;
      if (!cp.stick) slips[c] = 1;
      if (!cp.stick && coupled != nullptr && col.any_normal && col.normal_of[c] >= 0) {
        const auto j = static_cast<int>(i) - static_cast<int>(c) + col.normal_of[c];
        const double mu = col.friction_coefficients(static_cast<Eigen::Index>(c));
        if (lambda(j) > 0.0) coupled->push_back({static_cast<int>(i), j, cp.sigma * mu});
      }
    } else if (piece != nullptr) {  // the piece's branch
      d_branch = (*piece)[static_cast<size_t>(i)] != 0;
      phi(i) = d_branch ? gap(i) : force_compliance * lambda(i);
    } else {
      const auto cp = contact::signorini_min(force_compliance * lambda(i), gap(i));
      phi(i) = cp.value;
      d_branch = cp.gap_branch;
    }
    if (d_branch && gap_rows != nullptr) gap_rows->push_back(static_cast<int>(i));
  }
  for (size_t e = 0; e < stuck_row_of.size(); ++e) {
    if (slips[static_cast<size_t>(stuck_contact[e])] != 0) continue;
    // Full stick: the slips Δ_k sum to zero over the period, so the rows leave the contact's
    // position free: pinned at u(τ_1) = 0, the Jenkins convention as k_t → ∞.
    const auto ee = static_cast<Eigen::Index>(e);
    phi(stuck_row_of[e]) = friction_weight() * (stuck_rows.row(ee).dot(lambda) - load * stuck_lin(ee));
    if (col.pin_offsets.size() > 0) phi(stuck_row_of[e]) += friction_weight() * col.pin_offsets(stuck_contact[e]);
    if (pinned != nullptr) pinned->push_back(static_cast<int>(e));
  }
  return phi;
}


Eigen::MatrixXd WeightedResidual::Impl::constraint_rows(const std::vector<int>& rows, const std::vector<int>& pinned) const {
  Eigen::MatrixXd out = delassus(rows, Eigen::all);
  for (int e : pinned) {
    const auto at = std::find(rows.begin(), rows.end(), stuck_row_of[static_cast<size_t>(e)]);
    if (at != rows.end()) out.row(at - rows.begin()) = stuck_rows.row(e);
  }
  if (collocation->any_coulomb) {  // friction rows carry the weight ρ
    for (size_t r = 0; r < rows.size(); ++r) {
      if (collocation->coulomb[static_cast<size_t>(rows[r] % nc)] != 0) out.row(static_cast<Eigen::Index>(r)) *= friction_weight();
    }
  }
  return out;
}
bool WeightedResidual::rigid() const { return impl_->rigid; }

Eigen::VectorXd WeightedResidual::collocation_times() const {
  impl_->require_rigid("collocation_times");
  return impl_->collocation->tau;
}

const Eigen::MatrixXd& WeightedResidual::delassus() const {
  impl_->require_rigid("delassus");
  impl_->require_factorized();
  return impl_->delassus;
}

double WeightedResidual::force_compliance() const {
  impl_->require_rigid("force_compliance");
  impl_->require_factorized();
  return impl_->force_compliance;
}

Eigen::VectorXd WeightedResidual::signorini_residual(const Eigen::VectorXd& lambda, double load,
                                                     const ActiveSet* piece) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_residual");
  if (lambda.size() != static_cast<Eigen::Index>(p.nc) * p.m) {
    throw std::invalid_argument("WeightedResidual::signorini_residual: lambda has length " + std::to_string(lambda.size()) +
                                ", expected n_c*M = " + std::to_string(p.nc * p.m));
  }
  p.require_piece("signorini_residual", piece);
  return p.signorini(lambda, load, nullptr, nullptr, piece) / p.scale;
}

ActiveSet WeightedResidual::signorini_active_set(const Eigen::VectorXd& lambda, double load) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_active_set");
  if (p.collocation->any_coulomb) {
    throw std::logic_error("WeightedResidual::signorini_active_set: pieces are defined for rigid stops without "
                           "friction (a friction row has three branches: stick, slip either way)");
  }
  std::vector<int> gap_rows;
  (void)p.signorini(lambda, load, &gap_rows);
  ActiveSet a(static_cast<size_t>(p.nc) * static_cast<size_t>(p.m), 0);
  for (int i : gap_rows) a[static_cast<size_t>(i)] = 1;
  return a;
}

Eigen::VectorXd WeightedResidual::signorini_events(const Eigen::VectorXd& lambda, double load, const ActiveSet& piece) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_events");
  p.require_piece("signorini_events", &piece);
  // The other branch's value: on a gap row the force c λ, on a force row the gap g0 − u, each in
  // the same expression as signorini() (the event is the row the piece does not hold).
  ActiveSet other = piece;
  for (auto& e : other) e ^= 1U;
  return p.signorini(lambda, load, nullptr, nullptr, &other) / p.scale;
}

LowRankJacobian WeightedResidual::signorini_jacobian(const Eigen::VectorXd& lambda, double load,
                                                     const ActiveSet* piece) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_jacobian");
  p.require_piece("signorini_jacobian", piece);
  std::vector<int> active, pinned;
  std::vector<Impl::CoupledSlip> coupled;
  (void)p.signorini(lambda, load, &active, &pinned, piece, &coupled);
  const Eigen::Index size = lambda.size();
  const double c = p.force_compliance;
  LowRankJacobian jac;
  jac.scale = p.scale / c;  // J = (c/s_r)(I + P_A (D/c − I)_A)
  jac.rows = size;
  Eigen::MatrixXd d_rows = p.constraint_rows(active, pinned) / c;  // (D/c)_A, r × n
  if (!coupled.empty()) {  // slip rows on a pushing stop: c λ_i − σ μ c λ_j, the row e_i − σ μ e_j
    const auto gap_rank = static_cast<Eigen::Index>(active.size());
    d_rows.conservativeResize(gap_rank + static_cast<Eigen::Index>(coupled.size()), Eigen::NoChange);
    for (size_t e = 0; e < coupled.size(); ++e) {
      auto row = d_rows.row(gap_rank + static_cast<Eigen::Index>(e));
      row.setZero();
      row(coupled[e].row) = 1.0;
      row(coupled[e].normal_row) = -coupled[e].sigma_mu;
      active.push_back(coupled[e].row);
    }
  }
  const auto rank = static_cast<Eigen::Index>(active.size());
  if (4 * rank > 3 * size) {  // dense form: s J = I with the gap rows replaced by D/c
    jac.capacitance = Eigen::MatrixXd::Identity(size, size);
    for (Eigen::Index i = 0; i < rank; ++i) jac.capacitance.row(active[static_cast<size_t>(i)]) = d_rows.row(i);
    return jac;
  }
  jac.u = Eigen::MatrixXd::Zero(size, rank);
  for (Eigen::Index i = 0; i < rank; ++i) jac.u(active[static_cast<size_t>(i)], i) = 1.0;
  auto rows = std::make_shared<Eigen::MatrixXd>(d_rows);
  for (Eigen::Index i = 0; i < rank; ++i) (*rows)(i, active[static_cast<size_t>(i)]) -= 1.0;
  jac.capacitance = d_rows(Eigen::all, active);  // I + (D/c − I)_AA
  jac.times_v = [rows](const Eigen::MatrixXd& y) { return Eigen::MatrixXd(*rows * y); };
  return jac;
}

Eigen::VectorXd WeightedResidual::signorini_frequency_derivative(const Eigen::VectorXd& lambda, double load,
                                                                 const ActiveSet* piece) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_frequency_derivative");
  p.require_piece("signorini_frequency_derivative", piece);
  std::vector<int> gap_rows, pinned;
  (void)p.signorini(lambda, load, &gap_rows, &pinned, piece);
  const Eigen::MatrixXd a = spectral::as_coefficients(expand_forces(lambda, load), p.n);  // n × M
  // G′ a, then P G⁻¹, then the kinematic rows (trial values at τ_{k+1}, or their increments).
  const Eigen::VectorXd dx = p.gather(p.solve_stacked(p.frequency_derivative_times(a), false));
  const Eigen::VectorXd du = p.kinematic(dx);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(lambda.size());
  for (int i : gap_rows) out(i) = du(i) / p.scale;  // g = g0 − u and ∂u/∂f = −V P G⁻¹ G′ a
  for (int e : pinned) {  // the position row, −u(τ_1)
    const auto i = static_cast<size_t>(e);
    const Eigen::VectorXd dx_c = dx(Eigen::seq(p.stuck_contact[i], Eigen::last, p.nc));
    out(p.stuck_row_of[i]) = p.collocation->trial_values.row(0).dot(dx_c) / p.scale;
  }
  p.weigh_friction_rows(out);
  return out;
}

Eigen::VectorXd WeightedResidual::signorini_load_derivative(const Eigen::VectorXd& lambda, double load,
                                                            const ActiveSet* piece) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_load_derivative");
  p.require_piece("signorini_load_derivative", piece);
  std::vector<int> gap_rows, pinned;
  (void)p.signorini(lambda, load, &gap_rows, &pinned, piece);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(lambda.size());
  for (int i : gap_rows) out(i) = -p.u_lin(i) / p.scale;
  for (int e : pinned) out(p.stuck_row_of[static_cast<size_t>(e)]) = -p.stuck_lin(e) / p.scale;
  p.weigh_friction_rows(out);
  return out;
}

Eigen::VectorXd WeightedResidual::expand_forces(const Eigen::VectorXd& lambda, double load) const {
  const auto& p = *impl_;
  p.require_rigid("expand_forces");
  p.require_factorized();
  Eigen::VectorXd rhs = load * p.b;
  const Eigen::VectorXd nx = p.collocation_forces(lambda);
  p.scatter(rhs, nx, -1.0);
  return p.solve_stacked(rhs, false);
}

Eigen::VectorXd WeightedResidual::residual(const Eigen::VectorXd& a, const Eigen::VectorXd& lambda) const {
  const auto& p = *impl_;
  p.require_rigid("residual(a, lambda)");
  Eigen::VectorXd r = p.linear_residual(a);
  const Eigen::VectorXd nx = p.collocation_forces(lambda);
  p.scatter(r, nx, 1.0);
  return r;
}

// The Signorini conditions at load s as a NonlinearSystem on λ (rigid stops).
struct WeightedResidual::Signorini {
  const WeightedResidual* wr;
  double load;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& lambda) const { return wr->signorini_residual(lambda, load); }
  [[nodiscard]] LowRankJacobian jacobian(const Eigen::VectorXd& lambda) const { return wr->signorini_jacobian(lambda, load); }
};

// The Signorini conditions regularized by a penalty of relative stiffness κ = 10^μ at the same
// instants, as a ParametrizedSystem in μ (rigid stops):
//   r(λ, μ) = (c λ − κ (u(λ) − g0)₊) / s_r,   ∂r/∂λ = (c I + κ P_A D) / s_r,
//   ∂r/∂μ = −ln 10 · κ (u − g0)₊ / s_r,   A = the instants that penetrate.
// Its solutions are those of the linear penalty k = κ/c at the instants; as κ → ∞ they tend to
// the rigid one (penetration c λ/κ).
struct WeightedResidual::SignoriniPenalty {
  const WeightedResidual* wr;
  [[nodiscard]] Eigen::VectorXd penetration(const Eigen::VectorXd& lambda) const {
    const auto& p = *wr->impl_;
    return ((p.u_lin - p.delassus * lambda) - p.collocation->gaps).cwiseMax(0.0);
  }
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& lambda, double mu) const {
    const auto& p = *wr->impl_;
    return (p.force_compliance * lambda - std::pow(10.0, mu) * penetration(lambda)) / p.scale;
  }
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& lambda, double mu) const {
    const auto& p = *wr->impl_;
    const double kappa = std::pow(10.0, mu);
    const Eigen::VectorXd pen = penetration(lambda);
    Linearization l;
    l.residual = (p.force_compliance * lambda - kappa * pen) / p.scale;
    l.jacobian = Eigen::MatrixXd::Zero(lambda.size(), lambda.size());
    for (Eigen::Index i = 0; i < lambda.size(); ++i) {
      if (pen(i) > 0.0) l.jacobian.row(i) = (kappa / p.scale) * p.delassus.row(i);
      l.jacobian(i, i) += p.force_compliance / p.scale;
    }
    l.parameter_derivative = (-std::log(10.0) * kappa / p.scale) * pen;
    return l;
  }
};

NewtonResult WeightedResidual::solve_rigid_with_penalty_homotopy(HomotopyReport& report) const {
  const auto& p = *impl_;
  // From κ₀ = 10⁻², where λ ≈ κ₀ (u_lin − g0)₊ / c barely moves the structure, to κ = 10⁸
  // (penetration about 10⁻⁸ c λ), then the active-set Newton on the exact conditions.
  constexpr double kMuStart = -2.0, kMuEnd = 8.0;
  report.lambda_start = kMuStart;
  const SignoriniPenalty system{this};
  const Eigen::VectorXd start = std::pow(10.0, kMuStart) * system.penetration(Eigen::VectorXd::Zero(p.u_lin.size())) /
                                p.force_compliance;
  // λ in newtons: the state scaled so that c λ is compared with s_r in metres.
  const PseudoArclengthOptions o = detail::homotopy_continuation(kMuStart - 1.0, kMuEnd, p.scale / p.force_compliance, p.options);
  const Branch branch = pseudo_arclength(system, start, kMuStart, o);
  detail::record_homotopy(branch, kMuEnd, report);
  // Newton on the exact conditions from the stiffest penalty point reached: near the end of the
  // path its active set is the rigid one.
  Eigen::VectorXd guess = branch.points.empty() ? start : branch.points.back().x;
  NewtonResult out = newton(Signorini{this, 1.0}, std::move(guess), p.options.newton);
  out.report.iterations += static_cast<int>(branch.corrector_iterations);
  out.report.message = "penalty homotopy of the Signorini conditions, kappa from 1e" + format_number(kMuStart) +
                       " to " + format_number(report.sigma_reached) + " (" + std::to_string(report.points) + " points, " +
                       std::to_string(report.folds) + " folds; " + std::string(to_string(branch.stop)) + ": " +
                       report.message + "), then the active-set Newton: " +
                       out.report.message;
  if (!out.report.converged() && branch.stop != StopReason::RangeReached) out.report.status = SolveStatus::PathEnded;
  report.status = out.report.status;
  return out;
}

NewtonResult WeightedResidual::solve_exact_with_load_stepping(int& steps) const {
  // detail::load_stepping on the exact conditions from λ = 0, the secant predictor, steps of at
  // most ¼: each step changes the active set less (a mixed stop and friction contact stagnated
  // with ½, tests/solvers/test_friction.cpp).
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(impl_->u_lin.size());
  return detail::load_stepping([this](double s) { return Signorini{this, s}; }, secant_predictor, zero, zero,
                               impl_->options.newton, 0.25, steps);
}

WeightedResidualSolution WeightedResidual::solve_rigid(const Eigen::VectorXd* lambda0, WeightedResidualSolution s,
                                                       std::chrono::steady_clock::time_point start) const {
  const auto& p = *impl_;
  const Eigen::Index size = static_cast<Eigen::Index>(p.nc) * p.m;
  const Eigen::VectorXd l0 = lambda0 != nullptr ? *lambda0 : Eigen::VectorXd::Zero(size);
  if (l0.size() != size) {
    throw std::invalid_argument("WeightedResidual::solve: initial contact forces have length " + std::to_string(l0.size()) +
                                ", expected n_c*M = " + std::to_string(size) + " (rigid stops: the force samples λ)");
  }
  NewtonResult result = newton(Signorini{this, 1.0}, l0, p.options.newton);
  s.path = SolutionPath::DirectNewton;
  std::string history = "primal-dual active set (semismooth Newton on the Signorini conditions): " + result.report.message;
  if (!result.report.converged() && lambda0 == nullptr && p.options.contact_homotopy && p.collocation->any_coulomb) {
    // Exact friction has no penalty homotopy (its regularization, the Jenkins element, has a
    // state): the load is stepped instead, s: 0 → 1, from λ = 0 (at s = 0 every contact sticks or
    // stays open), each step's active-set Newton from the secant prediction.
    int steps = 0;
    NewtonResult stepped = solve_exact_with_load_stepping(steps);
    stepped.report.iterations += result.report.iterations;
    history += "; load stepping (" + std::to_string(steps) + " steps): " + stepped.report.message;
    if (stepped.report.converged()) s.path = SolutionPath::LoadStepping;
    result = std::move(stepped);
    if (!result.report.converged()) {
      // The active-set iteration with full steps (weighted_residual.hpp: the backtracking on ‖φ‖
      // stalls where an instant changes branch); a cycle of the residual norms ends it.
      NewtonOptions full = p.options.newton;
      full.line_search = false;
      full.levenberg_marquardt = false;
      full.stop_on_cycle = true;
      full.max_iterations = std::max(full.max_iterations, p.m);  // measured: 10 … 96 at M = 32 … 512
      NewtonResult pdas = newton(Signorini{this, 1.0}, Eigen::VectorXd::Zero(size), full);
      pdas.report.iterations += result.report.iterations;
      history += "; full-step active set from zero impulses: " + pdas.report.message;
      if (pdas.report.converged()) s.path = SolutionPath::FullStepActiveSet;
      result = std::move(pdas);
    }
  } else if (!result.report.converged() && lambda0 == nullptr && p.options.contact_homotopy) {
    NewtonResult h = solve_rigid_with_penalty_homotopy(s.homotopy);
    h.report.iterations += result.report.iterations;
    history += "; " + h.report.message;
    if (h.report.converged()) s.path = SolutionPath::ContactHomotopy;
    result = std::move(h);
  }
  s.report = std::move(result.report);
  s.report.message = history;
  const Eigen::VectorXd& lambda = result.x;
  const Eigen::VectorXd a = expand_forces(lambda);
  s.coefficients = spectral::as_coefficients(a, p.n);
  s.contact_force_samples = spectral::as_coefficients(lambda, p.nc);
  s.collocation_times = p.collocation->tau;
  const double bnorm = p.b.norm();
  const Eigen::VectorXd full = residual(a, lambda);
  s.relative_residual = full.norm() / (bnorm > 0.0 ? bnorm : 1.0);
  s.backward_error = backward_error(a, full);
  s.residual_tolerance = p.options.residual_tolerance;
  // The conditions recomputed from the coefficients, not from D λ.
  const Eigen::VectorXd xa = p.gather(a);
  const auto& col = *p.collocation;
  Eigen::VectorXd kin = p.kinematic(xa);  // u_c(τ_{k+1}) at a stop, Δ_k for friction
  if (col.slip_offsets.size() > 0) kin -= col.slip_offsets;  // friction's slip relative to the counter-surface
  Eigen::VectorXd phi(size);
  s.collocation_penetration = -std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < size; ++i) {
    const auto c = static_cast<size_t>(i % p.nc);
    if (col.coulomb[c] != 0) {
      phi(i) = p.friction_row(lambda(i), kin(i), p.slip_force(lambda, i)).value;
    } else {
      phi(i) = contact::signorini_min(p.force_compliance * lambda(i), col.gaps(i) - kin(i)).value;
      s.collocation_penetration = std::max(s.collocation_penetration, kin(i) - col.gaps(i));
    }
  }
  for (int c = 0; c < p.nc; ++c) {  // a stuck friction contact: u(τ_1) = 0 (relative: = s(τ_1))
    if (col.coulomb[static_cast<size_t>(c)] == 0) continue;
    bool slips = false;
    for (int k = 0; k < p.m; ++k) {
      const Eigen::Index i = static_cast<Eigen::Index>(k) * p.nc + c;
      slips = slips || !p.friction_row(lambda(i), kin(i), p.slip_force(lambda, i)).stick;
    }
    if (slips) continue;
    const Eigen::VectorXd x_c = xa(Eigen::seq(c, Eigen::last, p.nc));
    phi(c) = p.friction_weight() *
             (col.trial_values.row(0).dot(x_c) - (col.pin_offsets.size() > 0 ? col.pin_offsets(c) : 0.0));
  }
  s.complementarity = phi.cwiseAbs().maxCoeff();
  s.max_contact_force = lambda.cwiseAbs().maxCoeff();
  const Eigen::MatrixXd u = p.contact_samples(xa);
  s.max_penetration = -std::numeric_limits<double>::infinity();
  for (int c = 0; c < p.nc; ++c) {
    if (col.coulomb[static_cast<size_t>(c)] == 0) {
      s.max_penetration = std::max(s.max_penetration, u.row(c).maxCoeff() - p.contacts[c].law->gap());
    }
  }
  if (!std::isfinite(s.collocation_penetration)) s.collocation_penetration = std::numeric_limits<double>::quiet_NaN();
  if (!std::isfinite(s.max_penetration)) s.max_penetration = std::numeric_limits<double>::quiet_NaN();
  const double phi_norm = detail::residual_norm(phi / p.scale, p.options.newton.norm);
  if (s.report.converged() && (!std::isfinite(s.relative_residual) || !s.coefficients.allFinite())) {
    s.report.status = SolveStatus::NonFinite;
    s.report.message = "non-finite full residual after convergence of the Signorini conditions";
  } else if (s.report.converged() && !(s.backward_error <= p.options.residual_tolerance &&
                                       phi_norm <= p.options.newton.tolerance)) {
    s.report.status = SolveStatus::ResidualNotVerified;
    s.report.message = "the Signorini conditions converged (" + s.report.message + "), but recomputed from the "
                       "coefficients the full residual is " + format_number(s.relative_residual) + " ‖b‖, backward "
                       "error " + format_number(s.backward_error) + " (bound " +
                       format_number(p.options.residual_tolerance) + ") and the complementarity residual " +
                       format_number(phi_norm) + " s_r (bound " + format_number(p.options.newton.tolerance) +
                       "; condition estimate of G " + format_number(s.condition_number) + ")";
  }
  s.wall_time_s = detail::elapsed(start);
  return s;
}
}  // namespace wbm::solvers
