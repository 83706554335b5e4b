#include "blade_forced.hpp"

#include <cmath>
#include <numbers>

#include <Eigen/Cholesky>

namespace wbm::models {

BladeForcedModel blade_forced_model(const Blade& blade, const fem::CraigBamptonModel& cb,
                                    const BladeForcedInputs& in) {
  BladeForcedModel m;
  const Eigen::MatrixXd k_r = 0.5 * (cb.stiffness + cb.stiffness.transpose()), m_r = 0.5 * (cb.mass + cb.mass.transpose());
  const Eigen::VectorXd d = m_r.diagonal().cwiseSqrt().cwiseInverse();
  m.scale = d;
  auto& reduced = m.reduced;
  reduced.stiffness = (d.asDiagonal() * k_r * d.asDiagonal()).sparseView();
  reduced.mass = (d.asDiagonal() * m_r * d.asDiagonal()).sparseView();
  const auto n = static_cast<Eigen::Index>(reduced.mass.rows());
  m.stops = radial_stops(blade, in.gap);
  for (auto& st : m.stops) {
    for (auto& [j, w] : st.along) w *= d(j);
  }

  // First mode, onset node, damping, load.
  m.modes = std::make_unique<solvers::NonlinearModes>(
      [&] { auto s = reduced; s.damping.resize(n, n); return s; }(), m.stops,
      solvers::NonlinearModeOptions{.harmonics = in.mode_harmonics, .samples = in.mode_samples});
  m.f1 = m.modes->linear_frequency_hz();
  m.omega1 = 2.0 * std::numbers::pi * m.f1;
  m.onset = m.modes->onset_stop();
  m.observed = 3 * m.onset + 1;  // y DOF of the onset node (circumferential)
  m.unit = d(m.observed) / in.gap;  // scaled coordinate → gaps
  const Eigen::MatrixXd m_dense = Eigen::MatrixXd(reduced.mass), k_dense = Eigen::MatrixXd(reduced.stiffness);  // scaled
  Eigen::VectorXd phi = m.modes->onset_mode();
  phi /= std::sqrt(phi.dot(m_dense * phi));  // φ₁ᵀ M φ₁ = 1
  const auto& onset_stop = m.stops[static_cast<size_t>(m.onset)];
  double phi_c = 0.0;  // e_cᵀ φ₁ at the onset stop
  for (const auto& [j, w] : onset_stop.terms()) phi_c += w * phi(j);
  m.beta = 2.0 * in.zeta / m.omega1;
  reduced.damping = (m.beta * k_dense).sparseView();
  // Linear resonance of the first mode: η = s / (2 ζ ω₁²); radial peak η |φ_c| = overload · g0.
  m.load_scale = in.overload * in.gap * 2.0 * in.zeta * m.omega1 * m.omega1 / std::abs(phi_c);
  m.load = m.load_scale * (m_dense * phi);
  Eigen::Index lead = 0;
  m.load.cwiseAbs().maxCoeff(&lead);
  m.forcing = solvers::HarmonicForcing{static_cast<int>(lead), m.load(lead), in.from_f1 * m.f1, {}};
  for (Eigen::Index j = 0; j < n; ++j) {
    if (j != lead && m.load(j) != 0.0) m.forcing.more.push_back({static_cast<int>(j), m.load(j)});
  }
  // Penalty stiffness: `stiffness_ratio` × the static radial stiffness 1/(e_cᵀ K_r⁻¹ e_c) at the onset node.
  Eigen::VectorXd e_c = Eigen::VectorXd::Zero(n);
  for (const auto& [j, w] : onset_stop.terms()) e_c(j) = w;
  m.radial_stiffness = 1.0 / e_c.dot(k_dense.ldlt().solve(e_c));
  m.penalty_stiffness = in.stiffness_ratio * m.radial_stiffness;
  return m;
}

}  // namespace wbm::models
