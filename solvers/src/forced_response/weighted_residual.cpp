#include "weighted_residual_impl.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <unsupported/Eigen/KroneckerProduct>


namespace wbm::solvers {

WeightedResidual::WeightedResidual(MechanicalSystem system, HarmonicForcing forcing,
                                   std::vector<ContactPoint> contacts, TimeBasis trial, TimeBasis weighting,
                                   WeightedResidualOptions options)
    : impl_(std::make_unique<Impl>(std::move(system), forcing, std::move(contacts), std::move(trial),
                                   std::move(weighting), options)) {}
WeightedResidual::~WeightedResidual() = default;
WeightedResidual::WeightedResidual(WeightedResidual&&) noexcept = default;
WeightedResidual& WeightedResidual::operator=(WeightedResidual&&) noexcept = default;

int WeightedResidual::dofs() const { return impl_->n; }
int WeightedResidual::dimension() const { return impl_->m; }
int WeightedResidual::time_samples() const { return impl_->q; }
const MechanicalSystem& WeightedResidual::system() const { return impl_->system; }
const HarmonicForcing& WeightedResidual::forcing() const { return impl_->forcing; }
const std::vector<ContactPoint>& WeightedResidual::contacts() const { return impl_->contacts; }
const TimeBasis& WeightedResidual::trial() const { return impl_->trial; }
const TimeBasis& WeightedResidual::weighting() const { return impl_->weighting; }
Formulation WeightedResidual::formulation() const { return impl_->options.formulation; }
const TimeOperators& WeightedResidual::time_operators() const { return impl_->ops; }
std::string WeightedResidual::linear_solver() const { return impl_->g->modal() ? "modal" : "sparse-lu"; }

std::string WeightedResidual::describe() const {
  std::string d = impl_->trial.name() + ":" + impl_->weighting.name() + ", " + std::string(to_string(formulation()));
  if (!impl_->options.harmonics.empty()) {
    d += ", harmonics";
    for (size_t i = 0; i < impl_->options.harmonics.size(); ++i) {
      d.append(i == 0 ? " " : ", ").append(std::to_string(impl_->options.harmonics[i]));
    }
    d += " only";
  }
  return d;
}

double WeightedResidual::condition_number() const {
  const auto& p = *impl_;
  if (!p.factorized) return std::numeric_limits<double>::infinity();
  return p.g->condition_estimate();  // ‖G‖₁ · est(‖G⁻¹‖₁) through the factorization in use
}

double WeightedResidual::backward_error(const Eigen::VectorXd& a, const Eigen::VectorXd& r) const {
  const auto& p = *impl_;
  const Eigen::Index size = static_cast<Eigen::Index>(p.n) * p.m;
  if (a.size() != size || r.size() != size) {
    throw std::invalid_argument("WeightedResidual::backward_error: a has length " + std::to_string(a.size()) +
                                " and r " + std::to_string(r.size()) + ", expected n*M = " + std::to_string(size));
  }
  p.require_factorized();
  const double rnorm = r.norm();
  if (rnorm == 0.0) return 0.0;
  const double gamma = p.frobenius_norm();  // ≥ ‖G‖₂
  const double contact = (r - p.linear_residual(a)).norm();        // ‖n‖: r = (G a − b) + n
  return rnorm / (gamma * a.norm() + p.b.norm() + contact);
}

Eigen::VectorXd WeightedResidual::residual(const Eigen::VectorXd& a) const {
  const auto& p = *impl_;
  Eigen::VectorXd r = p.linear_residual(a);
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(p.gather(a), nullptr);
    p.scatter(r, nx, 1.0);
  }
  return r;
}

Eigen::MatrixXd WeightedResidual::jacobian(const Eigen::VectorXd& a) const {
  const auto& p = *impl_;
  const double fr = p.forcing.frequency_hz;
  Eigen::MatrixXd jac = Eigen::kroneckerProduct(fr * fr * p.ops.mass, Eigen::MatrixXd(p.system.mass)) +
                        Eigen::kroneckerProduct(fr * p.ops.damping, Eigen::MatrixXd(p.system.damping)) +
                        Eigen::kroneckerProduct(p.ops.stiffness, Eigen::MatrixXd(p.system.stiffness));
  if (p.nc > 0) {
    std::vector<Impl::ContactTangent> tangents;
    (void)p.contact_forces(p.gather(a), &tangents);
    const Eigen::MatrixXd nj = p.contact_force_jacobian(tangents);
    // Pᵀ N P with P's rows the contact directions.
    for (size_t i = 0; i < p.contact_terms.size(); ++i) {
      for (size_t j = 0; j < p.contact_terms.size(); ++j) {
        const double v = nj(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
        if (v == 0.0) continue;
        for (const auto& [ri, wi] : p.contact_terms[i]) {
          for (const auto& [rj, wj] : p.contact_terms[j]) jac(ri, rj) += wi * v * wj;
        }
      }
    }
  }
  return jac;
}

Eigen::VectorXd WeightedResidual::linear_response() const {
  impl_->require_factorized();
  return impl_->linear_coefficients();
}

Eigen::VectorXd WeightedResidual::contact_unknowns(const Eigen::VectorXd& a) const { return impl_->gather(a); }

const std::vector<int>& WeightedResidual::harmonics() const { return impl_->options.harmonics; }

double WeightedResidual::dropped_harmonics_residual(const Eigen::VectorXd& x, double load) const {
  const auto& p = *impl_;
  if (p.keep.size() == 0) return std::numeric_limits<double>::quiet_NaN();
  p.require_factorized();
  if (p.nc == 0) return 0.0;
  if (x.size() != static_cast<Eigen::Index>(p.nc) * p.m) {
    throw std::invalid_argument("WeightedResidual::dropped_harmonics_residual: x has length " + std::to_string(x.size()) +
                                ", expected n_c*M = " + std::to_string(p.nc * p.m));
  }
  // G a − b vanishes on the dropped functions (G is block-diagonal by harmonic, a and b are in
  // the kept span): (I − Π) R = (I − Π) Pᵀ n(a), the contact forces' projection there.
  Eigen::MatrixXd dropped = p.sampling->weighting->unselected_projection(p.contact_force_samples(x, nullptr));
  dropped *= (Eigen::RowVectorXd::Ones(p.m) - p.keep).asDiagonal();
  Eigen::VectorXd r = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(p.n) * p.m);
  p.scatter(r, spectral::stacked(dropped), 1.0);
  const double bnorm = std::abs(load) * p.b.norm();
  return r.norm() / (bnorm > 0.0 ? bnorm : 1.0);
}

Eigen::VectorXd WeightedResidual::contact_residual(const Eigen::VectorXd& x, double load,
                                                   const ActiveSet* piece) const {
  return impl_->contact_residual(x, load, piece);
}

WeightedResidual::WeightedResidual(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

WeightedResidual WeightedResidual::at_frequency(double frequency_hz) const {
  if (!(frequency_hz > 0.0) || !std::isfinite(frequency_hz)) {
    throw std::invalid_argument("WeightedResidual::at_frequency: f = " + format_number(frequency_hz) +
                                " Hz; must be > 0 and finite");
  }
  return WeightedResidual(std::make_unique<Impl>(*impl_, frequency_hz));
}

double WeightedResidual::frequency_hz() const { return impl_->forcing.frequency_hz; }
double WeightedResidual::residual_scale() const { return impl_->scale; }

Eigen::VectorXd WeightedResidual::contact_residual_frequency_derivative(const Eigen::VectorXd& x, double load,
                                                                       const ActiveSet* piece) const {
  const auto& p = *impl_;
  p.require_factorized();
  Eigen::VectorXd rhs = load * p.b;
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(x, nullptr, piece);
    p.scatter(rhs, nx, -1.0);
  }
  if (const auto gathered = p.gathered_solve(rhs, true)) return *gathered / p.scale;
  const Eigen::MatrixXd a = spectral::as_coefficients(p.solve_stacked(rhs, false), p.n);  // n × M
  return p.gather(p.solve_stacked(p.frequency_derivative_times(a), false)) / p.scale;
}

void WeightedResidual::set_friction_coefficient(double mu) {
  impl_->contacts = with_friction_coefficient(impl_->contacts, mu);
}

Eigen::VectorXd WeightedResidual::contact_residual_friction_derivative(const Eigen::VectorXd& x,
                                                                      const ActiveSet* piece) const {
  const auto& p = *impl_;
  p.refuse_rigid("contact_residual_friction_derivative");
  p.require_factorized();
  (void)common_friction_coefficient(p.contacts);
  if (piece != nullptr) p.check_jenkins_piece(*piece, "contact_residual_friction_derivative");
  int jenkins_index = 0;
  const Eigen::MatrixXd u = p.contact_samples(x);  // n_c × Q, relative to the counter-surfaces
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(p.nc, p.q);  // ∂f_c(τ_q)/∂μ [N]
  Eigen::VectorXd normal;
  for (int c = 0; c < p.nc; ++c) {
    const auto* jenkins = dynamic_cast<const contact::JenkinsLaw*>(p.contacts[static_cast<size_t>(c)].law.get());
    if (jenkins == nullptr) continue;
    std::vector<std::uint8_t> pattern;
    if (piece != nullptr) pattern = p.jenkins_pattern(*piece, jenkins_index++);
    const contact::JenkinsLoop loop =
        jenkins_contact_loop(p.contacts, c, u, piece != nullptr ? &pattern : nullptr, &normal);
    const double preload = jenkins->parameters().normal_load;
    for (int q = 0; q < p.q; ++q) {
      const int r = loop.stiffness(q) != 0.0 && loop.anchor(q) >= 0 ? loop.anchor(q) : q;
      d(c, q) = loop.slip_sensitivity(q) * (preload + normal(r));
    }
  }
  return p.compliance_times(Eigen::VectorXd(spectral::stacked(p.sampling->weighting->project(d)))) / p.scale;
}

Eigen::MatrixXd WeightedResidual::contact_jacobian(const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  p.require_factorized();
  std::vector<Impl::ContactTangent> tangents;
  (void)p.contact_forces(x, &tangents);
  return p.identity_plus_hn(tangents) / p.scale;
}

LowRankJacobian WeightedResidual::contact_jacobian_low_rank(const Eigen::VectorXd& x, const ActiveSet* piece) const {
  impl_->require_factorized();
  return impl_->low_rank_contact_jacobian(x, piece);
}

ActiveSet WeightedResidual::jenkins_active_set(const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  p.refuse_rigid("jenkins_active_set");
  const std::vector<int> elements = p.jenkins_contacts();
  const Eigen::MatrixXd u = p.contact_samples(x);
  ActiveSet piece;
  piece.reserve(elements.size() * static_cast<size_t>(p.q));
  for (int c : elements) {
    const Eigen::VectorXd k = jenkins_contact_loop(p.contacts, c, u).stiffness;
    for (int q = 0; q < p.q; ++q) piece.push_back(k(q) == 0.0 ? 1U : 0U);  // slip: ∂f_q/∂w_q = 0
  }
  return piece;
}

Eigen::VectorXd WeightedResidual::jenkins_events(const Eigen::VectorXd& x, const ActiveSet& piece) const {
  const auto& p = *impl_;
  p.refuse_rigid("jenkins_events");
  p.check_jenkins_piece(piece, "jenkins_events");
  const std::vector<int> elements = p.jenkins_contacts();
  const Eigen::MatrixXd u = p.contact_samples(x);
  Eigen::VectorXd events(static_cast<Eigen::Index>(piece.size()));
  for (size_t j = 0; j < elements.size(); ++j) {
    const int c = elements[j];
    const std::vector<std::uint8_t> pattern = p.jenkins_pattern(piece, static_cast<int>(j));
    const Eigen::VectorXd margin = jenkins_contact_loop(p.contacts, c, u, &pattern).margin;
    const auto& law = dynamic_cast<const contact::JenkinsLaw&>(*p.contacts[static_cast<size_t>(c)].law);
    const double kt = law.parameters().tangential_stiffness;
    for (int q = 0; q < p.q; ++q) {
      events(static_cast<Eigen::Index>(j) * p.q + q) = (pattern[static_cast<size_t>(q)] != 0 ? -1.0 : 1.0) *
                                                       margin(q) / (kt * p.scale);
    }
  }
  return events;
}

Eigen::VectorXd WeightedResidual::expand(const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  p.require_factorized();
  Eigen::VectorXd rhs = p.b;
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(x, nullptr);
    p.scatter(rhs, nx, -1.0);
  }
  return p.solve_stacked(rhs, false);
}

ContactQuadrature WeightedResidual::contact_quadrature() const {
  return impl_->cell_average_rule ? ContactQuadrature::CellAverage : ContactQuadrature::Midpoint;
}

}  // namespace wbm::solvers
