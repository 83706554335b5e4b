#include <wbm/contact/penalty.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <new>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_math.h>
#include <gsl/gsl_roots.h>

namespace wbm::contact {
namespace {

[[noreturn]] void bad(const char* law, const char* field, double value, const char* range) {
  std::ostringstream os;
  os << law << "." << field << " = " << value << ": " << range;
  throw std::invalid_argument(os.str());
}

}  // namespace

void ContactLaw::evaluate(const Eigen::Ref<const Eigen::VectorXd>& u,
                          Eigen::Ref<Eigen::VectorXd> force,
                          Eigen::Ref<Eigen::VectorXd> stiffness) const {
  for (Eigen::Index q = 0; q < u.size(); ++q) {
    force(q) = this->force(u(q));
    stiffness(q) = this->stiffness(u(q));
  }
}

void ContactLaw::evaluate_period(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> force,
                                 Eigen::Ref<Eigen::VectorXd> stiffness, Eigen::Ref<Eigen::VectorXi> anchor,
                                 double /*period_shift: a memoryless law has no state to carry*/) const {
  evaluate(u, force, stiffness);
  anchor.setConstant(-1);
}

void ContactLaw::evaluate_period_loaded(const Eigen::Ref<const Eigen::VectorXd>& /*u*/,
                                        const Eigen::Ref<const Eigen::VectorXd>& /*normal*/,
                                        Eigen::Ref<Eigen::VectorXd> /*force*/,
                                        Eigen::Ref<Eigen::VectorXd> /*stiffness*/,
                                        Eigen::Ref<Eigen::VectorXi> /*anchor*/,
                                        Eigen::Ref<Eigen::VectorXd> /*load_sensitivity*/,
                                        double /*period_shift*/) const {
  throw std::logic_error("ContactLaw::evaluate_period_loaded: the " + describe() + " takes no normal load; only a "
                         "friction law with takes_normal_load() (a Jenkins element) does");
}

void ExponentialPenaltyParameters::validate() const {
  const char* law = "ExponentialPenalty";
  if (!(coefficient > 0.0) || !std::isfinite(coefficient)) bad(law, "coefficient (a_c)", coefficient, "must be finite and > 0 [N]");
  if (!(exponent > 0.0) || !std::isfinite(exponent)) bad(law, "exponent (alpha)", exponent, "must be finite and > 0 [1/m]");
  if (!std::isfinite(gap)) bad(law, "gap (g0)", gap, "must be finite [m]");
  if (!(linear_beyond > 0.0 && linear_beyond <= 700.0)) bad(law, "linear_beyond", linear_beyond, "must lie in (0, 700] (e^700 is near the double limit)");
}

ExponentialPenalty::ExponentialPenalty(const ExponentialPenaltyParameters& parameters)
    : p_(parameters) {
  p_.validate();
}

double ExponentialPenalty::force(double u) const {
  const double x = p_.exponent * (u - p_.gap);
  if (x <= 0.0) return 0.0;  // NaN falls through and propagates to the caller
  if (x <= p_.linear_beyond) return p_.coefficient * std::expm1(x);
  const double e = std::exp(p_.linear_beyond);
  return p_.coefficient * (e * (1.0 + (x - p_.linear_beyond)) - 1.0);
}

double ExponentialPenalty::stiffness(double u) const {
  const double x = p_.exponent * (u - p_.gap);
  if (x <= 0.0) return 0.0;
  return p_.coefficient * p_.exponent * std::exp(std::min(x, p_.linear_beyond));
}

double ExponentialPenalty::potential(double u) const {
  const double x = p_.exponent * (u - p_.gap);
  if (x <= 0.0) return 0.0;
  const double a = p_.coefficient / p_.exponent;  // ∫ a_c (e^x − 1) du = (a_c/α)(e^x − 1 − x)
  const double xl = p_.linear_beyond;
  if (x <= xl) return a * (std::expm1(x) - x);
  const double e = std::exp(xl);
  const double dx = x - xl;
  return a * ((std::expm1(xl) - xl) + e * (dx + 0.5 * dx * dx) - dx);
}

std::string ExponentialPenalty::describe() const {
  std::ostringstream os;
  os << "exponential penalty a_c = " << p_.coefficient << " N, alpha = " << p_.exponent
     << " 1/m, g0 = " << p_.gap << " m (linear beyond alpha*(u-g0) = " << p_.linear_beyond << ")";
  return os.str();
}

void LinearPenaltyParameters::validate() const {
  const char* law = "LinearPenalty";
  if (!(stiffness > 0.0) || !std::isfinite(stiffness)) bad(law, "stiffness (k_pen)", stiffness, "must be finite and > 0 [N/m]");
  if (!std::isfinite(gap)) bad(law, "gap (g0)", gap, "must be finite [m]");
}

LinearPenalty::LinearPenalty(const LinearPenaltyParameters& parameters) : p_(parameters) {
  p_.validate();
}

double LinearPenalty::force(double u) const {
  const double d = u - p_.gap;
  return d <= 0.0 ? 0.0 : p_.stiffness * d;  // NaN propagates
}
double LinearPenalty::stiffness(double u) const {
  const double d = u - p_.gap;
  return d <= 0.0 ? 0.0 : (std::isnan(d) ? d : p_.stiffness);
}
double LinearPenalty::potential(double u) const {
  const double d = u - p_.gap;
  return d <= 0.0 ? 0.0 : 0.5 * p_.stiffness * d * d;
}
std::string LinearPenalty::describe() const {
  std::ostringstream os;
  os << "linear penalty k = " << p_.stiffness << " N/m, g0 = " << p_.gap << " m";
  return os.str();
}

SeriesCompliance::SeriesCompliance(std::shared_ptr<const ContactLaw> inner, double flexibility)
    : inner_(std::move(inner)), c_(flexibility) {
  if (!inner_) throw std::invalid_argument("SeriesCompliance: the inner law is null");
  if (inner_->rigid()) {
    throw std::invalid_argument("SeriesCompliance: a rigid stop behind a spring of flexibility c is the linear penalty "
                                "1/c; use LinearPenalty{1/c, g0}");
  }
  if (!(flexibility > 0.0) || !std::isfinite(flexibility)) {
    bad("SeriesCompliance", "flexibility (c)", flexibility, "must be finite and > 0 [m/N]");
  }
}

double SeriesCompliance::node_position(double s) const {
  const double g0 = inner_->gap();
  if (std::isnan(s)) return s;
  if (s <= g0 || inner_->force(s) == 0.0) return s;  // open: the node sits where the spring puts it
  // h(y) = y + c f(y) − s is increasing, h(g0) = g0 − s < 0 ≤ h(s) = c f(s): the root is in [g0, s].
  struct Residual {
    const ContactLaw* law;
    double c, s;
  } residual{inner_.get(), c_, s};
  gsl_function h;
  h.function = [](double y, void* p) {
    const auto* r = static_cast<const Residual*>(p);
    return y + r->c * r->law->force(y) - r->s;
  };
  h.params = &residual;
  // A force that overflows (an exponential law far in) is above the root: shrink the bracket
  // until h is finite at its upper end, as Brent's method needs.
  double lo = g0, hi = s;
  for (int k = 0; k < 2100 && !std::isfinite(GSL_FN_EVAL(&h, hi)); ++k) hi = 0.5 * (lo + hi);
  gsl_set_error_handler_off();  // report through return codes, never abort
  const std::unique_ptr<gsl_root_fsolver, decltype(&gsl_root_fsolver_free)> solver(
      gsl_root_fsolver_alloc(gsl_root_fsolver_brent), &gsl_root_fsolver_free);
  if (!solver) throw std::bad_alloc();
  const double tolerance = 1e-15 * (std::abs(s) + std::abs(g0));
  int status = gsl_root_fsolver_set(solver.get(), &h, lo, hi);
  for (int k = 0; k < 200 && status == GSL_SUCCESS; ++k) {
    status = gsl_root_fsolver_iterate(solver.get());
    if (status != GSL_SUCCESS) break;
    lo = gsl_root_fsolver_x_lower(solver.get());
    hi = gsl_root_fsolver_x_upper(solver.get());
    if (gsl_root_test_interval(lo, hi, tolerance, 0.0) == GSL_SUCCESS) return gsl_root_fsolver_root(solver.get());
  }
  std::ostringstream os;
  os << "SeriesCompliance::node_position: GSL's Brent solver did not bracket the node position to " << tolerance
     << " m within 200 iterations at s = " << s << " m (last bracket [" << lo << ", " << hi << "] m; GSL: "
     << gsl_strerror(status) << "; " << describe() << ")";
  throw std::runtime_error(os.str());
}

double SeriesCompliance::force(double s) const { return inner_->force(node_position(s)); }

double SeriesCompliance::stiffness(double s) const {
  const double k = inner_->stiffness(node_position(s));
  return k / (1.0 + c_ * k);
}

double SeriesCompliance::potential(double s) const {
  const double y = node_position(s);
  const double f = inner_->force(y);
  return inner_->potential(y) + 0.5 * c_ * f * f;
}

std::string SeriesCompliance::describe() const {
  std::ostringstream os;
  os << inner_->describe() << ", through a spring of flexibility " << c_ << " m/N (stiffness " << 1.0 / c_ << " N/m)";
  return os.str();
}

}  // namespace wbm::contact
