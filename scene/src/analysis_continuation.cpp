#include "analysis_detail.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <algorithm>
#include <sstream>
#include <stdexcept>

#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/spectral/aft.hpp>
#include <wbm/spectral/layout.hpp>

namespace wbm::scene::detail {

namespace {

// Each change of stability along the branch (issue #39): between points i − 1 and i the number of
// Floquet multipliers outside the unit circle changed (ResponsePoint::crossing), located by
// solvers::stability_crossings: frequency and amplitude interpolated linearly where the largest
// |μ| passes 1 between the two points; the multiplier is the unstable side's largest, and the kind
// is classify_crossing's (fold / period doubling / Neimark–Sacker). bifurcations.csv gets a row per
// crossing (written only when there is one); result.json the same list, empty when none.
// In a branch in μ the crossing is located in μ instead (friction_coefficient [-] and
// friction_coefficient, between; the frequency is the branch's).
nlohmann::json write_bifurcations(const solvers::ResponseCurve& curve, const std::string& dof, bool in_mu,
                                  AnalysisResult& out) {
  nlohmann::json list = nlohmann::json::array();
  std::vector<double> hz, before, after, amplitude, modulus, argument, lost;
  std::vector<std::string> kind;
  for (const solvers::StabilityCrossing& c : solvers::stability_crossings(curve)) {
    hz.push_back(c.parameter);
    before.push_back(curve.points[c.before].parameter);
    after.push_back(curve.points[c.after].parameter);
    amplitude.push_back(c.amplitude);
    modulus.push_back(std::abs(c.multiplier));
    argument.push_back(std::arg(c.multiplier));
    lost.push_back(c.stability_lost ? 1.0 : 0.0);
    kind.emplace_back(solvers::to_string(c.kind));
    list.push_back({{"kind", kind.back()},
                    {in_mu ? "friction_coefficient" : "frequency_hz", hz.back()},
                    {in_mu ? "between" : "between_hz", {before.back(), after.back()}},
                    {"amplitude_m", {{dof, amplitude.back()}}},
                    {"multiplier", {{"modulus", modulus.back()}, {"argument_rad", argument.back()}}},
                    {"stability", c.stability_lost ? "lost" : "regained"}});
  }
  if (!hz.empty()) {
    const auto column = [](const std::vector<double>& v) {
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
    };
    out.tables.push_back({"bifurcations.csv",
                          {in_mu ? "friction_coefficient [-]" : "frequency [Hz]",
                           in_mu ? "friction_coefficient_before [-]" : "frequency_before [Hz]",
                           in_mu ? "friction_coefficient_after [-]" : "frequency_after [Hz]",
                           "amplitude_" + dof + " [m]",
                           "floquet_multiplier_modulus [-]", "floquet_multiplier_argument [rad]", "stability_lost [-]"},
                          {column(hz), column(before), column(after), column(amplitude), column(modulus), column(argument),
                           column(lost)},
                          kind});
  }
  return list;
}

}  // namespace

void continuation(const Scene& scene, const Progress& progress, AnalysisResult& out) {
  const auto started = std::chrono::steady_clock::now();
  // A branch in the forcing frequency over its range, or in μ (every Jenkins element's, from the
  // range's start) at the one forcing frequency.
  const bool in_mu = scene.analysis.parameter == BranchParameter::FrictionCoefficient;
  const double from = in_mu ? scene.analysis.friction_from : scene.forcing->range->from_hz;
  const double to = in_mu ? scene.analysis.friction_to : scene.forcing->range->to_hz;
  std::vector<solvers::ContactPoint> contacts = scene.contact_points();
  if (in_mu) {
    const double given = solvers::common_friction_coefficient(contacts);
    if (given != from) {
      out.warnings.push_back("continuation in mu: the \"jenkins\" contacts' friction_coefficient = " +
                             format("%g", given) + " is replaced by the branch's mu, from analysis.friction_coefficient = [" +
                             format("%g", from) + ", " + format("%g", to) + "]");
    }
    contacts = solvers::with_friction_coefficient(contacts, from);
  }
  const solvers::WeightedResidual base(scene.system(),
                                       scene.harmonic_forcing(in_mu ? std::nullopt : std::optional(from)),
                                       std::move(contacts), scene.trial(), scene.weighting(),
                                       scene.weighted_residual_options());
  solvers::ResponseCurveOptions o;
  o.parameter = in_mu ? solvers::ContinuationParameter::FrictionCoefficient : solvers::ContinuationParameter::Frequency;
  o.parameter_min = std::min(from, to);
  o.parameter_max = std::max(from, to);
  o.direction = to > from ? +1 : -1;
  o.max_step = scene.analysis.max_step;
  o.initial_step = std::min(o.initial_step, o.max_step);
  o.max_parameter_step = in_mu ? 0.0 : scene.analysis.max_frequency_step_hz;
  o.max_points = scene.analysis.max_points;
  o.max_state = scene.analysis.max_state;
  o.stability = scene.analysis.stability;
  switch (scene.analysis.stick_slip_events) {
    case StickSlipEvents::OnStall: o.stick_slip_events = solvers::StickSlipEvents::OnStall; break;
    case StickSlipEvents::Always: o.stick_slip_events = solvers::StickSlipEvents::Always; break;
    case StickSlipEvents::Never: o.stick_slip_events = solvers::StickSlipEvents::Never; break;
  }
  o.corrector_tolerance = scene.solver.newton.tolerance;
  o.samples = scene.output.samples;
  // Observed DOFs: their amplitudes (beyond the forced DOF's) and harmonics along the branch.
  const std::vector<int> observed = scene.output.observe.empty() ? std::vector<int>{scene.forcing->dof} : scene.output.observe;
  const bool per_point = !scene.output.observe.empty() || scene.output.harmonics > 0;
  std::vector<int> kept;
  if (per_point && scene.condensation) {
    for (int d = 0; d < base.dofs(); ++d) kept.push_back(d);
  } else if (per_point) {
    for (int d : observed) kept.push_back(scene.solver_dof(d));
  }
  o.keep_dofs = kept;
  double reached = 0.0;  // the largest fraction of the range covered so far (a branch turns back at folds)
  if (progress) {
    o.on_point = [&](size_t i, const solvers::BranchPoint& p) {
      reached = std::max(reached, std::abs(p.parameter - from) / std::abs(to - from));
      progress(std::min(reached, 1.0), "point " + std::to_string(i + 1) +
                                           (in_mu ? ", mu = " + format("%.6g", p.parameter)
                                                  : ", f = " + format("%.6g", p.parameter) + " Hz") +
                                           ", step " + format("%.2g", p.step));
    };
  }
  const auto curve = solvers::trace_response(base, o);
  const std::string dof = scene.structure->dof_name(scene.forcing->dof);
  const auto n = static_cast<Eigen::Index>(curve.points.size());
  const bool rigid = base.rigid();
  Eigen::VectorXd f(n), umax(n), umin(n), amp(n), force(n), stable(n), mu(n), mu_error(n), steps(n), its(n);
  Eigen::VectorXd friction(n);  // a branch in μ: each point's
  Eigen::VectorXd distance(n), impacts(n);
  std::vector<std::string> verdict(static_cast<size_t>(n));
  std::string first_unavailable;
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& p = curve.points[static_cast<size_t>(i)];
    // The error estimate is missing (empty cell) where it could not be formed (floquet.hpp).
    mu_error(i) = std::isfinite(p.max_multiplier_error) ? p.max_multiplier_error : NAN;
    steps(i) = p.monodromy_steps;
    verdict[static_cast<size_t>(i)] = !p.stability_available                  ? "unavailable"
                                      : !std::isfinite(p.max_multiplier_error) ? "no error estimate"
                                      : p.stability_settled                    ? "settled"
                                                                               : "within its error estimate";
    f(i) = p.frequency_hz;
    friction(i) = p.parameter;
    umax(i) = p.max_displacement;
    umin(i) = p.min_displacement;
    amp(i) = p.amplitude;
    force(i) = p.max_contact_force;
    stable(i) = p.stable ? 1.0 : 0.0;
    mu(i) = p.max_multiplier;
    its(i) = p.corrector_iterations;
    // Rigid stops: the exact orbit's distance and impacts (empty where no orbit was found).
    distance(i) = std::isfinite(p.shooting_distance) ? p.shooting_distance : NAN;
    impacts(i) = std::isfinite(p.shooting_distance) ? p.impacts : NAN;
    if (!p.stability_available) {  // no verdict: empty cells
      stable(i) = mu(i) = mu_error(i) = NAN;
      if (first_unavailable.empty()) {
        first_unavailable = (in_mu ? "mu = " + format("%.6g", p.parameter) : format("%.6g", p.frequency_hz) + " Hz") +
                            ": " + p.stability_message;
      }
    }
  }
  if (n > 0) {
    std::vector<std::string> header = {"frequency [Hz]", "u_max_" + dof + " [m]", "u_min_" + dof + " [m]",
                                       "amplitude_" + dof + " [m]", "max_contact_force [N]"};
    std::vector<Eigen::VectorXd> columns = {f, umax, umin, amp, force};
    if (in_mu) {  // the branch's parameter first; the frequency column is then constant
      header.insert(header.begin(), "friction_coefficient [-]");
      columns.insert(columns.begin(), friction);
    }
    if (o.stability) {
      header.insert(header.end(), {"stable [-]", "max_floquet_multiplier [-]", "max_floquet_multiplier_error [-]"});
      columns.insert(columns.end(), {stable, mu, mu_error});
      // Rigid stops: the exact orbit by shooting (its saltation monodromy), not P steps.
      if (rigid) {
        header.insert(header.end(), {"shooting_distance [-]", "impacts_per_period [-]"});
        columns.insert(columns.end(), {distance, impacts});
      } else {
        header.push_back("monodromy_steps [-]");
        columns.push_back(steps);
      }
    }
    if (!scene.basis.selected_harmonics.empty()) {
      Eigen::VectorXd dropped(n);
      for (Eigen::Index i = 0; i < n; ++i) dropped(i) = curve.points[static_cast<size_t>(i)].dropped_harmonics_residual;
      header.push_back("dropped_harmonics_residual [-]");
      columns.push_back(dropped);
      warn_dropped_harmonics(scene, std::vector<double>(f.data(), f.data() + n),
                             std::vector<double>(dropped.data(), dropped.data() + n), out);
    }
    header.push_back("corrector_iterations [-]");
    columns.push_back(its);
    if (per_point) {
      const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(o.samples, 0.0, 1.0 - 1.0 / o.samples);
      std::vector<double> hz;
      std::vector<Eigen::MatrixXd> samples;
      for (const auto& p : curve.points) {
        hz.push_back(p.frequency_hz);
        samples.push_back(observed_samples(scene, base.trial(), p.kept_coefficients, kept, observed, tau, p.frequency_hz));
      }
      for (size_t d = 0; d < observed.size(); ++d) {
        if (observed[d] == scene.forcing->dof) continue;  // its columns are there already
        const std::string name = scene.structure->dof_name(observed[d]);
        Eigen::VectorXd hi(n), lo(n);
        for (Eigen::Index i = 0; i < n; ++i) {
          hi(i) = samples[static_cast<size_t>(i)].row(static_cast<Eigen::Index>(d)).maxCoeff();
          lo(i) = samples[static_cast<size_t>(i)].row(static_cast<Eigen::Index>(d)).minCoeff();
        }
        header.insert(header.end(), {"u_max_" + name + " [m]", "u_min_" + name + " [m]", "amplitude_" + name + " [m]"});
        columns.insert(columns.end(), {hi, lo, 0.5 * (hi - lo)});
      }
      if (scene.output.harmonics > 0) {
        out.tables.push_back(point_harmonics(scene, "branch_harmonics.csv", observed, hz, samples));
      }
    }
    if (o.stability) {
      out.tables.push_back({"branch.csv", header, columns, verdict});
    } else {
      out.tables.push_back({"branch.csv", header, columns});
    }
  }
  // Each fold with its state (issue #35): the amplitude of every output DOF at the fold itself,
  // so that a picture marks it on its own sheet of a multivalued curve.
  nlohmann::json folds = nlohmann::json::array();
  const auto nf = static_cast<Eigen::Index>(curve.folds.size());
  Eigen::VectorXd fold_hz(nf), fold_ok(nf), fold_max(nf), fold_min(nf), fold_amp(nf);
  std::vector<Eigen::VectorXd> fold_observed(observed.size(), Eigen::VectorXd(nf));
  for (Eigen::Index k = 0; k < nf; ++k) {
    const auto& fold = curve.fold_points[static_cast<size_t>(k)];
    const bool crossing = curve.fold_confirmed[static_cast<size_t>(k)];
    fold_hz(k) = fold.parameter;
    fold_ok(k) = crossing ? 1.0 : 0.0;
    fold_max(k) = fold.max_displacement;
    fold_min(k) = fold.min_displacement;
    fold_amp(k) = fold.amplitude;
    nlohmann::json amplitudes = {{dof, fold.amplitude}};
    if (per_point) {
      const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(o.samples, 0.0, 1.0 - 1.0 / o.samples);
      const Eigen::MatrixXd u = observed_samples(scene, base.trial(), fold.kept_coefficients, kept, observed, tau, fold.frequency_hz);
      for (size_t d = 0; d < observed.size(); ++d) {
        const auto row = u.row(static_cast<Eigen::Index>(d));
        fold_observed[d](k) = 0.5 * (row.maxCoeff() - row.minCoeff());
        amplitudes[scene.structure->dof_name(observed[d])] = fold_observed[d](k);
      }
    }
    folds.push_back({{in_mu ? "friction_coefficient" : "frequency_hz", fold.parameter},
                     {"floquet_crossing", crossing},
                     {"amplitude_m", amplitudes}});
  }
  if (nf > 0) {
    std::vector<std::string> header = {in_mu ? "friction_coefficient [-]" : "frequency [Hz]", "floquet_crossing [-]",
                                       "u_max_" + dof + " [m]",
                                       "u_min_" + dof + " [m]", "amplitude_" + dof + " [m]"};
    std::vector<Eigen::VectorXd> columns = {fold_hz, fold_ok, fold_max, fold_min, fold_amp};
    for (size_t d = 0; per_point && d < observed.size(); ++d) {
      if (observed[d] == scene.forcing->dof) continue;  // its columns are there already
      header.push_back("amplitude_" + scene.structure->dof_name(observed[d]) + " [m]");
      columns.push_back(fold_observed[d]);
    }
    out.tables.push_back({"folds.csv", header, columns});
  }
  const nlohmann::json bifurcations = o.stability ? write_bifurcations(curve, dof, in_mu, out) : nlohmann::json();
  out.stop = curve.stop;
  out.status = curve.status();
  out.diagnostics["continuation"] = {{"points", curve.points.size()},
                                     {"folds", folds},
                                     {"stop", std::string(solvers::to_string(curve.stop))},
                                     {"message", curve.message + way_out(scene, curve.stop, curve.stalled_residual)},
                                     {"rejected_steps", curve.rejected_steps},
                                     {"corners", curve.kinks},
                                     {"events", curve.events},
                                     {"switches", curve.switches},
                                     {"corrector_iterations", curve.corrector_iterations},
                                     {"continuation_time_s", curve.wall_time_s},
                                     {"stability_time_s", curve.stability_time_s},
                                     {"stability_work_s", curve.stability_work_s},
                                     {"stability_points_beside_continuation", curve.stability_points_beside},
                                     {"unsettled_stability_points", curve.unsettled_points},
                                     {"unavailable_stability_points", curve.unavailable_points}};
  if (o.stability) out.diagnostics["continuation"]["bifurcations"] = bifurcations;
  if (curve.unsettled_points > 0) {
    out.warnings.push_back("continuation: at " + std::to_string(curve.unsettled_points) +
                           " point(s) a Floquet multiplier lies within twice its error estimate of the unit circle "
                           "even with 16x the monodromy steps; their stability verdict may be wrong (branch.csv, "
                           "status column); raise [output] samples");
  }
  if (curve.unavailable_points > 0) {
    out.warnings.push_back("continuation: " + std::to_string(curve.unavailable_points) + " of " +
                           std::to_string(curve.points.size()) +
                           " point(s) have no stability verdict (branch.csv: empty cells, status \"unavailable\"): "
                           "no exact orbit with impacts was found near them; the first at " + first_unavailable);
  }
  out.summary = base.trial().name() + ":" + base.weighting().name() + ", M = " + std::to_string(base.dimension()) +
                (in_mu ? ", continuation in mu " + format("%g", from) + " → " + format("%g", to) + " at " +
                             format("%g", base.frequency_hz()) + " Hz: "
                       : ", continuation " + format("%g", from) + " → " + format("%g", to) + " Hz: ") +
                std::to_string(curve.points.size()) + " points, " + std::to_string(curve.folds.size()) + " folds, " +
                std::string(solvers::to_string(curve.stop)) + way_out(scene, curve.stop, curve.stalled_residual) +
                " (" +
                format("%.3f", std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()) +
                " s in all: continuation " + format("%.3f", curve.wall_time_s) + " s, stability " +
                format("%.3f", curve.stability_time_s) + " s)";
}

}  // namespace wbm::scene::detail
