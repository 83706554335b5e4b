// The declarations (declared_keys.hpp) of the model's sections: [structure] (rod, matrices, and
// the keys of a deck), [forcing] and its [[forcing.loads]], [[contact]] by law, and [basis].
// Most of their keys are Compound (a location, a matrix, a frequency range, a list): the
// section's parser reads them (scene_structure.cpp, scene_forcing.cpp, scene_contacts.cpp,
// scene_basis.cpp) and the declaration names and documents them.
#include "scene_keys.hpp"

#include <wbm/scene/reduce.hpp>

#include "scene_parser.hpp"

namespace wbm::scene::detail {

namespace {
constexpr const char* kMatrixType = "matrix";
constexpr const char* kLocation = "location";
}  // namespace

const std::vector<DeclaredKey<Structure>>& structure_keys() {
  using S = Structure;
  static const std::vector<DeclaredKey<S>> keys = {
      choice_key<S>("type", {"rod", "matrices", "deck"},
                    [](const S& s) { return s.deck ? "deck" : s.kind == StructureKind::Rod ? "rod" : "matrices"; },
                    [](S&, const std::string&) {},
                    "`\"deck\"` when `deck` is given, else `\"matrices\"` when any of `mass`, `stiffness`, `damping`, "
                    "`dofs` appears, else `\"rod\"`")
          .documented_default("inferred")
          .read_by_section(),
      number_key<S>("young_modulus", [](auto& s) -> auto& { return s.rod.young_modulus; }, positive("Pa"), "E")
          .is_required()
          .only_in({"rod"}),
      number_key<S>("density", [](auto& s) -> auto& { return s.rod.density; }, positive("kg/m^3"), "ρ")
          .is_required()
          .only_in({"rod"}),
      number_key<S>("area", [](auto& s) -> auto& { return s.rod.area; }, positive("m^2"), "S")
          .is_required()
          .only_in({"rod"}),
      number_key<S>("length", [](auto& s) -> auto& { return s.rod.length; }, positive("m"), "L")
          .is_required()
          .only_in({"rod"}),
      integer_key<S>("elements", [](auto& s) -> auto& { return s.rod.elements; }, 1, 100000,
                     "number of equal elements; DOF i is node i + 1")
          .is_required()
          .only_in({"rod"}),
      compound_key<S>("mass", kMatrixType, "—", "symmetric, positive definite on the DOFs with mass",
                      "M [kg]; rows of zeros are massless DOFs, condensed (below)")
          .only_in({"matrices"}),
      compound_key<S>("stiffness", kMatrixType, "—", "symmetric positive semidefinite, size of M (below)", "K [N/m]")
          .only_in({"matrices"}),
      compound_key<S>("damping", kMatrixType, "none", "symmetric, size of M", "C [N·s/m], added to `[damping]`")
          .only_in({"matrices"}),
      compound_key<S>("dofs", "list of names, or a file name", "`\"dof0\"`, `\"dof1\"`, …",
                      "one per row, unique, `[A-Za-z_][A-Za-z0-9_]*`",
                      "DOF names; they head CSV columns. A string is a file (relative to the scene) of one name per "
                      "line, `#`/`%` lines skipped: the `dofs.txt` of `wbm reduce`")
          .only_in({"matrices"}),
  };
  return keys;
}

const std::vector<DeclaredKey<DeckStructure>>& deck_keys() {
  using D = DeckStructure;
  static const std::vector<DeclaredKey<D>> keys = {
      compound_key<D>("deck", "string", "—", "a file, relative to the scene",
                      "a CalculiX/Abaqus deck (.inp), assembled by `ccx` and reduced by Craig–Bampton (\"Reducing a "
                      "finite-element model once\", above)",
                      [](const D& d) { return nlohmann::json(d.file); })
          .only_in({"deck"}),
      compound_key<D>("interface", "string or list of integers", "—", "a node set of the deck, or node numbers",
                      "the contact interface: its nodes' x, y, z are kept",
                      [](const D& d) { return nlohmann::json(d.interface); })
          .only_in({"deck"}),
      integer_key<D>("modes", [](auto& d) -> auto& { return d.modes; }, 0, 100000,
                     "fixed-interface normal modes kept")
          .only_in({"deck"}),
      text_key<D>("ccx", [](auto& d) -> auto& { return d.ccx; }, "the CalculiX executable").only_in({"deck"}),
      choice_key<D>("units", deck_unit_names(), [](const D& d) { return d.units; },
                    [](D& d, const std::string& v) { d.units = v; },
                    "the deck's consistent unit system, converted to SI")
          .only_in({"deck"}),
      compound_key<D>("axis", "`{ point, direction }`", "none", "two lists of three finite numbers [m]; direction ≠ 0",
                      "the rotation axis, for `[[contact]] direction = \"radial\"`",
                      [](const D& d) {
                        if (!d.axis) return nlohmann::json();
                        const auto& [p, n] = *d.axis;
                        return nlohmann::json{{"point", {p(0), p(1), p(2)}}, {"direction", {n(0), n(1), n(2)}}};
                      })
          .only_in({"deck"}),
  };
  return keys;
}

const std::vector<DeclaredKey<Forcing>>& forcing_keys() {
  using F = Forcing;
  static const std::vector<DeclaredKey<F>> keys = {
      number_key<F>("amplitude", [](auto& f) -> auto& { return f.amplitude; }, finite("N"), "F")
          .documented_default("— (`0` when `loads` or `vector` is given)")
          .read_by_section(),
      compound_key<F>("node", kLocation, "`\"tip\"`; with loads and no `amplitude`: the node of the largest load",
                      "see Locations", "rod only: the forced node (reported as \"forced\": branch amplitude, sweep "
                      "warnings)"),
      compound_key<F>("dof", kLocation, "1-DOF matrices: `0`; with loads and no `amplitude`: the DOF of the largest load",
                      "see Locations", "matrices only: the forced DOF (as `node`)"),
      compound_key<F>("loads", "`[[forcing.loads]]` tables", "none", "each as below",
                      "further loads F cos(2π h f t + φ)"),
      compound_key<F>("vector", "string", "none", "a Matrix Market file (coordinate, n × 1, relative to the scene)",
                      "the amplitude [N] of F_i cos(2π f t) on every DOF i (nonzero entries become loads; the resolved "
                      "scene lists them as `loads`)"),
      compound_key<F>("frequency_hz", "number or `[from, to]`", "—", "> 0",
                      "f [Hz]; a two-number list is a sweep (solve) or the continuation range (required there, except "
                      "in a branch in μ: one number)"),
      compound_key<F>("frequency_rad_s", "number or `[from, to]`", "—", "> 0",
                      "the same in rad/s (ω = 2πf), instead of `frequency_hz`; results and the resolved scene are in Hz"),
      compound_key<F>("frequencies_hz", "list of ≥ 2 numbers", "—", "> 0",
                      "solve only: a sweep at exactly these frequencies [Hz], in the order given (each solve starts "
                      "from the previous one), instead of an equispaced range"),
      compound_key<F>("frequencies_rad_s", "list of ≥ 2 numbers", "—", "> 0",
                      "the same in rad/s"),
      compound_key<F>("points", "integer", "`51`", "2 … 100000",
                      "sweep over a range (solve) only: equispaced frequencies, both ends included; continuation "
                      "picks its own points"),
  };
  return keys;
}

const std::vector<DeclaredKey<solvers::HarmonicLoad>>& load_keys() {
  using L = solvers::HarmonicLoad;
  static const std::vector<DeclaredKey<L>> keys = {
      number_key<L>("amplitude", [](auto& l) -> auto& { return l.amplitude; }, finite("N"), "F_j").is_required(),
      compound_key<L>("node", kLocation, "rod: `\"tip\"`", "see Locations", "rod only: the loaded node"),
      compound_key<L>("dof", kLocation, "1-DOF matrices: `0`", "see Locations", "matrices only: the loaded DOF"),
      compound_key<L>("phase_deg", "number", "`0`", "finite [deg]", "φ_j in degrees, instead of `phase_rad`"),
      number_key<L>("phase_rad", [](auto& l) -> auto& { return l.phase_rad; }, finite("rad"), "φ_j [rad]"),
      integer_key<L>("harmonic", [](auto& l) -> auto& { return l.harmonic; }, 0, 1000,
                     "h_j: the load acts at h_j f (0: a constant load F_j cos φ_j, e.g. a preload). 2h < M, the basis "
                     "dimension, or 2h < `output.samples` for `timestep`: a higher harmonic would be aliased and is "
                     "refused")
          .with_hint(" (0: a constant load F cos(phase), h: h times the forcing frequency)"),
  };
  return keys;
}

const std::vector<DeclaredKey<Contact>>& contact_keys() {
  using C = Contact;
  static const std::vector<DeclaredKey<C>> keys = {
      choice_key<C>("law", names(law_table()), [](const C& c) { return to_string(c.law); },
                    [](C& c, const std::string& v) { c.law = value_of(law_table(), v); },
                    "exponential penalty [JL14 Eq. (5)], linear penalty f = k max(u − g0, 0), a rigid stop with "
                    "exact contact (Signorini conditions; solve, sweep, continuation, timestep and "
                    "nnm; all contacts of a forced response rigid or none), or a Jenkins element: dry friction along "
                    "the contact's direction, a spring k_t in series with a Coulomb slider of slip force μN (solve, "
                    "sweep, continuation in frequency or in μ, with stability; Midpoint quadrature; timestep by central "
                    "differences), "
                    "or exact Coulomb friction along it "
                    "(\"coulomb\": the k_t → ∞ limit, its force a multiplier at the collocation instants as a rigid "
                    "stop's, first order in 1/M; solve, sweep, continuation without stability; timestep by Moreau–Jean "
                    "with Siconos; all contacts of the forced response \"rigid\" or \"coulomb\", or none)")
          .is_required()
          .read_by_section(),
      number_key<C>("gap", [](auto& c) -> auto& { return c.gap; }, finite("m"), "g0 [m]; < 0 is a prestress")
          .is_required()
          .documented_allowed("finite; > 0 for nnm")
          .only_in({"exponential", "linear", "rigid"})
          .read_by_section(),
      number_key<C>("coefficient", [](auto& c) -> auto& { return c.coefficient; }, positive("N"), "a_c [N]")
          .is_required()
          .only_in({"exponential"}),
      number_key<C>("exponent", [](auto& c) -> auto& { return c.exponent; }, positive("1/m"), "α [1/m]")
          .is_required()
          .only_in({"exponential"}),
      number_key<C>("stiffness", [](auto& c) -> auto& { return c.stiffness; }, positive("N/m"), "k [N/m]")
          .is_required()
          .only_in({"linear"}),
      number_key<C>("tangential_stiffness", [](auto& c) -> auto& { return c.tangential_stiffness; }, positive("N/m"),
                    "k_t [N/m], the stiffness while the contact sticks")
          .is_required()
          .only_in({"jenkins"}),
      number_key<C>("friction_coefficient", [](auto& c) -> auto& { return c.friction_coefficient; }, non_negative(""),
                    "μ [-]")
          .is_required()
          .only_in({"jenkins", "coulomb"}),
      number_key<C>("normal_load", [](auto& c) -> auto& { return c.normal_load; }, non_negative("N"),
                    "N [N], a constant normal preload: the slip force is μN (with `normal_contact`, μ (N + n), n the "
                    "normal contact's force)")
          .documented_default("required; 0 with `normal_contact`")
          .only_in({"jenkins", "coulomb"})
          .read_by_section(),
      compound_key<C>("normal_contact", "integer", "none (a constant normal load)",
                      "the index (0-based, in file order) of another `[[contact]]` located by `node` or `dof`: "
                      "`\"linear\"` or `\"exponential\"` for jenkins; `\"rigid\"` for coulomb (at most one coulomb "
                      "per rigid contact)",
                      "a normal load that varies with the normal gap: the slip force at each instant is μ (N + n), n "
                      "the force of that normal contact (its `gap` < 0 is a preload; n = 0 where it opens, and the "
                      "element then slides freely). For coulomb the normal contact's reaction is the normal load "
                      "(a 2D contact: the stop's multiplier of each instant in the weighted residual, its impulse "
                      "with Siconos' fc2d in time stepping): N must be 0, and a static load presses the normal DOF",
                      [](const C& c) { return c.normal_contact >= 0 ? nlohmann::json(c.normal_contact) : nlohmann::json(); })
          .only_in({"jenkins", "coulomb"}),
      compound_key<C>("second_tangent", kLocation, "none (one tangent)",
                      "a node (rod) or DOF (matrices) other than the contact's own; not beside `against`, `direction`, "
                      "`nodes`; not in a continuation with `stability = true` or `parameter = \"friction_coefficient\"`",
                      "a Jenkins element with two tangents, +e_dof and +e_second_tangent: its slider moves in their "
                      "plane and slips where \\|f\\| reaches μ (N + n) (an isotropic disc [MY98]). The force along each "
                      "tangent depends on both displacements; the counter-surface, if any, moves along the first",
                      [](const C& c) { return c.second_tangent >= 0 ? nlohmann::json(c.second_tangent) : nlohmann::json(); })
          .only_in({"jenkins"}),
      compound_key<C>("counter_surface", "string", "none (a fixed obstacle)", "the `name` of a `[[counter_surface]]`",
                      "the counter-surface this contact acts against moves: the law sees u_c − s(τ) (below)"),
      compound_key<C>("node", kLocation, "`\"tip\"`", "see Locations", "rod only: the contact node"),
      compound_key<C>("dof", kLocation, "1-DOF matrices: `0`", "see Locations", "matrices only: the contact DOF"),
      compound_key<C>("nodes", "node set name or list of node numbers", "none",
                      "deck structures only; interface nodes; needs `direction = \"radial\"` (with `structure.axis`) or "
                      "`[x, y, z]`; not beside `node`, `dof`, `against`",
                      "one contact per node along its normal (above)"),
      compound_key<C>("against", kLocation, "none (a fixed obstacle)",
                      "a node (rod) or DOF (matrices) other than the contact's own",
                      "the other body's DOF of a relative contact"),
      compound_key<C>("direction", "`+1`, `-1`, a table, `\"radial\"` or `[x, y, z]`", "`+1`",
                      "±1; or `{ name = weight, … }` over DOF names (matrices), including the contact's own DOF, not "
                      "all zero, not beside `against`; `\"radial\"` or `[x, y, z]` with `nodes`",
                      "the side of the stop along the DOF (`-1`: a stop on the −x side, the gap closes as u decreases), "
                      "or a direction n over several DOFs, g = g0 − n·u (e.g. a unit normal over a node's x, y, z; a "
                      "warning when \\|n\\| ≠ 1). For nnm, the energy is normalized by the stop that touches first in "
                      "the linear mode"),
  };
  return keys;
}

const std::vector<DeclaredKey<CounterSurface>>& counter_surface_keys() {
  using S = CounterSurface;
  const auto list = [](const std::vector<double>& v) { return v.empty() ? nlohmann::json() : nlohmann::json(v); };
  static const std::vector<DeclaredKey<S>> keys = {
      text_key<S>("name", [](auto& s) -> auto& { return s.name; },
                  "what a `[[contact]]` gives as `counter_surface`; unique")
          .is_required()
          .read_by_section(),
      choice_key<S>("type", {"fourier", "oval_casing"}, [](const S& s) { return s.type; },
                    [](S& s, const std::string& v) { s.type = v; },
                    "`fourier`: s(τ) = d τ + Σ_h (a_h cos 2πhτ + b_h sin 2πhτ) along each contact's direction, "
                    "τ = f t; `oval_casing`: a casing of radius R + δ cos nθ around a blade tip turning at "
                    "Ω = 2πf/n (below)")
          .documented_default("`\"fourier\"`")
          .read_by_section(),
      compound_key<S>("cosine", "list of numbers", "none", "finite [m]; entry h − 1 is harmonic h; 2h < M",
                      "a_h [m]", [list](const S& s) { return list(s.cosine); })
          .only_in({"fourier"}),
      compound_key<S>("sine", "list of numbers", "none", "finite [m]; as `cosine`", "b_h [m]",
                      [list](const S& s) { return list(s.sine); })
          .only_in({"fourier"}),
      number_key<S>("drift", [](auto& s) -> auto& { return s.drift; }, finite("m"),
                    "d [m per period]: the counter-surface sliding by; friction contacts only (a normal gap would "
                    "grow every period)")
          .only_in({"fourier"}),
      number_key<S>("ovalization", [](auto& s) -> auto& { return s.ovalization; }, non_negative("m"),
                    "δ [m]: the radius's variation; a normal contact's gap is g0 + δ cos(2πτ + φ)")
          .is_required()
          .only_in({"oval_casing"}),
      integer_key<S>("lobes", [](auto& s) -> auto& { return s.lobes; }, 1, 1000,
                     "n: lobes per turn; the response's period is one lobe passing, f = nΩ/(2π)")
          .only_in({"oval_casing"}),
      number_key<S>("radius", [](auto& s) -> auto& { return s.radius; }, positive("m"),
                    "R [m]: a friction contact (its direction along the rotation) sees the casing slide back by "
                    "2πR/n per period")
          .is_required()
          .only_in({"oval_casing"}),
      number_key<S>("phase_deg", [](auto& s) -> auto& { return s.phase_deg; }, finite("deg"),
                    "φ: the lobe's phase at τ = 0, s(τ) = δ cos(2πτ + φ) on a normal contact")
          .only_in({"oval_casing"}),
  };
  return keys;
}

const std::vector<DeclaredKey<Basis>>& basis_keys() {
  using B = Basis;
  static const std::vector<DeclaredKey<B>> keys = {
      text_key<B>("trial", [](auto& b) -> auto& { return b.trial; }, "trial basis (the basis drawn by basis-plot)")
          .documented_allowed("`fourier`, `haar`, `db4` … `db20` (even), `bspline`")
          .read_by_section(),
      text_key<B>("weighting", [](auto& b) -> auto& { return b.weighting; }, "weighting basis (solve)")
          .documented_default("= `trial`")
          .documented_allowed("as `trial`")
          .read_by_section(),
      integer_key<B>("dimension", [](auto& b) -> auto& { return b.dimension; }, 1, 1 << 20, "M, functions per DOF")
          .documented_default("`64` (Fourier:Fourier: see `harmonics`)")
          .documented_allowed("power of two, 1 … 2²⁰ (Fourier ≥ 2)")
          .read_by_section(),
      compound_key<B>("level", "integer", "none", "0 … 20", "alternatively J, M = 2^J"),
      integer_key<B>("harmonics", [](auto& b) -> auto& { return b.harmonics; }, 1, 1 << 19,
                     "H: harmonic balance as usually written, harmonics 0 … H, M = 2H + 1 functions")
          .documented_default("`32` for Fourier:Fourier when none of `dimension`, `level`, `harmonics` is given")
          .documented_allowed("1 … 2¹⁹; Fourier:Fourier only")
          .read_by_section(),
      choice_key<B>("formulation", {"strong", "weak", "distributional"},
                    [](const B& b) { return solvers::to_string(b.formulation); },
                    [](B& b, const std::string& v) { b.formulation = solvers::parse_formulation(v); },
                    "where the time derivatives sit [JL14 Eqs. (14)–(16)]"),
      integer_key<B>("time_samples", [](auto& b) -> auto& { return b.time_samples; }, 0, 1 << 24,
                     "Q, samples of the contact forces and discrete inner products; 0 = max(256, 2M)")
          .documented_allowed("0, or M … 2²⁴")
          .with_hint(" (0: max(256, 2M))"),
      choice_key<B>("operators", {"automatic", "discrete"},
                    [](const B& b) { return b.operators == solvers::OperatorRule::Discrete ? "discrete" : "automatic"; },
                    [](B& b, const std::string& v) {
                      b.operators = v == "discrete" ? solvers::OperatorRule::Discrete : solvers::OperatorRule::Automatic;
                    },
                    "exact linear operators where known (Fourier, Galerkin wavelets by connection coefficients), or "
                    "the paper's Q-point rule for all"),
      choice_key<B>("contact_quadrature", {"automatic", "midpoint", "cell-average"},
                    [](const B& b) { return solvers::to_string(b.contact_quadrature); }, [](B&, const std::string&) {},
                    "how the contact law is sampled on the Q cells: `midpoint`, f_c(u(τ_q)) as the paper does; "
                    "`cell-average`, the law integrated exactly over each cell along the tangent of u, (P(u + δ/2) − "
                    "P(u − δ/2))/δ with δ = u̇(τ_q)/Q (C¹ in the unknowns, so a branch meets a stiff stop smoothly; "
                    "needs a trial basis with a slope, not Haar); `automatic`, cell-average for `harmonics = H` (and "
                    "with no `[basis]` table) and for a `\"linear\"` law (its corner at the gap) on a trial with a "
                    "slope whatever M, midpoint otherwise (the smooth exponential law of the paper with M = 2^J, "
                    "rigid stops, Haar, and any scene with a `\"jenkins\"` contact, whose force has no f(u) to "
                    "average). result.json echoes the resolved rule")
          .documented_default("`\"automatic\"`")
          .read_by_section(),
      compound_key<B>("harmonic_selection", "string or list", "`\"all\"`",
                      "`\"all\"`, `\"odd\"` (1, 3, 5, …), or a list of harmonic numbers in [0, H] (H = `harmonics`, or "
                      "M/2 for `dimension = M`); Fourier:Fourier with penalty laws only; every load's harmonic must be "
                      "kept",
                      "the harmonics kept in the trial and weighting spaces (below)"),
  };
  return keys;
}

}  // namespace wbm::scene::detail
