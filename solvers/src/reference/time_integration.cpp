#include <wbm/solvers/time_integration.hpp>

#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include <Eigen/LU>

#include "periodicity.hpp"

namespace wbm::solvers {

void TimeIntegrationOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("TimeIntegrationOptions." + what); };
  if (samples_per_period < 4) fail("samples_per_period = " + std::to_string(samples_per_period) + ": must be >= 4");
  if (!(relative_tolerance > 0.0 && relative_tolerance < 1.0)) fail("relative_tolerance: must lie in (0, 1)");
  if (!(absolute_tolerance > 0.0)) fail("absolute_tolerance: must be > 0 [m]");
  if (!(periodicity_tolerance > 0.0)) fail("periodicity_tolerance: must be > 0");
  if (max_periods < 2) fail("max_periods = " + std::to_string(max_periods) + ": must be >= 2");
}

namespace {

// Right-hand side data, dense (n is small for the systems this reference is for).
struct Ode {
  int n;
  Eigen::MatrixXd minv_k;        // T² M⁻¹ K
  Eigen::MatrixXd minv_c;        // T M⁻¹ C
  Eigen::MatrixXd minv_loads;    // T² M⁻¹ e_{dof_j}: column j for load j
  std::vector<HarmonicLoad> loads;
  Eigen::MatrixXd minv_cols;     // T² M⁻¹ e_c: column c for contact c
  std::vector<ContactPoint> contacts;
};

int rhs(double tau, const double y[], double dydt[], void* params) {
  const auto& o = *static_cast<const Ode*>(params);
  const int n = o.n;
  Eigen::Map<const Eigen::VectorXd> u(y, n), w(y + n, n);
  Eigen::Map<Eigen::VectorXd> du(dydt, n), dw(dydt + n, n);
  du = w;
  dw.noalias() = -o.minv_k * u - o.minv_c * w;
  for (size_t j = 0; j < o.loads.size(); ++j) {
    const auto& l = o.loads[j];
    dw += l.amplitude * std::cos(2.0 * std::numbers::pi * l.harmonic * tau + l.phase_rad) *
          o.minv_loads.col(static_cast<Eigen::Index>(j));
  }
  for (size_t c = 0; c < o.contacts.size(); ++c) {
    dw -= o.contacts[c].law->force(o.contacts[c].displacement(u)) * o.minv_cols.col(static_cast<Eigen::Index>(c));
  }
  return dw.allFinite() ? GSL_SUCCESS : GSL_EBADFUNC;
}

// The status of a failed gsl_odeiv2_driver_apply: NonFinite when the state or the right-hand side
// (GSL_EBADFUNC from rhs) is not finite, else IntegratorFailed (GSL gave up with finite
// values: a step below its minimum, too many steps, no progress).
SolveStatus integration_failure(int gsl_status, const Eigen::VectorXd& y) {
  return gsl_status == GSL_EBADFUNC || !y.allFinite() ? SolveStatus::NonFinite : SolveStatus::IntegratorFailed;
}

int jacobian(double tau, const double y[], double* dfdy, double dfdt[], void* params) {
  const auto& o = *static_cast<const Ode*>(params);
  const int n = o.n;
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> j(dfdy, 2 * n, 2 * n);
  j.setZero();
  j.topRightCorner(n, n).setIdentity();
  j.bottomLeftCorner(n, n) = -o.minv_k;
  j.bottomRightCorner(n, n) = -o.minv_c;
  const Eigen::Map<const Eigen::VectorXd> u(y, n);
  for (size_t c = 0; c < o.contacts.size(); ++c) {
    const auto& ct = o.contacts[c];
    const Eigen::VectorXd kcol = ct.law->stiffness(ct.displacement(u)) * o.minv_cols.col(static_cast<Eigen::Index>(c));
    for (const auto& [dof, w] : ct.terms()) j.bottomRows(n).col(dof) -= w * kcol;
  }
  Eigen::Map<Eigen::VectorXd> dt(dfdt, 2 * n);
  dt.setZero();
  for (size_t j = 0; j < o.loads.size(); ++j) {
    const auto& l = o.loads[j];
    dt.tail(n) -= 2.0 * std::numbers::pi * l.harmonic * l.amplitude *
                  std::sin(2.0 * std::numbers::pi * l.harmonic * tau + l.phase_rad) * o.minv_loads.col(static_cast<Eigen::Index>(j));
  }
  return GSL_SUCCESS;
}

struct DriverDeleter {
  void operator()(gsl_odeiv2_driver* d) const { gsl_odeiv2_driver_free(d); }
};

// The normalized ODE with time unit t_unit [s] and the loads of `loads` (may be empty).
Ode make_ode(const MechanicalSystem& system, const std::vector<HarmonicLoad>& loads,
             const std::vector<ContactPoint>& contacts, double t_unit) {
  Ode ode;
  ode.n = system.dofs();
  const Eigen::MatrixXd mass(system.mass);
  const Eigen::PartialPivLU<Eigen::MatrixXd> mlu(mass);
  ode.minv_k = t_unit * t_unit * mlu.solve(Eigen::MatrixXd(system.stiffness));
  ode.minv_c = t_unit * mlu.solve(Eigen::MatrixXd(system.damping));
  ode.minv_loads.resize(ode.n, static_cast<Eigen::Index>(loads.size()));
  for (size_t j = 0; j < loads.size(); ++j) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(ode.n);
    e(loads[j].dof) = 1.0;
    ode.minv_loads.col(static_cast<Eigen::Index>(j)) = t_unit * t_unit * mlu.solve(e);
  }
  ode.minv_cols.resize(ode.n, static_cast<Eigen::Index>(contacts.size()));
  for (size_t c = 0; c < contacts.size(); ++c) {
    ode.minv_cols.col(static_cast<Eigen::Index>(c)) = t_unit * t_unit * mlu.solve(contacts[c].direction(ode.n));
  }
  ode.loads = loads;
  ode.contacts = contacts;
  return ode;
}

void refuse_rigid_stops(const std::vector<ContactPoint>& contacts, const char* where) {
  for (const auto& c : contacts) {
    if (c.law->hysteretic()) {
      throw std::invalid_argument(std::string(where) + ": the contact at DOF " + std::to_string(c.dof) + " is a " +
                                  c.law->describe() + ", a hysteretic law with a slider state that this integrator "
                                  "does not carry: use integrate_central_difference_to_periodic for a Jenkins element, "
                                  "integrate_moreau_jean_to_periodic for exact Coulomb friction");
    }
    if (c.law->rigid()) {
      throw std::invalid_argument(std::string(where) + ": the contact at DOF " + std::to_string(c.dof) + " is a " +
                                  c.law->describe() + ", which has no force law for an ODE integrator: use "
                                  "integrate_moreau_jean_to_periodic (impulses, restitution law) or a LinearPenalty");
    }
  }
}

}  // namespace

PeriodicResponse integrate_to_periodic(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                       const std::vector<ContactPoint>& contacts,
                                       const TimeIntegrationOptions& options) {
  system.validate();
  forcing.validate(system.dofs());
  ContactPoint::validate(contacts, system.dofs());
  require_fixed_obstacles(contacts, "the BDF reference (time_integration.hpp)",
                          "use integrate_central_difference_to_periodic, which takes them");
  refuse_rigid_stops(contacts, "integrate_to_periodic");
  options.validate();
  forcing.require_resolved(options.samples_per_period,
                           "the P = " + std::to_string(options.samples_per_period) + " output samples per period",
                           "raise TimeIntegrationOptions.samples_per_period");
  const auto start = std::chrono::steady_clock::now();

  const double t = 1.0 / forcing.frequency_hz;  // period T [s]
  Ode ode = make_ode(system, forcing.loads(), contacts, t);

  gsl_set_error_handler_off();  // report GSL failures through return codes, never abort
  gsl_odeiv2_system sys{rhs, jacobian, static_cast<size_t>(2 * ode.n), &ode};
  const int p_count = options.samples_per_period;
  const double h0 = 1.0 / (16.0 * p_count);
  std::unique_ptr<gsl_odeiv2_driver, DriverDeleter> driver(gsl_odeiv2_driver_alloc_y_new(
      &sys, gsl_odeiv2_step_msbdf, h0, options.absolute_tolerance, options.relative_tolerance));
  gsl_odeiv2_driver_set_nmax(driver.get(), 0);  // no per-interval step limit

  PeriodicResponse out;
  out.frequency_hz = forcing.frequency_hz;
  out.tau = Eigen::VectorXd::LinSpaced(p_count, 0.0, 1.0 - 1.0 / p_count);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(2 * ode.n);
  Eigen::MatrixXd disp(ode.n, p_count), vel(ode.n, p_count);
  Eigen::VectorXd previous_tip;
  double tau = 0.0;
  auto& rep = out.report;
  for (int period = 1; period <= options.max_periods; ++period) {
    for (int p = 0; p < p_count; ++p) {
      // Sample at the start of each sub-interval: sample p of period i is τ = (i−1) + p/P.
      disp.col(p) = y.head(ode.n);
      vel.col(p) = y.tail(ode.n) / t;
      const double target = (period - 1) + static_cast<double>(p + 1) / p_count;
      const int status = gsl_odeiv2_driver_apply(driver.get(), &tau, target, y.data());
      if (status != GSL_SUCCESS || !y.allFinite()) {
        rep.status = integration_failure(status, y);
        std::ostringstream os;
        os << "GSL msbdf failed (" << gsl_strerror(status) << ") in period " << period << " at tau = " << tau;
        rep.message = os.str();
        rep.periods = period;
        rep.steps = static_cast<long>(driver->e->count);
        rep.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return out;
      }
    }
    rep.periods = period;
    const Eigen::VectorXd tip = disp.row(forcing.dof).transpose();
    const size_t measured = rep.periodicity.size();
    const bool done = detail::periodic(tip, previous_tip, options.periodicity_tolerance, rep);
    if (options.on_period && rep.periodicity.size() > measured) options.on_period(period, rep.periodicity.back());
    if (done) break;
  }
  rep.steps = static_cast<long>(driver->e->count);
  out.displacement = std::move(disp);
  out.velocity = std::move(vel);
  std::ostringstream os;
  os << (rep.converged() ? "periodic" : "not periodic") << " after " << rep.periods
     << " periods, delta = " << (rep.periodicity.empty() ? NAN : rep.periodicity.back());
  rep.message = os.str();
  rep.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

Trajectory integrate_free(const MechanicalSystem& system, const std::vector<ContactPoint>& contacts,
                          const Eigen::VectorXd& u0, const Eigen::VectorXd& v0, double period_s, int periods,
                          const TimeIntegrationOptions& options) {
  system.validate();
  ContactPoint::validate(contacts, system.dofs());
  require_fixed_obstacles(contacts, "integrate_free (a free motion: nothing else moves)", "fix the obstacles");
  refuse_rigid_stops(contacts, "integrate_free");
  options.validate();
  const int n = system.dofs();
  if (u0.size() != n || v0.size() != n || !u0.allFinite() || !v0.allFinite()) {
    throw std::invalid_argument("integrate_free: u0 and v0 must be finite vectors of length " + std::to_string(n));
  }
  if (!(period_s > 0.0) || !std::isfinite(period_s)) {
    throw std::invalid_argument("integrate_free: period_s = " + std::to_string(period_s) + ": must be > 0 [s]");
  }
  if (periods < 1) throw std::invalid_argument("integrate_free: periods = " + std::to_string(periods) + ": must be >= 1");
  const auto start = std::chrono::steady_clock::now();
  Ode ode = make_ode(system, {}, contacts, period_s);
  gsl_set_error_handler_off();
  gsl_odeiv2_system sys{rhs, jacobian, static_cast<size_t>(2 * n), &ode};
  const int p_count = options.samples_per_period;
  std::unique_ptr<gsl_odeiv2_driver, DriverDeleter> driver(gsl_odeiv2_driver_alloc_y_new(
      &sys, gsl_odeiv2_step_msbdf, 1.0 / (16.0 * p_count), options.absolute_tolerance, options.relative_tolerance));
  gsl_odeiv2_driver_set_nmax(driver.get(), 0);
  const int total = periods * p_count + 1;
  Trajectory out;
  out.time_s = Eigen::VectorXd::LinSpaced(total, 0.0, periods * period_s);
  out.displacement.resize(n, total);
  out.velocity.resize(n, total);
  Eigen::VectorXd y(2 * n);
  y << u0, v0 * period_s;  // du/dτ = T du/dt
  double tau = 0.0;
  auto& rep = out.report;
  for (int k = 0; k < total; ++k) {
    if (k > 0) {
      const int status = gsl_odeiv2_driver_apply(driver.get(), &tau, static_cast<double>(k) / p_count, y.data());
      if (status != GSL_SUCCESS || !y.allFinite()) {
        rep.status = integration_failure(status, y);
        rep.message = std::string("GSL msbdf failed (") + gsl_strerror(status) + ") at t = " +
                      std::to_string(tau * period_s) + " s";
        out.time_s.conservativeResize(k);
        out.displacement.conservativeResize(n, k);
        out.velocity.conservativeResize(n, k);
        break;
      }
    }
    out.displacement.col(k) = y.head(n);
    out.velocity.col(k) = y.tail(n) / period_s;
  }
  if (rep.message.empty()) {
    rep.status = SolveStatus::Converged;
    rep.message = "integrated " + std::to_string(periods) + " spans of " + std::to_string(period_s) + " s";
  }
  rep.periods = periods;
  rep.steps = static_cast<long>(driver->e->count);
  rep.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace wbm::solvers
