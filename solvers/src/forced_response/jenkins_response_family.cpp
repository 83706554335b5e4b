// JenkinsResponseFamily (response_curve.hpp): the forced-response family on the stick/slip pieces
// of its Jenkins elements, for the continuation layer's events.
#include <wbm/solvers/response_curve.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <wbm/contact/friction.hpp>

namespace wbm::solvers {

JenkinsResponseFamily::JenkinsResponseFamily(const ForcedResponseFamily& family)
    : PiecewiseResponseFamily(family) {
  const auto& contacts = family.base().contacts();
  if (family.base().rigid() || std::none_of(contacts.begin(), contacts.end(), [](const ContactPoint& c) {
        return dynamic_cast<const contact::JenkinsLaw*>(c.law.get()) != nullptr;
      })) {
    throw std::invalid_argument("JenkinsResponseFamily: the problem needs a Jenkins element (contact::JenkinsLaw) and "
                                "no rigid stop; continue it with ForcedResponseFamily");
  }
}

ActiveSet JenkinsResponseFamily::active_set(const Eigen::VectorXd& x, double lambda) const {
  return family_->at(lambda).jenkins_active_set(x);
}

Eigen::VectorXd JenkinsResponseFamily::residual(const Eigen::VectorXd& x, double lambda, const ActiveSet& piece) const {
  if (!family_->defined(lambda)) return Eigen::VectorXd::Constant(x.size(), NAN);
  return family_->at(lambda).contact_residual(x, family_->load(lambda), &piece);
}

LowRankLinearization JenkinsResponseFamily::linearize(const Eigen::VectorXd& x, double lambda,
                                                      const ActiveSet& piece) const {
  if (!family_->defined(lambda)) return family_->linearize(x, lambda);  // NaN
  const WeightedResidual& wr = family_->at(lambda);
  const double s = family_->load(lambda);
  LowRankLinearization l;
  l.residual = wr.contact_residual(x, s, &piece);
  l.jacobian = wr.contact_jacobian_low_rank(x, &piece);
  switch (family_->parameter()) {
    case ContinuationParameter::Frequency:
      l.parameter_derivative = wr.contact_residual_frequency_derivative(x, s, &piece);
      break;
    case ContinuationParameter::FrictionCoefficient:
      l.parameter_derivative = wr.contact_residual_friction_derivative(x, &piece);
      break;
    case ContinuationParameter::Amplitude:
      l.parameter_derivative =
          -wr.contact_unknowns(wr.linear_response()) / (wr.residual_scale() * wr.forcing().amplitude);
      break;
  }
  return l;
}

Eigen::VectorXd JenkinsResponseFamily::events(const Eigen::VectorXd& x, double lambda, const ActiveSet& piece) const {
  if (!family_->defined(lambda)) return Eigen::VectorXd::Constant(static_cast<Eigen::Index>(piece.size()), NAN);
  return family_->at(lambda).jenkins_events(x, piece);
}

}  // namespace wbm::solvers
