// The non-template parts of newton.hpp, compiled once here instead of in every translation unit
// that includes the header: NewtonOptions::validate, LowRankJacobian's products, the dense and
// Woodbury linear-solver policies and the Levenberg–Marquardt step. Their documentation is in
// newton.hpp. (Inline in the header they instantiated Eigen's PartialPivLU and HouseholderQR in
// each of about a hundred translation units: about 9 s of g++'s front end each.)
#include <wbm/solvers/newton.hpp>

#include <memory>
#include <utility>

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

LowRankJacobian bordered_low_rank(const LowRankJacobian& j, double alpha, const Eigen::VectorXd& b,
                                  const Eigen::VectorXd& c, double d) {
  const Eigen::Index n = j.size();
  if (!(alpha > 0.0) || !std::isfinite(alpha)) {
    throw std::invalid_argument("bordered_low_rank: alpha = " + format_number(alpha) +
                                ": must be finite and > 0 (the factor of J in the bordered matrix)");
  }
  if (b.size() != n || c.size() != n) {
    throw std::invalid_argument("bordered_low_rank: the border has " + std::to_string(b.size()) + " rows and " +
                                std::to_string(c.size()) + " columns for a Jacobian of size " + std::to_string(n) +
                                "; both must equal it");
  }
  LowRankJacobian out;
  if (j.dense_form()) {
    out.capacitance.resize(n + 1, n + 1);
    out.capacitance.topLeftCorner(n, n) = (j.capacitance / j.scale) * alpha;
    out.capacitance.topRightCorner(n, 1) = b;
    out.capacitance.bottomLeftCorner(1, n) = c.transpose();
    out.capacitance(n, n) = d;
    return out;
  }
  const double a = alpha / j.scale;
  const Eigen::Index r = j.rank();
  const Eigen::MatrixXd u = r == 0 ? Eigen::MatrixXd(n, 0) : j.u.size() > 0 ? j.u : j.u_times(Eigen::MatrixXd::Identity(r, r));
  out.scale = 1.0 / a;
  out.rows = n + 1;
  out.capacitance = Eigen::MatrixXd::Zero(r + 2, r + 2);
  out.capacitance.topLeftCorner(r, r) = j.capacitance;
  if (r > 0) out.capacitance.block(0, r, r, 1) = j.times_v(b) / a;
  out.capacitance(r, r) = 1.0;
  out.capacitance(r, r + 1) = 1.0 / a;
  out.capacitance.block(r + 1, 0, 1, r) = c.transpose() * u;
  out.capacitance(r + 1, r) = c.dot(b) / a;
  out.capacitance(r + 1, r + 1) = d / a;
  // V̂ Y = [V Y_x; Y_λ; cᵀ Y_x + (d − a) Y_λ] and Û Z = [U Z_r + (b/a) z_(r+1); z_(r+2)/a] for Y with n + 1
  // rows and Z with r + 2.
  auto inner = std::make_shared<const LowRankJacobian>(j);
  auto border = std::make_shared<const std::pair<Eigen::VectorXd, Eigen::VectorXd>>(b / a, c);
  out.times_v = [inner, border, n, r, a, d](const Eigen::MatrixXd& y) {
    Eigen::MatrixXd v(r + 2, y.cols());
    if (r > 0) v.topRows(r) = inner->times_v(y.topRows(n));
    v.row(r) = y.row(n);
    v.row(r + 1) = border->second.transpose() * y.topRows(n) + (d - a) * y.row(n);
    return v;
  };
  out.times_u = [inner, border, n, r, a](const Eigen::MatrixXd& z) {
    Eigen::MatrixXd w(n + 1, z.cols());
    w.topRows(n) = border->first * z.row(r);
    if (r > 0) w.topRows(n) += inner->u_times(z.topRows(r));
    w.row(n) = z.row(r + 1) / a;
    return w;
  };
  return out;
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
