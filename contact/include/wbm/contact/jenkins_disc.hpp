#pragma once
/// Dry friction along two tangents: the Jenkins element of friction.hpp with an isotropic
/// Coulomb disc [MY98; PE03 in docs/references.md], a tangential spring k_t in series with a
/// slider that moves in the plane of the two tangents. Units: m, N, N/m, J.
///
/// With w_q ∈ R² the tangential displacement of the contact point relative to the counter-surface
/// at the Q uniform samples of one period (q = 0 … Q−1) and F_s,q ≥ 0 the slip force (μ (N + n_q)),
/// the force follows the return map, an elastic predictor projected on the disc |f| ≤ F_s:
///   f*_q = f_{q−1} + k_t (w_q − w_{q−1}),
///   f_q  = f*_q                  if |f*_q| ≤ F_s,q   (stick),
///   f_q  = F_s,q f*_q / |f*_q|   otherwise          (slip, along n_q = f*_q/|f*_q|),
/// the implicit (backward Euler) discretization of f = k_t (w − s), ṡ ∥ f, |f| ≤ F_s (the slider
/// moves along the force, the associated flow rule of an isotropic cone). f opposes w as a contact
/// law's force does: M ü + C u̇ + K u = f_ext − e_1 f_1 − e_2 f_2.
///
/// Unlike the element along one tangent, the slip direction n_q carries memory: in slip f_q still
/// turns with the displacement, so the force at a slip sample depends on every sample before it.
/// The periodic steady state is the fixed point f_{−1} = f_{Q−1} of the period map
/// Φ: f_{−1} ↦ f_{Q−1} (w_{−1} = w_{Q−1} − δ under a period_shift δ: the next period's samples are
/// w + δ, as in jenkins_loop). The first period starts from the unstretched spring at w = 0; Φ is
/// 1-Lipschitz (a composition of translations and projections on discs) but its contraction can be
/// slow: on a circular orbit of radius a it is exp(−2π r_s k_t/F_s) per period, r_s the slider's
/// radius, which tends to 1 as a → F_s/k_t. So each period is followed by a Newton step on
/// f = Φ(f), with Φ's exact 2 × 2 derivative ∂Φ/∂f_{−1} = P_{Q−1} ⋯ P_0, where
///   P_q = I (stick),   P_q = (F_s,q/|f*_q|) (I − n_q n_qᵀ) (slip),
/// taken when it lowers the fixed-point residual |Φ(f) − f| below the plain iterate's; iterations
/// stop when it is at most 16 roundings of max(F_s, k_t max|w|). A period without slip is full
/// stick: the slider stays at the origin and f_q = k_t w_q, as in jenkins_loop.
///
/// Derivatives. On the converged period, δf_q = P_q (δf_{q−1} + k_t (δw_q − δw_{q−1})) + s_q n_q
/// δF_s,q (s_q = 1 in slip, 0 in stick), closed cyclically by δf_{−1} = δf_{Q−1}: with
/// Ψ_q = P_q ⋯ P_0 and Φ_{q,r} = P_q ⋯ P_{r+1} (Φ_{q,q} = I), the response to v_r (the terms added
/// at r) is T_{q,r} = [r ≤ q] Φ_{q,r} + Ψ_q (I − Ψ_{Q−1})⁻¹ Φ_{Q−1,r}. I − Ψ_{Q−1} is invertible
/// once a slip sample has |f*| > F_s. In full stick ∂f/∂w = k_t I. The derivatives are exact away
/// from the samples where the state switches (a set of measure zero in w); no entry of ∂f/∂w is
/// structurally zero in slip, so the Jacobian is dense, 2Q × 2Q, per element.
/// Along a line (w_q = w_0 + t_q e, e fixed) the element is jenkins_loop along e: the same forces,
/// the same ∂f/∂w along e, and the same dissipated energy.
///
/// [MY98] Menq, C.-H., Yang, B.D. (1998). Non-linear spring resistance and friction damping of
/// frictional constraint having two-dimensional motion. J. Sound Vib. 217(1), 127–143.

#include <string>

#include <Eigen/Core>

#include <wbm/contact/friction.hpp>

namespace wbm::contact {

/// The periodic steady state of a Jenkins element with two tangents (jenkins_disc_loop).
/// Per-sample matrices are laid out tangent by tangent: row i·Q + q is tangent i ∈ {0, 1} at
/// sample q.
struct JenkinsDiscLoop {
  Eigen::MatrixXd force;          // f_q, 2 × Q [N] (row = tangent, column = sample)
  /// ∂f_{i,q}/∂w_{j,r} [N/m], 2Q × 2Q: row i·Q + q, column j·Q + r. Dense in slip.
  Eigen::MatrixXd jacobian;
  /// ∂f_{i,q}/∂F_s,r [-], 2Q × Q: row i·Q + q, column r.
  Eigen::MatrixXd load_jacobian;
  /// F_s,q − |f*_q| [N] (≥ 0: the map sticks at q), Q entries.
  Eigen::VectorXd margin;
  int slipping_samples = 0;       // samples in slip
  int periods = 0;                // period evaluations until the fixed point (≥ 2)
  /// The work of the slider over the period, Σ_q f̄_q · Δs_q ≥ 0 [J], Δs_q = (w_q − w_{q−1}) −
  /// (f_q − f_{q−1})/k_t in slip (zero in stick), f̄_q = f_q at a slip onset, ½ (f_q + f_{q−1})
  /// after a slip sample (jenkins_loop's rule): the energy the element dissipates per cycle.
  double dissipated_energy = 0.0;
};

/// The periodic force of a Jenkins element with two tangents, of stiffness k_t [N/m], driven by the
/// tangential displacements w (2 × Q) [m] and the slip forces F_s (Q entries) [N] (the return map
/// above). Throws std::invalid_argument naming the argument for a w without 2 rows or without
/// samples, a slip force of another length, a k_t that is not finite and > 0, a w or F_s that is
/// not finite, a negative F_s, max_periods < 2, or a period_shift that is not finite;
/// std::runtime_error when the fixed point is not reached in max_periods period evaluations (the
/// residual and the tolerance named; raise max_periods). With derivatives = false, jacobian and
/// load_jacobian are left empty (0 × 0): the forces alone cost O(Q) per period, the derivatives
/// O(Q²).
[[nodiscard]] JenkinsDiscLoop jenkins_disc_loop(double tangential_stiffness, const Eigen::Ref<const Eigen::MatrixXd>& w,
                                                const Eigen::Ref<const Eigen::VectorXd>& slip_force,
                                                int max_periods = 64,
                                                const Eigen::Vector2d& period_shift = Eigen::Vector2d::Zero(),
                                                bool derivatives = true);

/// The Jenkins element with two tangents as a ContactLaw shared by the two contact points that
/// carry its tangents (solvers::ContactPoint::second_tangent links them): hysteretic() and
/// takes_normal_load() are true; force(), stiffness() and potential() throw std::logic_error (no
/// f(u) exists), gap() is 0, and evaluate_period() and evaluate_period_loaded() throw
/// std::logic_error: the force along one tangent depends on both, so it is evaluated by loop()
/// on both rows (solvers::evaluate_contact_period does that). The slip force is μ (N + n_q), as for
/// JenkinsLaw. Throws std::invalid_argument (construction) as JenkinsParameters::validate.
class JenkinsDiscLaw final : public ContactLaw {
 public:
  explicit JenkinsDiscLaw(const JenkinsParameters& parameters);
  [[nodiscard]] double force(double u) const override;
  [[nodiscard]] double stiffness(double u) const override;
  [[nodiscard]] double potential(double u) const override;
  [[nodiscard]] double gap() const override { return 0.0; }
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] bool hysteretic() const override { return true; }
  [[nodiscard]] bool takes_normal_load() const override { return true; }
  void evaluate_period(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> force,
                       Eigen::Ref<Eigen::VectorXd> stiffness, Eigen::Ref<Eigen::VectorXi> anchor,
                       double period_shift = 0.0) const override;
  void evaluate_period_loaded(const Eigen::Ref<const Eigen::VectorXd>& u, const Eigen::Ref<const Eigen::VectorXd>& normal,
                              Eigen::Ref<Eigen::VectorXd> force, Eigen::Ref<Eigen::VectorXd> stiffness,
                              Eigen::Ref<Eigen::VectorXi> anchor, Eigen::Ref<Eigen::VectorXd> load_sensitivity,
                              double period_shift = 0.0) const override;
  /// The loop at the samples w (2 × Q) under the slip force μ (N + normal_q): `normal` has Q
  /// entries (n_q ≥ 0 [N], the normal law's force), or is empty for the constant μ N. The
  /// load_jacobian of the result is ∂f/∂n (μ times jenkins_disc_loop's ∂f/∂F_s). Throws
  /// std::invalid_argument for a normal of another length or not finite and >= 0, and as
  /// jenkins_disc_loop (derivatives as there).
  [[nodiscard]] JenkinsDiscLoop loop(const Eigen::Ref<const Eigen::MatrixXd>& w, const Eigen::VectorXd& normal = {},
                                     const Eigen::Vector2d& period_shift = Eigen::Vector2d::Zero(),
                                     bool derivatives = true) const;
  /// One step of the return map, for time stepping: the force after the tangential displacement
  /// moves by dw [m] from a state of force f [N] under the normal load n ≥ 0 [N]: f* = f + k_t dw
  /// projected on the disc |f| ≤ μ (N + n). Throws nothing.
  [[nodiscard]] Eigen::Vector2d return_map(const Eigen::Vector2d& f, const Eigen::Vector2d& dw, double n) const {
    const Eigen::Vector2d trial = f + p_.tangential_stiffness * dw;
    const double fs = p_.friction_coefficient * (p_.normal_load + n);
    const double size = trial.norm();
    return size > fs ? Eigen::Vector2d(trial * (fs / size)) : trial;
  }
  [[nodiscard]] const JenkinsParameters& parameters() const { return p_; }

 private:
  JenkinsParameters p_;
};

}  // namespace wbm::contact
