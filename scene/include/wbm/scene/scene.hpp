#pragma once
/// Scene files: one problem per TOML file (toml++), every key documented in docs/scenes.md.
/// Units: SI (Pa, kg/m³, m², m, N, s, Hz where the name says _hz).
///
/// A scene models only what its analysis needs: `basis-plot` builds no structure, a scene
/// without [contact] builds no contact law. Sections (defaults in docs/scenes.md):
///   title                      string
///   [structure]                the clamped-free FE rod (young_modulus, density, area, length,
///                              elements) or explicit matrices (mass, stiffness, damping: a number
///                              for 1 DOF, a list (diagonal), a list of rows, or a Matrix Market
///                              file name relative to the scene; dofs = names)
///   [damping]                  C += alpha M + beta K
///   [forcing]                  F cos 2πft on one DOF: amplitude, node | dof, frequency_hz (a number,
///                              or [from, to] with points for a sweep), and further loads
///                              [[forcing.loads]] (amplitude, node | dof, phase_deg | phase_rad,
///                              harmonic) or vector (a Matrix Market n x 1 file)
///   [contact] / [[contact]]    law ("exponential": coefficient, exponent; "linear": stiffness;
///                              "rigid": exact Signorini contact, nnm only), gap, node | dof
///   [basis]                    trial, weighting, dimension | level | harmonics, formulation,
///                              time_samples, operators, contact_quadrature
///   [solver]                   Newton on the contact unknowns (tolerance, max_iterations,
///                              line_search, linear_solver)
///   [timestep]                 BDF reference (relative_tolerance, absolute_tolerance,
///                              periodicity_tolerance, max_periods)
///   [analysis]                 type = "solve" | "timestep" | "basis-plot" | "continuation" | "nnm"
///                              (+ functions, derivative, normalization for basis-plot; max_step,
///                              max_frequency_step_hz, max_points, max_state, stability,
///                              parameter, friction_coefficient for continuation;
///                              energy, harmonics, samples, algorithm,
///                              max_energy_step, max_points, levels for nnm)
///   [output]                   samples per period, nodes | dofs to write, harmonics, formats
///                              ("csv", "mat")
/// Rod locations are node numbers 1 … elements (node 0 is clamped) or "tip"; matrix locations
/// are DOF names or 0-based indices.
///
/// Errors: load_scene collects every problem of a file and throws one std::invalid_argument whose
/// message has one line per problem, "file:line: key: what was expected" (line omitted for JSON
/// input); so does a missing or unreadable file, or a directory given as one (bad input, `wbm`
/// exit 2). A [structure] deck is read as text only (an unreadable deck file: std::runtime_error);
/// CalculiX and the reduction run later, in reduce_structure.

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <nlohmann/json.hpp>

#include <wbm/fem/rod.hpp>
#include <wbm/solvers/condensation.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/solvers/weighted_residual.hpp>

namespace wbm::scene {

enum class StructureKind { Rod, Matrices };
enum class AnalysisKind { Solve, Timestep, BasisPlot, Continuation, NonlinearModes };

/// "solve", "timestep", "basis-plot", "continuation", "nnm".
[[nodiscard]] std::string_view to_string(AnalysisKind kind) noexcept;

/// A structure given as a CalculiX/Abaqus deck ([structure] deck = …, docs/scenes.md). Reading
/// the scene runs no tool: it reads the deck's text and predicts the interface DOFs CalculiX will
/// keep (scene::predict_interface), so Structure::dof_names are those of `wbm reduce`'s dofs.txt
/// ("n<node>_x", …, "mode<k>") and contacts and loads resolve against them, while mass and
/// stiffness stay empty. reduce_structure (run by run_analysis) assembles the deck with ccx,
/// reduces it by Craig–Bampton onto the interface nodes, checks the names and fills M_r, K_r.
/// Units: SI, converted from the deck's `units` (coordinates in m).
struct DeckStructure {
  std::string file;                              // absolute path of the deck
  std::string interface;                         // node set name or node numbers, as given
  int modes = 40;                                // fixed-interface normal modes
  std::string ccx = "ccx";                       // the CalculiX executable
  std::string units = "SI";                      // the deck's unit system, converted to SI (scene::deck_units)
  std::map<int, Eigen::Vector3d> coordinates;    // of the interface nodes [m]
  std::map<std::string, std::vector<int>> node_sets;  // the deck's node sets (names upper-case)
  /// structure.axis: a point on the rotation axis and its direction, for radial contacts.
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> axis;
  /// The deck's keywords that can remove DOFs beyond *BOUNDARY (fem::CalculixDeck::constraint_keywords)
  std::vector<std::string> constraint_keywords;
  nlohmann::json reduction;                      // the reduction's summary (reduction.json), once reduced
};

/// The structure: FE rod [JL14 Sec. 2] or explicit symmetric matrices (n × n, sparse).
struct Structure {
  StructureKind kind = StructureKind::Rod;
  fem::RodParameters rod{0.0, 0.0, 0.0, 0.0, 0};   // Rod only
  Eigen::SparseMatrix<double> mass, stiffness, damping;  // Matrices only; damping may be 0 × 0
  /// Matrices only: "" when given inline, else the absolute path of the Matrix Market file.
  std::string mass_file, stiffness_file, damping_file;
  std::vector<std::string> dof_names;  // Matrices: given or "dof0" … ; Rod: "node1" … "nodeN"
  std::optional<DeckStructure> deck;   // Matrices reduced from a deck

  [[nodiscard]] int dofs() const;
  /// A deck whose reduction has not run yet (reduce_structure): dof_names are the predicted ones,
  /// mass and stiffness are empty.
  [[nodiscard]] bool awaiting_reduction() const { return deck.has_value() && mass.rows() == 0; }
  /// Rod: "node<j>"; matrices: the DOF's name.
  [[nodiscard]] std::string dof_name(int dof) const;
};

struct Damping {
  double alpha = 0.0;  // mass-proportional [1/s]
  double beta = 0.0;   // stiffness-proportional [s] (the paper's C = βK)
  double modal_ratio = 0.0;  // ζ of every mode [-]: C += M Φ diag(2ζω_i) Φᵀ M (solvers::modal_damping)
};

struct FrequencyRange {
  double from_hz = 0.0, to_hz = 0.0;
  int points = 0;  // >= 2, equispaced, both ends included
  /// An explicit sweep (`frequencies_hz` / `frequencies_rad_s`), in the order given [Hz]; when
  /// non-empty it is the sweep, from_hz/to_hz are its first and last values and points its size.
  std::vector<double> list_hz;
};

struct Forcing {
  double amplitude = 0.0;      // F [N] of F cos 2πft on `dof` (0 when only `loads` are given)
  int dof = 0;                 // forced DOF, 0-based (the DOF reported as "forced")
  /// Further loads F_j cos(2π h_j f t + φ_j) on DOFs (0-based): [[forcing.loads]] and the
  /// entries of a forcing.vector file, in that order.
  std::vector<solvers::HarmonicLoad> loads;
  double frequency_hz = 0.0;   // single frequency (when range is empty) [Hz]
  std::optional<FrequencyRange> range;
  /// The frequencies to solve at, in order (one, or the sweep).
  [[nodiscard]] std::vector<double> frequencies_hz() const;
};

/// The law of a [contact] entry: "exponential" [JL14 Eq. (5)], "linear" (penalty spring),
/// "rigid" (exact Signorini contact), "jenkins" (friction along the contact's direction: a
/// Jenkins element, contact/friction.hpp) or "coulomb" (exact Coulomb friction along it, its
/// force a multiplier as a rigid stop's: contact::CoulombFriction).
enum class ContactLawKind { Exponential, Linear, Rigid, Jenkins, Coulomb };
/// True for the laws whose force is a Lagrange multiplier (rigid, coulomb): a forced response
/// takes all of its contacts exact or none.
[[nodiscard]] constexpr bool exact(ContactLawKind law) noexcept {
  return law == ContactLawKind::Rigid || law == ContactLawKind::Coulomb;
}
[[nodiscard]] std::string_view to_string(ContactLawKind law) noexcept;

/// What a continuation follows: the forcing frequency over forcing.frequency_hz = [from, to]
/// ("frequency"), or the friction coefficient μ of every "jenkins" contact over
/// analysis.friction_coefficient = [from, to] at one forcing frequency ("friction_coefficient";
/// solvers::ContinuationParameter::FrictionCoefficient).
enum class BranchParameter { Frequency, FrictionCoefficient };
/// [analysis] stick_slip_events: "on-stall", "always", "never" (solvers::StickSlipEvents).
enum class StickSlipEvents { OnStall, Always, Never };

/// The outer algorithm of type = "nnm": "continuation" (pseudo-arclength on the KKT
/// conditions), "simultaneous" or "sequential" ([LL11 Algs. 1, 2], energy stepping).
enum class NnmAlgorithm { Continuation, Simultaneous, Sequential };
[[nodiscard]] std::string_view to_string(NnmAlgorithm algorithm) noexcept;

struct Contact {
  ContactLawKind law = ContactLawKind::Exponential;
  double coefficient = 0.0;  // a_c [N] (exponential)
  double exponent = 0.0;     // α [1/m] (exponential)
  double stiffness = 0.0;    // k [N/m] (linear)
  double tangential_stiffness = 0.0;  // k_t [N/m] (jenkins)
  double friction_coefficient = 0.0;  // μ [-] (jenkins, coulomb)
  double normal_load = 0.0;           // N [N] (jenkins, coulomb): a constant preload; slip force μ N
  /// jenkins: a normal load that varies with the normal gap. `normal_contact` is the index of the
  /// [[contact]] table (as given, 0-based) whose force n adds to N, and `normal_index` that
  /// contact's index in Scene::contacts (solvers::ContactPoint::normal); −1 for none.
  int normal_contact = -1;
  int normal_index = -1;
  /// jenkins with `second_tangent`: a Jenkins element with two tangents (an isotropic slip disc,
  /// contact::JenkinsDiscLaw), carried by two entries of Scene::contacts, this one at `dof` and
  /// the other at the second tangent's DOF; the index in Scene::contacts of the other entry
  /// (solvers::ContactPoint::second_tangent), −1 for one tangent. The entry of the second tangent
  /// repeats the law's parameters, has no counter-surface, and shares the normal load.
  int second_tangent = -1;
  double gap = 0.0;          // g0 [m] (not jenkins, coulomb)
  int dof = 0;               // 0-based
  /// The second DOF of a contact between two DOFs (0-based; `against` in the scene): the gap is
  /// g0 − (u[dof] − u[against]) and the force pushes the two apart. −1: a fixed obstacle.
  int against = -1;
  /// `direction` in the scene: the contact acts along Σ w e_j over these (DOF, weight) pairs
  /// (solvers::ContactPoint::along): {(dof, −1)} for a stop on the −x side, or a unit normal
  /// over several DOFs (matrices). Empty: +e_dof.
  std::vector<std::pair<int, double>> along;
  /// `counter_surface` in the scene: the index in Scene::counter_surfaces of the moving
  /// counter-surface this contact acts against (solvers::ContactPoint::obstacle); −1: fixed.
  int counter_surface = -1;
};

/// [[counter_surface]]: a counter-surface that moves over the period of the response, named by
/// contacts (Contact::counter_surface; solvers::ObstacleMotion gives the model).
///  - "fourier": s(τ) = d τ + Σ_h (a_h cos 2πhτ + b_h sin 2πhτ) [m] along each contact's
///    direction, τ = f t; the drift d [m per period] is a friction contact's sliding only.
///  - "oval_casing": a casing whose radius varies as R + δ cos(nθ) around a blade tip that turns at
///    Ω, with the response's frequency f = nΩ/(2π) (one lobe per period). A normal contact (the
///    radial gap) sees s(τ) = δ cos(2πτ + φ); a friction contact (its direction along the
///    rotation) the casing sliding back by one lobe, 2πR/n, per period: d = −2πR/n, no other term.
struct CounterSurface {
  std::string name;
  std::string type = "fourier";   // "fourier" | "oval_casing"
  std::vector<double> cosine;     // fourier: a_h [m], h = 1, 2, …
  std::vector<double> sine;       // fourier: b_h [m]
  double drift = 0.0;             // fourier: d [m per period]
  double ovalization = 0.0;       // oval_casing: δ [m]
  int lobes = 2;                  // oval_casing: n
  double radius = 0.0;            // oval_casing: R [m]
  double phase_deg = 0.0;         // oval_casing: φ [deg], as given (the echo reads back exactly)
  /// The motion along a contact's direction: a normal contact's (friction = false) or a friction
  /// contact's tangent (friction = true), as above.
  [[nodiscard]] solvers::ObstacleMotion motion(bool friction) const;
};

struct Basis {
  std::string trial = "fourier";
  std::string weighting = "fourier";
  int dimension = 64;  // M: 2^J, or 2H + 1 when harmonics > 0
  /// H for Fourier:Fourier as harmonic balance is usually written (harmonics 0 … H, 2H + 1
  /// functions, every harmonic damped); 0: the M = 2^J form of the paper, whose top function
  /// cos πMτ has no damping (spectral/fourier_basis.hpp). The Fourier:Fourier default when
  /// neither dimension, level nor harmonics is given: H = kDefaultHarmonics.
  int harmonics = 0;
  static constexpr int kDefaultHarmonics = 32;
  solvers::Formulation formulation = solvers::Formulation::Distributional;
  int time_samples = 0;  // Q; 0 = max(256, 2M)
  solvers::OperatorRule operators = solvers::OperatorRule::Automatic;
  /// Resolved from [basis] contact_quadrature = "automatic" (default) | "midpoint" |
  /// "cell-average": automatic is cell-average for harmonics = H (a C¹ discrete residual, so that
  /// continuation passes a stiff stop smoothly) and the paper's midpoint rule for M = 2^J and the
  /// wavelet bases (the reproductions keep the paper's discretization).
  solvers::ContactQuadrature contact_quadrature = solvers::ContactQuadrature::Midpoint;
  /// [basis] harmonic_selection = "all" (default) | "odd" | [h, …] (Fourier:Fourier only): the
  /// harmonics kept (solvers::WeightedResidualOptions::harmonics), ascending; empty = all.
  std::vector<int> selected_harmonics;
  std::string harmonic_selection = "all";  // "all", "odd" or "list", as given
};

struct Solver {
  solvers::NewtonOptions newton{};
  solvers::LinearSolverPath linear_solver = solvers::LinearSolverPath::Automatic;
  /// [solver] residual_tolerance: a solve is converged only if the normwise backward error of
  /// its full residual, ‖G a − b + n(a)‖ / (γ‖a‖ + ‖b‖ + ‖n(a)‖), γ ≥ ‖G‖₂, is at most this
  /// (solvers::WeightedResidualOptions::residual_tolerance), reported as used.
  double residual_tolerance = solvers::WeightedResidualOptions{}.residual_tolerance;
};

struct Analysis {
  AnalysisKind kind = AnalysisKind::Solve;
  std::vector<int> functions;       // basis-plot: shifts k to draw (empty = all M)
  int derivative = 0;               // basis-plot: 0 or 1
  bool unit_integral = false;       // basis-plot: ∫₀¹ φ_{J,k} = 1 (the paper's figures) instead of orthonormal
  // continuation (pseudo-arclength in the forcing frequency over forcing.frequency_hz = [from, to]):
  double max_step = 2e-2;           // scaled arclength (solvers/continuation.hpp)
  double max_frequency_step_hz = 0; // > 0: |Δf| per step at most this [Hz]
  int max_points = 5000;
  double max_state = 100.0;         // > 0: stop once ‖x‖∞ > max_state · s_r (s_r = max(largest gap, ‖x_lin‖∞)); 0: no bound
  bool stability = true;            // Floquet multipliers of every point (nnm: of every level; false unless asked)
  BranchParameter parameter = BranchParameter::Frequency;
  double friction_from = 0.0, friction_to = 0.0;  // parameter = friction_coefficient: μ from → to [-]
  StickSlipEvents stick_slip_events = StickSlipEvents::OnStall;  // "jenkins" contacts: how switches are crossed
  // nnm (first nonlinear normal mode against the stops, solvers/nonlinear_modes.hpp):
  double energy_min = 0.5, energy_max = 0.0;  // normalized energy range (1 = contact onset)
  int harmonics = 16;               // N
  int samples = 256;                // m time samples of the contact conditions, > 2N
  NnmAlgorithm algorithm = NnmAlgorithm::Continuation;
  double max_energy_step = 0.05;    // |ΔE| per step
  std::vector<double> levels;       // energies whose mode shapes are written
};

struct Output {
  int samples = 1024;      // P samples per period, τ_p = p/P
  std::vector<int> dofs;   // 0-based DOFs written; empty = the forced and the contact DOFs
  bool all_dofs = false;
  /// H > 0: harmonics.csv (solve at one frequency, timestep; sweep_harmonics.csv and
  /// branch_harmonics.csv per point of a sweep or a branch): amplitude A_h [m] and phase φ_h
  /// [rad] of u(t) = Σ_h A_h cos(2π h f t + φ_h), h = 0 … H, per output DOF, from the P samples
  /// (h = 0: the mean, phase 0). 0: not written.
  int harmonics = 0;
  /// `observe` (0-based DOFs): the DOFs reported per point of a sweep (frequency_response.csv,
  /// sweep_harmonics.csv; default: the output DOFs) or of a continuation branch (amplitude columns
  /// in branch.csv beside the forced DOF's, branch_harmonics.csv; default: the forced DOF).
  std::vector<int> observe;
  /// Result formats, a non-empty subset of {"csv", "mat"}: one CSV file per table and/or
  /// result.mat (scene::write_mat: one struct per table). result.json is always written.
  std::vector<std::string> formats = {"csv"};
};

/// A resolved scene: every default filled in, every location a 0-based DOF.
struct Scene {
  std::string name;   // file stem
  std::string path;   // file it was read from ("" if parsed from text)
  std::string title;
  Analysis analysis;
  std::optional<Structure> structure;  // absent only for basis-plot
  Damping damping;
  std::optional<Forcing> forcing;      // absent only for basis-plot
  std::vector<Contact> contacts;
  std::vector<CounterSurface> counter_surfaces;  // [[counter_surface]], in file order
  Basis basis;
  Solver solver;
  solvers::TimeIntegrationOptions timestep{};  // BDF, penalty laws
  solvers::MoreauJeanOptions moreau_jean{};    // type = "timestep" with law = "rigid"
  /// type = "timestep" with a "jenkins" contact: explicit central differences
  /// (solvers::integrate_central_difference_to_periodic), whose element carries its slider state.
  solvers::CentralDifferenceOptions central_difference{};
  /// True when the contacts are exact (every one "rigid" or "coulomb"): their forces are the
  /// multipliers of the weighted residual's collocation instants (solvers::WeightedResidual::rigid).
  [[nodiscard]] bool rigid() const { return !contacts.empty() && exact(contacts.front().law); }
  /// True when a contact is a Jenkins element (law = "jenkins").
  [[nodiscard]] bool jenkins() const {
    for (const auto& c : contacts) {
      if (c.law == ContactLawKind::Jenkins) return true;
    }
    return false;
  }
  /// True when a contact is a friction law ("jenkins" or "coulomb").
  [[nodiscard]] bool friction() const {
    for (const auto& c : contacts) {
      if (c.law == ContactLawKind::Jenkins || c.law == ContactLawKind::Coulomb) return true;
    }
    return false;
  }
  Output output;
  std::vector<std::string> warnings;   // sections given but unused by the analysis ("file:line: ...")
  /// Set when the matrices have massless DOFs (rows of zeros of M): their static condensation
  /// (solvers/condensation.hpp). system(), contact_points() and harmonic_forcing() are then the
  /// condensed model's (retained numbering); DOF numbers elsewhere in the scene stay the full ones.
  std::optional<solvers::MasslessCondensation> condensation;

  /// M, C = C_given + αM + βK, K (condensed: M_mm, C_mm + αM_mm + βK̃, K̃). Throws
  /// std::logic_error without a structure, or for a deck not reduced yet (reduce_structure).
  [[nodiscard]] solvers::MechanicalSystem system() const;
  /// F cos 2πft on the forced DOF and the further loads, at f (default: the single frequency).
  [[nodiscard]] solvers::HarmonicForcing harmonic_forcing(std::optional<double> frequency_hz = std::nullopt) const;
  /// One ContactPoint per [contact], in file order; empty without contact.
  [[nodiscard]] std::vector<solvers::ContactPoint> contact_points() const;
  [[nodiscard]] solvers::TimeBasis trial() const;
  [[nodiscard]] solvers::TimeBasis weighting() const;
  [[nodiscard]] solvers::WeightedResidualOptions weighted_residual_options() const;
  /// The solvers' number of a scene DOF: itself, or with a condensation its retained index
  /// (−1 for a massless DOF).
  [[nodiscard]] int solver_dof(int dof) const;
  /// Displacements of every scene DOF (n × P) from the solvers' (n_solver × P): the same matrix,
  /// or with a condensation the massless DOFs recovered statically. Velocities alike.
  [[nodiscard]] Eigen::MatrixXd expand_displacement(const Eigen::MatrixXd& solver_displacement) const;
  [[nodiscard]] Eigen::MatrixXd expand_velocity(const Eigen::MatrixXd& solver_displacement,
                                                const Eigen::MatrixXd& solver_velocity) const;
  /// The DOFs [output] writes (sorted, unique).
  [[nodiscard]] std::vector<int> output_dofs() const;
};

/// Reads a scene from a .toml file, or from a .json file holding a resolved scene (either the
/// object itself or a result.json whose "scene" member it is). Throws as described above.
[[nodiscard]] Scene load_scene(const std::filesystem::path& path);
/// Parses TOML text; `file` names it in messages and anchors relative Matrix Market paths.
[[nodiscard]] Scene parse_scene(std::string_view toml_text, const std::filesystem::path& file);
/// The resolved scene as JSON (every key explicit, matrices inline or as absolute paths); the
/// inverse of scene_from_json: scene_from_json(to_json(s)) == s up to `path` and `warnings`.
[[nodiscard]] nlohmann::json to_json(const Scene& scene);
[[nodiscard]] Scene scene_from_json(const nlohmann::json& json, const std::filesystem::path& file);

/// Reduces a [structure] deck: CalculiX assembles it and Craig–Bampton reduces it onto the
/// interface nodes and `modes` fixed-interface modes (scene/reduce.hpp, LL11 Sec. 5.2), filling
/// Structure::mass and stiffness with M_r, K_r [kg, N/m] and DeckStructure::reduction with the
/// summary; then K_r's inertia is checked as the parser checks given matrices (a warning is
/// appended to scene.warnings). Does nothing for another structure or a deck reduced already.
/// run_analysis calls it; `wbm check` does not. Throws std::invalid_argument (bad input) when the
/// DOFs CalculiX keeps at the interface differ from the names predicted when the scene was read
/// (an *EQUATION on an interface DOF, say; both lists and the way out named), when K_r is not
/// positive semidefinite or has rigid-body modes nothing holds, and as reduce_deck for bad
/// options; std::runtime_error when ccx or the reduction fails (a tool, `wbm` exit 1).
void reduce_structure(Scene& scene);

/// The key table of a declared section as docs/scenes.md prints it, generated from the one
/// declaration the parser, its errors and to_json read (| key | type | default | allowed |
/// meaning |, one row per key in declaration order; defaults from the settings' default values,
/// or the declared text where a default depends on other keys; a key read by some variants only
/// (analysis types, structure kinds, contact laws) says so first). `section`: one of
/// declared_sections() ("top" is the top level; "timestep" the BDF of penalty laws and
/// "timestep.rigid" Moreau–Jean, "timestep.jenkins" central differences; "forcing.loads" the
/// [[forcing.loads]] tables).
/// Throws std::invalid_argument for another section, naming the declared ones.
[[nodiscard]] std::string key_table_markdown(const std::string& section);

/// Every section key_table_markdown generates, in the order of docs/scenes.md.
[[nodiscard]] std::vector<std::string> declared_sections();

}  // namespace wbm::scene
