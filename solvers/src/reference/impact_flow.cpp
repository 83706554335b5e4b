// ImpactFlow (impact_shooting.hpp): the event-driven flow of a linear structure with rigid stops,
// in closed form between events, and its monodromy matrix through saltation matrices.
#include <wbm/solvers/impact_shooting.hpp>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <complex>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>

namespace wbm::solvers {

namespace {
using Complex = std::complex<double>;

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}
}  // namespace

void ImpactFlowOptions::validate() const {
  if (!(restitution >= 0.0 && restitution <= 1.0)) {
    throw std::invalid_argument("ImpactFlowOptions.restitution = " + num(restitution) +
                                ": Newton's coefficient must lie in [0, 1]");
  }
  if (steps_per_period < 8) {
    throw std::invalid_argument("ImpactFlowOptions.steps_per_period = " + std::to_string(steps_per_period) +
                                ": must be at least 8 (the event search's brackets per period)");
  }
  if (max_events < 1) {
    throw std::invalid_argument("ImpactFlowOptions.max_events = " + std::to_string(max_events) +
                                ": must be at least 1");
  }
}

// The closed-form flight with one active set A: reduced coordinates q (u = Z q + u_A), the
// first-order matrix's eigendecomposition, the periodic particular solution per load harmonic,
// and the rows that give the gaps and the contact forces.
struct Phase {
  std::vector<int> closed;            // the stops of A
  Eigen::MatrixXd z;                  // n × r, orthonormal, E_Aᵀ Z = 0
  Eigen::VectorXd u_a;                // n: E_Aᵀ u_A = g_A (least norm)
  Eigen::MatrixXcd v, v_inv;          // 2r × 2r: the first-order matrix = V diag(Λ) V⁻¹
  Eigen::VectorXcd lambda;            // 2r
  std::vector<int> harmonics;         // the load harmonics (0: static, with −K u_A)
  std::vector<Eigen::VectorXcd> q_h;  // per harmonic: the reduced particular amplitude Q_h (r)
  Eigen::MatrixXd force_rows;         // a × n: L = W⁻¹ E_Aᵀ M⁻¹ (λ_A = L (f − C u̇ − K u))
  double bracket = std::numeric_limits<double>::infinity();  // π / (2 max |Im Λ|) [s]: oscillations
  double fastest = std::numeric_limits<double>::infinity();  // π / (2 max |Λ|) [s]: also decays
  // The event indicators h (n_c: the gaps of the open stops, λ of the closed ones) and the stops'
  // rates ρ = −Eᵀu̇ as rows on the flight, so that the event search reads n_c numbers without the
  // 2n-state: h(t) = h₀ + Σ_j Re(h_j e^{i w_j t}) + Re(H_V (e^{Λ(t − t_a)} ∘ c)), likewise ρ (ρ₀ = 0),
  // the sum over the particular solution's and the load's harmonics w_j.
  Eigen::VectorXd h0;                       // n_c
  Eigen::MatrixXcd h_v, rate_v;             // n_c × 2r: the rows times V
  std::vector<double> row_w;                // w_j [rad/s]
  std::vector<Eigen::VectorXcd> h_w, rate_w;  // per w_j: n_c
  // conjugate(j): Λ_j is bitwise the conjugate of Λ_{j−1} (Eigen's real Schur pairs), so its
  // exponential is the conjugate of the one before, and one cexp serves the pair.
  std::vector<char> conjugate;
  [[nodiscard]] Eigen::Index r() const { return z.cols(); }
};

namespace {
// e^{Λτ} (2r), one cexp per conjugate pair.
Eigen::VectorXcd decay(const Phase& p, double tau) {
  Eigen::VectorXcd d(p.lambda.size());
  for (Eigen::Index j = 0; j < d.size(); ++j) {
    d(j) = p.conjugate[static_cast<size_t>(j)] ? std::conj(d(j - 1)) : std::exp(p.lambda(j) * tau);
  }
  return d;
}

// The flight's transition matrix over τ in the full state (2n × 2n): blockdiag(Z, Z) Re(V e^{Λτ} V⁻¹) blockdiag(Zᵀ, Zᵀ).
Eigen::MatrixXd transition(const Phase& p, double tau, Eigen::Index n) {
  const Eigen::Index r = p.r();
  if (r == 0) return Eigen::MatrixXd::Zero(2 * n, 2 * n);  // every DOF held: perturbations vanish
  const Eigen::MatrixXd tr = (p.v * decay(p, tau).asDiagonal() * p.v_inv).real();
  Eigen::MatrixXd zz = Eigen::MatrixXd::Zero(2 * n, 2 * r);
  zz.topLeftCorner(n, r) = p.z;
  zz.bottomRightCorner(n, r) = p.z;
  return zz * tr * zz.transpose();
}

// The monodromy matrix Φ accumulated along a flow. A flight of a phase with no stop closed (Z = I)
// is diag(e^{Λτ}) in that phase's eigen-coordinates Y = V⁻¹ Φ, and a saltation matrix is the
// identity plus rank k = n_A + 2 (the impulse's n_A + 1 directions and the field term), so over
// runs of free flights and impacts Φ is kept as Y: a flight costs O(n²) and an event O(k n²),
// instead of the dense products' O(n³) each. Φ = Re(V Y) is formed where a phase with closed stops
// begins and at the end. `dense` keeps the 2n × 2n products (ImpactFlowOptions::dense_monodromy).
class MonodromyProduct {
 public:
  MonodromyProduct(Eigen::Index n, bool dense) : n_(n), phi_(Eigen::MatrixXd::Identity(2 * n, 2 * n)), dense_(dense) {}
  // Φ ← Φ_flight(τ) Φ.
  void flight(const Phase& p, double tau) {
    if (dense_ || p.r() != n_) {
      phi_ = transition(p, tau, n_) * matrix();
    } else {
      if (eig_ != &p) {
        y_ = identity_ ? p.v_inv : Eigen::MatrixXcd(p.v_inv * matrix().cast<Complex>());
        eig_ = &p;
      }
      y_ = decay(p, tau).asDiagonal() * y_;
    }
    identity_ = false;
  }
  // Φ ← (I + A Bᵀ) Φ, A and B 2n × k.
  void saltation(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
    if (eig_ != nullptr) {  // Bᵀ Φ = Re(Bᵀ V Y); Re(V (Y + V⁻¹ A Bᵀ Φ)) = Φ + A Bᵀ Φ
      const Eigen::MatrixXd bt_phi = ((b.transpose().cast<Complex>() * eig_->v) * y_).real();
      y_ += (eig_->v_inv * a.cast<Complex>()) * bt_phi.cast<Complex>();
    } else if (dense_) {
      Eigen::MatrixXd salt = Eigen::MatrixXd::Identity(2 * n_, 2 * n_);
      salt += a * b.transpose();
      phi_ = salt * phi_;
    } else {
      phi_ += a * (b.transpose() * phi_);
    }
    identity_ = false;
  }
  const Eigen::MatrixXd& matrix() {
    if (eig_ != nullptr) {
      phi_ = (eig_->v * y_).real();
      eig_ = nullptr;
    }
    return phi_;
  }

 private:
  Eigen::Index n_;
  Eigen::MatrixXd phi_;          // Φ where eig_ is null
  Eigen::MatrixXcd y_;           // V⁻¹ Φ of the phase eig_
  const Phase* eig_ = nullptr;
  bool dense_, identity_ = true;
};
}  // namespace

struct ImpactFlow::Impl {
  int n = 0, nc = 0;
  Eigen::MatrixXd m, c, k, e;  // M, C, K (n × n), E (n × n_c): the directions e_c
  Eigen::VectorXd g;           // gaps g_c
  Eigen::LLT<Eigen::MatrixXd> m_llt;
  double omega = 0.0, period = 0.0;
  std::vector<int> harmonics;         // load harmonics present
  std::vector<Eigen::VectorXcd> f_h;  // complex load amplitudes per harmonic (n)
  ImpactFlowOptions options;
  mutable std::map<std::vector<char>, std::unique_ptr<Phase>> phases;

  [[nodiscard]] Eigen::VectorXd load(double t) const {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
    for (size_t j = 0; j < harmonics.size(); ++j) {
      f += (f_h[j] * std::exp(Complex(0.0, harmonics[j] * omega * t))).real();
    }
    return f;
  }
  [[nodiscard]] const Phase& phase(const std::vector<char>& active) const;
  // The reduced state s = (q, q̇) at t on the flight whose homogeneous coefficients are `coef`
  // (set at t_a), and the full state (u, u̇).
  [[nodiscard]] Eigen::VectorXd particular(const Phase& p, double t) const {
    const Eigen::Index r = p.r();
    Eigen::VectorXd s = Eigen::VectorXd::Zero(2 * r);
    for (size_t j = 0; j < p.harmonics.size(); ++j) {
      const double w = p.harmonics[j] * omega;
      const Complex rot = std::exp(Complex(0.0, w * t));
      s.head(r) += (p.q_h[j] * rot).real();
      s.tail(r) += (p.q_h[j] * (Complex(0.0, w) * rot)).real();
    }
    return s;
  }
  [[nodiscard]] Eigen::VectorXd full(const Phase& p, const Eigen::VectorXd& s) const {
    const Eigen::Index r = p.r();
    Eigen::VectorXd x(2 * n);
    x.head(n) = p.z * s.head(r) + p.u_a;
    x.tail(n) = p.z * s.tail(r);
    return x;
  }
  [[nodiscard]] Eigen::VectorXd state(const Phase& p, const Eigen::VectorXcd& coef, double ta, double t) const {
    return full(p, particular(p, t) + (p.v * decay(p, t - ta).cwiseProduct(coef)).real());
  }
  // The indicators h and the rates ρ (n_c each) at t on the flight set at t_a with `coef`, from
  // the phase's rows: O(n_c r) instead of the state's O(r²).
  void rows_at(const Phase& p, const Eigen::VectorXcd& coef, double ta, double t, Eigen::VectorXd& h,
               Eigen::VectorXd& rate) const {
    rows_at(p, coef, decay(p, t - ta), t, h, rate);
  }
  // The same with e^{Λ(t − t_a)} given (`d`, 2r).
  void rows_at(const Phase& p, const Eigen::VectorXcd& coef, const Eigen::VectorXcd& d, double t, Eigen::VectorXd& h,
               Eigen::VectorXd& rate) const {
    const Eigen::VectorXcd dc = d.cwiseProduct(coef);
    h = p.h0 + (p.h_v * dc).real();
    rate = (p.rate_v * dc).real();
    for (size_t j = 0; j < p.row_w.size(); ++j) {
      const Complex rot = std::exp(Complex(0.0, p.row_w[j] * t));
      h += (p.h_w[j] * rot).real();
      rate += (p.rate_w[j] * rot).real();
    }
  }
  void set_rows(Phase& p) const;
  // λ_A at (t, x) for the phase's closed stops.
  [[nodiscard]] Eigen::VectorXd forces(const Phase& p, double t, const Eigen::VectorXd& x) const {
    if (p.closed.empty()) return {};
    return p.force_rows * (load(t) - c * x.tail(n) - k * x.head(n));
  }
  // ẋ at (t, x) with the phase's closed stops.
  [[nodiscard]] Eigen::VectorXd field(const Phase& p, double t, const Eigen::VectorXd& x) const {
    Eigen::VectorXd rhs = load(t) - c * x.tail(n) - k * x.head(n);
    for (size_t a = 0; a < p.closed.size(); ++a) {
      rhs -= e.col(p.closed[a]) * (p.force_rows.row(static_cast<Eigen::Index>(a)) * rhs)(0);
    }
    Eigen::VectorXd f(2 * n);
    f.head(n) = x.tail(n);
    f.tail(n) = m_llt.solve(rhs);
    return f;
  }
  // The event indicators at (t, x): h_c = g_c − e_cᵀ u for an open stop, λ_c for a closed one.
  [[nodiscard]] Eigen::VectorXd indicators(const Phase& p, double t, const Eigen::VectorXd& x) const {
    Eigen::VectorXd ind = g - e.transpose() * x.head(n);
    const Eigen::VectorXd lam = forces(p, t, x);
    for (size_t a = 0; a < p.closed.size(); ++a) ind(p.closed[a]) = lam(static_cast<Eigen::Index>(a));
    return ind;
  }
};

const Phase& ImpactFlow::Impl::phase(const std::vector<char>& active) const {
  if (auto it = phases.find(active); it != phases.end()) return *it->second;
  auto p = std::make_unique<Phase>();
  for (int s = 0; s < nc; ++s) {
    if (active[static_cast<size_t>(s)]) p->closed.push_back(s);
  }
  const auto na = static_cast<Eigen::Index>(p->closed.size());
  Eigen::MatrixXd ea(n, na);
  Eigen::VectorXd ga(na);
  for (Eigen::Index a = 0; a < na; ++a) {
    ea.col(a) = e.col(p->closed[static_cast<size_t>(a)]);
    ga(a) = g(p->closed[static_cast<size_t>(a)]);
  }
  if (na == 0) {
    p->z = Eigen::MatrixXd::Identity(n, n);
    p->u_a = Eigen::VectorXd::Zero(n);
  } else {
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(ea);
    const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(n, n);
    p->z = q.rightCols(n - na);
    p->u_a = ea * (ea.transpose() * ea).ldlt().solve(ga);
    const Eigen::MatrixXd minv_e = m_llt.solve(ea);
    p->force_rows = (ea.transpose() * minv_e).ldlt().solve(minv_e.transpose());
  }
  const Eigen::Index r = p->r();
  if (r == 0) {  // every DOF held by the closed stops: nothing moves until a release
    set_rows(*p);
    const Phase& ref = *p;
    phases.emplace(active, std::move(p));
    return ref;
  }
  const Eigen::MatrixXd mr = p->z.transpose() * m * p->z, cr = p->z.transpose() * c * p->z,
                        kr = p->z.transpose() * k * p->z;
  // The first-order matrix of the balanced state (q, q̇/σ), σ = √‖M_r⁻¹ K_r‖₁: both off-diagonal
  // blocks are then of the order of the highest natural frequency, instead of its square beside 1,
  // which costs the eigenvalues ε ‖M_r⁻¹ K_r‖ (4e-5 rad/s on a 25-element rod: a phase error of
  // 3e-7 over a period, and vector fields at the events that disagree with the flow by as much).
  const Eigen::LLT<Eigen::MatrixXd> mr_llt(mr);
  const Eigen::MatrixXd minv_k = mr_llt.solve(kr);
  const double sigma = std::max(std::sqrt(minv_k.cwiseAbs().colwise().sum().maxCoeff()), 1e-300);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * r, 2 * r);
  a.topRightCorner(r, r).diagonal().setConstant(sigma);
  a.bottomLeftCorner(r, r) = -minv_k / sigma;
  a.bottomRightCorner(r, r) = -mr_llt.solve(cr);
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(a);
  if (eig.info() != Eigen::Success)
    throw std::invalid_argument("ImpactFlow: the eigendecomposition of the flight failed");
  const Eigen::MatrixXcd& v_balanced = eig.eigenvectors();
  p->lambda = eig.eigenvalues();
  p->conjugate.assign(static_cast<size_t>(p->lambda.size()), 0);
  for (Eigen::Index j = 1; j < p->lambda.size(); ++j) {
    p->conjugate[static_cast<size_t>(j)] = p->lambda(j) == std::conj(p->lambda(j - 1)) ? 1 : 0;
  }
  const Eigen::PartialPivLU<Eigen::MatrixXcd> v_lu(v_balanced);
  if (!(v_lu.rcond() > 1e-12)) {
    throw std::invalid_argument(
        "ImpactFlow: the flight's first-order matrix is (nearly) defective (rcond of its "
        "eigenvectors " +
        num(v_lu.rcond()) + "), e.g. a critically damped mode; change the damping");
  }
  // Back to (q, q̇): V = diag(I, σ I) V_b, V⁻¹ = V_b⁻¹ diag(I, I/σ).
  p->v = v_balanced;
  p->v.bottomRows(r) *= sigma;
  p->v_inv = v_lu.inverse();
  p->v_inv.rightCols(r) /= sigma;
  p->bracket = std::numbers::pi / (2.0 * p->lambda.imag().cwiseAbs().maxCoeff());
  p->fastest = std::numbers::pi / (2.0 * p->lambda.cwiseAbs().maxCoeff());
  // Particular solution: (K_r − (hω)² M_r + i hω C_r) Q_h = Zᵀ F_h, the static harmonic with −Zᵀ K u_A.
  std::vector<int> hs = harmonics;
  std::vector<Eigen::VectorXcd> fs = f_h;
  if (na > 0 && std::find(hs.begin(), hs.end(), 0) == hs.end()) {
    hs.push_back(0);
    fs.push_back(Eigen::VectorXcd::Zero(n));
  }
  for (size_t j = 0; j < hs.size(); ++j) {
    const double w = hs[j] * omega;
    Eigen::VectorXcd rhs = p->z.transpose().cast<Complex>() * fs[j];
    if (hs[j] == 0) rhs -= (p->z.transpose() * k * p->u_a).cast<Complex>();
    const Eigen::MatrixXcd d = kr.cast<Complex>() - (w * w) * mr.cast<Complex>() + Complex(0.0, w) * cr.cast<Complex>();
    const Eigen::PartialPivLU<Eigen::MatrixXcd> d_lu(d);
    if (!(d_lu.rcond() > 1e-13)) {
      throw std::invalid_argument("ImpactFlow: the dynamic stiffness at load harmonic " + std::to_string(hs[j]) +
                                  " is singular (rcond " + num(d_lu.rcond()) + ") with " + std::to_string(na) +
                                  " stops closed: an undamped resonance or a free structure under a static load; add "
                                  "damping or move the forcing frequency");
    }
    p->harmonics.push_back(hs[j]);
    p->q_h.push_back(d_lu.solve(rhs));
  }
  set_rows(*p);
  const Phase& ref = *p;
  phases.emplace(active, std::move(p));
  return ref;
}

void ImpactFlow::Impl::set_rows(Phase& p) const {
  const Eigen::Index r = p.r();
  const auto na = static_cast<Eigen::Index>(p.closed.size());
  Eigen::MatrixXd h_rows = Eigen::MatrixXd::Zero(nc, 2 * r), rate_rows = Eigen::MatrixXd::Zero(nc, 2 * r);
  const Eigen::MatrixXd ez = e.transpose() * p.z;  // n_c × r
  h_rows.leftCols(r) = -ez;                        // h_c = g_c − e_cᵀ (Z q + u_A)
  rate_rows.rightCols(r) = -ez;                    // ρ_c = −e_cᵀ Z q̇
  p.h0 = g - e.transpose() * p.u_a;
  if (na > 0) {         // λ_A = L (f − C Z q̇ − K (Z q + u_A))
    const Eigen::MatrixXd lk = p.force_rows * k, lc = p.force_rows * c;
    for (Eigen::Index a = 0; a < na; ++a) {
      const Eigen::Index i = p.closed[static_cast<size_t>(a)];
      h_rows.row(i).head(r) = -(lk.row(a) * p.z);
      h_rows.row(i).tail(r) = -(lc.row(a) * p.z);
      p.h0(i) = -lk.row(a).dot(p.u_a);
    }
  }
  p.h_v = h_rows.cast<Complex>() * p.v;
  p.rate_v = rate_rows.cast<Complex>() * p.v;
  auto term = [&](double w) {
    const auto it = std::find(p.row_w.begin(), p.row_w.end(), w);
    if (it != p.row_w.end()) return static_cast<size_t>(it - p.row_w.begin());
    p.row_w.push_back(w);
    p.h_w.push_back(Eigen::VectorXcd::Zero(nc));
    p.rate_w.push_back(Eigen::VectorXcd::Zero(nc));
    return p.row_w.size() - 1;
  };
  for (size_t j = 0; j < p.harmonics.size(); ++j) {  // the particular solution (Q_h, i w Q_h)
    const double w = p.harmonics[j] * omega;
    Eigen::VectorXcd sj(2 * r);
    sj << p.q_h[j], Complex(0.0, w) * p.q_h[j];
    const size_t t = term(w);
    p.h_w[t] += h_rows.cast<Complex>() * sj;
    p.rate_w[t] += rate_rows.cast<Complex>() * sj;
  }
  for (size_t j = 0; na > 0 && j < harmonics.size(); ++j) {  // the closed stops' L f
    const Eigen::VectorXcd lfj = p.force_rows.cast<Complex>() * f_h[j];
    const size_t t = term(harmonics[j] * omega);
    for (Eigen::Index a = 0; a < na; ++a) p.h_w[t](p.closed[static_cast<size_t>(a)]) += lfj(a);
  }
}

ImpactFlow::ImpactFlow(const MechanicalSystem& system, const HarmonicForcing& forcing,
                       std::vector<ContactPoint> contacts, ImpactFlowOptions options)
    : impl_(std::make_unique<Impl>()) {
  system.validate();
  options.validate();
  Impl& s = *impl_;
  s.n = static_cast<int>(system.mass.rows());
  forcing.validate(s.n);
  ContactPoint::validate(contacts, s.n);
  require_fixed_obstacles(contacts, "ImpactFlow (exact orbits with impacts)",
                          "fix the stops (ContactPoint::obstacle = {})");
  if (contacts.empty()) throw std::invalid_argument("ImpactFlow: no contacts; an orbit without stops needs no events");
  s.nc = static_cast<int>(contacts.size());
  s.e.resize(s.n, s.nc);
  s.g.resize(s.nc);
  for (int i = 0; i < s.nc; ++i) {
    const auto& law = *contacts[static_cast<size_t>(i)].law;
    if (!law.rigid() || law.hysteretic()) {
      throw std::invalid_argument("ImpactFlow: contact " + std::to_string(i) + " (" + law.describe() +
                                  ") is not a rigid stop; penalty laws take FloquetAnalysis (floquet.hpp)");
    }
    s.e.col(i) = contacts[static_cast<size_t>(i)].direction(s.n);
    s.g(i) = law.gap();
  }
  s.m = Eigen::MatrixXd(system.mass);
  s.c = Eigen::MatrixXd(system.damping);
  s.k = Eigen::MatrixXd(system.stiffness);
  s.m_llt.compute(s.m);
  if (s.m_llt.info() != Eigen::Success) throw std::invalid_argument("ImpactFlow: M is not positive definite");
  s.omega = 2.0 * std::numbers::pi * forcing.frequency_hz;
  s.period = 1.0 / forcing.frequency_hz;
  for (const auto& l : forcing.loads()) {
    if (l.amplitude == 0.0) continue;
    auto it = std::find(s.harmonics.begin(), s.harmonics.end(), l.harmonic);
    if (it == s.harmonics.end()) {
      s.harmonics.push_back(l.harmonic);
      s.f_h.push_back(Eigen::VectorXcd::Zero(s.n));
      it = s.harmonics.end() - 1;
    }
    s.f_h[static_cast<size_t>(it - s.harmonics.begin())](l.dof) += std::polar(l.amplitude, l.phase_rad);
  }
  s.options = options;
}

ImpactFlow::~ImpactFlow() = default;
ImpactFlow::ImpactFlow(ImpactFlow&&) noexcept = default;
ImpactFlow& ImpactFlow::operator=(ImpactFlow&&) noexcept = default;
int ImpactFlow::dofs() const noexcept { return impl_->n; }
double ImpactFlow::period_s() const noexcept { return impl_->period; }

namespace {
// Brent's method (GSL) on a function of time inside [lo, hi] with a sign change.
template <class F>
double locate(const F& fun, double lo, double hi, double tolerance) {
  gsl_function gf;
  gf.function = [](double t, void* params) { return (*static_cast<const F*>(params))(t); };
  gf.params = const_cast<F*>(&fun);
  const std::unique_ptr<gsl_root_fsolver, decltype(&gsl_root_fsolver_free)> solver(
      gsl_root_fsolver_alloc(gsl_root_fsolver_brent), &gsl_root_fsolver_free);
  gsl_error_handler_t* old = gsl_set_error_handler_off();
  int status = gsl_root_fsolver_set(solver.get(), &gf, lo, hi);
  for (int i = 0; status == GSL_SUCCESS && i < 200; ++i) {
    status = gsl_root_fsolver_iterate(solver.get());
    lo = gsl_root_fsolver_x_lower(solver.get());
    hi = gsl_root_fsolver_x_upper(solver.get());
    if (gsl_root_test_interval(lo, hi, tolerance, 0.0) == GSL_SUCCESS) break;
  }
  gsl_set_error_handler(old);
  return hi;  // the upper end: the indicator is ≤ 0 there (the event has happened)
}
}  // namespace

ImpactFlowResult ImpactFlow::flow(const Eigen::VectorXd& x0, double t0, double duration,
                                  const std::vector<char>& active_in, int samples) const {
  const Impl& s = *impl_;
  const int n = s.n, nc = s.nc;
  if (x0.size() != 2 * n || !x0.allFinite()) {
    throw std::invalid_argument("ImpactFlow::flow: x0 must hold 2n = " + std::to_string(2 * n) + " finite values");
  }
  if (!(duration > 0.0) || !std::isfinite(duration) || !std::isfinite(t0)) {
    throw std::invalid_argument("ImpactFlow::flow: duration = " + num(duration) + " must be finite and > 0");
  }
  std::vector<char> active = active_in.empty() ? std::vector<char>(static_cast<size_t>(nc), 0) : active_in;
  if (static_cast<int>(active.size()) != nc) {
    throw std::invalid_argument("ImpactFlow::flow: `active` must have one entry per stop (" + std::to_string(nc) + ")");
  }
  for (int i = 0; i < nc; ++i) {
    const double h = s.g(i) - s.e.col(i).dot(x0.head(n));
    if (!active[static_cast<size_t>(i)] && h < -1e-12 * (1.0 + std::abs(s.g(i)))) {
      throw std::domain_error("ImpactFlow::flow: x0 penetrates stop " + std::to_string(i) + " (gap " + num(h) + ")");
    }
  }
  ImpactFlowResult out;
  MonodromyProduct monodromy(n, s.options.dense_monodromy);
  out.contact_displacement.resize(nc, samples);
  out.state_samples.resize(2 * n, samples);
  const double t_end = t0 + duration, h_period = s.period / s.options.steps_per_period;
  const double tolerance = 1e-14 * s.period;
  int next_sample = 0;
  auto sample_time = [&](int j) { return t0 + duration * j / samples; };
  std::vector<char> fresh(static_cast<size_t>(nc), 0);  // an event just happened here: its indicator is ≈ 0
  double t = t0;
  Eigen::VectorXd x = x0;
  for (;;) {
    const Phase& p = s.phase(active);
    const Eigen::Index r = p.r();
    Eigen::VectorXd sa(2 * r);
    sa.head(r) = p.z.transpose() * (x.head(n) - p.u_a);
    sa.tail(r) = p.z.transpose() * x.tail(n);
    const Eigen::VectorXcd coef = p.v_inv * (sa - s.particular(p, t)).cast<Complex>();
    const double ta = t;
    auto at = [&](double time) { return s.state(p, coef, ta, time); };
    // Brackets of at most a quarter of the phase's shortest natural period (and T/P): between two
    // samples each gap then has at most one minimum, found where its rate −e_cᵀu̇ changes sign.
    // An overdamped mode (real Λ, |Λ| up to β ω_max² with Rayleigh damping: 6e6 1/s on the
    // 25-element JL14 rod against 1e4 rad/s for its fastest oscillation) does not oscillate, but
    // its transient, excited at an event, may add an extremum while it lasts: the flight's
    // brackets start at π/(2 max|Λ|) and double up to that cap, past e^{−π 2^(k−1)} of it after k.
    const double h_cap = std::min(h_period, p.bracket);
    double h_step = std::min(h_cap, p.fastest);
    const double t_left0 = t;
    double t_left = t;
    Eigen::VectorXd left = s.indicators(p, t_left, x);
    Eigen::VectorXd rate_left = -s.e.transpose() * x.tail(n);
    Eigen::VectorXd right, rate_right, h_q, rate_q;
    auto rows = [&](double time, Eigen::VectorXd& h, Eigen::VectorXd& rate) { s.rows_at(p, coef, ta, time, h, rate); };
    // The samples of e_cᵀu at times before `limit`, on this flight.
    auto fill_samples = [&](double limit) {
      for (; next_sample < samples && sample_time(next_sample) < limit; ++next_sample) {
        out.state_samples.col(next_sample) = at(sample_time(next_sample));
        out.contact_displacement.col(next_sample) = s.e.transpose() * out.state_samples.col(next_sample).head(n);
      }
    };
    for (int i = 0; i < nc; ++i) {
      if (fresh[static_cast<size_t>(i)] && !active[static_cast<size_t>(i)])
        left(i) = std::numeric_limits<double>::infinity();
    }
    int hit = -1;
    double t_hit = 0.0;
    // e^{Λ(t − t_a)} at the brackets' ends as products with e^{Λh} (h the bracket's length), exact
    // at a flight's end and every 32nd bracket (the products' rounding grows like their count).
    Eigen::VectorXcd d_left = Eigen::VectorXcd::Ones(p.lambda.size()), d_right, d_step;
    double h_of_step = -1.0;
    int products = 0;
    while (t_left < t_end && hit < 0) {
      const double t_right = std::min(t_left + h_step, t_end);
      if (t_right == t_end || ++products == 32) {
        d_right = decay(p, t_right - ta);
        products = 0;
      } else {
        if (h_step != h_of_step) {
          d_step = decay(p, h_step);
          h_of_step = h_step;
        }
        d_right = d_left.cwiseProduct(d_step);
      }
      s.rows_at(p, coef, d_right, t_right, right, rate_right);
      d_left.swap(d_right);
      for (int i = 0; i < nc; ++i) {
        const bool just_left = fresh[static_cast<size_t>(i)] && !active[static_cast<size_t>(i)];
        if (!just_left && !(left(i) > 0.0)) continue;
        double lo = t_left, hi = t_right;
        if (just_left) {
          // The stop of the last event, whose gap leaves 0 slowly (like τ² after a plastic impact that
          // does not close, τ³ after a release), below the rounding of e_cᵀu at first: until it is
          // clearly open at a bracket's end, a return counts when the gap is clearly negative at the
          // bracket's end, and the stop must have clearly opened in between (16 samples), else the
          // impacts accumulate.
          const double noise = 1e-11 * (std::abs(s.g(i)) + std::abs(s.e.col(i).dot(x.head(n))));
          if (right(i) > noise) {
            fresh[static_cast<size_t>(i)] = 0;  // open: the plain search from the next bracket
            continue;
          }
          if (right(i) > -noise) continue;
          lo = -1.0;
          for (int q = 1; q < 16 && lo < 0.0; ++q) {
            const double tq = t_left + (t_right - t_left) * q / 16.0;
            rows(tq, h_q, rate_q);
            if (h_q(i) > noise) lo = tq;
          }
          if (lo < 0.0) {
            throw std::domain_error("ImpactFlow::flow: stop " + std::to_string(i) + " returned within " +
                                    num(t_right - t_left0) + " s of its last event at t = " + num(t) +
                                    " s without opening (chatter or grazing): the orbit accumulates impacts, "
                                    "which the event-driven flow does not resolve");
          }
        } else if (right(i) > 0.0) {  // a gap that dips below zero and back inside the bracket
          if (active[static_cast<size_t>(i)] || !(rate_left(i) < 0.0 && rate_right(i) > 0.0)) continue;
          auto falling = [&](double time) {  // −ρ_c
            rows(time, h_q, rate_q);
            return -rate_q(i);
          };
          hi = locate(falling, t_left, t_right, std::max(tolerance, 4e-16 * std::abs(t_right)));
          rows(hi, h_q, rate_q);
          if (!(h_q(i) <= 0.0)) continue;
        }
        auto indicator = [&](double time) {
          rows(time, h_q, rate_q);
          return h_q(i);
        };
        const double te = locate(indicator, lo, hi, std::max(tolerance, 4e-16 * std::abs(hi)));
        if (hit < 0 || te < t_hit) {
          hit = i;
          t_hit = te;
        }
      }
      const double t_stop = hit >= 0 ? t_hit : t_right;
      fill_samples(t_stop);
      left = right;
      rate_left = rate_right;
      t_left = t_right;
      h_step = std::min(2.0 * h_step, h_cap);
    }
    const double t_stop = hit >= 0 ? t_hit : t_end;
    const Eigen::VectorXd x_minus = at(t_stop);
    monodromy.flight(p, t_stop - ta);
    std::fill(fresh.begin(), fresh.end(), 0);
    if (hit < 0) {
      out.state = x_minus;
      out.monodromy = monodromy.matrix();
      out.active = active;
      fill_samples(std::numeric_limits<double>::infinity());
      return out;
    }
    if (static_cast<int>(out.events.size()) >= s.options.max_events) {
      throw std::domain_error("ImpactFlow::flow: more than ImpactFlowOptions.max_events = " +
                              std::to_string(s.options.max_events) + " events (an accumulation of impacts?); raise it");
    }
    ImpactEvent ev;
    ev.time_s = t_stop;
    ev.contact = hit;
    ev.normal_velocity = s.e.col(hit).dot(x_minus.tail(n));
    t = t_stop;
    fresh[static_cast<size_t>(hit)] = 1;
    if (active[static_cast<size_t>(hit)]) {  // release: S = I
      ev.kind = ImpactEventKind::Release;
      active[static_cast<size_t>(hit)] = 0;
      x = x_minus;
      out.events.push_back(ev);
      continue;
    }
    // Impact: the impulse closes stop `hit` (e_cᵀ u̇⁺ = −e e_cᵀ u̇⁻) and keeps the closed stops closed.
    if (!(ev.normal_velocity > 0.0)) {
      throw std::domain_error("ImpactFlow::flow: grazing contact with stop " + std::to_string(hit) +
                              " at t = " + num(t_stop) + " s (normal velocity " + num(ev.normal_velocity) +
                              " m/s): the saltation matrix is unbounded there");
    }
    std::vector<int> cols = p.closed;
    cols.push_back(hit);
    const auto nn = static_cast<Eigen::Index>(cols.size());
    Eigen::MatrixXd ep(n, nn);
    Eigen::VectorXd d = Eigen::VectorXd::Ones(nn);
    for (Eigen::Index j = 0; j < nn; ++j) ep.col(j) = s.e.col(cols[static_cast<size_t>(j)]);
    d(nn - 1) = 1.0 + s.options.restitution;
    const Eigen::MatrixXd minv_ep = s.m_llt.solve(ep);
    const Eigen::MatrixXd w_inv_dt = (ep.transpose() * minv_ep).ldlt().solve(d.asDiagonal() * ep.transpose());
    const Eigen::VectorXd impulse = w_inv_dt * x_minus.tail(n);
    for (Eigen::Index j = 0; j + 1 < nn; ++j) {
      if (impulse(j) < -1e-9 * std::abs(impulse(nn - 1))) {
        throw std::domain_error("ImpactFlow::flow: the impact on stop " + std::to_string(hit) +
                                " would pull on closed stop " + std::to_string(cols[static_cast<size_t>(j)]) +
                                " (a simultaneous release, not covered)");
      }
    }
    Eigen::MatrixXd rmap = Eigen::MatrixXd::Identity(2 * n, 2 * n);
    rmap.bottomRightCorner(n, n) -= minv_ep * w_inv_dt;
    x = rmap * x_minus;
    const Eigen::VectorXd f_minus = s.field(p, t_stop, x_minus);
    if (s.options.restitution == 0.0) {  // a contact phase if the closed stop pushes
      std::vector<char> closed = active;
      closed[static_cast<size_t>(hit)] = 1;
      const Phase& pc = s.phase(closed);
      const Eigen::VectorXd lam = s.forces(pc, t_stop, x);
      const auto pos = std::find(pc.closed.begin(), pc.closed.end(), hit) - pc.closed.begin();
      if (lam(pos) > 0.0) {
        active = closed;
        ev.closes = true;
      }
    }
    const Eigen::VectorXd f_plus = s.field(s.phase(active), t_stop, x);
    // S = R + (f⁺ − R f⁻) ∇hᵀ / (∇hᵀ f⁻), ∇h = (−e_c, 0): ∇hᵀ f⁻ = −e_cᵀ u̇⁻. As I + A Bᵀ: R = I + Σ_j
    // (0, M⁻¹ e′_j)(0, −W′⁻¹D E′ᵀ)_j, and the field term (f⁺ − R f⁻)(e_c/(e_cᵀu̇⁻), 0)ᵀ.
    Eigen::MatrixXd low_a = Eigen::MatrixXd::Zero(2 * n, nn + 1), low_b = Eigen::MatrixXd::Zero(2 * n, nn + 1);
    low_a.bottomLeftCorner(n, nn) = minv_ep;
    low_b.bottomLeftCorner(n, nn) = -w_inv_dt.transpose();
    low_a.col(nn) = f_plus - rmap * f_minus;
    low_b.col(nn).head(n) = s.e.col(hit) / ev.normal_velocity;
    monodromy.saltation(low_a, low_b);
    out.events.push_back(ev);
  }
}

}  // namespace wbm::solvers
