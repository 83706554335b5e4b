#pragma once
/// Exact unilateral contact against a rigid stop: the Signorini conditions
///   g = g0 − u ≥ 0,   λ ≥ 0,   g λ = 0,
/// with u the displacement of the contact DOF towards the stop [m], g0 the gap [m] and λ the
/// force the stop exerts [N] (the sign convention of penalty.hpp: it pushes the DOF back). The
/// limit of the penalty laws as their stiffness grows [JL14 Sec. 6: "an exact unilateral contact
/// method ... should result in perfectly flat contact plateaus"]. Units: m, N.

#include <string>

#include <wbm/contact/penalty.hpp>

namespace wbm::contact {

/// The Signorini conditions written as one equation, the minimum complementarity function
///   φ(a, g) = min(a, g) = 0   ⇔   a ≥ 0, g ≥ 0, a g = 0,
/// with a = c λ the force scaled by a compliance c > 0 [m/N], so that both arguments are in
/// metres (φ's root set does not depend on c; Newton's path does). φ is semismooth: Newton with
/// the generalized derivative below is the primal–dual active-set method [Hintermüller, Ito &
/// Kunisch 2002, SIAM J. Optim. 13(3) 865–888]. On the tie a = g the gap branch is taken.
struct Complementarity {
  double value;      // φ [m]
  bool gap_branch;   // ∂φ/∂g = 1, ∂φ/∂a = 0 if true; ∂φ/∂a = 1, ∂φ/∂g = 0 otherwise
};
[[nodiscard]] inline Complementarity signorini_min(double a, double g) {
  return g <= a ? Complementarity{g, true} : Complementarity{a, false};
}

/// A rigid stop at gap g0 (finite, any sign; g0 < 0 is an initially penetrated, prestressed
/// contact). As a ContactLaw it only says rigid() and gap(): force() and stiffness() throw
/// std::logic_error (the force is a multiplier that the solver computes), and potential(u) is 0,
/// the stop stores no energy (the potential is the indicator function of u ≤ g0, evaluated on
/// the admissible side; penetration is reported by the solvers, not priced).
/// Throws std::invalid_argument (construction) for a non-finite gap.
class RigidStop final : public ContactLaw {
 public:
  explicit RigidStop(double gap);
  [[nodiscard]] double force(double u) const override;
  [[nodiscard]] double stiffness(double u) const override;
  [[nodiscard]] double potential(double /*u*/) const override { return 0.0; }
  [[nodiscard]] double gap() const override { return gap_; }
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] bool rigid() const override { return true; }

 private:
  double gap_;
};

}  // namespace wbm::contact
