#include <wbm/solvers/harmonic_balance.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

#include <wbm/spectral/fourier_basis.hpp>

namespace wbm::solvers {
namespace {

WeightedResidualOptions as_weighted_residual(const HarmonicBalanceOptions& o) {
  WeightedResidualOptions w;
  w.time_samples = o.time_samples;
  w.newton = o.newton;
  return w;
}

}  // namespace

HarmonicBalance::HarmonicBalance(MechanicalSystem system, HarmonicForcing forcing,
                                 std::vector<ContactPoint> contacts, HarmonicBalanceOptions options)
    : WeightedResidual(std::move(system), forcing, std::move(contacts), TimeBasis::fourier(options.dimension),
                       TimeBasis::fourier(options.dimension), as_weighted_residual(options)) {}

HarmonicBalanceSolution solve_harmonic_balance(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                               const std::vector<ContactPoint>& contacts,
                                               const HarmonicBalanceOptions& options) {
  return solve_weighted_residual(system, forcing, contacts, TimeBasis::fourier(options.dimension),
                                 TimeBasis::fourier(options.dimension), as_weighted_residual(options));
}

Eigen::VectorXd evaluate_dof(const Eigen::MatrixXd& coefficients, int dof, const Eigen::VectorXd& tau,
                             double frequency_hz, int derivative) {
  if (dof < 0 || dof >= coefficients.rows()) {
    throw std::invalid_argument("evaluate_dof: dof = " + std::to_string(dof) + " outside [0, " +
                                std::to_string(coefficients.rows()) + ")");
  }
  const spectral::FourierBasis basis(static_cast<int>(coefficients.cols()));
  const Eigen::MatrixXd v = basis.values(tau, derivative);
  return std::pow(frequency_hz, derivative) * (v * coefficients.row(dof).transpose());
}

}  // namespace wbm::solvers
