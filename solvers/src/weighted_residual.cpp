#include <wbm/solvers/weighted_residual.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include <unsupported/Eigen/KroneckerProduct>

#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/model_checks.hpp>
#include <wbm/spectral/aft.hpp>
#include <wbm/spectral/fourier_basis.hpp>
#include <wbm/spectral/layout.hpp>
#include <wbm/wavelets/connection_coefficients.hpp>

#include "kronecker_factorization.hpp"
#include "one_norm_estimate.hpp"

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

// ContactQuadrature::CellAverage at one sample: the law averaged over the cell along the tangent
// of u, f̄ = (P(u + δ/2) − P(u − δ/2))/δ, and its partial derivatives in u and δ:
//   ∂f̄/∂u = (f(u + δ/2) − f(u − δ/2))/δ,   ∂f̄/∂δ = ((f(u + δ/2) + f(u − δ/2))/2 − f̄)/δ.
// Where the potential difference would lose more than four digits to cancellation
// (|ΔP| ≤ 1e-4 max|P|: a short cell deep inside one smooth piece of the law, or δ = 0), the
// midpoint value f(u) is used; it differs from f̄ by f''δ²/24 there.
void cell_average(const contact::ContactLaw& law, double u, double delta, double& f, double& dfdu, double& dfdd) {
  const double up = u + 0.5 * delta, um = u - 0.5 * delta;
  const double pp = law.potential(up), pm = law.potential(um);
  if (!(std::abs(pp - pm) > 1e-4 * std::max(std::abs(pp), std::abs(pm)))) {
    f = law.force(u);
    dfdu = law.stiffness(u);
    dfdd = 0.0;
    return;
  }
  f = (pp - pm) / delta;
  const double fp = law.force(up), fm = law.force(um);
  dfdu = (fp - fm) / delta;
  dfdd = (0.5 * (fp + fm) - f) / delta;
}

using SparseRows = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// One time basis at the Q midpoints τ_q = (q + ½)/Q, V(q, k) = v_k^{(d)}(τ_q), d = 0 or 1, used
// without a dense Q × M matrix: by FFTW (spectral::Aft) for the Fourier basis, by a sparse
// row-major matrix for wavelets (compact support: O(Q · support) entries, so that the memory
// and the products grow like M, not M²).
struct SampledBasis {
  std::shared_ptr<const spectral::Aft> aft;  // Fourier
  SparseRows values;                          // wavelets (Q × M)
  Eigen::RowVectorXd top_derivative;          // Fourier, d = 1, M = 2^J: −πM sin πMτ_q (outside the span)
  Eigen::SparseMatrix<double> derivative_matrix;  // Fourier, d = 1: coefficients of the derivative
  // Harmonic selection of a weighting basis: keep(k) = 1 for a kept function, 0 for a dropped
  // one, applied to every projection (Π of WeightedResidualOptions::harmonics); empty: all kept.
  Eigen::RowVectorXd keep;
  int q = 0, m = 0, derivative = 0;

  SampledBasis(const TimeBasis& basis, const Eigen::VectorXd& tau, int d, std::shared_ptr<const spectral::Aft> fft)
      : q(static_cast<int>(tau.size())), m(basis.dimension()), derivative(d) {
    if (basis.is_fourier()) {
      aft = std::move(fft);
      if (d == 1) derivative_matrix = spectral::FourierBasis(m).derivative_matrix();
      if (d == 1 && m % 2 == 0) {
        top_derivative.resize(q);
        for (int r = 0; r < q; ++r) top_derivative(r) = -std::numbers::pi * m * std::sin(std::numbers::pi * m * tau(r));
      }
    } else {
      values = basis.wavelet_basis()->sparse_values(tau, d);
    }
  }

  // Σ_k X(i, k) v_k^{(d)}(τ_q): n × M coefficients → n × Q samples.
  [[nodiscard]] Eigen::MatrixXd to_time(const Eigen::MatrixXd& x) const {
    if (!aft) return (values * x.transpose()).transpose();
    if (derivative == 0) return aft->to_time(x);
    // The derivative's coefficients x D (spectral::FourierBasis::derivative_matrix), and the top
    // function's derivative −πM sin πMτ (not in the basis) added on the samples.
    const Eigen::MatrixXd dx = x * derivative_matrix;
    Eigen::MatrixXd out = aft->to_time(dx);
    if (top_derivative.size() > 0) out += x.col(m - 1) * top_derivative;
    return out;
  }

  // (1/Q) Σ_q S(i, q) v_j^{(d)}(τ_q): n × Q samples → n × M (the Q-point rule for ∫ v_j s dτ).
  // With a selection, only the kept functions' projections (the others 0).
  [[nodiscard]] Eigen::MatrixXd project(const Eigen::MatrixXd& s) const {
    Eigen::MatrixXd out = unselected_projection(s);
    if (keep.size() > 0) out *= keep.asDiagonal();
    return out;
  }
  // The projection on every function, selection or not.
  [[nodiscard]] Eigen::MatrixXd unselected_projection(const Eigen::MatrixXd& s) const {
    if (aft && derivative == 0) return aft->project(s);
    if (aft) throw std::logic_error("SampledBasis::project: derivative samples of a Fourier basis are not projected");
    return Eigen::MatrixXd(s * values) / static_cast<double>(q);
  }

  // project() of samples that are zero but at the times `at`: S(:, at[i]) = x(:, i) (k × |at|),
  // without forming the k × Q samples for wavelets (their sparse rows at those times).
  [[nodiscard]] Eigen::MatrixXd project_at(const std::vector<int>& at, const Eigen::MatrixXd& x) const {
    if (aft) {
      Eigen::MatrixXd samples = Eigen::MatrixXd::Zero(x.rows(), q);
      for (size_t i = 0; i < at.size(); ++i) samples.col(at[i]) = x.col(static_cast<Eigen::Index>(i));
      return project(samples);
    }
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(x.rows(), m);
    for (size_t i = 0; i < at.size(); ++i) {
      for (SparseRows::InnerIterator it(values, at[i]); it; ++it) {
        out.col(it.col()) += (it.value() / q) * x.col(static_cast<Eigen::Index>(i));
      }
    }
    if (keep.size() > 0) out *= keep.asDiagonal();
    return out;
  }
};

double elapsed(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// The continuation of a homotopy in decades of its parameter (κ of the penalty, σ of the contact
// forces), shared by the two homotopies below: λ̂ = λ (decades), the state in `state_scale`
// units, corners restarted (the (·)₊ of a penalty switches at every sample that starts touching).
PseudoArclengthOptions homotopy_continuation(double lambda_min, double lambda_max, double state_scale,
                                             const WeightedResidualOptions& w) {
  PseudoArclengthOptions o;
  o.parameter_min = lambda_min;
  o.parameter_max = lambda_max;
  o.parameter_scale = 1.0;
  o.state_scale = state_scale;
  o.initial_step = 0.05;
  o.max_step = 0.5;
  o.min_step = 1e-9;
  o.kink_step = 1e-6;
  o.corner_restart = true;
  o.max_points = w.homotopy_max_points;
  o.corrector_tolerance = w.newton.tolerance;
  o.initial_newton = w.newton;
  return o;
}

// The homotopy's path in its report: points, folds, iterations, stop, and the largest σ (or κ)
// reached, at most 10^lambda_cap.
void record_homotopy(const Branch& branch, double lambda_cap, HomotopyReport& report) {
  report.points = static_cast<int>(branch.points.size());
  report.folds = static_cast<int>(branch.folds.size());
  report.corrector_iterations = branch.corrector_iterations;
  report.stop = std::string(to_string(branch.stop)) + ": " + branch.message;
  double lambda_max = -std::numeric_limits<double>::infinity();
  for (const auto& bp : branch.points) lambda_max = std::max(lambda_max, bp.parameter);
  report.sigma_reached = branch.points.empty() ? 0.0 : std::pow(10.0, std::min(lambda_max, lambda_cap));
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

struct WeightedResidual::Impl {
  MechanicalSystem system;
  HarmonicForcing forcing;
  std::vector<ContactPoint> contacts;
  TimeBasis trial, weighting;
  WeightedResidualOptions options;
  int n, m, q, nc;
  TimeOperators ops;
  // Transposed time operators A_Mᵀ, A_Cᵀ, A_Kᵀ for the products U Aᵀ of the residual, sparse
  // when at most 25 % full (Fourier:Fourier: diagonal and 2 × 2 blocks; banded wavelet
  // Galerkin operators at large M), so that R(a) costs O(n · nnz) instead of O(n M²).
  struct OperatorProducts {
    std::array<Eigen::SparseMatrix<double>, 3> transposed;
    bool sparse = false;
  };
  std::shared_ptr<const OperatorProducts> operator_products;

  // The trial basis (values and, for ContactQuadrature::CellAverage, first derivatives) and the
  // weighting basis at the Q midpoints τ_q = (q + ½)/Q (SampledBasis: FFTW for Fourier, sparse
  // for wavelets); shared with at_frequency copies (const use only).
  struct Sampling {
    Eigen::VectorXd tau;
    std::shared_ptr<const spectral::Aft> aft;  // when either basis is Fourier
    std::optional<SampledBasis> trial, trial_slope, weighting;
  };
  std::shared_ptr<const Sampling> sampling;
  bool cell_average_rule = false;
  // Harmonic selection (WeightedResidualOptions::harmonics, sorted): keep(k) = 1 if function k's
  // harmonic is kept, else 0 (length M); empty without a selection.
  Eigen::RowVectorXd keep;

  // The rows of V (low_rank_contact_jacobian) of one contact: the trial functions at its samples
  // in contact (by FFTW for a Fourier trial basis, else these sparse rows), then their slopes at
  // its kink samples (CellAverage), from row `first` of V.
  struct ContactRows {
    std::vector<int> active;
    SparseRows values;           // wavelet trial: the rows at the active samples (active × M)
    Eigen::MatrixXd slope_rows;  // trial slopes at the kink samples (sloped × M)
    Eigen::Index first = 0;
  };
  // Y (n_c·M × k, rows x(k·n_c + c)) ↦ V Y (rank × k): LowRankJacobian::times_v. Holds its data.
  struct TrialRows {
    std::shared_ptr<const std::vector<ContactRows>> rows;
    std::shared_ptr<const Sampling> sampling;
    int contacts, dimension;
    Eigen::Index rank;
    Eigen::MatrixXd operator()(const Eigen::MatrixXd& y) const {
      Eigen::MatrixXd out(rank, y.cols());
      Eigen::MatrixXd yc;  // contact c's coefficients (M × k)
      for (int c = 0; c < contacts; ++c) {
        const ContactRows& rc = (*rows)[static_cast<size_t>(c)];
        const auto na = static_cast<Eigen::Index>(rc.active.size());
        if (na == 0 && rc.slope_rows.rows() == 0) continue;
        if (contacts > 1) {
          yc.resize(dimension, y.cols());
          for (int k = 0; k < dimension; ++k) yc.row(k) = y.row(static_cast<Eigen::Index>(k) * contacts + c);
        }
        const Eigen::MatrixXd& yv = contacts > 1 ? yc : y;
        if (na > 0 && sampling->trial->aft) {
          const Eigen::MatrixXd samples = sampling->trial->to_time(yv.transpose()).transpose();  // Q × k
          out.middleRows(rc.first, na) = samples(rc.active, Eigen::all);
        } else if (na > 0) {
          out.middleRows(rc.first, na) = rc.values * yv;
        }
        if (rc.slope_rows.rows() > 0) out.middleRows(rc.first + na, rc.slope_rows.rows()) = rc.slope_rows * yv;
      }
      return out;
    }
  };

  // Linear solves with G (kronecker_factorization.hpp); set up once, factorized per frequency.
  std::optional<detail::KroneckerFactorization> g;
  bool factorized = false;

  Eigen::VectorXd b, a_lin, x_lin;
  // H = P G⁻¹ Pᵀ (n_c·M square), and a sparse copy when at most 25 % of it is nonzero (the 1 × 1
  // and 2 × 2 harmonic blocks of Fourier:Fourier): H N and H n then cost O(nnz(H) · n_c M).
  // Otherwise the structured blocks the factorization kept (circulant, or A_K⁻¹ Σ S with a
  // shift-structured A_K: KroneckerFactorization::compliance_product) when there are any, else
  // the dense product.
  Eigen::MatrixXd h;
  std::shared_ptr<const Eigen::SparseMatrix<double>> h_sparse;  // shared with the Jacobians' products
  bool h_is_sparse = false;
  // Fourier:Fourier: H's blocks commute with time shifts (ShiftKernel), detected per frequency
  // on first use (a Jacobian of low rank), once even if several threads ask.
  struct ShiftKernel {
    std::vector<Eigen::VectorXd> kappa;  // κ_cd(s), s = 0..Q−1, at index c·n_c + d
    Eigen::MatrixXd top;                 // t_cd: H's entry on the top functions cos πMτ (0 for odd M)
    Eigen::VectorXd g;                   // cos πMτ_q (the top function at the samples)
  };
  mutable std::optional<ShiftKernel> kernel;
  mutable std::once_flag kernel_once;
  [[nodiscard]] const std::optional<ShiftKernel>& shift_kernel_once() const {
    std::call_once(kernel_once, [this] { kernel = shift_kernel(); });
    return kernel;
  }
  double scale = 1.0;
  // Row j = k·n_c + c of P (contact c at instant k): its nonzeros (row in a, weight), the
  // direction e_c of ContactPoint::terms() at coefficient k.
  std::vector<detail::StackedTerms> contact_terms;

  // Rigid stops (every contact a RigidStop): the trial functions at τ_{k+1} (M × M, row k: the
  // instant whose gap impulse k keeps open) and the weighting functions at the impulse instants
  // τ_k = (k + ½)/M over M (M × M, row j = function, column k), frequency independent and
  // shared; per frequency the Delassus operator D = V H W, u_lin = V x_lin, and c = mean |D_ii|.
  bool rigid = false;
  struct Collocation {
    Eigen::VectorXd tau;
    Eigen::MatrixXd trial_values, weights;
    Eigen::VectorXd gaps;  // g0 of contact c at row k·n_c + c
  };
  std::shared_ptr<const Collocation> collocation;
  Eigen::MatrixXd delassus;
  Eigen::VectorXd u_lin;
  double force_compliance = 1.0;

  Impl(MechanicalSystem s, HarmonicForcing f, std::vector<ContactPoint> c, TimeBasis tr, TimeBasis we,
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
    if (!(options.residual_tolerance > 0.0)) {
      throw std::invalid_argument("WeightedResidualOptions.residual_tolerance = " +
                                  format_number(options.residual_tolerance) +
                                  ": must be > 0 (a relative bound on the full residual, e.g. 1e-8)");
    }
    if (options.homotopy_max_points < 2) {
      throw std::invalid_argument("WeightedResidualOptions.homotopy_max_points = " +
                                  std::to_string(options.homotopy_max_points) +
                                  ": must be >= 2 (continuation points of the contact homotopy; e.g. 2000)");
    }
    if (options.time_samples < 0 || (options.time_samples > 0 && options.time_samples < m)) {
      throw std::invalid_argument("WeightedResidualOptions.time_samples Q = " + std::to_string(options.time_samples) +
                                  ": must be 0 (automatic, max(256, 2M)) or >= M = " + std::to_string(m));
    }
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
                                  " contacts are rigid stops and the others penalty laws; mixing them in one problem "
                                  "is not supported: make every contact rigid, or give the rigid ones a stiff "
                                  "LinearPenalty");
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
    sampling = smp;
    assemble_time_operators();
    if (keep.size() > 0) require_block_diagonal_operators();
    g.emplace(system, ops, options.linear_solver,
              weighting.is_fourier() && !trial.is_fourier() && options.formulation == Formulation::Distributional);

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

    if (rigid) {
      auto col = std::make_shared<Collocation>();
      col->tau.resize(m);
      for (int k = 0; k < m; ++k) col->tau(k) = (k + 0.5) / m;
      Eigen::VectorXd next(m);  // τ_{k+1}: the instant whose gap λ_k keeps open
      for (int k = 0; k < m; ++k) next(k) = col->tau((k + 1) % m);
      col->trial_values = trial.values(next, 0);
      col->weights = weighting.values(col->tau, 0).transpose() / static_cast<double>(m);
      col->gaps.resize(static_cast<Eigen::Index>(nc) * m);
      for (int k = 0; k < m; ++k) {
        for (int c = 0; c < nc; ++c) col->gaps(static_cast<Eigen::Index>(k) * nc + c) = contacts[c].law->gap();
      }
      collocation = col;
    }

    factorized = g->factorize(system, ops, forcing.frequency_hz);
    if (!factorized) return;
    a_lin = g->solve(b, false);
    x_lin = gather(a_lin);
    if (nc > 0) {
      set_compliance();
      if (rigid) set_delassus(true);
      double gmax = 0.0;
      for (const auto& ct : contacts) gmax = std::max(gmax, std::abs(ct.law->gap()));
      // The larger of the gap and the linear response: a 1 nm gap beside a millimetre motion
      // must not ask Newton for 1e-19 m.
      scale = std::max(gmax, x_lin.lpNorm<Eigen::Infinity>());
      if (!(scale > 0.0) || !std::isfinite(scale)) scale = 1.0;
    }
  }

  // The same problem at another frequency: every frequency-independent member is copied (time
  // operators, samples, b, modal basis, residual scale); only G is factorized again.
  Impl(const Impl& base, double frequency_hz)
      : system(base.system), forcing(base.forcing), contacts(base.contacts), trial(base.trial),
        weighting(base.weighting), options(base.options), n(base.n), m(base.m), q(base.q), nc(base.nc),
        ops(base.ops), operator_products(base.operator_products), sampling(base.sampling),
        cell_average_rule(base.cell_average_rule), keep(base.keep),
        g(base.g->unfactorized()), b(base.b), scale(base.scale),
        contact_terms(base.contact_terms), rigid(base.rigid), collocation(base.collocation) {
    forcing.frequency_hz = frequency_hz;
    forcing.validate(n);
    factorized = g->factorize(system, ops, forcing.frequency_hz);
    if (!factorized) return;
    a_lin = g->solve(b, false);
    x_lin = gather(a_lin);
    if (nc > 0) set_compliance();
    force_compliance = base.force_compliance;  // like s_r: residuals at different f comparable
    if (nc > 0 && rigid) set_delassus(false);
  }

  // Y (M·n_c × k, rows j·n_c + c) ↦ (T ⊗ I_{n_c}) Y for an M × M time matrix T.
  [[nodiscard]] Eigen::MatrixXd per_contact(const Eigen::MatrixXd& t, const Eigen::MatrixXd& y) const {
    if (nc == 1) return t * y;
    Eigen::MatrixXd out(y.rows(), y.cols());
    for (int c = 0; c < nc; ++c) {
      const Eigen::MatrixXd yc = y(Eigen::seq(c, Eigen::last, nc), Eigen::all);
      out(Eigen::seq(c, Eigen::last, nc), Eigen::all) = t * yc;
    }
    return out;
  }

  // D = V H W and u_lin = V x_lin (rigid stops) at this frequency, and c = mean |D_ii| if asked
  // (at the base frequency only; at_frequency copies keep it, as they keep s_r).
  void set_delassus(bool set_force_compliance) {
    const Collocation& col = *collocation;
    const Eigen::Index size = static_cast<Eigen::Index>(nc) * m;
    Eigen::MatrixXd w = Eigen::MatrixXd::Zero(size, size);  // W ⊗ I_{n_c}
    for (int c = 0; c < nc; ++c) w(Eigen::seq(c, Eigen::last, nc), Eigen::seq(c, Eigen::last, nc)) = col.weights;
    delassus = per_contact(col.trial_values, compliance_times(w));
    u_lin = per_contact(col.trial_values, x_lin);
    if (!set_force_compliance) return;
    force_compliance = delassus.diagonal().cwiseAbs().mean();
    if (!(force_compliance > 0.0) || !std::isfinite(force_compliance)) force_compliance = 1.0;
  }

  void require_rigid(const char* what) const {
    if (!rigid) {
      throw std::logic_error(std::string("WeightedResidual::") + what +
                             ": the contacts are penalty laws, not rigid stops (use the contact_* functions)");
    }
  }
  void refuse_rigid(const char* what) const {
    if (rigid) {
      throw std::logic_error(std::string("WeightedResidual::") + what + ": the contacts are rigid stops (" +
                             contacts.front().law->describe() +
                             "), which have no force law f_c(u): use signorini_residual, signorini_jacobian, "
                             "expand_forces and residual(a, lambda)");
    }
  }

  // φ(λ) = min(c λ, g0 − u(λ)) [m] at load s, with the gap samples u(λ) = s u_lin − D λ.
  [[nodiscard]] Eigen::VectorXd signorini(const Eigen::VectorXd& lambda, double load, std::vector<int>* gap_rows) const {
    require_factorized();
    const Eigen::VectorXd gap = collocation->gaps - (load * u_lin - delassus * lambda);
    Eigen::VectorXd phi(gap.size());
    if (gap_rows != nullptr) gap_rows->clear();
    for (Eigen::Index i = 0; i < gap.size(); ++i) {
      const auto cp = contact::signorini_min(force_compliance * lambda(i), gap(i));
      phi(i) = cp.value;
      if (cp.gap_branch && gap_rows != nullptr) gap_rows->push_back(static_cast<int>(i));
    }
    return phi;
  }

  // n(λ) = (W ⊗ I_{n_c}) λ, stacked like x: the weighted residual of the collocation impulses.
  [[nodiscard]] Eigen::VectorXd collocation_forces(const Eigen::VectorXd& lambda) const {
    return per_contact(collocation->weights, lambda);
  }

  void set_compliance() {
    h = g->compliance(contact_directions(), contact_terms);
    const auto nonzeros = (h.array() != 0.0).count();
    h_is_sparse = static_cast<double>(nonzeros) <= 0.25 * static_cast<double>(h.size());
    h_sparse.reset();
    if (h_is_sparse) h_sparse = std::make_shared<const Eigen::SparseMatrix<double>>(h.sparseView());
  }

  // H v for a vector or a matrix v (n_c·M rows, ordering x(k·n_c + c)).
  [[nodiscard]] Eigen::MatrixXd compliance_times(const Eigen::MatrixXd& v) const {
    if (h_is_sparse) return *h_sparse * v;
    if (g->fast_compliance_product()) return g->compliance_product(v);
    return h * v;
  }
  [[nodiscard]] Eigen::VectorXd compliance_times(const Eigen::VectorXd& v) const {
    return compliance_times(Eigen::MatrixXd(v)).col(0);
  }

  // Fourier:Fourier, midpoint rule: when every harmonic h of H_cd couples only its own cos hτ
  // and sin hτ, as the 2 × 2 block [[a_h, b_h], [−b_h, a_h]] (the structure of the exact
  // Galerkin operators: G commutes with time shifts), the kernel of the contact Jacobian is
  //   φ(τ_r)ᵀ H_cd φ(τ_r') = κ_cd(r − r' mod Q) + t_cd cos πMτ_r cos πMτ_r',
  //   κ_cd(s) = H_cd(0, 0) + Σ_h [a_h cos(2πhs/Q) − b_h sin(2πhs/Q)],
  // with t_cd the entry on the top function cos πMτ (M even; it has no sine partner, so it is
  // not shift invariant). The structure is checked on H to 1e-12 of its largest entry; any
  // other coupling (discrete operators, another basis) gives no kernel.
  [[nodiscard]] std::optional<ShiftKernel> shift_kernel() const {
    if (!trial.is_fourier() || !weighting.is_fourier() || cell_average_rule || !h_is_sparse) return std::nullopt;
    const spectral::FourierBasis basis(m);
    const bool top = basis.has_top_function();
    const int harmonics = top ? m / 2 : (m - 1) / 2;
    std::vector<int> cos_index(static_cast<size_t>(harmonics) + 1, -1), sin_index = cos_index;
    for (int k = 0; k < m; ++k) (basis.is_sine(k) ? sin_index : cos_index)[static_cast<size_t>(basis.harmonic(k))] = k;
    const double tol = 1e-12 * h.cwiseAbs().maxCoeff();
    for (Eigen::Index col = 0; col < h_sparse->outerSize(); ++col) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(*h_sparse, col); it; ++it) {
        const int row_harmonic = basis.harmonic(static_cast<int>(it.row() / nc));
        const int col_harmonic = basis.harmonic(static_cast<int>(it.col() / nc));
        if (std::abs(it.value()) > tol && row_harmonic != col_harmonic) return std::nullopt;
      }
    }
    const int paired = top ? harmonics - 1 : harmonics;
    ShiftKernel k;
    k.kappa.resize(static_cast<size_t>(nc) * nc);
    k.top = Eigen::MatrixXd::Zero(nc, nc);
    k.g = Eigen::VectorXd::Zero(q);
    Eigen::VectorXd cos_table(q), sin_table(q);
    for (int i = 0; i < q; ++i) {
      cos_table(i) = std::cos(2.0 * std::numbers::pi * i / q);
      sin_table(i) = std::sin(2.0 * std::numbers::pi * i / q);
    }
    if (top) {
      for (int r = 0; r < q; ++r) k.g(r) = basis.value(m - 1, sampling->tau(r));
    }
    auto at = [&](int kr, int c, int kc, int d) {  // H(k_r·n_c + c, k_c·n_c + d)
      return h(static_cast<Eigen::Index>(kr) * nc + c, static_cast<Eigen::Index>(kc) * nc + d);
    };
    for (int c = 0; c < nc; ++c) {
      for (int d = 0; d < nc; ++d) {
        // With a selection, W = Π W: only the kept harmonics enter the kernel.
        const auto kept = [&](int k) { return keep.size() == 0 || keep(k) != 0.0; };
        Eigen::VectorXd kappa = Eigen::VectorXd::Constant(q, kept(0) ? at(0, c, 0, d) : 0.0);
        for (int hh = 1; hh <= paired; ++hh) {
          if (!kept(cos_index[static_cast<size_t>(hh)])) continue;
          const int ci = cos_index[static_cast<size_t>(hh)], si = sin_index[static_cast<size_t>(hh)];
          const double a = at(ci, c, ci, d), b = at(ci, c, si, d);
          if (std::abs(a - at(si, c, si, d)) > tol || std::abs(b + at(si, c, ci, d)) > tol) return std::nullopt;
          for (int sft = 0, index = 0; sft < q; ++sft) {  // index = h·s mod Q
            kappa(sft) += a * cos_table(index) - b * sin_table(index);
            index += hh;
            if (index >= q) index -= q;
          }
        }
        if (top && kept(m - 1)) k.top(c, d) = at(m - 1, c, m - 1, d);
        k.kappa[static_cast<size_t>(c) * nc + d] = std::move(kappa);
      }
    }
    return k;
  }

  // WeightedResidualOptions::harmonics: validated, sorted, and the mask `keep` built.
  void select_harmonics() {
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

  // A selection projects the weighting functions only; that is the Galerkin projection on the
  // kept span only if no time operator couples a kept function with a dropped one. True for the
  // analytic Fourier operators and for discrete ones on Q ≥ M midpoints (products of harmonics
  // up to M − 1 are integrated exactly); checked, as an invariant, in case that ever changes.
  void require_block_diagonal_operators() const {
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

  [[nodiscard]] std::vector<std::vector<std::pair<int, double>>> contact_directions() const {
    std::vector<std::vector<std::pair<int, double>>> d;
    for (const auto& c : contacts) d.push_back(c.terms());
    return d;
  }

  // v += s Pᵀ x: each contact unknown spread over its direction's rows.
  void scatter(Eigen::VectorXd& v, const Eigen::VectorXd& x, double s) const {
    for (size_t j = 0; j < contact_terms.size(); ++j) {
      for (const auto& [row, w] : contact_terms[j]) v(row) += s * w * x(static_cast<Eigen::Index>(j));
    }
  }

  // G⁻¹ v (or G⁻ᵀ v) for a stacked v of length n·M.
  [[nodiscard]] Eigen::VectorXd solve_stacked(const Eigen::VectorXd& v, bool transposed) const {
    return g->solve(v, transposed);
  }

  void set_operator_products() {
    auto products = std::make_shared<OperatorProducts>();
    const Eigen::MatrixXd* a[3] = {&ops.mass, &ops.damping, &ops.stiffness};
    Eigen::Index nonzeros = 0;
    for (const auto* op : a) nonzeros += (op->array() != 0.0).count();
    products->sparse = static_cast<double>(nonzeros) <= 0.25 * 3.0 * static_cast<double>(m) * m;
    if (products->sparse) {
      for (int t = 0; t < 3; ++t) products->transposed[static_cast<size_t>(t)] = a[t]->transpose().sparseView();
    }
    operator_products = products;
  }

  // X U Aᵀ for the n × M coefficients U and operator t (0: A_M, 1: A_C, 2: A_K).
  [[nodiscard]] Eigen::MatrixXd operator_product(const Eigen::SparseMatrix<double>& x, const Eigen::MatrixXd& u,
                                                 int t) const {
    const Eigen::MatrixXd xu = x * u;
    if (operator_products->sparse) return xu * operator_products->transposed[static_cast<size_t>(t)];
    const Eigen::MatrixXd* a[3] = {&ops.mass, &ops.damping, &ops.stiffness};
    return xu * a[t]->transpose();
  }

  // [JL14 Eqs. (14)–(16)]: exactly (connection coefficients, analytic Fourier) or by the Q-point
  // rule A = (sign/Q) Σ_q p^{(dw)}(τ_q) q^{(dt)}(τ_q)ᵀ. The discrete rule exploits the bases:
  //  - Fourier weighting, wavelet trial: A^{(0)} = (1/Q) Σ_q p(τ_q) q^{(dt)}(τ_q)ᵀ by one FFTW
  //    projection per trial function (O(M Q log Q)); the weighting's derivatives stay in the
  //    basis, row(cos ωτ)' = −ω row(sin ωτ), row(sin ωτ)' = ω row(cos ωτ), row'' = −ω² row,
  //    except the first derivative of the top function cos πMτ, summed directly;
  //  - two wavelet bases: sparse products of their sample matrices;
  //  - otherwise (Fourier trial with OperatorRule::Discrete): dense values, O(Q M²).
  void assemble_time_operators() {
    const auto ts = terms(options.formulation);
    const bool exact = exact_rule(trial, weighting, options.operators);
    const Eigen::VectorXd& tau = sampling->tau;
    std::array<Eigen::MatrixXd, 3> a;
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
        a[t] = Eigen::MatrixXd(trial.exact_operator(term.weighting, term.trial));
        a[t] *= term.sign;
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
        a[t] = (term.sign / q) * Eigen::MatrixXd(Eigen::SparseMatrix<double>(w.transpose()) * Eigen::SparseMatrix<double>(v));
      } else {
        if (pw[term.weighting].size() == 0) pw[term.weighting] = weighting.values(tau, term.weighting);
        if (qt[term.trial].size() == 0) qt[term.trial] = trial.values(tau, term.trial);
        a[t] = (term.sign / q) * (pw[term.weighting].transpose() * qt[term.trial]);
      }
    }
    ops.mass = std::move(a[0]);
    ops.damping = std::move(a[1]);
    ops.stiffness = std::move(a[2]);
    set_operator_products();
    ops.rule = exact ? (trial.is_fourier() ? "exact (analytic)" : "exact (connection coefficients)")
                     : "discrete, Q = " + std::to_string(q) + " midpoints";
  }

  // (1/Q) Σ_q p_j^{(dw)}(τ_q) v_k(τ_q) from base(j, k) = (1/Q) Σ_q p_j(τ_q) v_k(τ_q) for the
  // Fourier weighting functions p_j (FourierBasis ordering) and the samples v (Q × M).
  [[nodiscard]] Eigen::MatrixXd fourier_weighting_derivative(const Eigen::MatrixXd& base, int dw, const SparseRows& v) const {
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

  [[nodiscard]] Eigen::VectorXd gather(const Eigen::VectorXd& a) const {  // P a
    Eigen::VectorXd x = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(contact_terms.size()));
    for (size_t j = 0; j < contact_terms.size(); ++j) {
      for (const auto& [row, w] : contact_terms[j]) x(static_cast<Eigen::Index>(j)) += w * a(row);
    }
    return x;
  }

  // Contact displacement samples U (n_c × Q) for stacked contact unknowns x.
  [[nodiscard]] Eigen::MatrixXd contact_samples(const Eigen::VectorXd& x) const {
    return sampling->trial->to_time(spectral::as_coefficients(x, nc));
  }

  // block(j, k) = (1/Q) Σ_q p_j(τ_q) κ_q q_k(τ_q) over the samples with κ_q ≠ 0 (`active`): the
  // contact Jacobian of one contact. Fourier:Fourier by Aft::jacobian (O(Q log Q + M²)); one
  // Fourier basis by one FFTW projection per function of the other (O(M Q log Q)); two wavelet
  // bases by their sparse rows (O(active · support²)).
  [[nodiscard]] Eigen::MatrixXd contact_block(const Eigen::VectorXd& kc, const std::vector<int>& active) const {
    const Sampling& smp = *sampling;
    if (trial.is_fourier() && weighting.is_fourier()) {
      if (keep.size() == 0) return smp.aft->jacobian(kc);
      return keep.transpose().asDiagonal() * smp.aft->jacobian(kc);  // rows: the weighting functions kept
    }
    if (weighting.is_fourier() || trial.is_fourier()) {
      const SparseRows& v = weighting.is_fourier() ? smp.trial->values : smp.weighting->values;
      Eigen::MatrixXd samples = Eigen::MatrixXd::Zero(m, q);  // S(k, q) = κ_q v_k(τ_q)
      for (int r : active) {
        for (SparseRows::InnerIterator it(v, r); it; ++it) samples(it.col(), r) = kc(r) * it.value();
      }
      const Eigen::MatrixXd p = smp.aft->project(samples);  // (1/Q) Σ_q S(k, q) f_l(τ_q), f the Fourier basis
      return weighting.is_fourier() ? Eigen::MatrixXd(p.transpose()) : p;
    }
    Eigen::MatrixXd block = Eigen::MatrixXd::Zero(m, m);
    const SparseRows& w = smp.weighting->values;
    const SparseRows& v = smp.trial->values;
    double loop_cost = 0.0;  // multiply-adds of the loops over the rows' nonzeros
    for (int r : active) loop_cost += static_cast<double>(w.outerIndexPtr()[r + 1] - w.outerIndexPtr()[r]) *
                                      static_cast<double>(v.outerIndexPtr()[r + 1] - v.outerIndexPtr()[r]);
    if (loop_cost > static_cast<double>(active.size()) * m * m / 8.0) {
      // Wide supports (the orthogonal B-spline's decays exponentially but spans the period at
      // small M): a dense product of the active rows, blocked, is faster than scalar loops.
      Eigen::MatrixXd wa(static_cast<Eigen::Index>(active.size()), m), va(wa.rows(), m);
      for (size_t i = 0; i < active.size(); ++i) {
        wa.row(static_cast<Eigen::Index>(i)) = w.row(active[i]) * (kc(active[i]) / q);
        va.row(static_cast<Eigen::Index>(i)) = v.row(active[i]);
      }
      block.noalias() = wa.transpose() * va;
      return block;
    }
    for (int r : active) {
      for (SparseRows::InnerIterator wj(w, r); wj; ++wj) {
        const double wk = wj.value() * kc(r) / q;
        for (SparseRows::InnerIterator vk(v, r); vk; ++vk) block(wj.col(), vk.col()) += wk * vk.value();
      }
    }
    return block;
  }

  // The contact law's derivatives at the samples of one contact: ∂f/∂u (kc) and, for
  // CellAverage, ∂f̄/∂δ (kd), with the samples where each is nonzero.
  struct ContactTangent {
    Eigen::VectorXd kc, kd;
    std::vector<int> active, sloped;
  };

  // n_c(x) = (1/Q) Σ_q p(τ_q) f_c(u_c(τ_q)) stacked like x (f̄_q for CellAverage); optionally
  // the law's derivatives at the samples, one ContactTangent per contact.
  Eigen::VectorXd contact_forces(const Eigen::VectorXd& x, std::vector<ContactTangent>* tangents) const {
    return spectral::stacked(sampling->weighting->project(contact_force_samples(x, tangents)));
  }

  // f_c(u_c(τ_q)) (f̄_q for CellAverage), n_c × Q, and optionally the tangents.
  Eigen::MatrixXd contact_force_samples(const Eigen::VectorXd& x, std::vector<ContactTangent>* tangents) const {
    refuse_rigid("contact forces as a function of the displacement");
    const Sampling& smp = *sampling;
    const Eigen::MatrixXd u = contact_samples(x);
    Eigen::MatrixXd slope;  // δ_q = u̇_c(τ_q)/Q, CellAverage only
    if (cell_average_rule) slope = smp.trial_slope->to_time(spectral::as_coefficients(x, nc)) / static_cast<double>(q);
    Eigen::MatrixXd force(nc, q);
    if (tangents != nullptr) tangents->assign(static_cast<size_t>(nc), {});
    Eigen::VectorXd fc(q), kc(q), kd = Eigen::VectorXd::Zero(q);  // f, ∂f/∂u, ∂f/∂δ per sample
    for (int c = 0; c < nc; ++c) {
      if (cell_average_rule) {
        for (int r = 0; r < q; ++r) cell_average(*contacts[c].law, u(c, r), slope(c, r), fc(r), kc(r), kd(r));
      } else {
        contacts[c].law->evaluate(u.row(c).transpose(), fc, kc);
      }
      force.row(c) = fc.transpose();
      if (tangents == nullptr) continue;
      ContactTangent& t = (*tangents)[static_cast<size_t>(c)];
      for (int r = 0; r < q; ++r) {
        if (kc(r) != 0.0) t.active.push_back(r);
        if (kd(r) != 0.0) t.sloped.push_back(r);
      }
      t.kc = kc;
      t.kd = kd;
    }
    return force;
  }

  // N(x) = ∂n_c/∂x (n_c·M square, dense) from the tangents.
  [[nodiscard]] Eigen::MatrixXd contact_force_jacobian(const std::vector<ContactTangent>& tangents) const {
    Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(nc * m, nc * m);
    for (int c = 0; c < nc; ++c) {
      const ContactTangent& t = tangents[static_cast<size_t>(c)];
      Eigen::MatrixXd block = t.active.empty() ? Eigen::MatrixXd::Zero(m, m) : contact_block(t.kc, t.active);
      if (!t.sloped.empty()) {
        // CellAverage: + Σ_q p_j(τ_q)/Q ∂f̄/∂δ q̇_k(τ_q)/Q over the samples whose cell meets the
        // law's kink (a few per crossing): their rows are evaluated here.
        const auto [ts, ks] = sloped_samples(t);
        block.noalias() += (ks.asDiagonal() * weighting_values(ts)).transpose() * trial.values(ts, 1);
      }
      for (int k = 0; k < m; ++k) {
        for (int j = 0; j < m; ++j) jac(j * nc + c, k * nc + c) = block(j, k);
      }
    }
    return jac;
  }

  // I + H N (n_c·M square, dense): s_r times the condensed Jacobian.
  [[nodiscard]] Eigen::MatrixXd identity_plus_hn(const std::vector<ContactTangent>& tangents) const {
    Eigen::MatrixXd j = compliance_times(contact_force_jacobian(tangents));
    j.diagonal().array() += 1.0;
    return j;
  }

  // The weighting functions at τ (rows = times), the dropped ones of a selection as 0.
  [[nodiscard]] Eigen::MatrixXd weighting_values(const Eigen::VectorXd& tau) const {
    Eigen::MatrixXd v = weighting.values(tau, 0);
    if (keep.size() > 0) v *= keep.asDiagonal();
    return v;
  }

  // The times τ_q and weights ∂f̄/∂δ / Q² of the CellAverage kink terms of one contact.
  [[nodiscard]] std::pair<Eigen::VectorXd, Eigen::VectorXd> sloped_samples(const ContactTangent& t) const {
    Eigen::VectorXd ts(static_cast<Eigen::Index>(t.sloped.size())), ks(ts.size());
    for (size_t i = 0; i < t.sloped.size(); ++i) {
      ts(static_cast<Eigen::Index>(i)) = sampling->tau(t.sloped[i]);
      ks(static_cast<Eigen::Index>(i)) = t.kd(t.sloped[i]) / (static_cast<double>(q) * q);
    }
    return {ts, ks};
  }

  // The condensed Jacobian (I + H N)/s_r with N = W V of rank r = Σ_c (active + sloped samples):
  // column i of W (n_c·M × r) is the weighting functions at the sample times κ_q/Q (or
  // ∂f̄/∂δ/Q² for a kink term), row i of V (r × n_c·M) the trial functions (or their slopes) at
  // the same time, both on the rows x(k·n_c + c) of their contact. With U = H W and
  // C = I_r + V U, Newton's step is an r × r solve (WoodburyLu). V is applied by FFTW for a
  // Fourier trial basis (all Q samples, the active ones kept) and by the sparse rows of the
  // wavelets otherwise. When r > ¾ n_c·M the dense form (I + H N) is factorized instead: an
  // r × r LU then saves less than the two products with V cost (bench_weighted_residual).
  [[nodiscard]] LowRankJacobian low_rank_contact_jacobian(const Eigen::VectorXd& x) const {
    std::vector<ContactTangent> tangents;
    (void)contact_forces(x, &tangents);
    LowRankJacobian jac;
    jac.scale = scale;
    Eigen::Index rank = 0;
    for (const auto& t : tangents) rank += static_cast<Eigen::Index>(t.active.size() + t.sloped.size());
    const Eigen::Index size = static_cast<Eigen::Index>(nc) * m;
    jac.rows = size;
    if (4 * rank > 3 * size) {
      jac.capacitance = identity_plus_hn(tangents);
      return jac;
    }
    if (shift_kernel_once()) return shift_kernel_jacobian(tangents, std::move(jac), rank);
    auto rows = std::make_shared<std::vector<ContactRows>>(static_cast<size_t>(nc));
    Eigen::MatrixXd w = Eigen::MatrixXd::Zero(size, rank);
    Eigen::Index first = 0;
    for (int c = 0; c < nc; ++c) {
      const ContactTangent& t = tangents[static_cast<size_t>(c)];
      ContactRows& rc = (*rows)[static_cast<size_t>(c)];
      rc.first = first;
      rc.active = t.active;
      const auto na = static_cast<Eigen::Index>(t.active.size());
      if (na > 0) {
        // Row i: κ_q p_j(τ_q)/Q at the active sample q = active[i].
        Eigen::VectorXd kc(na);
        for (Eigen::Index i = 0; i < na; ++i) kc(i) = t.kc(t.active[static_cast<size_t>(i)]);
        const Eigen::MatrixXd wa = sampling->weighting->project_at(t.active, kc.asDiagonal().toDenseMatrix());
        for (int j = 0; j < m; ++j) w.block(static_cast<Eigen::Index>(j) * nc + c, first, 1, na) = wa.col(j).transpose();
        if (!trial.is_fourier()) {
          const SparseRows& sv = sampling->trial->values;
          std::vector<Eigen::Triplet<double>> triplets;
          for (Eigen::Index i = 0; i < na; ++i) {
            for (SparseRows::InnerIterator it(sv, t.active[static_cast<size_t>(i)]); it; ++it) {
              triplets.emplace_back(static_cast<int>(i), static_cast<int>(it.col()), it.value());
            }
          }
          rc.values.resize(na, m);
          rc.values.setFromTriplets(triplets.begin(), triplets.end());
        }
      }
      if (!t.sloped.empty()) {
        const auto [ts, ks] = sloped_samples(t);
        const Eigen::MatrixXd ws = ks.asDiagonal() * weighting_values(ts);
        for (int j = 0; j < m; ++j) {
          w.block(static_cast<Eigen::Index>(j) * nc + c, first + na, 1, ws.rows()) = ws.col(j).transpose();
        }
        rc.slope_rows = trial.values(ts, 1);
      }
      first += na + static_cast<Eigen::Index>(t.sloped.size());
    }
    jac.times_v = TrialRows{rows, sampling, nc, m, rank};
    jac.u = compliance_times(w);
    jac.capacitance = jac.times_v(jac.u);
    jac.capacitance.diagonal().array() += 1.0;
    return jac;
  }

  // The low-rank Jacobian of Fourier:Fourier through its ShiftKernel: C is gathered from κ_cd
  // and t_cd in O(r²) (no product with V), U is never formed: U Z = H W Z with W Z one FFTW
  // projection of Z's rows placed at their samples, times the sparse H. V by FFTW, as above.
  [[nodiscard]] LowRankJacobian shift_kernel_jacobian(const std::vector<ContactTangent>& tangents, LowRankJacobian jac,
                                                      Eigen::Index rank) const {
    struct Sample {
      int contact, index;
      double stiffness;
    };
    auto samples = std::make_shared<std::vector<Sample>>();
    samples->reserve(static_cast<size_t>(rank));
    for (int c = 0; c < nc; ++c) {
      const ContactTangent& t = tangents[static_cast<size_t>(c)];
      for (int r : t.active) samples->push_back({c, r, t.kc(r)});
    }
    const ShiftKernel& k = *kernel;
    jac.capacitance.resize(rank, rank);
    for (Eigen::Index j = 0; j < rank; ++j) {
      const Sample& sj = (*samples)[static_cast<size_t>(j)];
      const double weight = sj.stiffness / q;
      for (Eigen::Index i = 0; i < rank; ++i) {
        const Sample& si = (*samples)[static_cast<size_t>(i)];
        const int shift = si.index >= sj.index ? si.index - sj.index : si.index - sj.index + q;
        jac.capacitance(i, j) = (k.kappa[static_cast<size_t>(si.contact) * nc + sj.contact](shift) +
                                 k.top(si.contact, sj.contact) * k.g(si.index) * k.g(sj.index)) * weight;
      }
      jac.capacitance(j, j) += 1.0;
    }
    auto rows = std::make_shared<std::vector<ContactRows>>(static_cast<size_t>(nc));
    Eigen::Index first = 0;
    for (int c = 0; c < nc; ++c) {
      ContactRows& rc = (*rows)[static_cast<size_t>(c)];
      rc.first = first;
      rc.active = tangents[static_cast<size_t>(c)].active;
      first += static_cast<Eigen::Index>(rc.active.size());
    }
    jac.times_v = TrialRows{rows, sampling, nc, m, rank};
    const std::shared_ptr<const Sampling> smp = sampling;
    const std::shared_ptr<const Eigen::SparseMatrix<double>> hs = h_sparse;
    const int contacts_n = nc, dimension = m;
    jac.times_u = [samples, rows, smp, hs, contacts_n, dimension](const Eigen::MatrixXd& z) {
      // W Z: per contact, the rows of Z times κ_q placed at their samples, projected.
      Eigen::MatrixXd wz(static_cast<Eigen::Index>(contacts_n) * dimension, z.cols());
      for (int c = 0; c < contacts_n; ++c) {
        const ContactRows& rc = (*rows)[static_cast<size_t>(c)];
        const auto na = static_cast<Eigen::Index>(rc.active.size());
        Eigen::MatrixXd x(z.cols(), na);  // k × active
        for (Eigen::Index i = 0; i < na; ++i) {
          x.col(i) = (*samples)[static_cast<size_t>(rc.first + i)].stiffness * z.row(rc.first + i).transpose();
        }
        const Eigen::MatrixXd projected = smp->weighting->project_at(rc.active, x);  // k × M
        for (int l = 0; l < dimension; ++l) wz.row(static_cast<Eigen::Index>(l) * contacts_n + c) = projected.col(l).transpose();
      }
      return Eigen::MatrixXd(*hs * wz);
    };
    return jac;
  }

  [[nodiscard]] Eigen::VectorXd contact_residual(const Eigen::VectorXd& x, double load) const {
    refuse_rigid("contact_residual");
    require_factorized();
    return (x - load * x_lin + compliance_times(contact_forces(x, nullptr))) / scale;
  }

  // What makes G singular, in words (model_checks.hpp), or the generic reasons.
  [[nodiscard]] std::string singular_reason() const {
    const std::string why = explain_singular_dynamic_stiffness(system, forcing.frequency_hz, highest_resolved_harmonic(m));
    return why.empty() ? "no rigid-body mode, overflow or undamped resonance found; G is singular to working precision "
                         "(check the scale of M, C and K)"
                       : why;
  }

  void require_factorized() const {
    if (!factorized) {
      std::ostringstream os;
      os << "weighted residual " << trial.name() << ":" << weighting.name() << ": the linear operator G is singular at f = "
         << forcing.frequency_hz << " Hz: " << singular_reason();
      throw std::runtime_error(os.str());
    }
  }
};

WeightedResidual::WeightedResidual(MechanicalSystem system, HarmonicForcing forcing,
                                   std::vector<ContactPoint> contacts, TimeBasis trial, TimeBasis weighting,
                                   WeightedResidualOptions options)
    : impl_(std::make_unique<Impl>(std::move(system), forcing, std::move(contacts), std::move(trial),
                                   std::move(weighting), options)) {}
WeightedResidual::~WeightedResidual() = default;
WeightedResidual::WeightedResidual(WeightedResidual&&) noexcept = default;
WeightedResidual& WeightedResidual::operator=(WeightedResidual&&) noexcept = default;

int WeightedResidual::dofs() const { return impl_->n; }
int WeightedResidual::dimension() const { return impl_->m; }
int WeightedResidual::time_samples() const { return impl_->q; }
const MechanicalSystem& WeightedResidual::system() const { return impl_->system; }
const HarmonicForcing& WeightedResidual::forcing() const { return impl_->forcing; }
const std::vector<ContactPoint>& WeightedResidual::contacts() const { return impl_->contacts; }
const TimeBasis& WeightedResidual::trial() const { return impl_->trial; }
const TimeBasis& WeightedResidual::weighting() const { return impl_->weighting; }
Formulation WeightedResidual::formulation() const { return impl_->options.formulation; }
const TimeOperators& WeightedResidual::time_operators() const { return impl_->ops; }
std::string WeightedResidual::linear_solver() const { return impl_->g->modal() ? "modal" : "sparse-lu"; }

std::string WeightedResidual::describe() const {
  std::string d = impl_->trial.name() + ":" + impl_->weighting.name() + ", " + std::string(to_string(formulation()));
  if (!impl_->options.harmonics.empty()) {
    d += ", harmonics";
    for (size_t i = 0; i < impl_->options.harmonics.size(); ++i) {
      d.append(i == 0 ? " " : ", ").append(std::to_string(impl_->options.harmonics[i]));
    }
    d += " only";
  }
  return d;
}

double WeightedResidual::condition_number() const {
  const auto& p = *impl_;
  if (!p.factorized) return std::numeric_limits<double>::infinity();
  // ‖G‖₁ from the Kronecker factors or the assembled G; ‖G⁻¹‖₁ by Hager–Higham (a few solves with G and Gᵀ through the factorization in use).
  const double inverse_norm = detail::inverse_one_norm_estimate(
      static_cast<Eigen::Index>(p.n) * p.m,
      [&](const Eigen::VectorXd& v, bool transposed) { return p.solve_stacked(v, transposed); });
  return p.g->norm1(p.system, p.ops) * inverse_norm;
}

Eigen::VectorXd WeightedResidual::residual(const Eigen::VectorXd& a) const {
  const auto& p = *impl_;
  const auto u = spectral::as_coefficients(a, p.n);
  const double fr = p.forcing.frequency_hz;
  // (T ⊗ X) vec(U) = vec(X U Tᵀ), layout.hpp.
  const Eigen::MatrixXd gu = fr * fr * p.operator_product(p.system.mass, u, 0) +
                             fr * p.operator_product(p.system.damping, u, 1) +
                             p.operator_product(p.system.stiffness, u, 2);
  Eigen::VectorXd r = spectral::stacked(gu) - p.b;
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(p.gather(a), nullptr);
    p.scatter(r, nx, 1.0);
  }
  return r;
}

Eigen::MatrixXd WeightedResidual::jacobian(const Eigen::VectorXd& a) const {
  const auto& p = *impl_;
  const double fr = p.forcing.frequency_hz;
  Eigen::MatrixXd jac = Eigen::kroneckerProduct(fr * fr * p.ops.mass, Eigen::MatrixXd(p.system.mass)) +
                        Eigen::kroneckerProduct(fr * p.ops.damping, Eigen::MatrixXd(p.system.damping)) +
                        Eigen::kroneckerProduct(p.ops.stiffness, Eigen::MatrixXd(p.system.stiffness));
  if (p.nc > 0) {
    std::vector<Impl::ContactTangent> tangents;
    (void)p.contact_forces(p.gather(a), &tangents);
    const Eigen::MatrixXd nj = p.contact_force_jacobian(tangents);
    // Pᵀ N P with P's rows the contact directions.
    for (size_t i = 0; i < p.contact_terms.size(); ++i) {
      for (size_t j = 0; j < p.contact_terms.size(); ++j) {
        const double v = nj(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
        if (v == 0.0) continue;
        for (const auto& [ri, wi] : p.contact_terms[i]) {
          for (const auto& [rj, wj] : p.contact_terms[j]) jac(ri, rj) += wi * v * wj;
        }
      }
    }
  }
  return jac;
}

Eigen::VectorXd WeightedResidual::linear_response() const {
  impl_->require_factorized();
  return impl_->a_lin;
}

Eigen::VectorXd WeightedResidual::contact_unknowns(const Eigen::VectorXd& a) const { return impl_->gather(a); }

const std::vector<int>& WeightedResidual::harmonics() const { return impl_->options.harmonics; }

double WeightedResidual::dropped_harmonics_residual(const Eigen::VectorXd& x, double load) const {
  const auto& p = *impl_;
  if (p.keep.size() == 0) return std::numeric_limits<double>::quiet_NaN();
  p.require_factorized();
  if (p.nc == 0) return 0.0;
  if (x.size() != static_cast<Eigen::Index>(p.nc) * p.m) {
    throw std::invalid_argument("WeightedResidual::dropped_harmonics_residual: x has length " + std::to_string(x.size()) +
                                ", expected n_c*M = " + std::to_string(p.nc * p.m));
  }
  // G a − b vanishes on the dropped functions (G is block-diagonal by harmonic, a and b are in
  // the kept span): (I − Π) R = (I − Π) Pᵀ n(a), the contact forces' projection there.
  Eigen::MatrixXd dropped = p.sampling->weighting->unselected_projection(p.contact_force_samples(x, nullptr));
  dropped *= (Eigen::RowVectorXd::Ones(p.m) - p.keep).asDiagonal();
  Eigen::VectorXd r = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(p.n) * p.m);
  p.scatter(r, spectral::stacked(dropped), 1.0);
  const double bnorm = std::abs(load) * p.b.norm();
  return r.norm() / (bnorm > 0.0 ? bnorm : 1.0);
}

Eigen::VectorXd WeightedResidual::contact_residual(const Eigen::VectorXd& x, double load) const {
  return impl_->contact_residual(x, load);
}

WeightedResidual::WeightedResidual(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

WeightedResidual WeightedResidual::at_frequency(double frequency_hz) const {
  if (!(frequency_hz > 0.0) || !std::isfinite(frequency_hz)) {
    throw std::invalid_argument("WeightedResidual::at_frequency: f = " + format_number(frequency_hz) +
                                " Hz; must be > 0 and finite");
  }
  return WeightedResidual(std::make_unique<Impl>(*impl_, frequency_hz));
}

double WeightedResidual::frequency_hz() const { return impl_->forcing.frequency_hz; }
double WeightedResidual::residual_scale() const { return impl_->scale; }

Eigen::VectorXd WeightedResidual::contact_residual_frequency_derivative(const Eigen::VectorXd& x, double load) const {
  const auto& p = *impl_;
  p.require_factorized();
  Eigen::VectorXd rhs = load * p.b;
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(x, nullptr);
    p.scatter(rhs, nx, -1.0);
  }
  const Eigen::MatrixXd a = spectral::as_coefficients(p.solve_stacked(rhs, false), p.n);  // n × M
  // G′ a with G′ = 2f A_M ⊗ M + A_C ⊗ C: (T ⊗ S) a ↔ S A Tᵀ on the n × M coefficients.
  const double f = p.forcing.frequency_hz;
  const Eigen::MatrixXd ga = 2.0 * f * p.operator_product(p.system.mass, a, 0) + p.operator_product(p.system.damping, a, 1);
  return p.gather(p.solve_stacked(spectral::stacked(ga), false)) / p.scale;
}

Eigen::MatrixXd WeightedResidual::contact_jacobian(const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  p.require_factorized();
  std::vector<Impl::ContactTangent> tangents;
  (void)p.contact_forces(x, &tangents);
  return p.identity_plus_hn(tangents) / p.scale;
}

LowRankJacobian WeightedResidual::contact_jacobian_low_rank(const Eigen::VectorXd& x) const {
  impl_->require_factorized();
  return impl_->low_rank_contact_jacobian(x);
}

Eigen::VectorXd WeightedResidual::expand(const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  p.require_factorized();
  Eigen::VectorXd rhs = p.b;
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(x, nullptr);
    p.scatter(rhs, nx, -1.0);
  }
  return p.solve_stacked(rhs, false);
}

bool WeightedResidual::rigid() const { return impl_->rigid; }
ContactQuadrature WeightedResidual::contact_quadrature() const {
  return impl_->cell_average_rule ? ContactQuadrature::CellAverage : ContactQuadrature::Midpoint;
}

Eigen::VectorXd WeightedResidual::collocation_times() const {
  impl_->require_rigid("collocation_times");
  return impl_->collocation->tau;
}

const Eigen::MatrixXd& WeightedResidual::delassus() const {
  impl_->require_rigid("delassus");
  impl_->require_factorized();
  return impl_->delassus;
}

double WeightedResidual::force_compliance() const {
  impl_->require_rigid("force_compliance");
  impl_->require_factorized();
  return impl_->force_compliance;
}

Eigen::VectorXd WeightedResidual::signorini_residual(const Eigen::VectorXd& lambda, double load) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_residual");
  if (lambda.size() != static_cast<Eigen::Index>(p.nc) * p.m) {
    throw std::invalid_argument("WeightedResidual::signorini_residual: lambda has length " + std::to_string(lambda.size()) +
                                ", expected n_c*M = " + std::to_string(p.nc * p.m));
  }
  return p.signorini(lambda, load, nullptr) / p.scale;
}

LowRankJacobian WeightedResidual::signorini_jacobian(const Eigen::VectorXd& lambda) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_jacobian");
  std::vector<int> active;
  (void)p.signorini(lambda, 1.0, &active);
  const Eigen::Index size = lambda.size();
  const auto rank = static_cast<Eigen::Index>(active.size());
  const double c = p.force_compliance;
  LowRankJacobian jac;
  jac.scale = p.scale / c;  // J = (c/s_r)(I + P_A (D/c − I)_A)
  jac.rows = size;
  if (4 * rank > 3 * size) {  // dense form: s J = I with the gap rows replaced by D/c
    jac.capacitance = Eigen::MatrixXd::Identity(size, size);
    for (int i : active) jac.capacitance.row(i) = p.delassus.row(i) / c;
    return jac;
  }
  jac.u = Eigen::MatrixXd::Zero(size, rank);
  for (Eigen::Index i = 0; i < rank; ++i) jac.u(active[static_cast<size_t>(i)], i) = 1.0;
  auto rows = std::make_shared<Eigen::MatrixXd>(p.delassus(active, Eigen::all) / c);  // (D/c)_A, r × n
  for (Eigen::Index i = 0; i < rank; ++i) (*rows)(i, active[static_cast<size_t>(i)]) -= 1.0;
  jac.capacitance = p.delassus(active, active) / c;  // I + (D/c − I)_AA
  jac.times_v = [rows](const Eigen::MatrixXd& y) { return Eigen::MatrixXd(*rows * y); };
  return jac;
}

Eigen::VectorXd WeightedResidual::signorini_frequency_derivative(const Eigen::VectorXd& lambda, double load) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_frequency_derivative");
  std::vector<int> gap_rows;
  (void)p.signorini(lambda, load, &gap_rows);
  const Eigen::MatrixXd a = spectral::as_coefficients(expand_forces(lambda, load), p.n);  // n × M
  // G′ a with G′ = 2f A_M ⊗ M + A_C ⊗ C, then P G⁻¹, then the trial values at τ_{k+1}.
  const double f = p.forcing.frequency_hz;
  const Eigen::MatrixXd ga = 2.0 * f * p.operator_product(p.system.mass, a, 0) + p.operator_product(p.system.damping, a, 1);
  const Eigen::VectorXd du = p.per_contact(p.collocation->trial_values, p.gather(p.solve_stacked(spectral::stacked(ga), false)));
  Eigen::VectorXd out = Eigen::VectorXd::Zero(lambda.size());
  for (int i : gap_rows) out(i) = du(i) / p.scale;  // g = g0 − u and ∂u/∂f = −V P G⁻¹ G′ a
  return out;
}

Eigen::VectorXd WeightedResidual::signorini_load_derivative(const Eigen::VectorXd& lambda, double load) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_load_derivative");
  std::vector<int> gap_rows;
  (void)p.signorini(lambda, load, &gap_rows);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(lambda.size());
  for (int i : gap_rows) out(i) = -p.u_lin(i) / p.scale;
  return out;
}

Eigen::VectorXd WeightedResidual::expand_forces(const Eigen::VectorXd& lambda, double load) const {
  const auto& p = *impl_;
  p.require_rigid("expand_forces");
  p.require_factorized();
  Eigen::VectorXd rhs = load * p.b;
  const Eigen::VectorXd nx = p.collocation_forces(lambda);
  p.scatter(rhs, nx, -1.0);
  return p.solve_stacked(rhs, false);
}

Eigen::VectorXd WeightedResidual::residual(const Eigen::VectorXd& a, const Eigen::VectorXd& lambda) const {
  const auto& p = *impl_;
  p.require_rigid("residual(a, lambda)");
  const auto u = spectral::as_coefficients(a, p.n);
  const double fr = p.forcing.frequency_hz;
  const Eigen::MatrixXd gu = fr * fr * p.operator_product(p.system.mass, u, 0) +
                             fr * p.operator_product(p.system.damping, u, 1) +
                             p.operator_product(p.system.stiffness, u, 2);
  Eigen::VectorXd r = spectral::stacked(gu) - p.b;
  const Eigen::VectorXd nx = p.collocation_forces(lambda);
  p.scatter(r, nx, 1.0);
  return r;
}

// The Signorini conditions at load s as a NonlinearSystem on λ (rigid stops).
struct WeightedResidual::Signorini {
  const WeightedResidual* wr;
  double load;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& lambda) const { return wr->signorini_residual(lambda, load); }
  [[nodiscard]] LowRankJacobian jacobian(const Eigen::VectorXd& lambda) const { return wr->signorini_jacobian(lambda); }
};

// The Signorini conditions regularized by a penalty of relative stiffness κ = 10^μ at the same
// instants, as a ParametrizedSystem in μ (rigid stops):
//   r(λ, μ) = (c λ − κ (u(λ) − g0)₊) / s_r,   ∂r/∂λ = (c I + κ P_A D) / s_r,
//   ∂r/∂μ = −ln 10 · κ (u − g0)₊ / s_r,   A = the instants that penetrate.
// Its solutions are those of the linear penalty k = κ/c at the instants; as κ → ∞ they tend to
// the rigid one (penetration c λ/κ).
struct WeightedResidual::SignoriniPenalty {
  const WeightedResidual* wr;
  [[nodiscard]] Eigen::VectorXd penetration(const Eigen::VectorXd& lambda) const {
    const auto& p = *wr->impl_;
    return ((p.u_lin - p.delassus * lambda) - p.collocation->gaps).cwiseMax(0.0);
  }
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& lambda, double mu) const {
    const auto& p = *wr->impl_;
    return (p.force_compliance * lambda - std::pow(10.0, mu) * penetration(lambda)) / p.scale;
  }
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& lambda, double mu) const {
    const auto& p = *wr->impl_;
    const double kappa = std::pow(10.0, mu);
    const Eigen::VectorXd pen = penetration(lambda);
    Linearization l;
    l.residual = (p.force_compliance * lambda - kappa * pen) / p.scale;
    l.jacobian = Eigen::MatrixXd::Zero(lambda.size(), lambda.size());
    for (Eigen::Index i = 0; i < lambda.size(); ++i) {
      if (pen(i) > 0.0) l.jacobian.row(i) = (kappa / p.scale) * p.delassus.row(i);
      l.jacobian(i, i) += p.force_compliance / p.scale;
    }
    l.parameter_derivative = (-std::log(10.0) * kappa / p.scale) * pen;
    return l;
  }
};

NewtonResult WeightedResidual::solve_rigid_with_penalty_homotopy(HomotopyReport& report) const {
  const auto& p = *impl_;
  report.tried = true;
  // From κ₀ = 10⁻², where λ ≈ κ₀ (u_lin − g0)₊ / c barely moves the structure, to κ = 10⁸
  // (penetration about 10⁻⁸ c λ), then the active-set Newton on the exact conditions.
  constexpr double kMuStart = -2.0, kMuEnd = 8.0;
  report.lambda_start = kMuStart;
  const SignoriniPenalty system{this};
  const Eigen::VectorXd start = std::pow(10.0, kMuStart) * system.penetration(Eigen::VectorXd::Zero(p.u_lin.size())) /
                                p.force_compliance;
  // λ in newtons: the state scaled so that c λ is compared with s_r in metres.
  const PseudoArclengthOptions o = homotopy_continuation(kMuStart - 1.0, kMuEnd, p.scale / p.force_compliance, p.options);
  const Branch branch = pseudo_arclength(system, start, kMuStart, o);
  record_homotopy(branch, kMuEnd, report);
  // Newton on the exact conditions from the stiffest penalty point reached: near the end of the
  // path its active set is the rigid one.
  Eigen::VectorXd guess = branch.points.empty() ? start : branch.points.back().x;
  NewtonResult out = newton(Signorini{this, 1.0}, std::move(guess), p.options.newton);
  out.report.iterations += static_cast<int>(branch.corrector_iterations);
  report.reached = out.report.converged();
  out.report.message = "penalty homotopy of the Signorini conditions, kappa from 1e" + format_number(kMuStart) +
                       " to " + format_number(report.sigma_reached) + " (" + std::to_string(report.points) + " points, " +
                       std::to_string(report.folds) + " folds; " + report.stop + "), then the active-set Newton: " +
                       out.report.message;
  if (!out.report.converged() && branch.stop != StopReason::RangeReached) out.report.status = SolveStatus::PathEnded;
  return out;
}

// The condensed system at load factor s (forcing s·F) as a NonlinearSystem.
struct WeightedResidual::Condensed {
  const WeightedResidual* wr;
  double load;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const {
    return wr->impl_->contact_residual(x, load);
  }
  [[nodiscard]] LowRankJacobian jacobian(const Eigen::VectorXd& x) const { return wr->contact_jacobian_low_rank(x); }
};

NewtonResult WeightedResidual::solve_with_load_stepping(Eigen::VectorXd x, int& steps) const {
  // Forcing s·F for s from 0 to 1; ds doubles after a success (at most ½) and is quartered after
  // a failure; predictor x + ds·x_lin (the linear part of the response).
  const auto& p = *impl_;
  double s = 0.0, ds = 0.125;
  NewtonResult last{std::move(x), {}};
  int iterations = 0;
  steps = 0;
  while (s < 1.0) {
    const double target = std::min(1.0, s + ds);
    Eigen::VectorXd guess = last.x + (target - s) * p.x_lin;
    NewtonResult trial = newton(Condensed{this, target}, std::move(guess), p.options.newton);
    iterations += trial.report.iterations;
    ++steps;
    if (trial.report.converged()) {
      s = target;
      last = std::move(trial);
      ds = std::min(0.5, 2.0 * ds);
    } else {
      ds *= 0.25;
      if (ds < 1e-6) {
        trial.report.iterations = iterations;
        trial.report.message = "load stepping stalled at s = " + std::to_string(s) + " of F: " + trial.report.message;
        return trial;
      }
    }
  }
  last.report.iterations = iterations;
  return last;
}

Eigen::VectorXd WeightedResidual::ContactHomotopy::residual(const Eigen::VectorXd& x, double lambda) const {
  const auto& p = *problem->impl_;
  p.require_factorized();
  return (x - p.x_lin + std::pow(10.0, lambda) * p.compliance_times(p.contact_forces(x, nullptr))) / p.scale;
}

Linearization WeightedResidual::ContactHomotopy::linearize(const Eigen::VectorXd& x, double lambda) const {
  const auto& p = *problem->impl_;
  p.require_factorized();
  const double sigma = std::pow(10.0, lambda);
  std::vector<Impl::ContactTangent> tangents;
  const Eigen::VectorXd hn = p.compliance_times(p.contact_forces(x, &tangents));
  const Eigen::MatrixXd nj = p.contact_force_jacobian(tangents);
  Linearization l;
  l.residual = (x - p.x_lin + sigma * hn) / p.scale;
  l.jacobian = (sigma / p.scale) * p.compliance_times(nj);
  l.jacobian.diagonal().array() += 1.0 / p.scale;
  l.parameter_derivative = (std::log(10.0) * sigma / p.scale) * hn;  // dσ/dλ = σ ln 10
  return l;
}

NewtonResult WeightedResidual::solve_with_contact_homotopy(HomotopyReport& report) const {
  const auto& p = *impl_;
  report.tried = true;
  // λ₀: σ₀ ‖H N(x_lin)‖∞ = 0.1, so that x_lin is within Newton's reach of the σ₀ solution.
  std::vector<Impl::ContactTangent> tangents;
  (void)p.contact_forces(p.x_lin, &tangents);
  const Eigen::MatrixXd nj = p.contact_force_jacobian(tangents);
  const double coupling = p.compliance_times(nj).lpNorm<Eigen::Infinity>();
  const double lambda0 = std::clamp(coupling > 0.0 ? std::log10(0.1 / coupling) : -1.0, -12.0, -1.0);
  report.lambda_start = lambda0;
  // From λ₀ to σ = 1 (a path turning back below λ₀ has ended), the state in metres as the residual.
  const PseudoArclengthOptions o = homotopy_continuation(lambda0 - 1.0, 0.0, p.scale, p.options);
  const Branch branch = pseudo_arclength(contact_homotopy(), p.x_lin, lambda0, o);
  record_homotopy(branch, 0.0, report);
  NewtonResult out;
  if (branch.stop != StopReason::RangeReached || branch.points.back().parameter < 0.0) {
    out.x = branch.points.empty() ? p.x_lin : branch.points.back().x;
    out.report.status = SolveStatus::PathEnded;
    out.report.iterations = static_cast<int>(branch.corrector_iterations);
    out.report.message = "contact homotopy ended at σ = " + format_number(report.sigma_reached) + " (from σ₀ = " +
                         format_number(std::pow(10.0, lambda0)) + ", " + std::to_string(report.points) +
                         " points, " + std::to_string(report.folds) + " folds in σ): " + report.stop;
    return out;
  }
  // The last step crossed σ = 1: interpolate x linearly in λ onto λ = 0, then Newton at σ = 1.
  const auto& b = branch.points.back();
  const auto& a = branch.points[branch.points.size() - 2];
  const double w = b.parameter > a.parameter ? (0.0 - a.parameter) / (b.parameter - a.parameter) : 1.0;
  Eigen::VectorXd guess = a.x + std::clamp(w, 0.0, 1.0) * (b.x - a.x);
  out = newton(Condensed{this, 1.0}, std::move(guess), p.options.newton);
  out.report.iterations += static_cast<int>(branch.corrector_iterations);
  report.reached = out.report.converged();
  if (report.reached) report.sigma_reached = 1.0;
  out.report.message = "contact homotopy from σ₀ = " + format_number(std::pow(10.0, lambda0)) + " (" +
                       std::to_string(report.points) + " points, " + std::to_string(report.folds) +
                       " folds in σ), then Newton at σ = 1: " + out.report.message;
  return out;
}

double WeightedResidual::rounding_floor(const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  const double bnorm = p.b.norm() > 0.0 ? p.b.norm() : 1.0;
  const Eigen::VectorXd r0 = residual(expand(x));
  double floor = 0.0;
  for (int pattern = 0; pattern < 2; ++pattern) {
    Eigen::VectorXd xe = x;
    for (Eigen::Index i = 0; i < xe.size(); ++i) {
      const double sign = ((i + pattern) % 2 == 0) ? 1.0 : -1.0;
      xe(i) *= 1.0 + sign * std::numeric_limits<double>::epsilon();
    }
    floor = std::max(floor, (residual(expand(xe)) - r0).norm() / bnorm);
  }
  return floor;
}

std::string_view to_string(SolutionPath path) noexcept {
  switch (path) {
    case SolutionPath::DirectNewton: return "direct Newton";
    case SolutionPath::ContactHomotopy: return "contact homotopy";
    case SolutionPath::LoadStepping: return "load stepping";
    case SolutionPath::Linear: return "linear";
  }
  return "unknown";
}

WeightedResidualSolution WeightedResidual::solve(const Eigen::VectorXd* x0) const {
  const auto start = std::chrono::steady_clock::now();
  const auto& p = *impl_;
  WeightedResidualSolution s;
  s.frequency_hz = p.forcing.frequency_hz;
  s.contact_unknowns = p.nc * p.m;
  s.linear_solver = linear_solver();
  s.operator_rule = p.ops.rule;
  s.condition_number = condition_number();
  if (!p.factorized) {
    s.report.status = SolveStatus::SingularJacobian;
    s.report.message = "linear operator G is singular: " + p.singular_reason();
    s.coefficients = Eigen::MatrixXd::Zero(p.n, p.m);
    s.relative_residual = std::numeric_limits<double>::infinity();
    return s;
  }
  if (p.rigid) return solve_rigid(x0, std::move(s), start);
  Eigen::VectorXd x;
  if (p.nc > 0) {
    Eigen::VectorXd start_x = x0 != nullptr ? *x0 : p.x_lin;
    if (start_x.size() != p.nc * p.m) {
      throw std::invalid_argument("WeightedResidual::solve: initial guess has length " +
                                  std::to_string(start_x.size()) + ", expected n_c*M = " + std::to_string(p.nc * p.m));
    }
    NewtonResult result = newton(Condensed{this, 1.0}, start_x, p.options.newton);
    s.path = SolutionPath::DirectNewton;
    std::string history = "direct Newton: " + result.report.message;
    int iterations = result.report.iterations;
    if (!result.report.converged() && x0 == nullptr && p.options.contact_homotopy) {
      NewtonResult h = solve_with_contact_homotopy(s.homotopy);
      iterations += h.report.iterations;
      history += "; " + h.report.message;
      if (h.report.converged()) {
        s.path = SolutionPath::ContactHomotopy;
        h.report.iterations = iterations;
        h.report.message = history;
      }
      result = std::move(h);
    }
    if (!result.report.converged() && x0 == nullptr) {
      int steps = 0;
      const SolveStatus before = result.report.status;
      NewtonResult stepped = solve_with_load_stepping(Eigen::VectorXd::Zero(start_x.size()), steps);
      iterations += stepped.report.iterations;
      stepped.report.iterations = iterations;
      stepped.report.message = history + "; load stepping (" + std::to_string(steps) + " steps): " +
                               stepped.report.message;
      if (stepped.report.converged()) {
        s.path = SolutionPath::LoadStepping;
      } else if (before == SolveStatus::PathEnded) {
        stepped.report.status = SolveStatus::PathEnded;  // the homotopy's diagnosis stands
      }
      result = std::move(stepped);
    }
    x = std::move(result.x);
    s.report = std::move(result.report);
  } else {
    s.report.status = SolveStatus::Converged;
    s.path = SolutionPath::Linear;
    s.report.message = "linear problem (no contact): one solve";
    s.report.residual_norms = {0.0};
  }
  const Eigen::VectorXd a = p.nc > 0 ? expand(x) : p.a_lin;
  s.coefficients = spectral::as_coefficients(a, p.n);
  const double bnorm = p.b.norm();
  s.relative_residual = residual(a).norm() / (bnorm > 0.0 ? bnorm : 1.0);
  if (p.nc > 0) {
    const Eigen::MatrixXd u = p.contact_samples(x);
    s.max_penetration = -std::numeric_limits<double>::infinity();
    for (int c = 0; c < p.nc; ++c) {
      for (int k = 0; k < p.q; ++k) {
        s.max_penetration = std::max(s.max_penetration, u(c, k) - p.contacts[c].law->gap());
        s.max_contact_force = std::max(s.max_contact_force, p.contacts[c].law->force(u(c, k)));
      }
    }
  }
  s.residual_tolerance = p.options.residual_tolerance;
  if (p.keep.size() > 0) s.dropped_harmonics_residual = p.nc > 0 ? dropped_harmonics_residual(x) : 0.0;
  if (s.report.converged() && (!std::isfinite(s.relative_residual) || !s.coefficients.allFinite())) {
    s.report.status = SolveStatus::NonFinite;
    s.report.message = "non-finite full residual after convergence of the condensed system";
  } else if (s.report.converged() && !(s.relative_residual <= p.options.residual_tolerance)) {
    s.report.status = SolveStatus::ResidualNotVerified;
    s.report.message = "the condensed system converged (" + s.report.message + "), but the full residual " +
                       format_number(s.relative_residual) + " ‖b‖ exceeds residual_tolerance = " +
                       format_number(p.options.residual_tolerance) +
                       " (ill-conditioned G? condition estimate " + format_number(s.condition_number) + ")";
    s.rounding_floor = rounding_floor(x);
    s.report.message += "; rounding floor of the residual at this solution " + format_number(s.rounding_floor);
  }
  s.wall_time_s = elapsed(start);
  return s;
}

WeightedResidualSolution WeightedResidual::solve_rigid(const Eigen::VectorXd* lambda0, WeightedResidualSolution s,
                                                       std::chrono::steady_clock::time_point start) const {
  const auto& p = *impl_;
  const Eigen::Index size = static_cast<Eigen::Index>(p.nc) * p.m;
  const Eigen::VectorXd l0 = lambda0 != nullptr ? *lambda0 : Eigen::VectorXd::Zero(size);
  if (l0.size() != size) {
    throw std::invalid_argument("WeightedResidual::solve: initial contact forces have length " + std::to_string(l0.size()) +
                                ", expected n_c*M = " + std::to_string(size) + " (rigid stops: the force samples λ)");
  }
  NewtonResult result = newton(Signorini{this, 1.0}, l0, p.options.newton);
  s.path = SolutionPath::DirectNewton;
  std::string history = "primal-dual active set (semismooth Newton on the Signorini conditions): " + result.report.message;
  if (!result.report.converged() && lambda0 == nullptr && p.options.contact_homotopy) {
    NewtonResult h = solve_rigid_with_penalty_homotopy(s.homotopy);
    h.report.iterations += result.report.iterations;
    history += "; " + h.report.message;
    if (h.report.converged()) s.path = SolutionPath::ContactHomotopy;
    result = std::move(h);
  }
  s.report = std::move(result.report);
  s.report.message = history;
  const Eigen::VectorXd& lambda = result.x;
  const Eigen::VectorXd a = expand_forces(lambda);
  s.coefficients = spectral::as_coefficients(a, p.n);
  s.contact_force_samples = spectral::as_coefficients(lambda, p.nc);
  const double bnorm = p.b.norm();
  s.relative_residual = residual(a, lambda).norm() / (bnorm > 0.0 ? bnorm : 1.0);
  s.residual_tolerance = p.options.residual_tolerance;
  // The conditions recomputed from the coefficients, not from D λ.
  const Eigen::VectorXd xa = p.gather(a);
  const Eigen::VectorXd gap = p.collocation->gaps - p.per_contact(p.collocation->trial_values, xa);
  Eigen::VectorXd phi(size);
  for (Eigen::Index i = 0; i < size; ++i) phi(i) = contact::signorini_min(p.force_compliance * lambda(i), gap(i)).value;
  s.collocation_penetration = (-gap).maxCoeff();
  s.complementarity = phi.cwiseAbs().maxCoeff();
  s.max_contact_force = lambda.maxCoeff();
  const Eigen::MatrixXd u = p.contact_samples(xa);
  s.max_penetration = -std::numeric_limits<double>::infinity();
  for (int c = 0; c < p.nc; ++c) s.max_penetration = std::max(s.max_penetration, u.row(c).maxCoeff() - p.contacts[c].law->gap());
  const double phi_norm = detail::residual_norm(phi / p.scale, p.options.newton.norm);
  if (s.report.converged() && (!std::isfinite(s.relative_residual) || !s.coefficients.allFinite())) {
    s.report.status = SolveStatus::NonFinite;
    s.report.message = "non-finite full residual after convergence of the Signorini conditions";
  } else if (s.report.converged() && !(s.relative_residual <= p.options.residual_tolerance &&
                                       phi_norm <= p.options.newton.tolerance)) {
    s.report.status = SolveStatus::ResidualNotVerified;
    s.report.message = "the Signorini conditions converged (" + s.report.message + "), but recomputed from the "
                       "coefficients the full residual is " + format_number(s.relative_residual) + " ‖b‖ (bound " +
                       format_number(p.options.residual_tolerance) + ") and the complementarity residual " +
                       format_number(phi_norm) + " s_r (bound " + format_number(p.options.newton.tolerance) +
                       "; condition estimate of G " + format_number(s.condition_number) + ")";
  }
  s.wall_time_s = elapsed(start);
  return s;
}

WeightedResidualSolution solve_weighted_residual(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                                 const std::vector<ContactPoint>& contacts, const TimeBasis& trial,
                                                 const TimeBasis& weighting, const WeightedResidualOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const WeightedResidual wr(system, forcing, contacts, trial, weighting, options);
  WeightedResidualSolution s = wr.solve();
  s.wall_time_s = elapsed(start);
  return s;
}

}  // namespace wbm::solvers
