// Explicit central differences to a periodic steady state, for penalty laws and Jenkins elements
// (wbm/solvers/time_integration.hpp): the time-stepping reference of friction.
#include <wbm/solvers/time_integration.hpp>

#include <chrono>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "periodicity.hpp"

#include <wbm/contact/friction.hpp>

namespace wbm::solvers {

void CentralDifferenceOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("CentralDifferenceOptions." + what); };
  detail::validate_fixed_step(samples_per_period, steps_per_period, periodicity_tolerance, max_periods, fail);
}

namespace {

// The law's stiffness in contact, for the stability limit: k_t of a Jenkins element, else the
// stiffness just past the gap (a linear law's k, an exponential law's onset a_c α).
double contact_stiffness(const contact::ContactLaw& law) {
  if (const auto* jenkins = dynamic_cast<const contact::JenkinsLaw*>(&law)) return jenkins->parameters().tangential_stiffness;
  if (const auto* disc = dynamic_cast<const contact::JenkinsDiscLaw*>(&law)) return disc->parameters().tangential_stiffness;
  const double g = law.gap();
  return law.stiffness(g + 1e-9 * std::max(1.0, std::abs(g)));
}

}  // namespace

PeriodicResponse integrate_central_difference_to_periodic(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                                          const std::vector<ContactPoint>& contacts,
                                                          const CentralDifferenceOptions& options) {
  system.validate();
  forcing.validate(system.dofs());
  ContactPoint::validate(contacts, system.dofs());
  options.validate();
  forcing.require_resolved(options.samples_per_period,
                           "the P = " + std::to_string(options.samples_per_period) + " output samples per period",
                           "raise CentralDifferenceOptions.samples_per_period (and steps_per_period, a multiple of it)");
  const int n = system.dofs();
  const auto nc = static_cast<Eigen::Index>(contacts.size());
  std::vector<const contact::JenkinsLaw*> jenkins(static_cast<size_t>(nc), nullptr);
  for (Eigen::Index i = 0; i < nc; ++i) {
    const auto& ct = contacts[static_cast<size_t>(i)];
    jenkins[static_cast<size_t>(i)] = dynamic_cast<const contact::JenkinsLaw*>(ct.law.get());
    const bool disc = ct.second_tangent >= 0;  // a JenkinsDiscLaw (ContactPoint::validate)
    if (ct.law->rigid() || (ct.law->hysteretic() && jenkins[static_cast<size_t>(i)] == nullptr && !disc)) {
      throw std::invalid_argument("integrate_central_difference_to_periodic: the contact at DOF " + std::to_string(ct.dof) +
                                  " is a " + ct.law->describe() + "; this scheme takes force laws (penalty laws and "
                                  "Jenkins elements): use integrate_moreau_jean_to_periodic for rigid stops");
    }
  }
  const auto start = std::chrono::steady_clock::now();
  const double period = 1.0 / forcing.frequency_hz;
  const int steps = options.steps_per_period, p_count = options.samples_per_period;
  const int stride = steps / p_count;
  const double h = period / steps;
  const Eigen::MatrixXd m = Eigen::MatrixXd(system.mass), c = Eigen::MatrixXd(system.damping),
                        k = Eigen::MatrixXd(system.stiffness);
  Eigen::MatrixXd e_cols = Eigen::MatrixXd::Zero(n, nc);
  for (Eigen::Index i = 0; i < nc; ++i) e_cols.col(i) = contacts[static_cast<size_t>(i)].direction(n);
  {  // the stability limit h ω_max < 2, with the contacts closed
    Eigen::MatrixXd k_closed = k;
    for (Eigen::Index i = 0; i < nc; ++i) {
      k_closed += contact_stiffness(*contacts[static_cast<size_t>(i)].law) * e_cols.col(i) * e_cols.col(i).transpose();
    }
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k_closed, m, Eigen::EigenvaluesOnly);
    const double omega_max = std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
    if (!(h * omega_max < 2.0)) {
      const double needed = std::ceil(period * omega_max / 2.0 / p_count) * p_count;
      std::ostringstream msg;
      msg << "CentralDifferenceOptions.steps_per_period = " << steps << ": h omega_max = " << h * omega_max
          << " >= 2 (omega_max = " << omega_max << " rad/s with the contacts closed), the explicit scheme is unstable; "
          << "raise steps_per_period to at least " << needed << " (a multiple of samples_per_period)";
      throw std::invalid_argument(msg.str());
    }
  }
  // Dense inverses, formed once: M⁻¹ and (M + (h/2) C)⁻¹ (n is small), so that a step only
  // multiplies.
  const Eigen::MatrixXd minv = Eigen::LLT<Eigen::MatrixXd>(m).solve(Eigen::MatrixXd::Identity(n, n));
  const Eigen::MatrixXd end_inv = Eigen::PartialPivLU<Eigen::MatrixXd>(m + 0.5 * h * c).solve(Eigen::MatrixXd::Identity(n, n));
  const Eigen::MatrixXd end_m = end_inv * m;
  const std::vector<HarmonicLoad> loads = forcing.loads();
  const double omega = 2.0 * std::numbers::pi * forcing.frequency_hz;
  Eigen::VectorXd f_ext(n);
  auto external = [&](double t) {
    f_ext.setZero();
    for (const auto& l : loads) f_ext(l.dof) += l.amplitude * std::cos(omega * l.harmonic * t + l.phase_rad);
  };
  // The contact forces at q, the Jenkins elements stepping from their forces at the previous
  // contact displacements.
  Eigen::VectorXd f_contact = Eigen::VectorXd::Zero(nc), u_contact = Eigen::VectorXd::Zero(nc), u_new(nc);
  // Displacements relative to the counter-surfaces (ContactPoint::obstacle) at τ = t/T.
  auto update_contacts = [&](const Eigen::VectorXd& q, double tau) {
    for (Eigen::Index i = 0; i < nc; ++i) {
      const auto& ct = contacts[static_cast<size_t>(i)];
      u_new(i) = ct.displacement(q) - (ct.obstacle.moving() ? ct.obstacle.at(tau) : 0.0);
    }
    for (Eigen::Index i = 0; i < nc; ++i) {
      const auto& ct = contacts[static_cast<size_t>(i)];
      const double normal = ct.normal >= 0 ? contacts[static_cast<size_t>(ct.normal)].law->force(u_new(ct.normal)) : 0.0;
      if (const auto* jl = jenkins[static_cast<size_t>(i)]) {
        f_contact(i) = jl->return_map(f_contact(i), u_new(i) - u_contact(i), normal);
      } else if (const Eigen::Index j = ct.second_tangent; j > i) {  // both tangents of the disc at its first
        const auto& disc = static_cast<const contact::JenkinsDiscLaw&>(*ct.law);
        const Eigen::Vector2d f = disc.return_map({f_contact(i), f_contact(j)},
                                                  {u_new(i) - u_contact(i), u_new(j) - u_contact(j)}, normal);
        f_contact(i) = f(0);
        f_contact(j) = f(1);
      } else if (j < 0) {
        f_contact(i) = ct.law->force(u_new(i));
      }
    }
    u_contact = u_new;
  };

  PeriodicResponse out;
  out.frequency_hz = forcing.frequency_hz;
  out.tau = Eigen::VectorXd::LinSpaced(p_count, 0.0, 1.0 - 1.0 / p_count);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(n), v = Eigen::VectorXd::Zero(n), v_half(n), f_end(n);
  Eigen::MatrixXd disp(n, p_count), vel(n, p_count), force(nc, p_count);
  Eigen::VectorXd previous_tip;
  auto& rep = out.report;
  update_contacts(q, 0.0);  // a preloaded penalty law pushes at rest; a Jenkins element starts unstretched
  external(0.0);
  Eigen::VectorXd rhs = f_ext - k * q - c * v - e_cols * f_contact;  // the force balance at step k
  for (int period_index = 1; period_index <= options.max_periods; ++period_index) {
    for (int step = 0; step < steps; ++step) {
      if (step % stride == 0) {
        disp.col(step / stride) = q;
        vel.col(step / stride) = v;
        force.col(step / stride) = f_contact;
      }
      v_half.noalias() = minv * rhs;
      v_half = v + (0.5 * h) * v_half;
      q += h * v_half;
      // τ counts the periods from the start, so that a drifting counter-surface keeps sliding.
      update_contacts(q, static_cast<double>(period_index - 1) + static_cast<double>(step + 1) / steps);
      external(static_cast<double>(step + 1) * h);
      f_end = f_ext;
      f_end.noalias() -= k * q;
      f_end.noalias() -= e_cols * f_contact;
      v.noalias() = end_m * v_half;
      v_half.noalias() = end_inv * f_end;  // reused as scratch
      v += (0.5 * h) * v_half;
      rhs = f_end;
      rhs.noalias() -= c * v;
    }
    if (detail::end_of_period(q, v, period_index, steps, disp, forcing.dof, previous_tip, options.periodicity_tolerance,
                              rep)) {
      break;
    }
  }
  detail::finish_run(out, std::move(disp), std::move(vel), std::move(force), steps, "central-difference");
  rep.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace wbm::solvers
