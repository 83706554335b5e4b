// Floquet multipliers with Jenkins elements (floquet.hpp, "Jenkins elements": the state carries
// each element's force perturbation φ). Truths not produced by this code:
//  - full stick: the element is a spring k_t in parallel with k, so the monodromy matrix is e^{AT}
//    of that linear oscillator, whose eigenvalues are e^{λT} with λ its characteristic roots;
//  - permanent slip against a sliding counter-surface, the slip force μ times a normal penalty's
//    force: a linear system whose tangential force follows the normal displacement, the
//    mode-coupling instability of friction-induced oscillations in the form of the minimal model of
//    [Hoffmann, Fischer, Allgaier & Gaul 2002, Mech. Res. Commun. 29, 197–205]: e^{λT} of its 4
//    eigenvalues, stable below the flutter threshold and unstable above it;
//  - stick–slip: the finite-difference monodromy of an independent explicit time stepping with
//    the element's return map, written here (velocity Verlet, 2^16 steps per period);
//  - incremental passivity: under a constant normal load, a viscously damped oscillator with a
//    Jenkins element dissipates the energy of the difference of two motions, so no forced orbit is
//    unstable (a normal load that varies can break it: the mode-coupling case above).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <numbers>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/time_basis.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "impact_oscillators.hpp"

namespace wbm::solvers {
namespace {

constexpr double kJenkinsPi = std::numbers::pi;
const double kOscillatorStiffness = std::pow(2.0 * kJenkinsPi * 10.0, 2);  // 1 kg at f_n = 10 Hz

std::shared_ptr<const contact::JenkinsLaw> jenkins(double kt, double mu, double normal_load) {
  return std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{kt, mu, normal_load});
}

// The largest distance from each expected multiplier to the nearest computed one, relative to 1.
double distance_to(const Eigen::VectorXcd& computed, const std::vector<std::complex<double>>& expected) {
  double worst = 0.0;
  for (const auto& e : expected) worst = std::max(worst, (computed.array() - e).abs().minCoeff());
  return worst;
}

// e^{λT} of the eigenvalues λ of [[0, I], [−M⁻¹K, −M⁻¹C]] (K may be non-symmetric).
std::vector<std::complex<double>> linear_multipliers(const Eigen::MatrixXd& m, const Eigen::MatrixXd& c,
                                                     const Eigen::MatrixXd& k, double period) {
  const Eigen::Index n = m.rows();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  a.topRightCorner(n, n).setIdentity();
  a.bottomLeftCorner(n, n) = -m.inverse() * k;
  a.bottomRightCorner(n, n) = -m.inverse() * c;
  const Eigen::VectorXcd lambda = Eigen::EigenSolver<Eigen::MatrixXd>(a).eigenvalues();
  std::vector<std::complex<double>> out;
  for (Eigen::Index i = 0; i < lambda.size(); ++i) out.push_back(std::exp(lambda(i) * period));
  return out;
}

TEST(FloquetJenkins, FullStickIsTheOscillatorWithTheTangentialSpring) {
  // 1 kg, k at 10 Hz, ζ = 2 %, k_t = 2k, slip force 1 kN far above the 1 N load at 12 Hz: the
  // orbit u = Re(X e^{iωt}), X = P/(k + k_t − ω² + icω), never slips.
  const double k = kOscillatorStiffness, kt = 2.0 * k, c = 2.0 * 0.02 * std::sqrt(k), f = 12.0;
  const MechanicalSystem s = wbm::testing::one_dof_system(1.0, c, k);
  const std::vector<ContactPoint> contacts = {{0, jenkins(kt, 1.0, 1e3)}};
  const double w = 2.0 * kJenkinsPi * f;
  const std::complex<double> x = 1.0 / std::complex<double>(k + kt - w * w, c * w);
  const Eigen::Matrix<double, 1, 1> mass{{1.0}}, damping{{c}}, total{{k + kt}};
  const auto expected = linear_multipliers(mass, damping, total, 1.0 / f);
  double error_coarse = 0.0;
  for (const int p : {1024, 2048}) {
    Eigen::MatrixXd uc(1, p);
    for (int q = 0; q < p; ++q) uc(0, q) = std::real(x * std::exp(std::complex<double>(0.0, 2.0 * kJenkinsPi * q / p)));
    const FloquetResult fl = floquet_multipliers(s, contacts, uc, f);
    ASSERT_EQ(fl.multipliers.size(), 3);  // (δu, δu̇, φ)
    EXPECT_EQ(fl.monodromy.rows(), 3);
    EXPECT_EQ(std::abs(fl.multipliers(2)), 0.0);  // the element's φ row: a spring, no state
    const double error = distance_to(fl.multipliers, expected);
    EXPECT_LT(error, 1e-4) << "P = " << p;
    // The modal path (C = c M, classical) gives the same multipliers.
    const FloquetResult modal = FloquetAnalysis(s, contacts)(uc, f);
    EXPECT_LT(distance_to(modal.multipliers, expected), 1e-4);
    if (p == 1024) error_coarse = error;
    if (p == 2048) {
      EXPECT_GT(error_coarse / error, 3.0) << "second order: " << error_coarse << " → " << error;
    }
  }
}

// The Hoffmann model: a point (normal x = DOF 0, tangential y = DOF 1) held by springs with a
// coupling k_xy, pressed on a belt by a preloaded normal penalty k_n, rubbing it through a Jenkins
// element whose slip force is μ times the normal force; the belt slides by 0.1 m per period, so
// the element slips in one direction (σ = −1) at every sample and the normal contact never opens.
// Linearized, the tangential force is σ μ k_n δx: the stiffness K + [[k_n, 0], [σ μ k_n, 0]],
// non-symmetric, whose two modes merge into a flutter pair above μ ≈ 0.59 (undamped).
struct Hoffmann {
  double k1 = std::pow(2.0 * kJenkinsPi * 10.0, 2), k2 = std::pow(2.0 * kJenkinsPi * 11.0, 2), k12 = 500.0;
  double kn = 2000.0, c = 2.0 * 0.01 * 2.0 * kJenkinsPi * 10.0, kt = 1e5;
  [[nodiscard]] MechanicalSystem system() const {
    MechanicalSystem s;
    s.mass = Eigen::MatrixXd::Identity(2, 2).sparseView();
    s.stiffness = (Eigen::MatrixXd(2, 2) << k1, k12, k12, k2).finished().sparseView();
    s.damping = (c * Eigen::MatrixXd::Identity(2, 2)).sparseView();
    return s;
  }
  [[nodiscard]] std::vector<ContactPoint> contacts(double mu) const {
    ContactPoint normal{0, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{kn, -0.01})};
    ContactPoint tangent{1, jenkins(kt, mu, 0.0)};
    tangent.normal = 0;
    tangent.obstacle.drift = 0.1;
    return {normal, tangent};
  }
};

TEST(FloquetJenkins, PermanentSlipUnderANormalPenaltyIsTheModeCouplingModel) {
  const Hoffmann h;
  const double f = 5.0;
  const int p = 4096;
  // Any orbit in permanent slip with the normal contact closed has the same linearization: small
  // circles, the tangential samples relative to the belt (u − d τ).
  Eigen::MatrixXd uc(2, p);
  for (int q = 0; q < p; ++q) {
    const double tau = static_cast<double>(q) / p;
    uc(0, q) = 1e-3 * std::cos(2.0 * kJenkinsPi * tau);
    uc(1, q) = 1e-3 * std::sin(2.0 * kJenkinsPi * tau) - 0.1 * tau;
  }
  for (const double mu : {0.3, 0.9}) {
    const Eigen::Matrix2d coupled = (Eigen::Matrix2d() << h.k1 + h.kn, h.k12, h.k12 - mu * h.kn, h.k2).finished();
    const auto expected = linear_multipliers(Eigen::Matrix2d::Identity(), h.c * Eigen::Matrix2d::Identity(), coupled,
                                             1.0 / f);
    const double largest = std::abs(*std::max_element(expected.begin(), expected.end(), [](auto a, auto b) {
      return std::abs(a) < std::abs(b);
    }));
    for (const bool modal : {false, true}) {
      const FloquetResult fl = modal ? FloquetAnalysis(h.system(), h.contacts(mu))(uc, f)
                                     : floquet_multipliers(h.system(), h.contacts(mu), uc, f);
      ASSERT_EQ(fl.multipliers.size(), 5);  // (δx, δy, δẋ, δẏ, φ)
      // The slip forgets φ: 0 but for the O(h) of φ(0) that the first half kick carries.
      EXPECT_LT(std::abs(fl.multipliers(4)), 1e-9);
      EXPECT_LT(distance_to(fl.multipliers, expected), 1e-4 * largest) << "μ = " << mu;
      EXPECT_EQ(fl.stable(), largest < 1.0) << "μ = " << mu << ": |μ|max " << fl.max_modulus << " against " << largest;
    }
    // The closed form's verdicts: stable below the threshold, flutter above it.
    EXPECT_EQ(largest < 1.0, mu < 0.5) << "μ = " << mu << ": |e^{λT}|max " << largest;
  }
}

// m ü + c u̇ + k u + f = P cos ωt with a Jenkins element of stiffness k_t and slip force F_s, by
// velocity Verlet (damping by the trapezoidal rule) and one step of the return map per step:
// the state (u, u̇, f) after `periods` periods of N steps from x0, and the samples of u at P
// instants of the last period.
struct SteppedOscillator {
  double m = 1.0, k = kOscillatorStiffness, c = 2.0 * 0.05 * 2.0 * kJenkinsPi * 10.0;
  double kt = 0.25 * kOscillatorStiffness, slip = 1.0, load = 2.0, f = 10.0;
  int steps = 65536;
  [[nodiscard]] Eigen::Vector3d run(Eigen::Vector3d x, int periods, Eigen::RowVectorXd* samples = nullptr) const {
    const double h = 1.0 / (f * steps), w = 2.0 * kJenkinsPi * f;
    const int stride = samples != nullptr ? steps / static_cast<int>(samples->size()) : 1;
    for (int period = 0; period < periods; ++period) {
      for (int i = 0; i < steps; ++i) {
        if (samples != nullptr && period + 1 == periods && i % stride == 0) (*samples)(i / stride) = x(0);
        const double t = static_cast<double>(i) * h;
        const double half = x(1) + 0.5 * h * (load * std::cos(w * t) - k * x(0) - c * x(1) - x(2)) / m;
        const double u1 = x(0) + h * half;
        const double trial = x(2) + kt * (u1 - x(0));
        const double f1 = std::clamp(trial, -slip, slip);
        x(1) = (half + 0.5 * h * (load * std::cos(w * (t + h)) - k * u1 - f1) / m) / (1.0 + 0.5 * h * c / m);
        x(0) = u1;
        x(2) = f1;
      }
    }
    return x;
  }
};

TEST(FloquetJenkins, StickSlipMatchesAFiniteDifferenceMonodromyOfTimeStepping) {
  const SteppedOscillator o;
  // The periodic orbit: from rest, 80 periods (ζ = 5 %: the transient decays by e^{−25}).
  const Eigen::Vector3d x0 = o.run(Eigen::Vector3d::Zero(), 80);
  const Eigen::Vector3d x1 = o.run(x0, 1);
  ASSERT_LT((x1 - x0).cwiseAbs().maxCoeff(), 1e-9 * x0.cwiseAbs().maxCoeff()) << "periodic";
  // Central differences of one period's map, each state by 1e-5 of its scale (1e-7 gave the same
  // multipliers to 1e-5 at 2^16 steps; 2^14 and 2^18 steps the same to 1e-6).
  const double amplitude = std::abs(x0(0)) + std::abs(x0(1)) / (2.0 * kJenkinsPi * o.f);
  const Eigen::Vector3d step(1e-5 * amplitude, 1e-5 * amplitude * 2.0 * kJenkinsPi * o.f, 1e-5 * o.slip);
  Eigen::Matrix3d fd;
  for (int j = 0; j < 3; ++j) {
    Eigen::Vector3d plus = x0, minus = x0;
    plus(j) += step(j);
    minus(j) -= step(j);
    fd.col(j) = (o.run(plus, 1) - o.run(minus, 1)) / (2.0 * step(j));
  }
  const Eigen::VectorXcd truth = Eigen::EigenSolver<Eigen::Matrix3d>(fd).eigenvalues();
  std::vector<std::complex<double>> expected(truth.data(), truth.data() + truth.size());
  const MechanicalSystem s = wbm::testing::one_dof_system(o.m, o.c, o.k);
  const std::vector<ContactPoint> contacts = {{0, jenkins(o.kt, o.slip, 1.0)}};
  // The element sticks over about a fifth of the period, twice; t = 0 is in slip.
  for (const int p : {512, 2048}) {
    Eigen::RowVectorXd samples(p);
    (void)o.run(x0, 1, &samples);
    const FloquetResult fl = floquet_multipliers(s, contacts, samples, o.f);
    ASSERT_EQ(fl.multipliers.size(), 3);
    EXPECT_LT(distance_to(fl.multipliers, expected), 3e-5) << "P = " << p << ": " << fl.multipliers.transpose()
                                                           << " against " << truth.transpose();
    // The (δu, δu̇) block of Φ, relative to its largest entry in the balanced state (δu, δu̇/ω).
    const double w = 2.0 * kJenkinsPi * o.f;
    const Eigen::Matrix2d scaling = Eigen::Vector2d(1.0, 1.0 / w).asDiagonal();
    const Eigen::Matrix2d computed = scaling * fl.monodromy.topLeftCorner<2, 2>() * scaling.inverse();
    const Eigen::Matrix2d reference = scaling * fd.topLeftCorner<2, 2>() * scaling.inverse();
    EXPECT_LT((computed - reference).cwiseAbs().maxCoeff(), 1e-4 * reference.cwiseAbs().maxCoeff()) << "P = " << p;
    EXPECT_TRUE(fl.stable());
  }
}

// Hoffmann's point pressed by a normal penalty under a harmonic normal force, rubbing a fixed plane
// through a Jenkins element whose slip force is μ times the normal force, driven along the plane:
// the slip force varies over the period, so the slip ends where σ k_t w − F_s is largest and the
// slip value carries μ σ k_n δx. The same velocity Verlet and return map as SteppedOscillator,
// on the state (x, y, ẋ, ẏ, f).
struct SteppedNormalLoad {
  Hoffmann h;
  double mu = 0.3, preload = 0.01, normal_force = 6.0, tangential_force = 15.0, f = 8.0;
  int steps = 65536;
  using State = Eigen::Matrix<double, 5, 1>;
  [[nodiscard]] double normal(double x) const { return std::max(h.kn * (x + preload), 0.0); }
  [[nodiscard]] State run(State x, int periods, Eigen::MatrixXd* samples = nullptr) const {
    const double dt = 1.0 / (f * steps), w = 2.0 * kJenkinsPi * f;
    const int stride = samples != nullptr ? steps / static_cast<int>(samples->cols()) : 1;
    auto acceleration = [&](const State& z, double t) {
      return Eigen::Vector2d(normal_force * std::cos(w * t) - h.k1 * z(0) - h.k12 * z(1) - h.c * z(2) - normal(z(0)),
                             tangential_force * std::sin(w * t) - h.k12 * z(0) - h.k2 * z(1) - h.c * z(3) - z(4));
    };
    for (int period = 0; period < periods; ++period) {
      for (int i = 0; i < steps; ++i) {
        if (samples != nullptr && period + 1 == periods && i % stride == 0) samples->col(i / stride) = x.head<2>();
        const double t = static_cast<double>(i) * dt;
        const Eigen::Vector2d half = x.segment<2>(2) + 0.5 * dt * acceleration(x, t);
        State next = x;
        next.head<2>() = x.head<2>() + dt * half;
        const double slip = mu * normal(next(0));
        next(4) = std::clamp(x(4) + h.kt * (next(1) - x(1)), -slip, slip);
        next.segment<2>(2) = half;
        next.segment<2>(2) = (half + 0.5 * dt * (acceleration(next, t + dt) + h.c * half)) / (1.0 + 0.5 * dt * h.c);
        x = next;
      }
    }
    return x;
  }
};

TEST(FloquetJenkins, StickSlipUnderAVaryingNormalLoadMatchesAFiniteDifferenceMonodromy) {
  SteppedNormalLoad o;
  o.h.kt = 2e4;
  o.h.c = 2.0 * 0.05 * 2.0 * kJenkinsPi * 10.0;  // ζ = 5 %: 80 periods decay the start by e^{−30}
  using State = SteppedNormalLoad::State;
  const State x0 = o.run(State::Zero(), 80);
  ASSERT_LT((o.run(x0, 1) - x0).cwiseAbs().maxCoeff(), 1e-9 * x0.cwiseAbs().maxCoeff()) << "periodic";
  const double w = 2.0 * kJenkinsPi * o.f;
  State step;
  const double amplitude = x0.head<2>().cwiseAbs().maxCoeff() + x0.segment<2>(2).cwiseAbs().maxCoeff() / w;
  step << amplitude, amplitude, amplitude * w, amplitude * w, o.mu * o.h.kn * o.preload;
  step *= 1e-5;
  Eigen::Matrix<double, 5, 5> fd;
  for (int j = 0; j < 5; ++j) {
    State plus = x0, minus = x0;
    plus(j) += step(j);
    minus(j) -= step(j);
    fd.col(j) = (o.run(plus, 1) - o.run(minus, 1)) / (2.0 * step(j));
  }
  const Eigen::VectorXcd truth = Eigen::EigenSolver<Eigen::Matrix<double, 5, 5>>(fd).eigenvalues();
  const std::vector<std::complex<double>> expected(truth.data(), truth.data() + truth.size());
  std::vector<ContactPoint> contacts = o.h.contacts(o.mu);
  contacts[0].law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{o.h.kn, -o.preload});
  contacts[1].law = jenkins(o.h.kt, o.mu, 0.0);
  contacts[1].obstacle = {};
  // The element sticks over about 11 % of the period, twice; the normal force swings 8.7 … 18 N.
  for (const int p : {1024, 4096}) {
    Eigen::MatrixXd samples(2, p);
    (void)o.run(x0, 1, &samples);
    const FloquetResult fl = floquet_multipliers(o.h.system(), contacts, samples, o.f);
    ASSERT_EQ(fl.multipliers.size(), 5);
    EXPECT_LT(distance_to(fl.multipliers, expected), 5e-5) << "P = " << p << ": " << fl.multipliers.transpose()
                                                           << " against " << truth.transpose();
  }
}

// The three paths of the stepping on one orbit with a Jenkins element (stick–slip under a normal
// penalty that opens and closes) and a penalty stop: the balanced dense path (floquet_multipliers),
// the modal path forming Φ, and the modal path's Arnoldi on products Φ v. A 12-mass chain with
// Rayleigh damping, its last mass rubbing (tangent = DOF 11, normal = DOF 10 for the
// test's sake), a stop at DOF 5. The same scheme in other coordinates: the same multipliers and Φ
// (the element's force perturbation last) to rounding, and Arnoldi's dominant ones to its tolerance.
TEST(FloquetJenkins, TheBalancedModalAndArnoldiPathsAgree) {
  const int n = 12;
  const double k = 4e4;
  Eigen::MatrixXd stiffness = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    stiffness(i, i) = i + 1 < n ? 2.0 * k : k;
    if (i > 0) stiffness(i, i - 1) = stiffness(i - 1, i) = -k;
  }
  MechanicalSystem s;
  s.mass = Eigen::MatrixXd::Identity(n, n).sparseView();
  s.stiffness = stiffness.sparseView();
  s.damping = (0.5 * Eigen::MatrixXd::Identity(n, n) + 2e-5 * stiffness).sparseView();
  ContactPoint normal{10, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{2e4, -1e-3})};
  ContactPoint tangent{11, jenkins(5e4, 0.4, 0.0)};
  tangent.normal = 0;
  ContactPoint stop{5, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e5, 2e-3})};
  const std::vector<ContactPoint> contacts = {normal, tangent, stop};
  const int p = 256;
  Eigen::MatrixXd uc(3, p);
  for (int q = 0; q < p; ++q) {
    const double t = 2.0 * kJenkinsPi * q / p;
    uc(0, q) = -1e-3 + 1.5e-3 * std::cos(t);        // the normal contact opens over part of the cycle
    uc(1, q) = 2e-3 * std::sin(t);                    // the element slips between its reversals
    uc(2, q) = 2e-3 + 1e-3 * std::cos(t + 0.5);       // the stop closes over half of it
  }
  const double hz = 3.0;
  const FloquetResult balanced = floquet_multipliers(s, contacts, uc, hz);
  const FloquetResult modal = FloquetAnalysis(s, contacts, {.dense_states = 1000})(uc, hz);
  const FloquetResult arnoldi = FloquetAnalysis(s, contacts, {.monodromy = false, .dense_states = 0})(uc, hz);
  ASSERT_EQ(balanced.monodromy.rows(), 2 * n + 1);
  ASSERT_EQ(modal.monodromy.rows(), 2 * n + 1);
  EXPECT_LT((modal.monodromy - balanced.monodromy).norm(), 1e-9 * balanced.monodromy.norm());
  std::vector<std::complex<double>> dense(balanced.multipliers.data(),
                                          balanced.multipliers.data() + balanced.multipliers.size());
  EXPECT_LT(distance_to(modal.multipliers, dense), 1e-9);
  // Arnoldi's tolerance (1e-10 on its Ritz residuals) mapped by the conditioning of a non-normal
  // Φ: 1e-9 for the leading pair, 3e-8 measured for the smallest found (|μ| ≈ 0.7).
  ASSERT_TRUE(arnoldi.dominant_only);
  for (Eigen::Index i = 0; i < arnoldi.multipliers.size(); ++i) {
    EXPECT_LT((balanced.multipliers.array() - arnoldi.multipliers(i)).abs().minCoeff(), 1e-7)
        << arnoldi.multipliers(i);
  }
  EXPECT_NEAR(arnoldi.max_modulus, balanced.max_modulus, 1e-9);
  EXPECT_EQ(balanced.steps, modal.steps);
}

// A continuation with stability = true over the damper's resonance: every point has a verdict,
// and every verdict is stable, as incremental passivity requires of a viscously damped structure
// with Jenkins elements under constant normal loads: the energy of the difference of two motions
// (kinetic, elastic and the Jenkins springs' δf²/(2k_t)) only decreases, the sliders dissipating
// (f₁ − f₂)(ṡ₁ − ṡ₂) ≥ 0 by Coulomb's maximal dissipation, and the viscous damping strictly.
TEST(FloquetJenkins, EveryPointOfADamperBranchIsStable) {
  const double k = kOscillatorStiffness;
  const MechanicalSystem s = wbm::testing::one_dof_system(1.0, 2.0 * 0.005 * std::sqrt(k), k);
  const std::vector<ContactPoint> contacts = {{0, jenkins(10.0 * k, 0.2, 1.0)}};
  const TimeBasis fourier = TimeBasis::fourier_harmonics(16);
  const WeightedResidualOptions wo{.time_samples = 256, .contact_quadrature = ContactQuadrature::Midpoint};
  ResponseCurveOptions o;
  o.parameter_min = 5.0;
  o.parameter_max = 20.0;
  o.samples = 256;
  const ResponseCurve curve = trace_response(WeightedResidual(s, {0, 1.0, 5.0}, contacts, fourier, fourier, wo), o);
  ASSERT_EQ(curve.stop, StopReason::RangeReached) << curve.message;
  EXPECT_EQ(curve.unavailable_points, 0);
  double largest = 0.0;
  for (const ResponsePoint& r : curve.points) {
    EXPECT_TRUE(r.stable) << r.frequency_hz << " Hz: |μ| = " << r.max_multiplier;
    largest = std::max(largest, r.max_multiplier);
  }
  EXPECT_LT(largest, 1.0);
  EXPECT_GT(largest, 0.9) << "near resonance the least damped multiplier is e^{−ζωT}, close to 1";
}

}  // namespace
}  // namespace wbm::solvers
