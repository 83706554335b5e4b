#pragma once
/// Dry friction along one tangent over one period of samples: the Jenkins element [J62; G80], a
/// tangential spring k_t in series with a Coulomb slider. Units: m, N, N/m, J.
///
/// With w the tangential displacement of the contact point relative to the counter-surface and s
/// the slider's position, the element's force is f = k_t (w − s) with |f| ≤ F_s, the slip force
/// (μ N for a friction coefficient μ and a normal load N ≥ 0). f opposes w as a contact law's
/// force does: M ü + C u̇ + K u = f_ext − e_t f. The element is rate independent, so its state
/// over the samples w_q of one period (q = 0 … Q−1, uniform in time) follows the return map, an
/// elastic predictor projected on |f| ≤ F_s,q:
///   f* = f_a + k_t (w_q − w_a)   (= f_{q−1} + k_t (w_q − w_{q−1}) in exact arithmetic),
///   f_q = f*                 if |f*| ≤ F_s,q   (stick: the slider holds),
///   f_q = σ_q F_s,q          otherwise        (slip, σ_q = sign f*),
/// a the last slip before q (f_a = σ_a F_s,a), or the start (f = 0 at w = 0) before any. The
/// predictor is evaluated from a, never by accumulating increments: sums along different paths
/// round differently, and a stick sample within rounding of F_s would then slip in one period
/// and not in the next, a two-period cycle of the ends at the rounding level.
/// The periodic steady state (Masing's rules) starts from the unstretched spring at w = 0 (f = 0
/// before sample 0), runs the period, and runs it again from the force it ended with until that
/// force repeats, to 16 roundings of max(F_s, k_t max|w|) (the predictor's rounding). Each
/// period's map f_start ↦ f_end is monotone and 1-Lipschitz, and constant once a slip is met, so
/// the second period repeats the first as soon as the first slips with a constant slip force; a
/// varying one may need a third. (In floating point a stick sample within rounding of F_s may slip
/// in one period and not the next, so the ends may alternate a few ulps apart; hence the
/// tolerance. The last period is returned.) With a period_shift δ the samples of the next period
/// are w_q + δ (w is not periodic: the displacement relative to a counter-surface that slides by
/// −δ per period); the state carried into the next period is shifted by −δ, so that the force
/// over the period is periodic. Under a slide |δ| larger than twice the loop's width the element
/// slips at every sample after the first period. A period without slip is full
/// stick: the slider stays where it started, at the origin, and f_q = k_t w_q (the convention of
/// harmonic-balance codes for a stuck joint, whose mean force is otherwise undetermined).
///
/// The force is piecewise linear in the samples. After the last slip at sample a (of this period,
/// or of the previous one, cyclically), a stick sample has f_q = σ_a F_s,a + k_t (w_q − w_a); a
/// slip sample has f_q = σ_q F_s,q; full stick has f_q = k_t w_q. Hence
///   ∂f_q/∂w_q = k_t (stick) or 0 (slip),  ∂f_q/∂w_a = −k_t,  ∂f_q/∂F_s,a = σ_a,
/// at most two entries in a row of ∂f/∂w: only the stick samples carry rank. The derivatives are
/// exact away from the samples where the state switches (a set of measure zero in w).
///
/// A stick/slip pattern (1 = slip, 0 = stick, one entry per sample) names one piece of that
/// piecewise-linear map: given a pattern, every sample takes the branch the pattern names instead
/// of the one |f*| ≤ F_s picks (a slip sample f_q = σ_q F_s,q with σ_q = sign f*, a stick sample
/// f_q = f*, full stick when no sample slips), so the force is the same affine function of (w,
/// F_s) on the whole pattern's piece and beyond it, the piece's own extension. Its switching
/// functions are the margins F_s,q − |f*_q|: ≥ 0 on a stick sample and ≤ 0 on a slip sample
/// exactly where the return map picks the pattern's branch. The pieces of the piecewise-smooth
/// continuation of the weighted residual (solvers::JenkinsResponseFamily) are these patterns.
///
/// [J62] Jenkins, G.M. (1962). Analysis of the stress–strain relationships in reactor grade
/// graphite. Br. J. Appl. Phys. 13, 30–32. [G80] Griffin, J.H. (1980). Friction damping of
/// resonant stresses in gas turbine engine airfoils. J. Eng. Power 102, 329–333.

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <wbm/contact/penalty.hpp>

namespace wbm::contact {

/// The periodic steady state of a Jenkins element over one period (jenkins_loop). Vectors have
/// one entry per sample q = 0 … Q−1.
struct JenkinsLoop {
  Eigen::VectorXd force;      // f_q [N]
  /// ∂f_q/∂w_q [N/m]: k_t in stick, 0 in slip.
  Eigen::VectorXd stiffness;
  /// The sample a of the last slip before a stick sample q (∂f_q/∂w_a = −k_t, cyclically: a > q
  /// is a slip of the previous period); −1 in slip and in full stick.
  Eigen::VectorXi anchor;
  /// ∂f_q/∂F_s,r [-]: σ_a at r = anchor(q) in stick after a slip, σ_q at r = q in slip, 0 in full
  /// stick (σ = ±1, the slip direction).
  Eigen::VectorXd slip_sensitivity;
  /// F_s,q − |f*_q| [N], f*_q the elastic predictor at q: the margin of the return map (≥ 0:
  /// the map sticks there). The switching functions of a pattern's piece.
  Eigen::VectorXd margin;
  int slipping_samples = 0;   // samples in slip
  int periods = 0;            // periods run until the end force repeated (≥ 2)
  /// The work of the slider over the period, Σ_q f̄_q Δs_q ≥ 0 [J], with the slider increment
  /// Δs_q = (w_q − w_{q−1}) − (f_q − f_{q−1})/k_t (zero in stick) and f̄_q = f_q at a slip onset
  /// (exact for w linear between samples), ½ (f_q + f_{q−1}) along a slip in one direction
  /// (equal to f_q under a constant slip force; second order under a varying one): the energy
  /// the element dissipates per cycle, ∮ f dw.
  double dissipated_energy = 0.0;
};

/// The periodic force of a Jenkins element of stiffness k_t [N/m] driven by the tangential
/// displacements w [m] and the slip forces F_s [N] at the Q samples of one period (the return
/// map above). Throws std::invalid_argument naming the argument for an empty w, sizes that
/// differ, a k_t that is not finite and > 0, a w or F_s that is not finite, or a negative F_s;
/// std::runtime_error when the force at the period's end has not repeated after max_periods
/// periods (both last values named; raise max_periods), which the proof above excludes for a
/// constant slip force; std::invalid_argument for a period_shift δ [m] that is not finite.
/// With a `pattern` (Q entries, 1 = slip, 0 = stick) the samples take the pattern's branches
/// (the piece above; std::invalid_argument for a pattern of another size); without one, the
/// return map's.
[[nodiscard]] JenkinsLoop jenkins_loop(double tangential_stiffness, const Eigen::Ref<const Eigen::VectorXd>& w,
                                       const Eigen::Ref<const Eigen::VectorXd>& slip_force, int max_periods = 8,
                                       double period_shift = 0.0, const std::vector<std::uint8_t>* pattern = nullptr);

/// A Jenkins element under a constant normal load, as a contact law along one tangent.
struct JenkinsParameters {
  double tangential_stiffness;  // k_t [N/m], finite and > 0
  double friction_coefficient;  // μ [-], finite and >= 0
  double normal_load;           // N [N], finite and >= 0: a preload; the slip force is μ N
  /// Throws std::invalid_argument naming the field, its value and the allowed range.
  void validate() const;
};

/// The Jenkins element of JenkinsParameters as a ContactLaw on the tangential displacement u of a
/// contact point (ContactPoint::along the tangent): hysteretic() is true and evaluate_period() is
/// jenkins_loop with F_s = μ N at every sample (stiffness, anchor as documented there); force(),
/// stiffness() and potential() throw std::logic_error (no f(u) exists), and gap() is 0 (a
/// tangential law has no gap). evaluate_period throws as jenkins_loop does for sizes that differ.
class JenkinsLaw final : public ContactLaw {
 public:
  explicit JenkinsLaw(const JenkinsParameters& parameters);
  [[nodiscard]] double force(double u) const override;
  [[nodiscard]] double stiffness(double u) const override;
  [[nodiscard]] double potential(double u) const override;
  [[nodiscard]] double gap() const override { return 0.0; }
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] bool hysteretic() const override { return true; }
  void evaluate_period(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> force,
                       Eigen::Ref<Eigen::VectorXd> stiffness, Eigen::Ref<Eigen::VectorXi> anchor,
                       double period_shift = 0.0) const override;
  /// The whole loop at the samples u (jenkins_loop, the next period's samples u + period_shift),
  /// with its slip sensitivities and energy.
  /// With a stick/slip pattern, that pattern's piece (jenkins_loop).
  [[nodiscard]] JenkinsLoop loop(const Eigen::Ref<const Eigen::VectorXd>& u, double period_shift = 0.0,
                                 const std::vector<std::uint8_t>* pattern = nullptr) const;
  /// A normal load that varies with the normal gap [YCM98; PE03 in docs/references.md]: the slip
  /// force at sample q is F_s,q = μ (N + n_q), n_q ≥ 0 [N] the force of the contact point's
  /// normal law (`normal`, one per sample; N the preload of the parameters, 0 if there is none).
  /// Where the normal law opens (n_q = 0, N = 0) F_s = 0: the tangential force vanishes and the
  /// slider follows, the separation of a 2D frictional contact. Throws std::invalid_argument for
  /// a normal of another size than u, or a normal load that is not finite and >= 0.
  [[nodiscard]] JenkinsLoop loop(const Eigen::Ref<const Eigen::VectorXd>& u,
                                 const Eigen::Ref<const Eigen::VectorXd>& normal, double period_shift = 0.0,
                                 const std::vector<std::uint8_t>* pattern = nullptr) const;
  [[nodiscard]] bool takes_normal_load() const override { return true; }
  /// evaluate_period with F_s,q = μ (N + normal_q) (loop above); load_sensitivity = μ σ, the
  /// slip_sensitivity of the loop times μ (ContactLaw::evaluate_period_loaded).
  void evaluate_period_loaded(const Eigen::Ref<const Eigen::VectorXd>& u, const Eigen::Ref<const Eigen::VectorXd>& normal,
                              Eigen::Ref<Eigen::VectorXd> force, Eigen::Ref<Eigen::VectorXd> stiffness,
                              Eigen::Ref<Eigen::VectorXi> anchor, Eigen::Ref<Eigen::VectorXd> load_sensitivity,
                              double period_shift = 0.0) const override;
  /// One step of the return map, for time stepping: the force after the tangential displacement
  /// moves by du [m] from a state of force f [N], under the normal load n ≥ 0 [N] of the normal
  /// law: f* = f + k_t du, projected on |f| ≤ μ (N + n). Throws nothing.
  [[nodiscard]] double return_map(double f, double du, double n) const {
    const double trial = f + p_.tangential_stiffness * du;
    const double fs = p_.friction_coefficient * (p_.normal_load + n);
    return trial > fs ? fs : (trial < -fs ? -fs : trial);
  }
  [[nodiscard]] const JenkinsParameters& parameters() const { return p_; }
  [[nodiscard]] double slip_force() const { return p_.friction_coefficient * p_.normal_load; }

 private:
  JenkinsParameters p_;
};

/// Exact Coulomb friction in discrete time, the tangential analogue of signorini_min: with λ the
/// friction force over one time cell [N] (its mean), F_s = μ N ≥ 0 the slip force and Δ the
/// tangential displacement of the contact point over that cell [m] (Δ = w(t + h) − w(t)), the
/// law Δ ∈ N_[−F_s, F_s](λ) (the implicit, Moreau-type discretization of f ∈ F_s Sign(ẇ): the
/// force opposes the slip and stays inside the cone) is the projection equation
///   φ(a, Δ, b) = a − proj_[−b, b](a + Δ) = 0,    a = c λ,  b = c F_s,
/// with c > 0 [m/N] a compliance that puts both arguments in metres (the root set does not
/// depend on c; Newton's path does: c plays the role of the DLFT's inverse penalty, 1/ε).
/// Branches: stick, |a + Δ| ≤ b, φ = −Δ (the point holds); slip, φ = a − σ b with σ =
/// sign(a + Δ) (the force saturates). The tie |a + Δ| = b is taken as stick. φ is semismooth,
/// so Newton with its generalized derivative is an active-set method, as for the Signorini
/// conditions. Units: m. Throws nothing; b < 0 is the caller's error (CoulombFriction checks).
struct CoulombProjection {
  double value;   // φ [m]
  bool stick;     // ∂φ/∂Δ = −1, ∂φ/∂a = 0 if true; ∂φ/∂a = 1, ∂φ/∂b = −σ otherwise
  double sigma;   // σ = ±1 in slip, 0 in stick
};
[[nodiscard]] inline CoulombProjection coulomb_projection(double a, double delta, double b) {
  const double t = a + delta;
  if (std::abs(t) <= b) return {-delta, true, 0.0};
  const double sigma = t > 0.0 ? 1.0 : -1.0;
  return {a - sigma * b, false, sigma};
}

/// Exact (rigid-plastic) Coulomb friction along one tangent under a constant normal load: the
/// limit k_t → ∞ of the Jenkins element, with no tangential compliance. Like RigidStop its force
/// is a Lagrange multiplier that the solver computes (rigid() is true), here from the projection
/// equation above at each time cell (solvers/weighted_residual.hpp); it is also hysteretic(), so
/// that laws needing f(u) or a slider state refuse it. force(), stiffness() throw
/// std::logic_error; potential() is 0 (a rigid-plastic slider stores no energy); gap() is 0 (a
/// tangential law has no gap). Throws std::invalid_argument (construction) naming the field for
/// a μ or N that is not finite and ≥ 0.
struct CoulombParameters {
  double friction_coefficient;  // μ [-], finite and >= 0
  double normal_load;           // N [N], finite and >= 0: a preload; the slip force is μ N
  void validate() const;
};

class CoulombFriction final : public ContactLaw {
 public:
  explicit CoulombFriction(const CoulombParameters& parameters);
  [[nodiscard]] double force(double u) const override;
  [[nodiscard]] double stiffness(double u) const override;
  [[nodiscard]] double potential(double /*u*/) const override { return 0.0; }
  [[nodiscard]] double gap() const override { return 0.0; }
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] bool rigid() const override { return true; }
  [[nodiscard]] bool hysteretic() const override { return true; }
  [[nodiscard]] const CoulombParameters& parameters() const { return p_; }
  [[nodiscard]] double slip_force() const { return p_.friction_coefficient * p_.normal_load; }

 private:
  CoulombParameters p_;
};

}  // namespace wbm::contact
