// Friction beyond the papers (issue #36): a 1-DOF friction damper, m ẍ + c ẋ + k x + f_J = P cos ωt
// with a Jenkins element f_J (tangential spring k_t in series with a Coulomb slider of slip force
// F0 = μN), by every trial:weighting pair of [JL14 Table 2] in the distributional form, each
// solved along k_t = 1e2, 1e3, 1e4 k by warm starts. The references are computed here and share
// no code with the weighted residual: Den Hartog's closed form for continuous Coulomb motion
// [Den Hartog, Phil. Mag. (7) 9 (1930) 801–817], and the event-driven integration, in closed
// form phase by phase, of the same oscillator with Coulomb's law or with the Jenkins element at
// the same k_t (common/coulomb_oscillator.hpp).
//  (a) Den Hartog's frequency response: undamped, F0/P = 0.2, r = ω/ω_n from 0.6 to 3: each
//      pair against his closed form (the element's error and the basis' together) and against
//      the exact Jenkins motion at the same k_t (the basis' error alone); the order in 1/k_t.
//  (b) Stick plateaus: ζ = 2 %, F0/P = 0.5, r = 0.4, a motion that sticks about a third of the
//      period (nearly flat plateaus of x, the friction analogue of the contact plateaus of [JL14
//      Sec. 5.3]), k_t = 1e4 k, M = 16 … 512, against the exact Jenkins motion: do Haar trial
//      functions capture stick better than harmonic balance?
// ~2 min. Writes out/friction_den_hartog/{reference,frf,stick,history}.csv, meta.json, report.md.
// --quick: r = 0.75 and 1.5, M = 32, Q = 512, k_t ≤ 1e3 k; (b) M = 16, 32.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>

#include <wbm/contact/friction.hpp>
#include <wbm/solvers/post_processing.hpp>

#include "combinations.hpp"
#include "coulomb_oscillator.hpp"

namespace {
using namespace wbm;
using namespace wbm::reproduce;
constexpr double kPi = std::numbers::pi;

// m = 1 kg, f_n = 10 Hz, P = 1 N (common/coulomb_oscillator.hpp: friction_damper).
const CoulombOscillator kDamper = friction_damper(0.0, 0.0, 1.0);
const double kMass = kDamper.mass, kNaturalHz = kDamper.frequency_hz, kForce = kDamper.force_amplitude,
             kStiffness = kDamper.stiffness;

CoulombOscillator oscillator(double zeta, double slip_force, double r) { return friction_damper(zeta, slip_force, r); }

// One weighted-residual solve of the oscillator with a Jenkins element k_t = ratio · k by direct
// Newton from the contact unknowns x0; the displacement at `tau`.
struct FrictionSolve {
  solvers::WeightedResidualSolution solution;
  Eigen::VectorXd displacement;  // at tau [m], empty unless converged
  [[nodiscard]] bool converged() const { return solution.converged(); }
  // The contact unknowns: the contact DOF's coefficients (one contact along the only DOF).
  [[nodiscard]] Eigen::VectorXd unknowns() const { return solution.coefficients.row(0).transpose(); }
};
solvers::MechanicalSystem system_of(const CoulombOscillator& o) { return oscillator_system(o); }
FrictionSolve solve(const CoulombOscillator& o, double ratio, const Combination& c, int m, int samples,
                    const Eigen::VectorXd& tau, const Eigen::VectorXd* x0) {
  const auto law = std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{ratio * o.stiffness, o.slip_force, 1.0});
  const auto trial = solvers::TimeBasis::from_name(c.trial, m), weighting = solvers::TimeBasis::from_name(c.weighting, m);
  const solvers::WeightedResidual w(system_of(o), {0, o.force_amplitude, o.frequency_hz}, {{0, law}}, trial, weighting,
                                    {.formulation = kFigureFormulation, .time_samples = samples});
  FrictionSolve out;
  out.solution = w.solve(x0);
  if (out.converged()) out.displacement = trial.values(tau, 0) * out.solution.coefficients.row(0).transpose();
  return out;
}

// Solves along the ascending tangential stiffnesses `ratios` (× k) by direct Newton, the first
// from the frictionless response (as solve() starts), each next one from the one before: a continuation in k_t by warm starts, the
// way a user stiffens a contact. The series stops at the first solve that fails (the returned
// vector is then shorter than `ratios`). Direct Newton only, so that the cost stays bounded:
// solve()'s fallbacks (the contact homotopy, then load stepping) take minutes on stick–slip when
// they fail.
std::vector<FrictionSolve> stiffness_series(const CoulombOscillator& o, const std::vector<double>& ratios,
                                            const Combination& c, int m, int samples, const Eigen::VectorXd& tau) {
  std::vector<FrictionSolve> out;
  const auto trial = solvers::TimeBasis::from_name(c.trial, m), weighting = solvers::TimeBasis::from_name(c.weighting, m);
  const auto linear = solvers::solve_weighted_residual(system_of(o), {0, o.force_amplitude, o.frequency_hz}, {}, trial,
                                                       weighting, {.formulation = kFigureFormulation, .time_samples = samples});
  if (!linear.converged()) {  // G itself is singular: the status and message say why
    out.push_back({linear, {}});
    return out;
  }
  Eigen::VectorXd x0 = linear.coefficients.row(0).transpose();
  for (double ratio : ratios) {
    out.push_back(solve(o, ratio, c, m, samples, tau, &x0));
    if (!out.back().converged()) break;
    x0 = out.back().unknowns();
  }
  return out;
}

// The largest spread max − min of u over one stick interval of the reference (cyclic runs of
// `stuck`), over the amplitude max |u_ref|: 0 for a perfectly flat plateau.
double plateau_spread(const Eigen::VectorXd& u, const Eigen::VectorXd& reference, const std::vector<bool>& stuck) {
  const auto n = static_cast<Eigen::Index>(stuck.size());
  Eigen::Index start = 0;
  while (start < n && stuck[static_cast<size_t>(start)]) ++start;  // a slip sample: runs begin after it
  if (start == n) return NAN;
  double worst = 0.0, lo = INFINITY, hi = -INFINITY;
  for (Eigen::Index i = 1; i <= n; ++i) {
    const Eigen::Index q = (start + i) % n;
    if (stuck[static_cast<size_t>(q)]) {
      lo = std::min(lo, u(q));
      hi = std::max(hi, u(q));
    } else if (hi >= lo) {
      worst = std::max(worst, hi - lo);
      lo = INFINITY, hi = -INFINITY;
    }
  }
  return worst / reference.cwiseAbs().maxCoeff();
}

}  // namespace

int main(int argc, char** argv) {
  auto run = Run::from_args(argc, argv, "friction_den_hartog");
  return run.execute([](Run& run) {
    const bool quick = run.quick();
    const auto& combos = table2_combinations();
    const int samples = quick ? 512 : 4096;  // Q, and the references' samples
    const std::vector<double> kts = quick ? std::vector<double>{1e2, 1e3} : std::vector<double>{1e2, 1e3, 1e4};  // × k
    const double kt_top = kts.back();
    nlohmann::json meta = {{"formulation", std::string(solvers::to_string(kFigureFormulation))},
                           {"mass_kg", kMass}, {"natural_frequency_hz", kNaturalHz}, {"force_N", kForce},
                           {"stiffness_N_per_m", kStiffness}, {"time_samples", samples}, {"kt_over_k", kts}};
    auto status_text = [](const std::vector<FrictionSolve>& series, size_t i) {
      return i < series.size() ? std::string(solvers::to_string(series[i].solution.report.status))
                               : std::string("not run: a softer k_t failed");
    };

    // (a) Den Hartog's frequency response.
    constexpr double kSlipA = 0.2, kFrfTolerance = 1e-2, kOrderTolerance = 0.15;
    // The claims' tolerances (reported as used): the two references against each other; the weighted
    // residual against the exact stick–slip motion at the softest and the stiffest k_t.
    constexpr double kReferenceTolerance = 1e-9, kSoftTolerance = 1e-4, kStiffTolerance = 1e-2;
    const std::vector<double> ratios = quick ? std::vector<double>{0.75, 1.5}
                                             : std::vector<double>{0.6, 0.7, 0.8, 0.9, 0.95, 1.05, 1.1, 1.25, 1.5, 2.0, 3.0};
    const int m_a = quick ? 32 : 256;
    std::vector<double> ref_r, ref_kt, ref_dh, ref_amp, ref_err, ref_stick;
    std::vector<std::vector<double>> jenkins_amplitude(ratios.size());  // [r][k_t] exact
    double coulomb_vs_den_hartog = 0.0, coulomb_stick = 0.0;
    std::vector<double> reference_orders;
    for (size_t i = 0; i < ratios.size(); ++i) {
      auto o = oscillator(0.0, kSlipA, ratios[i]);
      const double dh = den_hartog_amplitude(o);
      std::vector<double> errs;
      for (size_t j = 0; j <= kts.size(); ++j) {  // j = 0: Coulomb; then each k_t
        o.tangential_stiffness = j == 0 ? INFINITY : kts[j - 1] * kStiffness;
        const auto s = coulomb_steady_state(o, 64);
        if (!s.periodic) run.fail("event-driven reference at r = " + format("%g", ratios[i]) + ": " + s.message);
        const double err = std::abs(s.amplitude / dh - 1.0);
        ref_r.push_back(ratios[i]), ref_kt.push_back(j == 0 ? 0.0 : kts[j - 1]), ref_dh.push_back(dh);
        ref_amp.push_back(s.amplitude), ref_err.push_back(err), ref_stick.push_back(s.stick_fraction);
        if (j == 0) {
          coulomb_vs_den_hartog = std::max(coulomb_vs_den_hartog, std::isfinite(err) ? err : INFINITY);
          coulomb_stick = std::max(coulomb_stick, s.stick_fraction);
        } else {
          jenkins_amplitude[i].push_back(s.amplitude);
          errs.push_back(err);
        }
      }
      reference_orders.push_back(-loglog_slope(kts, errs));
    }
    // kt_over_k = 0 marks Coulomb's law (k_t = ∞, which a CSV cannot hold).
    run.table("reference.csv", {"r [-]", "kt_over_k [-]", "den_hartog [m]", "amplitude [m]", "relative_difference [-]",
                                "stick_fraction [-]"},
              {as_column(ref_r), as_column(ref_kt), as_column(ref_dh), as_column(ref_amp), as_column(ref_err), as_column(ref_stick)});

    const Eigen::VectorXd fine = Eigen::VectorXd::LinSpaced(8192, 0.0, 1.0 - 1.0 / 8192);
    std::vector<double> frf_c, frf_r, frf_kt, frf_a, frf_dh, frf_exact, frf_err, frf_disc, frf_it;
    std::vector<std::string> frf_status;
    std::vector<double> worst_dh(combos.size(), 0.0), worst_disc(combos.size(), 0.0);
    std::vector<double> order_lo(combos.size(), INFINITY), order_hi(combos.size(), -INFINITY);
    std::vector<bool> singular(combos.size(), true);  // G singular at every r (the undamped Haar pairs)
    for (size_t ci = 0; ci < combos.size(); ++ci) {
      for (size_t i = 0; i < ratios.size(); ++i) {
        const auto o = oscillator(0.0, kSlipA, ratios[i]);
        const double dh = den_hartog_amplitude(o);
        const auto series = stiffness_series(o, kts, combos[ci], m_a, samples, fine);
        if (series.front().solution.report.status != solvers::SolveStatus::SingularJacobian) singular[ci] = false;
        std::vector<double> errs;
        for (size_t j = 0; j < kts.size(); ++j) {
          const bool ok = j < series.size() && series[j].converged();
          const double amplitude = ok ? series[j].displacement.cwiseAbs().maxCoeff() : NAN;
          const double exact = jenkins_amplitude[i][j];
          errs.push_back(std::abs(amplitude / dh - 1.0));
          frf_c.push_back(static_cast<double>(ci)), frf_r.push_back(ratios[i]), frf_kt.push_back(kts[j]);
          frf_a.push_back(amplitude), frf_dh.push_back(dh), frf_exact.push_back(exact);
          frf_err.push_back(errs.back()), frf_disc.push_back(std::abs(amplitude / exact - 1.0));
          frf_it.push_back(j < series.size() ? series[j].solution.report.iterations : 0);
          frf_status.push_back(status_text(series, j));
          if (j + 1 == kts.size()) {
            worst_dh[ci] = std::max(worst_dh[ci], ok ? errs.back() : INFINITY);
            worst_disc[ci] = std::max(worst_disc[ci], ok ? frf_disc.back() : INFINITY);
          }
        }
        // A missing order (a solve that failed) makes the pair's range missing (NaN, printed —).
        const double order = -loglog_slope(kts, errs);
        order_lo[ci] = std::isfinite(order) ? std::min(order_lo[ci], order) : NAN;
        order_hi[ci] = std::isfinite(order) ? std::max(order_hi[ci], order) : NAN;
      }
    }
    run.table("frf.csv", {"combination [-]", "r [-]", "kt_over_k [-]", "amplitude [m]", "den_hartog [m]",
                          "jenkins_exact [m]", "error_den_hartog [-]", "error_jenkins_exact [-]", "newton_iterations [-]"},
              {as_column(frf_c), as_column(frf_r), as_column(frf_kt), as_column(frf_a), as_column(frf_dh), as_column(frf_exact),
               as_column(frf_err), as_column(frf_disc), as_column(frf_it)},
              frf_status);

    // (b) Stick plateaus against the exact Jenkins motion at each k_t.
    constexpr double kZetaB = 0.02, kSlipB = 0.5, kRB = 0.4;
    auto ob = oscillator(kZetaB, kSlipB, kRB);
    const auto coulomb = coulomb_steady_state(ob, samples);
    if (!coulomb.periodic) run.fail("event-driven Coulomb reference of (b): " + coulomb.message);
    std::vector<CoulombSteadyState> exact_b;
    for (double kt : kts) {
      ob.tangential_stiffness = kt * kStiffness;
      exact_b.push_back(coulomb_steady_state(ob, samples));
      if (!exact_b.back().periodic) run.fail("event-driven Jenkins reference of (b): " + exact_b.back().message);
    }
    const auto& ref = exact_b.back();
    const double jenkins_vs_coulomb = solvers::rms_relative_error(ref.displacement, coulomb.displacement);
    const std::vector<int> dims_b = quick ? std::vector<int>{16, 32} : std::vector<int>{16, 32, 64, 128, 256, 512};
    const int history_m = quick ? 32 : 64;
    std::vector<double> st_c, st_m, st_kt, st_tip, st_stick, st_slip, st_spread, st_coulomb, st_it;
    std::vector<std::string> st_status;
    std::vector<std::string> history_header = {"tau [-]", "coulomb [m]"};
    std::vector<Eigen::VectorXd> history_columns = {ref.tau, coulomb.displacement};
    for (size_t j = 0; j < kts.size(); ++j) {
      history_header.push_back("jenkins_exact_kt" + format("%g", kts[j]) + " [m]");
      history_columns.push_back(exact_b[j].displacement);
    }
    history_header.push_back("stuck [-]");
    history_columns.push_back(Eigen::VectorXd::NullaryExpr(samples, [&](Eigen::Index q) {
      return ref.stuck[static_cast<size_t>(q)] ? 1.0 : 0.0;
    }));
    for (size_t ci = 0; ci < combos.size(); ++ci) {
      for (int m : dims_b) {
        const auto series = stiffness_series(ob, kts, combos[ci], m, samples, ref.tau);
        for (size_t j = 0; j < kts.size(); ++j) {
          const bool ok = j < series.size() && series[j].converged();
          const auto& exact = exact_b[j];
          std::vector<bool> slipping(exact.stuck.size());
          std::transform(exact.stuck.begin(), exact.stuck.end(), slipping.begin(), [](bool b) { return !b; });
          const Eigen::VectorXd u = ok ? series[j].displacement : Eigen::VectorXd();
          st_c.push_back(static_cast<double>(ci)), st_m.push_back(m), st_kt.push_back(kts[j]);
          st_tip.push_back(ok ? solvers::rms_relative_error(u, exact.displacement) : NAN);
          st_stick.push_back(ok ? rms_relative_error_on(u, exact.displacement, exact.stuck) : NAN);
          st_slip.push_back(ok ? rms_relative_error_on(u, exact.displacement, slipping) : NAN);
          st_spread.push_back(ok ? plateau_spread(u, exact.displacement, exact.stuck) : NAN);
          st_coulomb.push_back(ok ? solvers::rms_relative_error(u, coulomb.displacement) : NAN);
          st_it.push_back(j < series.size() ? series[j].solution.report.iterations : 0);
          st_status.push_back(status_text(series, j));
        }
        // The history at the stiffest k_t this pair reached.
        if (m == history_m && !series.empty()) {
          const size_t j = series.back().converged() ? series.size() - 1 : series.size() - 2;
          if (j < series.size()) {
            history_header.push_back(combos[ci].key() + "_kt" + format("%g", kts[j]) + " [m]");
            history_columns.push_back(series[j].displacement);
          }
        }
      }
    }
    run.table("stick.csv", {"combination [-]", "M [-]", "kt_over_k [-]", "error [-]", "stick_error [-]",
                            "slip_error [-]", "plateau_spread [-]", "error_coulomb [-]", "newton_iterations [-]"},
              {as_column(st_c), as_column(st_m), as_column(st_kt), as_column(st_tip), as_column(st_stick), as_column(st_slip),
               as_column(st_spread), as_column(st_coulomb), as_column(st_it)},
              st_status);
    run.table("history.csv", history_header, history_columns);

    // Claims and the report.
    // The row of (combination, M, k_t) in the (b) columns, or −1.
    auto row = [&](size_t ci, int m, double kt) {
      for (size_t i = 0; i < st_c.size(); ++i) {
        if (st_c[i] == static_cast<double>(ci) && st_m[i] == m && st_kt[i] == kt) return static_cast<long>(i);
      }
      return -1L;
    };
    // The stiffest k_t at which (combination, M) converged, or NaN.
    auto stiffest = [&](size_t ci, int m) {
      double best = NAN;
      for (double kt : kts) {
        const long i = row(ci, m, kt);
        if (i >= 0 && std::isfinite(st_tip[static_cast<size_t>(i)])) best = kt;
      }
      return best;
    };
    const int m_top = dims_b.back();
    // Over the pairs whose G is regular (the claims of (a) exclude the singular ones, named).
    std::string excluded;
    for (size_t ci = 0; ci < combos.size(); ++ci) {
      if (singular[ci]) excluded += (excluded.empty() ? "" : ", ") + combos[ci].label();
    }
    const std::string every_pair = excluded.empty() ? "every pair" : "every pair but " + excluded + " (G singular, below)";
    auto worst_of = [&](const std::vector<double>& v, std::string& label) {
      double worst = 0.0;
      for (size_t ci = 0; ci < combos.size(); ++ci) {
        if (singular[ci]) continue;
        if (!(v[ci] <= worst)) worst = v[ci], label = combos[ci].label();
      }
      return worst;
    };
    std::string worst_dh_label, worst_disc_label;
    const double worst_dh_all = worst_of(worst_dh, worst_dh_label), worst_disc_all = worst_of(worst_disc, worst_disc_label);
    const double ref_order_lo = *std::min_element(reference_orders.begin(), reference_orders.end()),
                 ref_order_hi = *std::max_element(reference_orders.begin(), reference_orders.end());
    double pair_order_lo = INFINITY, pair_order_hi = -INFINITY;
    for (size_t ci = 0; ci < combos.size(); ++ci) {
      if (singular[ci]) continue;
      if (std::isnan(order_lo[ci]) || std::isnan(pair_order_lo)) {  // a failed solve: no order to claim
        pair_order_lo = pair_order_hi = NAN;
      } else {
        pair_order_lo = std::min(pair_order_lo, order_lo[ci]), pair_order_hi = std::max(pair_order_hi, order_hi[ci]);
      }
    }
    auto near_half = [&](double o) { return std::isfinite(o) && std::abs(o - 0.5) <= kOrderTolerance; };
    // The smallest error of the exact Jenkins motion itself against Den Hartog at the stiffest k_t.
    double element_error = INFINITY;
    for (size_t i = 0; i < ref_kt.size(); ++i) {
      if (ref_kt[i] == kt_top) element_error = std::min(element_error, ref_err[i]);
    }
    const long fourier_row = row(0, m_top, kt_top);
    const double fourier_tip = fourier_row >= 0 ? st_tip[static_cast<size_t>(fourier_row)] : NAN;
    const long soft_row = row(0, m_top, kts.front());
    const double fourier_soft = soft_row >= 0 ? st_tip[static_cast<size_t>(soft_row)] : NAN;
    // The Haar question at M_top and the stiffest k_t at which Fourier:Fourier and a Haar pair
    // both converged.
    double haar_stick = NAN, fourier_stick = NAN, haar_kt = NAN;
    std::string haar_label = "no Haar pair converged at M = " + std::to_string(m_top);
    for (double kt : kts) {
      const long fi = row(0, m_top, kt);
      if (fi < 0 || !std::isfinite(st_stick[static_cast<size_t>(fi)])) continue;
      for (size_t ci = 0; ci < combos.size(); ++ci) {
        const long hi = row(ci, m_top, kt);
        if (combos[ci].trial != "haar" || hi < 0 || !std::isfinite(st_stick[static_cast<size_t>(hi)])) continue;
        if (!(haar_kt == kt) || st_stick[static_cast<size_t>(hi)] < haar_stick) {
          haar_kt = kt, haar_stick = st_stick[static_cast<size_t>(hi)], haar_label = combos[ci].label();
          fourier_stick = st_stick[static_cast<size_t>(fi)];
        }
      }
    }
    const std::string kt_label = format("%g", kt_top) + " k";
    std::vector<Claim> claims = {
        {"the event-driven Coulomb integration equals Den Hartog's closed form at every r of (a) (two independent "
         "derivations; within " + format("%g", kReferenceTolerance) + "), and the motion has no stops there (stick "
         "fraction 0)",
         coulomb_vs_den_hartog <= kReferenceTolerance && coulomb_stick == 0.0,
         "largest relative difference " + format("%.1e", coulomb_vs_den_hartog) + ", largest stick fraction " +
             format("%.1e", coulomb_stick)},
        {"the exact Jenkins motion tends to Den Hartog's at order 1/2 in 1/k_t (a stick of duration ∝ (F0/k_t)^(1/2) "
         "at each reversal): fitted order within " + format("%g", kOrderTolerance) + " of 0.5 at every r",
         near_half(ref_order_lo) && near_half(ref_order_hi),
         "orders " + format("%.2f", ref_order_lo) + " to " + format("%.2f", ref_order_hi)},
        {every_pair + " at M = " + std::to_string(m_a) + ", k_t = " + kt_label + " gives Den Hartog's amplitude within " +
             format("%g", kFrfTolerance) + " at every r",
         std::isfinite(worst_dh_all) && worst_dh_all <= kFrfTolerance,
         "largest relative error " + format("%.2e", worst_dh_all) + " (" + worst_dh_label + ")"},
        {"the error against Den Hartog is the element's, not the basis': at M = " + std::to_string(m_a) + ", for " +
             every_pair + ", the difference to the exact Jenkins motion at k_t = " + kt_label +
             " is below the smallest difference of that motion to Den Hartog",
         std::isfinite(worst_disc_all) && worst_disc_all < element_error,
         "largest basis error " + format("%.2e", worst_disc_all) + " (" + worst_disc_label + "), smallest element error " +
             format("%.2e", element_error)},
        {"for " + every_pair + ", the error against Den Hartog falls at order 1/2 in 1/k_t, as the exact motion's: "
         "fitted orders within " +
             format("%g", kOrderTolerance) + " of 0.5",
         near_half(pair_order_lo) && near_half(pair_order_hi),
         "orders " + format("%.2f", pair_order_lo) + " to " + format("%.2f", pair_order_hi)},
        {"(b) the weighted residual reproduces the exact stick–slip motion of the soft element: Fourier:Fourier at M = " +
             std::to_string(m_top) + ", k_t = " + format("%g", kts.front()) + " k, within " + format("%g", kSoftTolerance) + " (rms)",
         std::isfinite(fourier_soft) && fourier_soft <= kSoftTolerance, "error " + format("%.2e", fourier_soft)},
        {"(b) Fourier:Fourier at M = " + std::to_string(m_top) + ", k_t = " + kt_label +
             " reproduces the exact stick–slip motion within " + format("%g", kStiffTolerance) + " (rms)",
         std::isfinite(fourier_tip) && fourier_tip <= kStiffTolerance, "error " + format("%.2e", fourier_tip)},
        {"(b) the issue's question, whether Haar trial functions capture stick plateaus better than harmonic balance "
         "(as they give flat contact plateaus [JL14 Sec. 5.3]): the best Haar pair's rms error on the stick samples "
         "below Fourier:Fourier's at M = " + std::to_string(m_top) + ", at the stiffest k_t where both converged",
         std::isfinite(haar_stick) && std::isfinite(fourier_stick) ? std::optional<bool>(haar_stick < fourier_stick)
                                                                    : std::nullopt,
         std::isfinite(haar_stick) ? haar_label + " " + format("%.2e", haar_stick) + ", Fourier:Fourier " +
                                         format("%.2e", fourier_stick) + " at k_t = " + format("%g", haar_kt) + " k"
                                   : haar_label + " (stick.csv gives each status)"}};

    std::ostringstream md;
    md << "## Friction beyond the papers: a 1-DOF damper against Den Hartog, and stick plateaus (issue #36)\n\n"
       << "Files: `out/friction_den_hartog/friction.{png,pdf}`, `reference.csv` (the exact motions; kt_over_k = 0 "
          "is Coulomb's law), `frf.csv`, `stick.csv`, `history.csv`, `meta.json`. m ẍ + c ẋ + k x + f_J = P cos ωt, m = " << format("%g", kMass)
       << " kg, f_n = " << format("%g", kNaturalHz) << " Hz, P = " << format("%g", kForce)
       << " N, f_J a Jenkins element (`law = \"jenkins\"`: a spring k_t in series with a Coulomb slider of slip force "
          "F0 = μN). Every pair of Table 2 in the " << solvers::to_string(kFigureFormulation) << " form, Q = " << samples
       << " midpoint samples, solved along k_t = " << format("%g", kts.front()) << " … " << kt_label
       << " by direct Newton, the first from the frictionless response, each next one from the one before (a series stops at its first "
          "failure; no fallback path, to bound the cost). The references share no code with the weighted "
          "residual: Den Hartog's closed form for continuous Coulomb motion (Phil. Mag. (7) 9 (1930) 801–817; the "
          "issue cites it as 1931), and the event-driven integration of the same oscillator, in closed form phase by "
          "phase, with Coulomb's law or with the Jenkins element at the same k_t "
          "(`reproduce/common/coulomb_oscillator.hpp`).\n\n"
       << "**(a) Frequency response**, undamped, F0/P = " << format("%g", kSlipA / kForce) << ", M = " << m_a << ", r = "
       << format("%g", ratios.front()) << " … " << format("%g", ratios.back()) << " (" << ratios.size()
       << " frequencies). Largest relative error of the amplitude max|x| at k_t = " << kt_label
       << " against Den Hartog and against the exact Jenkins motion, and the fitted order of the error against Den "
          "Hartog in 1/k_t (range over r):\n\n"
       << "| pair | vs Den Hartog | vs exact Jenkins | order in 1/k_t |\n|---|---|---|---|\n";
    for (size_t ci = 0; ci < combos.size(); ++ci) {
      md << "| " << combos[ci].label() << " | " << format("%.2e", std::isfinite(worst_dh[ci]) ? worst_dh[ci] : NAN)
         << " | " << format("%.2e", std::isfinite(worst_disc[ci]) ? worst_disc[ci] : NAN) << " | "
         << format("%.2f", order_lo[ci]) << " to " << format("%.2f", order_hi[ci]) << " |\n";
    }
    double element_worst = 0.0;  // the exact Jenkins motion's own largest error at the stiffest k_t
    for (size_t i = 0; i < ref_kt.size(); ++i) {
      if (ref_kt[i] == kt_top) element_worst = std::max(element_worst, ref_err[i]);
    }
    md << "| exact Jenkins | " << format("%.2e", element_worst) << " | 0 | "
       << format("%.2f", ref_order_lo) << " to " << format("%.2f", ref_order_hi) << " |\n\n"
       << (excluded.empty() ? std::string()
                            : excluded + ": G = f² A_M ⊗ M + A_K ⊗ K is singular without damping at every r (status "
                                         "singular-jacobian in frf.csv).")
       << (excluded.find("Haar:Fourier") == std::string::npos
               ? std::string()
               : std::string(" For Haar:Fourier at M = 2^J the reason is exact: the weighting function cos πMτ "
                             "integrates to zero over every Haar cell, and so does its second derivative, so its row of "
                             "A_M and A_K vanishes; only damping (A_C = −∫ ṗ q ≠ 0) would fill it."))
       << "\n\n"
       << "**(b) Stick plateaus**, ζ = " << format("%g", kZetaB) << ", F0/P = " << format("%g", kSlipB / kForce)
       << ", r = " << format("%g", kRB) << ": at k_t = " << kt_label << " the exact Jenkins motion sticks "
       << format("%.1f", 100.0 * ref.stick_fraction) << " % of the period (Coulomb's "
       << format("%.1f", 100.0 * coulomb.stick_fraction) << " %; the two differ by " << format("%.1e", jenkins_vs_coulomb)
       << " rms). Each cell: at the stiffest k_t the series reached (× k), the relative rms error against the exact "
          "Jenkins motion at that k_t on all samples / on its stick samples / the largest spread of x over one stick "
          "interval over max|x| (the exact motion's at " << kt_label << ": "
       << format("%.1e", plateau_spread(ref.displacement, ref.displacement, ref.stuck)) << "); — where even the "
          "softest k_t failed, with its status:\n\n"
       << dimension_table_header(dims_b);
    for (size_t ci = 0; ci < combos.size(); ++ci) {
      md << "| " << combos[ci].label() << " |";
      for (int m : dims_b) {
        const double kt = stiffest(ci, m);
        if (std::isfinite(kt)) {
          const auto i = static_cast<size_t>(row(ci, m, kt));
          md << " " << format("%.1e", st_tip[i]) << " / " << format("%.1e", st_stick[i]) << " / "
             << format("%.1e", st_spread[i]) << " (" << format("%g", kt) << ") |";
        } else {
          md << " — (" << st_status[static_cast<size_t>(row(ci, m, kts.front()))] << ") |";
        }
      }
      md << "\n";
    }
    md << "\nWhere a pair stops short of " << kt_label << ", direct Newton on the Jenkins residual did not converge from "
          "the softer solution: stick–slip makes the residual piecewise linear with one corner per sample that "
          "switches, and the Newton step crosses many of them. Crossing those corners as events is item 4 of "
          "issue #36, still open.\n";
    md << "\n" << claims_markdown(claims);
    run.report(md.str());
    meta["a"] = {{"slip_force_N", kSlipA}, {"dimension", m_a}, {"ratios", ratios}, {"largest_error_den_hartog", worst_dh},
                 {"largest_error_jenkins_exact", worst_disc}, {"tolerance", kFrfTolerance},
                 {"reference_orders", reference_orders}, {"coulomb_vs_den_hartog", coulomb_vs_den_hartog}};
    meta["b"] = {{"zeta", kZetaB}, {"slip_force_N", kSlipB}, {"r", kRB}, {"stick_fraction", ref.stick_fraction},
                 {"coulomb_stick_fraction", coulomb.stick_fraction}, {"jenkins_vs_coulomb", jenkins_vs_coulomb},
                 {"reference_periods", ref.periods}, {"dimensions", dims_b}, {"history_dimension", history_m}};
    meta["combinations"] = nlohmann::json::array();
    for (const auto& c : combos) meta["combinations"].push_back(c.label());
    run.meta(meta);
  });
}
