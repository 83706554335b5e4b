// Private to wbm_scene: the pieces of run_analysis (analysis.hpp), one file each:
//   analysis_tables.cpp        the period and harmonic tables (JSON of the reports: json.cpp)
//   analysis_forced.cpp        [analysis] type = solve, sweep, timestep, basis-plot
//   analysis_continuation.cpp  type = continuation (the frequency-response curve)
//   analysis_modes.cpp         type = nnm (nonlinear normal modes)
#pragma once

#include <chrono>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/json.hpp>
#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/weighted_residual.hpp>

namespace wbm::scene::detail {

// Wall time since `start` [s].
double seconds_since(std::chrono::steady_clock::time_point start);

// The solver reports go to result.json through their serializers (wbm/scene/json.hpp), e.g.
// `nlohmann::json(solution)`; finite_or_null (same header) writes a non-finite number as null.

// One number in printf notation (`spec`, e.g. "%.6g"): the solvers' one formatter.
using solvers::format;

// How to get past a stop that is not a computed outcome, as "; way out: …" naming the scene key
// to change and a value to try (issue #35, item 4), for type = "continuation" and "nnm": the
// point limit ([analysis] max_points), the state bound ([analysis] max_state), a step below
// minimum ([analysis] max_step; for nnm, or another N/m), a retraced backbone or a degenerate
// switching point ([analysis] harmonics, samples), LL11 Alg. 1/2's wall-time budget ([analysis]
// algorithm). A step below minimum whose corrector stalled at its rounding floor (stalled_residual
// finite: Branch::stalled_residual) names [solver] tolerance instead of a shorter step (for nnm,
// whose KKT tolerance is not a scene key, another N/m). Empty for an outcome (range or goal
// reached) and for stops whose solver message names its way out already (the undamped top
// Fourier function, a start that did not converge).
std::string way_out(const Scene& scene, solvers::StopReason stop,
                    double stalled_residual = std::numeric_limits<double>::quiet_NaN());

// The column name of the scene's contact c: its DOF, or "dof-other" for a contact between two DOFs.
std::string contact_label(const Scene& scene, size_t c);
// diagnostics.friction of an exact Coulomb contact from its multipliers λ_k [N] at the instants τ_k
// (the weighted residual) or its mean forces over the output intervals [τ_k, τ_{k+1}) (Moreau–Jean),
// its tangential displacements w_k = w(τ_k) [m] and its slip forces F_k [N] (μN, or μ times the
// normal stop's reaction over the same interval): stick_fraction (the instants with
// |λ_k| < F_k (1 − 1e-9): the slip rows hold |λ| = F exactly), slip_amplitude_m ((max w − min w)/2:
// the rigid-plastic slider moves with the point), dissipated_energy_per_cycle_J
// (Σ_k λ_k (w_{k+1} − w_k) ≥ 0, the work of the slips paired with the impulses) and
// dissipated_power_W (that times f), and the number of instants under `count_key`
// ("collocation_instants", "output_samples"). All vectors have one entry per instant. w is
// relative to a moving counter-surface, which slides by `drift` d per period
// (solvers::ObstacleMotion): the last slip is w_0 − d − w_{m−1}, and the slip amplitude is that of
// w_k + d k/m, the drift's ramp removed.
nlohmann::json coulomb_diagnostics(const std::string& label, const Eigen::VectorXd& force, const Eigen::VectorXd& w,
                                   const Eigen::VectorXd& slip_force, double frequency_hz, const std::string& count_key,
                                   double drift = 0.0);

// A_h and φ_h of u = Σ_h A_h cos(2πhτ + φ_h), h = 0 … h_max, for each row of `samples` (k × P,
// equispaced over one period), by FFT (spectral::Aft). amplitude, phase: k × (h_max + 1).
void harmonics_of(const Eigen::MatrixXd& samples, int h_max, Eigen::MatrixXd& amplitude, Eigen::MatrixXd& phase);

// Per-period files from displacement/velocity of every solver DOF (n × P), shared by solve and
// timestep; the written DOFs are the scene's (massless ones recovered, Scene::expand_displacement).
void period_tables(const Scene& scene, const std::vector<solvers::ContactPoint>& contacts,
                   const solvers::MechanicalSystem& system, double frequency_hz, const Eigen::VectorXd& tau,
                   const Eigen::MatrixXd& solver_displacement, const Eigen::MatrixXd* solver_velocity,
                   AnalysisResult& out);

// Per point of a sweep or branch: A_h and φ_h of each observed DOF (rows: points). `samples[i]` is
// the observed DOFs' samples (k × P) at frequency `hz[i]`.
Table point_harmonics(const Scene& scene, const std::string& file, const std::vector<int>& observed,
                      const std::vector<double>& hz, const std::vector<Eigen::MatrixXd>& samples);

// Samples (rows: `observed` scene DOFs, P columns) of a weighted-residual solution given by the
// trial coefficients of the solver DOFs `kept` (rows of `coefficients`; with a condensation, every
// solver DOF, so that massless DOFs can be recovered).
Eigen::MatrixXd observed_samples(const Scene& scene, const solvers::TimeBasis& trial, const Eigen::MatrixXd& coefficients,
                                 const std::vector<int>& kept, const std::vector<int>& observed,
                                 const Eigen::VectorXd& tau, double frequency_hz);

// The scene's harmonic selection as written in the scene: "odd" or [1, 3, ...].
std::string selection_label(const Scene& scene);

// A warning in `out` when the residual left in the dropped harmonics (per point, `dropped` at
// `hz`) exceeds 1e-6 ‖b‖: the results are then not the full harmonic balance's.
void warn_dropped_harmonics(const Scene& scene, const std::vector<double>& hz, const std::vector<double>& dropped,
                            AnalysisResult& out);

// The analyses, each filling `out` (tables, scalars, messages) from the scene.

void solve_one(const Scene& scene, AnalysisResult& out);

void solve_sweep(const Scene& scene, const Progress& progress, AnalysisResult& out);

void timestep(const Scene& scene, const Progress& progress, AnalysisResult& out);

void basis_plot(const Scene& scene, AnalysisResult& out);

void continuation(const Scene& scene, const Progress& progress, AnalysisResult& out);

void nonlinear_modes(const Scene& scene, const Progress& progress, AnalysisResult& out);

}  // namespace wbm::scene::detail
