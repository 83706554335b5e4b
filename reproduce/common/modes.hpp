#pragma once
/// Shared pieces of the LL11 nonlinear-mode reproductions (ll11_*): the rod scene and running its
/// nnm analysis through wbm::scene, so that each figure's numbers come from
/// reproduce/scenes/ll11_rod.toml and a solve, exactly as `wbm run` would compute them.

#include <string>
#include <vector>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/scene.hpp>

#include "run.hpp"

namespace wbm::reproduce {

/// reproduce/scenes/ll11_rod.toml, checked to be an nnm scene on the FE rod. With run.quick():
/// N = 8, m = 64 and the energy range capped at 3 (for ctest). Throws std::invalid_argument if
/// the file is not such a scene.
[[nodiscard]] scene::Scene ll11_scene(const Run& run);

/// scene::run_analysis of an nnm scene; its tables are written into the run, each file name
/// prefixed by `prefix`. A non-converged analysis fails the run with its message.
scene::AnalysisResult run_modes(Run& run, const scene::Scene& scene, const std::string& prefix = "");

/// The i-th column of a result table named `file` whose header is `column`; throws
/// std::out_of_range naming both if absent.
[[nodiscard]] const Eigen::VectorXd& result_column(const scene::AnalysisResult& result, const std::string& file,
                                                   const std::string& column);

}  // namespace wbm::reproduce
