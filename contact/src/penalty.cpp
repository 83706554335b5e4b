#include <wbm/contact/penalty.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

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

}  // namespace wbm::contact
