#pragma once
/// Harmonic balance: the Fourier:Fourier case of the weighted-residual method, with alternating
/// frequency/time evaluation of the contact forces [JL14 Eqs. (14), (17), Sec. 3.1; CG89].
/// All three formulations coincide for Fourier:Fourier [JL14 Sec. 3.1]; operators are exact.

#include <Eigen/Core>

#include <wbm/solvers/weighted_residual.hpp>

namespace wbm::solvers {

struct HarmonicBalanceOptions {
  int dimension = 64;    // M = 2^J ≥ 2 Fourier functions per DOF (M/2 harmonics)
  int time_samples = 0;  // Q ≥ M AFT samples; 0 selects max(256, 2M) (256 as in [JL14 Sec. 4.1])
  NewtonOptions newton{};
};

using HarmonicBalanceSolution = WeightedResidualSolution;

/// WeightedResidual with trial = weighting = TimeBasis::fourier(M) (see weighted_residual.hpp
/// for the residual, the condensation on the contact unknowns and the errors thrown).
class HarmonicBalance : public WeightedResidual {
 public:
  HarmonicBalance(MechanicalSystem system, HarmonicForcing forcing, std::vector<ContactPoint> contacts,
                  HarmonicBalanceOptions options);
};

/// Convenience: build and solve in one call.
[[nodiscard]] HarmonicBalanceSolution solve_harmonic_balance(const MechanicalSystem& system,
                                                             const HarmonicForcing& forcing,
                                                             const std::vector<ContactPoint>& contacts,
                                                             const HarmonicBalanceOptions& options);

/// u_i(τ_p) (or its d-th time derivative in physical time, [m/s^d]) of DOF i at the given
/// normalized times from an n × M Fourier coefficient matrix [JL14 Eqs. (11), (34)].
/// Throws std::invalid_argument for a DOF outside [0, n).
[[nodiscard]] Eigen::VectorXd evaluate_dof(const Eigen::MatrixXd& coefficients, int dof,
                                           const Eigen::VectorXd& tau, double frequency_hz,
                                           int derivative = 0);

}  // namespace wbm::solvers
