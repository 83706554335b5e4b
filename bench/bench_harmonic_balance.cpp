// Harmonic balance kernels on Case 1 of [JL14 Table 1] (scene reproduce/scenes/jl14_case1.toml):
// set-up (Kronecker assembly, sparse LU, condensation H = P G⁻¹ Pᵀ), one condensed residual +
// Jacobian evaluation, and a full solve (set-up + Newton), for M = 16 … 256. Also the BDF
// reference of Case 1. Goal (foundation issue): a full Case 1 solve at M = 64 in < 5 ms.
#include <benchmark/benchmark.h>

#include <wbm/solvers/harmonic_balance.hpp>
#include <wbm/solvers/time_integration.hpp>

#include "shipped_scenes.hpp"

namespace {
const wbm::scene::Scene& case1() {
  static const auto scene = wbm::models::load_scene("jl14_case1");
  return scene;
}
const wbm::scene::Scene& case2() {
  static const auto scene = wbm::models::load_scene("jl14_case2");
  return scene;
}

void BM_HarmonicBalance_Setup(benchmark::State& state) {
  const auto& s = case1();
  const int m = static_cast<int>(state.range(0));
  for (auto _ : state) {
    wbm::solvers::HarmonicBalance hb(s.system(), s.harmonic_forcing(), s.contact_points(), {.dimension = m});
    benchmark::DoNotOptimize(hb);
  }
  state.SetComplexityN(m);
}

void BM_HarmonicBalance_ResidualAndJacobian(benchmark::State& state) {
  const auto& s = case1();
  const int m = static_cast<int>(state.range(0));
  const wbm::solvers::HarmonicBalance hb(s.system(), s.harmonic_forcing(), s.contact_points(), {.dimension = m});
  const Eigen::VectorXd x = hb.contact_unknowns(hb.linear_response());
  for (auto _ : state) {
    benchmark::DoNotOptimize(hb.contact_residual(x));
    benchmark::DoNotOptimize(hb.contact_jacobian(x));
  }
  state.SetComplexityN(m);
}

template <const wbm::scene::Scene& (*Scene)()>
void BM_HarmonicBalance_FullSolve(benchmark::State& state) {
  const auto& s = Scene();
  const int m = static_cast<int>(state.range(0));
  int iterations = 0;
  for (auto _ : state) {
    const auto sol = wbm::solvers::solve_harmonic_balance(s.system(), s.harmonic_forcing(), s.contact_points(), {.dimension = m});
    if (!sol.converged()) state.SkipWithError(sol.report.message.c_str());
    iterations = sol.report.iterations;
  }
  state.counters["newton_iterations"] = iterations;
  state.SetComplexityN(m);
}

void BM_TimeIntegration_Case1(benchmark::State& state) {
  const auto& s = case1();
  for (auto _ : state) {
    const auto ref = wbm::solvers::integrate_to_periodic(s.system(), s.harmonic_forcing(), s.contact_points(),
                                                         {.samples_per_period = static_cast<int>(state.range(0))});
    state.counters["periods"] = ref.report.periods;
    state.counters["steps"] = static_cast<double>(ref.report.steps);
  }
}
}  // namespace

BENCHMARK(BM_HarmonicBalance_Setup)->RangeMultiplier(2)->Range(16, 256)->Unit(benchmark::kMillisecond)->Complexity();
BENCHMARK(BM_HarmonicBalance_ResidualAndJacobian)->RangeMultiplier(2)->Range(16, 256)->Unit(benchmark::kMillisecond)->Complexity();
BENCHMARK(BM_HarmonicBalance_FullSolve<case1>)->Name("BM_HarmonicBalance_FullSolve_Case1")->RangeMultiplier(2)->Range(16, 256)->Unit(benchmark::kMillisecond)->Complexity();
BENCHMARK(BM_HarmonicBalance_FullSolve<case2>)->Name("BM_HarmonicBalance_FullSolve_Case2")->RangeMultiplier(2)->Range(16, 256)->Unit(benchmark::kMillisecond)->Complexity();
BENCHMARK(BM_TimeIntegration_Case1)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond)->Iterations(3);

BENCHMARK_MAIN();
