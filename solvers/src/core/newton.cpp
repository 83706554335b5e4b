// The non-template parts of newton.hpp, compiled once here instead of in every translation unit
// that includes the header: NewtonOptions::validate, LowRankJacobian's products, the dense and
// Woodbury linear-solver policies and the Levenberg–Marquardt step. Their documentation is in
// newton.hpp. (Inline in the header they instantiated Eigen's PartialPivLU and HouseholderQR in
// each of about a hundred translation units: about 9 s of g++'s front end each.)
#include <wbm/solvers/newton.hpp>

#include <Eigen/QR>

namespace wbm::solvers {

void NewtonOptions::validate() const {
  auto fail = [](const std::string& field, const std::string& value, const std::string& rule) {
    throw std::invalid_argument("NewtonOptions." + field + " = " + value + ": " + rule);
  };
  if (!(tolerance > 0.0) || !std::isfinite(tolerance)) {
    fail("tolerance", format_number(tolerance),
         "must be > 0 and finite (the bound on ‖R‖ in the system's scaling; the default is 1e-10)");
  }
  if (max_iterations < 0) {
    fail("max_iterations", std::to_string(max_iterations), "must be >= 0 (0 only evaluates the start; default 50)");
  }
  if (max_backtracks < 0) {
    fail("max_backtracks", std::to_string(max_backtracks), "must be >= 0 (default 30; or line_search = false)");
  }
  if (!(min_rcond >= 0.0 && min_rcond < 1.0)) {
    fail("min_rcond", format_number(min_rcond), "must lie in [0, 1) (a reciprocal condition number; default 1e-15)");
  }
  if (levenberg_marquardt && max_lm_trials < 1) {
    fail("max_lm_trials", std::to_string(max_lm_trials),
         "must be >= 1 with levenberg_marquardt (default 20; or levenberg_marquardt = false)");
  }
  if (stop_on_cycle && !(cycle_tolerance > 0.0)) {
    fail("cycle_tolerance", format_number(cycle_tolerance),
         "must be > 0 with stop_on_cycle (a relative tolerance on repeated residuals; default 1e-3)");
  }
}

Eigen::MatrixXd LowRankJacobian::u_times(const Eigen::MatrixXd& z) const {
  return times_u ? times_u(z) : Eigen::MatrixXd(u * z);
}

Eigen::VectorXd LowRankJacobian::apply(const Eigen::VectorXd& y) const {
  if (dense_form()) return capacitance * y / scale;
  if (rank() == 0) return y / scale;
  return (y + u_times(times_v(y)).col(0)) / scale;
}

Eigen::MatrixXd LowRankJacobian::dense() const {
  if (dense_form()) return capacitance / scale;
  Eigen::MatrixXd j = Eigen::MatrixXd::Identity(size(), size());
  if (rank() > 0) j += u_times(times_v(Eigen::MatrixXd::Identity(size(), size())));
  return j / scale;
}

bool DenseLu::factorize(const Eigen::MatrixXd& jacobian) {
  lu_.compute(jacobian);
  return lu_.matrixLU().allFinite();
}

Eigen::VectorXd DenseLu::solve(const Eigen::VectorXd& rhs) const { return lu_.solve(rhs); }

std::optional<double> DenseLu::rcond() const { return lu_.rcond(); }

bool WoodburyLu::factorize(const LowRankJacobian& jacobian) {
  j_ = jacobian;
  if (j_.capacitance.rows() > 0) lu_.compute(j_.capacitance);
  return j_.capacitance.allFinite() && j_.u.allFinite();  // times_u's products are checked by newton()
}

Eigen::VectorXd WoodburyLu::solve(const Eigen::VectorXd& rhs) const {
  Eigen::VectorXd d = woodbury(rhs);
  if (!j_.dense_form()) d += woodbury(rhs - j_.apply(d));
  return d;
}

std::optional<double> WoodburyLu::rcond() const {
  return j_.capacitance.rows() > 0 ? lu_.rcond() : 1.0;  // rank 0: J = I / s
}

Eigen::VectorXd WoodburyLu::woodbury(const Eigen::VectorXd& y) const {
  if (j_.dense_form()) return j_.scale * lu_.solve(y);
  if (j_.capacitance.rows() == 0) return j_.scale * y;
  return j_.scale * (y - j_.u_times(lu_.solve(j_.times_v(y))).col(0));
}

namespace detail {

Eigen::VectorXd levenberg_marquardt_step(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& r, double mu) {
  const Eigen::Index m = jacobian.rows();
  const Eigen::Index n = jacobian.cols();
  Eigen::MatrixXd stacked(m + n, n);
  stacked.topRows(m) = jacobian;
  stacked.bottomRows(n) = mu * Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m + n);
  rhs.head(m) = -r;
  return stacked.householderQr().solve(rhs);
}

}  // namespace detail
}  // namespace wbm::solvers
