#include <wbm/scene/analysis.hpp>

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

namespace wbm::scene {

using namespace detail;

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

AnalysisResult run_analysis(const Scene& given, const Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  AnalysisResult out;
  std::optional<Scene> reduced;  // a deck is reduced here, not when the scene is read
  if (given.structure && given.structure->awaiting_reduction()) {
    reduced = given;
    reduce_structure(*reduced);
    for (size_t i = given.warnings.size(); i < reduced->warnings.size(); ++i) out.warnings.push_back(reduced->warnings[i]);
  }
  const Scene& scene = reduced ? *reduced : given;
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
  if (scene.structure && scene.structure->deck) out.diagnostics["reduction"] = scene.structure->deck->reduction;
  out.diagnostics["analysis"] = std::string(to_string(scene.analysis.kind));
  out.diagnostics["converged"] = out.converged();
  out.diagnostics["status"] = std::string(solvers::to_string(out.status));
  if (out.stop) out.diagnostics["stop"] = std::string(solvers::to_string(*out.stop));
  out.diagnostics["wall_time_s"] = seconds_since(start);
  return out;
}

}  // namespace wbm::scene
