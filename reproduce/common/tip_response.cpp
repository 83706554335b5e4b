#include "tip_response.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <wbm/solvers/harmonic_balance.hpp>
#include <wbm/solvers/time_integration.hpp>

#include "scene.hpp"

namespace wbm::reproduce {
namespace {

nlohmann::json to_json(const solvers::NewtonReport& r) {
  return {{"status", std::string(solvers::to_string(r.status))}, {"iterations", r.iterations},
          {"residual_norms", r.residual_norms}, {"jacobian_rcond", r.jacobian_rcond}, {"message", r.message}};
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

}  // namespace

void tip_displacement_figure(Run& run, const TipFigure& figure) {
  const RodScene scene = load_scene(figure.scene);
  if (!scene.contact) {
    throw std::invalid_argument(scene.path + ": [contact] is required for a tip-displacement figure "
                                "(the gap is drawn and the law is solved); add a [contact] table");
  }
  const auto system = scene.system();
  const auto forcing = scene.forcing();
  const auto contacts = scene.contacts();
  const int tip = forcing.dof;

  const auto ref = solvers::integrate_to_periodic(system, forcing, contacts,
                                                  {.samples_per_period = run.quick() ? 256 : 1024});
  if (!ref.report.converged()) run.fail("BDF reference: " + ref.report.message);
  const Eigen::VectorXd u_ref = ref.displacement.row(tip).transpose();

  const int m_figure = run.quick() ? 16 : 64;
  const std::vector<int> sweep = run.quick() ? std::vector<int>{16} : std::vector<int>{8, 16, 32, 64, 128, 256};
  Eigen::VectorXd u_figure;
  Eigen::VectorXd col_m(sweep.size()), col_err(sweep.size()), col_time(sweep.size()), col_it(sweep.size());
  nlohmann::json reports = nlohmann::json::object();
  for (size_t i = 0; i < sweep.size(); ++i) {
    const int m = sweep[i];
    std::vector<double> times;
    solvers::HarmonicBalanceSolution sol;
    for (int rep = 0; rep < (m <= 64 ? 7 : 3); ++rep) {  // median wall time of a full solve
      const auto t0 = std::chrono::steady_clock::now();
      sol = solvers::solve_harmonic_balance(system, forcing, contacts, {.dimension = m});
      times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
    if (!sol.converged()) run.fail("harmonic balance M = " + std::to_string(m) + ": " + sol.report.message);
    const Eigen::VectorXd u = solvers::evaluate_dof(sol.coefficients, tip, ref.tau, scene.frequency_hz);
    col_m(i) = m;
    col_err(i) = (u - u_ref).norm() / u_ref.norm();
    col_time(i) = times[times.size() / 2];
    col_it(i) = sol.report.iterations;
    reports[std::to_string(m)] = to_json(sol.report);
    reports[std::to_string(m)]["relative_residual"] = sol.relative_residual;
    reports[std::to_string(m)]["max_penetration_m"] = sol.max_penetration;
    if (m == m_figure) u_figure = u;
  }

  run.table("tip_displacement.csv", {"tau [-]", "u_tip_bdf [m]", "u_tip_fourier_fourier [m]"},
            {ref.tau, u_ref, u_figure});
  run.table("convergence.csv",
            {"M [-]", "rms_relative_error_fourier_fourier [-]", "solve_time_fourier_fourier [s]",
             "newton_iterations_fourier_fourier [-]"},
            {col_m, col_err, col_time, col_it});
  run.meta({{"scene", {{"name", scene.name}, {"file", scene.path}, {"title", scene.title},
                       {"E_Pa", scene.rod.young_modulus}, {"rho_kg_m3", scene.rod.density},
                       {"S_m2", scene.rod.area}, {"L_m", scene.rod.length}, {"elements", scene.rod.elements},
                       {"beta_s", scene.beta}, {"F_N", scene.force_amplitude},
                       {"frequency_hz", scene.frequency_hz}, {"contact", scene.contact_law()->describe()}}},
            {"gap_m", scene.contact->gap},
            {"figure_basis", "fourier:fourier"},
            {"figure_dimension", m_figure},
            {"harmonic_balance", reports},
            {"reference", {{"method", "GSL msbdf, rtol 1e-10, atol 1e-13 m"},
                           {"status", std::string(solvers::to_string(ref.report.status))},
                           {"periods", ref.report.periods}, {"steps", ref.report.steps},
                           {"periodicity", ref.report.periodicity.empty() ? 0.0 : ref.report.periodicity.back()},
                           {"wall_time_s", ref.report.wall_time_s}, {"samples", ref.tau.size()}}}});

  std::ostringstream md;
  md << "## " << figure.figure << ": tip displacement, " << scene.title << "\n\n"
     << "Files: `out/" << run.id() << "/tip_displacement.{csv,png,pdf}`, `convergence.csv`, `meta.json`."
     << " Scene: `reproduce/scenes/" << scene.name << ".toml`.\n\n"
     << "Paper: " << figure.paper_note << "\n\n"
     << "- BDF reference (GSL msbdf): periodic after " << ref.report.periods << " periods (rms change "
     << fmt("%.1e", ref.report.periodicity.empty() ? 0.0 : ref.report.periodicity.back()) << " < 1e-7), "
     << ref.report.steps << " steps, " << fmt("%.2f", ref.report.wall_time_s) << " s; tip range ["
     << fmt("%.4f", u_ref.minCoeff() * 1e3) << ", " << fmt("%.4f", u_ref.maxCoeff() * 1e3) << "] mm, gap "
     << fmt("%.1f", scene.contact->gap * 1e3) << " mm.\n"
     << "- Harmonic balance (Fourier:Fourier) against it, rms relative tip error "
     << "‖u − u_ref‖₂/‖u_ref‖₂ over " << ref.tau.size() << " samples, median wall time of a full solve:\n\n"
     << "| M | rms rel. error | solve time [ms] | Newton iterations |\n|---|---|---|---|\n";
  for (Eigen::Index i = 0; i < col_m.size(); ++i) {
    md << "| " << static_cast<int>(col_m(i)) << " | " << fmt("%.3e", col_err(i)) << " | "
       << fmt("%.2f", col_time(i) * 1e3) << " | " << static_cast<int>(col_it(i)) << " |\n";
  }
  md << "\n";
  run.report(md.str());
}

}  // namespace wbm::reproduce
