#pragma once
/// Shared body of the weighted-residual figures and tables of [JL14 Secs. 4.1, 5] (Figs. 6–11,
/// Table 2, the speed/accuracy study): the BDF reference of a scene, the trial:weighting
/// combinations of Table 2 solved on it, and their post-processed errors. Units: SI.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "run.hpp"
#include "scene.hpp"

namespace wbm::reproduce {

/// A trial:weighting pair by TimeBasis names ("fourier", "bspline", "db6", "haar").
struct Combination {
  std::string trial, weighting;
  [[nodiscard]] std::string label() const;  // "DB6:Fourier"
  [[nodiscard]] std::string key() const;    // "db6_fourier", for CSV columns
};

/// The six combinations of [JL14 Table 2], in the paper's order.
[[nodiscard]] const std::vector<Combination>& table2_combinations();

/// The formulation every figure uses: distributional, the form of Figs. 10–11 [JL14 Sec. 5.4],
/// admissible for all six combinations (the paper does not say which form Figs. 6–9 use).
inline constexpr solvers::Formulation kFigureFormulation = solvers::Formulation::Distributional;

/// A scene with its BDF periodic reference (GSL msbdf, rtol as given, 1024 samples per period;
/// 256 with quick) and the reference's tip displacement, velocity, contact force and energy.
struct Reference {
  scene::Scene scene;
  solvers::MechanicalSystem system;
  solvers::HarmonicForcing forcing;
  std::vector<solvers::ContactPoint> contacts;
  solvers::PeriodicResponse response;
  Eigen::VectorXd tip_displacement, tip_velocity, contact_force, energy;  // on response.tau
  [[nodiscard]] const Eigen::VectorXd& tau() const { return response.tau; }
};
/// Throws std::invalid_argument for a scene without [contact]; a BDF run that does not reach
/// the periodic state is recorded with run.fail().
[[nodiscard]] Reference solve_reference(Run& run, const std::string& scene, double relative_tolerance = 1e-10);

/// One combination at one M on a reference: the solve (median wall time over `repeats` full
/// solves, set-up included) and its post-processing on the reference samples.
struct CombinationResult {
  Combination combination;
  int dimension = 0;
  solvers::WeightedResidualSolution solution;
  double median_time_s = 0.0;
  Eigen::VectorXd tip_displacement, tip_velocity, contact_force, energy;  // on the reference τ
  double tip_error = 0.0;    // rms(u − u_ref)/rms(u_ref) of the tip [JL14 Sec. 5.5]
  double energy_norm = 0.0;  // rms(E)/rms(E_ref) [JL14 Sec. 5.4]
  [[nodiscard]] bool converged() const { return solution.converged(); }
};
[[nodiscard]] CombinationResult solve_combination(const Reference& reference, const Combination& combination,
                                                  int dimension, int repeats = 1);

/// Solver diagnostics of a result for meta.json.
[[nodiscard]] nlohmann::json to_json(const CombinationResult& result);
/// Scene parameters and BDF diagnostics for meta.json.
[[nodiscard]] nlohmann::json to_json(const Reference& reference);

/// Writes a long-format sweep table (one row per combination and M): combination index into
/// `combinations`, M, converged (1/0), tip error, energy norm, median solve time, Newton
/// iterations, condition estimate; rows that did not converge carry 0 in the value columns
/// (never NaN) and are listed in meta.json with their messages.
void write_sweep(Run& run, const std::string& file, const std::vector<CombinationResult>& results);

/// Time-history figure (Figs. 6–9): the BDF reference and every Table 2 combination at M = 64
/// (16 with --quick) of `quantity` ("displacement" [m], "velocity" [m/s] or "force", the contact
/// force divided by F [-]) in one CSV, with the report fragment. A combination that does not
/// converge is left out of the CSV and reported with its status and message.
void history_figure(Run& run, const std::string& scene, const std::string& figure, const std::string& quantity,
                    const std::string& paper_note);

/// Printf-style formatting of one number, for report tables.
[[nodiscard]] std::string format(const char* spec, double value);

}  // namespace wbm::reproduce

namespace wbm::reproduce {

/// Convergence figure (Figs. 10–11): Cases 1 and 2, every Table 2 combination at M = 8 … 256
/// (8, 16 with --quick), written as sweep_case1.csv and sweep_case2.csv (write_sweep) with a report
/// table of `metric` ("energy_norm" or "tip_error") per combination and M.
void convergence_figure(Run& run, const std::string& figure, const std::string& metric, const std::string& paper_note);

}  // namespace wbm::reproduce
