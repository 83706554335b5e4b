#include <wbm/scene/analysis.hpp>

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

namespace wbm::scene {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// JSON has no NaN/inf: a non-finite diagnostic is written as null.
nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json to_json(const solvers::NewtonReport& r) {
  nlohmann::json norms = nlohmann::json::array();
  for (double v : r.residual_norms) norms.push_back(finite_or_null(v));
  return {{"status", std::string(solvers::to_string(r.status))},
          {"converged", r.converged()},
          {"iterations", r.iterations},
          {"residual_norms", norms},
          {"message", r.message}};
}

nlohmann::json to_json(const solvers::HomotopyReport& h) {
  if (!h.tried) return nullptr;
  return {{"reached", h.reached},          {"sigma_reached", h.sigma_reached}, {"lambda_start", h.lambda_start},
          {"points", h.points},            {"folds", h.folds},                 {"corrector_iterations", h.corrector_iterations},
          {"stop", h.stop}};
}

nlohmann::json to_json(const solvers::WeightedResidualSolution& s) {
  return {{"frequency_hz", s.frequency_hz},
          {"newton", to_json(s.report)},
          {"path", std::string(solvers::to_string(s.path))},
          {"contact_homotopy", to_json(s.homotopy)},
          {"rounding_floor", finite_or_null(s.rounding_floor)},
          {"relative_residual", finite_or_null(s.relative_residual)},
          {"residual_tolerance", s.residual_tolerance},
          {"max_penetration_m", finite_or_null(s.max_penetration)},
          {"max_contact_force_N", finite_or_null(s.max_contact_force)},
          {"collocation_penetration_m", finite_or_null(s.collocation_penetration)},
          {"complementarity_m", finite_or_null(s.complementarity)},
          {"contact_unknowns", s.contact_unknowns},
          {"condition_number", finite_or_null(s.condition_number)},
          {"dropped_harmonics_residual", finite_or_null(s.dropped_harmonics_residual)},
          {"linear_solver", s.linear_solver},
          {"operators", s.operator_rule},
          {"wall_time_s", s.wall_time_s}};
}

std::string format(const char* spec, double v) {
  char b[64];
  std::snprintf(b, sizeof b, spec, v);
  return b;
}

// The column name of the scene's contact c: its DOF, or "dof-other" for a contact between two DOFs.
std::string contact_label(const Scene& scene, size_t c) {
  const Structure& st = *scene.structure;
  const Contact& k = scene.contacts[c];
  return k.against < 0 ? st.dof_name(k.dof) : st.dof_name(k.dof) + "-" + st.dof_name(k.against);
}

// A_h and φ_h of u = Σ_h A_h cos(2πhτ + φ_h), h = 0 … h_max, for each row of `samples` (k × P,
// equispaced over one period), by FFT (spectral::Aft). amplitude, phase: k × (h_max + 1).
void harmonics_of(const Eigen::MatrixXd& samples, int h_max, Eigen::MatrixXd& amplitude, Eigen::MatrixXd& phase) {
  const spectral::Aft aft(2 * h_max + 1, static_cast<int>(samples.cols()), 0.0);
  const Eigen::MatrixXd c = aft.to_frequency(samples);  // {1, cos 2πτ, sin 2πτ, cos 4πτ, …}
  amplitude.resize(samples.rows(), h_max + 1);
  phase.resize(samples.rows(), h_max + 1);
  for (Eigen::Index r = 0; r < samples.rows(); ++r) {
    amplitude(r, 0) = c(r, 0);
    phase(r, 0) = 0.0;
    for (int k = 1; k <= h_max; ++k) {
      amplitude(r, k) = std::hypot(c(r, 2 * k - 1), c(r, 2 * k));
      phase(r, k) = std::atan2(-c(r, 2 * k), c(r, 2 * k - 1));
    }
  }
}

// Per-period files from displacement/velocity of every solver DOF (n × P), shared by solve and
// timestep; the written DOFs are the scene's (massless ones recovered, Scene::expand_displacement).
void period_tables(const Scene& scene, const std::vector<solvers::ContactPoint>& contacts,
                   const solvers::MechanicalSystem& system, double frequency_hz, const Eigen::VectorXd& tau,
                   const Eigen::MatrixXd& solver_displacement, const Eigen::MatrixXd* solver_velocity,
                   AnalysisResult& out) {
  const Structure& st = *scene.structure;
  const Eigen::VectorXd time = tau / frequency_hz;
  const Eigen::MatrixXd displacement = scene.expand_displacement(solver_displacement);
  std::optional<Eigen::MatrixXd> full_velocity;
  if (solver_velocity != nullptr) full_velocity = scene.expand_velocity(solver_displacement, *solver_velocity);
  const Eigen::MatrixXd* velocity = full_velocity ? &*full_velocity : nullptr;
  Table u{"displacement.csv", {"tau [-]", "time [s]"}, {tau, time}};
  nlohmann::json response = nlohmann::json::array();
  for (int dof : scene.output_dofs()) {
    const Eigen::VectorXd v = displacement.row(dof).transpose();
    u.header.push_back("u_" + st.dof_name(dof) + " [m]");
    u.columns.push_back(v);
    response.push_back({{"dof", st.dof_name(dof)},
                        {"max_m", v.maxCoeff()},
                        {"min_m", v.minCoeff()},
                        {"rms_m", solvers::rms(v)}});
  }
  out.diagnostics["response"] = response;
  out.tables.push_back(std::move(u));
  if (velocity != nullptr) {
    Table v{"velocity.csv", {"tau [-]", "time [s]"}, {tau, time}};
    for (int dof : scene.output_dofs()) {
      v.header.push_back("v_" + st.dof_name(dof) + " [m/s]");
      v.columns.push_back(velocity->row(dof).transpose());
    }
    out.tables.push_back(std::move(v));
  }
  if (!contacts.empty() && !contacts.front().law->rigid()) {  // rigid: their impulses (solve_one)
    Table f{"contact_force.csv", {"tau [-]", "time [s]"}, {tau, time}};
    for (size_t k = 0; k < contacts.size(); ++k) {
      const auto& c = contacts[k];
      Eigen::VectorXd force(tau.size());
      for (Eigen::Index p = 0; p < tau.size(); ++p) force(p) = c.law->force(c.displacement(solver_displacement.col(p)));
      f.header.push_back("f_c_" + contact_label(scene, k) + " [N]");
      f.columns.push_back(force);
    }
    out.tables.push_back(std::move(f));
  }
  if (scene.output.harmonics > 0) {  // A_h, φ_h of u = Σ A_h cos(2πhτ + φ_h) from the P samples
    const int h_max = scene.output.harmonics;
    const std::vector<int> dofs = scene.output_dofs();
    Eigen::MatrixXd observed(static_cast<Eigen::Index>(dofs.size()), tau.size());
    for (size_t i = 0; i < dofs.size(); ++i) observed.row(static_cast<Eigen::Index>(i)) = displacement.row(dofs[i]);
    Eigen::MatrixXd amplitude, phase;
    harmonics_of(observed, h_max, amplitude, phase);
    const Eigen::VectorXd h = Eigen::VectorXd::LinSpaced(h_max + 1, 0.0, h_max);
    Table t{"harmonics.csv", {"h [-]", "frequency [Hz]"}, {h, h * frequency_hz}};
    for (size_t i = 0; i < dofs.size(); ++i) {
      const auto r = static_cast<Eigen::Index>(i);
      t.header.push_back("A_" + st.dof_name(dofs[i]) + " [m]");
      t.columns.push_back(amplitude.row(r).transpose());
      t.header.push_back("phase_" + st.dof_name(dofs[i]) + " [rad]");
      t.columns.push_back(phase.row(r).transpose());
    }
    out.tables.push_back(std::move(t));
  }
  if (velocity != nullptr) {
    out.tables.push_back({"energy.csv",
                          {"tau [-]", "time [s]", "energy [J]"},
                          {tau, time, solvers::system_energy(system, contacts, solver_displacement, *solver_velocity)}});
  }
}

// Per point of a sweep or branch: A_h and φ_h of each observed DOF (rows: points). `samples[i]` is
// the observed DOFs' samples (k × P) at frequency `hz[i]`.
Table point_harmonics(const Scene& scene, const std::string& file, const std::vector<int>& observed,
                      const std::vector<double>& hz, const std::vector<Eigen::MatrixXd>& samples) {
  const int h_max = scene.output.harmonics;
  const auto n = static_cast<Eigen::Index>(hz.size());
  Table t{file, {"frequency [Hz]"}, {Eigen::Map<const Eigen::VectorXd>(hz.data(), n)}};
  std::vector<Eigen::VectorXd> columns(observed.size() * 2 * static_cast<size_t>(h_max + 1), Eigen::VectorXd(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::MatrixXd amplitude, phase;
    harmonics_of(samples[static_cast<size_t>(i)], h_max, amplitude, phase);
    size_t c = 0;
    for (size_t d = 0; d < observed.size(); ++d) {
      for (int h = 0; h <= h_max; ++h) {
        columns[c++](i) = amplitude(static_cast<Eigen::Index>(d), h);
        columns[c++](i) = phase(static_cast<Eigen::Index>(d), h);
      }
    }
  }
  for (int dof : observed) {
    const std::string name = scene.structure->dof_name(dof);
    for (int h = 0; h <= h_max; ++h) {
      const std::string suffix = std::to_string(h) + "_" + name;  // (not "A" + to_string: GCC 12 -Wrestrict false positive)
      t.header.push_back(std::string("A").append(suffix).append(" [m]"));
      t.header.push_back(std::string("phase").append(suffix).append(" [rad]"));
    }
  }
  t.columns.insert(t.columns.end(), columns.begin(), columns.end());
  return t;
}

// Samples (rows: `observed` scene DOFs, P columns) of a weighted-residual solution given by the
// trial coefficients of the solver DOFs `kept` (rows of `coefficients`; with a condensation, every
// solver DOF, so that massless DOFs can be recovered).
Eigen::MatrixXd observed_samples(const Scene& scene, const solvers::TimeBasis& trial, const Eigen::MatrixXd& coefficients,
                                 const std::vector<int>& kept, const std::vector<int>& observed,
                                 const Eigen::VectorXd& tau, double frequency_hz) {
  Eigen::MatrixXd u(coefficients.rows(), tau.size());
  for (Eigen::Index r = 0; r < coefficients.rows(); ++r) {
    u.row(r) = solvers::evaluate_trial(trial, coefficients, static_cast<int>(r), tau, frequency_hz).transpose();
  }
  Eigen::MatrixXd out(static_cast<Eigen::Index>(observed.size()), tau.size());
  if (scene.condensation) {
    const Eigen::MatrixXd full = scene.expand_displacement(u);  // kept = every solver DOF
    for (size_t i = 0; i < observed.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = full.row(observed[i]);
    return out;
  }
  for (size_t i = 0; i < observed.size(); ++i) {
    const auto at = std::find(kept.begin(), kept.end(), observed[i]);
    out.row(static_cast<Eigen::Index>(i)) = u.row(at - kept.begin());
  }
  return out;
}

// [basis] harmonic_selection: warn when the solutions leave more than kDroppedWarning ‖b‖ of the
// full residual in the dropped harmonics (the selection is then an approximation, not the full
// harmonic balance), with the largest value and where.
constexpr double kDroppedWarning = 1e-6;
std::string selection_label(const Scene& scene) {
  if (scene.basis.harmonic_selection == "odd") return "\"odd\"";
  std::string l = "[";
  for (size_t i = 0; i < scene.basis.selected_harmonics.size(); ++i) {
    l.append(i == 0 ? "" : ", ").append(std::to_string(scene.basis.selected_harmonics[i]));
  }
  return l + "]";
}
void warn_dropped_harmonics(const Scene& scene, const std::vector<double>& hz, const std::vector<double>& dropped,
                            AnalysisResult& out) {
  if (scene.basis.selected_harmonics.empty()) return;
  double worst = 0.0, at = 0.0;
  for (size_t i = 0; i < dropped.size(); ++i) {
    if (std::isfinite(dropped[i]) && dropped[i] > worst) {
      worst = dropped[i];
      at = hz[i];
    }
  }
  if (!(worst > kDroppedWarning)) return;
  out.warnings.push_back("harmonic_selection = " + selection_label(scene) + ": the contact forces have " +
                         "harmonics outside the selection (e.g. the mean and even harmonics of a one-sided stop); the "
                         "residual left in the dropped harmonics reaches " + format("%.3g", worst) + " ‖b‖ at f = " +
                         format("%.6g", at) + " Hz (> " + format("%g", kDroppedWarning) + "), so these results are "
                         "not the full harmonic balance's: keep every harmonic (remove harmonic_selection) to compare");
}

void solve_one(const Scene& scene, AnalysisResult& out) {
  const auto system = scene.system();
  const auto forcing = scene.harmonic_forcing();
  const auto contacts = scene.contact_points();
  const auto trial = scene.trial();
  const auto weighting = scene.weighting();
  const auto solution =
      solvers::solve_weighted_residual(system, forcing, contacts, trial, weighting, scene.weighted_residual_options());
  out.converged = solution.report.converged();
  out.diagnostics["solution"] = to_json(solution);
  out.summary = trial.name() + ":" + weighting.name() + ", M = " + std::to_string(trial.dimension()) + ", " +
                std::string(solvers::to_string(scene.basis.formulation)) + ", f = " +
                format("%g", forcing.frequency_hz) + " Hz: " + solution.report.message + ", relative residual " +
                format("%.2e", solution.relative_residual) + ", " + format("%.3f", solution.wall_time_s * 1e3) + " ms";
  if (!scene.basis.selected_harmonics.empty()) {
    out.summary += "; harmonic_selection = " + selection_label(scene) + ": residual in the dropped harmonics " +
                   format("%.2e", solution.dropped_harmonics_residual) + " ‖b‖";
    warn_dropped_harmonics(scene, {forcing.frequency_hz}, {solution.dropped_harmonics_residual}, out);
  }
  if (!out.converged) return;  // no curve from an unconverged iterate
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
    // The multipliers at their instants τ_k = (k + ½)/M: the mean force over each cell.
    const int m = trial.dimension();
    const Eigen::VectorXd tk = (Eigen::VectorXd::LinSpaced(m, 0.0, m - 1.0).array() + 0.5) / m;
    Table f{"contact_force.csv", {"tau [-]", "time [s]"}, {tk, tk / forcing.frequency_hz}};
    for (size_t c = 0; c < contacts.size(); ++c) {
      f.header.push_back("f_c_" + contact_label(scene, c) + " [N]");
      f.columns.push_back(solution.contact_force_samples.row(static_cast<Eigen::Index>(c)).transpose());
    }
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
    nlohmann::json point = to_json(solution);
    point["restarted_from_linear"] = restarted;
    points.push_back(point);
    if (progress) {
      progress(static_cast<double>(i + 1) / static_cast<double>(frequencies.size()),
               "point " + std::to_string(i + 1) + "/" + std::to_string(frequencies.size()) + ", f = " + format("%.6g", f) + " Hz");
    }
    if (!solution.report.converged()) {
      ++failed;
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
  out.converged = failed == 0;
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
  const bool rigid = scene.rigid();
  auto mj = scene.moreau_jean;
  const auto response = rigid ? solvers::integrate_moreau_jean_to_periodic(system, forcing, contacts, mj)
                              : solvers::integrate_to_periodic(system, forcing, contacts, options);
  const auto& rep = response.report;
  out.converged = rep.converged();
  const std::string method = rigid ? "Moreau–Jean (theta = 0.5, restitution " + format("%g", mj.restitution) + ", " +
                                         std::to_string(mj.steps_per_period) + " steps per period)"
                                   : "GSL msbdf (variable-order BDF)";
  out.diagnostics["timestep"] = {{"method", method},
                                 {"status", std::string(solvers::to_string(rep.status))},
                                 {"converged", rep.converged()},
                                 {"periods", rep.periods},
                                 {"steps", rep.steps},
                                 {"periodicity", rep.periodicity.empty() ? nlohmann::json(nullptr)
                                                                         : finite_or_null(rep.periodicity.back())},
                                 {"message", rep.message},
                                 {"wall_time_s", rep.wall_time_s}};
  out.summary = (rigid ? "Moreau–Jean at " : "BDF at ") + format("%g", forcing.frequency_hz) + " Hz: " + rep.message + ", " +
                std::to_string(rep.steps) + " steps, " + format("%.3f", rep.wall_time_s) + " s";
  if (!out.converged) return;
  period_tables(scene, contacts, system, forcing.frequency_hz, response.tau, response.displacement,
                &response.velocity, out);
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
  out.converged = true;
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

void continuation(const Scene& scene, const Progress& progress, AnalysisResult& out) {
  const auto started = std::chrono::steady_clock::now();
  const auto& range = *scene.forcing->range;
  const solvers::WeightedResidual base(scene.system(), scene.harmonic_forcing(range.from_hz), scene.contact_points(),
                                       scene.trial(), scene.weighting(), scene.weighted_residual_options());
  solvers::ResponseCurveOptions o;
  o.parameter_min = std::min(range.from_hz, range.to_hz);
  o.parameter_max = std::max(range.from_hz, range.to_hz);
  o.direction = range.to_hz > range.from_hz ? +1 : -1;
  o.max_step = scene.analysis.max_step;
  o.initial_step = std::min(o.initial_step, o.max_step);
  o.max_parameter_step = scene.analysis.max_frequency_step_hz;
  o.max_points = scene.analysis.max_points;
  o.max_state = scene.analysis.max_state;
  o.stability = scene.analysis.stability;
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
      reached = std::max(reached, std::abs(p.parameter - range.from_hz) / std::abs(range.to_hz - range.from_hz));
      progress(std::min(reached, 1.0), "point " + std::to_string(i + 1) + ", f = " + format("%.6g", p.parameter) +
                                           " Hz, step " + format("%.2g", p.step));
    };
  }
  const auto curve = solvers::trace_response(base, o);
  const std::string dof = scene.structure->dof_name(scene.forcing->dof);
  const auto n = static_cast<Eigen::Index>(curve.points.size());
  Eigen::VectorXd f(n), umax(n), umin(n), amp(n), force(n), stable(n), mu(n), mu_error(n), steps(n), its(n);
  std::vector<std::string> verdict(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& p = curve.points[static_cast<size_t>(i)];
    // The error estimate is missing (empty cell) where it could not be formed (floquet.hpp).
    mu_error(i) = std::isfinite(p.max_multiplier_error) ? p.max_multiplier_error : NAN;
    steps(i) = p.monodromy_steps;
    verdict[static_cast<size_t>(i)] = !std::isfinite(p.max_multiplier_error) ? "no error estimate"
                                      : p.stability_settled                 ? "settled"
                                                                            : "within its error estimate";
    f(i) = p.frequency_hz;
    umax(i) = p.max_displacement;
    umin(i) = p.min_displacement;
    amp(i) = p.amplitude;
    force(i) = p.max_contact_force;
    stable(i) = p.stable ? 1.0 : 0.0;
    mu(i) = p.max_multiplier;
    its(i) = p.corrector_iterations;
  }
  if (n > 0) {
    std::vector<std::string> header = {"frequency [Hz]", "u_max_" + dof + " [m]", "u_min_" + dof + " [m]",
                                       "amplitude_" + dof + " [m]", "max_contact_force [N]"};
    std::vector<Eigen::VectorXd> columns = {f, umax, umin, amp, force};
    if (o.stability) {
      header.insert(header.end(), {"stable [-]", "max_floquet_multiplier [-]", "max_floquet_multiplier_error [-]",
                                   "monodromy_steps [-]"});
      columns.insert(columns.end(), {stable, mu, mu_error, steps});
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
    folds.push_back({{"frequency_hz", fold.parameter}, {"floquet_crossing", crossing}, {"amplitude_m", amplitudes}});
  }
  if (nf > 0) {
    std::vector<std::string> header = {"frequency [Hz]", "floquet_crossing [-]", "u_max_" + dof + " [m]",
                                       "u_min_" + dof + " [m]", "amplitude_" + dof + " [m]"};
    std::vector<Eigen::VectorXd> columns = {fold_hz, fold_ok, fold_max, fold_min, fold_amp};
    for (size_t d = 0; per_point && d < observed.size(); ++d) {
      if (observed[d] == scene.forcing->dof) continue;  // its columns are there already
      header.push_back("amplitude_" + scene.structure->dof_name(observed[d]) + " [m]");
      columns.push_back(fold_observed[d]);
    }
    out.tables.push_back({"folds.csv", header, columns});
  }
  out.converged = curve.stop == solvers::StopReason::RangeReached;
  out.diagnostics["continuation"] = {{"points", curve.points.size()},
                                     {"folds", folds},
                                     {"stop", std::string(solvers::to_string(curve.stop))},
                                     {"message", curve.message},
                                     {"rejected_steps", curve.rejected_steps},
                                     {"corners", curve.kinks},
                                     {"corrector_iterations", curve.corrector_iterations},
                                     {"continuation_time_s", curve.wall_time_s},
                                     {"stability_time_s", curve.stability_time_s},
                                     {"unsettled_stability_points", curve.unsettled_points}};
  if (curve.unsettled_points > 0) {
    out.warnings.push_back("continuation: at " + std::to_string(curve.unsettled_points) +
                           " point(s) a Floquet multiplier lies within twice its error estimate of the unit circle "
                           "even with 16x the monodromy steps; their stability verdict may be wrong (branch.csv, "
                           "status column); raise [output] samples");
  }
  out.summary = base.trial().name() + ":" + base.weighting().name() + ", M = " + std::to_string(base.dimension()) +
                ", continuation " + format("%g", range.from_hz) + " → " + format("%g", range.to_hz) + " Hz: " +
                std::to_string(curve.points.size()) + " points, " + std::to_string(curve.folds.size()) + " folds, " +
                std::string(solvers::to_string(curve.stop)) + " (" +
                format("%.3f", std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()) +
                " s in all: continuation " + format("%.3f", curve.wall_time_s) + " s, stability " +
                format("%.3f", curve.stability_time_s) + " s)";
}

nlohmann::json to_json(const solvers::ModeLevel& l) {
  return {{"energy", l.energy},
          {"converged", l.converged()},
          {"status", std::string(solvers::to_string(l.status))},
          {"residual_norm", finite_or_null(l.residual_norm)},
          {"tolerance", l.tolerance},
          {"frequency_hz", finite_or_null(l.frequency_hz)},
          {"rayleigh_frequency_hz", finite_or_null(l.rayleigh_frequency_hz)},
          {"equality_multiplier", finite_or_null(l.equality_multiplier)},
          {"max_penetration_gaps", finite_or_null(l.max_penetration)},
          {"complementarity_gaps", finite_or_null(l.complementarity)},
          {"normalization_error", finite_or_null(l.normalization_error)},
          {"powell_iterations", l.powell_iterations},
          {"newton_iterations", l.newton_iterations},
          {"inequality_measure", finite_or_null(l.inequality_measure)},
          {"equality_measure", finite_or_null(l.equality_measure)},
          {"message", l.message},
          {"wall_time_s", l.wall_time_s}};
}

void nonlinear_modes(const Scene& scene, const Progress& progress, AnalysisResult& out) {
  const ModeProblem problem = mode_problem(scene);
  const Analysis& a = scene.analysis;
  const solvers::NonlinearModes modes(problem.system, problem.stops, problem.options);
  solvers::Backbone b;
  const bool continuation = a.algorithm == NnmAlgorithm::Continuation;
  if (continuation) {
    solvers::BackboneContinuationOptions o;
    o.energy_min = a.energy_min;
    o.energy_max = a.energy_max;
    o.penalty_stiffness = problem.penalty_stiffness;
    o.max_step = a.max_step;
    o.initial_step = std::min(o.initial_step, o.max_step);
    o.max_energy_step = a.max_energy_step;
    o.max_points = a.max_points;
    o.include = a.levels;
    double reached = 0.0;
    if (progress) {
      o.on_point = [&](size_t i, const solvers::BranchPoint& p) {
        reached = std::max(reached, (p.parameter - o.energy_min) / (o.energy_max - o.energy_min));
        progress(std::clamp(reached, 0.0, 1.0), "point " + std::to_string(i + 1) + ", E = " + format("%.4g", p.parameter) +
                                                    ", step " + format("%.2g", p.step));
      };
    }
    b = modes.continue_backbone(o);
  } else {
    solvers::BackboneOptions o;
    o.energy_min = a.energy_min;
    o.energy_max = a.energy_max;
    o.max_step = a.max_energy_step;
    o.initial_step = std::min(o.initial_step, o.max_step);
    o.min_step = std::min(o.min_step, o.initial_step);
    o.include = a.levels;
    int count = 0;
    if (progress) {
      o.on_level = [&](const solvers::ModeLevel& l) {
        ++count;
        progress(std::clamp((l.energy - o.energy_min) / (o.energy_max - o.energy_min), 0.0, 1.0),
                 "level " + std::to_string(count) + ", E = " + format("%.4g", l.energy) + ", " +
                     std::to_string(l.powell_iterations) + " Powell iterations");
      };
    }
    b = modes.backbone(o);
  }
  const auto n = static_cast<Eigen::Index>(b.levels.size());
  Eigen::VectorXd e(n), f(n), fr(n), pen(n), comp(n), norm(n), force(n), its(n), gi(n), ge(n), powell(n);
  Eigen::VectorXd first_share(n), other_mode(n), other_harmonic(n), other_share(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& l = b.levels[static_cast<size_t>(i)];
    e(i) = l.energy;
    f(i) = l.frequency_hz;
    fr(i) = l.rayleigh_frequency_hz;
    pen(i) = l.max_penetration;
    comp(i) = l.complementarity;
    norm(i) = l.normalization_error;
    force(i) = l.contact_force.size() > 0 ? l.contact_force.maxCoeff() : 0.0;
    its(i) = l.newton_iterations;
    gi(i) = l.inequality_measure;
    ge(i) = l.equality_measure;
    powell(i) = l.powell_iterations;
    const auto mc = modes.modal_components(l);
    first_share(i) = mc.first_mode_share;
    other_mode(i) = mc.mode;
    other_harmonic(i) = mc.harmonic;
    other_share(i) = mc.share;
  }
  if (n > 0) {
    std::vector<std::string> header = {"energy [-]", "frequency [Hz]", "rayleigh_frequency [Hz]",
                                       "max_penetration [gap]", "complementarity [gap]", "normalization_error [-]",
                                       "max_contact_force [N]", "newton_iterations [-]"};
    std::vector<Eigen::VectorXd> columns = {e, f, fr, pen, comp, norm, force, its};
    if (!continuation) {
      header.insert(header.end(), {"powell_iterations [-]", "G_i [gap]", "G_e [-]"});
      columns.insert(columns.end(), {powell, gi, ge});
    }
    header.insert(header.end(), {"first_mode_share [-]", "other_mode [-]", "other_harmonic [-]", "other_share [-]"});
    columns.insert(columns.end(), {first_share, other_mode, other_harmonic, other_share});
    out.tables.push_back({"backbone.csv", header, columns});
  }
  if (!b.folds.empty()) {  // each fold at its own frequency (the backbone can be multivalued in E)
    Eigen::VectorXd fold_hz(static_cast<Eigen::Index>(b.fold_levels.size()));
    std::vector<std::string> state;
    for (Eigen::Index k = 0; k < fold_hz.size(); ++k) {
      const solvers::ModeLevel& l = b.fold_levels[static_cast<size_t>(k)];
      fold_hz(k) = std::isfinite(l.frequency_hz) ? l.frequency_hz : NAN;
      state.push_back(l.converged() ? "on the branch (residual within tolerance)"
                                    : "interpolated on the step (residual " + format("%.2g", l.residual_norm) + ")");
    }
    out.tables.push_back({"folds.csv", {"energy [-]", "frequency [Hz]"},
                          {Eigen::Map<const Eigen::VectorXd>(b.folds.data(), static_cast<Eigen::Index>(b.folds.size())), fold_hz},
                          state});
  }
  // Mode shapes at the asked energies.
  const Structure& st = *scene.structure;
  std::vector<int> dofs = scene.output.dofs.empty() ? std::vector<int>{} : scene.output_dofs();
  if (dofs.empty()) {
    for (int i = 0; i < st.dofs(); ++i) dofs.push_back(i);  // nnm default: every DOF (space-time maps)
  }
  const int p = scene.output.samples;
  bool levels_ok = true;
  nlohmann::json included = nlohmann::json::array();
  for (double energy : a.levels) {
    const auto it = std::find_if(b.included.begin(), b.included.end(),
                                 [&](const solvers::ModeLevel& l) { return std::abs(l.energy - energy) <= 1e-12 * energy; });
    if (it == b.included.end() || !it->converged()) {
      levels_ok = false;
      included.push_back({{"energy", energy}, {"converged", false},
                          {"message", it == b.included.end() ? "not reached by the backbone" : it->message}});
      continue;
    }
    included.push_back(to_json(*it));
    const Eigen::MatrixXd u = modes.displacement(*it, p), v = modes.velocity(*it, p);
    const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(p, 0.0, 1.0 - 1.0 / p);
    Table t{"mode_E" + format("%g", energy) + ".csv", {"tau [-]", "time [s]"}, {tau, tau / it->frequency_hz}};
    for (int d : dofs) {
      t.header.push_back("u_" + st.dof_name(d) + " [m]");
      t.columns.push_back(u.row(d).transpose());
    }
    for (int d : dofs) {
      t.header.push_back("v_" + st.dof_name(d) + " [m/s]");
      t.columns.push_back(v.row(d).transpose());
    }
    out.tables.push_back(std::move(t));
    const int m = problem.options.samples;
    Table c{"mode_E" + format("%g", energy) + "_contact.csv", {"tau [-]"}, {Eigen::VectorXd::LinSpaced(m, 0.0, 1.0 - 1.0 / m)}};
    for (size_t k = 0; k < problem.stops.size(); ++k) {
      c.header.push_back("contact_force_" + st.dof_name(problem.stops[k].dof) + " [N]");
      c.columns.push_back(it->contact_force.segment(static_cast<Eigen::Index>(k) * m, m));
    }
    out.tables.push_back(std::move(c));
  }
  out.converged = b.complete && levels_ok;
  double worst_pen = -1e300, worst_comp = 0.0;
  for (const auto& l : b.levels) {
    worst_pen = std::max(worst_pen, l.max_penetration);
    worst_comp = std::max(worst_comp, l.complementarity);
  }
  nlohmann::json failed = b.failed_energies;
  out.diagnostics["nnm"] = {{"algorithm", std::string(to_string(a.algorithm))},
                            {"linear_frequency_hz", modes.linear_frequency_hz()},
                            {"levels", b.levels.size()},
                            {"complete", b.complete},
                            {"message", b.message},
                            {"folds", b.folds},
                            {"corners", b.kinks},
                            {"rejected_steps", b.rejected_steps},
                            {"failed_energies", failed},
                            {"worst_penetration_gaps", n > 0 ? finite_or_null(worst_pen) : nullptr},
                            {"worst_complementarity_gaps", finite_or_null(worst_comp)},
                            {"included", included},
                            {"wall_time_s", b.wall_time_s}};
  const auto& last = b.levels.empty() ? solvers::ModeLevel{} : b.levels.back();
  out.summary = "first nonlinear mode, N = " + std::to_string(problem.options.harmonics) + ", m = " +
                std::to_string(problem.options.samples) + ", " + std::string(to_string(a.algorithm)) + ": " + std::to_string(b.levels.size()) +
                " levels, linear " + format("%.3f", modes.linear_frequency_hz()) + " Hz, E = " +
                format("%g", last.energy) + ": " + format("%.3f", last.frequency_hz) + " Hz; " + b.message + " (" +
                format("%.2f", b.wall_time_s) + " s)";
}

}  // namespace

ModeProblem mode_problem(const Scene& scene) {
  if (scene.analysis.kind != AnalysisKind::NonlinearModes || !scene.structure) {
    throw std::logic_error("mode_problem: scene \"" + scene.name + "\" is not an nnm scene with a structure");
  }
  ModeProblem p;
  p.system = scene.system();
  p.system.damping = Eigen::SparseMatrix<double>(p.system.dofs(), p.system.dofs());
  for (const auto& c : scene.contacts) {
    p.stops.push_back({c.dof, c.gap, c.along});
    if (c.law == ContactLawKind::Linear) p.penalty_stiffness = c.stiffness;
  }
  p.options.harmonics = scene.analysis.harmonics;
  p.options.samples = scene.analysis.samples;
  if (scene.analysis.algorithm == NnmAlgorithm::Sequential) p.options.algorithm = solvers::ModeAlgorithm::Sequential;
  return p;
}

AnalysisResult run_analysis(const Scene& scene, const Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  AnalysisResult out;
  const bool unforced = scene.analysis.kind == AnalysisKind::BasisPlot || scene.analysis.kind == AnalysisKind::NonlinearModes;
  if (scene.analysis.kind != AnalysisKind::BasisPlot && (!scene.structure || (!unforced && !scene.forcing))) {
    throw std::logic_error("run_analysis: scene \"" + scene.name + "\" lacks [structure] or [forcing]; load it "
                           "with load_scene");
  }
  switch (scene.analysis.kind) {
    case AnalysisKind::Solve:
      if (scene.forcing->range) {
        solve_sweep(scene, progress, out);
      } else {
        solve_one(scene, out);
      }
      break;
    case AnalysisKind::Timestep: timestep(scene, progress, out); break;
    case AnalysisKind::BasisPlot: basis_plot(scene, out); break;
    case AnalysisKind::Continuation: continuation(scene, progress, out); break;
    case AnalysisKind::NonlinearModes: nonlinear_modes(scene, progress, out); break;
  }
  if (scene.condensation) {  // say which DOFs were condensed and how each contact reaches the structure
    nlohmann::json massless = nlohmann::json::array(), laws = nlohmann::json::array();
    for (int d : scene.condensation->massless) massless.push_back(scene.structure->dof_name(d));
    for (const auto& c : scene.condensation->contacts) laws.push_back(c.law->describe());
    out.diagnostics["condensation"] = {{"massless_dofs", massless}, {"contact_laws_on_the_structure", laws}};
  }
  out.diagnostics["analysis"] = std::string(to_string(scene.analysis.kind));
  out.diagnostics["converged"] = out.converged;
  out.diagnostics["wall_time_s"] = seconds_since(start);
  return out;
}

}  // namespace wbm::scene
