// Solves Case 1 of [JL14 Table 1] from C++ with the installed modules: the clamped-free rod
// (fem), the exponential penalty stop (contact) and harmonic balance with M = 64 (solvers; the
// same as `wbm run reproduce/scenes/jl14_case1.toml`, which reads these numbers from the scene).
#include <cstdio>
#include <memory>

#include <wbm/contact/penalty.hpp>
#include <wbm/fem/rod.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/weighted_residual.hpp>

int main() {
  // E [Pa], ρ [kg/m³], S [m²], L [m], elements [JL14 Sec. 4]
  const wbm::fem::Rod rod({.young_modulus = 70e9, .density = 2700.0, .area = 25e-4, .length = 1.0, .elements = 25});
  const auto system = wbm::solvers::beta_damped(rod, 1e-4);  // C = βK, β = 1e-4 s [JL14 Table 1]
  const wbm::solvers::HarmonicForcing forcing{rod.tip_dof(), 250e3, 150.0};  // F = 250 kN at 150 Hz
  // a_c = 1e8 N, α = 50 1/m, g0 = 1 mm [JL14 Table 1, Case 1]
  const auto stop = std::make_shared<wbm::contact::ExponentialPenalty>(
      wbm::contact::ExponentialPenaltyParameters{.coefficient = 1e8, .exponent = 50.0, .gap = 1e-3});
  const auto fourier = wbm::solvers::TimeBasis::fourier(64);
  const auto solution = wbm::solvers::solve_weighted_residual(system, forcing, {{rod.tip_dof(), stop}}, fourier,
                                                              fourier);
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(1024, 0.0, 1.0 - 1.0 / 1024);
  const Eigen::VectorXd tip =
      wbm::solvers::evaluate_trial(fourier, solution.coefficients, rod.tip_dof(), tau, forcing.frequency_hz);
  std::printf("Case 1, Fourier:Fourier M = 64: %s, %d Newton iterations, relative residual %.2e\n",
              solution.report.converged() ? "converged" : "NOT converged", solution.report.iterations,
              solution.relative_residual);
  std::printf("max tip displacement %.6e m (gap 1e-3 m), max contact force %.6e N\n", tip.maxCoeff(),
              solution.max_contact_force);
  return solution.report.converged() ? 0 : 1;
}
