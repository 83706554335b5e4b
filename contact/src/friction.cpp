#include <wbm/contact/friction.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace wbm::contact {

JenkinsLoop jenkins_loop(double tangential_stiffness, const Eigen::Ref<const Eigen::VectorXd>& w,
                         const Eigen::Ref<const Eigen::VectorXd>& slip_force, int max_periods, double period_shift,
                         const std::vector<std::uint8_t>* pattern) {
  const double kt = tangential_stiffness;
  if (!(kt > 0.0) || !std::isfinite(kt)) {
    std::ostringstream m;
    m << "jenkins_loop: tangential_stiffness (k_t) = " << kt << " must be finite and > 0 [N/m]";
    throw std::invalid_argument(m.str());
  }
  if (w.size() == 0) throw std::invalid_argument("jenkins_loop: w is empty; give the Q > 0 samples of one period");
  if (slip_force.size() != w.size()) {
    throw std::invalid_argument("jenkins_loop: slip_force has " + std::to_string(slip_force.size()) + " samples, w " +
                                std::to_string(w.size()) + "; give one slip force per sample (a constant load repeated)");
  }
  if (max_periods < 2) throw std::invalid_argument("jenkins_loop: max_periods = " + std::to_string(max_periods) + " must be >= 2");
  if (!std::isfinite(period_shift)) {
    throw std::invalid_argument(
        "jenkins_loop: period_shift is not finite; give the change of w over one period [m] (0: periodic)");
  }
  if (pattern != nullptr && static_cast<Eigen::Index>(pattern->size()) != w.size()) {
    throw std::invalid_argument("jenkins_loop: pattern has " + std::to_string(pattern->size()) + " entries, w " +
                                std::to_string(w.size()) + " samples; give one stick (0) or slip (1) per sample");
  }
  for (Eigen::Index q = 0; q < w.size(); ++q) {
    if (!std::isfinite(w(q))) throw std::invalid_argument("jenkins_loop: w[" + std::to_string(q) + "] is not finite");
    if (!(slip_force(q) >= 0.0) || !std::isfinite(slip_force(q))) {
      std::ostringstream m;
      m << "jenkins_loop: slip_force[" << q << "] = " << slip_force(q) << " must be finite and >= 0 [N] (mu N, N >= 0)";
      throw std::invalid_argument(m.str());
    }
  }
  const Eigen::Index n = w.size();
  JenkinsLoop out;
  out.force.resize(n);
  out.stiffness.resize(n);
  out.anchor.resize(n);
  out.slip_sensitivity.resize(n);
  out.margin.resize(n);
  double f_prev = 0.0, w_prev = 0.0;  // the unstretched spring at w = 0 before sample 0
  // The elastic predictor from the last slip (or from the start), f_a + k_t (w_q − w_a), not
  // accumulated sample by sample, so that rounding does not drift along a long stick.
  double f_anchor = 0.0, w_anchor = 0.0;
  int last_slip = -1;
  double sigma_last = 0.0;
  double previous_end = 0.0, before = 0.0;
  double previous_sigma = 0.0;  // σ of the previous sample if it slipped, else 0
  // The end force repeats when it is within kUlps roundings of the force scale. In exact
  // arithmetic the period map is monotone, so it has no cycle of two periods; in floating point a
  // stick sample whose predictor lies within rounding of F_s can slip in one period and not in the
  // next, and the ends then alternate between two values a few ulps apart (seen on a stick–slip
  // oscillator with DB6: 1.9102933194927472e-06 and 1.9102933194927468e-06 N). Either period is
  // the steady state to rounding; the last one is returned.
  constexpr double kUlps = 16.0;
  const double scale = std::max(slip_force.maxCoeff(), kt * (w.cwiseAbs().maxCoeff() + std::abs(period_shift)));
  for (int period = 1; period <= max_periods; ++period) {
    int first_slip = -1;
    out.slipping_samples = 0;
    out.dissipated_energy = 0.0;
    for (Eigen::Index q = 0; q < n; ++q) {
      const double trial = f_anchor + kt * (w(q) - w_anchor);  // the elastic predictor
      double f = trial;
      double sigma_here = 0.0;  // σ if this sample slips
      out.margin(q) = slip_force(q) - std::abs(trial);
      const bool stick =
          pattern != nullptr ? (*pattern)[static_cast<size_t>(q)] == 0 : std::abs(trial) <= slip_force(q);
      if (stick) {
        out.stiffness(q) = kt;
        out.anchor(q) = last_slip;
        out.slip_sensitivity(q) = last_slip >= 0 ? sigma_last : 0.0;
      } else {  // slip: the projection on |f| <= F_s
        const double sigma = trial > 0.0 ? 1.0 : -1.0;
        sigma_here = sigma;
        f = sigma * slip_force(q);
        out.stiffness(q) = 0.0;
        out.anchor(q) = -1;
        out.slip_sensitivity(q) = sigma;
        // f Δs, Δs the slider's increment: exact at a slip onset for w linear between samples (the
        // slider moves only once f has reached the slip force); along a slip in one direction the
        // slip force may vary (a varying normal load), so the mean ½ (f_q + f_{q−1}) Δs (the same
        // value when it does not vary): second order instead of first.
        const bool slipping_on = previous_sigma == sigma;
        out.dissipated_energy += (slipping_on ? 0.5 * (f + f_prev) : f) * ((w(q) - w_prev) - (f - f_prev) / kt);
        last_slip = static_cast<int>(q);
        sigma_last = sigma;
        f_anchor = f;
        w_anchor = w(q);
        if (first_slip < 0) first_slip = static_cast<int>(q);
        ++out.slipping_samples;
      }
      out.force(q) = f;
      previous_sigma = sigma_here;
      f_prev = f;
      w_prev = w(q);
    }
    out.periods = period;
    if (period >= 2 && std::abs(f_prev - previous_end) <= kUlps * std::numeric_limits<double>::epsilon() * scale) {
      // Periodic: the stick samples before this period's first slip hang on its last slip.
      for (int q = 0; q < first_slip; ++q) {
        out.anchor(q) = last_slip;
        out.slip_sensitivity(q) = sigma_last;
      }
      return out;
    }
    before = previous_end;
    previous_end = f_prev;
    // The next period's samples are w + δ: the state carried into it (the anchor and the last
    // sample, in the coordinates of the samples as given) moves by −δ.
    w_anchor -= period_shift;
    w_prev -= period_shift;
  }
  std::ostringstream m;
  m.precision(17);
  m << "jenkins_loop: the force at the period's end has not repeated after max_periods = " << max_periods
    << " periods (the last two ends: " << before << " N and " << previous_end << " N); raise max_periods";
  throw std::runtime_error(m.str());
}

void JenkinsParameters::validate() const {
  const auto bad = [](const char* field, double value, const char* range) {
    std::ostringstream m;
    m << "JenkinsParameters." << field << " = " << value << ": " << range;
    throw std::invalid_argument(m.str());
  };
  if (!(tangential_stiffness > 0.0) || !std::isfinite(tangential_stiffness)) {
    bad("tangential_stiffness (k_t)", tangential_stiffness, "must be finite and > 0 [N/m]");
  }
  if (!(friction_coefficient >= 0.0) || !std::isfinite(friction_coefficient)) {
    bad("friction_coefficient (mu)", friction_coefficient, "must be finite and >= 0 (0: no friction)");
  }
  if (!(normal_load >= 0.0) || !std::isfinite(normal_load)) {
    bad("normal_load (N)", normal_load, "must be finite and >= 0 [N] (a compressive preload)");
  }
}

JenkinsLaw::JenkinsLaw(const JenkinsParameters& parameters) : p_(parameters) { p_.validate(); }

namespace {
[[noreturn]] void no_function(const char* what) {
  throw std::logic_error(std::string("JenkinsLaw::") + what + ": a Jenkins element is hysteretic; its force depends on the "
                         "history over the period, not on u alone: use evaluate_period()");
}
}  // namespace

double JenkinsLaw::force(double /*u*/) const { no_function("force"); }
double JenkinsLaw::stiffness(double /*u*/) const { no_function("stiffness"); }
double JenkinsLaw::potential(double /*u*/) const { no_function("potential"); }

std::string JenkinsLaw::describe() const {
  std::ostringstream d;
  d << "Jenkins element k_t = " << p_.tangential_stiffness << " N/m, mu = " << p_.friction_coefficient
    << ", N = " << p_.normal_load << " N";
  return d.str();
}

JenkinsLoop JenkinsLaw::loop(const Eigen::Ref<const Eigen::VectorXd>& u, double period_shift,
                             const std::vector<std::uint8_t>* pattern) const {
  return jenkins_loop(p_.tangential_stiffness, u, Eigen::VectorXd::Constant(u.size(), slip_force()), 8, period_shift,
                      pattern);
}

JenkinsLoop JenkinsLaw::loop(const Eigen::Ref<const Eigen::VectorXd>& u,
                             const Eigen::Ref<const Eigen::VectorXd>& normal, double period_shift,
                             const std::vector<std::uint8_t>* pattern) const {
  if (normal.size() != u.size()) {
    throw std::invalid_argument("JenkinsLaw::loop: normal has " + std::to_string(normal.size()) + " samples, u " +
                                std::to_string(u.size()) + "; give the normal load at every sample of u");
  }
  for (Eigen::Index q = 0; q < normal.size(); ++q) {
    if (!(normal(q) >= 0.0) || !std::isfinite(normal(q))) {
      std::ostringstream m;
      m << "JenkinsLaw::loop: normal[" << q << "] = " << normal(q)
        << " must be finite and >= 0 [N] (the compressive force of the normal law)";
      throw std::invalid_argument(m.str());
    }
  }
  const Eigen::VectorXd fs = p_.friction_coefficient * (normal.array() + p_.normal_load).matrix();
  return jenkins_loop(p_.tangential_stiffness, u, fs, 8, period_shift, pattern);
}

void JenkinsLaw::evaluate_period_loaded(const Eigen::Ref<const Eigen::VectorXd>& u,
                                        const Eigen::Ref<const Eigen::VectorXd>& normal, Eigen::Ref<Eigen::VectorXd> force,
                                        Eigen::Ref<Eigen::VectorXd> stiffness, Eigen::Ref<Eigen::VectorXi> anchor,
                                        Eigen::Ref<Eigen::VectorXd> load_sensitivity, double period_shift) const {
  if (force.size() != u.size() || stiffness.size() != u.size() || anchor.size() != u.size() ||
      load_sensitivity.size() != u.size()) {
    throw std::invalid_argument("JenkinsLaw::evaluate_period_loaded: force, stiffness, anchor and load_sensitivity "
                                "must have the " + std::to_string(u.size()) + " samples of u");
  }
  const JenkinsLoop l = loop(u, normal, period_shift);
  force = l.force;
  stiffness = l.stiffness;
  anchor = l.anchor;
  load_sensitivity = p_.friction_coefficient * l.slip_sensitivity;
}

void JenkinsLaw::evaluate_period(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> force,
                                 Eigen::Ref<Eigen::VectorXd> stiffness, Eigen::Ref<Eigen::VectorXi> anchor,
                                 double period_shift) const {
  if (force.size() != u.size() || stiffness.size() != u.size() || anchor.size() != u.size()) {
    throw std::invalid_argument("JenkinsLaw::evaluate_period: force, stiffness and anchor must have the " +
                                std::to_string(u.size()) + " samples of u");
  }
  const JenkinsLoop l = loop(u, period_shift);
  force = l.force;
  stiffness = l.stiffness;
  anchor = l.anchor;
}

void CoulombParameters::validate() const {
  const auto bad = [](const char* field, double value, const char* range) {
    std::ostringstream m;
    m << "CoulombParameters." << field << " = " << value << ": " << range;
    throw std::invalid_argument(m.str());
  };
  if (!(friction_coefficient >= 0.0) || !std::isfinite(friction_coefficient)) {
    bad("friction_coefficient (mu)", friction_coefficient, "must be finite and >= 0 (0: no friction)");
  }
  if (!(normal_load >= 0.0) || !std::isfinite(normal_load)) {
    bad("normal_load (N)", normal_load, "must be finite and >= 0 [N] (a compressive preload)");
  }
}

CoulombFriction::CoulombFriction(const CoulombParameters& parameters) : p_(parameters) { p_.validate(); }

double CoulombFriction::force(double /*u*/) const {
  throw std::logic_error("CoulombFriction::force: exact Coulomb friction has no force law f(u); its force is the "
                         "multiplier of the projection equation, computed by the solver (check ContactLaw::rigid() first)");
}

double CoulombFriction::stiffness(double /*u*/) const {
  throw std::logic_error("CoulombFriction::stiffness: exact Coulomb friction has no stiffness (check ContactLaw::rigid() first)");
}

std::string CoulombFriction::describe() const {
  std::ostringstream d;
  d << "Coulomb friction (exact) mu = " << p_.friction_coefficient << ", N = " << p_.normal_load << " N";
  return d.str();
}

}  // namespace wbm::contact
