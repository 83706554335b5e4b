// The non-template parts of newton.hpp, compiled once here instead of in every translation unit
// that includes the header: NewtonOptions::validate, LowRankJacobian's products, the dense and
// Woodbury linear-solver policies and the Levenberg–Marquardt step. Their documentation is in
// newton.hpp. (Inline in the header they instantiated Eigen's PartialPivLU and HouseholderQR in
// each of about a hundred translation units: about 9 s of g++'s front end each.)
#include <wbm/solvers/newton.hpp>

#include <memory>
#include <utility>
#include <vector>

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

bool LowRankJacobian::all_finite() const {
  const auto finite = [](const Eigen::SparseMatrix<double>& m) {
    return Eigen::Map<const Eigen::VectorXd>(m.valuePtr(), m.nonZeros()).allFinite();
  };
  return capacitance.allFinite() && u.allFinite() && finite(sparse_capacitance) && finite(sparse_u) &&
         finite(sparse_v);
}

Eigen::VectorXd LowRankJacobian::apply(const Eigen::VectorXd& y) const {
  if (dense_form()) return capacitance * y / scale;
  if (sparse_form()) return (y + times_update(y).col(0)) / scale;
  if (rank() == 0) return y / scale;
  return (y + u_times(times_v(y)).col(0)) / scale;
}

Eigen::MatrixXd LowRankJacobian::dense() const {
  if (dense_form()) return capacitance / scale;
  Eigen::MatrixXd j = Eigen::MatrixXd::Identity(size(), size());
  if (sparse_form()) {
    j += times_update(Eigen::MatrixXd::Identity(size(), size()));
  } else if (rank() > 0) {
    j += u_times(times_v(Eigen::MatrixXd::Identity(size(), size())));
  }
  return j / scale;
}

namespace {

// bordered_low_rank for the sparse form (newton.hpp): K̂, V̂′ and Û assembled by triplets, and
// the update Û L̂⁻¹ V̂′ from J's (L̂⁻¹ = diag(L⁻¹, 1, 1) leaves the border rows as they are).
LowRankJacobian bordered_sparse_form(const LowRankJacobian& j, double alpha, const Eigen::VectorXd& b,
                                     const Eigen::VectorXd& c, double d) {
  using Triplets = std::vector<Eigen::Triplet<double>>;
  const Eigen::Index n = j.size();
  const Eigen::Index q = j.rank();
  const double a = alpha / j.scale;
  // The rows of V′ and the columns of U that hold an entry: where V′ b and cᵀ U are stored.
  std::vector<char> v_rows(static_cast<size_t>(q), 0), u_cols(static_cast<size_t>(q), 0);
  for (Eigen::Index k = 0; k < j.sparse_v.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(j.sparse_v, k); it; ++it) {
      v_rows[static_cast<size_t>(it.row())] = 1;
    }
  }
  for (Eigen::Index k = 0; k < j.sparse_u.outerSize(); ++k) {
    if (j.sparse_u.outerIndexPtr()[k + 1] > j.sparse_u.outerIndexPtr()[k]) u_cols[static_cast<size_t>(k)] = 1;
  }
  const Eigen::VectorXd vb = j.sparse_v * b / a;
  const Eigen::VectorXd cu = j.sparse_u.transpose() * c;
  Triplets t;
  t.reserve(static_cast<size_t>(j.sparse_capacitance.nonZeros() + 2 * q + 4));
  for (Eigen::Index k = 0; k < j.sparse_capacitance.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(j.sparse_capacitance, k); it; ++it) {
      t.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
    }
  }
  const auto qi = static_cast<int>(q);
  for (int i = 0; i < qi; ++i) {
    if (v_rows[static_cast<size_t>(i)] != 0) t.emplace_back(i, qi, vb(i));
    if (u_cols[static_cast<size_t>(i)] != 0) t.emplace_back(qi + 1, i, cu(i));
  }
  t.emplace_back(qi, qi, 1.0);
  t.emplace_back(qi, qi + 1, 1.0 / a);
  t.emplace_back(qi + 1, qi, c.dot(b) / a);
  t.emplace_back(qi + 1, qi + 1, d / a);
  LowRankJacobian out;
  out.scale = 1.0 / a;
  out.rows = n + 1;
  out.sparse_capacitance.resize(q + 2, q + 2);
  out.sparse_capacitance.setFromTriplets(t.begin(), t.end());
  t.clear();
  for (Eigen::Index k = 0; k < j.sparse_v.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(j.sparse_v, k); it; ++it) {
      t.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
    }
  }
  const auto ni = static_cast<int>(n);
  for (int i = 0; i < ni; ++i) t.emplace_back(qi + 1, i, c(i));
  t.emplace_back(qi, ni, 1.0);
  t.emplace_back(qi + 1, ni, d - a);
  out.sparse_v.resize(q + 2, n + 1);
  out.sparse_v.setFromTriplets(t.begin(), t.end());
  t.clear();
  for (Eigen::Index k = 0; k < j.sparse_u.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(j.sparse_u, k); it; ++it) {
      t.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
    }
  }
  for (int i = 0; i < ni; ++i) t.emplace_back(i, qi, b(i) / a);
  t.emplace_back(ni, qi + 1, 1.0 / a);
  out.sparse_u.resize(n + 1, q + 2);
  out.sparse_u.setFromTriplets(t.begin(), t.end());
  // Û L̂⁻¹ V̂′ Y = [U L⁻¹ V′ Y_x + (b/a) Y_λ; (cᵀ Y_x + (d − a) Y_λ)/a] (apply() and dense() only).
  auto inner = std::make_shared<const LowRankJacobian>(j);
  auto border = std::make_shared<const std::pair<Eigen::VectorXd, Eigen::VectorXd>>(b / a, c);
  out.times_update = [inner, border, n, a, d](const Eigen::MatrixXd& y) {
    Eigen::MatrixXd w(n + 1, y.cols());
    w.topRows(n) = inner->times_update(y.topRows(n)) + border->first * y.row(n);
    w.row(n) = (border->second.transpose() * y.topRows(n) + (d - a) * y.row(n)) / a;
    return w;
  };
  return out;
}

}  // namespace

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
  if (j.sparse_form()) return bordered_sparse_form(j, alpha, b, c, d);
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
  if (!j_.all_finite()) return false;  // times_u's and times_v's products are checked by newton()
  if (j_.sparse_form()) {
    if (!sparse_lu_ || sparse_lu_.use_count() > 1) sparse_lu_ = std::make_shared<SparseLu>();
    return sparse_lu_->factorize(j_.sparse_capacitance);
  }
  if (j_.capacitance.rows() > 0) lu_.compute(j_.capacitance);
  return true;
}

Eigen::VectorXd WoodburyLu::solve(const Eigen::VectorXd& rhs) const {
  Eigen::VectorXd d = woodbury(rhs);
  if (!j_.dense_form()) d += woodbury(rhs - j_.apply(d));
  return d;
}

std::optional<double> WoodburyLu::rcond() const {
  if (j_.sparse_form()) return std::nullopt;
  return j_.capacitance.rows() > 0 ? lu_.rcond() : 1.0;  // rank 0: J = I / s
}

Eigen::VectorXd WoodburyLu::woodbury(const Eigen::VectorXd& y) const {
  if (j_.dense_form()) return j_.scale * lu_.solve(y);
  if (j_.sparse_form()) return j_.scale * (y - j_.sparse_u * sparse_lu_->solve(j_.sparse_v * y));
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
