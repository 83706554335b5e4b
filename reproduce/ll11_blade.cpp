// Laxalde & Legrand 2011, Figs. 6–8 (Sec. 5.2): a compressor blade in radial frictionless
// contact with a rigid casing at a uniform gap, reduced by Craig–Bampton to 72 constraint modes
// (24 tip nodes × 3 translations) + 40 fixed-interface modes, and its first nonlinear mode.
// The paper's blade is not public: reproduce/blade/blade.geo is a representative one (README.md
// there). Pipeline, all from a fresh clone: gmsh meshes blade.geo (quadratic tetrahedra),
// CalculiX assembles K and M from blade.inp (Ti-6Al-4V, clamped root), Craig–Bampton (one CHOLMOD
// Cholesky, Spectra's Lanczos), the full model's first 10 frequencies by Spectra on the full
// sparse matrices (Craig–Bampton with no interface), and the backbone by pseudo-arclength
// continuation of the KKT conditions with 24 stops along the radial directions (exact contact).
// Writes out/ll11_blade/: frequencies.csv, craig_bampton_convergence.csv, backbone.csv,
// contact_nodes.csv, mesh_nodes.csv, tip_E<e>.csv and deformed_E<e>.csv (e = 0.8, 4.7, 10.4),
// timings in meta.json, report.md. Two branches: 0 from the linear mode (which leaves mode 1
// through internal-resonance tongues), 1 the first bending mode past them, started from the
// N = 3 level at E = 3.6 by the penalty homotopy; Fig. 8's levels above 3.6 come from branch 1.
// --quick: mesh size 5 mm (~12 000 DOFs), N = 3, m = 24, E ≤ 2, branch 0 only; run by ctest.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include <wbm/fem/calculix.hpp>
#include <wbm/fem/craig_bampton.hpp>
#include <wbm/fem/gmsh.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>

#include "blade.hpp"
#include "combinations.hpp"
#include "parameters.hpp"
#include "run.hpp"

namespace {

using namespace wbm;

}  // namespace

int main(int argc, char** argv) {
  auto run = reproduce::Run::from_args(argc, argv, "ll11_blade");
  return run.execute([](reproduce::Run& run) {
    using reproduce::format;
    const auto started = std::chrono::steady_clock::now();
    const bool quick = run.quick();
    // Every model and run parameter from reproduce/scenes/ll11_blade.toml (its [quick] values with --quick).
    const auto parameters = reproduce::Parameters::load("ll11_blade", quick);
    const double mesh_size = parameters.number("mesh.size_m");  // m, the largest element edge
    const double hub_radius = models::kHubRadius;               // m, engine axis ∥ x at z = −0.25 (blade.geo)
    const double gap = parameters.number("contact.gap_m");      // m, uniform radial gap (results are per gap)
    const int n_tip = parameters.integer("interface.tip_nodes"), modes = parameters.integer("interface.modes");
    const int reference_modes = parameters.integer("interface.reference_modes");
    const int harmonics = parameters.integer("nnm.harmonics"), samples = parameters.integer("nnm.samples");
    const double energy_max = parameters.number("nnm.energy_max");
    const std::vector<double> shown = parameters.numbers("nnm.levels");
    const models::ScratchFolder scratch("wbm_ll11_blade");
    nlohmann::json timing;

    // 1–2. Mesh (gmsh), root node set, model deck, K and M (CalculiX), the 24 tip nodes from the
    // leading to the trailing edge (models/blade.hpp).
    const auto blade = models::build_blade(scratch.dir, mesh_size, n_tip);
    timing["gmsh_s"] = blade.gmsh_s;
    timing["ccx_and_read_s"] = blade.ccx_s;
    const auto& deck = blade.deck;
    const auto& model = blade.model;
    const auto& boundary = blade.boundary;
    const auto& tip_nodes = blade.tip_nodes;
    const Eigen::VectorXd& chord = blade.chord;
    const int written = blade.nodes_written;
    const auto n_full = static_cast<Eigen::Index>(model.dofs.size());
    const int c3d10 = deck.element_types.count("C3D10") != 0 ? deck.element_types.at("C3D10") : 0;
    auto t = std::chrono::steady_clock::now();

    // 3. Craig–Bampton (72 + 40), and the full model's first 10 frequencies (Spectra, no interface).
    t = std::chrono::steady_clock::now();
    const auto cb = fem::craig_bampton(model.stiffness, model.mass, boundary, modes);
    timing["craig_bampton_s"] = models::seconds_since(t);
    timing["cholesky_s"] = cb.factorization_s;
    timing["constraint_modes_s"] = cb.constraint_modes_s;
    timing["lanczos_s"] = cb.eigensolve_s;

    // 4. The reduced system and its 24 radial stops (g = g0 − n·u, n from the engine axis).
    solvers::MechanicalSystem reduced;
    reduced.stiffness = (0.5 * (cb.stiffness + cb.stiffness.transpose())).sparseView();
    reduced.mass = (0.5 * (cb.mass + cb.mass.transpose())).sparseView();
    reduced.damping.resize(reduced.mass.rows(), reduced.mass.cols());
    const auto stops = models::radial_stops(blade, gap);
    solvers::BackboneContinuationOptions co;
    co.energy_min = parameters.number("nnm.energy_min");
    co.energy_max = energy_max;
    co.max_energy_step = parameters.number("nnm.max_energy_step");
    co.include = shown;

    // 5. The first bending mode past the tongues (not in --quick). The branch from the linear mode
    // (branch 0) leaves mode 1 through internal-resonance tongues (claim (e) below). With N = 3
    // there is no 4th harmonic, hence no 4:1 tongue, and the N = 3 branch from the linear mode stays
    // on mode 1: its level at E = start_energy starts an N = 8 branch by the penalty homotopy
    // (BackboneContinuationOptions::start_penalty_stiffness, k0 = homotopy_factor × the radial
    // static stiffness 1/(nᵀK⁻¹n) at the onset node), continued up to energy_max (`up`) and down
    // until it turns back and leaves the start's energy again (`down`): branch 1 in backbone.csv.
    // It runs on a second thread while the reference frequencies and branch 0 are computed.
    const double start_energy = parameters.number("first_mode_branch.start_energy");
    const double homotopy_factor = parameters.number("first_mode_branch.homotopy_factor");
    const int start_harmonics = parameters.integer("first_mode_branch.start_harmonics");
    if (start_harmonics < 1 || start_harmonics >= 4) {
      throw std::invalid_argument(parameters.file() + ": first_mode_branch.start_harmonics = " +
                                  std::to_string(start_harmonics) + ": expected 1 … 3 (the start must have no 4th "
                                  "harmonic, hence no 4:1 tongue); use 3");
    }
    struct FirstModeBranch {
      std::optional<solvers::Backbone> up, down;
      double k_radial = std::nan(""), coarse_share = std::nan(""), seconds = 0.0;
      std::vector<std::string> errors;
    };
    std::future<FirstModeBranch> first_mode_task;
    if (!quick) {
      first_mode_task = std::async(std::launch::async, [&]() {
        FirstModeBranch r;
        const auto t0 = std::chrono::steady_clock::now();
        const solvers::NonlinearModes coarse(reduced, stops, {.harmonics = start_harmonics, .samples = samples});
        const solvers::NonlinearModes fine(reduced, stops, {.harmonics = harmonics, .samples = samples});
        solvers::BackboneContinuationOptions cc = co;
        cc.energy_max = start_energy + 0.1;
        cc.include = {start_energy};
        const auto bc = coarse.continue_backbone(cc);
        if (bc.included.empty() || !bc.included[0].converged()) {
          r.errors.push_back("the N = " + std::to_string(start_harmonics) + " level at E = " + format("%g", start_energy) + " did not converge: " + bc.message);
        } else {
          r.coarse_share = coarse.modal_components(bc.included[0]).first_mode_share;
          Eigen::VectorXd n_onset = Eigen::VectorXd::Zero(reduced.stiffness.rows());
          for (const auto& [dof, weight] : stops[static_cast<size_t>(fine.onset_stop())].terms()) n_onset(dof) = weight;
          r.k_radial = 1.0 / n_onset.dot(Eigen::MatrixXd(reduced.stiffness).ldlt().solve(n_onset));
          solvers::BackboneContinuationOptions fo = co;
          fo.start = solvers::PeriodicOrbit{bc.included[0].coefficients, bc.included[0].frequency_hz};
          fo.start_penalty_stiffness = homotopy_factor * r.k_radial;
          fo.include.clear();
          for (double level : shown) {
            if (level > start_energy) fo.include.push_back(level);
          }
          r.up = fine.continue_backbone(fo);
          fo.direction = -1;
          fo.include.clear();
          fo.energy_max = start_energy + 0.05;
          r.down = fine.continue_backbone(fo);
          if (!r.up->complete()) r.errors.push_back("first-mode branch (up) incomplete: " + r.up->message);
          if (!r.down->complete()) r.errors.push_back("first-mode branch (down) incomplete: " + r.down->message);
        }
        r.seconds = models::seconds_since(t0);
        return r;
      });
    }

    t = std::chrono::steady_clock::now();
    const auto full = fem::craig_bampton(model.stiffness, model.mass, {}, reference_modes);
    timing["full_model_modes_s"] = models::seconds_since(t);
    const Eigen::VectorXd f_full = full.normal_frequencies_hz;
    // A second, independent reference: CalculiX's own eigensolver on the same deck (*FREQUENCY).
    t = std::chrono::steady_clock::now();
    const std::vector<double> ccx_hz = fem::calculix_frequencies(deck, reference_modes);
    timing["ccx_frequencies_s"] = models::seconds_since(t);
    const Eigen::VectorXd f_ccx = Eigen::Map<const Eigen::VectorXd>(ccx_hz.data(), reference_modes);
    const Eigen::VectorXd ccx_error = ((f_full - f_ccx).array() / f_ccx.array()).matrix();  // Spectra vs ccx
    const auto nb = static_cast<Eigen::Index>(boundary.size());
    // Reduced frequencies with the first m fixed-interface modes: the leading (72 + m) block.
    auto reduced_hz = [&](int m) {
      const Eigen::Index r = nb + m;
      const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(cb.stiffness.topLeftCorner(r, r),
                                                                          cb.mass.topLeftCorner(r, r));
      return Eigen::VectorXd((eig.eigenvalues().head(reference_modes).array().sqrt() / (2.0 * std::numbers::pi)).matrix());
    };
    const Eigen::VectorXd f_cb = reduced_hz(modes);
    const Eigen::VectorXd f_error = ((f_cb - f_full).array() / f_full.array()).matrix();
    run.table("frequencies.csv", {"mode [-]", "full_model [Hz]", "craig_bampton_72_plus_40 [Hz]", "relative_error [-]",
                                  "ccx_frequency_step [Hz]", "full_model_vs_ccx [-]"},
              {Eigen::VectorXd::LinSpaced(reference_modes, 1, reference_modes), f_full, f_cb, f_error, f_ccx, ccx_error});
    const std::vector<int> convergence_modes = {5, 10, 20, 40};
    Eigen::VectorXd cm(4), worst5(4), worst10(4);
    for (int k = 0; k < 4; ++k) {
      const Eigen::VectorXd e = ((reduced_hz(convergence_modes[k]) - f_full).array() / f_full.array()).matrix();
      cm(k) = convergence_modes[k];
      worst5(k) = e.head(5).cwiseAbs().maxCoeff();
      worst10(k) = e.cwiseAbs().maxCoeff();
    }
    run.table("craig_bampton_convergence.csv", {"normal_modes [-]", "worst_error_modes_1_5 [-]", "worst_error_modes_1_10 [-]"},
              {cm, worst5, worst10});

    Eigen::VectorXd ny(n_tip), nz(n_tip);
    for (int i = 0; i < n_tip; ++i) {
      ny(i) = stops[static_cast<size_t>(i)].along[0].second;
      nz(i) = stops[static_cast<size_t>(i)].along[1].second;
    }
    const Eigen::VectorXd px = blade.position.col(0), py = blade.position.col(1), pz = blade.position.col(2);
    t = std::chrono::steady_clock::now();
    const solvers::NonlinearModes nnm(reduced, stops, {.harmonics = harmonics, .samples = samples});
    const auto b = nnm.continue_backbone(co);
    timing["backbone_s"] = models::seconds_since(t);
    if (!b.complete()) run.fail("backbone incomplete: " + b.message);
    const double f1 = nnm.linear_frequency_hz();

    // Branch 1, traced on the second core meanwhile.
    std::optional<solvers::Backbone> up, down;
    double k_radial = std::nan(""), coarse_share = std::nan("");
    if (first_mode_task.valid()) {
      FirstModeBranch r = first_mode_task.get();
      timing["first_mode_branch_s"] = r.seconds;
      for (const auto& why : r.errors) run.fail(why);
      up = std::move(r.up);
      down = std::move(r.down);
      k_radial = r.k_radial;
      coarse_share = r.coarse_share;
    }
    // Branch 1 in order along the curve: down (reversed, without its start) then up.
    std::vector<const solvers::ModeLevel*> branch1;
    if (up && down) {
      // (an index loop: rbegin() + 1 of an empty vector lies past rend(), and a failed branch has
      // no levels; it read garbage and ended in std::bad_alloc)
      for (size_t k = down->levels.size(); k > 1; --k) branch1.push_back(&down->levels[k - 1]);
      for (const auto& l : up->levels) branch1.push_back(&l);
    }

    // Backbone table, one row per level, for both branches: E, f/f1, f, worst penetration,
    // complementarity, largest contact force, tip nodes in contact, and modal_components.
    auto columns = [&](const std::vector<const solvers::ModeLevel*>& branch) {
      const auto n = static_cast<Eigen::Index>(branch.size());
      std::vector<Eigen::VectorXd> cols(11, Eigen::VectorXd(n));
      for (Eigen::Index k = 0; k < n; ++k) {
        const auto& l = *branch[static_cast<size_t>(k)];
        const auto mc = nnm.modal_components(l);
        int count = 0;
        for (Eigen::Index c = 0; c < n_tip; ++c) count += l.contact_force.segment(c * samples, samples).maxCoeff() > 0.0 ? 1 : 0;
        const double values[] = {l.energy, l.frequency_hz / f1, l.frequency_hz, l.max_penetration, l.complementarity,
                                 l.contact_force.size() > 0 ? l.contact_force.maxCoeff() : 0.0, static_cast<double>(count),
                                 mc.first_mode_share, static_cast<double>(mc.mode), static_cast<double>(mc.harmonic), mc.share};
        for (size_t i = 0; i < 11; ++i) cols[i](k) = values[i];
      }
      return cols;
    };
    std::vector<const solvers::ModeLevel*> branch0;
    for (const auto& l : b.levels) branch0.push_back(&l);
    const std::vector<Eigen::VectorXd> cols0 = columns(branch0), cols1 = columns(branch1);
    const auto nl = static_cast<Eigen::Index>(branch0.size()), n1 = static_cast<Eigen::Index>(branch1.size());
    const Eigen::VectorXd &e = cols0[0], &ratio = cols0[1], &fhz = cols0[2], &pen = cols0[3], &comp = cols0[4];
    const Eigen::VectorXd &first_share = cols0[7], &other_mode = cols0[8], &other_harmonic = cols0[9],
                          &other_share = cols0[10];
    // Per tip node, the first energy of branch 0 where it carries a contact force.
    Eigen::VectorXd first_contact = Eigen::VectorXd::Constant(n_tip, std::nan(""));
    for (const auto& l : b.levels) {
      for (Eigen::Index c = 0; c < n_tip; ++c) {
        if (std::isnan(first_contact(c)) && l.contact_force.segment(c * samples, samples).maxCoeff() > 0.0) {
          first_contact(c) = l.energy;
        }
      }
    }
    {
      std::vector<Eigen::VectorXd> both;
      both.emplace_back((Eigen::VectorXd(nl + n1) << Eigen::VectorXd::Zero(nl), Eigen::VectorXd::Ones(n1)).finished());
      for (size_t i = 0; i < 11; ++i) both.emplace_back((Eigen::VectorXd(nl + n1) << cols0[i], cols1[i]).finished());
      run.table("backbone.csv", {"branch [-]", "energy [-]", "frequency_over_f1 [-]", "frequency [Hz]",
                                 "max_penetration [gap]", "complementarity [gap]", "max_contact_force [N]",
                                 "nodes_in_contact [-]", "first_mode_share [-]", "other_mode [-]", "other_harmonic [-]",
                                 "other_share [-]"},
                both);
    }
    std::vector<std::string> contact_status;
    for (Eigen::Index c = 0; c < n_tip; ++c) contact_status.push_back(std::isnan(first_contact(c)) ? "never in contact" : "");
    run.table("contact_nodes.csv", {"index [-]", "node [-]", "chord_fraction [-]", "x [m]", "y [m]", "z [m]", "n_y [-]",
                                    "n_z [-]", "first_contact_energy [-]"},
              {Eigen::VectorXd::LinSpaced(n_tip, 1, n_tip), Eigen::Map<const Eigen::VectorXi>(tip_nodes.data(), n_tip).cast<double>(),
               chord, px, py, pz, ny, nz, first_contact},
              contact_status);
    {
      Eigen::VectorXd id(static_cast<Eigen::Index>(deck.nodes.size())), x(id.size()), y(id.size()), z(id.size());
      Eigen::Index k = 0;
      for (const auto& [node, c] : deck.nodes) {
        id(k) = node;
        x(k) = c(0);
        y(k) = c(1);
        z(k) = c(2);
        ++k;
      }
      run.table("mesh_nodes.csv", {"node [-]", "x [m]", "y [m]", "z [m]"}, {id, x, y, z});
    }

    // The levels of Fig. 8: tip radial displacement over the period and the deformed blade at
    // t = 0 and T/2 (every node, u/g0; root nodes are clamped and absent from the model's DOFs).
    std::ostringstream level_rows;
    double trailing_max = std::nan("");  // max over the period of the trailing-edge node's u_c/g0, last level shown
    nlohmann::json levels = nlohmann::json::array();
    // Fig. 8's levels: from branch 1 (the first bending mode) where it was traced, else from branch 0.
    std::vector<std::pair<const solvers::ModeLevel*, int>> figure_levels;
    for (const auto& l : b.included) {
      const solvers::ModeLevel* from_up = nullptr;
      if (up) {
        for (const auto& u : up->included) {
          if (u.energy == l.energy && u.converged()) from_up = &u;
        }
      }
      figure_levels.emplace_back(from_up != nullptr ? from_up : &l, from_up != nullptr ? 1 : 0);
    }
    for (const auto& [level, branch_id] : figure_levels) {
      const solvers::ModeLevel& l = *level;
      const std::string tag = format("%g", l.energy);
      if (!l.converged()) {
        run.fail("level E = " + tag + " did not converge: " + l.message);
        continue;
      }
      const int p_samples = parameters.integer("nnm.output_samples");
      const Eigen::MatrixXd q = nnm.displacement(l, p_samples);  // 112 × P
      Eigen::VectorXd u0(n_tip), uh(n_tip), umax(n_tip), force(n_tip);
      for (Eigen::Index c = 0; c < n_tip; ++c) {
        const Eigen::RowVectorXd uc = ny(c) * q.row(3 * c + 1) + nz(c) * q.row(3 * c + 2);
        u0(c) = uc(0) / gap;
        uh(c) = uc(p_samples / 2) / gap;
        umax(c) = uc.maxCoeff() / gap;
        force(c) = l.contact_force.segment(c * samples, samples).maxCoeff();
      }
      run.table("tip_E" + tag + ".csv", {"chord_fraction [-]", "radial_t0 [gap]", "radial_half_period [gap]",
                                         "radial_max [gap]", "max_contact_force [N]"},
                {chord, u0, uh, umax, force});
      Eigen::MatrixXd two(q.rows(), 2);
      two << q.col(0), q.col(p_samples / 2);
      const Eigen::MatrixXd u = cb.expand(two) / gap;  // n_full × 2
      std::map<int, Eigen::Matrix<double, 3, 2>> by_node;
      for (Eigen::Index r = 0; r < n_full; ++r) {
        const auto [node, d] = model.dofs[static_cast<size_t>(r)];
        auto it = by_node.try_emplace(node, Eigen::Matrix<double, 3, 2>::Zero()).first;
        it->second.row(d - 1) = u.row(r);
      }
      const auto nn = static_cast<Eigen::Index>(deck.nodes.size());
      std::vector<Eigen::VectorXd> cols(7, Eigen::VectorXd::Zero(nn));
      Eigen::Index k = 0;
      for (const auto& [node, c] : deck.nodes) {
        cols[0](k) = node;
        if (const auto it = by_node.find(node); it != by_node.end()) {
          for (int d = 0; d < 3; ++d) {
            cols[static_cast<size_t>(1 + d)](k) = it->second(d, 0);
            cols[static_cast<size_t>(4 + d)](k) = it->second(d, 1);
          }
        }
        ++k;
      }
      run.table("deformed_E" + tag + ".csv", {"node [-]", "ux_t0 [gap]", "uy_t0 [gap]", "uz_t0 [gap]", "ux_half_period [gap]",
                                              "uy_half_period [gap]", "uz_half_period [gap]"},
                cols);
      int in_contact = 0;
      for (Eigen::Index c = 0; c < n_tip; ++c) in_contact += force(c) > 0.0 ? 1 : 0;
      trailing_max = umax(n_tip - 1);
      const auto mc = nnm.modal_components(l);
      level_rows << "| " << tag << " | " << branch_id << " | " << format("%.5f", l.frequency_hz / f1) << " | " << format("%.2f", l.frequency_hz)
                 << " | " << in_contact << " | " << format("%.2f", umax.maxCoeff()) << " | "
                 << format("%.1e", l.max_penetration) << " | " << format("%.1e", l.complementarity) << " | "
                 << format("%.3f", mc.first_mode_share) << " | mode " << mc.mode << ", h = " << mc.harmonic << ": "
                 << format("%.3f", mc.share) << " |\n";
      levels.push_back({{"energy", l.energy}, {"branch", branch_id}, {"frequency_hz", l.frequency_hz}, {"frequency_over_f1", l.frequency_hz / f1},
                        {"nodes_in_contact", in_contact}, {"max_radial_over_gap", umax.maxCoeff()}});
    }

    // Claims, computed. (a) Craig–Bampton: the first 5 frequencies within 0.1 % with 40 modes
    // (issue #15). (b) Which nodes touch first: the paper says the leading and trailing edges
    // (LL11 Sec. 5.2); ours: the nodes with the smallest first-contact energy, at chord
    // fraction < 0.25 (leading edge) or > 0.75 (trailing edge). (c) The frequency rises with
    // energy above contact (Fig. 7: "an increase of the natural frequency").
    const bool cb_ok = worst5(3) <= 1e-3;
    const bool ccx_ok = ccx_error.cwiseAbs().maxCoeff() <= 1e-6;
    const double first_energy = first_contact.array().isNaN().all() ? std::nan("") : first_contact.minCoeff();
    std::string first_nodes;
    bool edges = std::isfinite(first_energy);
    for (Eigen::Index c = 0; c < n_tip; ++c) {
      if (!std::isnan(first_contact(c)) && first_contact(c) <= first_energy + 1e-12) {
        first_nodes += (first_nodes.empty() ? "" : ", ") + std::string("#") + std::to_string(c + 1) + " (chord " +
                       format("%.2f", chord(c)) + ")";
        edges = edges && (chord(c) < 0.25 || chord(c) > 0.75);
      }
    }
    // (d) The paper: "intermittent contacts occur at the leading and trailing edges": does the
    // trailing edge (chord fraction > 0.75) ever carry a contact force along the branch?
    bool leading = false, trailing = false;
    for (Eigen::Index c = 0; c < n_tip; ++c) {
      if (std::isnan(first_contact(c))) continue;
      leading = leading || chord(c) < 0.25;
      trailing = trailing || chord(c) > 0.75;
    }
    const int onset = nnm.onset_stop();
    const double worst_pen = pen.maxCoeff(), worst_comp = comp.maxCoeff();
    Eigen::Index peak = 0;
    ratio.maxCoeff(&peak);
    const bool hardening = ratio(nl - 1) > 1.0 + 1e-6 && ratio.minCoeff() >= 1.0 - 1e-8;  // 1e-8: the KKT tolerance's reach
    // (e) Is the branch the first mode's? The first level where mode 1 at the fundamental holds
    // less than half of m̂ (modal_energy_shares), and at the last level the largest other
    // component (mode j, harmonic h): an h:1 internal resonance if it holds more than half and
    // h f is within 1 % of f_j.
    Eigen::Index leaves = -1;
    for (Eigen::Index k = 0; k < nl && leaves < 0; ++k) {
      if (first_share(k) < 0.5) leaves = k;
    }
    const int end_mode = static_cast<int>(other_mode(nl - 1)), end_harmonic = static_cast<int>(other_harmonic(nl - 1));
    const double end_fj = nnm.linear_frequencies_hz()(end_mode - 1);
    const double end_detuning = end_harmonic * fhz(nl - 1) / end_fj - 1.0;
    const bool end_resonant = other_share(nl - 1) > 0.5 && std::abs(end_detuning) <= 1e-2;
    // Touch order along the chord: nodes sorted by first-contact energy, at most 8.
    std::vector<Eigen::Index> by_energy;
    for (Eigen::Index c = 0; c < n_tip; ++c) {
      if (!std::isnan(first_contact(c))) by_energy.push_back(c);
    }
    std::stable_sort(by_energy.begin(), by_energy.end(), [&](auto a, auto c) { return first_contact(a) < first_contact(c); });
    std::string sequence;
    for (size_t i = 0; i < std::min<size_t>(8, by_energy.size()); ++i) {
      sequence += (i ? ", " : "") + std::string("#") + std::to_string(by_energy[i] + 1) + " at E = " +
                  format("%.2f", first_contact(by_energy[i]));
    }

    // (f) Branch 1, the first bending mode past the tongues: is it mode 1's (share ≥ ½ along the
    // upward part)? does its frequency increase along it? where does it turn going down, and
    // what does it hold at Fig. 8's levels compared with branch 0?
    std::ostringstream first_mode_text;
    bool b1_first_mode = false, b1_hardening = false;
    std::vector<reproduce::Claim> b1_claims;  // branch 1's claims, listed with the others below
    if (up && down && !up->levels.empty() && !down->levels.empty()) {
      const auto& ul = up->levels;
      // The upward part is the tail of branch 1's columns.
      const auto nu = static_cast<Eigen::Index>(ul.size());
      const Eigen::VectorXd up_share = cols1[7].tail(nu), up_ratio = cols1[1].tail(nu);
      Eigen::Index weakest = 0;
      const double min_share = up_share.minCoeff(&weakest), min_share_energy = ul[static_cast<size_t>(weakest)].energy;
      b1_first_mode = min_share >= 0.5;
      b1_hardening = nu < 2 || ((up_ratio.tail(nu - 1) - up_ratio.head(nu - 1)).array() >= -1e-8).all();
      b1_claims.push_back({"Fig. 7 is the first nonlinear mode: on branch 1, mode 1 at h = 1 holds at least half of m̂ at "
                           "every level of the upward part",
                           b1_first_mode,
                           "minimum " + format("%.3f", min_share) + " at E = " + format("%.2f", min_share_energy)});
      b1_claims.push_back({"Fig. 7: on branch 1 the frequency increases along the upward part (no step lowers it by more "
                           "than 1e-8 f1)",
                           b1_hardening,
                           "f/f1 = " + format("%.5f", ul.front().frequency_hz / f1) + " at E = " +
                               format("%.2f", ul.front().energy) + " to " + format("%.5f", ul.back().frequency_hz / f1) +
                               " at E = " + format("%.2f", ul.back().energy)});
      const auto lowest = std::min_element(down->levels.begin(), down->levels.end(),
                                           [](const auto& a, const auto& c) { return a.energy < c.energy; });
      const auto down_end = nnm.modal_components(down->levels.back());
      const double pen1 = n1 > 0 ? cols1[3].maxCoeff() : std::nan(""), comp1 = n1 > 0 ? cols1[4].maxCoeff() : std::nan("");
      first_mode_text
          << "**Branch 1: the first bending mode past the tongues.** With N = " << start_harmonics
          << " there is no 4th harmonic and so no 4:1 tongue: the N = " << start_harmonics
          << " branch from the linear mode keeps mode 1 (it holds "
          << format("%.3f", coarse_share) << " of m̂ at E = " << format("%g", start_energy) << "). That level started an N = "
          << harmonics << " branch by the penalty homotopy (`BackboneContinuationOptions::start_penalty_stiffness`): k0 = "
          << format("%g", homotopy_factor) << " × the radial static stiffness of node #" << onset + 1 << " ("
          << format("%.3g", k_radial) << " N/m); Signorini converged from k = " << format("%.3g", up->homotopy_stiffness)
          << " N/m after " << up->homotopy_stages << " penalty orbits, at f/f1 = " << format("%.5f", ul.front().frequency_hz / f1)
          << " with mode 1 holding " << format("%.3f", up_share(0)) << ". Upward to E = "
          << format("%.2f", ul.back().energy) << ": " << ul.size() << " levels, " << up->folds.size() << " folds in E, "
          << up->kinks << " corners, " << up->rejected_steps << " rejected steps, "
          << format("%.1f", up->wall_time_s) << " s; worst penetration " << format("%.1e", pen1)
          << " g0, worst complementarity " << format("%.1e", comp1) << " g0 over branch 1.\n\n"
          << "Going down from E = " << format("%g", start_energy) << ", branch 1 turns back at E = "
          << format("%.3f", lowest->energy) << " (f/f1 = " << format("%.5f", lowest->frequency_hz / f1)
          << ") and leaves through the tongue of mode " << down_end.mode << " at harmonic " << down_end.harmonic
          << " (which holds " << format("%.3f", down_end.share) << " at E = " << format("%.2f", down->levels.back().energy)
          << "): traced this way it does not join branch 0. Fig. 8's levels above E = " << format("%g", start_energy)
          << " are taken from branch 1 (column `branch` of the table above).";
      for (const auto& u : up->included) {
        for (const auto& l0 : b.included) {
          if (l0.energy != u.energy || !u.converged() || !l0.converged()) continue;
          first_mode_text << " At E = " << format("%g", u.energy) << " mode 1 holds "
                          << format("%.3f", nnm.modal_components(u).first_mode_share) << " on branch 1 (f/f1 = "
                          << format("%.5f", u.frequency_hz / f1) << ") and " << format("%.3f", nnm.modal_components(l0).first_mode_share)
                          << " on branch 0 (f/f1 = " << format("%.5f", l0.frequency_hz / f1) << ").";
        }
      }
      first_mode_text << "\n\n";
    } else if (quick) {
      first_mode_text << "Branch 1 (the first bending mode past the tongues, started by the penalty homotopy) is not "
                         "traced with --quick.\n\n";
    } else {
      first_mode_text << "Branch 1 (the first bending mode past the tongues) could not be traced: "
                      << (up ? up->message : "the N = " + std::to_string(start_harmonics) + " start did not converge")
                      << ".\n\n";
    }

    const double total = models::seconds_since(started);  // wall time: branch 1 overlaps the references and branch 0
    run.meta({{"figure", "LL11 Figs. 6-8"}, {"parameters", parameters.used()}, {"mesh_size_m", mesh_size}, {"nodes", written}, {"c3d10_elements", c3d10},
              {"dofs", n_full}, {"interface_dofs", nb}, {"normal_modes", modes}, {"harmonics", harmonics},
              {"samples", samples}, {"gap_m", gap}, {"hub_radius_m", hub_radius}, {"linear_frequency_hz", f1},
              {"full_first_frequency_hz", f_full(0)}, {"ccx_first_frequency_hz", f_ccx(0)},
              {"full_model_vs_ccx_max_relative", ccx_error.cwiseAbs().maxCoeff()}, {"timing_s", timing}, {"pipeline_s", total},
              {"backbone_levels", nl}, {"kinks", b.kinks}, {"folds", b.folds}, {"levels", levels},
              {"first_mode_branch", up && down ? nlohmann::json({{"levels", n1}, {"start_energy", start_energy},
                                                                 {"homotopy_stiffness_n_per_m", up->homotopy_stiffness},
                                                                 {"radial_stiffness_n_per_m", k_radial},
                                                                 {"kinks", up->kinks + down->kinks},
                                                                 {"rejected_steps", up->rejected_steps + down->rejected_steps},
                                                                 {"first_mode", b1_first_mode}, {"hardening", b1_hardening}})
                                               : nlohmann::json()},
              {"onset_node_index", onset + 1}, {"leading_edge_contact", leading}, {"trailing_edge_contact", trailing}, {"first_contact_energy", std::isfinite(first_energy) ? nlohmann::json(first_energy) : nlohmann::json()},
              {"worst_penetration_gaps", worst_pen}, {"worst_complementarity_gaps", worst_comp},
              {"first_mode_share_below_half_from_energy", leaves >= 0 ? nlohmann::json(e(leaves)) : nlohmann::json()},
              {"end_component", {{"mode", end_mode}, {"harmonic", end_harmonic}, {"share", other_share(nl - 1)},
                                 {"first_mode_share", first_share(nl - 1)}, {"detuning", end_detuning},
                                 {"internal_resonance", end_resonant}}}});

    const models::BladeGeometry geometry = models::read_blade_geometry();
    std::ostringstream md;
    md << "## LL11 Figs. 6–8 — compressor blade against a rigid casing (`ll11_blade`)\n\n"
       << "The paper's industrial blade is not public; this is a representative compressor rotor blade built "
          "in the project (`reproduce/blade/blade.geo`, `reproduce/blade/README.md`): span "
       << format("%g", 1e3 * geometry.span) << " mm, chord " << format("%g", 1e3 * geometry.chord_root) << " → "
       << format("%g", 1e3 * geometry.chord_tip) << " mm, " << format("%g", geometry.stagger_tip_deg - geometry.stagger_root_deg)
       << "° of twist (blade.geo's inputs), Ti-6Al-4V, clamped root. gmsh mesh of "
       << written << " nodes, " << c3d10 << " quadratic tetrahedra (C3D10), " << n_full
       << " free DOFs; K and M assembled by CalculiX. Interface: " << n_tip << " tip nodes on the camber line, leading to "
          "trailing edge (" << nb << " DOFs), + " << modes << " fixed-interface modes = " << nb + modes
       << " DOFs, as in the paper. Radial frictionless contact (directions from the engine axis, hub radius "
       << format("%.0f", 1e3 * hub_radius) << " mm) at a uniform gap; exact (Signorini) contact, N = " << harmonics
       << ", m = " << samples << ". Parameters: `reproduce/scenes/ll11_blade.toml`.\n\n"
       << "Fig. 6: `mesh.png` (contact nodes in red). Fig. 7: `frequency_energy.png`. Fig. 8: `deformed.png`.\n\n"
       << "**First linear frequencies** (full model: Spectra shift-invert Lanczos on the full sparse K, M; reduced: "
       << nb << " + " << modes << "; ccx: CalculiX's own *FREQUENCY step on the same deck, 7 printed digits):\n\n"
       << "| mode | full [Hz] | reduced [Hz] | relative error | ccx [Hz] | full − ccx (relative) |\n"
          "|---|---|---|---|---|---|\n";
    for (int k = 0; k < reference_modes; ++k) {
      md << "| " << k + 1 << " | " << format("%.2f", f_full(k)) << " | " << format("%.2f", f_cb(k)) << " | "
         << format("%.1e", f_error(k)) << " | " << format("%.2f", f_ccx(k)) << " | " << format("%+.1e", ccx_error(k))
         << " |\n";
    }
    std::vector<reproduce::Claim> claims;
    claims.push_back({"the full model's frequencies (Spectra) equal CalculiX's own to its printed 7 digits (relative 1e-6)",
                      ccx_ok, "largest relative difference " + format("%.1e", ccx_error.cwiseAbs().maxCoeff())});
    md << "\n**Craig–Bampton convergence** (worst relative frequency error against the full model):\n\n"
       << "| normal modes | modes 1–5 | modes 1–" << reference_modes << " |\n|---|---|---|\n";
    for (int k = 0; k < 4; ++k) {
      md << "| " << convergence_modes[static_cast<size_t>(k)] << " | " << format("%.1e", worst5(k)) << " | "
         << format("%.1e", worst10(k)) << " |\n";
    }
    claims.push_back({"the first 5 frequencies within 0.1 % with " + std::to_string(modes) + " modes (issue #15)", cb_ok,
                      "worst relative error " + format("%.1e", worst5(3))});
    md << "\n**Nonlinear mode** (frequency normalized by the reduced model's first linear frequency f1 = "
       << format("%.2f", f1) << " Hz; full model " << format("%.2f", f_full(0)) << " Hz):\n\n"
       << "| E | branch | f/f1 | f [Hz] | tip nodes in contact | max radial u/g0 | worst penetration [g0] | "
          "complementarity [g0] | share of mode 1 at h = 1 | largest other component |\n"
       << "|---|---|---|---|---|---|---|---|---|---|\n"
       << level_rows.str()
       << "\nBranch 0 is the continuation from the linear mode; branch 1 (below) the first bending mode past the "
          "tongues. Over the whole of branch 0 (" << nl << " levels, E = " << format("%.2f", e(0)) << " to "
       << format("%.2f", e(nl - 1)) << ", " << b.folds.size() << " folds, " << b.kinks
       << " corners): worst penetration " << format("%.1e", worst_pen) << " g0, worst complementarity "
       << format("%.1e", worst_comp) << " g0. The paper gives Fig. 7 as a curve without numbers, so the values "
          "are not compared one by one; the paper's blade is not ours.\n\n";
    claims.push_back({"Fig. 7: the frequency increases with energy past contact onset and never drops below f1 (by more "
                      "than 1e-8)",
                      hardening,
                      "f/f1 = " + format("%.4f", ratio(nl - 1)) + " at E = " + format("%.2f", e(nl - 1)) + ", minimum " +
                          format("%.10f", ratio.minCoeff()) + "; the largest f/f1 is " + format("%.4f", ratio.maxCoeff()) +
                          " at E = " + format("%.2f", e(peak)) +
                          (ratio(nl - 1) < ratio.maxCoeff() - 1e-6 ? ", after which it decreases: not monotone"
                                                                   : ": monotone")});
    claims.push_back({"Fig. 7 is the first nonlinear mode: along the whole of branch 0 the first linear mode at the "
                      "fundamental holds at least half of the energy m̂ (NonlinearModes::modal_energy_shares, columns of "
                      "backbone.csv)",
                      leaves < 0,
                      leaves >= 0 ? "below ½ from E = " + format("%.2f", e(leaves))
                                  : "at least ½ up to E = " + format("%.2f", e(nl - 1))});
    claims.push_back({"branch 0 ends in a " + std::to_string(end_harmonic) + ":1 internal resonance with mode " +
                          std::to_string(end_mode) + " (more than half of m̂ and h f within 1 % of f_j)",
                      end_resonant, "h f/f_j − 1 = " + format("%+.1e", end_detuning)});
    claims.insert(claims.end(), b1_claims.begin(), b1_claims.end());
    md << "On branch 0, at E = " << format("%.2f", e(nl - 1)) << " the first mode holds "
       << format("%.3f", first_share(nl - 1)) << ", and mode " << end_mode << " at harmonic " << end_harmonic << " holds " << format("%.3f", other_share(nl - 1)) << " (f_"
       << end_mode << " = " << format("%.4f", end_fj / f1) << " f1 = " << end_harmonic << " × "
       << format("%.5f", end_fj / (end_harmonic * f1)) << " f1)"
       << (end_resonant && leaves >= 0
               ? std::string(". Past E = ").append(format("%.2f", e(leaves)))
                     .append(" branch 0 is the tongue of that internal resonance (its frequency tends to f_j/h), "
                             "not the first bending mode the paper draws; branch 1 below is that mode")
               : std::string())
       << ". The paper's blade is another geometry, whose frequency ratios we do not know.\n\n"
       << first_mode_text.str()
       << "Order of first contact along branch 0: " << sequence << ". Our blade's first mode moves the tip radially "
          "mostly near the leading edge (per-node excursions in tip_E*.csv); the paper's blade is another geometry, and "
          "without it we cannot tell whether the difference is only geometric.\n\n";
    claims.push_back({"LL11 Sec. 5.2: the leading and trailing edges touch first (an edge: chord fraction < 0.25 or > 0.75)",
                      edges,
                      "in the linear mode the first node to reach the gap is #" + std::to_string(onset + 1) + " (chord " +
                          format("%.2f", chord(onset)) + "); along branch 0 the first contact forces appear at E = " +
                          format("%.3f", first_energy) + " on " + first_nodes});
    claims.push_back({"LL11 Sec. 5.2: contacts occur at both the leading and the trailing edge", leading && trailing,
                      std::string("leading edge ") + (leading ? "in contact" : "never in contact") + ", trailing edge " +
                          (trailing ? "in contact" : "never in contact") + " up to E = " + format("%.2f", e(nl - 1)) +
                          "; the largest radial excursion of the trailing-edge node is " + format("%.2f", trailing_max) +
                          " g0 at E = " +
                          format("%g", figure_levels.empty() ? std::nan("") : figure_levels.back().first->energy)});
    md << reproduce::claims_markdown(claims)
       << "Timings (one run, 2 cores): gmsh " << format("%.1f", timing["gmsh_s"].get<double>()) << " s, ccx + reading "
       << format("%.1f", timing["ccx_and_read_s"].get<double>()) << " s, Craig–Bampton "
       << format("%.1f", timing["craig_bampton_s"].get<double>()) << " s (Cholesky "
       << format("%.1f", cb.factorization_s) << ", constraint modes " << format("%.1f", cb.constraint_modes_s)
       << ", Lanczos " << format("%.1f", cb.eigensolve_s) << "), full-model modes "
       << format("%.1f", timing["full_model_modes_s"].get<double>()) << " s, ccx's *FREQUENCY step "
       << format("%.1f", timing["ccx_frequencies_s"].get<double>()) << " s, backbone "
       << format("%.1f", timing["backbone_s"].get<double>()) << " s"
       << (timing.contains("first_mode_branch_s")
               ? ", branch 1 (N = " + std::to_string(start_harmonics) + std::string(" start, homotopy, up and down) ")
                     .append(format("%.1f", timing["first_mode_branch_s"].get<double>()))
                     .append(" s on a second thread, concurrently with the reference frequencies and branch 0")
               : std::string())
       << "; wall time of the whole run " << format("%.1f", total) << " s.\n";
    run.report(md.str());
    if (!cb_ok && !quick) run.fail("Craig–Bampton: first 5 frequencies not within 0.1 % with " + std::to_string(modes) + " modes");
    if (!ccx_ok) run.fail("the full model's frequencies differ from CalculiX's own by more than 1e-6");
  });
}
