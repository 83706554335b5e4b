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

// analysis.stability: every level's stability through the exact orbit with elastic impacts near it
// (NonlinearModes::stability of the backbone: seeded from the level, else from the last exact orbit
// found), as backbone.csv's columns stable, max_multiplier, exact_frequency, orbit_distance and
// impacts (empty where a level has no verdict, its status saying why) and diagnostics.nnm_stability.
void level_stability(const solvers::NonlinearModes& modes, const solvers::Backbone& b, const Progress& progress,
                     std::vector<std::string>& header, std::vector<Eigen::VectorXd>& columns,
                     std::vector<std::string>& status, AnalysisResult& out) {
  const auto n = static_cast<Eigen::Index>(b.levels.size());
  Eigen::VectorXd stable(n), modulus(n), frequency(n), distance(n), impacts(n);
  const solvers::ModeStabilityOptions options;
  int counts[3] = {0, 0, 0};  // stable, unstable, no verdict
  const auto start = std::chrono::steady_clock::now();
  const auto results = modes.stability(b, options, [&](size_t i, size_t count) {
    if (progress) {
      progress(static_cast<double>(i + 1) / static_cast<double>(count),
               "stability of level " + std::to_string(i + 1) + " of " + std::to_string(count));
    }
  });
  for (Eigen::Index i = 0; i < n; ++i) {
    const solvers::ModeStability& r = results[static_cast<size_t>(i)];
    stable(i) = r.available ? (r.stable ? 1.0 : 0.0) : NAN;
    modulus(i) = r.available ? r.max_modulus : NAN;
    frequency(i) = r.available ? r.frequency_hz : NAN;
    distance(i) = r.available ? r.distance : NAN;
    impacts(i) = r.available ? r.impacts : NAN;
    status.push_back(r.available        ? (r.stable ? "stable" : "unstable")
                     : r.orbit.converged() ? "no verdict: the exact orbit found is beyond max_distance"
                                           : "no verdict: no exact orbit found near the level");
    ++counts[r.available ? (r.stable ? 0 : 1) : 2];
  }
  header.insert(header.end(), {"stable [-]", "max_multiplier [-]", "exact_frequency [Hz]", "orbit_distance [-]",
                               "impacts [-]"});
  columns.insert(columns.end(), {stable, modulus, frequency, distance, impacts});
  out.diagnostics["nnm_stability"] = {
      {"stable", counts[0]},
      {"unstable", counts[1]},
      {"no_verdict", counts[2]},
      {"max_distance", options.max_distance},
      {"stability_tolerance", options.orbit.stability_tolerance},
      {"shooting_tolerance", options.orbit.newton.tolerance},
      {"wall_time_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()}};
}

}  // namespace

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
  if (!b.complete()) b.message += way_out(scene, b.stop, b.stalled_residual);
  const BackboneColumns c = backbone_columns(modes, b);
  const Eigen::Index n = c.energy.size();
  if (n > 0) {
    std::vector<std::string> header = {"energy [-]", "frequency [Hz]", "rayleigh_frequency [Hz]",
                                       "max_penetration [gap]", "complementarity [gap]", "normalization_error [-]",
                                       "max_contact_force [N]", "newton_iterations [-]"};
    std::vector<Eigen::VectorXd> columns = {c.energy,          c.frequency_hz,        c.rayleigh_frequency_hz,
                                           c.max_penetration, c.complementarity,     c.normalization_error,
                                           c.max_contact_force, c.newton_iterations};
    if (!continuation) {
      header.insert(header.end(), {"powell_iterations [-]", "G_i [gap]", "G_e [-]"});
      columns.insert(columns.end(), {c.powell_iterations, c.inequality_measure, c.equality_measure});
    }
    header.insert(header.end(), {"first_mode_share [-]", "other_mode [-]", "other_harmonic [-]", "other_share [-]"});
    columns.insert(columns.end(), {c.first_mode_share, c.other_mode, c.other_harmonic, c.other_share});
    std::vector<std::string> status;
    if (a.stability) level_stability(modes, b, progress, header, columns, status, out);
    out.tables.push_back({"backbone.csv", header, columns, status});
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
  std::optional<solvers::SolveStatus> first_failed_level;  // the first level asked for that did not converge
  nlohmann::json included = nlohmann::json::array();
  for (double energy : a.levels) {
    const solvers::ModeLevel* it = b.included_at(energy);
    if (it == nullptr || !it->converged()) {
      if (!first_failed_level && it != nullptr) first_failed_level = it->status;
      included.push_back({{"energy", energy}, {"converged", false},
                          {"message", it == nullptr ? "not reached by the backbone" : it->message}});
      continue;
    }
    included.push_back(nlohmann::json(*it));
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
  // The one definition of a converged backbone (Backbone::converged), as in the Python module.
  out.stop = b.stop;
  out.status = b.converged(a.levels) ? solvers::SolveStatus::Converged
               : b.complete()        ? first_failed_level.value_or(solvers::SolveStatus::PathEnded)
                                     : solvers::SolveStatus::PathEnded;
  double worst_pen = -1e300, worst_comp = 0.0;
  for (const auto& l : b.levels) {
    worst_pen = std::max(worst_pen, l.max_penetration);
    worst_comp = std::max(worst_comp, l.complementarity);
  }
  nlohmann::json failed = b.failed_energies;
  out.diagnostics["nnm"] = {{"algorithm", std::string(to_string(a.algorithm))},
                            {"linear_frequency_hz", modes.linear_frequency_hz()},
                            {"levels", b.levels.size()},
                            {"complete", b.complete()},
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

}  // namespace wbm::scene::detail

namespace wbm::scene {

BackboneColumns backbone_columns(const solvers::NonlinearModes& modes, const solvers::Backbone& b) {
  const auto n = static_cast<Eigen::Index>(b.levels.size());
  BackboneColumns c;
  for (Eigen::VectorXd* v : {&c.energy, &c.frequency_hz, &c.rayleigh_frequency_hz, &c.max_penetration, &c.complementarity,
                             &c.normalization_error, &c.max_contact_force, &c.newton_iterations, &c.powell_iterations,
                             &c.inequality_measure, &c.equality_measure, &c.first_mode_share, &c.other_mode,
                             &c.other_harmonic, &c.other_share}) {
    v->resize(n);
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& l = b.levels[static_cast<size_t>(i)];
    c.energy(i) = l.energy;
    c.frequency_hz(i) = l.frequency_hz;
    c.rayleigh_frequency_hz(i) = l.rayleigh_frequency_hz;
    c.max_penetration(i) = l.max_penetration;
    c.complementarity(i) = l.complementarity;
    c.normalization_error(i) = l.normalization_error;
    c.max_contact_force(i) = l.contact_force.size() > 0 ? l.contact_force.maxCoeff() : 0.0;
    c.newton_iterations(i) = l.newton_iterations;
    c.powell_iterations(i) = l.powell_iterations;
    c.inequality_measure(i) = l.inequality_measure;
    c.equality_measure(i) = l.equality_measure;
    const auto mc = modes.modal_components(l);
    c.first_mode_share(i) = mc.first_mode_share;
    c.other_mode(i) = mc.mode;
    c.other_harmonic(i) = mc.harmonic;
    c.other_share(i) = mc.share;
  }
  return c;
}

}  // namespace wbm::scene
