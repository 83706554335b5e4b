// Moreau–Jean time stepping to a periodic steady state: rigid stops (impulses, Newton's
// restitution law) and exact Coulomb friction (time_integration.hpp).
#include <wbm/solvers/time_integration.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>

#include <Eigen/LU>

#include <wbm/contact/friction.hpp>

#include "reference/friction_contact_step.hpp"
#include "periodicity.hpp"

namespace wbm::solvers {

namespace {

// Projected Gauss–Seidel sweeps on the contact LCP of one Moreau–Jean step, at most.
constexpr int kLcpSweeps = 1000;
// A frictional step is counted as unsettled when Siconos reports failure or the error of its
// solution (fc2d_compute_error, relative to ‖q‖) exceeds this.
constexpr double kFrictionError = 1e-10;

// One contact of the fc2d problem of a step: a normal row and a tangent row.
struct FrictionalContact {
  Eigen::Index normal = -1;   // the rigid stop (index in the contact list), or −1: a constant load
  Eigen::Index tangent = -1;  // the exact Coulomb contact, or −1: a frictionless stop
  double mu = 0.0;            // friction coefficient [-]
  double load = 0.0;          // the constant normal load N [N] when normal = −1
};

const contact::CoulombFriction* coulomb(const ContactPoint& c) {
  return dynamic_cast<const contact::CoulombFriction*>(c.law.get());
}

// The contacts of the fc2d problem, or none when no contact has friction (the stops then go to
// projected Gauss–Seidel, as before friction existed). Checks the laws (the pairing: ContactPoint::validate).
std::vector<FrictionalContact> frictional_contacts(const std::vector<ContactPoint>& contacts) {
  const auto nc = static_cast<Eigen::Index>(contacts.size());
  std::vector<FrictionalContact> out;
  std::vector<Eigen::Index> friction_of(static_cast<size_t>(nc), -1);
  for (Eigen::Index i = 0; i < nc; ++i) {
    const auto& c = contacts[static_cast<size_t>(i)];
    const auto* law = coulomb(c);
    if (law == nullptr) continue;
    if (c.normal == -1) {
      out.push_back({-1, i, law->parameters().friction_coefficient, law->parameters().normal_load});
      continue;
    }
    friction_of[static_cast<size_t>(c.normal)] = i;  // ContactPoint::validate: a rigid stop, one tangent each
  }
  bool friction = false;
  for (Eigen::Index i = 0; i < nc; ++i) {
    const auto& c = contacts[static_cast<size_t>(i)];
    const bool stop = c.law->rigid() && !c.law->hysteretic();
    if (coulomb(c) != nullptr) {
      friction = true;
    } else if (!stop) {
      throw std::invalid_argument("integrate_moreau_jean_to_periodic: the contact at DOF " + std::to_string(c.dof) +
                                  " is a " + c.law->describe() + "; this scheme takes rigid stops (contact::RigidStop) "
                                  "and exact Coulomb friction (contact::CoulombFriction) only: use "
                                  "integrate_to_periodic for penalty laws, integrate_central_difference_to_periodic "
                                  "for Jenkins elements");
    }
  }
  if (!friction) return {};
  for (Eigen::Index i = 0; i < nc; ++i) {
    const auto& c = contacts[static_cast<size_t>(i)];
    if (coulomb(c) != nullptr) continue;
    const Eigen::Index t = friction_of[static_cast<size_t>(i)];
    out.push_back({i, t, t >= 0 ? coulomb(contacts[static_cast<size_t>(t)])->parameters().friction_coefficient : 0.0, 0.0});
  }
  return out;
}

// The fc2d problem of one step on the frictional contacts `act` (indices into `pairs`), from the
// Delassus matrix W of every contact direction and the velocities towards the contacts without
// impulse (u_free) and at the step's start (u_old); its impulses are written into `impulse`.
// The local velocities are those away from the contacts, u = −Eᵀ v_{k+1} (the tangent's sign
// makes Siconos' r_t = −μ r_n sign(u_t) a force opposing e_tᵀ v).
void frictional_step(const std::vector<FrictionalContact>& pairs, const std::vector<size_t>& act,
                     const Eigen::MatrixXd& delassus, const Eigen::VectorXd& u_free, const Eigen::VectorXd& u_old,
                     double e, double h, detail::FrictionContactStep& solver, Eigen::VectorXd& impulse,
                     TimeIntegrationReport& rep) {
  const auto m = static_cast<Eigen::Index>(act.size());
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(2 * m, 2 * m);
  Eigen::VectorXd q(2 * m), mu(m), r;
  auto index = [&](Eigen::Index a, int side) {
    const auto& f = pairs[act[static_cast<size_t>(a)]];
    return side == 0 ? f.normal : f.tangent;
  };
  for (Eigen::Index a = 0; a < m; ++a) {
    for (Eigen::Index b = 0; b < m; ++b) {
      for (int s = 0; s < 2; ++s) {
        for (int t = 0; t < 2; ++t) {
          const Eigen::Index i = index(a, s), j = index(b, t);
          if (i >= 0 && j >= 0) w(2 * a + s, 2 * b + t) = delassus(i, j);
        }
      }
    }
  }
  for (Eigen::Index a = 0; a < m; ++a) {
    const auto& f = pairs[act[static_cast<size_t>(a)]];
    mu(a) = f.mu;
    if (f.normal >= 0) {
      q(2 * a) = -(u_free(f.normal) + e * u_old(f.normal));  // Newton's law on the normal velocity
    } else {
      // A constant normal load: a decoupled normal row u_n = d (r_n − h N) ⊥ r_n ≥ 0 gives
      // r_n = h N, the impulse of N over the step (d scales the row like the tangent's).
      w(2 * a, 2 * a) = delassus(f.tangent, f.tangent);
      q(2 * a) = -w(2 * a, 2 * a) * h * f.load;
    }
    if (f.tangent >= 0) {
      q(2 * a + 1) = -u_free(f.tangent);
    } else {
      w(2 * a + 1, 2 * a + 1) = delassus(f.normal, f.normal);  // a frictionless stop: μ = 0, r_t = 0
      q(2 * a + 1) = 0.0;
    }
  }
  const auto outcome = solver.solve(w, q, mu, r);
  if (outcome.info != 0 || !(outcome.error <= kFrictionError)) {
    ++rep.unsettled_lcp_steps;
    rep.largest_lcp_change = std::max(rep.largest_lcp_change, std::isfinite(outcome.error) ? outcome.error : INFINITY);
  }
  for (Eigen::Index a = 0; a < m; ++a) {
    const auto& f = pairs[act[static_cast<size_t>(a)]];
    if (f.normal >= 0) impulse(f.normal) = r(2 * a);
    if (f.tangent >= 0) impulse(f.tangent) = r(2 * a + 1);
  }
}

}  // namespace

void MoreauJeanOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("MoreauJeanOptions." + what); };
  detail::validate_fixed_step(samples_per_period, steps_per_period, periodicity_tolerance, max_periods, fail);
  if (!(theta >= 0.5 && theta <= 1.0)) fail("theta = " + std::to_string(theta) + ": must lie in [0.5, 1]");
  if (!(restitution >= 0.0 && restitution <= 1.0)) fail("restitution = " + std::to_string(restitution) + ": must lie in [0, 1]");
}

PeriodicResponse integrate_moreau_jean_to_periodic(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                                   const std::vector<ContactPoint>& contacts,
                                                   const MoreauJeanOptions& options) {
  system.validate();
  forcing.validate(system.dofs());
  ContactPoint::validate(contacts, system.dofs());  // also the pairing of exact Coulomb contacts with stops
  require_fixed_obstacles(contacts, "integrate_moreau_jean_to_periodic",
                          "solve it by the weighted residual (any pair), which takes moving counter-surfaces");
  options.validate();
  forcing.require_resolved(options.samples_per_period,
                           "the P = " + std::to_string(options.samples_per_period) + " output samples per period",
                           "raise MoreauJeanOptions.samples_per_period (and steps_per_period, a multiple of it)");
  const std::vector<FrictionalContact> pairs = frictional_contacts(contacts);
  std::optional<detail::FrictionContactStep> fc2d;  // Siconos' solver options, with friction only
  if (!pairs.empty()) fc2d.emplace();
  const auto start = std::chrono::steady_clock::now();
  const int n = system.dofs();
  const auto nc = static_cast<Eigen::Index>(contacts.size());
  const double period = 1.0 / forcing.frequency_hz;
  const int steps = options.steps_per_period, p_count = options.samples_per_period;
  const int stride = steps / p_count;
  const double h = period / steps, th = options.theta, e = options.restitution;
  const Eigen::MatrixXd m = Eigen::MatrixXd(system.mass), c = Eigen::MatrixXd(system.damping),
                        k = Eigen::MatrixXd(system.stiffness);
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(m + h * th * c + h * h * th * th * k);
  Eigen::MatrixXd e_cols = Eigen::MatrixXd::Zero(n, nc);
  for (Eigen::Index i = 0; i < nc; ++i) e_cols.col(i) = contacts[static_cast<size_t>(i)].direction(n);
  // Eigen's triangular solve takes the address of the first entry, so an n × 0 right-hand side
  // (no contacts) is undefined behaviour there: skip it.
  const Eigen::MatrixXd minv_e = nc > 0 ? Eigen::MatrixXd(lu.solve(e_cols)) : Eigen::MatrixXd(n, 0);  // M̂⁻¹ E
  const Eigen::MatrixXd delassus = e_cols.transpose() * minv_e;     // W
  // v_free = M̂⁻¹ [(M − h(1−θ)C − h²θ(1−θ)K) v − hK q + h f_θ]
  const Eigen::MatrixXd a_v = lu.solve(m - h * (1.0 - th) * c - h * h * th * (1.0 - th) * k);
  const Eigen::MatrixXd a_q = lu.solve(-h * k);
  const std::vector<HarmonicLoad> loads = forcing.loads();
  const auto nl = static_cast<Eigen::Index>(loads.size());
  Eigen::MatrixXd e_loads = Eigen::MatrixXd::Zero(n, nl);
  for (Eigen::Index j = 0; j < nl; ++j) e_loads(loads[static_cast<size_t>(j)].dof, j) = h;
  const Eigen::MatrixXd a_f = lu.solve(e_loads);  // h M̂⁻¹ e_{dof_j}
  const double omega = 2.0 * std::numbers::pi * forcing.frequency_hz;
  Eigen::VectorXd f_theta(nl);  // θ F_j cos(ω h_j t1 + φ_j) + (1 − θ) F_j cos(ω h_j t0 + φ_j)

  PeriodicResponse out;
  out.frequency_hz = forcing.frequency_hz;
  out.tau = Eigen::VectorXd::LinSpaced(p_count, 0.0, 1.0 - 1.0 / p_count);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(n), v = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd disp(n, p_count), vel(n, p_count), force(nc, p_count);
  Eigen::VectorXd previous_tip, impulse(nc), u_free(nc), u_old(nc);
  auto& rep = out.report;
  const Eigen::SparseMatrix<double>& damping = system.damping;
  for (int period_index = 1; period_index <= options.max_periods; ++period_index) {
    double input = 0.0, dissipated = 0.0, absorbed = 0.0;  // work over this period [J]
    for (int step = 0; step < steps; ++step) {
      if (step % stride == 0) {
        disp.col(step / stride) = q;
        vel.col(step / stride) = v;
        force.col(step / stride).setZero();
      }
      const double t0 = static_cast<double>(step) * h, t1 = t0 + h;  // the forcing has period T
      for (Eigen::Index j = 0; j < nl; ++j) {
        const auto& l = loads[static_cast<size_t>(j)];
        f_theta(j) = l.amplitude * (th * std::cos(omega * l.harmonic * t1 + l.phase_rad) +
                                    (1.0 - th) * std::cos(omega * l.harmonic * t0 + l.phase_rad));
      }
      Eigen::VectorXd v_new = a_v * v + a_q * q + a_f * f_theta;
      impulse.setZero();
      if (nc > 0) {
        std::vector<Eigen::Index> active;
        for (Eigen::Index i = 0; i < nc; ++i) {
          const auto& ct = contacts[static_cast<size_t>(i)];
          u_old(i) = ct.displacement(v);
          u_free(i) = ct.displacement(v_new);
          if (ct.law->gap() - ct.displacement(q) - 0.5 * h * u_old(i) <= 0.0) active.push_back(i);
        }
        if (!pairs.empty()) {
          // With friction, one fc2d problem (Siconos) on the stops whose predicted gap is closed
          // and the Coulomb contacts with a constant load μ N > 0.
          std::vector<size_t> act;
          for (size_t a = 0; a < pairs.size(); ++a) {
            const auto& f = pairs[a];
            if (f.normal >= 0 ? std::find(active.begin(), active.end(), f.normal) != active.end()
                              : f.mu * f.load > 0.0) {
              act.push_back(a);
            }
          }
          if (!act.empty()) frictional_step(pairs, act, delassus, u_free, u_old, e, h, *fc2d, impulse, rep);
        } else {
          // LCP on the active set: w = W P − (U_free + e U_old) ≥ 0, P ≥ 0, wᵀP = 0, by projected
          // Gauss–Seidel until the impulses change by at most 1e-14 of the largest, or kLcpSweeps
          // sweeps (counted in the report when they end unsettled).
          bool settled = active.empty();
          double change = 0.0, size = 0.0;
          for (int sweep = 0; sweep < kLcpSweeps && !active.empty(); ++sweep) {
            change = 0.0;
            size = 0.0;
            for (Eigen::Index i : active) {
              double r = -(u_free(i) + e * u_old(i));
              for (Eigen::Index j : active) if (j != i) r += delassus(i, j) * impulse(j);
              const double p_new = std::max(0.0, -r / delassus(i, i));
              change = std::max(change, std::abs(p_new - impulse(i)));
              size = std::max(size, std::abs(p_new));
              impulse(i) = p_new;
            }
            if (active.size() == 1 || change <= 1e-14 * size) {
              settled = true;
              break;
            }
          }
          if (!settled) {
            ++rep.unsettled_lcp_steps;
            rep.largest_lcp_change = std::max(rep.largest_lcp_change, size > 0.0 ? change / size : change);
          }
        }
        v_new.noalias() -= minv_e * impulse;
        force.col(step / stride) += impulse / (h * stride);
      }
      const Eigen::VectorXd v_theta = th * v_new + (1.0 - th) * v;
      for (Eigen::Index j = 0; j < nl; ++j) input += h * f_theta(j) * v_theta(loads[static_cast<size_t>(j)].dof);
      dissipated += h * v_theta.dot(damping * v_theta);
      for (Eigen::Index i = 0; i < nc; ++i) absorbed += impulse(i) * contacts[static_cast<size_t>(i)].displacement(v_theta);
      q += h * v_theta;
      v = std::move(v_new);
    }
    out.input_power = input / period;
    out.damping_power = dissipated / period;
    out.stop_power = absorbed / period;
    if (detail::end_of_period(q, v, period_index, steps, disp, forcing.dof, previous_tip, options.periodicity_tolerance,
                              rep)) {
      break;
    }
  }
  detail::finish_run(out, std::move(disp), std::move(vel), std::move(force), steps, "Moreau–Jean");
  if (rep.unsettled_lcp_steps > 0 && pairs.empty()) {
    rep.message += "; in " + std::to_string(rep.unsettled_lcp_steps) + " steps the contact LCP was still changing by " +
                   format_number(rep.largest_lcp_change) + " of its largest impulse after " +
                   std::to_string(kLcpSweeps) + " projected Gauss–Seidel sweeps";
  } else if (rep.unsettled_lcp_steps > 0) {
    rep.message += "; in " + std::to_string(rep.unsettled_lcp_steps) + " steps Siconos' fc2d (Lemke) failed or left "
                   "an error up to " + format_number(rep.largest_lcp_change) + " (above " +
                   format_number(kFrictionError) + ")";
  }
  rep.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}


}  // namespace wbm::solvers
