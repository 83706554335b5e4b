// Beyond the papers (issue #36, items 3 and 8): the reduced compressor blade of ll11_blade rubbing
// an oval casing with friction. The casing's radius is R + δ cos nθ in the engine's frame; the
// blade turns at Ω about the engine axis (x), so each tip node meets a lobe every 2π/(nΩ): the
// response's frequency is f = nΩ/(2π) and a continuation in f is one in the rotation speed. Each
// of the 24 tip nodes has a radial penalty contact (k as ll11_blade_forced) against the casing,
// whose gap moves by s = δ cos(2πτ + nθ_i) (θ_i the node's angle about the axis), and a Jenkins
// element (k_t, μ) along the rotation, its slip force μ times that radial force, against
// the casing sliding back by one lobe, 2πR_i/n, per period (solvers::ContactPoint::obstacle). No
// other load: the casing alone excites the blade. Traced by pseudo-arclength continuation with
// Fourier:Fourier over 0.9 … 1.1 f1, with and without friction. At 0.9 f1, a pseudo-arclength
// continuation in μ from the frictionless solution says which μ of the scan (the issue's 0.15
// among them) has a response connected to it. Where the frictional amplitude is
// largest, the orbit's
// samples check Coulomb's sliding law (a sliding far faster than the vibration keeps every sample
// in slip, f_t = μ f_n against the rotation) and the energy balance over a period (the casing's
// work on the blade = the viscous dissipation; no other load works). Our own blade and parameters
// (reproduce/scenes/friction_oval_casing.toml): LL11 has neither friction nor a moving casing.
// The Floquet multipliers (with the Jenkins elements' force perturbations) of the μ-branch at the
// file's μ and at its end, and of the frictional curve's largest amplitude, say whether those
// orbits are stable and what the μ-branch meets.
// Writes out/friction_oval_casing/{frictionless,friction,orbit}.csv, meta.json, report.md.
// --quick: mesh size 5 mm, H = 3, coarse steps; run by ctest.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <future>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <wbm/contact/friction.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/fem/craig_bampton.hpp>
#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/spectral/layout.hpp>

#include "blade.hpp"
#include "blade_forced.hpp"
#include "combinations.hpp"
#include "parameters.hpp"
#include "run.hpp"

namespace {

using namespace wbm;
using reproduce::Claim;
using reproduce::format;
constexpr double kPi = std::numbers::pi;
// Coulomb's sliding law at the samples, relative to μ max f_n (the slips' forces are ±μ f_n to
// rounding); the energy balance's quadrature (trapezoidal products of P samples across the
// penalty's kinks, second order; measured in the note).
constexpr double kSlidingTolerance = 1e-12, kBalanceTolerance = 1e-3;
constexpr int kSamples = 2048;
// The friction coefficient issue #36 asks for (a Rotor 37 rubbing benchmark's); the continuation
// in μ reports whether it reaches it.
constexpr double kIssueFrictionCoefficient = 0.15;
struct Curve {
  std::string label;
  solvers::ResponseCurve curve;
  double time_s = 0.0;
};

}  // namespace

int main(int argc, char** argv) {
  auto run = reproduce::Run::from_args(argc, argv, "friction_oval_casing");
  return run.execute([](reproduce::Run& run) {
    const auto parameters = reproduce::Parameters::load("friction_oval_casing", run.quick());
    const double gap = parameters.number("contact.gap_m"), zeta = parameters.number("damping.zeta");
    const double mu = parameters.number("contact.friction_coefficient");
    const double delta = parameters.number("casing.ovalization_gaps") * gap;
    const int lobes = parameters.integer("casing.lobes"), harmonics = parameters.integer("response.harmonics");
    const double from = parameters.number("response.from_f1"), to = parameters.number("response.to_f1");
    const models::ScratchFolder scratch("wbm_friction_oval_casing");
    const auto blade =
        models::build_blade(scratch.dir, parameters.number("mesh.size_m"), parameters.integer("interface.tip_nodes"));
    const auto cb = fem::craig_bampton(blade.model.stiffness, blade.model.mass, blade.boundary,
                                       parameters.integer("interface.modes"));
    // The forced model of ll11_blade_forced (scaled coordinates, radial stops, C = β K̂); its load
    // is not used: the casing is the only excitation.
    const auto model = models::blade_forced_model(blade, cb,
                                                  {.gap = gap,
                                                   .zeta = zeta,
                                                   .overload = 1.0,
                                                   .stiffness_ratio = parameters.number("contact.stiffness_ratio"),
                                                   .from_f1 = from,
                                                   .mode_harmonics = 3,
                                                   .mode_samples = 24});
    const double f1 = model.f1, k_pen = model.penalty_stiffness;
    const double k_t = parameters.number("contact.tangential_stiffness_ratio") * k_pen;
    const auto radial_law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{k_pen, gap});
    const auto jenkins = std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{k_t, mu, 0.0});
    const auto nt = static_cast<int>(model.stops.size());
    std::vector<solvers::ContactPoint> radial, rubbing;
    std::vector<double> radius(static_cast<size_t>(nt)), theta(static_cast<size_t>(nt));
    for (int i = 0; i < nt; ++i) {
      // The node in the plane normal to the axis: (y, z + R_hub); it turns towards t = (−(z + R), y)/r.
      const double y = blade.position(i, 1), z = blade.position(i, 2) + models::kHubRadius, r = std::hypot(y, z);
      radius[static_cast<size_t>(i)] = r;
      theta[static_cast<size_t>(i)] = std::atan2(z, y);  // grows along t
      const double phase = lobes * theta[static_cast<size_t>(i)];
      const auto& st = model.stops[static_cast<size_t>(i)];
      radial.push_back({.dof = st.dof,
                        .law = radial_law,
                        .along = st.along,
                        .obstacle = {.cosine = {delta * std::cos(phase)}, .sine = {-delta * std::sin(phase)}}});
    }
    rubbing = radial;
    for (int i = 0; i < nt; ++i) {
      const double y = blade.position(i, 1), z = blade.position(i, 2) + models::kHubRadius,
                   r = radius[static_cast<size_t>(i)];
      const int jy = 3 * i + 1, jz = 3 * i + 2;  // the scaled coordinates of the node's y and z
      rubbing.push_back({.dof = jy,
                         .law = jenkins,
                         .along = {{jy, -z / r * model.scale(jy)}, {jz, y / r * model.scale(jz)}},
                         .normal = i,
                         .obstacle = {.drift = -2.0 * kPi * r / lobes}});
    }
    const solvers::HarmonicForcing casing_only{model.observed, 0.0, from * f1};

    // The frictional start by pseudo-arclength continuation in μ at the start frequency (the
    // continuation layer, through folds): from μ = 0, the frictionless solution (a slider of no
    // force), over [0, the scan's largest μ], landing on each value of the scan, |Δμ| per step at
    // most contact.friction_step.
    const auto scan_basis = solvers::TimeBasis::fourier_harmonics(harmonics);
    // The rubbing contacts with the Jenkins elements' friction coefficient set to μ.
    const auto rubbing_at = [&](double mu_value) {
      auto contacts = rubbing;
      const auto law = std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{k_t, mu_value, 0.0});
      for (int i = nt; i < 2 * nt; ++i) contacts[static_cast<size_t>(i)].law = law;
      return contacts;
    };
    const auto with_friction = [&](double mu_value) {
      return solvers::WeightedResidual(model.reduced, casing_only, rubbing_at(mu_value), scan_basis, scan_basis,
                                       {.formulation = reproduce::kFigureFormulation});
    };
    const solvers::WeightedResidual dry_start(model.reduced, casing_only, radial, scan_basis, scan_basis,
                                              {.formulation = reproduce::kFigureFormulation});
    const auto dry_solution = dry_start.solve();
    if (!dry_solution.converged()) run.fail("frictionless start: " + dry_solution.brief());
    std::vector<double> scan = parameters.numbers("contact.friction_scan");
    std::sort(scan.begin(), scan.end());
    if (scan.empty() || !(scan.front() > 0.0)) run.fail("contact.friction_scan: needs values of μ > 0");
    // The library's continuation in μ: one factorization of G, every Jenkins element at each μ
    // asked for, ∂r/∂μ exact on each stick/slip pattern (ContinuationParameter::FrictionCoefficient).
    const solvers::WeightedResidual mu_problem = with_friction(0.0);
    const solvers::ForcedResponseFamily family(mu_problem, solvers::ContinuationParameter::FrictionCoefficient);
    solvers::PseudoArclengthOptions in_mu;
    in_mu.parameter_min = 0.0;
    in_mu.parameter_max = scan.back();
    in_mu.parameter_scale = scan.back();
    // x̂ = x / its largest start value, so that μ and the state weigh alike in the arclength.
    const Eigen::VectorXd mu_x0 = mu_problem.contact_unknowns(spectral::stacked(dry_solution.coefficients));
    in_mu.state_scale = std::max(mu_x0.lpNorm<Eigen::Infinity>(), dry_start.residual_scale());
    in_mu.initial_step = 2e-2;  // in that scaled metric (the defaults: 1e-2 and 5e-2)
    in_mu.max_step = 1e-1;
    in_mu.max_parameter_step = parameters.number("contact.friction_step");
    in_mu.max_points = parameters.integer("contact.friction_points");
    in_mu.max_state = parameters.number("contact.friction_max_state");
    in_mu.land_on = scan;
    const auto mu_start = std::chrono::steady_clock::now();
    const auto mu_branch = solvers::pseudo_arclength(family, mu_x0, 0.0, in_mu);
    const double mu_time = models::seconds_since(mu_start);
    double mu_largest = 0.0;
    for (const auto& p : mu_branch.points) mu_largest = std::max(mu_largest, p.parameter);
    // Where the state grows without bound, ‖x‖∞ ≈ C/(μ* − μ) near a pole μ*: 1/‖x‖∞ extrapolated
    // linearly to 0 through the branch's last two points.
    double mu_pole = NAN;
    if (mu_branch.points.size() >= 2) {
      const auto& a = mu_branch.points[mu_branch.points.size() - 2];
      const auto& b = mu_branch.points.back();
      const double ia = 1.0 / a.x.lpNorm<Eigen::Infinity>(), ib = 1.0 / b.x.lpNorm<Eigen::Infinity>();
      if (ia > ib) mu_pole = b.parameter + ib * (b.parameter - a.parameter) / (ia - ib);
    }
    const bool unbounded = mu_branch.stop == solvers::StopReason::StateBound && std::isfinite(mu_pole);
    const std::string pole_text = std::isfinite(mu_pole) ? format("%.4g", mu_pole) : std::string("—");
    // Newton at each μ of the scan straight from the frictionless solution (no continuation): the
    // solutions a start there finds, on the branch or off it.
    std::vector<solvers::WeightedResidualSolution> direct;
    for (const double mu_value : scan) direct.push_back(with_friction(mu_value).solve(&mu_x0));
    const double mu_growth = mu_branch.points.empty() ? NAN
                                                      : mu_branch.points.back().x.lpNorm<Eigen::Infinity>() /
                                                            mu_x0.lpNorm<Eigen::Infinity>();
    const std::string growth_text = std::isfinite(mu_growth) ? format("%.3g", mu_growth) : std::string("—");
    std::printf("continuation in mu at %g f1: %s; largest mu %g, %.1f s: %s\n", from, mu_branch.brief().c_str(),
                mu_largest, mu_time, mu_branch.message.c_str());
    // The scan's values the continuation landed on (each a converged point of the branch).
    const auto landing = [&](double mu_value) -> const solvers::BranchPoint* {
      for (const auto& p : mu_branch.landings) {
        if (p.parameter == mu_value) return &p;
      }
      return nullptr;
    };

    // The curves start from the problems of the start scan: frictionless, and at the file's μ.
    const solvers::WeightedResidual wet_start = with_friction(mu);
    std::vector<Curve> curves;
    for (const bool friction : {false, true}) {
      const auto t = std::chrono::steady_clock::now();
      const solvers::WeightedResidual& base = friction ? wet_start : dry_start;
      solvers::ResponseCurveOptions o;
      o.parameter_min = from * f1;
      o.parameter_max = to * f1;
      o.max_parameter_step = parameters.number("response.max_step_f1") * f1;
      o.max_step = parameters.number("response.max_step");
      o.observed_dof = model.observed;
      // Stability at a few orbits below, not at every point: each costs about 9 s (the stiff
      // contacts need 65 536 steps of the monodromy's 2n + 24 states).
      o.stability = false;
      o.max_state = parameters.number("response.max_state");
      for (int j = 0; j < static_cast<int>(model.reduced.mass.rows()); ++j) o.keep_dofs.push_back(j);
      curves.push_back({friction ? "with friction (μ = " + format("%g", mu) + ")" : "frictionless",
                        solvers::trace_response(base, o), models::seconds_since(t)});
      const auto& c = curves.back();
      if (!c.curve.converged()) {
        run.fail(c.label + ": continuation stopped: " + std::string(solvers::to_string(c.curve.stop)) + ", " +
                 c.curve.message);
      }
      std::printf("%s: %zu points, %.1f s, %s\n", c.label.c_str(), c.curve.points.size(), c.time_s,
                  c.curve.message.c_str());
    }

    // Tables: per point f, f/f1, Ω = 2πf/n, the observed (circumferential) amplitude in gaps.
    const auto write_curve = [&](const Curve& c, const std::string& file) {
      const auto np = static_cast<Eigen::Index>(c.curve.points.size());
      Eigen::VectorXd f(np), ratio(np), omega(np), amplitude(np), force(np);
      for (Eigen::Index i = 0; i < np; ++i) {
        const auto& p = c.curve.points[static_cast<size_t>(i)];
        f(i) = p.frequency_hz;
        ratio(i) = p.frequency_hz / f1;
        omega(i) = 2.0 * kPi * p.frequency_hz / lobes;
        amplitude(i) = p.amplitude * model.unit;
        force(i) = p.max_contact_force;
      }
      run.table(
          file,
          {"frequency [Hz]", "f_over_f1 [-]", "rotation_speed [rad/s]", "amplitude [gap]", "max_contact_force [N]"},
          {f, ratio, omega, amplitude, force});
    };
    write_curve(curves[0], "frictionless.csv");
    write_curve(curves[1], "friction.csv");
    const auto peak_of = [](const solvers::ResponseCurve& c) {
      return std::max_element(c.points.begin(), c.points.end(),
                              [](const auto& a, const auto& b) { return a.amplitude < b.amplitude; });
    };
    if (curves[1].curve.points.empty() || curves[0].curve.points.empty()) return;
    const auto dry = peak_of(curves[0].curve), wet = peak_of(curves[1].curve);

    // The orbit where the frictional curve's amplitude is largest, at P samples: every DOF from its
    // trial coefficients.
    const auto basis = solvers::TimeBasis::fourier_harmonics(harmonics);
    const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(kSamples, 0.0, 1.0 - 1.0 / kSamples);
    const Eigen::MatrixXd q = basis.values(tau, 0), dq = basis.values(tau, 1);
    const Eigen::MatrixXd u = wet->kept_coefficients * q.transpose();                         // n × P
    const Eigen::MatrixXd v = wet->frequency_hz * (wet->kept_coefficients * dq.transpose());  // n × P, d/dt
    const auto nc = static_cast<Eigen::Index>(rubbing.size());
    Eigen::MatrixXd displacement(nc, kSamples);  // u_c(τ_p)
    for (Eigen::Index c = 0; c < nc; ++c) {
      for (Eigen::Index p = 0; p < kSamples; ++p) {
        displacement(c, p) = rubbing[static_cast<size_t>(c)].displacement(u.col(p));
      }
    }
    const Eigen::MatrixXd relative = displacement - solvers::obstacle_samples(rubbing, tau);
    Eigen::MatrixXd force(nc, kSamples);
    Eigen::VectorXd fq(kSamples), kq(kSamples), sq(kSamples);
    Eigen::VectorXi anchor(kSamples);
    for (Eigen::Index c = 0; c < nc; ++c) {
      solvers::evaluate_contact_period(rubbing, static_cast<int>(c), relative, fq, kq, anchor, sq);
      force.row(c) = fq.transpose();
    }
    // Coulomb's sliding law, and the stick samples (none expected).
    double sliding = 0.0, normal_max = 0.0;
    int stuck = 0;
    for (int i = 0; i < nt; ++i) {
      for (Eigen::Index p = 0; p < kSamples; ++p) {
        const double fn = force(i, p), ft = force(nt + i, p);
        normal_max = std::max(normal_max, fn);
        sliding = std::max(sliding, std::abs(ft - mu * fn));
      }
    }
    for (Eigen::Index c = nt; c < nc; ++c) {
      solvers::evaluate_contact_period(rubbing, static_cast<int>(c), relative, fq, kq, anchor, sq);
      for (Eigen::Index p = 0; p < kSamples; ++p) stuck += kq(p) != 0.0 ? 1 : 0;
    }
    // The energy balance over the period: the contacts' work on the blade, −Σ_c ∮ f_c du_c (the
    // force pushes along −e_c), against the viscous dissipation ∮ u̇ᵀ C u̇ dt. Both by the periodic
    // trapezoidal rule over the P samples (∮ f du as Σ_p f_p (u_{p+1} − u_{p−1})/2).
    double work = 0.0, viscous = 0.0, friction_work = 0.0;
    const Eigen::MatrixXd cv = model.reduced.damping * v;
    for (Eigen::Index p = 0; p < kSamples; ++p) {
      viscous += v.col(p).dot(cv.col(p)) / (wet->frequency_hz * kSamples);
      const Eigen::Index next = (p + 1) % kSamples, prev = (p + kSamples - 1) % kSamples;
      for (Eigen::Index c = 0; c < nc; ++c) {
        const double w = -force(c, p) * 0.5 * (displacement(c, next) - displacement(c, prev));
        work += w;
        if (c >= nt) friction_work += w;
      }
    }
    const double balance = std::abs(work - viscous) / viscous;
    // What friction dissipates: its force against the casing's sliding, Σ_i ∮ f_t,i dτ · 2πR_i/n per
    // period (the slips' work, the blade's own tangential motion aside).
    double sliding_dissipation = 0.0;
    for (int i = 0; i < nt; ++i) {
      sliding_dissipation += force.row(nt + i).mean() * 2.0 * kPi * radius[static_cast<size_t>(i)] / lobes;
    }
    {
      Eigen::VectorXd fn = force.row(model.onset).transpose(), ft = force.row(nt + model.onset).transpose();
      Eigen::VectorXd gap_tau = (relative.row(model.onset).array() * -1.0 + gap).matrix().transpose();
      run.table("orbit.csv", {"tau [-]", "normal_force [N]", "friction_force [N]", "gap [m]"}, {tau, fn, ft, gap_tau});
    }

    // Floquet multipliers (solvers/floquet.hpp: the monodromy matrix carries each Jenkins element's
    // force perturbation) of a few orbits: the μ-branch's first point past μ = 0, its landing on
    // the file's μ and its last point, and the frictional curve's largest amplitude. They say what
    // the μ-branch meets (a real multiplier through +1: a resonance of the forced response in μ,
    // where I − Φ is singular; a complex pair leaving the circle: flutter, the mode coupling of
    // friction-induced instability, [HFAG02] in docs/references.md) and whether those orbits are
    // stable. The samples as trace_response takes them (the trial functions at the steps the
    // stiffest contact needs).
    struct Verdict {
      std::string where;
      double mu = 0.0, frequency_hz = 0.0, time_s = 0.0;
      solvers::FloquetResult floquet;
    };
    const auto verdict_at = [&](const std::string& where, const Eigen::VectorXd& x, double mu_value, double hz) {
      const auto contacts = rubbing_at(mu_value);
      const auto t = std::chrono::steady_clock::now();
      const solvers::FloquetAnalysis floquet(model.reduced, contacts, {.monodromy = false});
      const Eigen::MatrixXd coefficients = spectral::as_coefficients(x, nc);  // n_c × M
      const auto samples_at = [&](Eigen::Index count) {
        const Eigen::VectorXd at = Eigen::VectorXd::LinSpaced(count, 0.0, 1.0 - 1.0 / static_cast<double>(count));
        return Eigen::MatrixXd(coefficients * scan_basis.values(at, 0).transpose() -
                               solvers::obstacle_samples(contacts, at));
      };
      Eigen::MatrixXd samples = samples_at(kSamples);
      const Eigen::Index steps = floquet.resolved_steps(samples, hz);
      if (steps > kSamples) samples = samples_at(steps);
      Verdict v{where, mu_value, hz, 0.0, floquet(samples, hz)};
      v.time_s = models::seconds_since(t);
      return v;
    };
    // The μ-branch at the file's μ and at its end, and the frictional curve's largest amplitude:
    // three independent monodromies (each about 5 s at 65 536 steps), the first two on their own
    // threads while this one computes the third. Each result depends only on its orbit.
    std::optional<Verdict> at_file_mu, at_branch_end;
    std::future<Verdict> file_mu_task, branch_end_task;
    if (const auto* at_mu = landing(mu)) {
      file_mu_task = std::async(std::launch::async, [&verdict_at, x = at_mu->x, mu, hz = from * f1] {
        return verdict_at("the μ-branch at the file's μ", x, mu, hz);
      });
    }
    if (!mu_branch.points.empty()) {
      branch_end_task = std::async(std::launch::async, [&verdict_at, &mu_branch, hz = from * f1] {
        return verdict_at("the μ-branch's last point", mu_branch.points.back().x, mu_branch.points.back().parameter,
                          hz);
      });
    }
    const Verdict at_peak =
        verdict_at("the largest frictional amplitude", wet->contact_unknowns, mu, wet->frequency_hz);
    if (file_mu_task.valid()) at_file_mu = file_mu_task.get();
    if (branch_end_task.valid()) at_branch_end = branch_end_task.get();
    std::vector<const Verdict*> verdicts;
    if (at_file_mu) verdicts.push_back(&*at_file_mu);
    if (at_branch_end) verdicts.push_back(&*at_branch_end);
    verdicts.push_back(&at_peak);
    for (const Verdict* v : verdicts) {
      const std::complex<double> lead = v->floquet.multipliers(0);
      std::printf("floquet, %s (mu = %.5g, f = %.5g f1): |mu| = %.6f, arg = %.4f, %d steps, %s, %.1f s\n",
                  v->where.c_str(), v->mu, v->frequency_hz / f1, std::abs(lead), std::arg(lead), v->floquet.steps,
                  v->floquet.settled() ? "settled" : "not settled", v->time_s);
    }
    const auto lead_arg = [](const Verdict& v) { return std::abs(std::arg(v.floquet.multipliers(0))); };
    const auto stable_verdict = [](const Verdict& v) { return v.floquet.stable() && v.floquet.settled(); };
    const auto describe = [](const Verdict& v) {
      const std::complex<double> lead = v.floquet.multipliers(0);
      return "|μ|max " + format("%.4f", std::abs(lead)) + " at arg " + format("%.3f", std::arg(lead)) + " rad" +
             (v.floquet.settled() ? "" : " (not settled)");
    };

    const auto* issue_point = landing(kIssueFrictionCoefficient);
    const bool issue_in_scan = std::find(scan.begin(), scan.end(), kIssueFrictionCoefficient) != scan.end();
    std::vector<Claim> claims = {
        {"the issue's μ = " + format("%g", kIssueFrictionCoefficient) + " has a periodic response at the start, " +
             format("%g", from) + " f1, reached by continuation in μ from the frictionless one",
         issue_in_scan ? std::optional<bool>(issue_point != nullptr) : std::nullopt,
         issue_in_scan
             ? std::string(solvers::to_string(mu_branch.stop)) + " at μ = " + format("%.4g", mu_largest) +
                   ", the contact unknowns " + growth_text + " times those at μ = 0 (1/‖x‖∞ extrapolated to 0 at μ ≈ " +
                   pole_text + "), " + std::to_string(mu_branch.points.size()) + " points"
             : "μ = " + format("%g", kIssueFrictionCoefficient) + " not in contact.friction_scan"},
        {"both branches reach the range end " + format("%g", to) + " f1 (pseudo-arclength in f, i.e. in Ω = 2πf/" +
             std::to_string(lobes) + ")",
         curves[0].curve.converged() && curves[1].curve.converged(),
         std::to_string(curves[0].curve.points.size()) + " and " + std::to_string(curves[1].curve.points.size()) +
             " points; " + std::string(solvers::to_string(curves[1].curve.stop))},
        {"where the frictional curve's amplitude is largest every Jenkins sample slides (the casing slides back by "
         "2πR/n ≈ " +
             format("%.3g", 2.0 * kPi * radius[static_cast<size_t>(model.onset)] / lobes) +
             " m per period, far more than the tip moves) with Coulomb's f_t = μ f_n against the rotation, to " +
             format("%g", kSlidingTolerance) + " of μ max f_n",
         stuck == 0 && sliding <= kSlidingTolerance * mu * normal_max,
         std::to_string(stuck) + " stuck samples of " + std::to_string(nt * kSamples) + "; largest |f_t − μ f_n| " +
             format("%.1e", sliding) + " N against μ max f_n = " + format("%.3g", mu * normal_max) + " N"},
        {"along the continuation in μ the orbits stay stable and the leading pair of Floquet multipliers turns "
         "towards +1 as the branch ends (its argument shrinks): the response meets a resonance in μ, a mode of the "
         "frictional linearization reaching the excitation, not flutter (a pair leaving the unit circle)",
         at_file_mu && at_branch_end
             ? std::optional<bool>(stable_verdict(*at_file_mu) && stable_verdict(*at_branch_end) &&
                                   lead_arg(*at_branch_end) < lead_arg(*at_file_mu))
             : std::nullopt,
         at_file_mu && at_branch_end
             ? "at μ = " + format("%g", mu) + " " + describe(*at_file_mu) + "; at μ = " +
                   format("%.4g", at_branch_end->mu) + " " + describe(*at_branch_end)
             : std::string("the branch did not land on the file's μ")},
        {"the frictional curve's orbit where its amplitude is largest is stable (every |μ| < 1, a verdict its error "
         "estimate cannot overturn)",
         stable_verdict(at_peak), describe(at_peak) + ", " + std::to_string(at_peak.floquet.steps) + " steps"},
        {"there the casing's work on the blade over a period equals the viscous dissipation (no "
         "other load works), to " +
             format("%g", kBalanceTolerance) + " (P = " + std::to_string(kSamples) + " samples)",
         std::isfinite(balance) ? std::optional<bool>(balance <= kBalanceTolerance) : std::nullopt,
         "work " + format("%.4e", work) + " J, dissipation " + format("%.4e", viscous) + " J, difference " +
             format("%.1e", balance) + "; of the work, the friction forces' " + format("%.4e", friction_work) + " J"}};

    std::ostringstream md;
    md << "## The LL11 blade rubbing an oval casing, with friction (issue #36)\n\n"
       << "Files: `out/friction_oval_casing/friction_oval_casing.{png,pdf}`, `frictionless.csv`, `friction.csv`, "
          "`orbit.csv`, `meta.json`. Beyond both papers: the reduced blade of `ll11_blade` ("
       << nt << " tip nodes, " << parameters.integer("interface.modes") << " modes, f1 = " << format("%.2f", f1)
       << " Hz) turns inside a casing of radius R + δ cos " << lobes
       << "θ, δ = " << format("%g", parameters.number("casing.ovalization_gaps")) << " gaps (gap "
       << format("%g", gap * 1e3) << " mm), with no other load. One lobe passes per period: f = " << lobes
       << "Ω/(2π). Each tip node has a "
          "radial penalty contact (k = "
       << format("%.3g", k_pen)
       << " N/m, as `ll11_blade_forced`) whose gap moves "
          "with the lobes, and a Jenkins element along the rotation (k_t = "
       << format("%.3g", k_t) << " N/m, μ = " << format("%g", mu) << ") against the casing sliding back by 2πR/"
       << lobes
       << " per period, its slip force μ "
          "times the radial force (solvers::ContactPoint::obstacle; docs/scenes.md, `[[counter_surface]]`). "
          "Fourier:Fourier, H = "
       << harmonics << ", pseudo-arclength over " << format("%g", from) << " … " << format("%g", to)
       << " f1. Amplitude: half the peak-to-peak circumferential displacement of the first "
          "tip node to touch, in gaps. Both curves' amplitudes still grow at the range's end: with the casing the "
          "blade's resonance lies above 1.1 f1 (the contacts stiffen it), so the table gives the largest amplitude in "
          "the range, not a peak.\n\n"
       << "| | points | largest amplitude at f/f1 | Ω [rad/s] | largest amplitude [gap] | time [s] "
          "|\n|---|---|---|---|---|---|\n";
    for (const auto& [c, peak] : {std::pair{&curves[0], dry}, std::pair{&curves[1], wet}}) {
      md << "| " << c->label << " | " << c->curve.points.size() << " | " << format("%.4f", peak->frequency_hz / f1)
         << " | " << format("%.1f", 2.0 * kPi * peak->frequency_hz / lobes) << " | "
         << format("%.3f", peak->amplitude * model.unit) << " | " << format("%.1f", c->time_s) << " |\n";
    }
    md << "\nWhich μ has a periodic response at " << format("%g", from)
       << " f1: a pseudo-arclength continuation in μ from the frictionless solution at μ = 0 (|Δμ| ≤ "
       << format("%g", in_mu.max_parameter_step)
       << " per step, `contact.friction_step`; the library's ContinuationParameter::FrictionCoefficient, G factorized "
          "once, ∂r/∂μ analytic, exact on each stick/slip pattern, where the Jenkins force is affine in μ) took "
       << mu_branch.points.size() << " points and " << format("%.1f", mu_time) << " s, and ended "
       << solvers::to_string(mu_branch.stop) << " at μ = " << format("%.4g", mu_largest) << " (" << mu_branch.message
       << "; " << mu_branch.folds.size() << " folds). There the contact unknowns are " << growth_text
       << " times those at μ = 0"
       << (unbounded
               ? " and 1/‖x‖∞, extrapolated linearly through the last two points, would vanish near μ ≈ " + pole_text +
                     " (an estimate, not a located singularity): the response grows without bound as μ nears a "
                     "value a little above the branch's end, as at a resonance (the Floquet multipliers below say "
                     "which kind)"
               : std::string())
       << ". Beside it, Newton at each μ of `contact.friction_scan` straight from the frictionless solution:\n\n"
       << "| μ | on the continuation in μ | its Newton iterations | Newton from μ = 0: status | iterations | "
          "backward error |\n|---|---|---|---|---|---|\n";
    for (size_t i = 0; i < scan.size(); ++i) {
      const auto* p = landing(scan[i]);
      md << "| " << format("%g", scan[i]) << " | " << (p != nullptr ? "reached" : "not reached") << " | "
         << (p != nullptr ? std::to_string(p->corrector_iterations) : std::string()) << " | "
         << solvers::to_string(direct[i].report.status) << " | " << direct[i].report.iterations << " | "
         << format("%.1e", direct[i].backward_error) << " |\n";
    }
    md << "\nA μ beyond the branch's end whose Newton converges has a response on another branch: the one from the "
          "frictionless solution does not reach it. The curves use the file's μ = "
       << format("%g", mu) << " (`contact.friction_coefficient`).\n";
    md << "\nFloquet multipliers (solvers/floquet.hpp: the monodromy matrix carries each Jenkins element's force "
          "perturbation, 2n + "
       << nt << " = " << 2 * model.reduced.mass.rows() + nt
       << " states; the dominant ones by Arnoldi on the modal path; the steps the stiff contacts need):\n\n"
       << "| orbit | μ | f/f1 | leading multiplier | modulus | argument [rad] | verdict | steps | time [s] "
          "|\n|---|---|---|---|---|---|---|---|---|\n";
    for (const Verdict* v : verdicts) {
      const std::complex<double> lead = v->floquet.multipliers(0);
      md << "| " << v->where << " | " << format("%.4g", v->mu) << " | " << format("%.4f", v->frequency_hz / f1)
         << " | " << format("%.4f", lead.real()) << (lead.imag() < 0.0 ? " − " : " + ")
         << format("%.4f", std::abs(lead.imag())) << "i | " << format("%.4f", std::abs(lead)) << " | "
         << format("%.3f", std::arg(lead)) << " | "
         << (v->floquet.settled() ? (v->floquet.stable() ? "stable" : "unstable") : "not settled") << " | "
         << v->floquet.steps << " | " << format("%.1f", v->time_s) << " |\n";
    }
    md << "\nA multiplier of a lightly damped mode is e^{(−ζω ± iω_d)T}: its modulus stays near e^{−ζωT} while its "
          "argument ω_d T (mod 2π) goes to 0 where the mode's frequency reaches a multiple of the excitation's, "
          "the forced response's resonance.\n";
    md << "\nWhere the frictional curve's amplitude is largest (f/f1 = " << format("%.4f", wet->frequency_hz / f1)
       << "), friction dissipates " << format("%.3g", sliding_dissipation)
       << " J per period against the casing's sliding (Σ_i ∮ μ f_n,i dτ · 2πR_i/" << lobes
       << "), drawn from the "
          "rotation, not from the blade's vibration: its forces do "
       << format("%.3g", friction_work) << " J on the blade, against a viscous dissipation of "
       << format("%.3g", viscous) << " J.\n\n"
       << reproduce::claims_markdown(claims);
    run.report(md.str());
    run.meta({{"f1_hz", f1},
              {"gap_m", gap},
              {"ovalization_m", delta},
              {"lobes", lobes},
              {"penalty_stiffness_N_per_m", k_pen},
              {"tangential_stiffness_N_per_m", k_t},
              {"friction_coefficient", mu},
              {"harmonics", harmonics},
              {"friction_scan", scan},
              {"friction_continuation",
               {{"stop", std::string(solvers::to_string(mu_branch.stop))},
                {"points", mu_branch.points.size()},
                {"largest_mu", mu_largest},
                {"pole_mu", std::isfinite(mu_pole) ? nlohmann::json(mu_pole) : nlohmann::json()},
                {"growth", std::isfinite(mu_growth) ? nlohmann::json(mu_growth) : nlohmann::json()},
                {"folds", mu_branch.folds.size()},
                {"time_s", mu_time}}},
              {"floquet",
               [&] {
                 nlohmann::json list = nlohmann::json::array();
                 for (const Verdict* v : verdicts) {
                   const std::complex<double> lead = v->floquet.multipliers(0);
                   list.push_back({{"orbit", v->where},
                                   {"friction_coefficient", v->mu},
                                   {"frequency_hz", v->frequency_hz},
                                   {"leading_multiplier", {lead.real(), lead.imag()}},
                                   {"settled", v->floquet.settled()},
                                   {"stable", v->floquet.stable()},
                                   {"steps", v->floquet.steps},
                                   {"time_s", v->time_s}});
                 }
                 return list;
               }()},
              {"tip_radius_m", radius},
              {"tip_angle_rad", theta},
              {"largest_amplitude_frequency_hz", {dry->frequency_hz, wet->frequency_hz}},
              {"energy_balance",
               {{"work_J", work},
                {"viscous_J", viscous},
                {"friction_on_blade_J", friction_work},
                {"sliding_dissipation_J", sliding_dissipation}}},
              {"curve_time_s", {curves[0].time_s, curves[1].time_s}}});
  });
}
