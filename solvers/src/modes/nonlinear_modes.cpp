#include <wbm/solvers/nonlinear_modes.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include <wbm/spectral/fourier_basis.hpp>
#include <wbm/spectral/layout.hpp>

namespace wbm::solvers {

const ModeLevel* Backbone::included_at(double energy) const {
  const auto it = std::find_if(included.begin(), included.end(),
                               [&](const ModeLevel& l) { return std::abs(l.energy - energy) <= 1e-12 * std::abs(energy); });
  return it == included.end() ? nullptr : &*it;
}

bool Backbone::converged(const std::vector<double>& requested) const {
  if (!complete()) return false;
  return std::all_of(requested.begin(), requested.end(), [&](double energy) {
    const ModeLevel* l = included_at(energy);
    return l != nullptr && l->converged();
  });
}

void NonlinearModeOptions::validate(int dofs) const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("NonlinearModeOptions." + what); };
  if (harmonics < 1 || harmonics > 512) fail("harmonics = " + std::to_string(harmonics) + ": must lie in [1, 512]");
  if (samples <= 2 * harmonics) {
    fail("samples = " + std::to_string(samples) + ": must exceed 2N = " + std::to_string(2 * harmonics) +
         " (LL11: m much larger than N)");
  }
  if (max_powell_iterations < 1 || max_newton_iterations < 1) fail("iteration limits must be >= 1");
  if (!(stationarity_tolerance > 0.0)) fail("stationarity_tolerance must be > 0");
  if (phase_dof < -1 || phase_dof >= dofs) fail("phase_dof = " + std::to_string(phase_dof) + ": must be -1 or a DOF");
  powell.validate();
}

NonlinearModes::NonlinearModes(const MechanicalSystem& system, std::vector<RigidStop> stops, NonlinearModeOptions options)
    : system_(system), stops_(std::move(stops)), options_(options) {
  system_.validate();  // square, finite, symmetric: the eigensolver reads one triangle
  system_.mass.makeCompressed();
  n_ = system_.dofs();
  options_.validate(n_);
  if (stops_.empty()) throw std::invalid_argument("NonlinearModes: no rigid stop; a linear mode needs no solver");
  for (size_t i = 0; i < stops_.size(); ++i) {
    const auto& s = stops_[i];
    if (s.dof < 0 || s.dof >= n_) {
      throw std::invalid_argument("NonlinearModes: stop DOF " + std::to_string(s.dof) + " outside [0, " +
                                  std::to_string(n_) + ")");
    }
    if (!s.along.empty()) {
      validate_direction(s.along, s.dof, n_, std::string("NonlinearModes: stops[").append(std::to_string(i)).append("].along"));
    }
    if (!(s.gap > 0.0) || !std::isfinite(s.gap)) {
      throw std::invalid_argument("NonlinearModes: stop gap " + format_number(s.gap) + " m: must be > 0 (energies "
                                  "are normalized by contact onset; the normalized backbone does not depend on g0, "
                                  "so any small positive gap will do)");
    }
  }
  n_harm_ = options_.harmonics;
  f_ = 2 * n_harm_ + 1;
  k_ = Eigen::MatrixXd(system_.stiffness);
  m_ = Eigen::MatrixXd(system_.mass);
  weight_ = Eigen::VectorXd::Constant(f_, 0.5);
  weight_(0) = 1.0;
  nu_.resize(f_);
  for (int k = 0; k < f_; ++k) nu_(k) = (k + 1) / 2;
  theta_ = basis_values(options_.samples, 0);

  // Linear first mode and the onset scaling [LL11 Sec. 5.1: 1297.5 Hz for the rod].
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k_, m_);
  if (eig.info() != Eigen::Success) throw std::invalid_argument("NonlinearModes: K φ = M φ ω² failed (is M SPD?)");
  omega0_ = std::sqrt(eig.eigenvalues()(0));
  modal_projection_ = eig.eigenvectors().transpose() * m_;  // η = ΦᵀM y
  frequencies_ = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt() / (2.0 * std::numbers::pi);
  // Contact onset: the linear mode scaled so that the stop with the largest |e_cᵀφ|/g_c touches.
  const Eigen::VectorXd phi = eig.eigenvectors().col(0);
  double reach = 0.0, signed_reach = 0.0;
  for (size_t i = 0; i < stops_.size(); ++i) {
    double uc = 0.0;
    for (const auto& [j, w] : stops_[i].terms()) uc += w * phi(j);
    if (std::abs(uc) / stops_[i].gap > reach) {
      reach = std::abs(uc) / stops_[i].gap;
      signed_reach = uc / stops_[i].gap;
      onset_stop_ = static_cast<int>(i);
    }
  }
  double largest_gap = 0.0;
  for (const auto& s : stops_) largest_gap = std::max(largest_gap, s.gap);
  if (!(reach > 1e-12 * phi.cwiseAbs().maxCoeff() / largest_gap)) {
    throw std::invalid_argument("NonlinearModes: no stop moves in the first linear mode (e_cᵀφ₁ = 0 for every stop): "
                                "contact cannot start; check the stops' DOFs and directions");
  }
  const int c0 = stops_[static_cast<size_t>(onset_stop_)].dof;
  onset_ = phi / signed_reach;  // e_cᵀφ = +g_c at τ = 0 at the first stop to touch: contact onset
  // Unknowns in units of that stop's gap, so that Y/g_ref is O(1) near onset whatever the other
  // gaps (with the largest gap a far stop shrank the scaled state and the continuation jumped
  // branches).
  g_ref_ = stops_[static_cast<size_t>(onset_stop_)].gap;
  const Eigen::VectorXd on = onset_ / g_ref_;
  m_c_ = 0.5 * on.dot(m_ * on);  // m̂ of the onset mode (cos 2πτ, w = ½, ν = 1), normalized units
  phase_index_ = static_cast<int>(spectral::stacked_index(2, options_.phase_dof >= 0 ? options_.phase_dof : c0, n_));
  m_ref_ = 2.0 * m_c_;
  ks_ = system_.stiffness / (omega0_ * omega0_ * m_ref_);
  ms_ = system_.mass / m_ref_;
  ks_.makeCompressed();
  ms_.makeCompressed();
}

Eigen::VectorXd NonlinearModes::gaps(const Eigen::Ref<const Eigen::MatrixXd>& ym) const {
  const auto ms = static_cast<Eigen::Index>(options_.samples);
  Eigen::VectorXd g(static_cast<Eigen::Index>(stops_.size()) * ms);
  Eigen::RowVectorXd row(f_);
  for (size_t c = 0; c < stops_.size(); ++c) {
    row.setZero();
    for (const auto& [j, w] : stops_[c].terms()) row += w * ym.row(j);
    g.segment(static_cast<Eigen::Index>(c) * ms, ms) = (theta_ * row.transpose()).array() - stops_[c].gap / g_ref_;
  }
  return g;
}

void NonlinearModes::add_contact_forces(Eigen::MatrixXd& grad, const Eigen::VectorXd& lambda) const {
  const auto ms = static_cast<Eigen::Index>(options_.samples);
  for (size_t c = 0; c < stops_.size(); ++c) {
    const Eigen::RowVectorXd force = (theta_.transpose() * lambda.segment(static_cast<Eigen::Index>(c) * ms, ms)).transpose();
    for (const auto& [j, w] : stops_[c].terms()) grad.row(j) += w * force;
  }
}

std::vector<Eigen::Triplet<double>> NonlinearModes::contact_curvature(const Eigen::VectorXd& curvature) const {
  const auto ms = static_cast<Eigen::Index>(options_.samples);
  std::vector<Eigen::Triplet<double>> out;
  for (size_t c = 0; c < stops_.size(); ++c) {
    const Eigen::VectorXd cc = curvature.segment(static_cast<Eigen::Index>(c) * ms, ms);
    if (cc.isZero(0.0)) continue;
    const Eigen::MatrixXd block = theta_.transpose() * cc.asDiagonal() * theta_;  // F × F
    const auto terms = stops_[c].terms();
    for (const auto& [i, wi] : terms) {
      for (const auto& [j, wj] : terms) {
        for (int k = 0; k < f_; ++k) {
          for (int l = 0; l < f_; ++l) out.emplace_back(k * n_ + i, l * n_ + j, wi * wj * block(k, l));
        }
      }
    }
  }
  return out;
}

Eigen::MatrixXd NonlinearModes::modal_energy_shares(const ModeLevel& level) const {
  const Eigen::MatrixXd& y = level.coefficients;
  if (y.rows() != n_ || y.cols() != f_) {
    throw std::invalid_argument("NonlinearModes::modal_energy_shares: coefficients " + std::to_string(y.rows()) + " × " +
                                std::to_string(y.cols()) + ": need " + std::to_string(n_) + " × " + std::to_string(f_));
  }
  const Eigen::MatrixXd eta = modal_projection_ * y;  // modal coordinates, n × F
  Eigen::MatrixXd shares = Eigen::MatrixXd::Zero(n_, n_harm_ + 1);
  for (int k = 1; k < f_; ++k) shares.col((k + 1) / 2) += weight_(k) * nu_(k) * nu_(k) * eta.col(k).cwiseAbs2();
  const double total = shares.sum();
  if (!(total > 0.0) || !std::isfinite(total)) {
    throw std::invalid_argument("NonlinearModes::modal_energy_shares: the level carries no kinetic energy (m̂ = " +
                                format_number(total) + ")");
  }
  return shares / total;
}

ModalComponents NonlinearModes::modal_components(const ModeLevel& level) const {
  Eigen::MatrixXd s = modal_energy_shares(level);
  ModalComponents c;
  c.first_mode_share = s(0, 1);
  s(0, 1) = -1.0;  // excluded from the search
  Eigen::Index j = 0, h = 0;
  c.share = s.maxCoeff(&j, &h);
  c.mode = static_cast<int>(j) + 1;
  c.harmonic = static_cast<int>(h);
  return c;
}

double NonlinearModes::energy(const Eigen::MatrixXd& coefficients) const {
  if (coefficients.rows() != n_) {
    throw std::invalid_argument("NonlinearModes::energy: coefficients with " + std::to_string(coefficients.rows()) +
                                " rows: need " + std::to_string(n_) + " (one per DOF)");
  }
  double mh = 0.0;
  for (Eigen::Index k = 0; k < std::min<Eigen::Index>(coefficients.cols(), f_); ++k) {
    const Eigen::VectorXd yk = coefficients.col(k) / g_ref_;
    mh += weight_(k) * nu_(k) * nu_(k) * yk.dot(m_ * yk);
  }
  return mh / m_c_;
}

Eigen::VectorXd NonlinearModes::with_phase(const Eigen::VectorXd& x) const {
  Eigen::VectorXd full(x.size() + 1);
  full << x.head(phase_index_), 0.0, x.tail(x.size() - phase_index_);
  return full;
}

Eigen::MatrixXd NonlinearModes::basis_values(int samples, int derivative) const {
  // LL11 Eq. (21): harmonics 0 … N, each cosine with its sine (spectral's 2N + 1 form).
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(samples, 0.0, samples - 1.0) / samples;
  return spectral::FourierBasis::with_harmonics(n_harm_).values(tau, derivative);
}

Eigen::MatrixXd NonlinearModes::displacement(const ModeLevel& level, int samples) const {
  return level.coefficients * basis_values(samples, 0).transpose();
}

Eigen::MatrixXd NonlinearModes::velocity(const ModeLevel& level, int samples) const {
  return level.frequency_hz * (level.coefficients * basis_values(samples, 1).transpose());  // d/dt = f d/dτ
}

}  // namespace wbm::solvers
