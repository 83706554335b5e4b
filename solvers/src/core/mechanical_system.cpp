#include <wbm/solvers/mechanical_system.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseLU>

#include <wbm/contact/friction.hpp>
#include <wbm/solvers/model_checks.hpp>
#include <wbm/solvers/status.hpp>

#include "second_tangents.hpp"

namespace wbm::solvers {

void MechanicalSystem::validate() const {
  const auto n = mass.rows();
  auto check = [n](const Eigen::SparseMatrix<double>& x, const char* name) {
    if (x.rows() != n || x.cols() != n) {
      std::ostringstream os;
      os << "MechanicalSystem." << name << " is " << x.rows() << " x " << x.cols()
         << ": all three matrices must be n x n with n = mass.rows() = " << n;
      throw std::invalid_argument(os.str());
    }
    for (int k = 0; k < x.outerSize(); ++k) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(x, k); it; ++it) {
        if (!std::isfinite(it.value())) {
          throw std::invalid_argument(std::string("MechanicalSystem.") + name +
                                      " has a non-finite entry at (" + std::to_string(it.row()) +
                                      ", " + std::to_string(it.col()) + ")");
        }
      }
    }
  };
  // Symmetry: the modal paths (generalized eigensolver, nonlinear modes) read one triangle only,
  // so a non-symmetric matrix would be solved silently as another one.
  auto symmetric = [](const Eigen::SparseMatrix<double>& x, const char* name) {
    const Eigen::SparseMatrix<double> xt = x.transpose();
    const Eigen::SparseMatrix<double> d = x - xt;
    double largest = 0.0, worst = 0.0;
    Eigen::Index wr = 0, wc = 0;
    for (int k = 0; k < x.outerSize(); ++k) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(x, k); it; ++it) largest = std::max(largest, std::abs(it.value()));
    }
    for (int k = 0; k < d.outerSize(); ++k) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(d, k); it; ++it) {
        if (std::abs(it.value()) > worst) {
          worst = std::abs(it.value());
          wr = it.row();
          wc = it.col();
        }
      }
    }
    // 1e-12 of the largest entry: FE assembly and Matrix Market round trips are symmetric to rounding.
    if (worst > 1e-12 * largest) {
      std::ostringstream os;
      os << "MechanicalSystem." << name << " is not symmetric: |X(" << wr << ", " << wc << ") - X(" << wc << ", " << wr
         << ")| = " << worst << ", " << worst / largest << " of the largest entry (allowed 1e-12); symmetrize it "
         << "((X + X^T)/2) if the asymmetry is rounding, or check the assembly (wbm solves self-adjoint structures)";
      throw std::invalid_argument(os.str());
    }
  };
  if (n < 1) throw std::invalid_argument("MechanicalSystem: mass matrix is empty, need n >= 1 DOF");
  check(mass, "mass");
  check(damping, "damping");
  check(stiffness, "stiffness");
  symmetric(mass, "mass");
  symmetric(damping, "damping");
  symmetric(stiffness, "stiffness");
}

MechanicalSystem beta_damped(const fem::Rod& rod, double beta) {
  if (!(beta >= 0.0) || !std::isfinite(beta)) {
    std::ostringstream os;
    os << "damping factor beta = " << beta << " s: must be finite and >= 0 (C = beta K)";
    throw std::invalid_argument(os.str());
  }
  return {rod.mass(), beta * rod.stiffness(), rod.stiffness()};
}

std::vector<HarmonicLoad> HarmonicForcing::loads() const {
  std::vector<HarmonicLoad> all = {{dof, amplitude, 0.0, 1}};
  all.insert(all.end(), more.begin(), more.end());
  return all;
}

Eigen::VectorXd HarmonicForcing::at(double tau, int n) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
  for (const auto& l : loads()) f(l.dof) += l.amplitude * std::cos(2.0 * std::numbers::pi * l.harmonic * tau + l.phase_rad);
  return f;
}

void HarmonicForcing::validate(int dofs) const {
  for (size_t j = 0; j < more.size(); ++j) {
    const auto& l = more[j];
    const std::string where = "HarmonicForcing.more[" + std::to_string(j) + "]";
    if (l.dof < 0 || l.dof >= dofs) {
      throw std::invalid_argument(where + ".dof = " + std::to_string(l.dof) + ": must lie in [0, " + std::to_string(dofs) + ")");
    }
    if (!std::isfinite(l.amplitude)) throw std::invalid_argument(where + ".amplitude is not finite");
    if (!std::isfinite(l.phase_rad)) throw std::invalid_argument(where + ".phase_rad is not finite");
    if (l.harmonic < 0) {
      throw std::invalid_argument(where + ".harmonic = " + std::to_string(l.harmonic) +
                                  ": must be >= 0 (0: a constant load, 1: the forcing frequency, h: h times it)");
    }
  }
  if (dof < 0 || dof >= dofs) {
    throw std::invalid_argument("HarmonicForcing.dof = " + std::to_string(dof) +
                                ": must lie in [0, " + std::to_string(dofs) + ")");
  }
  if (!std::isfinite(amplitude)) {
    throw std::invalid_argument("HarmonicForcing.amplitude is not finite");
  }
  if (!(frequency_hz > 0.0) || !std::isfinite(frequency_hz)) {
    std::ostringstream os;
    os << "HarmonicForcing.frequency_hz = " << frequency_hz << " Hz: must be finite and > 0";
    throw std::invalid_argument(os.str());
  }
}

void HarmonicForcing::require_resolved(int functions, const std::string& what, const std::string& fix) const {
  const int highest = highest_resolved_harmonic(functions);
  const auto all = loads();
  for (size_t j = 0; j < all.size(); ++j) {
    const auto& l = all[j];
    if (l.amplitude == 0.0 || l.harmonic <= highest) continue;
    const std::string name = j == 0 ? "HarmonicForcing (the load F cos 2πft)" : "HarmonicForcing.more[" + std::to_string(j - 1) + "]";
    throw std::invalid_argument(name + " acts at harmonic " + std::to_string(l.harmonic) + " on DOF " +
                                std::to_string(l.dof) + ", above the highest harmonic " + std::to_string(highest) +
                                " that " + what + " resolve (2h < " + std::to_string(functions) +
                                "); its samples would alias it to a lower harmonic: " + fix + " to more than " +
                                std::to_string(2 * l.harmonic) + ", or remove the load");
  }
}

void validate_direction(const std::vector<std::pair<int, double>>& along, int dof, int dofs, const std::string& where) {
  std::set<int> dofs_in;
  double norm = 0.0;
  for (const auto& [j, w] : along) {
    if (j < 0 || j >= dofs) {
      throw std::invalid_argument(where + ": DOF " + std::to_string(j) + " must lie in [0, " + std::to_string(dofs) + ")");
    }
    if (!std::isfinite(w)) throw std::invalid_argument(where + ": the weight of DOF " + std::to_string(j) + " is not finite");
    if (!dofs_in.insert(j).second) {
      throw std::invalid_argument(where + ": DOF " + std::to_string(j) + " appears twice; give each DOF one weight");
    }
    norm += w * w;
  }
  if (!(norm > 0.0)) throw std::invalid_argument(where + ": every weight is zero; give a direction (e.g. a unit normal)");
  if (dofs_in.count(dof) == 0) {
    throw std::invalid_argument(where + ": dof " + std::to_string(dof) +
                                " is not among its DOFs; dof names the contact and must be one of them");
  }
}

void ContactPoint::validate(const std::vector<ContactPoint>& contacts, int dofs) {
  std::set<std::vector<std::pair<int, double>>> seen;
  for (const auto& c : contacts) {
    if (c.dof < 0 || c.dof >= dofs) {
      throw std::invalid_argument("ContactPoint.dof = " + std::to_string(c.dof) +
                                  ": must lie in [0, " + std::to_string(dofs) + ")");
    }
    if (c.other < -1 || c.other >= dofs || c.other == c.dof) {
      throw std::invalid_argument("ContactPoint.other = " + std::to_string(c.other) + " (dof " + std::to_string(c.dof) +
                                  "): must be -1 (a fixed obstacle) or another DOF in [0, " + std::to_string(dofs) + ")");
    }
    if (!c.law) throw std::invalid_argument("ContactPoint.law is null for DOF " + std::to_string(c.dof));
    if (!c.along.empty()) {
      const std::string where = "ContactPoint.along (contact at DOF " + std::to_string(c.dof) + ")";
      if (c.other >= 0) {
        throw std::invalid_argument(where + ": other = " + std::to_string(c.other) +
                                    " beside a direction; put the other DOF in along with its weight");
      }
      validate_direction(c.along, c.dof, dofs, where);
    }
    auto key = c.terms();
    std::sort(key.begin(), key.end());
    if (!seen.insert(key).second) {
      throw std::invalid_argument("ContactPoint.dof = " + std::to_string(c.dof) +
                                  (c.other >= 0 ? " against DOF " + std::to_string(c.other) : std::string()) +
                                  (c.along.empty() ? std::string() : " (along a direction)") +
                                  " appears twice: combine the laws into one per DOF");
    }
  }
  for (size_t i = 0; i < contacts.size(); ++i) {
    const ContactPoint& c = contacts[i];
    const ObstacleMotion& o = c.obstacle;
    const std::string where =
        "ContactPoint.obstacle (contact " + std::to_string(i) + " at DOF " + std::to_string(c.dof) + ")";
    if (!std::isfinite(o.drift)) {
      throw std::invalid_argument(where + ".drift = " + format_number(o.drift) + ": must be finite [m]");
    }
    for (const auto* list : {&o.cosine, &o.sine}) {
      for (size_t h = 0; h < list->size(); ++h) {
        if (std::isfinite((*list)[h])) continue;
        throw std::invalid_argument(where + (list == &o.cosine ? ".cosine[" : ".sine[") + std::to_string(h) +
                                    "] = " + format_number((*list)[h]) + " (harmonic " + std::to_string(h + 1) +
                                    "): must be finite [m]");
      }
    }
    if (o.drift != 0.0 && !c.law->hysteretic()) {
      throw std::invalid_argument(where + ".drift = " + format_number(o.drift) + " m per period on a " +
                                  c.law->describe() +
                                  ": a normal gap that grows by the drift every period has no periodic response; a "
                                  "drift is a friction contact's sliding (set drift = 0 here)");
    }
  }
  detail::validate_second_tangents(contacts);
  const auto count = static_cast<int>(contacts.size());
  for (int i = 0; i < count; ++i) {
    const ContactPoint& c = contacts[static_cast<size_t>(i)];
    if (c.normal == -1) continue;
    const std::string where = "ContactPoint.normal = " + std::to_string(c.normal) + " (contact " + std::to_string(i) +
                              " at DOF " + std::to_string(c.dof) + ")";
    if (c.normal < -1 || c.normal >= count || c.normal == i) {
      throw std::invalid_argument(where + ": must be -1 (a constant normal load) or the index of another contact in [0, " +
                                  std::to_string(count) + ")");
    }
    const auto& n = *contacts[static_cast<size_t>(c.normal)].law;
    if (const auto* coulomb = dynamic_cast<const contact::CoulombFriction*>(c.law.get())) {
      // Exact Coulomb friction: a 2D contact, the normal load the stop's reaction (a multiplier).
      if (!n.rigid() || n.hysteretic()) {
        throw std::invalid_argument(where + ": the normal contact is a " + n.describe() +
                                    "; exact Coulomb friction takes its normal load from a rigid stop "
                                    "(contact::RigidStop); for a penalty normal law use a Jenkins element "
                                    "(contact::JenkinsLaw)");
      }
      if (coulomb->parameters().normal_load != 0.0) {
        throw std::invalid_argument(where + ": normal_load = " + format_number(coulomb->parameters().normal_load) +
                                    " N beside a rigid normal stop, whose reaction is the normal load: set it to 0 and "
                                    "press the normal DOF with a static load (HarmonicLoad with harmonic 0)");
      }
      for (int j = 0; j < i; ++j) {
        const ContactPoint& o = contacts[static_cast<size_t>(j)];
        if (o.normal == c.normal && dynamic_cast<const contact::CoulombFriction*>(o.law.get()) != nullptr) {
          throw std::invalid_argument(where + ": contact " + std::to_string(j) + " already takes its normal load from "
                                      "that stop; one tangent per stop (a 2D contact)");
        }
      }
      continue;
    }
    if (!c.law->takes_normal_load()) {
      throw std::invalid_argument(where + ": the " + c.law->describe() + " takes no varying normal load; only a "
                                  "Jenkins element (on a penalty normal law) and exact Coulomb friction (on a rigid "
                                  "stop) do");
    }
    if (n.rigid() || n.hysteretic()) {
      throw std::invalid_argument(where + ": the normal contact is a " + n.describe() + "; the normal load of a "
                                  "Jenkins element comes from a penalty law (linear or exponential) whose force is a "
                                  "function of the normal gap (for a rigid stop, use exact Coulomb friction)");
    }
  }
}

Eigen::VectorXcd frequency_response(const MechanicalSystem& system, const HarmonicForcing& forcing) {
  system.validate();
  forcing.validate(system.dofs());
  const double w = 2.0 * std::numbers::pi * forcing.frequency_hz;
  using Complex = std::complex<double>;
  const Eigen::SparseMatrix<Complex> d =
      (system.stiffness - w * w * system.mass).cast<Complex>() +
      Complex(0.0, w) * system.damping.cast<Complex>();
  Eigen::SparseLU<Eigen::SparseMatrix<Complex>> lu(d);
  if (lu.info() != Eigen::Success) {
    std::ostringstream os;
    const std::string why = explain_singular_dynamic_stiffness(system, forcing.frequency_hz, 1);
    os << "frequency_response: K - w^2 M + i w C is singular at f = " << forcing.frequency_hz << " Hz: "
       << (why.empty() ? "G is singular to working precision (check the scale of M, C and K)" : why);
    throw std::runtime_error(os.str());
  }
  Eigen::VectorXcd rhs = Eigen::VectorXcd::Zero(system.dofs());
  for (const auto& l : forcing.loads()) {
    if (l.harmonic != 1) {
      throw std::invalid_argument("frequency_response: the load on DOF " + std::to_string(l.dof) + " has harmonic " +
                                  std::to_string(l.harmonic) + "; the complex response is at the forcing frequency "
                                  "only: solve the weighted residual (any basis) for several harmonics");
    }
    rhs(l.dof) += l.amplitude * std::polar(1.0, l.phase_rad);
  }
  return lu.solve(rhs);
}

bool ObstacleMotion::moving() const {
  if (drift != 0.0) return true;
  const auto nonzero = [](double v) { return v != 0.0; };
  return std::any_of(cosine.begin(), cosine.end(), nonzero) || std::any_of(sine.begin(), sine.end(), nonzero);
}

int ObstacleMotion::highest_harmonic() const {
  int h = 0;
  for (size_t i = 0; i < cosine.size(); ++i) {
    if (cosine[i] != 0.0) h = std::max(h, static_cast<int>(i) + 1);
  }
  for (size_t i = 0; i < sine.size(); ++i) {
    if (sine[i] != 0.0) h = std::max(h, static_cast<int>(i) + 1);
  }
  return h;
}

double ObstacleMotion::at(double tau) const {
  double s = drift * tau;
  for (size_t i = 0; i < std::max(cosine.size(), sine.size()); ++i) {
    const double arg = 2.0 * std::numbers::pi * static_cast<double>(i + 1) * tau;
    if (i < cosine.size() && cosine[i] != 0.0) s += cosine[i] * std::cos(arg);
    if (i < sine.size() && sine[i] != 0.0) s += sine[i] * std::sin(arg);
  }
  return s;
}

double ObstacleMotion::rate(double tau) const {
  double s = drift;
  for (size_t i = 0; i < std::max(cosine.size(), sine.size()); ++i) {
    const double w = 2.0 * std::numbers::pi * static_cast<double>(i + 1);
    if (i < cosine.size() && cosine[i] != 0.0) s -= w * cosine[i] * std::sin(w * tau);
    if (i < sine.size() && sine[i] != 0.0) s += w * sine[i] * std::cos(w * tau);
  }
  return s;
}

double ObstacleMotion::amplitude_bound() const {
  double bound = 0.0;
  for (size_t i = 0; i < std::max(cosine.size(), sine.size()); ++i) {
    const double a = i < cosine.size() ? cosine[i] : 0.0, b = i < sine.size() ? sine[i] : 0.0;
    bound += std::hypot(a, b);
  }
  return bound;
}

bool any_moving_obstacle(const std::vector<ContactPoint>& contacts) {
  return std::any_of(contacts.begin(), contacts.end(), [](const ContactPoint& c) { return c.obstacle.moving(); });
}

Eigen::MatrixXd obstacle_samples(const std::vector<ContactPoint>& contacts,
                                 const Eigen::Ref<const Eigen::VectorXd>& tau, int derivative) {
  if (derivative != 0 && derivative != 1) {
    throw std::invalid_argument("obstacle_samples: derivative = " + std::to_string(derivative) + " must be 0 or 1");
  }
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(contacts.size()), tau.size());
  for (size_t c = 0; c < contacts.size(); ++c) {
    const ObstacleMotion& o = contacts[c].obstacle;
    if (!o.moving()) continue;
    for (Eigen::Index p = 0; p < tau.size(); ++p) {
      out(static_cast<Eigen::Index>(c), p) = derivative == 0 ? o.at(tau(p)) : o.rate(tau(p));
    }
  }
  return out;
}

void require_fixed_obstacles(const std::vector<ContactPoint>& contacts, const std::string& what,
                             const std::string& fix) {
  for (size_t c = 0; c < contacts.size(); ++c) {
    if (!contacts[c].obstacle.moving()) continue;
    throw std::invalid_argument(what + ": contact " + std::to_string(c) + " (DOF " + std::to_string(contacts[c].dof) +
                                ") has a moving counter-surface (ContactPoint::obstacle), which " + what +
                                " does not model; " + fix);
  }
}

void evaluate_contact_period(const std::vector<ContactPoint>& contacts, int c, const Eigen::MatrixXd& u,
                             Eigen::Ref<Eigen::VectorXd> force, Eigen::Ref<Eigen::VectorXd> stiffness,
                             Eigen::Ref<Eigen::VectorXi> anchor, Eigen::Ref<Eigen::VectorXd> load_sensitivity,
                             const std::vector<std::uint8_t>* pattern) {
  const ContactPoint& point = contacts[static_cast<size_t>(c)];
  if (point.second_tangent >= 0) {
    if (pattern != nullptr) {
      throw std::logic_error("evaluate_contact_period: contact " + std::to_string(c) + " is a " +
                             point.law->describe() + ", which has no stick/slip pieces");
    }
    force = jenkins_disc_contact_loop(contacts, c, u, nullptr, false).force.row(0).transpose();
    stiffness.setZero();
    anchor.setConstant(-1);
    load_sensitivity.setZero();
    return;
  }
  // u is relative to the counter-surface: over the next period it moves by −d (its drift).
  const double shift = -point.obstacle.drift;
  if (pattern != nullptr) {
    const contact::JenkinsLoop loop = jenkins_contact_loop(contacts, c, u, pattern);
    force = loop.force;
    stiffness = loop.stiffness;
    anchor = loop.anchor;
    if (point.normal >= 0) {
      load_sensitivity = dynamic_cast<const contact::JenkinsLaw&>(*point.law).parameters().friction_coefficient *
                         loop.slip_sensitivity;
    } else {
      load_sensitivity.setZero();
    }
    return;
  }
  if (point.normal < 0) {
    point.law->evaluate_period(u.row(c).transpose(), force, stiffness, anchor, shift);
    load_sensitivity.setZero();
    return;
  }
  Eigen::VectorXd normal(u.cols()), normal_stiffness(u.cols());
  contacts[static_cast<size_t>(point.normal)].law->evaluate(u.row(point.normal).transpose(), normal, normal_stiffness);
  point.law->evaluate_period_loaded(u.row(c).transpose(), normal, force, stiffness, anchor, load_sensitivity, shift);
}

contact::JenkinsLoop jenkins_contact_loop(const std::vector<ContactPoint>& contacts, int c, const Eigen::MatrixXd& u,
                                          const std::vector<std::uint8_t>* pattern, Eigen::VectorXd* normal) {
  const ContactPoint& point = contacts[static_cast<size_t>(c)];
  const auto* jenkins = dynamic_cast<const contact::JenkinsLaw*>(point.law.get());
  if (jenkins == nullptr) {
    throw std::logic_error("jenkins_contact_loop: contact " + std::to_string(c) + " (" + point.law->describe() +
                           ") is not a Jenkins element");
  }
  const double shift = -point.obstacle.drift;  // as evaluate_contact_period
  if (point.normal < 0) {
    if (normal != nullptr) *normal = Eigen::VectorXd::Zero(u.cols());
    return jenkins->loop(u.row(c).transpose(), shift, pattern);
  }
  Eigen::VectorXd n(u.cols()), normal_stiffness(u.cols());
  contacts[static_cast<size_t>(point.normal)].law->evaluate(u.row(point.normal).transpose(), n, normal_stiffness);
  contact::JenkinsLoop loop = jenkins->loop(u.row(c).transpose(), n, shift, pattern);
  if (normal != nullptr) *normal = std::move(n);
  return loop;
}

double common_friction_coefficient(const std::vector<ContactPoint>& contacts) {
  int first = -1;
  double mu = 0.0;
  for (size_t c = 0; c < contacts.size(); ++c) {
    const auto& law = contacts[c].law;
    if (dynamic_cast<const contact::JenkinsDiscLaw*>(law.get()) != nullptr) {
      throw std::invalid_argument("friction coefficient continuation: contact " + std::to_string(c) + " (DOF " +
                                  std::to_string(contacts[c].dof) + ") is a Jenkins element with two tangents "
                                  "(second_tangent), whose mu is not a continuation parameter; continue in frequency, "
                                  "or give it one tangent");
    }
    if (dynamic_cast<const contact::CoulombFriction*>(law.get()) != nullptr) {
      throw std::invalid_argument("friction coefficient continuation: contact " + std::to_string(c) + " (DOF " +
                                  std::to_string(contacts[c].dof) + ") is exact Coulomb friction (law \"coulomb\"), "
                                  "whose mu is not a parameter of the weighted residual's rigid path; use a stiff "
                                  "Jenkins element (law \"jenkins\", contact::JenkinsLaw)");
    }
    const auto* jenkins = dynamic_cast<const contact::JenkinsLaw*>(law.get());
    if (jenkins == nullptr) continue;
    const double m = jenkins->parameters().friction_coefficient;
    if (first < 0) {
      first = static_cast<int>(c);
      mu = m;
    } else if (m != mu) {
      throw std::invalid_argument("friction coefficient continuation: the Jenkins elements of contacts " +
                                  std::to_string(first) + " and " + std::to_string(c) + " have mu = " +
                                  format_number(mu) + " and " + format_number(m) + "; the parameter is one mu "
                                  "shared by every element: give them all the start's mu");
    }
  }
  if (first < 0) {
    throw std::invalid_argument("friction coefficient continuation: no contact is a Jenkins element "
                                "(contact::JenkinsLaw, law \"jenkins\"): there is no friction coefficient to vary");
  }
  return mu;
}

std::vector<ContactPoint> with_friction_coefficient(const std::vector<ContactPoint>& contacts, double mu) {
  if (!(mu >= 0.0) || !std::isfinite(mu)) {
    throw std::invalid_argument("friction coefficient mu = " + format_number(mu) + ": must be finite and >= 0");
  }
  (void)common_friction_coefficient(contacts);
  std::vector<ContactPoint> out = contacts;
  for (auto& c : out) {
    if (const auto* jenkins = dynamic_cast<const contact::JenkinsLaw*>(c.law.get())) {
      contact::JenkinsParameters p = jenkins->parameters();
      p.friction_coefficient = mu;
      c.law = std::make_shared<contact::JenkinsLaw>(p);
    }
  }
  return out;
}

Eigen::SparseMatrix<double> modal_damping(const MechanicalSystem& system, double ratio) {
  if (!(ratio >= 0.0) || !std::isfinite(ratio)) {
    throw std::invalid_argument("modal damping ratio zeta = " + format_number(ratio) +
                                ": must be finite and >= 0 (0.01 is 1 % of critical damping in every mode)");
  }
  system.validate();
  const auto n = system.mass.rows();
  if (ratio == 0.0 || n == 0) return Eigen::SparseMatrix<double>(n, n);
  const Eigen::MatrixXd m(system.mass);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(system.stiffness), m);
  if (eig.info() != Eigen::Success || !eig.eigenvalues().allFinite()) {
    throw std::invalid_argument("modal damping: K phi = M phi omega^2 failed; M must be symmetric positive definite "
                                "(condense massless DOFs first, or give C as alpha M + beta K)");
  }
  const Eigen::VectorXd& w2 = eig.eigenvalues();
  const double floor = 1e-12 * w2.cwiseAbs().maxCoeff();
  Eigen::VectorXd c(n);
  for (Eigen::Index i = 0; i < n; ++i) c(i) = w2(i) > floor ? 2.0 * ratio * std::sqrt(w2(i)) : 0.0;
  const Eigen::MatrixXd mp = m * eig.eigenvectors();
  Eigen::MatrixXd dense = mp * c.asDiagonal() * mp.transpose();
  dense = 0.5 * (dense + dense.transpose()).eval();  // symmetric to the last bit
  return dense.sparseView(0.0, 0.0);
}

}  // namespace wbm::solvers
