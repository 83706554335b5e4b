// Modal damping (solvers::modal_damping, [damping] modal_ratio) and the modal path for a
// classical C that is not Rayleigh (KroneckerFactorization, issue #39 item 7: NLvib's rod).
// Truths: the damped system's own eigenvalues (the state matrix's, by Eigen's nonsymmetric
// solver, not the modes modal_damping used); a rigid-body mode's C φ = 0; and the sparse LU of
// the assembled Kronecker sum, which never uses modes, as the slow reference of the modal path.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <wbm/contact/penalty.hpp>
#include <wbm/fem/rod.hpp>
#include <wbm/scene/scene.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/weighted_residual.hpp>

namespace {

using wbm::solvers::LinearSolverPath;
using wbm::solvers::MechanicalSystem;
using wbm::solvers::TimeBasis;

// The unit rod of NLvib's FE_ElasticRod (E = ρ = A = L = 1), clamped at x = 0, undamped.
MechanicalSystem unit_rod(int elements) {
  wbm::fem::RodParameters p;
  p.young_modulus = 1.0;
  p.density = 1.0;
  p.area = 1.0;
  p.length = 1.0;
  p.elements = elements;
  return wbm::solvers::beta_damped(wbm::fem::Rod(p), 0.0);
}

// Eigenvalues s of M ẍ + C ẋ + K x = 0 from the state matrix [[0, I], [−M⁻¹K, −M⁻¹C]].
Eigen::VectorXcd state_eigenvalues(const MechanicalSystem& s) {
  const auto n = s.mass.rows();
  const Eigen::MatrixXd m(s.mass), c(s.damping), k(s.stiffness);
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(m);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  a.topRightCorner(n, n).setIdentity();
  a.bottomLeftCorner(n, n) = -lu.solve(k);
  a.bottomRightCorner(n, n) = -lu.solve(c);
  return Eigen::EigenSolver<Eigen::MatrixXd>(a, false).eigenvalues();
}

TEST(ModalDamping, EveryModeOfTheDampedRodDecaysAtTheGivenRatio) {
  // An underdamped mode's pair s = −ζω ± iω√(1 − ζ²) has ζ = −Re s / |s|: read from the damped
  // system's eigenvalues, which modal_damping never computes.
  for (const double zeta : {0.01, 0.2}) {
    auto s = unit_rod(20);
    s.damping = wbm::solvers::modal_damping(s, zeta);
    ASSERT_NO_THROW(s.validate());
    const Eigen::VectorXcd ev = state_eigenvalues(s);
    ASSERT_EQ(ev.size(), 40);
    for (Eigen::Index i = 0; i < ev.size(); ++i) {
      EXPECT_NEAR(-ev(i).real() / std::abs(ev(i)), zeta, 1e-9) << "eigenvalue " << ev(i) << ", zeta = " << zeta;
    }
  }
}

TEST(ModalDamping, RigidBodyModesAreNotDampedAndBadRatiosAreRefused) {
  // Two unit masses on one unit spring, free-free: modes ω = 0 (translation) and √2.
  MechanicalSystem s;
  s.mass = Eigen::MatrixXd::Identity(2, 2).sparseView();
  s.stiffness = (Eigen::MatrixXd(2, 2) << 1.0, -1.0, -1.0, 1.0).finished().sparseView();
  s.damping = Eigen::MatrixXd::Zero(2, 2).sparseView();
  const Eigen::MatrixXd c(wbm::solvers::modal_damping(s, 0.05));
  EXPECT_LT((c * Eigen::Vector2d(1.0, 1.0)).norm(), 1e-15);  // the translation costs nothing
  // The relative mode (1, −1)/√2 with ω = √2: C = 2ζω φ φᵀ (mass-normalized φ).
  const Eigen::Vector2d phi = Eigen::Vector2d(1.0, -1.0) / std::sqrt(2.0);
  EXPECT_LT((c - 2.0 * 0.05 * std::sqrt(2.0) * phi * phi.transpose()).norm(), 1e-14);
  EXPECT_EQ(wbm::solvers::modal_damping(s, 0.0).nonZeros(), 0);
  for (const double bad : {-0.01, std::nan(""), std::numeric_limits<double>::infinity()}) {
    try {
      (void)wbm::solvers::modal_damping(s, bad);
      ADD_FAILURE() << "zeta = " << bad << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("must be finite and >= 0"), std::string::npos) << e.what();
    }
  }
}

// The modal path on a classical C that is not Rayleigh (a mode-by-mode (Φᵀ C Φ)_ii) against the
// sparse LU of the assembled G, with a penalty stop in contact; and a C the modes do not
// diagonalize is refused on the modal path and solved by the sparse LU under Automatic.
TEST(ModalDamping, ModalPathOfAClassicalDampingMatrixAgreesWithTheSparseLu) {
  auto s = unit_rod(20);
  s.damping = wbm::solvers::modal_damping(s, 0.01);
  const wbm::solvers::HarmonicForcing forcing{19, 0.05, 0.25};  // the linear tip motion is ~20 gaps
  const std::vector<wbm::solvers::ContactPoint> stops = {
      {19, std::make_shared<wbm::contact::LinearPenalty>(wbm::contact::LinearPenaltyParameters{10.0, 0.1})}};
  // The three block forms, each with a per-mode damping: harmonic components (Fourier), circulant
  // (DB6 with itself), dense (DB6 trial, Fourier weighting, weak form: neither shift-invariant
  // nor the distributional form's factored Fourier weighting).
  struct Case {
    const char *trial, *weighting;
    wbm::solvers::Formulation form;
  };
  using wbm::solvers::Formulation;
  for (const auto& [trial, weighting, form] : {Case{"fourier", "fourier", Formulation::Distributional},
                                               Case{"db6", "db6", Formulation::Distributional},
                                               Case{"db6", "fourier", Formulation::Weak}}) {
    const std::string pair = std::string(trial) + ":" + weighting;
    const auto tb = TimeBasis::from_name(trial, 32), wb = TimeBasis::from_name(weighting, 32);
    const auto automatic = wbm::solvers::solve_weighted_residual(s, forcing, stops, tb, wb, {.formulation = form});
    const auto sparse = wbm::solvers::solve_weighted_residual(
        s, forcing, stops, tb, wb, {.formulation = form, .linear_solver = LinearSolverPath::SparseLU});
    ASSERT_TRUE(automatic.converged() && sparse.converged()) << pair;
    EXPECT_EQ(automatic.linear_solver, "modal") << pair;
    EXPECT_EQ(sparse.linear_solver, "sparse-lu") << pair;
    ASSERT_GT(automatic.max_contact_force, 0.0) << pair << ": the stop must be reached";
    EXPECT_LT((automatic.coefficients - sparse.coefficients).norm(), 1e-10 * sparse.coefficients.norm()) << pair;
  }

  // Damping at one DOF only: C M⁻¹ K ≠ K M⁻¹ C.
  auto local = unit_rod(20);
  local.damping = Eigen::SparseMatrix<double>(20, 20);
  local.damping.insert(19, 19) = 0.05;
  const auto basis = TimeBasis::fourier(32);
  try {
    (void)wbm::solvers::solve_weighted_residual(local, forcing, stops, basis, basis,
                                                {.linear_solver = LinearSolverPath::Modal});
    ADD_FAILURE() << "a C the modes do not diagonalize was put on the modal path";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("diagonalize"), std::string::npos) << e.what();
  }
  const auto fallback = wbm::solvers::solve_weighted_residual(local, forcing, stops, basis, basis);
  EXPECT_TRUE(fallback.converged());
  EXPECT_EQ(fallback.linear_solver, "sparse-lu");
}

TEST(ModalDamping, SceneKeyAddsModalDampingToTheRod) {
  const std::string text =
      "[structure]\nyoung_modulus = 1.0\ndensity = 1.0\narea = 1.0\nlength = 1.0\nelements = 20\n"
      "[damping]\nmodal_ratio = 0.01\n[forcing]\namplitude = 0.01\nfrequency_hz = 0.27\n"
      "[contact]\nlaw = \"linear\"\nstiffness = 10.0\ngap = 0.1\n";
  const auto scene = wbm::scene::parse_scene(text, "rod.toml");
  const auto s = scene.system();
  const Eigen::VectorXcd ev = state_eigenvalues(s);
  for (Eigen::Index i = 0; i < ev.size(); ++i) EXPECT_NEAR(-ev(i).real() / std::abs(ev(i)), 0.01, 1e-9);
  // A negative ratio is refused when the scene is read, naming the key (the same scene with
  // 0.01 reads).
  const std::string bad =
      "[structure]\nyoung_modulus = 1.0\ndensity = 1.0\narea = 1.0\nlength = 1.0\nelements = 2\n"
      "[damping]\nmodal_ratio = RATIO\n[forcing]\namplitude = 1.0\nfrequency_hz = 1.0\n";
  const auto with_ratio = [&](const std::string& r) { return std::string(bad).replace(bad.find("RATIO"), 5, r); };
  EXPECT_NO_THROW((void)wbm::scene::parse_scene(with_ratio("0.01"), "good.toml"));
  try {
    (void)wbm::scene::parse_scene(with_ratio("-0.01"), "bad.toml");
    ADD_FAILURE() << "modal_ratio = -0.01 was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("modal_ratio"), std::string::npos) << e.what();
  }
}

}  // namespace
