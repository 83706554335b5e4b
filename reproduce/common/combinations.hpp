#pragma once
/// Shared body of the weighted-residual figures and tables of [JL14 Secs. 4.1, 5] (Figs. 6–11,
/// Table 2, the speed/accuracy study): the BDF reference of a scene, the trial:weighting
/// combinations of Table 2 solved on it, and their post-processed errors. Units: SI.

#include <array>
#include <optional>
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
  std::string method;  // "GSL msbdf" or "Moreau–Jean (...)"
  [[nodiscard]] const Eigen::VectorXd& tau() const { return response.tau; }
};
/// Throws std::invalid_argument for a scene without [contact]; a BDF run that does not reach
/// the periodic state is recorded with run.fail().
[[nodiscard]] Reference solve_reference(Run& run, const std::string& scene, double relative_tolerance = 1e-10);
/// The scene with its contact law replaced by a rigid stop at the same gap (contact::RigidStop)
/// and its Moreau–Jean periodic reference (θ = ½, restitution e, `steps` per period, at most
/// `max_periods`, 1024 samples; 256 with quick); contact_force is the mean force over each
/// sample interval [N]. A run that does not become periodic is returned as it is (its report
/// says so): the caller decides whether that fails the run.
[[nodiscard]] Reference solve_rigid_reference(Run& run, const std::string& scene, int steps, double restitution = 0.0,
                                              int max_periods = 5000);

/// One combination at one M on a reference: the solve (median wall time over `repeats` full
/// solves, set-up included) and its post-processing on the reference samples (contact_force
/// empty for rigid stops: their force is the solution's contact_force_samples).
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

/// Writes a long-format sweep table (one row per combination and M): combination index in the
/// order of Table 2, M, tip error, energy norm, median solve time, Newton iterations, condition
/// estimate, and the solve's status. Values that do not exist (errors of a solve that did not
/// converge, an infinite condition estimate) are empty cells beside the status.
void write_sweep(Run& run, const std::string& file, const std::vector<CombinationResult>& results);

/// The converged result of `key` ("db6_fourier") at M (any M if 0) in `results`, else nullptr.
[[nodiscard]] const CombinationResult* find_converged(const std::vector<CombinationResult>& results,
                                                      const std::string& key, int dimension = 0);

/// A time history of the tip of one combination (or the reference) as the figures draw it.
/// "displacement" [m], "velocity" [m/s] or "force" (the contact force over F [-]).
[[nodiscard]] Eigen::VectorXd history(const Reference& reference, const std::string& quantity);
[[nodiscard]] Eigen::VectorXd history(const Reference& reference, const CombinationResult& result,
                                      const std::string& quantity);

/// Time-history figure (Figs. 6–9): solves the BDF reference of `scene` and every Table 2
/// combination at M = 64 (16 with --quick), writes `quantity` of each in one CSV, meta.json and
/// the report table (status, rms and max difference to BDF). A combination that does not
/// converge is left out of the CSV and reported with its status and message. Returns the
/// results (in Table 2 order) so that the executable checks its paper's statements.
struct HistoryFigure {
  Reference reference;
  std::vector<CombinationResult> results;
  int dimension = 0;
};
[[nodiscard]] HistoryFigure history_figure(Run& run, const std::string& scene, const std::string& figure,
                                           const std::string& quantity, const std::string& paper_note);

/// One statement of a paper, checked: `agrees` is computed from `numbers` (printed beside it);
/// no value means it could not be checked (a missing solve, a qualitative statement) and
/// `numbers` says why.
struct Claim {
  std::string statement;
  std::optional<bool> agrees;
  std::string numbers;
};
/// "Against the paper's text:" and one bullet per claim: statement, numbers, agrees/disagrees/not
/// checked; then the count of each.
[[nodiscard]] std::string claims_markdown(const std::vector<Claim>& claims);

/// The header of a report table with one row per pair and one column per dimension M:
/// "| pair | M = m_1 | … |" (then " <last> |" if `last` is not empty), its separator row, each
/// line ended by a newline.
[[nodiscard]] std::string dimension_table_header(const std::vector<int>& dimensions, const std::string& last = "");

/// Signal measures for the claims, on samples over one period:
///  - fraction of samples with u > threshold;
///  - periodic total variation Σ_q |v_{q+1} − v_q| (with v_Q = v_0);
///  - rms relative difference rms(v − v_ref)/rms(v_ref) restricted to the samples where
///    `mask` is true (NaN if none).
[[nodiscard]] double fraction_above(const Eigen::VectorXd& u, double threshold);
[[nodiscard]] double total_variation(const Eigen::VectorXd& v);
[[nodiscard]] double rms_relative_error_on(const Eigen::VectorXd& v, const Eigen::VectorXd& reference,
                                           const std::vector<bool>& mask);

/// Least-squares slope of log y against log x over the pairs with x > 0 and y > 0 finite (an
/// observed order of convergence or a cost exponent): (n Σxy − Σx Σy)/(n Σx² − (Σx)²) in the logs;
/// NaN with fewer than two such pairs or all x equal. Throws std::invalid_argument if the sizes
/// differ.
[[nodiscard]] double loglog_slope(const std::vector<double>& x, const std::vector<double>& y);

/// A column of a report table (Run::table) from the values gathered row by row.
[[nodiscard]] inline Eigen::VectorXd as_column(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

/// One number for report tables through the solvers' one formatter (solvers::format); NaN (a
/// missing value) prints "—".
[[nodiscard]] std::string format(const char* spec, double value);

}  // namespace wbm::reproduce

namespace wbm::reproduce {

/// Convergence figure (Figs. 10–11): Cases 1 and 2, every Table 2 combination at M = 8 … 256
/// (8, 16 with --quick), written as sweep_case1.csv and sweep_case2.csv (write_sweep) with a report
/// table of `metric` ("energy_norm" or "tip_error") per combination and M. Returns the results
/// of each case and the M used, for the executable's checks of the paper's statements.
struct ConvergenceFigure {
  std::vector<int> dimensions;
  std::array<std::vector<CombinationResult>, 2> cases;  // Case 1, Case 2
  std::array<double, 2> frequencies_hz{};                // each case's forcing frequency (its scene)
  /// "150 Hz" for case c (0, 1), formatted from the scene, for claim labels.
  [[nodiscard]] std::string frequency_label(int c) const;
};
[[nodiscard]] ConvergenceFigure convergence_figure(Run& run, const std::string& figure, const std::string& metric,
                                                   const std::string& paper_note);

}  // namespace wbm::reproduce
