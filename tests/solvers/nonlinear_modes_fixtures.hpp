// Helpers shared by the nonlinear-mode tests (test_nonlinear_modes*.cpp): the rod of [LL11 Sec.
// 5.1] from reproduce/scenes/ll11_rod.toml, its modes with a tip stop, and backbone look-ups.
#pragma once

#include <cmath>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/scene.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>

#include "shipped_scenes.hpp"

namespace wbm::testing {

// Backbone continuation options over [E_min, E_max], the other fields at their defaults.
inline wbm::solvers::BackboneContinuationOptions range(double energy_min, double energy_max) {
  wbm::solvers::BackboneContinuationOptions o;
  o.energy_min = energy_min;
  o.energy_max = energy_max;
  return o;
}

// [LL11 Sec. 5.1], from the scene every reproduction uses, with the stop's gap replaced.
inline wbm::solvers::MechanicalSystem ll11_system() {
  const auto scene = wbm::scene::load_scene(wbm::models::scene_directory() / "ll11_rod.toml");
  return wbm::scene::mode_problem(scene).system;
}

// The tip DOF of the 20-element clamped-free rod.
inline int tip_dof() { return 19; }

// The modes of that rod with a stop at the tip, gap `gap` [m].
inline wbm::solvers::NonlinearModes modes(
    double gap, int harmonics = 8, int samples = 256,
    wbm::solvers::ModeAlgorithm algorithm = wbm::solvers::ModeAlgorithm::Simultaneous) {
  return wbm::solvers::NonlinearModes(ll11_system(), {{tip_dof(), gap}},
                                      {.harmonics = harmonics, .samples = samples, .algorithm = algorithm});
}

// A trial state of BackboneSystem(modes(1e-3, 4, 32), k) at E = 1.4: the linear state at E = 1
// scaled by 1.3 (the tip beyond its gap over part of the period), ω²/ω₀² = 1.01 and, for exact
// contact (k = 0), multipliers 0 … 0.05 over the 32 samples (no λ tail with a penalty).
inline Eigen::VectorXd backbone_trial_state(const wbm::solvers::NonlinearModes::BackboneSystem& system, double k) {
  Eigen::VectorXd x = system.linear_state(1.0) * 1.3;
  x(x.size() - 1) = 1.01;
  if (k == 0.0) x.tail(32) = Eigen::VectorXd::LinSpaced(32, 0.0, 0.05);
  return x;
}

// The converged level of the backbone at `energy` (to 1e-12), or nullptr.
inline const wbm::solvers::ModeLevel* included(const wbm::solvers::Backbone& b, double energy) {
  for (const auto& l : b.included) {
    if (std::abs(l.energy - energy) < 1e-12 && l.converged()) return &l;
  }
  return nullptr;
}

}  // namespace wbm::testing
