// G(f) factorized block by block over the components of the time operators (Fourier:Fourier off
// the modal path: a non-classical C, or LinearSolverPath::SparseLU), each block by LAPACK's band
// LU or, for a structure whose DOF order has a wide band, by KLU (kronecker_components.cpp).
// Truths from outside the code under test:
//  - the linear response against a dense LU of G = f² A_M ⊗ M + f A_C ⊗ C + A_K ⊗ K formed here
//    from the public time operators, with b = −R(0);
//  - for a classical C, the condensed Jacobian J = I + H N and the contact residual at a state in
//    contact against the modal path (the undamped modes, an independent factorization);
//  - a contact solve verified on the full residual R(a), which never touches the factorization,
//    with the band and the KLU blocks (the same rod with its DOFs numbered backwards and forwards
//    alternately, so that its band is as wide as the rod);
//  - on 1 280 elements, the contact residual smooth in the frequency: a second difference at
//    rounding level and a central difference that matches the analytic ∂r/∂f.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include <Eigen/Dense>
#include <unsupported/Eigen/KroneckerProduct>

#include <wbm/contact/penalty.hpp>
#include <wbm/fem/rod.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/weighted_residual.hpp>

namespace wbm::solvers {
namespace {

// A clamped steel rod with C = βK plus a dashpot of 40 N·s/m at its middle DOF (not classical,
// so Automatic does not take the modal path). `scrambled` renumbers the DOFs 0, n−1, 1, n−2, …
// (a half-bandwidth of n − 1): the components' blocks then go to KLU instead of the band LU.
struct Rod {
  MechanicalSystem system;
  int tip = 0;
};

Rod dashpot_rod(int elements, bool scrambled) {
  const fem::Rod rod({210e9, 7800.0, 1e-4, 1.0, elements});
  MechanicalSystem s = beta_damped(rod, 1e-6);
  const int n = s.dofs();
  s.damping.coeffRef(n / 2, n / 2) += 40.0;
  int tip = rod.tip_dof();
  if (scrambled) {
    Eigen::VectorXi order(n);  // new index of old DOF i
    for (int k = 0; k < n; ++k) order(k % 2 == 0 ? k / 2 : n - 1 - k / 2) = k;
    const Eigen::PermutationMatrix<Eigen::Dynamic> p(order);
    for (auto* x : {&s.mass, &s.damping, &s.stiffness}) *x = Eigen::SparseMatrix<double>(p * *x * p.transpose());
    tip = order(tip);
  }
  return {s, tip};
}

Eigen::MatrixXd dense_g(const WeightedResidual& wr) {
  const TimeOperators& ops = wr.time_operators();
  const double f = wr.frequency_hz();
  const MechanicalSystem& s = wr.system();
  return Eigen::MatrixXd(Eigen::kroneckerProduct(Eigen::MatrixXd(f * f * ops.mass), Eigen::MatrixXd(s.mass))) +
         Eigen::MatrixXd(Eigen::kroneckerProduct(Eigen::MatrixXd(f * ops.damping), Eigen::MatrixXd(s.damping))) +
         Eigen::MatrixXd(Eigen::kroneckerProduct(Eigen::MatrixXd(ops.stiffness), Eigen::MatrixXd(s.stiffness)));
}

TEST(KroneckerComponents, LinearResponseMatchesTheDenseLuOfG) {
  for (const bool scrambled : {false, true}) {
    SCOPED_TRACE(scrambled ? "KLU blocks" : "band blocks");
    const Rod rod = dashpot_rod(24, scrambled);
    const HarmonicForcing forcing{rod.tip, 1e4, 300.0, {}};
    const auto basis = TimeBasis::fourier_harmonics(5);
    const WeightedResidual wr(rod.system, forcing, {}, basis, basis);
    ASSERT_EQ(wr.linear_solver(), "sparse-lu");
    const Eigen::VectorXd b = -wr.residual(Eigen::VectorXd::Zero(wr.dofs() * wr.dimension()));
    const Eigen::VectorXd truth = dense_g(wr).partialPivLu().solve(b);
    EXPECT_LE((wr.linear_response() - truth).norm(), 1e-11 * truth.norm());
  }
}

TEST(KroneckerComponents, CondensedJacobianMatchesTheModalPath) {
  // A classical C (βK): LinearSolverPath::SparseLU takes the components, Modal the eigenbasis, an
  // independent factorization. J = I + H N at a state with the tip in contact part of the period.
  for (const bool scrambled : {false, true}) {
    SCOPED_TRACE(scrambled ? "KLU blocks" : "band blocks");
    Rod rod = dashpot_rod(24, scrambled);
    rod.system.damping = 1e-6 * rod.system.stiffness;
    const HarmonicForcing forcing{rod.tip, 1e4, 300.0, {}};
    const auto basis = TimeBasis::fourier_harmonics(5);
    const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{2e8, 1e-5});
    const WeightedResidual components(rod.system, forcing, {{rod.tip, law}}, basis, basis,
                                      {.linear_solver = LinearSolverPath::SparseLU});
    const WeightedResidual modal(rod.system, forcing, {{rod.tip, law}}, basis, basis,
                                 {.linear_solver = LinearSolverPath::Modal});
    ASSERT_EQ(components.linear_solver(), "sparse-lu");
    ASSERT_EQ(modal.linear_solver(), "modal");
    const Eigen::VectorXd x = 3.0 * modal.contact_unknowns(modal.linear_response());
    const Eigen::MatrixXd jc = components.contact_jacobian(x), jm = modal.contact_jacobian(x);
    ASSERT_GT((jm - Eigen::MatrixXd::Identity(jm.rows(), jm.cols())).norm(), 1e-3) << "the tip never reached the stop";
    EXPECT_LE((jc - jm).norm(), 1e-9 * jm.norm());
    EXPECT_LE((components.contact_residual(x) - modal.contact_residual(x)).norm(),
              1e-9 * modal.contact_residual(x).norm());
  }
}

TEST(KroneckerComponents, ContactSolveVerifiesOnTheFullResidualWithBandAndKluBlocks) {
  Eigen::VectorXd tips[2];
  for (const bool scrambled : {false, true}) {
    SCOPED_TRACE(scrambled ? "KLU blocks" : "band blocks");
    const Rod rod = dashpot_rod(40, scrambled);
    const HarmonicForcing forcing{rod.tip, 2e4, 300.0, {}};
    const auto basis = TimeBasis::fourier_harmonics(7);
    const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{5e8, 1e-5});
    const auto s = solve_weighted_residual(rod.system, forcing, {{rod.tip, law}}, basis, basis, {});
    ASSERT_TRUE(s.converged()) << s.brief();
    EXPECT_EQ(s.linear_solver, "sparse-lu");
    const WeightedResidual wr(rod.system, forcing, {{rod.tip, law}}, basis, basis);
    // n × M, column k the DOFs' coefficient k: stacked as k·n + DOF.
    const Eigen::VectorXd a = Eigen::Map<const Eigen::VectorXd>(s.coefficients.data(), s.coefficients.size());
    EXPECT_LE(wr.backward_error(a, wr.residual(a)), 1e-12);
    ASSERT_GT(s.max_contact_force, 0.0) << "the tip never reached the stop";
    tips[scrambled ? 1 : 0] = wr.contact_unknowns(a);
  }
  EXPECT_LE((tips[0] - tips[1]).norm(), 1e-9 * tips[0].norm()) << "the numbering changed the tip's motion";
}

TEST(KroneckerComponents, ContactResidualIsSmoothInFrequencyOnAFineRod) {
  // At a fixed x the contact residual r(x, f) = (x − P G(f)⁻¹ (b − Pᵀ n(x))) / s_r is analytic in
  // f away from resonances (s_r held, at_frequency). Two truths about it: its second difference
  // over f(1 ± 1e-12) is 1e-24 f² ∂²r/∂f², far below rounding; and its central difference over
  // f ± 1e-3 Hz agrees with ∂r/∂f = P G⁻¹ G′ G⁻¹ (b − Pᵀ n) / s_r
  // (contact_residual_frequency_derivative) to the truncation h² ∂³r/∂f³ / 6, 47 Hz below the
  // first resonance. On 1 280 elements, before the refinement on G's terms (issue #39, item 5),
  // these were 1.5e-11 ‖r‖ and 7.1e-6 ‖∂r/∂f‖ (band), 6.4e-11 ‖r‖ and 2.0e-5 ‖∂r/∂f‖ (KLU):
  // the stored G(f), its entries rounded after K and ω² M cancel, moves in steps as f varies;
  // after it, 5.2e-15 ‖r‖ and 5.2e-10 ‖∂r/∂f‖ for both.
  for (const bool scrambled : {false, true}) {
    SCOPED_TRACE(scrambled ? "KLU blocks" : "band blocks");
    const Rod rod = dashpot_rod(1280, scrambled);
    const auto basis = TimeBasis::fourier_harmonics(15);
    const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{5e8, 1e-5});
    const double f0 = 1250.0;
    const WeightedResidual w0(rod.system, HarmonicForcing{rod.tip, 2e4, f0, {}}, {{rod.tip, law}}, basis, basis,
                              {.linear_solver = LinearSolverPath::SparseLU});
    auto at = [&](double f) { return w0.at_frequency(f); };  // the same scale s_r
    ASSERT_EQ(w0.linear_solver(), "sparse-lu");
    const Eigen::VectorXd x = 1.5 * w0.contact_unknowns(w0.linear_response());
    const Eigen::VectorXd r0 = w0.contact_residual(x);
    ASSERT_GT(r0.norm(), 0.0);
    const double delta = 1e-12;
    const Eigen::VectorXd second = at(f0 * (1.0 + delta)).contact_residual(x) - 2.0 * r0 +
                                   at(f0 * (1.0 - delta)).contact_residual(x);
    const double h = 1e-3;
    const Eigen::VectorXd central = (at(f0 + h).contact_residual(x) - at(f0 - h).contact_residual(x)) / (2.0 * h);
    const Eigen::VectorXd derivative = w0.contact_residual_frequency_derivative(x);
    EXPECT_LE(second.norm(), 2e-13 * r0.norm());
    EXPECT_LE((central - derivative).norm(), 1e-8 * derivative.norm());
  }
}

}  // namespace
}  // namespace wbm::solvers
