#pragma once
/// Runs the analysis a scene asks for and gathers its result files and diagnostics; the `wbm`
/// command writes them (docs/scenes.md lists every file and column). Units: SI.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <wbm/scene/output.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>
#include <wbm/solvers/status.hpp>
#include <wbm/scene/scene.hpp>

namespace wbm::scene {

/// Progress of a long analysis: fraction in [0, 1] and a short label ("period 12, δ = 3e-5").
using Progress = std::function<void(double fraction, const std::string& label)>;

/// How a run ended, in the solvers' one vocabulary (status.hpp: SolveStatus and StopReason):
///  - status: Converged only if every solve's residual was verified (a sweep: every frequency;
///    timestep: the period-to-period criterion met) and, for a branch (continuation, nnm), the
///    branch reached its range (and every nnm level asked for converged); else the status of the
///    first failed solve, or PathEnded for a branch that stopped before its range's end.
///  - stop: for a branch, why it ended (absent for solve, timestep and basis-plot).
/// converged() is the project's one definition of a converged run: `wbm run`'s exit status and
/// status line, result.json's diagnostics.converged and the MAT-file's `converged` all read it.
/// Tables hold converged data only; a point that failed is listed in diagnostics with its status
/// and residuals.
struct AnalysisResult {
  solvers::SolveStatus status = solvers::SolveStatus::MaxIterations;
  std::optional<solvers::StopReason> stop;
  [[nodiscard]] bool converged() const { return status == solvers::SolveStatus::Converged; }
  nlohmann::json diagnostics;   // status, iterations, residuals, condition estimate, timings
  std::vector<Table> tables;    // the CSV files, in the order written
  std::string summary;          // a few lines for the terminal
  /// What the user must know although the run converged (a sweep that restarted from the
  /// linear response and may have left its branch); `wbm run` prints them on stderr and writes
  /// them to result.json.
  std::vector<std::string> warnings;
};

/// Runs `scene.analysis`:
///  - solve, one frequency: weighted residual [JL14 Eqs. (14)–(17)] with the scene's basis pair,
///    formulation and Newton options (solvers::solve_weighted_residual). Files:
///    displacement.csv, velocity.csv (absent for a trial basis without a pointwise derivative
///    other than Haar), contact_force.csv (with contact), energy.csv [JL14 Eq. (35)],
///    coefficients.csv (the trial coefficients of the output DOFs, one row per basis function).
///  - solve, frequency range: one solve per frequency, each started from the previous converged
///    contact unknowns; if that fails, from the linear response (contact homotopy, then load
///    stepping). Such a restart may land on another branch: it is a column of the CSV
///    (restarted_from_linear), a warning with the jump of the forced DOF's amplitude, and
///    diagnostics.restarted_points. Files: frequency_response.csv (max, min and rms displacement
///    of each output DOF per frequency). A sweep does not pass folds: that is continuation.
///  - timestep: GSL BDF from rest to the periodic state [JL14 Sec. 4]; the same per-period files
///    as solve, from the last period.
///  - basis-plot: basis_functions.csv, values (or first τ-derivatives) of the trial basis'
///    functions at τ_p = p/P.
///  - continuation: pseudo-arclength continuation in f over frequency_hz = [from, to]
///    (solvers::trace_response) with Floquet stability; branch.csv (max, min and amplitude of
///    the forced DOF, contact force, stability, corrector iterations per point) and folds.csv
///    (with whether a Floquet multiplier crosses +1 there). Converged = the range was reached.
///  - nnm: the first nonlinear normal mode of the undamped structure against its stops
///    (solvers::NonlinearModes, [LL11]) over analysis.energy: by pseudo-arclength continuation in
///    energy (algorithm "continuation") or by the augmented Lagrangian with Powell's updates at
///    energy steps (LL11 Alg. 1 "simultaneous" or Alg. 2 "sequential", rigid stops only).
///    Files: backbone.csv (per level: normalized energy, orbit and Rayleigh-quotient frequencies,
///    penetration, complementarity, normalization error, largest contact force, iterations;
///    Powell's measures for Alg. 1/2), folds.csv (energies where the branch turns back), and per
///    analysis.levels energy E: mode_E<E>.csv (u and du/dt of the output DOFs over one period,
///    [output] samples) and mode_E<E>_contact.csv (contact force samples). Converged = the
///    energy range was covered and every level converged.
/// A [structure] deck not reduced yet is reduced first (reduce_structure, on a copy of the scene;
/// its summary is diagnostics["reduction"], its warnings join `warnings`), and throws as
/// reduce_structure does. Other bad scenes are refused by load_scene; this throws only
/// std::logic_error for a scene that bypassed it. Non-convergence is reported (converged =
/// false), never thrown.
[[nodiscard]] AnalysisResult run_analysis(const Scene& scene, const Progress& progress = {});

/// The modal problem of an nnm scene: M and K of [structure] (damping ignored), one stop per
/// [contact] (dof, gap), the penalty stiffness (0 for rigid stops) and N, m of [analysis].
struct ModeProblem {
  solvers::MechanicalSystem system;
  std::vector<solvers::RigidStop> stops;
  double penalty_stiffness = 0.0;  // [N/m]
  solvers::NonlinearModeOptions options;
};
/// Throws std::logic_error unless the scene's analysis is nnm.
[[nodiscard]] ModeProblem mode_problem(const Scene& scene);

/// The per-level summary of a backbone [LL11], one entry per level of b.levels in that order:
/// the one definition behind the nnm scene's backbone.csv and the Python module's
/// nonlinear_mode() dict. energy [-] (1 at contact onset), frequency_hz and
/// rayleigh_frequency_hz [Hz], max_penetration and complementarity [gap], normalization_error
/// [-], max_contact_force [N] (0 without contact samples), newton_iterations, and for Alg. 1/2
/// levels powell_iterations, inequality_measure G_i [gap] and equality_measure G_e [-]; then
/// NonlinearModes::modal_components: first_mode_share [-] (of m̂ held by linear mode 1 at the
/// fundamental), other_mode and other_harmonic (1-based) and other_share [-] of the largest other
/// component. `modes` must be the NonlinearModes that computed `b` (modal_components uses its
/// linear modes). Throws nothing.
struct BackboneColumns {
  Eigen::VectorXd energy, frequency_hz, rayleigh_frequency_hz, max_penetration, complementarity, normalization_error,
      max_contact_force, newton_iterations, powell_iterations, inequality_measure, equality_measure,
      first_mode_share, other_mode, other_harmonic, other_share;
};
[[nodiscard]] BackboneColumns backbone_columns(const solvers::NonlinearModes& modes, const solvers::Backbone& b);

}  // namespace wbm::scene
