// The cost of friction (issue #36): the 1-DOF damper of examples/scenes/friction_damper.toml
// (1 kg, f_n = 10 Hz, ζ = 0.5 %, 1 N; a Jenkins element k_t = 1000 k, μN = 0.2 N) against the same
// oscillator with a frictionless linear penalty stop of the same stiffness at 0.3 mm (it touches
// over part of each cycle at 8 Hz; cell-average quadrature, the scenes' rule for that law; the
// Jenkins element takes midpoints), per pair at Q = 1024 samples: one solve at 8 Hz (counter:
// Newton iterations), and the continuation from 5 to 20 Hz without stability (counters: points,
// points per second; at most 20 000 points). The Jenkins law evaluates the whole period per
// residual (the return map, two periods) and its Jacobian is dense in the condensed unknowns;
// the stop's is diagonal in the samples and goes through Woodbury.
#include <cmath>
#include <memory>
#include <numbers>
#include <string>

#include <benchmark/benchmark.h>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/weighted_residual.hpp>

namespace {

constexpr double kPi = std::numbers::pi;
const double kStiffness = std::pow(2.0 * kPi * 10.0, 2);  // k [N/m], m = 1 kg

wbm::solvers::MechanicalSystem damper() {
  wbm::solvers::MechanicalSystem s;
  s.mass.resize(1, 1);
  s.mass.insert(0, 0) = 1.0;
  s.stiffness.resize(1, 1);
  s.stiffness.insert(0, 0) = kStiffness;
  s.damping.resize(1, 1);
  s.damping.insert(0, 0) = 2.0 * 0.005 * 2.0 * kPi * 10.0;
  return s;
}

std::shared_ptr<const wbm::contact::ContactLaw> law(bool friction) {
  if (friction) return std::make_shared<wbm::contact::JenkinsLaw>(wbm::contact::JenkinsParameters{1e3 * kStiffness, 0.2, 1.0});
  return std::make_shared<wbm::contact::LinearPenalty>(wbm::contact::LinearPenaltyParameters{1e3 * kStiffness, 3e-4});
}

const char* const kPairs[] = {"fourier", "db6", "bspline"};

wbm::solvers::TimeBasis basis(int pair) {
  return pair == 0 ? wbm::solvers::TimeBasis::fourier_harmonics(32) : wbm::solvers::TimeBasis::from_name(kPairs[pair], 64);
}

wbm::solvers::WeightedResidualOptions options(bool friction) {
  return {.time_samples = 1024,
          .contact_quadrature = friction ? wbm::solvers::ContactQuadrature::Midpoint : wbm::solvers::ContactQuadrature::CellAverage};
}

void label(benchmark::State& state, int pair, bool friction) {
  state.SetLabel(std::string(kPairs[pair]) + ":" + kPairs[pair] + (friction ? ", Jenkins" : ", frictionless stop"));
}

void BM_Friction_Solve(benchmark::State& state) {
  const int pair = static_cast<int>(state.range(0));
  const bool friction = state.range(1) != 0;
  label(state, pair, friction);
  const wbm::solvers::WeightedResidual w(damper(), {0, 1.0, 8.0}, {{0, law(friction)}}, basis(pair), basis(pair),
                                         options(friction));
  int iterations = 0;
  for (auto _ : state) {
    const auto s = w.solve();
    if (!s.converged()) state.SkipWithError(s.brief().c_str());
    iterations = s.report.iterations;
  }
  state.counters["newton_iterations"] = iterations;
}

void BM_Friction_Continuation(benchmark::State& state) {
  const int pair = static_cast<int>(state.range(0));
  const bool friction = state.range(1) != 0;
  label(state, pair, friction);
  const wbm::solvers::WeightedResidual base(damper(), {0, 1.0, 5.0}, {{0, law(friction)}}, basis(pair), basis(pair),
                                            options(friction));
  wbm::solvers::ResponseCurveOptions o;
  o.parameter_min = 5.0;
  o.parameter_max = 20.0;
  o.stability = false;
  o.max_points = 20000;
  size_t points = 0;
  double wall = 0.0;
  for (auto _ : state) {
    const auto curve = wbm::solvers::trace_response(base, o);
    if (curve.stop != wbm::solvers::StopReason::RangeReached) state.SkipWithError(curve.message.c_str());
    points = curve.points.size();
    wall = curve.wall_time_s;
  }
  state.counters["points"] = static_cast<double>(points);
  state.counters["points_per_s"] = static_cast<double>(points) / wall;
}

}  // namespace

BENCHMARK(BM_Friction_Solve)->ArgsProduct({{0, 1, 2}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Friction_Continuation)->ArgsProduct({{0, 1, 2}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
