// WeightedResidual, set-up: which basis:formulation pairs are admissible, the time operators
// [JL14 Eqs. (14)–(16)], the harmonic selection and the load projection (weighted_residual_impl.hpp).
#include "weighted_residual_impl.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/LU>
#include <Eigen/QR>

#include <wbm/contact/friction.hpp>
#include <wbm/solvers/model_checks.hpp>
#include <wbm/wavelets/connection_coefficients.hpp>

namespace wbm::solvers {

namespace {

// One term of [JL14 Eqs. (14)–(16)]: sign · ∫ p^{(weighting)} q^{(trial)} dτ.
struct Term {
  int weighting, trial;
  double sign;
  const char* text;  // the integral as written in the paper
};

// Mass, damping, stiffness terms of each formulation.
std::array<Term, 3> terms(Formulation f) {
  switch (f) {
    case Formulation::Strong:
      return {{{0, 2, 1.0, "∫ p M q̈ (Eq. 14)"}, {0, 1, 1.0, "∫ p C q̇ (Eq. 14)"}, {0, 0, 1.0, "∫ p K q"}}};
    case Formulation::Weak:
      return {{{1, 1, -1.0, "−∫ ṗ M q̇ (Eq. 15)"}, {0, 1, 1.0, "∫ p C q̇ (Eq. 15)"}, {0, 0, 1.0, "∫ p K q"}}};
    case Formulation::Distributional:
      return {{{2, 0, 1.0, "∫ p̈ M q (Eq. 16)"}, {1, 0, -1.0, "−∫ ṗ C q (Eq. 16)"}, {0, 0, 1.0, "∫ p K q"}}};
  }
  throw std::logic_error("unknown formulation");
}

bool exact_rule(const TimeBasis& trial, const TimeBasis& weighting, OperatorRule rule) {
  return rule == OperatorRule::Automatic && trial.same_family(weighting);
}

int connection_limit(const TimeBasis& b) {
  return b.is_fourier() ? 2 : wavelets::max_connection_order(b.wavelet_basis()->family());
}

std::string why_term(const TimeBasis& trial, const TimeBasis& weighting, Formulation f, OperatorRule rule,
                     const Term& t) {
  std::ostringstream os;
  if (exact_rule(trial, weighting, rule)) {
    const int limit = connection_limit(trial);
    if (t.weighting + t.trial > limit) {
      os << trial.name() << ":" << weighting.name() << " (Galerkin, connection coefficients), "
         << to_string(f) << " form: the term " << t.text << " needs ∫ φ^(" << t.weighting << ") φ^(" << t.trial
         << "), order " << t.weighting + t.trial << ", but " << trial.name()
         << " admits connection coefficients up to order " << limit;
    }
    return os.str();
  }
  if (t.trial > trial.max_derivative()) {
    os << trial.name() << ":" << weighting.name() << ", " << to_string(f) << " form: the trial basis "
       << trial.name() << " has no pointwise derivative of order " << t.trial << " (largest: "
       << trial.max_derivative() << "), needed by the term " << t.text;
  } else if (t.weighting > weighting.max_derivative()) {
    os << trial.name() << ":" << weighting.name() << ", " << to_string(f) << " form: the weighting basis "
       << weighting.name() << " has no pointwise derivative of order " << t.weighting << " (largest: "
       << weighting.max_derivative() << "), needed by the term " << t.text;
  }
  return os.str();
}

std::string why_not(const TimeBasis& trial, const TimeBasis& weighting, Formulation f, OperatorRule rule) {
  for (const Term& t : terms(f)) {
    std::string w = why_term(trial, weighting, f, rule, t);
    if (!w.empty()) return w;
  }
  return {};
}

}  // namespace

std::string_view to_string(Formulation f) noexcept {
  switch (f) {
    case Formulation::Strong: return "strong";
    case Formulation::Weak: return "weak";
    case Formulation::Distributional: return "distributional";
  }
  return "unknown";
}

Formulation parse_formulation(const std::string& name) {
  for (Formulation f : {Formulation::Strong, Formulation::Weak, Formulation::Distributional}) {
    if (name == to_string(f)) return f;
  }
  throw std::invalid_argument("formulation '" + name + "' is unknown; use strong (JL14 Eq. 14), weak (Eq. 15) "
                              "or distributional (Eq. 16)");
}

std::string_view to_string(ContactQuadrature q) noexcept {
  switch (q) {
    case ContactQuadrature::Midpoint: return "midpoint";
    case ContactQuadrature::CellAverage: return "cell-average";
  }
  return "unknown";
}

std::string inadmissibility(const TimeBasis& trial, const TimeBasis& weighting, Formulation formulation,
                            OperatorRule rule) {
  std::string why = why_not(trial, weighting, formulation, rule);
  if (why.empty()) return why;
  std::string alternatives;
  for (Formulation f : {Formulation::Strong, Formulation::Weak, Formulation::Distributional}) {
    if (f != formulation && why_not(trial, weighting, f, rule).empty()) {
      alternatives += std::string(alternatives.empty() ? "" : " or ") + "the " + std::string(to_string(f)) + " form";
    }
  }
  why += alternatives.empty()
             ? "; no formulation admits this pair: pair the basis with a smooth one (e.g. Haar:Fourier or "
               "Haar:B-spline in the distributional form)"
             : "; use " + alternatives + " instead";
  return why;
}


void WeightedResidualOptions::validate(int dimension) const {
  if (!(residual_tolerance > 0.0)) {
    throw std::invalid_argument("WeightedResidualOptions.residual_tolerance = " + format_number(residual_tolerance) +
                                ": must be > 0 (a relative bound on the full residual, e.g. 1e-8)");
  }
  if (homotopy_max_points < 2) {
    throw std::invalid_argument("WeightedResidualOptions.homotopy_max_points = " + std::to_string(homotopy_max_points) +
                                ": must be >= 2 (continuation points of the contact homotopy; e.g. 2000)");
  }
  if (time_samples < 0 || (time_samples > 0 && time_samples < dimension)) {
    throw std::invalid_argument("WeightedResidualOptions.time_samples Q = " + std::to_string(time_samples) +
                                ": must be 0 (automatic, max(256, 2M)) or >= M = " + std::to_string(dimension));
  }
  newton.validate();
}

WeightedResidual::Impl::Impl(MechanicalSystem s, HarmonicForcing f, std::vector<ContactPoint> c, TimeBasis tr, TimeBasis we,
                             WeightedResidualOptions o)
    : system(std::move(s)), forcing(f), contacts(std::move(c)), trial(std::move(tr)), weighting(std::move(we)),
      options(o) {
  system.validate();
  forcing.validate(system.dofs());
  ContactPoint::validate(contacts, system.dofs());
  n = system.dofs();
  m = trial.dimension();
  nc = static_cast<int>(contacts.size());
  if (weighting.dimension() != m) {
    throw std::invalid_argument("weighted residual: trial " + trial.name() + " has M = " + std::to_string(m) +
                                " functions but weighting " + weighting.name() + " has " +
                                std::to_string(weighting.dimension()) + "; use one dimension M for both");
  }
  options.validate(m);
  q = options.time_samples > 0 ? options.time_samples : std::max(256, 2 * m);
  if (dynamic_stiffness_overflows(system, forcing.frequency_hz, highest_resolved_harmonic(m))) {
    throw std::invalid_argument("HarmonicForcing.frequency_hz = " + format_number(forcing.frequency_hz) + " Hz: " +
                                explain_singular_dynamic_stiffness(system, forcing.frequency_hz,
                                                                   highest_resolved_harmonic(m)));
  }
  forcing.require_resolved(m, "the weighted residual's M = " + std::to_string(m) + " trial functions", "raise the basis dimension");
  const std::string why = inadmissibility(trial, weighting, options.formulation, options.operators);
  if (!why.empty()) throw std::invalid_argument(why);

  int rigid_count = 0;
  for (const auto& ct : contacts) rigid_count += ct.law->rigid() ? 1 : 0;
  rigid = rigid_count > 0;
  if (rigid && rigid_count < nc) {
    throw std::invalid_argument("weighted residual: " + std::to_string(rigid_count) + " of the " + std::to_string(nc) +
                                " contacts are exact (rigid stops or Coulomb friction, whose forces are multipliers) "
                                "and the others penalty or Jenkins laws; mixing them in one problem is not supported: "
                                "make every contact exact, or give the rigid ones a stiff LinearPenalty and the "
                                "Coulomb ones a stiff JenkinsLaw");
  }
  if (rigid && options.contact_quadrature == ContactQuadrature::CellAverage) {
    throw std::invalid_argument("WeightedResidualOptions.contact_quadrature = cell-average integrates a penalty law over "
                                "each cell; rigid stops impose the Signorini conditions at the collocation instants "
                                "instead: use ContactQuadrature::Midpoint");
  }
  cell_average_rule = options.contact_quadrature == ContactQuadrature::CellAverage;
  if (cell_average_rule && trial.max_derivative() < 1) {
    throw std::invalid_argument("WeightedResidualOptions.contact_quadrature = cell-average averages the contact law "
                                "along the slope u̇ of the trial functions; the trial basis " + trial.name() +
                                " has no pointwise derivative: use ContactQuadrature::Midpoint (the paper's rule)");
  }
  select_harmonics();
  auto smp = std::make_shared<Sampling>();
  smp->tau.resize(q);
  for (int k = 0; k < q; ++k) smp->tau(k) = (k + 0.5) / q;
  if (trial.is_fourier() || weighting.is_fourier()) smp->aft = std::make_shared<const spectral::Aft>(m, q, 0.5);
  smp->trial.emplace(trial, smp->tau, 0, smp->aft);
  if (cell_average_rule) smp->trial_slope.emplace(trial, smp->tau, 1, smp->aft);
  smp->weighting.emplace(weighting, smp->tau, 0, smp->aft);
  smp->weighting->keep = keep;
  if (any_moving_obstacle(contacts)) {
    for (int c = 0; c < nc; ++c) {
      const int h = contacts[c].obstacle.highest_harmonic();
      if (h <= highest_resolved_harmonic(m)) continue;
      throw std::invalid_argument("ContactPoint.obstacle (contact " + std::to_string(c) + " at DOF " +
                                  std::to_string(contacts[c].dof) + ") moves at harmonic " + std::to_string(h) +
                                  ", which the weighted residual's M = " + std::to_string(m) + " trial functions "
                                  "cannot carry (2h < M, harmonic " + std::to_string(highest_resolved_harmonic(m)) +
                                  " at most): raise the basis dimension, or drop that harmonic");
    }
    smp->obstacle = obstacle_samples(contacts, smp->tau);
    if (cell_average_rule) smp->obstacle_slope = obstacle_samples(contacts, smp->tau, 1) / static_cast<double>(q);
  }
  sampling = smp;
  assemble_time_operators();
  if (keep.size() > 0) require_block_diagonal_operators();
  g.emplace(system, ops, options.linear_solver,
            weighting.is_fourier() && !trial.is_fourier() && options.formulation == Formulation::Distributional,
            operator_products->sparse ? &operator_products->transposed : nullptr);

  // b: the weighted projections of every load F_j cos(2π h_j τ + φ_j) on its DOF.
  Eigen::MatrixXd bm = Eigen::MatrixXd::Zero(n, m);
  for (const auto& l : forcing.loads()) {
    if (l.amplitude == 0.0) continue;
    Eigen::RowVectorXd cosine(q);
    for (int k = 0; k < q; ++k) cosine(k) = std::cos(2.0 * std::numbers::pi * l.harmonic * smp->tau(k) + l.phase_rad);
    bm.row(l.dof) += l.amplitude * smp->weighting->project(cosine);
  }
  b = spectral::stacked(bm);

  contact_terms.assign(static_cast<size_t>(nc) * m, {});
  for (int k = 0; k < m; ++k) {
    for (int c = 0; c < nc; ++c) {
      for (const auto& [dof, w] : contacts[c].terms()) {
        contact_terms[static_cast<size_t>(k) * nc + c].emplace_back(spectral::stacked_index(k, dof, n), w);
      }
    }
  }

  for (const auto& terms : contact_terms) {
    for (const auto& [row, w] : terms) contact_dofs.push_back(row % n);
  }
  std::sort(contact_dofs.begin(), contact_dofs.end());
  contact_dofs.erase(std::unique(contact_dofs.begin(), contact_dofs.end()), contact_dofs.end());

  if (rigid) {
    auto col = std::make_shared<Collocation>();
    // V (trial functions at τ_{k+1}), W (weighting functions at τ_k, over M) and the trial
    // functions at τ_k (friction's increments), on the uniform grid of the impulses (TimeBasis::
    // grid_values: Fourier's arguments reduced exactly). V is the table at τ_k with its rows
    // rotated by one; with one family for both, W is that table too: one table of M² values.
    Eigen::MatrixXd trial_at_tau;
    const auto set_collocation_values = [&](Collocation& cl, bool midpoints) {
      trial_at_tau = trial.grid_values(m, midpoints);
      cl.trial_values.resize(m, m);
      cl.trial_values.topRows(m - 1) = trial_at_tau.bottomRows(m - 1);
      cl.trial_values.row(m - 1) = trial_at_tau.row(0);
      cl.weights = (trial.same_family(weighting) ? trial_at_tau : weighting.grid_values(m, midpoints)).transpose() /
                   static_cast<double>(m);
    };
    col->tau.resize(m);
    for (int k = 0; k < m; ++k) col->tau(k) = (k + 0.5) / m;
    set_collocation_values(*col, true);  // row k of V: τ_{k+1}, the instant whose gap λ_k keeps open
    col->gaps.resize(static_cast<Eigen::Index>(nc) * m);
    for (int k = 0; k < m; ++k) {
      for (int c = 0; c < nc; ++c) col->gaps(static_cast<Eigen::Index>(k) * nc + c) = contacts[c].law->gap();
    }
    col->coulomb.assign(static_cast<size_t>(nc), 0);
    col->slip_forces = Eigen::VectorXd::Zero(nc);
    col->normal_of.assign(static_cast<size_t>(nc), -1);
    col->friction_coefficients = Eigen::VectorXd::Zero(nc);
    for (int c = 0; c < nc; ++c) {
      if (const auto* f = dynamic_cast<const contact::CoulombFriction*>(contacts[c].law.get())) {
        col->coulomb[static_cast<size_t>(c)] = 1;
        col->slip_forces(c) = f->slip_force();
        col->friction_coefficients(c) = f->parameters().friction_coefficient;
        col->normal_of[static_cast<size_t>(c)] = contacts[c].normal;  // a rigid stop (ContactPoint::validate)
        col->any_coulomb = true;
        col->any_normal = col->any_normal || contacts[c].normal >= 0;
      }
    }
    if (col->any_coulomb) {
      // Friction needs every impulse pattern to move the structure: in full stick the slips do
      // not fix the impulses W cannot see, and with one slip row the stick rows become singular.
      // At the midpoints the top function of Fourier with even M vanishes, and the symmetric
      // B-splines sum to zero against (−1)^k: there the impulses move to the cell ends k/M.
      const auto singular = [](const Eigen::MatrixXd& weights) {
        Eigen::FullPivLU<Eigen::MatrixXd> lu(weights);
        lu.setThreshold(1e-10);
        return lu.dimensionOfKernel() > 0;
      };
      if (singular(col->weights)) {
        for (int k = 0; k < m; ++k) col->tau(k) = static_cast<double>(k) / m;
        set_collocation_values(*col, false);
        if (singular(col->weights)) {
          throw std::invalid_argument("exact Coulomb friction (law \"coulomb\"): the weighting basis " + weighting.name() +
                                      " of M = " + std::to_string(m) + " functions does not see every pattern of M "
                                      "impulses, at the midpoints (k + 1/2)/M nor at the instants k/M, so the friction "
                                      "forces in stick are not determined: use another weighting basis or M, or a "
                                      "Jenkins element (law \"jenkins\")");
        }
      }
      col->increments = col->trial_values - trial_at_tau;
    }
    if (any_moving_obstacle(contacts)) {
      // Impulse k keeps the gap at τ_{k+1} and sets the slip over [τ_k, τ_{k+1}]; τ_M = τ_0 + 1 (a
      // drift counts over the last cell).
      Eigen::VectorXd next(m);
      for (int k = 0; k < m; ++k) next(k) = k + 1 < m ? col->tau(k + 1) : col->tau(0) + 1.0;
      const Eigen::MatrixXd s_next = obstacle_samples(contacts, next), s_at = obstacle_samples(contacts, col->tau);
      col->slip_offsets = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(nc) * m);
      col->pin_offsets = s_next.col(0);
      for (int k = 0; k < m; ++k) {
        for (int c = 0; c < nc; ++c) {
          const Eigen::Index i = static_cast<Eigen::Index>(k) * nc + c;
          if (col->coulomb[static_cast<size_t>(c)] != 0) {
            col->slip_offsets(i) = s_next(c, k) - s_at(c, k);
          } else {
            col->gaps(i) += s_next(c, k);
          }
        }
      }
    }
    collocation = col;
  }

  factorized = g->factorize({&system, &ops, forcing.frequency_hz});
  if (!factorized) return;
  if (nc > 0) {
    const auto gathered = gathered_solve(b, false);
    x_lin = gathered ? *gathered : gather(linear_coefficients());
    set_compliance();
    if (rigid) set_delassus(true);
    double gmax = 0.0;
    for (const auto& ct : contacts) gmax = std::max(gmax, std::abs(ct.law->gap()));
    // A moving counter-surface's excursion is a length of the problem too (0 when fixed).
    for (const auto& ct : contacts) gmax = std::max(gmax, ct.obstacle.amplitude_bound());
    // The larger of the gap and the linear response: a 1 nm gap beside a millimetre motion
    // must not ask Newton for 1e-19 m.
    scale = std::max(gmax, x_lin.lpNorm<Eigen::Infinity>());
    if (!(scale > 0.0) || !std::isfinite(scale)) scale = 1.0;
  }
}


WeightedResidual::Impl::Impl(const Impl& base, double frequency_hz)
    : system(base.system), forcing(base.forcing), contacts(base.contacts), trial(base.trial),
      weighting(base.weighting), options(base.options), n(base.n), m(base.m), q(base.q), nc(base.nc),
      ops(base.ops), operator_products(base.operator_products), sampling(base.sampling),
      cell_average_rule(base.cell_average_rule), keep(base.keep),
      g(base.g->unfactorized()), b(base.b), scale(base.scale),
      contact_terms(base.contact_terms), contact_dofs(base.contact_dofs), rigid(base.rigid),
      collocation(base.collocation) {
  forcing.frequency_hz = frequency_hz;
  forcing.validate(n);
  factorized = g->factorize({&system, &ops, forcing.frequency_hz});
  if (!factorized) return;
  if (nc > 0) {
    const auto gathered = gathered_solve(b, false);
    x_lin = gathered ? *gathered : gather(linear_coefficients());
    set_compliance();
  }
  force_compliance = base.force_compliance;  // like s_r: residuals at different f comparable
  friction_compliance = base.friction_compliance;
  if (nc > 0 && rigid) set_delassus(false);
}


void WeightedResidual::Impl::select_harmonics() {
  auto& kept = options.harmonics;
  if (kept.empty()) return;
  const std::string what = "WeightedResidualOptions.harmonics (harmonic selection)";
  if (!trial.is_fourier() || !weighting.is_fourier()) {
    throw std::invalid_argument(what + ": needs the Fourier basis as trial and weighting (harmonic balance); " +
                                trial.name() + ":" + weighting.name() + " has no harmonics to select: leave the "
                                "list empty, or use Fourier:Fourier");
  }
  if (rigid) {
    throw std::invalid_argument(what + ": rigid stops impose the Signorini conditions at M collocation instants, "
                                "which need every function of the basis; leave the list empty, or model the stops "
                                "as penalty laws");
  }
  const spectral::FourierBasis basis(m);
  const int highest = basis.highest_harmonic();
  std::sort(kept.begin(), kept.end());
  for (size_t i = 0; i < kept.size(); ++i) {
    if (kept[i] < 0 || kept[i] > highest) {
      throw std::invalid_argument(what + ": harmonic " + std::to_string(kept[i]) + " is outside [0, " +
                                  std::to_string(highest) + "], the harmonics of the Fourier basis of M = " +
                                  std::to_string(m) + " functions; remove it or raise the number of harmonics");
    }
    if (i > 0 && kept[i] == kept[i - 1]) {
      throw std::invalid_argument(what + ": harmonic " + std::to_string(kept[i]) + " is listed twice; list each once");
    }
  }
  std::vector<char> chosen(static_cast<size_t>(highest) + 1, 0);
  for (int h : kept) chosen[static_cast<size_t>(h)] = 1;
  for (const auto& l : forcing.loads()) {
    if (l.amplitude != 0.0 && l.harmonic <= highest && chosen[static_cast<size_t>(l.harmonic)] == 0) {
      throw std::invalid_argument(what + ": the load on DOF " + std::to_string(l.dof) + " acts at harmonic " +
                                  std::to_string(l.harmonic) + ", which is not kept: the projection would drop it; "
                                  "add " + std::to_string(l.harmonic) + " to the harmonics or remove the load");
    }
  }
  keep.resize(m);
  for (int k = 0; k < m; ++k) keep(k) = chosen[static_cast<size_t>(basis.harmonic(k))];
}


void WeightedResidual::Impl::require_block_diagonal_operators() const {
  const Eigen::MatrixXd* a[3] = {&ops.mass, &ops.damping, &ops.stiffness};
  for (const auto* op : a) {
    const double tol = 1e-12 * std::max(op->cwiseAbs().maxCoeff(), 1.0);
    for (int j = 0; j < m; ++j) {
      for (int k = 0; k < m; ++k) {
        if (keep(j) != keep(k) && std::abs((*op)(j, k)) > tol) {
          throw std::logic_error("weighted residual, harmonic selection: the time operators (" + ops.rule +
                                 ") couple a kept harmonic with a dropped one (entry " + format_number((*op)(j, k)) +
                                 " at functions " + std::to_string(j) + ", " + std::to_string(k) +
                                 "): the projection would not be Galerkin; please report this");
        }
      }
    }
  }
}


void WeightedResidual::Impl::set_operator_products(
    const std::array<std::optional<Eigen::SparseMatrix<double>>, 3>& sparse) {
  auto products = std::make_shared<OperatorProducts>();
  const Eigen::MatrixXd* a[3] = {&ops.mass, &ops.damping, &ops.stiffness};
  const bool from_sparse = sparse[0] && sparse[1] && sparse[2];
  Eigen::Index nonzeros = 0;
  for (int t = 0; t < 3; ++t) nonzeros += from_sparse ? sparse[t]->nonZeros() : (a[t]->array() != 0.0).count();
  products->sparse = static_cast<double>(nonzeros) <= 0.25 * 3.0 * static_cast<double>(m) * m;
  if (products->sparse) {
    for (int t = 0; t < 3; ++t) {
      products->transposed[static_cast<size_t>(t)] =
          from_sparse ? Eigen::SparseMatrix<double>(sparse[t]->transpose()) : a[t]->transpose().sparseView();
    }
  }
  size_t k = 0;
  for (size_t s = 0; s < 3; ++s) {
    for (size_t r = s; r < 3; ++r, ++k) {
      products->time_inner[k] = products->sparse
                                    ? products->transposed[s].cwiseProduct(products->transposed[r]).sum()
                                    : a[s]->cwiseProduct(*a[r]).sum();
    }
  }
  operator_products = products;
}


double WeightedResidual::Impl::frobenius_norm() const {
  const double fr = forcing.frequency_hz;
  const std::array<double, 3> c = {fr * fr, fr, 1.0};
  const std::array<const Eigen::SparseMatrix<double>*, 3> x = {&system.mass, &system.damping, &system.stiffness};
  double sum = 0.0;
  size_t k = 0;
  for (size_t s = 0; s < 3; ++s) {
    for (size_t r = s; r < 3; ++r, ++k) {  // the pairs (s, r) and (r, s) alike
      const double time = operator_products->time_inner[k];
      if (time == 0.0) continue;
      sum += (r == s ? 1.0 : 2.0) * c[s] * c[r] * time * x[s]->cwiseProduct(*x[r]).sum();
    }
  }
  return std::sqrt(std::max(sum, 0.0));
}


Eigen::MatrixXd WeightedResidual::Impl::time_product(const Eigen::MatrixXd& u, int t) const {
  if (operator_products->sparse) return u * operator_products->transposed[static_cast<size_t>(t)];
  const Eigen::MatrixXd* a[3] = {&ops.mass, &ops.damping, &ops.stiffness};
  return u * a[t]->transpose();
}


Eigen::MatrixXd WeightedResidual::Impl::operator_product(const Eigen::SparseMatrix<double>& x, const Eigen::MatrixXd& u,
                                                         int t) const {
  return time_product(x * u, t);
}


std::optional<Eigen::VectorXd> WeightedResidual::Impl::gathered_solve(const Eigen::VectorXd& v,
                                                                      bool frequency_derivative) const {
  if (!g->modal_blocks()) return std::nullopt;
  const Eigen::MatrixXd vm = spectral::as_coefficients(v, n);  // n × M
  std::vector<Eigen::Index> sources;
  for (Eigen::Index dof = 0; dof < n; ++dof) {
    if ((vm.row(dof).array() != 0.0).any()) sources.push_back(dof);
  }
  Eigen::MatrixXd y = g->modal_block_solve(g->modal_projection(vm, sources));
  if (frequency_derivative) {
    const double f = forcing.frequency_hz;
    y = g->modal_block_solve(2.0 * f * time_product(y, 0) + g->modal_damping().asDiagonal() * time_product(y, 1));
  }
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, m);
  a(contact_dofs, Eigen::all) = g->modal_rows(y, contact_dofs);
  return gather(spectral::stacked(a));
}


void WeightedResidual::Impl::assemble_time_operators() {
  const auto ts = terms(options.formulation);
  const bool exact = exact_rule(trial, weighting, options.operators);
  const Eigen::VectorXd& tau = sampling->tau;
  std::array<Eigen::MatrixXd, 3> a;
  std::array<std::optional<Eigen::SparseMatrix<double>>, 3> a_sparse;  // when the rule gives them sparse
  // Without stored zeros, so that their pattern is that of the dense operator's nonzeros.
  const auto keep_sparse = [&](int t, Eigen::SparseMatrix<double> s) {
    s.prune([](Eigen::Index, Eigen::Index, double v) { return v != 0.0; });
    a[t] = Eigen::MatrixXd(s);
    a_sparse[t] = std::move(s);
  };
  std::array<Eigen::MatrixXd, 3> pw, qt;                // dense values by derivative order (fallback)
  std::array<std::optional<SparseRows>, 3> ws, tsparse;  // sparse values by derivative order
  std::array<Eigen::MatrixXd, 3> projected;              // Fourier weighting: A^{(0)} by trial derivative
  const auto sparse_of = [&](std::array<std::optional<SparseRows>, 3>& cache, const TimeBasis& basis, int d) -> const SparseRows& {
    if (!cache[d]) cache[d] = basis.wavelet_basis()->sparse_values(tau, d);
    return *cache[d];
  };
  for (int t = 0; t < 3; ++t) {
    const Term& term = ts[t];
    if (exact) {
      keep_sparse(t, term.sign * trial.exact_operator(term.weighting, term.trial));
    } else if (weighting.is_fourier() && !trial.is_fourier()) {
      Eigen::MatrixXd& base = projected[term.trial];
      if (base.size() == 0) {
        const SparseRows& v = sparse_of(tsparse, trial, term.trial);
        base = sampling->aft->project(Eigen::MatrixXd(v.transpose())).transpose();  // (j, k)
      }
      a[t] = term.sign * fourier_weighting_derivative(base, term.weighting, sparse_of(tsparse, trial, term.trial));
    } else if (!weighting.is_fourier() && !trial.is_fourier()) {
      const SparseRows& w = sparse_of(ws, weighting, term.weighting);
      const SparseRows& v = sparse_of(tsparse, trial, term.trial);
      keep_sparse(t, (term.sign / q) * Eigen::SparseMatrix<double>(Eigen::SparseMatrix<double>(w.transpose()) *
                                                                Eigen::SparseMatrix<double>(v)));
    } else {
      if (pw[term.weighting].size() == 0) pw[term.weighting] = weighting.values(tau, term.weighting);
      if (qt[term.trial].size() == 0) qt[term.trial] = trial.values(tau, term.trial);
      a[t] = (term.sign / q) * (pw[term.weighting].transpose() * qt[term.trial]);
    }
  }
  ops.mass = std::move(a[0]);
  ops.damping = std::move(a[1]);
  ops.stiffness = std::move(a[2]);
  set_operator_products(a_sparse);
  ops.rule = exact ? (trial.is_fourier() ? "exact (analytic)" : "exact (connection coefficients)")
                   : "discrete, Q = " + std::to_string(q) + " midpoints";
}


Eigen::MatrixXd WeightedResidual::Impl::fourier_weighting_derivative(const Eigen::MatrixXd& base, int dw, const SparseRows& v) const {
  if (dw == 0) return base;
  if (dw > 2) throw std::logic_error("fourier_weighting_derivative: order " + std::to_string(dw) + " > 2");
  // ṗ_j = Σ_l D(j, l) p_l (spectral::FourierBasis::derivative_matrix) for every row but the top.
  const Eigen::SparseMatrix<double> d = spectral::FourierBasis(m).derivative_matrix();
  Eigen::MatrixXd out = d * base;
  if (dw == 2) out = d * out;
  const bool top = m % 2 == 0;
  if (top) {
    const double omega = std::numbers::pi * m;
    if (dw == 1) {
      Eigen::RowVectorXd dtop(q);
      for (int r = 0; r < q; ++r) dtop(r) = -omega * std::sin(omega * sampling->tau(r));
      out.row(m - 1) = (dtop * v) / static_cast<double>(q);
    } else {
      out.row(m - 1) = -omega * omega * base.row(m - 1);
    }
  }
  return out;
}


std::string WeightedResidual::Impl::singular_reason() const {
  const std::string why = explain_singular_dynamic_stiffness(system, forcing.frequency_hz, highest_resolved_harmonic(m));
  return why.empty() ? "no rigid-body mode, overflow or undamped resonance found; G is singular to working precision "
                       "(check the scale of M, C and K)"
                     : why;
}


void WeightedResidual::Impl::require_factorized() const {
  if (!factorized) {
    std::ostringstream os;
    os << "weighted residual " << trial.name() << ":" << weighting.name() << ": the linear operator G is singular at f = "
       << forcing.frequency_hz << " Hz: " << singular_reason();
    throw std::runtime_error(os.str());
  }
}
}  // namespace wbm::solvers
