#include "analysis_detail.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <algorithm>
#include <sstream>
#include <stdexcept>

#include <wbm/contact/friction.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/spectral/aft.hpp>
#include <wbm/spectral/layout.hpp>

namespace wbm::scene::detail {

void solve_one(const Scene& scene, AnalysisResult& out) {
  const auto system = scene.system();
  const auto forcing = scene.harmonic_forcing();
  const auto contacts = scene.contact_points();
  const auto trial = scene.trial();
  const auto weighting = scene.weighting();
  const auto solution =
      solvers::solve_weighted_residual(system, forcing, contacts, trial, weighting, scene.weighted_residual_options());
  out.status = solution.report.status;
  out.diagnostics["solution"] = solution;
  out.summary = trial.name() + ":" + weighting.name() + ", M = " + std::to_string(trial.dimension()) + ", " +
                std::string(solvers::to_string(scene.basis.formulation)) + ", f = " +
                format("%g", forcing.frequency_hz) + " Hz: " + solution.report.message + ", relative residual " +
                format("%.2e", solution.relative_residual) + ", " + format("%.3f", solution.wall_time_s * 1e3) + " ms";
  if (!scene.basis.selected_harmonics.empty()) {
    out.summary += "; harmonic_selection = " + selection_label(scene) + ": residual in the dropped harmonics " +
                   format("%.2e", solution.dropped_harmonics_residual) + " ‖b‖";
    warn_dropped_harmonics(scene, {forcing.frequency_hz}, {solution.dropped_harmonics_residual}, out);
  }
  if (!out.converged()) return;  // no curve from an unconverged iterate
  const int p = scene.output.samples;
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(p, 0.0, 1.0 - 1.0 / p);
  const Eigen::MatrixXd& a = solution.coefficients;
  std::optional<solvers::PeriodicFields> fields;
  Eigen::MatrixXd displacement;
  if (const std::string why = solvers::velocity_unavailable(trial); why.empty()) {
    fields = solvers::evaluate_fields(trial, a, tau, forcing.frequency_hz);
    displacement = fields->displacement;
  } else {
    out.diagnostics["velocity"] = "not written: " + why;
    displacement.resize(a.rows(), p);
    for (Eigen::Index i = 0; i < a.rows(); ++i) {
      displacement.row(i) = solvers::evaluate_trial(trial, a, static_cast<int>(i), tau, forcing.frequency_hz).transpose();
    }
  }
  period_tables(scene, contacts, system, forcing.frequency_hz, tau, displacement, fields ? &fields->velocity : nullptr,
                out);
  if (scene.rigid()) {
    // The multipliers at their instants τ_k: the mean force over each cell.
    const int m = trial.dimension();
    const Eigen::VectorXd& tk = solution.collocation_times;
    Table f{"contact_force.csv", {"tau [-]", "time [s]"}, {tk, tk / forcing.frequency_hz}};
    Eigen::MatrixXd at_instants(a.rows(), m);  // the displacements at τ_k, for friction contacts
    if (scene.friction()) {
      for (Eigen::Index i = 0; i < a.rows(); ++i) {
        at_instants.row(i) = solvers::evaluate_trial(trial, a, static_cast<int>(i), tk, forcing.frequency_hz).transpose();
      }
    }
    nlohmann::json friction = nlohmann::json::array();
    for (size_t c = 0; c < contacts.size(); ++c) {
      const Eigen::VectorXd force = solution.contact_force_samples.row(static_cast<Eigen::Index>(c)).transpose();
      f.header.push_back("f_c_" + contact_label(scene, c) + " [N]");
      f.columns.push_back(force);
      if (const auto* coulomb = dynamic_cast<const contact::CoulombFriction*>(contacts[c].law.get())) {
        Eigen::VectorXd w(m);  // relative to a moving counter-surface (ContactPoint::obstacle)
        for (int k = 0; k < m; ++k) {
          w(k) = contacts[c].displacement(at_instants.col(k)) - contacts[c].obstacle.at(tk(k));
        }
        f.header.push_back("w_c_" + contact_label(scene, c) + " [m]");
        f.columns.push_back(w);
        // The slip force μ N, or μ times the normal stop's multiplier at the same instants.
        const int normal = contacts[c].normal;
        const double mu = coulomb->parameters().friction_coefficient;
        const Eigen::VectorXd slip =
            normal >= 0 ? Eigen::VectorXd(mu * solution.contact_force_samples.row(normal).transpose().cwiseMax(0.0))
                        : Eigen::VectorXd::Constant(m, coulomb->slip_force());
        friction.push_back(coulomb_diagnostics(contact_label(scene, c), force, w, slip, forcing.frequency_hz,
                                               "collocation_instants", contacts[c].obstacle.drift));
      }
    }
    if (!friction.empty()) out.diagnostics["friction"] = friction;
    out.tables.push_back(std::move(f));
  }
  Table c{"coefficients.csv", {"k [-]"}, {Eigen::VectorXd::LinSpaced(a.cols(), 0.0, static_cast<double>(a.cols() - 1))}};
  for (int dof : scene.output_dofs()) {
    if (scene.solver_dof(dof) < 0) continue;  // a massless DOF has no coefficients (recovered in displacement.csv)
    c.header.push_back("a_" + scene.structure->dof_name(dof) + " [m]");
    c.columns.push_back(a.row(scene.solver_dof(dof)).transpose());
  }
  out.tables.push_back(std::move(c));
}

void solve_sweep(const Scene& scene, const Progress& progress, AnalysisResult& out) {
  const auto system = scene.system();
  const auto contacts = scene.contact_points();
  const auto trial = scene.trial();
  const auto weighting = scene.weighting();
  const auto frequencies = scene.forcing->frequencies_hz();
  const auto dofs = scene.output.observe.empty() ? scene.output_dofs() : scene.output.observe;
  std::vector<double> harmonic_hz;           // [output] harmonics: per converged point
  std::vector<Eigen::MatrixXd> harmonic_samples;
  const int p = scene.output.samples;
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(p, 0.0, 1.0 - 1.0 / p);
  std::vector<std::vector<double>> rows;
  nlohmann::json points = nlohmann::json::array();
  Eigen::VectorXd previous;  // contact unknowns of the last converged point
  double previous_amplitude = NAN;  // (max − min)/2 of the forced DOF at the last converged point
  int failed = 0, restarts = 0;
  solvers::SolveStatus first_failure = solvers::SolveStatus::Converged;  // the status of the first failed point
  nlohmann::json restarted_points = nlohmann::json::array();
  const int forced = scene.harmonic_forcing(frequencies.front()).dof;
  const bool selection = !scene.basis.selected_harmonics.empty();
  std::vector<double> dropped_hz, dropped;  // with a selection: per converged point
  const auto start = std::chrono::steady_clock::now();
  for (size_t i = 0; i < frequencies.size(); ++i) {
    const double f = frequencies[i];
    const solvers::WeightedResidual wr(system, scene.harmonic_forcing(f), contacts, trial, weighting,
                                       scene.weighted_residual_options());
    auto solution = wr.solve(previous.size() > 0 ? &previous : nullptr);
    bool restarted = false;
    std::string continued_status;
    if (!solution.report.converged() && previous.size() > 0) {
      continued_status = std::string(solvers::to_string(solution.report.status));
      solution = wr.solve();  // from the linear response: contact homotopy, then load stepping
      restarted = true;
    }
    nlohmann::json point = solution;
    point["restarted_from_linear"] = restarted;
    points.push_back(point);
    if (progress) {
      progress(static_cast<double>(i + 1) / static_cast<double>(frequencies.size()),
               "point " + std::to_string(i + 1) + "/" + std::to_string(frequencies.size()) + ", f = " + format("%.6g", f) + " Hz");
    }
    if (!solution.report.converged()) {
      if (failed++ == 0) first_failure = solution.report.status;
      previous.resize(0);
      previous_amplitude = NAN;
      continue;
    }
    previous = wr.rigid() ? spectral::stacked(solution.contact_force_samples)
                          : wr.contact_unknowns(spectral::stacked(solution.coefficients));
    const Eigen::VectorXd u_forced = solvers::evaluate_trial(trial, solution.coefficients, forced, tau, f);
    const double amplitude = 0.5 * (u_forced.maxCoeff() - u_forced.minCoeff());
    if (restarted) {
      // A restart from the linear response may land on another branch: say so with the jump.
      ++restarts;
      const double jump = amplitude - previous_amplitude;
      restarted_points.push_back({{"frequency_hz", f},
                                  {"continued_status", continued_status},
                                  {"amplitude_before_m", finite_or_null(previous_amplitude)},
                                  {"amplitude_after_m", amplitude}});
      out.warnings.push_back(
          "sweep: at f = " + format("%.6g", f) + " Hz the solve continued from the previous point ended " +
          continued_status + "; restarted from the linear response (" + std::string(solvers::to_string(solution.path)) +
          "): amplitude of " + scene.structure->dof_name(scene.forcing->dof) + " " + format("%.4g", previous_amplitude) + " m -> " +
          format("%.4g", amplitude) + " m (" + (jump >= 0 ? "+" : "") + format("%.3g", jump) +
          " m); the sweep may have left its branch (a fold?): use [analysis] type = \"continuation\" to follow it");
    }
    previous_amplitude = amplitude;
    std::vector<double> row = {f};
    Eigen::MatrixXd every;  // with massless DOFs: all of them, recovered from the retained ones
    if (scene.condensation) {
      Eigen::MatrixXd retained(solution.coefficients.rows(), p);
      for (Eigen::Index d = 0; d < retained.rows(); ++d) {
        retained.row(d) = solvers::evaluate_trial(trial, solution.coefficients, static_cast<int>(d), tau, f).transpose();
      }
      every = scene.expand_displacement(retained);
    }
    Eigen::MatrixXd observed(static_cast<Eigen::Index>(dofs.size()), p);
    for (size_t d = 0; d < dofs.size(); ++d) {
      const int dof = dofs[d];
      const Eigen::VectorXd u = scene.condensation ? Eigen::VectorXd(every.row(dof).transpose())
                                                   : solvers::evaluate_trial(trial, solution.coefficients, dof, tau, f);
      observed.row(static_cast<Eigen::Index>(d)) = u.transpose();
      row.insert(row.end(), {u.maxCoeff(), u.minCoeff(), solvers::rms(u)});
    }
    if (scene.output.harmonics > 0) {
      harmonic_hz.push_back(f);
      harmonic_samples.push_back(std::move(observed));
    }
    row.push_back(contacts.empty() ? 0.0 : solution.max_contact_force);
    if (selection) {
      row.push_back(solution.dropped_harmonics_residual);
      dropped_hz.push_back(f);
      dropped.push_back(solution.dropped_harmonics_residual);
    }
    row.push_back(solution.report.iterations);
    row.push_back(restarted ? 1.0 : 0.0);
    rows.push_back(row);
  }
  Table t{"frequency_response.csv", {"frequency [Hz]"}, {}};
  for (int dof : dofs) {
    const std::string name = scene.structure->dof_name(dof);
    t.header.insert(t.header.end(), {"max_u_" + name + " [m]", "min_u_" + name + " [m]", "rms_u_" + name + " [m]"});
  }
  t.header.push_back("max_contact_force [N]");
  if (selection) t.header.push_back("dropped_harmonics_residual [-]");
  t.header.insert(t.header.end(), {"newton_iterations [-]", "restarted_from_linear [-]"});
  for (size_t c = 0; c < t.header.size(); ++c) {
    Eigen::VectorXd column(static_cast<Eigen::Index>(rows.size()));
    for (size_t r = 0; r < rows.size(); ++r) column(static_cast<Eigen::Index>(r)) = rows[r][c];
    t.columns.push_back(column);
  }
  if (!rows.empty()) out.tables.push_back(std::move(t));
  warn_dropped_harmonics(scene, dropped_hz, dropped, out);
  if (!harmonic_hz.empty()) {
    out.tables.push_back(point_harmonics(scene, "sweep_harmonics.csv", dofs, harmonic_hz, harmonic_samples));
  }
  out.status = failed == 0 ? solvers::SolveStatus::Converged : first_failure;
  out.diagnostics["points"] = points;
  out.diagnostics["converged_points"] = rows.size();
  out.diagnostics["failed_points"] = failed;
  out.diagnostics["restarted_points"] = restarted_points;
  out.diagnostics["wall_time_s"] = seconds_since(start);
  out.summary = trial.name() + ":" + weighting.name() + ", M = " + std::to_string(trial.dimension()) + ", sweep " +
                format("%g", frequencies.front()) + " … " + format("%g", frequencies.back()) + " Hz: " +
                std::to_string(rows.size()) + " of " + std::to_string(frequencies.size()) + " points converged in " +
                format("%.3f", seconds_since(start)) + " s" +
                (restarts > 0 ? ", " + std::to_string(restarts) + " restarted from the linear response (see warnings)"
                              : std::string());
}

void timestep(const Scene& scene, const Progress& progress, AnalysisResult& out) {
  const auto system = scene.system();
  const auto forcing = scene.harmonic_forcing();
  const auto contacts = scene.contact_points();
  auto options = scene.timestep;
  double first = 0.0;
  if (progress) {
    // Progress on a log scale of δ_i, from its first value to the tolerance.
    options.on_period = [&](int period, double delta) {
      if (first == 0.0) first = std::max(delta, options.periodicity_tolerance * 10.0);
      const double done = std::log(first / std::max(delta, 1e-300)) / std::log(first / options.periodicity_tolerance);
      progress(std::clamp(done, 0.0, 1.0), "period " + std::to_string(period) + ", δ = " + format("%.1e", delta));
    };
  }
  const bool rigid = scene.rigid(), jenkins = scene.jenkins();
  auto mj = scene.moreau_jean;
  const auto& cd = scene.central_difference;
  // Rigid stops and exact friction: Moreau–Jean; a Jenkins element (its slider state carried from
  // step to step): explicit central differences; memoryless penalty laws: the BDF.
  const auto response = rigid     ? solvers::integrate_moreau_jean_to_periodic(system, forcing, contacts, mj)
                        : jenkins ? solvers::integrate_central_difference_to_periodic(system, forcing, contacts, cd)
                                  : solvers::integrate_to_periodic(system, forcing, contacts, options);
  const auto& rep = response.report;
  out.status = rep.status;
  const std::string method =
      rigid     ? "Moreau–Jean (theta = 0.5, restitution " + format("%g", mj.restitution) + ", " +
                      std::to_string(mj.steps_per_period) + " steps per period)"
      : jenkins ? "central differences (explicit, " + std::to_string(cd.steps_per_period) + " steps per period)"
                : "GSL msbdf (variable-order BDF)";
  out.diagnostics["timestep"] = rep;
  out.diagnostics["timestep"]["method"] = method;
  out.summary = std::string(rigid ? "Moreau–Jean at " : jenkins ? "central differences at " : "BDF at ") +
                format("%g", forcing.frequency_hz) + " Hz: " + rep.message + ", " + std::to_string(rep.steps) +
                " steps, " + format("%.3f", rep.wall_time_s) + " s";
  if (!out.converged()) return;
  period_tables(scene, contacts, system, forcing.frequency_hz, response.tau, response.displacement,
                &response.velocity, out);
  if (!rigid) return;
  // The scheme's own energy account over the last period (PeriodicResponse): input − damping −
  // contacts (the stops' absorption and the friction's dissipation) ≈ 0 once periodic.
  out.diagnostics["timestep"]["powers_W"] = {{"input", response.input_power},
                                             {"damping", response.damping_power},
                                             {"contacts", response.stop_power}};
  // Moreau–Jean's impulses over each output interval [τ_p, τ_{p+1}) divided by its duration: the
  // mean contact forces; a Coulomb contact's tangential displacement at τ_p beside it.
  const Eigen::VectorXd& tau = response.tau;
  const auto p = tau.size();
  Table f{"contact_force.csv", {"tau [-]", "time [s]"}, {tau, tau / forcing.frequency_hz}};
  nlohmann::json friction = nlohmann::json::array();
  for (size_t c = 0; c < contacts.size(); ++c) {
    const Eigen::VectorXd force = response.contact_force.row(static_cast<Eigen::Index>(c)).transpose();
    f.header.push_back("f_c_" + contact_label(scene, c) + " [N]");
    f.columns.push_back(force);
    const auto* coulomb = dynamic_cast<const contact::CoulombFriction*>(contacts[c].law.get());
    if (coulomb == nullptr) continue;
    Eigen::VectorXd w(p);
    for (Eigen::Index k = 0; k < p; ++k) w(k) = contacts[c].displacement(response.displacement.col(k));
    f.header.push_back("w_c_" + contact_label(scene, c) + " [m]");
    f.columns.push_back(w);
    // The slip force μ N, or μ times the normal stop's mean reaction over the same interval.
    const double mu = coulomb->parameters().friction_coefficient;
    const Eigen::VectorXd slip = contacts[c].normal >= 0
                                     ? Eigen::VectorXd(mu * response.contact_force.row(contacts[c].normal).transpose())
                                     : Eigen::VectorXd::Constant(p, coulomb->slip_force());
    friction.push_back(coulomb_diagnostics(contact_label(scene, c), force, w, slip, forcing.frequency_hz, "output_samples"));
  }
  if (!friction.empty()) out.diagnostics["friction"] = friction;
  out.tables.push_back(std::move(f));
}

void basis_plot(const Scene& scene, AnalysisResult& out) {
  const auto basis = scene.trial();
  const int p = scene.output.samples;
  const int m = basis.dimension();
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(p, 0.0, 1.0 - 1.0 / p);
  Eigen::MatrixXd values = basis.values(tau, scene.analysis.derivative);  // P × M
  // Unit-integral normalization ∫₀¹ φ_{J,k} = 1 [JL14 Sec. 3.3] = orthonormal × 2^{J/2}.
  if (scene.analysis.unit_integral) values *= std::sqrt(static_cast<double>(m));
  std::vector<int> functions = scene.analysis.functions;
  if (functions.empty()) {
    for (int k = 0; k < m; ++k) functions.push_back(k);
  }
  const std::string symbol = basis.is_fourier() ? "q" : "phi";
  Table t{"basis_functions.csv", {"tau [-]"}, {tau}};
  for (int k : functions) {
    t.header.push_back((scene.analysis.derivative ? "d" + symbol : symbol) + "_" + std::to_string(k) +
                       (scene.analysis.derivative ? "/dtau [-]" : " [-]"));
    t.columns.push_back(values.col(k));
  }
  out.tables.push_back(std::move(t));
  out.status = solvers::SolveStatus::Converged;  // nothing to solve: the values are exact
  out.diagnostics["basis"] = {{"family", basis.name()},
                              {"dimension", m},
                              {"level", static_cast<int>(std::lround(std::log2(m)))},
                              {"max_pointwise_derivative", std::min(basis.max_derivative(), 1000)},
                              {"normalization", scene.analysis.unit_integral ? "unit-integral" : "orthonormal"},
                              {"functions", functions},
                              {"derivative", scene.analysis.derivative}};
  out.summary = basis.name() + ", M = " + std::to_string(m) + ": " + std::to_string(functions.size()) +
                " functions on " + std::to_string(p) + " samples";
}

}  // namespace wbm::scene::detail
