// A Jenkins element with two tangents on two contact points (ContactPoint::second_tangent): the
// checks of the pair, and its loop under the pair's normal law (mechanical_system.hpp).
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <wbm/contact/jenkins_disc.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/status.hpp>

#include "second_tangents.hpp"

namespace wbm::solvers {

namespace detail {

void validate_second_tangents(const std::vector<ContactPoint>& contacts) {
  const auto count = static_cast<int>(contacts.size());
  for (int i = 0; i < count; ++i) {
    const ContactPoint& c = contacts[static_cast<size_t>(i)];
    const bool disc = dynamic_cast<const contact::JenkinsDiscLaw*>(c.law.get()) != nullptr;
    const std::string where = "ContactPoint.second_tangent = " + std::to_string(c.second_tangent) + " (contact " +
                              std::to_string(i) + " at DOF " + std::to_string(c.dof) + ")";
    if (c.second_tangent == -1) {
      if (disc) {
        throw std::invalid_argument(where + ": the contact is a " + c.law->describe() + ", which needs the index of "
                                    "the contact along its other tangent; give it, or use contact::JenkinsLaw (one "
                                    "tangent)");
      }
      continue;
    }
    if (c.second_tangent < -1 || c.second_tangent >= count || c.second_tangent == i) {
      throw std::invalid_argument(where + ": must be -1 (one tangent) or the index of another contact in [0, " +
                                  std::to_string(count) + ")");
    }
    const ContactPoint& t = contacts[static_cast<size_t>(c.second_tangent)];
    if (!disc || t.law.get() != c.law.get()) {
      throw std::invalid_argument(where + ": the two tangents of one element share one contact::JenkinsDiscLaw "
                                  "object; this contact is a " + c.law->describe() + " and contact " +
                                  std::to_string(c.second_tangent) + " a " + t.law->describe());
    }
    if (t.second_tangent != i) {
      throw std::invalid_argument(where + ": contact " + std::to_string(c.second_tangent) + " names " +
                                  std::to_string(t.second_tangent) + " as its second tangent; the two name each other");
    }
    if (t.normal != c.normal) {
      throw std::invalid_argument(where + ": normal = " + std::to_string(c.normal) + " here and " +
                                  std::to_string(t.normal) + " on the other tangent; one element has one normal load");
    }
    // An isotropic disc: orthogonal directions of equal length.
    double dot = 0.0, own = 0.0, other = 0.0;
    for (const auto& [j, w] : c.terms()) {
      own += w * w;
      for (const auto& [k, v] : t.terms()) {
        if (j == k) dot += w * v;
      }
    }
    for (const auto& [k, v] : t.terms()) other += v * v;
    const double scale = std::sqrt(own * other);
    if (std::abs(dot) > 1e-12 * scale || std::abs(own - other) > 1e-12 * std::max(own, other)) {
      throw std::invalid_argument(where + ": the directions have e_1.e_2 = " + format_number(dot) + " and lengths^2 " +
                                  format_number(own) + ", " + format_number(other) + "; an isotropic disc needs "
                                  "orthogonal directions of equal length (two DOFs of one node, or unit vectors)");
    }
  }
}

}  // namespace detail

contact::JenkinsDiscLoop jenkins_disc_contact_loop(const std::vector<ContactPoint>& contacts, int c,
                                                   const Eigen::MatrixXd& u, Eigen::VectorXd* normal,
                                                   bool derivatives) {
  const ContactPoint& point = contacts[static_cast<size_t>(c)];
  const auto* law = dynamic_cast<const contact::JenkinsDiscLaw*>(point.law.get());
  if (point.second_tangent < 0 || law == nullptr) {
    throw std::logic_error("jenkins_disc_contact_loop: contact " + std::to_string(c) + " (" + point.law->describe() +
                           ") is not a Jenkins element with two tangents");
  }
  const int t = point.second_tangent;
  Eigen::MatrixXd w(2, u.cols());
  w.row(0) = u.row(c);
  w.row(1) = u.row(t);
  // u is relative to the counter-surfaces: over the next period it moves by −d (their drifts).
  const Eigen::Vector2d shift(-point.obstacle.drift, -contacts[static_cast<size_t>(t)].obstacle.drift);
  Eigen::VectorXd n;
  if (point.normal >= 0) {
    Eigen::VectorXd slope(u.cols());
    n.resize(u.cols());
    contacts[static_cast<size_t>(point.normal)].law->evaluate(u.row(point.normal).transpose(), n, slope);
  }
  contact::JenkinsDiscLoop loop = law->loop(w, n, shift, derivatives);
  if (normal != nullptr) *normal = n.size() > 0 ? n : Eigen::VectorXd::Zero(u.cols());
  return loop;
}

}  // namespace wbm::solvers
