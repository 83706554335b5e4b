#include "modes.hpp"

#include <algorithm>
#include <stdexcept>

#include "scene.hpp"

namespace wbm::reproduce {

scene::Scene ll11_scene(const Run& run) {
  const std::filesystem::path path = scene_directory() / "ll11_rod.toml";
  scene::Scene s = scene::load_scene(path);
  if (!s.structure || s.structure->kind != scene::StructureKind::Rod ||
      s.analysis.kind != scene::AnalysisKind::NonlinearModes || s.contacts.empty()) {
    throw std::invalid_argument(path.string() + ": the LL11 reproductions need the FE rod, [contact] stops and "
                                "[analysis] type = \"nnm\"");
  }
  if (run.quick()) {
    s.analysis.harmonics = 8;
    s.analysis.samples = 64;
    s.analysis.energy_max = std::min(s.analysis.energy_max, 3.0);
    s.output.samples = 128;
  }
  return s;
}

scene::AnalysisResult run_modes(Run& run, const scene::Scene& scene, const std::string& prefix) {
  scene::AnalysisResult r = scene::run_analysis(scene);
  for (const auto& t : r.tables) run.table(prefix + t.file, t.header, t.columns);
  if (!r.converged()) {
    run.fail(prefix + scene.name + ": " + r.diagnostics["nnm"].value("message", std::string("not converged")));
  }
  return r;
}

const Eigen::VectorXd& result_column(const scene::AnalysisResult& result, const std::string& file,
                                     const std::string& column) {
  for (const auto& t : result.tables) {
    if (t.file != file) continue;
    for (size_t i = 0; i < t.header.size(); ++i) {
      if (t.header[i] == column) return t.columns[i];
    }
  }
  throw std::out_of_range("result has no column \"" + column + "\" in " + file);
}

}  // namespace wbm::reproduce
