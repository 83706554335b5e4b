// The cost of friction (issue #36): the 1-DOF damper of examples/scenes/friction_damper.toml
// (1 kg, f_n = 10 Hz, ζ = 0.5 %, 1 N; a Jenkins element k_t = 1000 k, μN = 0.2 N, or exact Coulomb
// friction of the same μN) against the same oscillator with a frictionless linear penalty stop of
// the Jenkins stiffness at 0.3 mm (it touches over part of each cycle at 8 Hz; cell-average
// quadrature, the scenes' rule for that law; the Jenkins element takes midpoints), per pair at
// Q = 1024 samples: one solve at 8 Hz (counter: Newton iterations), and the continuation from 5
// to 20 Hz without stability (counters: points, points per second; at most 20 000 points). The
// Jenkins law evaluates the whole period per residual (the return map, two periods) and its
// Jacobian is dense in the condensed unknowns; the stop's is diagonal in the samples and goes
// through Woodbury; exact Coulomb friction forms the Delassus operator (M × M) once per
// frequency, then solves with the stick rows only.
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/jenkins_disc.hpp>
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

// 0: the frictionless stop, 1: the Jenkins element, 2: exact Coulomb friction.
std::shared_ptr<const wbm::contact::ContactLaw> law(int kind) {
  if (kind == 1) return std::make_shared<wbm::contact::JenkinsLaw>(wbm::contact::JenkinsParameters{1e3 * kStiffness, 0.2, 1.0});
  if (kind == 2) return std::make_shared<wbm::contact::CoulombFriction>(wbm::contact::CoulombParameters{0.2, 1.0});
  return std::make_shared<wbm::contact::LinearPenalty>(wbm::contact::LinearPenaltyParameters{1e3 * kStiffness, 3e-4});
}
const char* const kLaws[] = {"frictionless stop", "Jenkins", "exact Coulomb"};

const char* const kPairs[] = {"fourier", "db6", "bspline"};

wbm::solvers::TimeBasis basis(int pair) {
  return pair == 0 ? wbm::solvers::TimeBasis::fourier_harmonics(32) : wbm::solvers::TimeBasis::from_name(kPairs[pair], 64);
}

wbm::solvers::WeightedResidualOptions options(int kind) {
  return {.time_samples = 1024,
          .contact_quadrature = kind != 0 ? wbm::solvers::ContactQuadrature::Midpoint : wbm::solvers::ContactQuadrature::CellAverage};
}

void label(benchmark::State& state, int pair, int kind) {
  state.SetLabel(std::string(kPairs[pair]) + ":" + kPairs[pair] + ", " + kLaws[kind]);
}

void BM_Friction_Solve(benchmark::State& state) {
  const int pair = static_cast<int>(state.range(0));
  const auto kind = static_cast<int>(state.range(1));
  label(state, pair, kind);
  const wbm::solvers::WeightedResidual w(damper(), {0, 1.0, 8.0}, {{0, law(kind)}}, basis(pair), basis(pair), options(kind));
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
  const auto kind = static_cast<int>(state.range(1));
  label(state, pair, kind);
  const wbm::solvers::WeightedResidual base(damper(), {0, 1.0, 5.0}, {{0, law(kind)}}, basis(pair), basis(pair),
                                            options(kind));
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

// Two tangents: a point mass on x, y (the damper's k, 2 % damping) under a rotating 2 N force at
// 9 Hz, with one Jenkins element on both tangents (an isotropic disc, k_t = 2k, μN = 0.3 N; kind 1)
// or with one element per tangent (kind 0, the same k_t and μN each: a square instead of a disc),
// Fourier H = 8, one solve per Q = range(1): the disc's sample Jacobian is dense (O(Q²) to form,
// and its blocks O(Q² M)) where the elements along one tangent are sparse.
void BM_FrictionDisc_Solve(benchmark::State& state) {
  const bool disc = state.range(0) == 1;
  const auto q = static_cast<int>(state.range(1));
  state.SetLabel(std::string(disc ? "one element on two tangents" : "one element per tangent") + ", Q = " +
                 std::to_string(q));
  wbm::solvers::MechanicalSystem s;
  s.mass.resize(2, 2);
  s.stiffness.resize(2, 2);
  s.damping.resize(2, 2);
  for (int i = 0; i < 2; ++i) {
    s.mass.insert(i, i) = 1.0;
    s.stiffness.insert(i, i) = kStiffness;
    s.damping.insert(i, i) = 2.0 * 0.02 * 2.0 * kPi * 10.0;
  }
  const wbm::contact::JenkinsParameters p{2.0 * kStiffness, 0.3, 1.0};
  std::vector<wbm::solvers::ContactPoint> contacts;
  if (disc) {
    const auto shared = std::make_shared<wbm::contact::JenkinsDiscLaw>(p);
    contacts = {{0, shared}, {1, shared}};
    contacts[0].second_tangent = 1;
    contacts[1].second_tangent = 0;
  } else {
    contacts = {{0, std::make_shared<wbm::contact::JenkinsLaw>(p)}, {1, std::make_shared<wbm::contact::JenkinsLaw>(p)}};
  }
  const auto fourier = wbm::solvers::TimeBasis::fourier_harmonics(8);
  const wbm::solvers::WeightedResidual w(s, {0, 2.0, 9.0, {{1, 2.0, -kPi / 2.0}}}, contacts, fourier, fourier,
                                         {.time_samples = q});
  int iterations = 0;
  for (auto _ : state) {
    const auto solution = w.solve();
    if (!solution.converged()) state.SkipWithError(solution.brief().c_str());
    iterations = solution.report.iterations;
  }
  state.counters["newton_iterations"] = iterations;
}

}  // namespace

BENCHMARK(BM_FrictionDisc_Solve)->ArgsProduct({{0, 1}, {256, 1024}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Friction_Solve)->ArgsProduct({{0, 1, 2}, {0, 1, 2}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Friction_Continuation)->ArgsProduct({{0, 1, 2}, {0, 1, 2}})->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
