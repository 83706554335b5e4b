#include "analysis_detail.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/jenkins_disc.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/spectral/aft.hpp>
#include <wbm/spectral/layout.hpp>

namespace wbm::scene::detail {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string way_out(const Scene& scene, solvers::StopReason stop, double stalled_residual) {
  using solvers::StopReason;
  const Analysis& a = scene.analysis;
  const bool nnm = a.kind == AnalysisKind::NonlinearModes;
  const std::string another_discretization =
      "change [analysis] harmonics (now " + std::to_string(a.harmonics) + ") or samples (now " +
      std::to_string(a.samples) + "; more samples per harmonic resolve the contact instants finer, fewer keep the "
      "constraint rows of neighbouring samples independent)";
  switch (stop) {
    case StopReason::MaxPoints:
      return "; way out: raise [analysis] max_points (now " + std::to_string(a.max_points) + "), e.g. to " +
             std::to_string(std::min(2 * a.max_points, 1000000));
    case StopReason::StateBound:
      return "; way out: raise [analysis] max_state (now " + format("%g", a.max_state) + "), or set it to 0 for no bound";
    case StopReason::StepBelowMinimum:
      if (std::isfinite(stalled_residual)) {
        if (nnm) return "; way out: " + another_discretization;
        return "; way out: raise [solver] tolerance (now " + format("%g", scene.solver.newton.tolerance) +
               ") above the corrector's rounding floor ‖R‖ = " + format("%.2g", stalled_residual) + ", e.g. to " +
               format("%.0e", 10.0 * stalled_residual) +
               " (the floor grows with the response; a shorter step does not lower it)";
      }
      return "; way out: lower [analysis] max_step (now " + format("%g", a.max_step) + "), e.g. to " +
             format("%g", a.max_step / 4.0) +
             (nnm ? ", or " + another_discretization
                  : scene.basis.harmonics == 0 ? ", or use [basis] harmonics = H (2H + 1 functions, the contact "
                                                 "averaged over cells: a smooth residual)"
                                               : "");
    case StopReason::Retraced:
    case StopReason::DegenerateEvent:
      return nnm ? "; way out: " + another_discretization : "";
    case StopReason::TimeBudget:
      return nnm ? "; way out: [analysis] algorithm = \"continuation\" (the KKT continuation, not bounded by a budget)" : "";
    case StopReason::RangeReached:
    case StopReason::GoalReached:
    case StopReason::InitialPointFailed:
    case StopReason::UndampedResonance:
      return "";
  }
  return "";
}

// The column name of the scene's contact c: its DOF, or "dof-other" for a contact between two DOFs.
std::string contact_label(const Scene& scene, size_t c) {
  const Structure& st = *scene.structure;
  const Contact& k = scene.contacts[c];
  return k.against < 0 ? st.dof_name(k.dof) : st.dof_name(k.dof) + "-" + st.dof_name(k.against);
}

// A_h and φ_h of u = Σ_h A_h cos(2πhτ + φ_h), h = 0 … h_max, for each row of `samples` (k × P,
// equispaced over one period), by FFT (spectral::Aft). amplitude, phase: k × (h_max + 1).
void harmonics_of(const Eigen::MatrixXd& samples, int h_max, Eigen::MatrixXd& amplitude, Eigen::MatrixXd& phase) {
  const spectral::Aft aft(2 * h_max + 1, static_cast<int>(samples.cols()), 0.0);
  const Eigen::MatrixXd c = aft.to_frequency(samples);  // {1, cos 2πτ, sin 2πτ, cos 4πτ, …}
  amplitude.resize(samples.rows(), h_max + 1);
  phase.resize(samples.rows(), h_max + 1);
  for (Eigen::Index r = 0; r < samples.rows(); ++r) {
    amplitude(r, 0) = c(r, 0);
    phase(r, 0) = 0.0;
    for (int k = 1; k <= h_max; ++k) {
      amplitude(r, k) = std::hypot(c(r, 2 * k - 1), c(r, 2 * k));
      phase(r, k) = std::atan2(-c(r, 2 * k), c(r, 2 * k - 1));
    }
  }
}

// Per-period files from displacement/velocity of every solver DOF (n × P), shared by solve and
// timestep; the written DOFs are the scene's (massless ones recovered, Scene::expand_displacement).
void period_tables(const Scene& scene, const std::vector<solvers::ContactPoint>& contacts,
                   const solvers::MechanicalSystem& system, double frequency_hz, const Eigen::VectorXd& tau,
                   const Eigen::MatrixXd& solver_displacement, const Eigen::MatrixXd* solver_velocity,
                   AnalysisResult& out) {
  const Structure& st = *scene.structure;
  const Eigen::VectorXd time = tau / frequency_hz;
  const Eigen::MatrixXd displacement = scene.expand_displacement(solver_displacement);
  std::optional<Eigen::MatrixXd> full_velocity;
  if (solver_velocity != nullptr) full_velocity = scene.expand_velocity(solver_displacement, *solver_velocity);
  const Eigen::MatrixXd* velocity = full_velocity ? &*full_velocity : nullptr;
  Table u{"displacement.csv", {"tau [-]", "time [s]"}, {tau, time}};
  nlohmann::json response = nlohmann::json::array();
  for (int dof : scene.output_dofs()) {
    const Eigen::VectorXd v = displacement.row(dof).transpose();
    u.header.push_back("u_" + st.dof_name(dof) + " [m]");
    u.columns.push_back(v);
    response.push_back({{"dof", st.dof_name(dof)},
                        {"max_m", v.maxCoeff()},
                        {"min_m", v.minCoeff()},
                        {"rms_m", solvers::rms(v)}});
  }
  out.diagnostics["response"] = response;
  out.tables.push_back(std::move(u));
  if (velocity != nullptr) {
    Table v{"velocity.csv", {"tau [-]", "time [s]"}, {tau, time}};
    for (int dof : scene.output_dofs()) {
      v.header.push_back("v_" + st.dof_name(dof) + " [m/s]");
      v.columns.push_back(velocity->row(dof).transpose());
    }
    out.tables.push_back(std::move(v));
  }
  if (!contacts.empty() && !contacts.front().law->rigid()) {  // rigid: their impulses (solve_one)
    Table f{"contact_force.csv", {"tau [-]", "time [s]"}, {tau, time}};
    // What a law sees: u_c relative to its counter-surface (ContactPoint::obstacle), at τ_p.
    const Eigen::MatrixXd obstacle = solvers::obstacle_samples(contacts, tau);
    const auto relative = [&](const solvers::ContactPoint& ct, size_t index, Eigen::Index p) {
      return ct.displacement(solver_displacement.col(p)) - obstacle(static_cast<Eigen::Index>(index), p);
    };
    nlohmann::json friction = nlohmann::json::array();
    std::vector<std::pair<size_t, Eigen::VectorXd>> slip_displacements;  // (contact, w) of friction contacts
    Eigen::MatrixXd u(static_cast<Eigen::Index>(contacts.size()), tau.size());  // n_c × P, relative
    for (size_t j = 0; j < contacts.size(); ++j) {
      for (Eigen::Index p = 0; p < tau.size(); ++p) u(static_cast<Eigen::Index>(j), p) = relative(contacts[j], j, p);
    }
    for (size_t k = 0; k < contacts.size(); ++k) {
      const auto& c = contacts[k];
      Eigen::VectorXd force(tau.size());
      if (const auto* disc = dynamic_cast<const contact::JenkinsDiscLaw*>(c.law.get())) {
        // A Jenkins element with two tangents: its loop over both, one diagnostics entry per element.
        const auto second = static_cast<size_t>(c.second_tangent);
        const contact::JenkinsDiscLoop loop =
            solvers::jenkins_disc_contact_loop(contacts, static_cast<int>(k), u, nullptr, false);
        force = loop.force.row(0).transpose();
        slip_displacements.emplace_back(k, u.row(static_cast<Eigen::Index>(k)).transpose());
        if (k < second) {
          // The slider's path in the plane, the drift's ramps removed; its amplitude is half its diameter.
          Eigen::MatrixXd slider = u({static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(second)}, Eigen::all) -
                                   loop.force / disc->parameters().tangential_stiffness;
          slider.row(0) += c.obstacle.drift * tau.transpose();
          slider.row(1) += contacts[second].obstacle.drift * tau.transpose();
          double diameter = 0.0;
          for (Eigen::Index p = 0; p < slider.cols(); ++p) {
            diameter = std::max(diameter, (slider.colwise() - slider.col(p)).colwise().norm().maxCoeff());
          }
          friction.push_back({{"contact", contact_label(scene, k)},
                              {"second_tangent", contact_label(scene, second)},
                              {"stick_fraction", 1.0 - static_cast<double>(loop.slipping_samples) /
                                                           static_cast<double>(tau.size())},
                              {"slip_amplitude_m", 0.5 * diameter},
                              {"dissipated_energy_per_cycle_J", loop.dissipated_energy},
                              {"dissipated_power_W", loop.dissipated_energy * frequency_hz},
                              {"output_samples", tau.size()}});
        }
      } else if (const auto* jenkins = dynamic_cast<const contact::JenkinsLaw*>(c.law.get())) {
        // The element's periodic loop over the P output samples (tau uniform over one period),
        // under its normal contact's force there, the counter-surface's drift carried over.
        const Eigen::VectorXd w = u.row(static_cast<Eigen::Index>(k)).transpose();
        const contact::JenkinsLoop loop = solvers::jenkins_contact_loop(contacts, static_cast<int>(k), u);
        force = loop.force;
        slip_displacements.emplace_back(k, w);
        // The slider's position, its drift's ramp removed (w + d τ is periodic).
        const Eigen::VectorXd slider = w - force / jenkins->parameters().tangential_stiffness + c.obstacle.drift * tau;
        friction.push_back({{"contact", contact_label(scene, k)},
                            {"stick_fraction", 1.0 - static_cast<double>(loop.slipping_samples) / static_cast<double>(tau.size())},
                            {"slip_amplitude_m", 0.5 * (slider.maxCoeff() - slider.minCoeff())},
                            {"dissipated_energy_per_cycle_J", loop.dissipated_energy},
                            {"dissipated_power_W", loop.dissipated_energy * frequency_hz},
                            {"output_samples", tau.size()}});
      } else {
        for (Eigen::Index p = 0; p < tau.size(); ++p) force(p) = c.law->force(u(static_cast<Eigen::Index>(k), p));
      }
      f.header.push_back("f_c_" + contact_label(scene, k) + " [N]");
      f.columns.push_back(force);
      if (!slip_displacements.empty() && slip_displacements.back().first == k) {
        // A friction contact's tangential displacement beside its force: the hysteresis loop f(w).
        f.header.push_back("w_c_" + contact_label(scene, k) + " [m]");
        f.columns.push_back(slip_displacements.back().second);
      }
    }
    if (!friction.empty()) out.diagnostics["friction"] = friction;
    out.tables.push_back(std::move(f));
  }
  if (scene.output.harmonics > 0) {  // A_h, φ_h of u = Σ A_h cos(2πhτ + φ_h) from the P samples
    const int h_max = scene.output.harmonics;
    const std::vector<int> dofs = scene.output_dofs();
    Eigen::MatrixXd observed(static_cast<Eigen::Index>(dofs.size()), tau.size());
    for (size_t i = 0; i < dofs.size(); ++i) observed.row(static_cast<Eigen::Index>(i)) = displacement.row(dofs[i]);
    Eigen::MatrixXd amplitude, phase;
    harmonics_of(observed, h_max, amplitude, phase);
    const Eigen::VectorXd h = Eigen::VectorXd::LinSpaced(h_max + 1, 0.0, h_max);
    Table t{"harmonics.csv", {"h [-]", "frequency [Hz]"}, {h, h * frequency_hz}};
    for (size_t i = 0; i < dofs.size(); ++i) {
      const auto r = static_cast<Eigen::Index>(i);
      t.header.push_back("A_" + st.dof_name(dofs[i]) + " [m]");
      t.columns.push_back(amplitude.row(r).transpose());
      t.header.push_back("phase_" + st.dof_name(dofs[i]) + " [rad]");
      t.columns.push_back(phase.row(r).transpose());
    }
    out.tables.push_back(std::move(t));
  }
  if (velocity != nullptr && scene.friction()) {
    out.diagnostics["energy"] = "not written: a friction law's energy depends on the history (diagnostics.friction "
                                "gives the energy it dissipates per cycle)";
  } else if (velocity != nullptr && solvers::any_moving_obstacle(contacts)) {
    out.diagnostics["energy"] = "not written: a moving counter-surface works on the structure, so the energy of "
                                "[JL14 Eq. (35)] is not an invariant of the motion";
  } else if (velocity != nullptr) {
    out.tables.push_back({"energy.csv",
                          {"tau [-]", "time [s]", "energy [J]"},
                          {tau, time, solvers::system_energy(system, contacts, solver_displacement, *solver_velocity)}});
  }
}

nlohmann::json coulomb_diagnostics(const std::string& label, const Eigen::VectorXd& force, const Eigen::VectorXd& w,
                                   const Eigen::VectorXd& slip_force, double frequency_hz, const std::string& count_key,
                                   double drift) {
  const Eigen::Index m = force.size();
  int stuck = 0;
  double energy = 0.0;
  for (Eigen::Index k = 0; k < m; ++k) {
    if (std::abs(force(k)) < slip_force(k) * (1.0 - 1e-9)) ++stuck;
    // w over the next period is w − d (a counter-surface sliding by d per period).
    energy += force(k) * (w((k + 1) % m) - w(k) - (k + 1 == m ? drift : 0.0));
  }
  // The slip amplitude of the periodic part, w + d k/m (the drift's ramp removed).
  const Eigen::VectorXd periodic = w + drift * Eigen::VectorXd::LinSpaced(m, 0.0, static_cast<double>(m - 1)) / m;
  return {{"contact", label},
          {"stick_fraction", static_cast<double>(stuck) / static_cast<double>(m)},
          {"slip_amplitude_m", 0.5 * (periodic.maxCoeff() - periodic.minCoeff())},
          {"dissipated_energy_per_cycle_J", energy},
          {"dissipated_power_W", energy * frequency_hz},
          {count_key, m}};
}

// Per point of a sweep or branch: A_h and φ_h of each observed DOF (rows: points). `samples[i]` is
// the observed DOFs' samples (k × P) at frequency `hz[i]`.
Table point_harmonics(const Scene& scene, const std::string& file, const std::vector<int>& observed,
                      const std::vector<double>& hz, const std::vector<Eigen::MatrixXd>& samples) {
  const int h_max = scene.output.harmonics;
  const auto n = static_cast<Eigen::Index>(hz.size());
  Table t{file, {"frequency [Hz]"}, {Eigen::Map<const Eigen::VectorXd>(hz.data(), n)}};
  std::vector<Eigen::VectorXd> columns(observed.size() * 2 * static_cast<size_t>(h_max + 1), Eigen::VectorXd(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::MatrixXd amplitude, phase;
    harmonics_of(samples[static_cast<size_t>(i)], h_max, amplitude, phase);
    size_t c = 0;
    for (size_t d = 0; d < observed.size(); ++d) {
      for (int h = 0; h <= h_max; ++h) {
        columns[c++](i) = amplitude(static_cast<Eigen::Index>(d), h);
        columns[c++](i) = phase(static_cast<Eigen::Index>(d), h);
      }
    }
  }
  for (int dof : observed) {
    const std::string name = scene.structure->dof_name(dof);
    for (int h = 0; h <= h_max; ++h) {
      const std::string suffix = std::to_string(h) + "_" + name;  // (not "A" + to_string: GCC 12 -Wrestrict false positive)
      t.header.push_back(std::string("A").append(suffix).append(" [m]"));
      t.header.push_back(std::string("phase").append(suffix).append(" [rad]"));
    }
  }
  t.columns.insert(t.columns.end(), columns.begin(), columns.end());
  return t;
}

// Samples (rows: `observed` scene DOFs, P columns) of a weighted-residual solution given by the
// trial coefficients of the solver DOFs `kept` (rows of `coefficients`; with a condensation, every
// solver DOF, so that massless DOFs can be recovered).
Eigen::MatrixXd observed_samples(const Scene& scene, const solvers::TimeBasis& trial, const Eigen::MatrixXd& coefficients,
                                 const std::vector<int>& kept, const std::vector<int>& observed,
                                 const Eigen::VectorXd& tau, double frequency_hz) {
  Eigen::MatrixXd u(coefficients.rows(), tau.size());
  for (Eigen::Index r = 0; r < coefficients.rows(); ++r) {
    u.row(r) = solvers::evaluate_trial(trial, coefficients, static_cast<int>(r), tau, frequency_hz).transpose();
  }
  Eigen::MatrixXd out(static_cast<Eigen::Index>(observed.size()), tau.size());
  if (scene.condensation) {
    const Eigen::MatrixXd full = scene.expand_displacement(u);  // kept = every solver DOF
    for (size_t i = 0; i < observed.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = full.row(observed[i]);
    return out;
  }
  for (size_t i = 0; i < observed.size(); ++i) {
    const auto at = std::find(kept.begin(), kept.end(), observed[i]);
    out.row(static_cast<Eigen::Index>(i)) = u.row(at - kept.begin());
  }
  return out;
}

// [basis] harmonic_selection: warn when the solutions leave more than kDroppedWarning ‖b‖ of the
// full residual in the dropped harmonics (the selection is then an approximation, not the full
// harmonic balance), with the largest value and where.
constexpr double kDroppedWarning = 1e-6;
std::string selection_label(const Scene& scene) {
  if (scene.basis.harmonic_selection == "odd") return "\"odd\"";
  std::string l = "[";
  for (size_t i = 0; i < scene.basis.selected_harmonics.size(); ++i) {
    l.append(i == 0 ? "" : ", ").append(std::to_string(scene.basis.selected_harmonics[i]));
  }
  return l + "]";
}
void warn_dropped_harmonics(const Scene& scene, const std::vector<double>& hz, const std::vector<double>& dropped,
                            AnalysisResult& out) {
  if (scene.basis.selected_harmonics.empty()) return;
  double worst = 0.0, at = 0.0;
  for (size_t i = 0; i < dropped.size(); ++i) {
    if (std::isfinite(dropped[i]) && dropped[i] > worst) {
      worst = dropped[i];
      at = hz[i];
    }
  }
  if (!(worst > kDroppedWarning)) return;
  out.warnings.push_back("harmonic_selection = " + selection_label(scene) + ": the contact forces have " +
                         "harmonics outside the selection (e.g. the mean and even harmonics of a one-sided stop); the "
                         "residual left in the dropped harmonics reaches " + format("%.3g", worst) + " ‖b‖ at f = " +
                         format("%.6g", at) + " Hz (> " + format("%g", kDroppedWarning) + "), so these results are "
                         "not the full harmonic balance's: keep every harmonic (remove harmonic_selection) to compare");
}

}  // namespace wbm::scene::detail
