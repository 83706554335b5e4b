#include <wbm/contact/augmented_lagrangian.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace wbm::contact {

void PowellParameters::validate() const {
  auto require = [](bool ok, const char* field, double value, const std::string& range) {
    if (!ok) {
      throw std::invalid_argument(std::string("PowellParameters.") + field + " = " + std::to_string(value) +
                                  ": must be " + range);
    }
  };
  require(alpha > 1.0, "alpha", alpha, "> 1 (Powell's decrease factor; 4 is usual)");
  require(beta > 1.0, "beta", beta, "> 1 (the penalty growth factor; 10 is usual)");
  require(tolerance > 0.0, "tolerance", tolerance, "> 0 (e.g. 1e-8)");
  require(initial_inequality_penalty > 0.0, "initial_inequality_penalty", initial_inequality_penalty, "> 0 (e.g. 10)");
  require(initial_equality_penalty > 0.0, "initial_equality_penalty", initial_equality_penalty, "> 0 (e.g. 10)");
  require(max_penalty >= initial_inequality_penalty && max_penalty >= initial_equality_penalty, "max_penalty",
          max_penalty, ">= both initial penalties (" + std::to_string(initial_inequality_penalty) + ", " +
                           std::to_string(initial_equality_penalty) + ")");
}

AugmentedLagrangian::AugmentedLagrangian(int inequalities, PowellParameters parameters) : p_(parameters) {
  p_.validate();
  if (inequalities < 0) throw std::invalid_argument("AugmentedLagrangian: negative constraint count");
  kappa_ = Eigen::VectorXd::Constant(inequalities, p_.initial_inequality_penalty);
  theta_ = Eigen::VectorXd::Zero(inequalities);
  kappa_e_ = p_.initial_equality_penalty;
  const double inf = std::numeric_limits<double>::infinity();
  best_i_ = previous_best_i_ = best_e_ = previous_best_e_ = inf;
}

void AugmentedLagrangian::warm_start(const Eigen::VectorXd& multipliers, double equality_multiplier) {
  if (multipliers.size() != theta_.size()) {
    throw std::invalid_argument("AugmentedLagrangian::warm_start: " + std::to_string(multipliers.size()) +
                                " multipliers for " + std::to_string(theta_.size()) + " constraints");
  }
  theta_ = (multipliers.array().max(0.0) / kappa_.array()).matrix();
  theta_e_ = equality_multiplier / kappa_e_;
}

double AugmentedLagrangian::value(const Eigen::VectorXd& g, double h) const {
  const Eigen::ArrayXd plus = (g + theta_).array().max(0.0);
  return 0.5 * (kappa_.array() * plus.square()).sum() + 0.5 * kappa_e_ * (h + theta_e_) * (h + theta_e_);
}

Eigen::VectorXd AugmentedLagrangian::inequality_gradient(const Eigen::VectorXd& g) const {
  return (kappa_.array() * (g + theta_).array().max(0.0)).matrix();
}

double AugmentedLagrangian::equality_gradient(double h) const { return kappa_e_ * (h + theta_e_); }

Eigen::VectorXd AugmentedLagrangian::inequality_curvature(const Eigen::VectorXd& g) const {
  return ((g + theta_).array() > 0.0).select(kappa_.array(), 0.0).matrix();
}

double AugmentedLagrangian::inequality_measure(const Eigen::VectorXd& g) const {
  return g.size() == 0 ? 0.0 : g.cwiseMax(-theta_).cwiseAbs().maxCoeff();  // Eq. (25a)
}

PowellUpdate AugmentedLagrangian::update(const Eigen::VectorXd& g, double h) {
  PowellUpdate u;
  u.inequality_measure = inequality_measure(g);  // Alg. 3, l. 5
  u.equality_measure = equality_measure(h);
  const double gi = u.inequality_measure, ge = u.equality_measure;
  u.measures_met = gi < p_.tolerance && ge < p_.tolerance;  // l. 6–7
  if (u.measures_met) return u;
  // κ ← βκ unless that passes max_penalty; with `keep_multiplier`, θ ← θ/β so that κθ is kept.
  auto raise = [&](double& kappa, double& theta, bool keep_multiplier) {
    if (kappa * p_.beta > p_.max_penalty) {
      ++u.penalties_capped;
      return;
    }
    kappa *= p_.beta;
    if (keep_multiplier) theta /= p_.beta;
    ++u.penalties_raised;
  };
  if (gi >= p_.tolerance) {  // l. 10: inequality constraints
    const Eigen::VectorXd violation = g.cwiseMax(-theta_).cwiseAbs();
    if (gi >= best_i_) {  // l. 12: no improvement: raise the penalties of the worst constraints
      for (Eigen::Index k = 0; k < g.size(); ++k) {
        if (violation(k) >= best_i_ / p_.alpha) raise(kappa_(k), theta_(k), true);  // S_i, Eq. (26a)
      }
    } else {  // l. 14–16: multiplier update, Eq. (21a)
      previous_best_i_ = best_i_;
      best_i_ = gi;
      theta_ += g.cwiseMax(-theta_);
      ++u.multiplier_updates;
      if (best_i_ >= previous_best_i_ / p_.alpha) {  // l. 17: not enough improvement
        for (Eigen::Index k = 0; k < g.size(); ++k) {
          if (violation(k) >= best_i_ / p_.alpha) raise(kappa_(k), theta_(k), false);
        }
      }
    }
  }
  if (ge >= p_.tolerance) {  // l. 22: the equality constraint
    if (ge >= best_e_) {     // l. 23–24, Eq. (26b)
      raise(kappa_e_, theta_e_, true);
    } else {  // l. 25–27, Eq. (21b)
      previous_best_e_ = best_e_;
      best_e_ = ge;
      theta_e_ += h;
      ++u.multiplier_updates;
      if (best_e_ > previous_best_e_ / p_.alpha) raise(kappa_e_, theta_e_, false);  // l. 28–29
    }
  }
  return u;
}

}  // namespace wbm::contact
