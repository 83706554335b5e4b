#pragma once
/// Augmented Lagrangian terms for inequality constraints g_k ≤ 0 and one equality h = 0, with
/// Powell's multiplier and selective penalty updates [LL11 Eqs. (18), (21), (25), (26), Alg. 3;
/// Powell 1978 (ref. [18] of LL11)]. Dimensionless: the caller scales g and h.
///
///   φ(g, h) = ½ Σ_k κ_k (g_k + θ_k)₊² + ½ κ_e (h + θ_e)²                              (18)
/// Multipliers: λ_k = κ_k (g_k + θ_k)₊ ≥ 0 (the contact forces at convergence), μ = κ_e (h + θ_e).
/// Powell's measures (25): G_i = max_k |max(g_k, −θ_k)|, G_e = |h|; converged when both < ε.
/// Update (Alg. 3, after each minimization of the primal problem):
///  - inequalities, if G_i ≥ ε: if G_i did not decrease below the best G_i* so far, the penalty
///    of every constraint still far from satisfied (|max(g_k, −θ_k)| ≥ G_i*/α, Eq. 26a) is
///    multiplied by β and its θ divided by β (the multiplier κθ is kept); otherwise G_i* ← G_i,
///    θ ← θ + max(g, −θ) (Eq. 21a), and if G_i* did not fall below its previous value / α, the
///    penalties of those constraints are multiplied by β;
///  - the equality alike with h, θ_e, κ_e (Eqs. 21b, 26b).
/// The paper's Alg. 3 writes max(g, θ) in Eq. (26a) and max(g, −θ) in line 11; we use −θ (the
/// measure of Eq. 25a) in both.

#include <string>

#include <Eigen/Core>

namespace wbm::contact {

struct PowellParameters {
  double alpha = 4.0;                 // α > 1: required decrease factor of the measures
  double beta = 10.0;                 // β > 1: penalty growth factor
  double tolerance = 1e-8;            // ε: both measures below it is convergence
  double initial_inequality_penalty = 10.0;  // κ_k at the start
  double initial_equality_penalty = 10.0;    // κ_e at the start
  double max_penalty = 1e12;          // penalties are not raised past this
  /// Throws std::invalid_argument naming the field, its value and the range.
  void validate() const;
};

/// What one pass of Alg. 3 found and did. Meeting Powell's measures is necessary, not sufficient,
/// for a converged level: the caller also verifies its own stationarity residual (LL11 Alg. 2).
struct PowellUpdate {
  double inequality_measure = 0.0;  // G_i of Eq. (25a) at the given g
  double equality_measure = 0.0;    // G_e of Eq. (25b) at the given h
  bool measures_met = false;        // G_i < ε and G_e < ε (Alg. 3 l. 6): nothing was changed
  int multiplier_updates = 0;       // groups (inequalities, equality) whose θ moved by Eq. (21): 0, 1 or 2
  int penalties_raised = 0;         // penalties multiplied by β (Eq. 26), inequalities and equality
  int penalties_capped = 0;         // raises refused because κβ would exceed max_penalty
};

class AugmentedLagrangian {
 public:
  /// `inequalities` constraints g_k ≤ 0 and one equality; multipliers start at zero.
  AugmentedLagrangian(int inequalities, PowellParameters parameters = {});

  /// Starts from known multipliers λ ≥ 0 (one per inequality) and μ: θ = λ/κ, θ_e = μ/κ_e, e.g.
  /// those of a neighbouring solution. Throws std::invalid_argument on a size mismatch.
  void warm_start(const Eigen::VectorXd& multipliers, double equality_multiplier);

  /// φ(g, h) of Eq. (18).
  [[nodiscard]] double value(const Eigen::VectorXd& g, double h) const;
  /// ∂φ/∂g = κ (g + θ)₊ (the multipliers λ), ∂φ/∂h = κ_e (h + θ_e).
  [[nodiscard]] Eigen::VectorXd inequality_gradient(const Eigen::VectorXd& g) const;
  [[nodiscard]] double equality_gradient(double h) const;
  /// ∂²φ/∂g² (diagonal): κ_k where g_k + θ_k > 0, else 0; ∂²φ/∂h² = κ_e.
  [[nodiscard]] Eigen::VectorXd inequality_curvature(const Eigen::VectorXd& g) const;
  [[nodiscard]] double equality_curvature() const { return kappa_e_; }

  /// Powell's measures (25).
  [[nodiscard]] double inequality_measure(const Eigen::VectorXd& g) const;
  [[nodiscard]] static double equality_measure(double h) { return h < 0 ? -h : h; }
  /// One pass of Alg. 3 lines 4–33 at the primal solution's (g, h). When both measures are below
  /// ε (measures_met) nothing is changed; otherwise the multipliers and penalties of the group(s)
  /// still violated are updated as described above. The report says which of these happened.
  PowellUpdate update(const Eigen::VectorXd& g, double h);

  [[nodiscard]] const Eigen::VectorXd& inequality_penalties() const { return kappa_; }
  [[nodiscard]] double equality_penalty() const { return kappa_e_; }
  [[nodiscard]] const Eigen::VectorXd& inequality_shifts() const { return theta_; }
  [[nodiscard]] double equality_shift() const { return theta_e_; }
  [[nodiscard]] const PowellParameters& parameters() const { return p_; }

 private:
  PowellParameters p_;
  Eigen::VectorXd kappa_, theta_;
  double kappa_e_, theta_e_ = 0.0;
  double best_i_, previous_best_i_, best_e_, previous_best_e_;  // G*^{(j)}, G*^{(j−1)}
};

}  // namespace wbm::contact
