#include <wbm/contact/jenkins_disc.hpp>

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/LU>

namespace wbm::contact {

namespace {

// One period of the return map from the state (f_start, w_start) before sample 0.
struct Period {
  Eigen::MatrixXd force;              // 2 × Q
  std::vector<Eigen::Matrix2d> p;     // P_q, the derivative of the projection at q
  std::vector<Eigen::Vector2d> n;     // n_q in slip, 0 in stick
  Eigen::VectorXd margin;             // F_s,q − |f*_q|
  Eigen::Matrix2d derivative;         // ∂Φ/∂f_start = P_{Q−1} ⋯ P_0
  int slips = 0;
};

Period run_period(double kt, const Eigen::Ref<const Eigen::MatrixXd>& w, const Eigen::Ref<const Eigen::VectorXd>& fs,
                  const Eigen::Vector2d& f_start, const Eigen::Vector2d& w_start) {
  const Eigen::Index q_count = w.cols();
  Period out;
  out.force.resize(2, q_count);
  out.p.resize(static_cast<size_t>(q_count));
  out.n.resize(static_cast<size_t>(q_count));
  out.margin.resize(q_count);
  out.derivative.setIdentity();
  // The elastic predictor from the last slip (or the start), f_a + k_t (w_q − w_a), not
  // accumulated sample by sample: rounding does not drift along a long stick (jenkins_loop).
  Eigen::Vector2d f_anchor = f_start, w_anchor = w_start;
  for (Eigen::Index q = 0; q < q_count; ++q) {
    const Eigen::Vector2d trial = f_anchor + kt * (w.col(q) - w_anchor);
    const double size = trial.norm();
    out.margin(q) = fs(q) - size;
    auto& pq = out.p[static_cast<size_t>(q)];
    auto& nq = out.n[static_cast<size_t>(q)];
    if (size <= fs(q)) {  // stick (the tie too, as jenkins_loop)
      out.force.col(q) = trial;
      pq.setIdentity();
      nq.setZero();
    } else {
      nq = trial / size;
      out.force.col(q) = fs(q) * nq;
      pq = (fs(q) / size) * (Eigen::Matrix2d::Identity() - nq * nq.transpose());
      f_anchor = out.force.col(q);
      w_anchor = w.col(q);
      ++out.slips;
    }
    out.derivative = pq * out.derivative;
  }
  return out;
}

void validate(double kt, const Eigen::Ref<const Eigen::MatrixXd>& w, const Eigen::Ref<const Eigen::VectorXd>& fs,
              int max_periods, const Eigen::Vector2d& shift) {
  if (!(kt > 0.0) || !std::isfinite(kt)) {
    std::ostringstream m;
    m << "jenkins_disc_loop: tangential_stiffness (k_t) = " << kt << " must be finite and > 0 [N/m]";
    throw std::invalid_argument(m.str());
  }
  if (w.rows() != 2 || w.cols() == 0) {
    throw std::invalid_argument("jenkins_disc_loop: w is " + std::to_string(w.rows()) + " x " +
                                std::to_string(w.cols()) + "; give 2 rows (the tangents) and Q > 0 samples");
  }
  if (fs.size() != w.cols()) {
    throw std::invalid_argument("jenkins_disc_loop: slip_force has " + std::to_string(fs.size()) + " samples, w " +
                                std::to_string(w.cols()) + "; give one slip force per sample (a constant load repeated)");
  }
  if (max_periods < 2) {
    throw std::invalid_argument("jenkins_disc_loop: max_periods = " + std::to_string(max_periods) + " must be >= 2");
  }
  if (!shift.allFinite()) {
    throw std::invalid_argument("jenkins_disc_loop: period_shift is not finite; give the change of w over one "
                                "period [m] (0: periodic)");
  }
  for (Eigen::Index q = 0; q < w.cols(); ++q) {
    if (!w.col(q).allFinite()) {
      throw std::invalid_argument("jenkins_disc_loop: w[:, " + std::to_string(q) + "] is not finite");
    }
    if (!(fs(q) >= 0.0) || !std::isfinite(fs(q))) {
      std::ostringstream m;
      m << "jenkins_disc_loop: slip_force[" << q << "] = " << fs(q) << " must be finite and >= 0 [N] (mu N, N >= 0)";
      throw std::invalid_argument(m.str());
    }
  }
}

// The columns of T, the response of f to a term v_r added at sample r through the cyclic
// recurrence δf_q = P_q δf_{q−1} + v_q (header): T_{q,r} = [r ≤ q] Φ_{q,r} + Ψ_q X Φ_{Q−1,r},
// X = (I − Ψ_{Q−1})⁻¹, one block column (2Q × 2, tangent-major rows) at a time.
class CyclicResponse {
 public:
  explicit CyclicResponse(const Period& period) : p_(period.p), q_(static_cast<Eigen::Index>(period.p.size())) {
    psi_.resize(static_cast<size_t>(q_));
    tail_.resize(static_cast<size_t>(q_));
    Eigen::Matrix2d acc = Eigen::Matrix2d::Identity();
    for (Eigen::Index q = 0; q < q_; ++q) psi_[static_cast<size_t>(q)] = acc = p_[static_cast<size_t>(q)] * acc;
    tail_[static_cast<size_t>(q_ - 1)].setIdentity();  // Φ_{Q−1,r} = P_{Q−1} ⋯ P_{r+1}
    for (Eigen::Index r = q_ - 2; r >= 0; --r) {
      tail_[static_cast<size_t>(r)] = tail_[static_cast<size_t>(r + 1)] * p_[static_cast<size_t>(r + 1)];
    }
    closure_ = (Eigen::Matrix2d::Identity() - psi_.back()).inverse();
  }
  // T_{:,r}, 2Q × 2.
  [[nodiscard]] Eigen::MatrixXd column(Eigen::Index r) const {
    Eigen::MatrixXd t(2 * q_, 2);
    const Eigen::Matrix2d wrap = closure_ * tail_[static_cast<size_t>(r)];
    Eigen::Matrix2d forward = Eigen::Matrix2d::Identity();  // Φ_{q,r}
    for (Eigen::Index q = 0; q < q_; ++q) {
      Eigen::Matrix2d block = psi_[static_cast<size_t>(q)] * wrap;
      if (q > r) forward = p_[static_cast<size_t>(q)] * forward;
      if (q >= r) block += forward;
      t.row(q) = block.row(0);
      t.row(q_ + q) = block.row(1);
    }
    return t;
  }

 private:
  const std::vector<Eigen::Matrix2d>& p_;
  Eigen::Index q_;
  std::vector<Eigen::Matrix2d> psi_, tail_;
  Eigen::Matrix2d closure_;
};

}  // namespace

JenkinsDiscLoop jenkins_disc_loop(double tangential_stiffness, const Eigen::Ref<const Eigen::MatrixXd>& w,
                                  const Eigen::Ref<const Eigen::VectorXd>& slip_force, int max_periods,
                                  const Eigen::Vector2d& period_shift, bool derivatives) {
  const double kt = tangential_stiffness;
  validate(kt, w, slip_force, max_periods, period_shift);
  const Eigen::Index q_count = w.cols();
  const Eigen::Vector2d w_before = w.col(q_count - 1) - period_shift;  // w_{−1}, in this period's frame
  // Stop within 16 roundings of the force scale (the predictor's rounding, as jenkins_loop).
  constexpr double kUlps = 16.0;
  const double scale =
      std::max(slip_force.maxCoeff(), kt * (w.cwiseAbs().maxCoeff() + period_shift.cwiseAbs().maxCoeff()));
  const double tolerance = kUlps * std::numeric_limits<double>::epsilon() * scale;
  // The first period from the unstretched spring at w = 0; then the fixed point f = Φ(f).
  Period first = run_period(kt, w, slip_force, Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero());
  Eigen::Vector2d x = first.force.col(q_count - 1);
  Period at_x = run_period(kt, w, slip_force, x, w_before);
  int periods = 2;
  double residual = (at_x.force.col(q_count - 1) - x).norm();
  while (residual > tolerance) {
    if (periods >= max_periods) {
      std::ostringstream m;
      m << "jenkins_disc_loop: the force at the period's end has not repeated after " << periods
        << " period evaluations (|Phi(f) - f| = " << residual << " N against " << tolerance
        << " N); raise max_periods";
      throw std::runtime_error(m.str());
    }
    if (at_x.slips == 0) {
      // No slip under a slide δ ≠ 0: Φ is the translation by d = k_t δ, and Newton has no
      // derivative to use. Jump to the first period whose predictor leaves a disc: the larger
      // root m of |g_q + m d| = F_s,q, g_q the predictor of this period.
      const Eigen::Vector2d d = kt * period_shift;
      double jump = std::numeric_limits<double>::infinity();
      for (Eigen::Index q = 0; q < q_count; ++q) {
        const Eigen::Vector2d g = x + kt * (w.col(q) - w_before);
        const double gd = g.dot(d), dd = d.squaredNorm();
        const double root = (-gd + std::sqrt(std::max(0.0, gd * gd - dd * (g.squaredNorm() - slip_force(q) *
                                                                                           slip_force(q))))) / dd;
        jump = std::min(jump, root);
      }
      x += (std::floor(std::max(jump - 1.0, 0.0)) + 1.0) * d;  // lands on the first slipping period, or before
      at_x = run_period(kt, w, slip_force, x, w_before);
      ++periods;
      residual = (at_x.force.col(q_count - 1) - x).norm();
      continue;
    }
    const Eigen::Vector2d y = at_x.force.col(q_count - 1);
    // Newton on f = Φ(f), kept only where it lowers the residual; else the plain iterate y,
    // whose residual is never larger (Φ is 1-Lipschitz).
    const Eigen::Matrix2d a = Eigen::Matrix2d::Identity() - at_x.derivative;
    bool stepped = false;
    if (std::abs(a.determinant()) > 1e-12) {
      const Eigen::Vector2d c = x + a.inverse() * (y - x);
      Period at_c = run_period(kt, w, slip_force, c, w_before);
      ++periods;
      const double rc = (at_c.force.col(q_count - 1) - c).norm();
      if (rc < residual) {
        x = c;
        at_x = std::move(at_c);
        residual = rc;
        stepped = true;
      }
    }
    if (!stepped) {
      Period at_y = run_period(kt, w, slip_force, y, w_before);
      ++periods;
      residual = (at_y.force.col(q_count - 1) - y).norm();
      x = y;
      at_x = std::move(at_y);
    }
  }
  JenkinsDiscLoop out;
  out.force = at_x.force;
  out.margin = at_x.margin;
  out.slipping_samples = at_x.slips;
  out.periods = periods;
  // The slider's work: Δs_q = Δw_q − Δf_q/k_t at slip samples (jenkins_loop's rule for f̄).
  for (Eigen::Index q = 0; q < q_count; ++q) {
    if (at_x.n[static_cast<size_t>(q)].isZero()) continue;
    const Eigen::Vector2d w_prev = q > 0 ? Eigen::Vector2d(w.col(q - 1)) : w_before;
    const Eigen::Vector2d f_prev = q > 0 ? Eigen::Vector2d(out.force.col(q - 1)) : x;
    const bool after_slip = q > 0 ? !at_x.n[static_cast<size_t>(q - 1)].isZero() : !at_x.n.back().isZero();
    const Eigen::Vector2d slide = (w.col(q) - w_prev) - (out.force.col(q) - f_prev) / kt;
    const Eigen::Vector2d mean = after_slip ? Eigen::Vector2d(0.5 * (out.force.col(q) + f_prev))
                                            : Eigen::Vector2d(out.force.col(q));
    out.dissipated_energy += mean.dot(slide);
  }
  if (!derivatives) return out;
  out.jacobian = Eigen::MatrixXd::Zero(2 * q_count, 2 * q_count);
  out.load_jacobian = Eigen::MatrixXd::Zero(2 * q_count, q_count);
  if (at_x.slips == 0) {  // full stick: the slider held, f = k_t w (+ its constant offset)
    out.jacobian.diagonal().setConstant(kt);
    return out;
  }
  // ∂f/∂w_s = k_t (T_{:,s} P_s − T_{:,s+1} P_{s+1}) (w_{−1} = w_{Q−1}: s + 1 wraps to 0);
  // ∂f/∂F_s,s = T_{:,s} n_s. T's columns one at a time: O(Q) memory beside the result.
  const CyclicResponse t(at_x);
  const Eigen::MatrixXd first_column = t.column(0);
  Eigen::MatrixXd here = first_column;
  for (Eigen::Index s = 0; s < q_count; ++s) {
    const Eigen::Index next = s + 1 < q_count ? s + 1 : 0;
    const Eigen::MatrixXd after = next == 0 ? first_column : t.column(next);
    const Eigen::MatrixXd block =
        kt * (here * at_x.p[static_cast<size_t>(s)] - after * at_x.p[static_cast<size_t>(next)]);  // 2Q × 2
    out.jacobian.col(s) = block.col(0);
    out.jacobian.col(q_count + s) = block.col(1);
    if (const Eigen::Vector2d& ns = at_x.n[static_cast<size_t>(s)]; !ns.isZero()) out.load_jacobian.col(s) = here * ns;
    here = after;
  }
  return out;
}

JenkinsDiscLaw::JenkinsDiscLaw(const JenkinsParameters& parameters) : p_(parameters) { p_.validate(); }

namespace {
[[noreturn]] void no_function_of_u(const JenkinsDiscLaw& law, const char* what) {
  throw std::logic_error(std::string("JenkinsDiscLaw::") + what + ": a " + law.describe() +
                         " has no function of u; its force depends on both tangents over the period (loop)");
}
}  // namespace

double JenkinsDiscLaw::force(double /*u*/) const { no_function_of_u(*this, "force"); }
double JenkinsDiscLaw::stiffness(double /*u*/) const { no_function_of_u(*this, "stiffness"); }
double JenkinsDiscLaw::potential(double /*u*/) const { no_function_of_u(*this, "potential"); }

std::string JenkinsDiscLaw::describe() const {
  std::ostringstream m;
  m << "Jenkins element with two tangents (isotropic disc) k_t = " << p_.tangential_stiffness << " N/m, mu = "
    << p_.friction_coefficient << ", N = " << p_.normal_load << " N";
  return m.str();
}

void JenkinsDiscLaw::evaluate_period(const Eigen::Ref<const Eigen::VectorXd>& /*u*/, Eigen::Ref<Eigen::VectorXd> /*force*/,
                                     Eigen::Ref<Eigen::VectorXd> /*stiffness*/, Eigen::Ref<Eigen::VectorXi> /*anchor*/,
                                     double /*period_shift*/) const {
  throw std::logic_error("JenkinsDiscLaw::evaluate_period: the force along one tangent of a " + describe() +
                         " depends on both; evaluate loop() on the two tangents' samples "
                         "(solvers::evaluate_contact_period does)");
}

void JenkinsDiscLaw::evaluate_period_loaded(const Eigen::Ref<const Eigen::VectorXd>& u,
                                            const Eigen::Ref<const Eigen::VectorXd>& /*normal*/,
                                            Eigen::Ref<Eigen::VectorXd> force, Eigen::Ref<Eigen::VectorXd> stiffness,
                                            Eigen::Ref<Eigen::VectorXi> anchor,
                                            Eigen::Ref<Eigen::VectorXd> /*load_sensitivity*/,
                                            double period_shift) const {
  evaluate_period(u, force, stiffness, anchor, period_shift);
}

JenkinsDiscLoop JenkinsDiscLaw::loop(const Eigen::Ref<const Eigen::MatrixXd>& w, const Eigen::VectorXd& normal,
                                     const Eigen::Vector2d& period_shift, bool derivatives) const {
  const double mu = p_.friction_coefficient;
  Eigen::VectorXd fs = Eigen::VectorXd::Constant(w.cols(), mu * p_.normal_load);
  if (normal.size() > 0) {
    if (normal.size() != w.cols()) {
      throw std::invalid_argument("JenkinsDiscLaw::loop: normal has " + std::to_string(normal.size()) +
                                  " samples, w " + std::to_string(w.cols()) + "; give one normal force per sample");
    }
    for (Eigen::Index q = 0; q < normal.size(); ++q) {
      if (!(normal(q) >= 0.0) || !std::isfinite(normal(q))) {
        std::ostringstream m;
        m << "JenkinsDiscLaw::loop: normal[" << q << "] = " << normal(q) << " must be finite and >= 0 [N]";
        throw std::invalid_argument(m.str());
      }
    }
    fs.array() += mu * normal.array();
  }
  JenkinsDiscLoop out = jenkins_disc_loop(p_.tangential_stiffness, w, fs, 64, period_shift, derivatives);
  out.load_jacobian *= mu;
  return out;
}

}  // namespace wbm::contact
