// The Python module `wbm` (pybind11): scenes, time bases, connection coefficients, explicit and
// rod systems, contact laws and the forced-response solve for any trial:weighting pair, with
// numpy arrays in and out (through Eigen) and C++ exceptions as Python exceptions with the same
// message (std::invalid_argument → ValueError, std::out_of_range → IndexError, other
// std::exception → RuntimeError). Issue #18.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <optional>
#include <tuple>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Eigenvalues>
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>
#include <wbm/contact/friction.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/fem/rod.hpp>
#include <wbm/scene/analysis.hpp>
#include <wbm/scene/json.hpp>
#include <wbm/scene/scene.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/model_checks.hpp>
#include <wbm/solvers/basis_modes.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/time_basis.hpp>
#include <wbm/solvers/weighted_residual.hpp>
#include <wbm/wavelets/connection_coefficients.hpp>

#include "arguments.hpp"
#include "bindings.hpp"

namespace py = pybind11;
using namespace wbm;

namespace {

// JSON (nlohmann) ↔ Python objects through the json module: exact for numbers and strings.
py::object to_python(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// A scene from a path (str or os.PathLike naming an existing file), a TOML string or a dict.
scene::Scene scene_of(const py::object& source) {
  if (py::isinstance<py::dict>(source)) return scene::scene_from_json(python::json_of(source, ""), "<dict>");
  const py::object fspath = py::module_::import("os").attr("fspath");
  if (py::isinstance<py::str>(source)) {
    const std::string text = source.cast<std::string>();
    if (text.find('\n') == std::string::npos && text.find('=') == std::string::npos &&
        std::filesystem::is_regular_file(text)) {
      return scene::load_scene(text);
    }
    if (text.find('=') == std::string::npos) {
      throw std::invalid_argument("run_scene: '" + text + "' is neither an existing scene file nor TOML text "
                                  "(no key = value); pass a path, a TOML string or a dict");
    }
    return scene::parse_scene(text, "<string>");
  }
  if (py::hasattr(source, "__fspath__")) return scene::load_scene(fspath(source).cast<std::string>());
  throw std::invalid_argument("run_scene: expected a path, a TOML string or a dict, got " +
                              py::str(py::type::of(source)).cast<std::string>());
}

// AnalysisResult → {"converged", "summary", "warnings", "diagnostics", "tables"}, each table a
// dict {column header: numpy array}, plus "status" (list of str) when the table has one.
py::dict result_dict(const scene::AnalysisResult& r) {
  py::dict tables;
  for (const auto& t : r.tables) {
    py::dict columns;
    for (size_t c = 0; c < t.header.size(); ++c) columns[py::str(t.header[c])] = py::cast(t.columns[c]);
    if (!t.status.empty()) columns["status"] = py::cast(t.status);
    tables[py::str(t.file)] = columns;
  }
  py::dict out;
  out["converged"] = r.converged();
  out["status"] = std::string(solvers::to_string(r.status));
  out["summary"] = r.summary;
  out["warnings"] = r.warnings;
  out["diagnostics"] = to_python(r.diagnostics);
  out["tables"] = tables;
  return out;
}

// "haar", "bspline" or "db<L>" (Family::daubechies validates L and says what is allowed).
wavelets::Family family_of(const std::string& name) {
  if (name == "haar") return wavelets::Family::haar();
  if (name == "bspline") return wavelets::Family::orthogonal_cubic_bspline();
  if (name.size() > 2 && name.size() < 5 && name.rfind("db", 0) == 0 &&
      name.find_first_not_of("0123456789", 2) == std::string::npos) {
    return wavelets::Family::daubechies(std::stoi(name.substr(2)));
  }
  throw std::invalid_argument("family '" + name + "' is unknown; use haar, db4 … db20 (even) or bspline");
}

Eigen::SparseMatrix<double> sparse(const Eigen::MatrixXd& m) { return m.sparseView(); }

// (dof, amplitude [N], phase [rad], harmonic) of a further load.
using Load = std::tuple<int, double, double, int>;

// The contact quadrature by name (docs/scenes.md [basis] contact_quadrature).
solvers::ContactQuadrature quadrature(const std::string& name) {
  if (name == "midpoint") return solvers::ContactQuadrature::Midpoint;
  if (name == "cell-average") return solvers::ContactQuadrature::CellAverage;
  throw std::invalid_argument("contact_quadrature = \"" + name + "\": must be \"midpoint\" (the paper's rule) or "
                              "\"cell-average\" (smooth for a law with a corner, e.g. LinearPenalty)");
}

solvers::HarmonicForcing forcing(int dof, double amplitude, double frequency_hz, const std::vector<Load>& loads) {
  solvers::HarmonicForcing f{dof, amplitude, frequency_hz};
  for (const auto& [d, a, phase, h] : loads) f.more.push_back({d, a, phase, h});
  return f;
}

// A contact of the Python API: (dof, law), or (dof, law, normal) for a friction law whose slip
// force follows the contact at index `normal` of the same list (solvers::ContactPoint::normal).
using ContactSpec = std::variant<std::tuple<int, std::shared_ptr<contact::ContactLaw>>,
                                 std::tuple<int, std::shared_ptr<contact::ContactLaw>, int>>;

std::vector<solvers::ContactPoint> points(const std::vector<ContactSpec>& contacts) {
  std::vector<solvers::ContactPoint> out;
  for (const auto& spec : contacts) {
    if (const auto* pair = std::get_if<0>(&spec)) {
      out.push_back({std::get<0>(*pair), std::get<1>(*pair)});
    } else {
      const auto& [d, law, normal] = std::get<1>(spec);
      out.push_back({d, law, -1, {}, normal});
    }
  }
  return out;
}

}  // namespace

PYBIND11_MODULE(wbm, m) {
  m.doc() = "wbm: periodic vibrations of structures with unilateral contact, by weighted residuals in time "
            "(wavelet balance, harmonic balance) [Jones & Legrand 2014; Laxalde & Legrand 2011]. SI units.";

  m.def(
      "run_scene", [](const py::object& source) { return result_dict(scene::run_analysis(scene_of(source))); },
      py::arg("source"),
      R"(Run a scene (docs/scenes.md) and return its results.

source: a path to a .toml scene, TOML text, or a dict with the scene's keys (as scene_json() gives).
Returns a dict: converged (bool, from verified residuals: AnalysisResult::converged, as wbm run), status (str, the solvers' vocabulary), summary (str), warnings (list of str),
diagnostics (dict: statuses, iterations, residuals, timings), tables ({file name: {column header:
1-D numpy array}}; headers carry the units, e.g. "u_tip [m]"; "status" is a list of str when a
table has one). Nothing is written to disk. Raises ValueError for a bad scene, with the file, line,
key, allowed range and a way out, as `wbm check` prints it.)");
  m.def(
      "scene_json",
      [](const py::object& source, const py::object& file) {
        if (!file.is_none() && py::isinstance<py::dict>(source)) {  // a dict read from that file
          const auto anchor = py::module_::import("os").attr("fspath")(file).cast<std::string>();
          return to_python(scene::to_json(scene::scene_from_json(python::json_of(source, ""), anchor)));
        }
        return to_python(scene::to_json(scene_of(source)));
      },
      py::arg("source"), py::arg("file") = py::none(),
      "The resolved scene (every default filled in) as a dict, accepted back by run_scene. file: for a dict "
      "source, the scene file it was read from: it names the scene in messages and anchors relative paths "
      "(Matrix Market files, decks), as if the dict were that file. Raises ValueError as run_scene.");
  m.def(
      "study",
      [](py::args args, py::kwargs kwargs) { return py::module_::import("wbm_study").attr("study")(*args, **kwargs); },
      R"(Runs a parametric or Monte Carlo study of a scene on Dask and returns its table as a pandas
DataFrame: study(source, output=None, workers=None, scheduler=None, quiet=True, cli=None).

source: a study .toml path or a dict of its keys (docs/studies.md: a base scene, [[axis]] tables
of dotted scene keys with values, a range or random draws, `combine` and `collect`). Each case
runs as `wbm run` on a worker of an embedded LocalCluster (`workers` processes on 127.0.0.1,
default one per core) or of the cluster at `scheduler` (tcp://HOST:PORT), and writes
output/cases/<id>/ (default output: wbm-study/<title>); output/study.csv, study.json and
study.png hold the table. Cases complete in `output` are not run again. The DataFrame has
study.csv's columns (units in the headers; NaN where a quantity is missing). Raises ValueError
for a bad study or axis, with the scene parser's message, before any case runs (nothing is
written). Implemented in wbm_study.py beside this module (issue #37).)");

  // Time bases.
  py::class_<solvers::TimeBasis>(m, "TimeBasis", "A family of M periodic trial or weighting functions on τ ∈ [0, 1).")
      .def(py::init([](const std::string& name, int dimension) { return solvers::TimeBasis::from_name(name, dimension); }),
           py::arg("name"), py::arg("dimension"),
           "name: fourier, haar, db4 … db20, bspline; dimension M (a power of two for wavelets). Raises ValueError.")
      .def_property_readonly("name", &solvers::TimeBasis::name)
      .def_property_readonly("dimension", &solvers::TimeBasis::dimension)
      .def(
          "values",
          [](const solvers::TimeBasis& b, const py::object& tau, int derivative) {
            return b.values(python::vector(tau, "TimeBasis.values: tau", -1, "a 1-D array of finite times τ"),
                            derivative);
          },
          py::arg("tau"), py::arg("derivative") = 0,
          "Values (or d-th τ-derivatives) at tau (1-D, finite, normalized time, 1-periodic): array (len(tau), M), "
          "column k = function k. Raises ValueError for another shape or dtype, a non-finite τ, or a derivative the "
          "family does not have pointwise.")
      .def("__repr__", [](const solvers::TimeBasis& b) {
        return "TimeBasis('" + b.key() + "', " + std::to_string(b.dimension()) + ")";
      });
  m.def("basis_names", &solvers::TimeBasis::names, "The names TimeBasis accepts.");

  m.def(
      "connection_coefficients",
      [](const std::string& family, int d1, int d2) {
        const auto g = wavelets::connection_coefficients(family_of(family), d1, d2);
        py::dict out;
        out["first_shift"] = g.first_shift;
        out["last_shift"] = g.last_shift;
        out["values"] = py::cast(g.values);
        out["residual"] = g.residual;
        return out;
      },
      py::arg("family"), py::arg("d1"), py::arg("d2"),
      R"(Connection coefficients Γ^{d1,d2}[k] = ∫ φ^(d1)(t) φ^(d2)(t − k) dt on the real line
[Latto et al. 1991; Beylkin 1992]: a dict with first_shift, last_shift, values (values[k −
first_shift] = Γ[k]) and residual. family: haar, db4 … db20, bspline. Raises ValueError for an
order the family does not have.)");

  // Systems.
  py::class_<solvers::MechanicalSystem>(m, "MechanicalSystem", "M ü + C u̇ + K u = f: n × n SI matrices, stored sparse.")
      .def(py::init([](const py::object& mass, const py::object& damping, const py::object& stiffness) {
             const Eigen::MatrixXd m = python::matrix(mass, "MechanicalSystem: mass", -1, -1, "(n, n), n >= 1");
             const std::string square = "(n, n) = (" + std::to_string(m.rows()) + ", " + std::to_string(m.rows()) +
                                        "), the shape of the mass";
             if (m.cols() != m.rows()) {
               throw std::invalid_argument("MechanicalSystem: mass has shape (" + std::to_string(m.rows()) + ", " +
                                           std::to_string(m.cols()) + "); expected a square (n, n)");
             }
             solvers::MechanicalSystem s{
                 sparse(m), sparse(python::matrix(damping, "MechanicalSystem: damping", m.rows(), m.rows(), square)),
                 sparse(python::matrix(stiffness, "MechanicalSystem: stiffness", m.rows(), m.rows(), square))};
             solvers::require_physical(s, "MechanicalSystem");
             return s;
           }),
           py::arg("mass"), py::arg("damping"), py::arg("stiffness"),
           "Dense n × n arrays of finite reals M [kg], C [N·s/m], K [N/m]. Raises ValueError for another shape or "
           "dtype, a non-finite entry, an asymmetric matrix, a mass that is not positive definite or a stiffness that "
           "is not positive semidefinite (solvers::require_physical; rigid-body modes are accepted).")
      .def_property_readonly("dofs", &solvers::MechanicalSystem::dofs)
      .def_property_readonly("mass", [](const solvers::MechanicalSystem& s) { return Eigen::MatrixXd(s.mass); })
      .def_property_readonly("damping", [](const solvers::MechanicalSystem& s) { return Eigen::MatrixXd(s.damping); })
      .def_property_readonly("stiffness", [](const solvers::MechanicalSystem& s) { return Eigen::MatrixXd(s.stiffness); });
  m.def(
      "rod",
      [](double young_modulus, double density, double area, double length, int elements, double beta) {
        return solvers::beta_damped(fem::Rod({young_modulus, density, area, length, elements}), beta);
      },
      py::arg("young_modulus"), py::arg("density"), py::arg("area"), py::arg("length"), py::arg("elements"),
      py::arg("beta") = 0.0,
      "The clamped-free FE rod of [JL14 Sec. 2] (linear elements, consistent mass, node 0 clamped; DOF i is "
      "node i + 1, the tip is DOF elements − 1) with C = βK [s]. Raises ValueError.");
  m.def(
      "natural_frequencies_hz",
      [](const solvers::MechanicalSystem& s) {
        const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Eigen::MatrixXd(s.stiffness), Eigen::MatrixXd(s.mass));
        return Eigen::VectorXd(es.eigenvalues().cwiseMax(0.0).cwiseSqrt() / (2.0 * std::numbers::pi));
      },
      py::arg("system"), "Undamped natural frequencies [Hz], ascending (dense generalized eigenproblem K φ = ω² M φ).");

  // Contact laws.
  py::class_<contact::ContactLaw, std::shared_ptr<contact::ContactLaw>>(m, "ContactLaw")
      .def(
          "force", [](const contact::ContactLaw& l, double u) { return l.force(python::finite(u, "ContactLaw.force: u")); },
          py::arg("u"), "Contact force f_c(u) ≥ 0 [N] at displacement u [m] (finite; ValueError otherwise).")
      .def(
          "stiffness",
          [](const contact::ContactLaw& l, double u) { return l.stiffness(python::finite(u, "ContactLaw.stiffness: u")); },
          py::arg("u"), "df_c/du [N/m] at u [m] (finite; ValueError otherwise).")
      .def_property_readonly("gap", &contact::ContactLaw::gap)
      .def_property_readonly("rigid", &contact::ContactLaw::rigid)
      .def("__repr__", &contact::ContactLaw::describe);
  py::class_<contact::ExponentialPenalty, contact::ContactLaw, std::shared_ptr<contact::ExponentialPenalty>>(
      m, "ExponentialPenalty", "f = a_c (e^{α(u − g0)} − 1) for u > g0, else 0 [JL14 Eq. (5)].")
      .def(py::init([](double coefficient, double exponent, double gap) {
             return std::make_shared<contact::ExponentialPenalty>(contact::ExponentialPenaltyParameters{coefficient, exponent, gap});
           }),
           py::arg("coefficient"), py::arg("exponent"), py::arg("gap"));
  py::class_<contact::LinearPenalty, contact::ContactLaw, std::shared_ptr<contact::LinearPenalty>>(
      m, "LinearPenalty", "f = k max(u − g0, 0).")
      .def(py::init([](double stiffness, double gap) {
             return std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{stiffness, gap});
           }),
           py::arg("stiffness"), py::arg("gap"));
  py::class_<contact::RigidStop, contact::ContactLaw, std::shared_ptr<contact::RigidStop>>(
      m, "RigidStop", "Exact unilateral contact at g0 (Signorini conditions; force() and stiffness() raise).")
      .def(py::init([](double gap) { return std::make_shared<contact::RigidStop>(gap); }), py::arg("gap"));
  py::class_<contact::JenkinsLaw, contact::ContactLaw, std::shared_ptr<contact::JenkinsLaw>>(
      m, "JenkinsLaw",
      "Dry friction along the contact's direction: a spring k_t [N/m] in series with a Coulomb slider of slip force "
      "mu N [N] (contact/friction.hpp). Hysteretic: force() and stiffness() raise; wbm.solve evaluates its periodic "
      "loop.")
      .def(py::init([](double tangential_stiffness, double friction_coefficient, double normal_load) {
             return std::make_shared<contact::JenkinsLaw>(
                 contact::JenkinsParameters{tangential_stiffness, friction_coefficient, normal_load});
           }),
           py::arg("tangential_stiffness"), py::arg("friction_coefficient"), py::arg("normal_load"));
  py::class_<contact::CoulombFriction, contact::ContactLaw, std::shared_ptr<contact::CoulombFriction>>(
      m, "CoulombFriction",
      "Exact Coulomb friction along the contact's direction, slip force mu N [N] (contact/friction.hpp): the k_t -> inf "
      "limit of JenkinsLaw. Its force is a multiplier at the collocation instants, as a RigidStop's (rigid is True; "
      "force() and stiffness() raise); wbm.solve returns it in contact_force_samples with collocation_times. All "
      "contacts of one solve exact (RigidStop, CoulombFriction) or none. As (dof, law, normal) with `normal` the "
      "index of a RigidStop in the same list and normal_load = 0, a 2D contact: the slip force is mu times that "
      "stop's multiplier at each instant (one CoulombFriction per stop).")
      .def(py::init([](double friction_coefficient, double normal_load) {
             return std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{friction_coefficient, normal_load});
           }),
           py::arg("friction_coefficient"), py::arg("normal_load"));
  m.def(
      "jenkins_loop",
      [](double tangential_stiffness, const py::object& w, const py::object& slip_force) {
        const Eigen::VectorXd wv = python::vector(w, "jenkins_loop: w", -1, "a 1-D array of finite displacements [m]");
        const Eigen::VectorXd fs = python::vector(slip_force, "jenkins_loop: slip_force", wv.size(),
                                                  "a 1-D array of finite slip forces [N], one per sample of w");
        const contact::JenkinsLoop l = contact::jenkins_loop(tangential_stiffness, wv, fs);
        py::dict out;
        out["force"] = py::cast(l.force);
        out["stiffness"] = py::cast(l.stiffness);
        out["slipping_samples"] = l.slipping_samples;
        out["periods"] = l.periods;
        out["dissipated_energy"] = l.dissipated_energy;
        return out;
      },
      py::arg("tangential_stiffness"), py::arg("w"), py::arg("slip_force"),
      R"(The periodic steady state of a Jenkins element (contact::jenkins_loop): the return map
f*_q = f_a + k_t (w_q − w_a), f_q = f*_q if |f*_q| ≤ F_s,q else ±F_s,q, run over the period until
its end force repeats. tangential_stiffness k_t [N/m] > 0; w: the Q tangential displacements of one
period, uniform in time [m]; slip_force: Q slip forces F_s = mu N ≥ 0 [N]. Returns a dict: force (Q,
[N]), stiffness (Q, ∂f_q/∂w_q: k_t in stick, 0 in slip [N/m]), slipping_samples, periods (run until
the end repeated) and dissipated_energy (the slider's work over the period, ∮ f dw [J]). Raises
ValueError for bad input.)");

  m.def(
      "solve",
      [](const solvers::MechanicalSystem& system, int dof, double amplitude, double frequency_hz,
         const std::vector<ContactSpec>& contacts, const solvers::TimeBasis& trial,
         const solvers::TimeBasis& weighting, const std::string& formulation, const std::vector<Load>& loads,
         const std::vector<int>& harmonics, const std::string& contact_quadrature) {
        solvers::WeightedResidualOptions options;
        options.formulation = solvers::parse_formulation(formulation);
        options.harmonics = harmonics;
        options.contact_quadrature = quadrature(contact_quadrature);
        const auto s = solvers::solve_weighted_residual(system, forcing(dof, amplitude, frequency_hz, loads),
                                                        points(contacts), trial, weighting, options);
        // The solution's one JSON form (wbm/scene/json.hpp, as result.json's diagnostics.solution),
        // plus its arrays.
        py::dict out = to_python(nlohmann::json(s));
        out["coefficients"] = py::cast(s.coefficients);
        if (s.contact_force_samples.size() > 0) {
          out["contact_force_samples"] = py::cast(s.contact_force_samples);
          out["collocation_times"] = py::cast(s.collocation_times);
        }
        return out;
      },
      py::arg("system"), py::arg("dof"), py::arg("amplitude"), py::arg("frequency_hz"), py::arg("contacts"),
      py::arg("trial"), py::arg("weighting"), py::arg("formulation") = "distributional",
      py::arg("loads") = std::vector<Load>{}, py::arg("harmonics") = std::vector<int>{},
      py::arg("contact_quadrature") = "midpoint",
      R"(Forced response by weighted residuals [JL14 Eqs. (14)–(17)] to F cos(2π f t) on DOF `dof`.

loads: further loads, a list of (dof, amplitude [N], phase [rad], harmonic h ≥ 0) tuples, each
F cos(2π h f t + φ) (h = 0: a constant load). contacts: list of (dof, ContactLaw) pairs (all
RigidStop and CoulombFriction, or penalty and JenkinsLaw ones; a JenkinsLaw needs contact_quadrature "midpoint"),
or (dof, JenkinsLaw, normal) triples for a normal load that varies: the slip force is μ (N + n), n the force of
the penalty contact at index `normal` of this list (ContactPoint::normal). harmonics: harmonic selection for Fourier:Fourier, e.g. [1, 3, 5]
(empty: all; WeightedResidualOptions::harmonics, docs/scenes.md); the dict then also has
dropped_harmonics_residual, the residual left in the other harmonics over ‖b‖ (None without a
selection).
contact_quadrature: "midpoint" (the paper's f_c(u(τ_q))) or "cell-average" (the law integrated
over each cell: C¹ in the unknowns, so a law with a corner such as LinearPenalty gives a smooth
residual; needs a trial with a slope). Returns a dict with the keys of result.json's
diagnostics.solution (docs/scenes.md; one serializer, wbm/scene/json.hpp): converged (verified
residual), status, message, newton (iterations, residual_norms, tolerance, ...), path,
relative_residual, backward_error (the verified quantity), residual_tolerance, max_penetration_m, max_contact_force_N, condition_number,
dropped_harmonics_residual, wall_time_s, ... (None for a value that is not finite); and the
arrays coefficients (n × M: row = DOF, column = trial function), contact_force_samples
(n_c × M [N], exact contacts only: the multipliers) and collocation_times (M, their instants τ_k). Non-convergence is returned, not raised; bad input raises ValueError.)");
  m.def(
      "trace_response",
      [](const solvers::MechanicalSystem& system, int dof, double amplitude,
         const std::variant<double, std::pair<double, double>>& frequency_hz, const std::vector<ContactSpec>& contacts,
         const solvers::TimeBasis& trial, const solvers::TimeBasis& weighting, const std::string& formulation,
         bool stability, double max_step, double max_frequency_step_hz, int max_points, int samples,
         const std::vector<Load>& loads, const std::vector<int>& harmonics, const std::string& contact_quadrature,
         const std::optional<std::pair<double, double>>& friction_coefficient, int time_samples,
         const std::string& stick_slip_events) {
        solvers::WeightedResidualOptions options;
        options.time_samples = time_samples;
        options.formulation = solvers::parse_formulation(formulation);
        options.harmonics = harmonics;
        options.contact_quadrature = quadrature(contact_quadrature);
        // A branch in f over frequency_hz = (from, to), or in μ over friction_coefficient = (from, to)
        // at the one frequency frequency_hz = f.
        const bool in_mu = friction_coefficient.has_value();
        const auto* one = std::get_if<double>(&frequency_hz);
        if (in_mu && one == nullptr) {
          throw std::invalid_argument("trace_response: frequency_hz is a range (from, to) beside "
                                      "friction_coefficient = (from, to); a branch in mu is at one frequency: pass "
                                      "frequency_hz = f");
        }
        if (!in_mu && one != nullptr) {
          throw std::invalid_argument("trace_response: frequency_hz = " + solvers::format_number(*one) +
                                      " is one frequency; give the range (from, to) of the branch, or "
                                      "friction_coefficient = (from, to) for a branch in mu at that frequency");
        }
        const std::pair<double, double> range =
            in_mu ? *friction_coefficient : std::get<std::pair<double, double>>(frequency_hz);
        std::vector<solvers::ContactPoint> laws = points(contacts);
        if (in_mu) laws = solvers::with_friction_coefficient(laws, range.first);  // the branch starts at `from`
        const solvers::WeightedResidual base(system, forcing(dof, amplitude, in_mu ? *one : range.first, loads),
                                             std::move(laws), trial, weighting, options);
        solvers::ResponseCurveOptions o;
        if (in_mu) o.parameter = solvers::ContinuationParameter::FrictionCoefficient;
        o.parameter_min = std::min(range.first, range.second);
        o.parameter_max = std::max(range.first, range.second);
        o.direction = range.second > range.first ? +1 : -1;
        o.stability = stability;
        o.max_step = max_step;
        o.initial_step = std::min(o.initial_step, max_step);
        if (in_mu && max_frequency_step_hz != 0.0) {
          throw std::invalid_argument("trace_response: max_frequency_step_hz caps |df| of a branch in frequency; a "
                                      "branch in mu is at one frequency: leave it 0");
        }
        o.max_parameter_step = max_frequency_step_hz;
        o.max_points = max_points;
        o.samples = samples;
        if (stick_slip_events == "always") {
          o.stick_slip_events = solvers::StickSlipEvents::Always;
        } else if (stick_slip_events == "never") {
          o.stick_slip_events = solvers::StickSlipEvents::Never;
        } else if (stick_slip_events != "on-stall") {
          throw std::invalid_argument("trace_response: stick_slip_events = \"" + stick_slip_events +
                                      "\" is not one of \"on-stall\", \"always\", \"never\" (default \"on-stall\")");
        }
        const auto curve = solvers::trace_response(base, o);
        const auto n = static_cast<Eigen::Index>(curve.points.size());
        Eigen::VectorXd f(n), umax(n), umin(n), amp(n), force(n), mu(n), mu_error(n), dropped(n), distance(n);
        Eigen::VectorXd friction(n);
        Eigen::Matrix<bool, Eigen::Dynamic, 1> stable(n), available(n);
        for (Eigen::Index i = 0; i < n; ++i) {
          const auto& p = curve.points[static_cast<size_t>(i)];
          f(i) = p.frequency_hz;
          friction(i) = p.parameter;
          umax(i) = p.max_displacement;
          umin(i) = p.min_displacement;
          amp(i) = p.amplitude;
          force(i) = p.max_contact_force;
          // A point without a verdict (rigid stops: no exact orbit near it): NaN multipliers, not stable.
          mu(i) = stability && p.stability_available ? p.max_multiplier : NAN;
          mu_error(i) = stability && p.stability_available ? p.max_multiplier_error : NAN;
          stable(i) = p.stable;
          available(i) = p.stability_available;
          distance(i) = p.shooting_distance;
          dropped(i) = p.dropped_harmonics_residual;
        }
        std::vector<double> folds, fold_amplitudes;
        for (const auto& fold : curve.folds) folds.push_back(fold.parameter);
        for (const auto& fold : curve.fold_points) fold_amplitudes.push_back(fold.amplitude);
        py::dict out;
        out["converged"] = curve.converged();  // the one definition (solvers::branch_status), as wbm run
        out["stop"] = std::string(solvers::to_string(curve.stop));
        out["message"] = curve.message;
        out["frequency_hz"] = py::cast(f);
        if (in_mu) out["friction_coefficient"] = py::cast(friction);
        out["max_displacement"] = py::cast(umax);
        out["min_displacement"] = py::cast(umin);
        out["amplitude"] = py::cast(amp);
        out["max_contact_force"] = py::cast(force);
        if (!harmonics.empty()) out["dropped_harmonics_residual"] = py::cast(dropped);
        if (stability) {
          out["stable"] = py::cast(stable);
          out["max_floquet_multiplier"] = py::cast(mu);
          out["max_floquet_multiplier_error"] = py::cast(mu_error);
          out["stability_available"] = py::cast(available);
          if (base.rigid()) out["shooting_distance"] = py::cast(distance);  // the exact orbit's, relative
        }
        out[in_mu ? "folds_friction_coefficient" : "folds_hz"] = folds;
        out["fold_amplitudes"] = fold_amplitudes;
        out["fold_confirmed"] = curve.fold_confirmed;
        out["wall_time_s"] = curve.wall_time_s;
        out["stability_time_s"] = curve.stability_time_s;
        out["stability_work_s"] = curve.stability_work_s;
        out["events"] = curve.events;
        return out;
      },
      py::arg("system"), py::arg("dof"), py::arg("amplitude"), py::arg("frequency_hz"), py::arg("contacts"),
      py::arg("trial"), py::arg("weighting"), py::arg("formulation") = "distributional", py::arg("stability") = true,
      py::arg("max_step") = 2e-2, py::arg("max_frequency_step_hz") = 0.0, py::arg("max_points") = 5000,
      py::arg("samples") = 512, py::arg("loads") = std::vector<Load>{}, py::arg("harmonics") = std::vector<int>{},
      py::arg("contact_quadrature") = "midpoint", py::arg("friction_coefficient") = py::none(),
      py::arg("time_samples") = 0, py::arg("stick_slip_events") = "on-stall",
      R"(Frequency-response curve by pseudo-arclength continuation in f over frequency_hz = (from, to)
[Hz] (solvers::trace_response; folds passed); or, with friction_coefficient = (from, to), a branch
in the friction coefficient mu shared by every Jenkins element (it starts at `from`, replacing the
elements' own mu) at the one frequency frequency_hz = f [Hz] (ContinuationParameter::
FrictionCoefficient: G factorized once; under a constant normal load the damper's curve of
amplitude against mu N); with Floquet stability of every point (monodromy
matrix on `samples` steps; with rigid stops, the saltation monodromy of the exact orbit with plastic
impacts near each point, by shooting; with Jenkins elements, one more state per element, its force
perturbation; refused for exact Coulomb friction: pass stability=False). Arguments as solve();
max_step: scaled arclength per step; max_frequency_step_hz > 0 caps |Δf|; time_samples: Q samples
per period of the contact forces (0: max(256, 2M); a Jenkins element's stick/slip kinks are milder
with more, e.g. 4M, as the stop message advises); stick_slip_events: "on-stall" (the nonsmooth
corrector, and piece by piece on located stick/slip events where it stalls), "always" or "never"
(solvers::StickSlipEvents).
Returns a dict of arrays in branch order (length = points): frequency_hz, max_displacement,
min_displacement, amplitude [m] of the forced DOF, max_contact_force [N]; with stability: stable
(bool), max_floquet_multiplier, max_floquet_multiplier_error (NaN where stability_available (bool)
is false: no exact orbit found near a point with rigid stops), with rigid stops shooting_distance
(the exact orbit's rms distance from the point's, relative); and folds_hz (turning points; in a
branch in mu folds_friction_coefficient instead, and friction_coefficient per point),
fold_amplitudes [m] (the forced DOF's amplitude at each fold's own state, Hermite-interpolated on
its step: on a multivalued curve not the nearest point's), fold_confirmed (a multiplier crosses +1 near it), converged (the range was reached), stop,
message, wall_time_s, stability_time_s (the wait for the multipliers after the continuation: with
two threads or more they are computed during it), stability_work_s (their thread time), events (stick/slip or impulse switches located and
crossed); with harmonics (a selection, as in solve()):
dropped_harmonics_residual per point. Non-convergence is returned, not raised.)");
  m.def(
      "nonlinear_mode",
      [](const solvers::MechanicalSystem& system, const std::vector<std::pair<int, double>>& stops,
         std::pair<double, double> energy, int harmonics, int samples, double penalty_stiffness, double max_energy_step,
         bool stability) {
        if (stability && penalty_stiffness > 0.0) {
          throw std::invalid_argument("nonlinear_mode: stability=True with penalty_stiffness = " +
                                      solvers::format_number(penalty_stiffness) +
                                      " N/m: a backbone's stability is computed for rigid stops only (through the "
                                      "exact orbits with elastic impacts); pass stability=False or "
                                      "penalty_stiffness=0");
        }
        std::vector<solvers::RigidStop> rigid;
        for (const auto& [dof, gap] : stops) rigid.push_back({dof, gap});
        solvers::NonlinearModeOptions options;
        options.harmonics = harmonics;
        options.samples = samples;
        const solvers::NonlinearModes modes(system, rigid, options);
        solvers::BackboneContinuationOptions o;
        o.energy_min = energy.first;
        o.energy_max = energy.second;
        o.penalty_stiffness = penalty_stiffness;
        o.max_energy_step = max_energy_step;
        const auto b = modes.continue_backbone(o);
        const scene::BackboneColumns c = scene::backbone_columns(modes, b);
        py::dict out;
        out["converged"] = b.converged();  // the one definition (Backbone::converged), as wbm run
        out["message"] = b.message;
        out["linear_frequency_hz"] = modes.linear_frequency_hz();
        out["energy"] = py::cast(c.energy);
        out["frequency_hz"] = py::cast(c.frequency_hz);
        out["rayleigh_frequency_hz"] = py::cast(c.rayleigh_frequency_hz);
        out["max_penetration"] = py::cast(c.max_penetration);
        out["complementarity"] = py::cast(c.complementarity);
        out["first_mode_share"] = py::cast(c.first_mode_share);
        out["other_mode"] = py::cast(Eigen::VectorXi(c.other_mode.cast<int>()));
        out["other_harmonic"] = py::cast(Eigen::VectorXi(c.other_harmonic.cast<int>()));
        out["other_share"] = py::cast(c.other_share);
        out["folds"] = b.folds;
        std::vector<double> fold_hz;
        for (const auto& l : b.fold_levels) fold_hz.push_back(l.frequency_hz);
        out["fold_frequencies_hz"] = fold_hz;
        out["wall_time_s"] = b.wall_time_s;
        if (stability) {  // NonlinearModes::stability of every level (NaN where no verdict)
          const auto results = modes.stability(b);
          const auto n = static_cast<Eigen::Index>(results.size());
          const double nan = std::numeric_limits<double>::quiet_NaN();
          Eigen::VectorXd mu(n), exact(n), distance(n), impacts(n);
          std::vector<bool> stable, available;
          std::vector<std::string> why;
          for (Eigen::Index i = 0; i < n; ++i) {
            const auto& r = results[static_cast<size_t>(i)];
            available.push_back(r.available);
            stable.push_back(r.available && r.stable);
            mu(i) = r.available ? r.max_modulus : nan;
            exact(i) = r.available ? r.frequency_hz : nan;
            distance(i) = r.available ? r.distance : nan;
            impacts(i) = r.available ? r.impacts : nan;
            why.push_back(r.message);
          }
          out["stability_available"] = available;
          out["stable"] = stable;
          out["max_floquet_multiplier"] = py::cast(mu);
          out["exact_frequency_hz"] = py::cast(exact);
          out["orbit_distance"] = py::cast(distance);
          out["impacts"] = py::cast(impacts);
          out["stability_message"] = why;
        }
        return out;
      },
      py::arg("system"), py::arg("stops"), py::arg("energy"), py::arg("harmonics") = 16, py::arg("samples") = 256,
      py::arg("penalty_stiffness") = 0.0, py::arg("max_energy_step") = 0.05, py::arg("stability") = false,
      R"(First nonlinear normal mode of the undamped system (damping ignored) against rigid stops
[LL11], by pseudo-arclength continuation in energy over energy = (min, max) (normalized: 1 at
contact onset). stops: list of (dof, gap [m] > 0). harmonics N, samples m > 2N of the contact
conditions; penalty_stiffness > 0 replaces exact contact by a linear spring [N/m].
Returns a dict of arrays per backbone level: energy, frequency_hz (of the periodic orbit),
rayleigh_frequency_hz, max_penetration and complementarity [gap], first_mode_share (of the energy m̂
held by linear mode 1 at the fundamental) and the largest other component other_mode, other_harmonic
(1-based), other_share (NonlinearModes::modal_components: an internal resonance shows as a large
other_share with f_j ≈ h f); and linear_frequency_hz, folds
(energies where the branch turns back) and fold_frequencies_hz (the frequency at each), converged (Backbone::converged: the energy range covered, as wbm run), message, wall_time_s.
stability=True (rigid stops only; a ValueError with penalty_stiffness > 0): each level's stability
through the exact orbit with elastic impacts near it (NonlinearModes::stability: autonomous
shooting at the level's mean energy, the nontrivial multipliers of its saltation monodromy), as
stability_available (bool), stable (bool), max_floquet_multiplier, exact_frequency_hz [Hz],
orbit_distance (relative rms of the stops' displacements) and impacts per period (NaN where no
verdict), and stability_message (why a level has none).)");
  m.def(
      "basis_mode",
      [](const solvers::MechanicalSystem& system, const std::vector<std::pair<int, double>>& stops,
         std::pair<double, double> energy, const solvers::TimeBasis& basis, int samples,
         std::optional<double> sample_offset, double max_energy_step) {
        std::vector<solvers::RigidStop> rigid;
        for (const auto& [dof, gap] : stops) rigid.push_back({dof, gap});
        // The problem (structure, stops, onset normalization); its harmonics are not used.
        const solvers::NonlinearModes problem(system, rigid, {.harmonics = 1, .samples = 3});
        const solvers::BasisModes modes(problem, basis, {.samples = samples, .sample_offset = sample_offset});
        solvers::BackboneContinuationOptions o;
        o.energy_min = energy.first;
        o.energy_max = energy.second;
        o.max_energy_step = max_energy_step;
        const auto b = modes.continue_backbone(o);
        const auto n = static_cast<Eigen::Index>(b.levels.size());
        Eigen::VectorXd e(n), f(n), r(n), pen(n), comp(n), sigma(n);
        for (Eigen::Index i = 0; i < n; ++i) {
          const auto& l = b.levels[static_cast<size_t>(i)];
          e(i) = l.level.energy;
          f(i) = l.level.frequency_hz;
          r(i) = l.level.rayleigh_frequency_hz;
          pen(i) = l.level.max_penetration;
          comp(i) = l.level.complementarity;
          sigma(i) = l.phase_multiplier;
        }
        py::dict out;
        out["converged"] = b.complete();
        out["stop"] = std::string(solvers::to_string(b.stop));
        out["message"] = b.message;
        out["linear_frequency_hz"] = problem.linear_frequency_hz();
        out["basis"] = modes.basis().name();
        out["unknowns"] = modes.unknowns();
        out["samples"] = modes.samples();
        out["sample_offset"] = modes.sample_offset();
        out["energy"] = py::cast(e);
        out["frequency_hz"] = py::cast(f);
        out["rayleigh_frequency_hz"] = py::cast(r);
        out["max_penetration"] = py::cast(pen);
        out["complementarity"] = py::cast(comp);
        out["phase_multiplier"] = py::cast(sigma);
        out["events"] = b.kinks;
        out["wall_time_s"] = b.wall_time_s;
        return out;
      },
      py::arg("system"), py::arg("stops"), py::arg("energy"), py::arg("basis"), py::arg("samples") = 0,
      py::arg("sample_offset") = py::none(), py::arg("max_energy_step") = 0.05,
      R"(First nonlinear normal mode against rigid stops in any time basis (solvers::BasisModes,
issue #38): LL11's KKT conditions (Signorini at m instants, energy normalization) in the Galerkin
form of basis (a TimeBasis: Fourier, B-spline, DB6, or Haar with the delta-pair velocity, its
Galerkin system then the central-difference scheme in time), continued in energy from energy[0] < 1
(below contact onset) to energy[1]. stops: list of (dof, gap [m] > 0). samples: m instants τ_s =
(s + o)/m, 0 for m = M; sample_offset: o in [0, 1), None for ½ with Haar and 0 otherwise.
Returns a dict: arrays per level energy, frequency_hz, rayleigh_frequency_hz, max_penetration and
complementarity [gap], phase_multiplier (the phase condition's multiplier: 0 for Fourier, of the
order of the discretization otherwise); converged (the range was reached), stop, message,
linear_frequency_hz, basis, unknowns, samples, sample_offset (as used), events, wall_time_s.
Raises ValueError for a basis without a velocity (DB4), samples < M, bad stops or energies.
Non-convergence is returned, not raised.)");
  m.def(
      "evaluate",
      [](const solvers::TimeBasis& trial, const py::object& coefficients, const py::object& tau) -> Eigen::MatrixXd {
        const int m = trial.dimension();
        const Eigen::MatrixXd a = python::matrix(coefficients, "evaluate: coefficients", -1, m,
                                                 "(n, M) = (n, " + std::to_string(m) +
                                                     "): one row per DOF, one column per trial function");
        return a * trial.values(python::vector(tau, "evaluate: tau", -1, "a 1-D array of finite times τ"), 0).transpose();
      },
      py::arg("trial"), py::arg("coefficients"), py::arg("tau"),
      "Displacements u(τ) [m] of every DOF: array (n, len(tau)) from the n × M coefficients of solve() (finite "
      "reals) at the finite normalized times tau (1-D). Raises ValueError for another shape or dtype, or a "
      "non-finite entry.");

  python::bind_haar_impact(m);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const std::invalid_argument& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const std::out_of_range& e) {
      PyErr_SetString(PyExc_IndexError, e.what());
    }
  });
}
