#pragma once
/// Penalty contact laws against a rigid stop [JL14 Eq. (5)]. Units: m, N, N/m, J.
///
/// Sign convention (all laws): u is the displacement of the contact DOF along the direction
/// towards the stop, g0 the initial gap (g0 < 0 is a prestressed, initially penetrated
/// contact). The law returns the magnitude f_c(u) ≥ 0 of the force the stop exerts, which
/// pushes the DOF back: the equation of motion reads M ü + C u̇ + K u = f_ext(t) − e_c f_c(u_c).
/// stiffness(u) = df_c/du ≥ 0; potential(u) = ∫_{−∞}^{u} f_c(s) ds ≥ 0, the energy stored in
/// the stop (E_contact of [JL14 Eq. (35)]).

#include <memory>
#include <string>

#include <Eigen/Core>

namespace wbm::contact {

/// Interface of a contact law; implementations are immutable and cheap to evaluate.
class ContactLaw {
 public:
  virtual ~ContactLaw() = default;
  [[nodiscard]] virtual double force(double u) const = 0;      // f_c(u) [N]
  [[nodiscard]] virtual double stiffness(double u) const = 0;  // df_c/du [N/m]
  [[nodiscard]] virtual double potential(double u) const = 0;  // ∫ f_c du [J]
  [[nodiscard]] virtual double gap() const = 0;                // g0 [m]
  /// One-line description with the parameters, for reports ("exponential a_c = ...").
  [[nodiscard]] virtual std::string describe() const = 0;
  /// True for a rigid stop (RigidStop, signorini.hpp): its force is a Lagrange multiplier of
  /// the Signorini conditions, not a function of u, so force() and stiffness() throw
  /// std::logic_error; solvers that sample a law as a function of u refuse it by name.
  [[nodiscard]] virtual bool rigid() const { return false; }

  /// True for a hysteretic law (JenkinsLaw, friction.hpp): its force at a sample depends on the
  /// history over the period, not on u alone, so force(), stiffness() and potential() throw
  /// std::logic_error and solvers call evaluate_period(); solvers that need f(u) refuse it by name.
  [[nodiscard]] virtual bool hysteretic() const { return false; }

  /// Batched evaluation over samples: force(q) = f_c(u(q)), stiffness(q) = f_c'(u(q)).
  /// Writes into `force` and `stiffness`, which must have the size of `u`.
  void evaluate(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> force,
                Eigen::Ref<Eigen::VectorXd> stiffness) const;

  /// Evaluation over the Q uniform samples u(q) of one period, for memoryless and hysteretic laws
  /// alike: force(q) = f_q, stiffness(q) = ∂f_q/∂u_q, and anchor(q) = r ≥ 0 when f_q also
  /// depends on one earlier sample, ∂f_q/∂u_r = −stiffness(q) (a Jenkins element's last slip),
  /// else −1. The default is evaluate() with every anchor −1. All four have the size of u.
  /// period_shift [m]: the samples of the next period are u + period_shift (a displacement relative
  /// to a counter-surface that slides by; 0 for a periodic u). A hysteretic law carries its state
  /// across it (JenkinsLaw); a memoryless one ignores it.
  virtual void evaluate_period(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> force,
                               Eigen::Ref<Eigen::VectorXd> stiffness, Eigen::Ref<Eigen::VectorXi> anchor,
                               double period_shift = 0.0) const;

  /// True for a friction law whose slip force follows a normal load that varies over the period
  /// (JenkinsLaw): evaluate_period_loaded() is then defined.
  [[nodiscard]] virtual bool takes_normal_load() const { return false; }

  /// evaluate_period under a normal load N_q ≥ 0 [N] per sample (`normal`, from the normal law of
  /// the same contact point), with also load_sensitivity(q) = ∂f_q/∂N_r [-] at the sample
  /// r = q where stiffness(q) = 0 (slip), r = anchor(q) where stiffness(q) ≠ 0 and anchor(q) ≥ 0
  /// (stick after a slip), and 0 in full stick. All six have the size of u; period_shift as in
  /// evaluate_period. The default throws std::logic_error (a law without a normal load: check
  /// takes_normal_load() first).
  virtual void evaluate_period_loaded(const Eigen::Ref<const Eigen::VectorXd>& u,
                                      const Eigen::Ref<const Eigen::VectorXd>& normal, Eigen::Ref<Eigen::VectorXd> force,
                                      Eigen::Ref<Eigen::VectorXd> stiffness, Eigen::Ref<Eigen::VectorXi> anchor,
                                      Eigen::Ref<Eigen::VectorXd> load_sensitivity, double period_shift = 0.0) const;
};

/// Exponential penalty [JL14 Eq. (5)]:
///   f_c(u) = a_c (e^{x} − 1) for x = α (u − g0) > 0, and 0 otherwise,
/// continuous at contact onset, where f_c' jumps from 0 to a_c α (as in the paper).
/// Overflow guard: beyond x > x_lin (`linear_beyond`, default 30, i.e. a force of a_c·1.1e13)
/// the law continues along its tangent, f_c = a_c (e^{x_lin}(1 + x − x_lin) − 1), so that
/// no Newton iterate produces inf; converged solutions that reach this branch are flagged by
/// the solvers. The potential is integrated consistently on both branches.
struct ExponentialPenaltyParameters {
  double coefficient;           // a_c [N] > 0
  double exponent;              // α [1/m] > 0
  double gap;                   // g0 [m], any finite value (< 0: prestress)
  double linear_beyond = 30.0;  // x_lin [-] in (0, 700]
  void validate() const;        // throws std::invalid_argument naming the field and range
};

class ExponentialPenalty final : public ContactLaw {
 public:
  explicit ExponentialPenalty(const ExponentialPenaltyParameters& parameters);
  [[nodiscard]] double force(double u) const override;
  [[nodiscard]] double stiffness(double u) const override;
  [[nodiscard]] double potential(double u) const override;
  [[nodiscard]] double gap() const override { return p_.gap; }
  [[nodiscard]] std::string describe() const override;
  /// Penetration u − g0 [m] beyond which the linear continuation applies (x_lin / α).
  [[nodiscard]] double linear_onset() const { return p_.linear_beyond / p_.exponent; }
  [[nodiscard]] const ExponentialPenaltyParameters& parameters() const { return p_; }

 private:
  ExponentialPenaltyParameters p_;
};

/// Piecewise-linear penalty spring used by other harmonic-balance codes:
///   f_c(u) = k_pen · max(u − g0, 0).
struct LinearPenaltyParameters {
  double stiffness;  // k_pen [N/m] > 0
  double gap;        // g0 [m], any finite value
  void validate() const;
};

class LinearPenalty final : public ContactLaw {
 public:
  explicit LinearPenalty(const LinearPenaltyParameters& parameters);
  [[nodiscard]] double force(double u) const override;
  [[nodiscard]] double stiffness(double u) const override;
  [[nodiscard]] double potential(double u) const override;
  [[nodiscard]] double gap() const override { return p_.gap; }
  [[nodiscard]] std::string describe() const override;

 private:
  LinearPenaltyParameters p_;
};

/// A penalty law reached through a spring: the law acts on a massless node that the structure
/// holds with flexibility c [m/N] (a contact node on a spring, condensed statically). With s the
/// position the node would take without contact (towards the stop) and y its actual position,
///   y + c f(y) = s,          f_eff(s) = f(y(s)),
///   f_eff'(s) = f'(y) / (1 + c f'(y)),   P_eff(s) = P(y) + ½ c f(y)²,
/// where f, f', P are the inner law's force, stiffness and potential (P_eff: the energy of the
/// stop and of the spring's share that the contact compresses; dP_eff/ds = f_eff). For a linear
/// inner law k this is the series spring k / (1 + c k); a rigid stop behind a spring is the
/// penalty 1/c (use LinearPenalty, as solvers::condense_massless does). y is the root of the
/// monotone y + c f(y) − s on the bracket [g0, s], by GSL's Brent solver (gsl_root_fsolver_brent;
/// the upper end first halved while a force overflows there), to a bracket of width
/// ≤ 1e-15 (|s| + |g0|) within 200 iterations; else std::runtime_error with GSL's status and the
/// last bracket.
/// Throws std::invalid_argument for a rigid or null inner law, or c not finite and > 0.
class SeriesCompliance final : public ContactLaw {
 public:
  SeriesCompliance(std::shared_ptr<const ContactLaw> inner, double flexibility);
  [[nodiscard]] double force(double s) const override;
  [[nodiscard]] double stiffness(double s) const override;
  [[nodiscard]] double potential(double s) const override;
  [[nodiscard]] double gap() const override { return inner_->gap(); }
  [[nodiscard]] std::string describe() const override;
  /// The contact node's position y(s) [m] (s itself while the contact is open).
  [[nodiscard]] double node_position(double s) const;
  [[nodiscard]] double flexibility() const { return c_; }

 private:
  std::shared_ptr<const ContactLaw> inner_;
  double c_;
};

}  // namespace wbm::contact
