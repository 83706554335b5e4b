// Weighted-residual kernels for the six combinations of [JL14 Table 2] on Case 1
// (reproduce/scenes/jl14_case1.toml), distributional form, M = 16 … 256: assembly (time
// operators, modal factorization of G, condensation H = P G⁻¹ Pᵀ), one condensed residual +
// Jacobian, and a full solve (assembly + Newton + recovery). Goal (issue #4): every
// combination's Case 1 solve at M = 64 in < 20 ms on one core. The full solve with a rigid stop
// against the penalty law at M = 64 and 256 (issue #16), and the Delassus operator's formation at
// a new frequency (issue #39: Fourier:Fourier by its shift structure). The assembly on the assembled-G path
// (LinearSolverPath::SparseLU: one sparse LU of the n·M Kronecker sum, the path of non-Rayleigh
// damping), whose factorization is the SparseLu policy (KLU) since issue #41.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/haar_impact.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "shipped_scenes.hpp"

namespace {

const wbm::scene::Scene& case1() {
  static const auto scene = wbm::models::load_scene("jl14_case1");
  return scene;
}

// Table 2 order; the benchmark argument range(1) indexes it.
const std::vector<std::pair<std::string, std::string>> kPairs = {
    {"fourier", "fourier"}, {"bspline", "bspline"}, {"db6", "db6"},
    {"haar", "fourier"},    {"db6", "fourier"},     {"haar", "bspline"}};

wbm::solvers::WeightedResidual build(int m, int pair,
                                     wbm::solvers::LinearSolverPath path = wbm::solvers::LinearSolverPath::Automatic) {
  const auto& s = case1();
  const auto& p = kPairs[static_cast<size_t>(pair)];
  return {s.system(),
          s.harmonic_forcing(),
          s.contact_points(),
          wbm::solvers::TimeBasis::from_name(p.first, m),
          wbm::solvers::TimeBasis::from_name(p.second, m),
          {.linear_solver = path}};
}

void label(benchmark::State& state) {
  const auto& p = kPairs[static_cast<size_t>(state.range(1))];
  state.SetLabel(p.first + ":" + p.second);
}

void BM_WeightedResidual_Assembly(benchmark::State& state) {
  const int m = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(build(m, static_cast<int>(state.range(1))));
  label(state);
}

// Assembly with G factorized as one sparse LU of the assembled Kronecker sum instead of modal
// blocks: the factorization and the n_c·M solves of H = P G⁻¹ Pᵀ dominate.
// Counter: nonzeros per row of the time operators' joint pattern (A_M, A_C, A_K), which sets G's
// fill: about 2 for Fourier:Fourier, the support width for Galerkin wavelet pairs, M when dense.
void BM_WeightedResidual_AssemblySparseLu(benchmark::State& state) {
  const int m = static_cast<int>(state.range(0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(build(m, static_cast<int>(state.range(1)), wbm::solvers::LinearSolverPath::SparseLU));
  }
  const auto& ops = build(m, static_cast<int>(state.range(1))).time_operators();
  const auto joint = (ops.mass.array() != 0.0 || ops.damping.array() != 0.0 || ops.stiffness.array() != 0.0);
  state.counters["time_nnz_per_row"] = static_cast<double>(joint.count()) / m;
  label(state);
}

// The residual alone: the contact samples u_c(τ_q) and the projection of the sampled forces,
// by FFTW for Fourier trial/weighting functions (issue #14), by dense sample matrices otherwise.
void BM_WeightedResidual_Residual(benchmark::State& state) {
  const auto wr = build(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const Eigen::VectorXd x = wr.contact_unknowns(wr.linear_response());
  for (auto _ : state) benchmark::DoNotOptimize(wr.contact_residual(x));
  label(state);
}

void BM_WeightedResidual_ResidualAndJacobian(benchmark::State& state) {
  const auto wr = build(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const Eigen::VectorXd x = wr.contact_unknowns(wr.linear_response());
  for (auto _ : state) {
    benchmark::DoNotOptimize(wr.contact_residual(x));
    benchmark::DoNotOptimize(wr.contact_jacobian(x));
  }
  label(state);
}

void BM_WeightedResidual_FullSolve(benchmark::State& state) {
  const int m = static_cast<int>(state.range(0));
  int iterations = 0;
  auto status = wbm::solvers::SolveStatus::Converged;
  for (auto _ : state) {
    const auto wr = build(m, static_cast<int>(state.range(1)));
    const auto sol = wr.solve();
    iterations = sol.report.iterations;
    status = sol.report.status;
  }
  state.counters["newton_iterations"] = iterations;
  // 1 when the last solve converged.
  state.counters["converged"] = status == wbm::solvers::SolveStatus::Converged ? 1 : 0;
  label(state);
}

// The same full solve with the penalty replaced by a rigid stop at the same gap (Signorini
// conditions, issue #16): range(2) = 0 the exponential penalty of Case 1, 1 the rigid stop.
// Counters: Newton iterations and the solve's path (0 direct, 1 homotopy).
void BM_WeightedResidual_FullSolveRigidVsPenalty(benchmark::State& state) {
  const int m = static_cast<int>(state.range(0));
  const auto& s = case1();
  const auto& p = kPairs[static_cast<size_t>(state.range(1))];
  std::vector<wbm::solvers::ContactPoint> contacts = s.contact_points();
  const bool rigid = state.range(2) == 1;
  if (rigid) contacts.front().law = std::make_shared<wbm::contact::RigidStop>(contacts.front().law->gap());
  int iterations = 0;
  auto status = wbm::solvers::SolveStatus::Converged;
  double path = 0.0;
  for (auto _ : state) {
    const wbm::solvers::WeightedResidual wr(s.system(), s.harmonic_forcing(), contacts,
                                            wbm::solvers::TimeBasis::from_name(p.first, m),
                                            wbm::solvers::TimeBasis::from_name(p.second, m));
    const auto sol = wr.solve();
    iterations = sol.report.iterations;
    status = sol.report.status;
    path = sol.path == wbm::solvers::SolutionPath::DirectNewton ? 0.0 : 1.0;
  }
  state.counters["newton_iterations"] = iterations;
  // 1 when the last solve converged.
  state.counters["converged"] = status == wbm::solvers::SolveStatus::Converged ? 1 : 0;
  state.counters["fallback_path"] = path;
  state.SetLabel(p.first + ":" + p.second + (rigid ? ", rigid stop" : ", exponential penalty"));
}

// The Delassus operator D = V H W at a new frequency (WeightedResidual::at_frequency: G factorized
// again, H, then D and u_lin), rigid stop of Case 1: Fourier:Fourier forms D from its first block
// column (H commutes with time shifts, O(M²)), the wavelet pairs by the dense products (O(M³));
// issue #39 item 3. range(0) = M, range(1) the pair.
void BM_WeightedResidual_DelassusAtFrequency(benchmark::State& state) {
  const int m = static_cast<int>(state.range(0));
  const auto& s = case1();
  const auto& p = kPairs[static_cast<size_t>(state.range(1))];
  std::vector<wbm::solvers::ContactPoint> contacts = s.contact_points();
  contacts.front().law = std::make_shared<wbm::contact::RigidStop>(contacts.front().law->gap());
  const wbm::solvers::WeightedResidual wr(s.system(), s.harmonic_forcing(), contacts,
                                          wbm::solvers::TimeBasis::from_name(p.first, m),
                                          wbm::solvers::TimeBasis::from_name(p.second, m));
  const double f = 1.01 * s.harmonic_forcing().frequency_hz;
  for (auto _ : state) {
    const wbm::solvers::WeightedResidual at = wr.at_frequency(f);
    benchmark::DoNotOptimize(at.delassus().data());
  }
  state.SetLabel(p.first + ":" + p.second);
}

// The Haar weighted residual with Newton's impact law (haar_impact.hpp) on issue #16's point mass:
// 1 kg, 10 Hz, ζ = 0.05, forced at 8 Hz with k g0/F = ½ (plastic) — the transient's sweeps and the
// fixed point, O(M) per sweep. range(0) = M, range(1) = 10 e.
void BM_WeightedResidual_HaarImpactPointMass(benchmark::State& state) {
  const double k = std::pow(2.0 * std::numbers::pi * 10.0, 2);
  wbm::solvers::MechanicalSystem sys;
  sys.mass = Eigen::MatrixXd::Constant(1, 1, 1.0).sparseView();
  sys.damping = Eigen::MatrixXd::Constant(1, 1, 0.1 * std::sqrt(k)).sparseView();
  sys.stiffness = Eigen::MatrixXd::Constant(1, 1, k).sparseView();
  const std::vector<wbm::solvers::ContactPoint> stop{{0, std::make_shared<wbm::contact::RigidStop>(5.0 / k)}};
  wbm::solvers::HaarImpactOptions o;
  o.cells = static_cast<int>(state.range(0));
  o.restitution = 0.1 * static_cast<double>(state.range(1));
  int converged = 0;
  for (auto _ : state) {
    const auto s = wbm::solvers::solve_haar_impact(sys, {0, 10.0, 8.0}, stop, o);
    converged = s.converged() ? 1 : 0;
    benchmark::DoNotOptimize(s.displacement.data());
  }
  state.counters["converged"] = converged;
  state.SetComplexityN(state.range(0));
}

void delassus_arguments(benchmark::internal::Benchmark* b) {
  for (int pair : {0, 1, 2}) {
    for (int m : {64, 256, 1024}) {
      if (pair == 0 || m <= 256) b->Args({m, pair});
    }
  }
  b->Unit(benchmark::kMillisecond);
}

void rigid_arguments(benchmark::internal::Benchmark* b) {
  for (int pair = 0; pair < 6; ++pair) {
    for (int m : {64, 256}) {
      for (int rigid : {0, 1}) b->Args({m, pair, rigid});
    }
  }
  b->Unit(benchmark::kMillisecond);
}

void sparse_lu_arguments(benchmark::internal::Benchmark* b) {
  for (int pair = 0; pair < 6; ++pair) {
    for (int m : {16, 64, 256}) b->Args({m, pair});
  }
  b->Unit(benchmark::kMillisecond);
}

void arguments(benchmark::internal::Benchmark* b) {
  for (int pair = 0; pair < 6; ++pair) {
    for (int m : {16, 32, 64, 128, 256}) b->Args({m, pair});
  }
  b->Args({1024, 0});  // Fourier:Fourier only: the Petrov-Galerkin set-up is O(M^3) (issue #17)
  b->Unit(benchmark::kMillisecond);
}

}  // namespace

BENCHMARK(BM_WeightedResidual_Assembly)->Apply(arguments);
BENCHMARK(BM_WeightedResidual_AssemblySparseLu)->Apply(sparse_lu_arguments);
BENCHMARK(BM_WeightedResidual_Residual)->Apply(arguments);
BENCHMARK(BM_WeightedResidual_ResidualAndJacobian)->Apply(arguments);
BENCHMARK(BM_WeightedResidual_FullSolve)->Apply(arguments);
BENCHMARK(BM_WeightedResidual_FullSolveRigidVsPenalty)->Apply(rigid_arguments);
BENCHMARK(BM_WeightedResidual_DelassusAtFrequency)->Apply(delassus_arguments);
BENCHMARK(BM_WeightedResidual_HaarImpactPointMass)
    ->ArgsProduct({{64, 256, 1024, 4096}, {0, 5}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
