#pragma once
// Private to wbm_solvers: the monodromy stepping of floquet.hpp (trapezoidal rule for the contact
// stiffness, the linear part exact, a switch split at its interpolated crossing, runs of equal
// steps by binary powers), written once for any representation of the linear part, and the
// multipliers' analysis shared by the two representations:
// - floquet.cpp: the balanced physical state (δu, δu̇/σ), e^{A₀h} by Eigen's Padé exponential of
//   the dense 2n × 2n matrix (any damping matrix);
// - floquet_modal.cpp: the undamped modes' coordinates (q, q̇/s) of a classical damping matrix,
//   where e^{A₀h} is one 2 × 2 block per mode in closed form, set up once per branch.
// Both are similar to the physical state, so they give the same multipliers.

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/mechanical_system.hpp>

namespace wbm::solvers::detail {

/// The balanced state ỹ = (δu, δu̇ / σ), σ = √‖M⁻¹K‖₁ [1/s] (1 without stiffness): Ã₀ = D A₀ D⁻¹
/// with D = diag(I, I/σ) has the blocks [[0, σI], [−M⁻¹K/σ, −M⁻¹C]], whose norms are both about the
/// highest natural frequency, while ‖A₀‖₁ is its square. Scaling and squaring takes
/// log₂(‖A₀h‖₁ / 5.4) squarings, each losing accuracy: for the rod of jl14_case2 (25 elements,
/// h = T/8192) ‖A₀h‖₁ = 8.1e3 gave blocks of e^{A₀h} wrong by 3e-13 relative, in 0.63 ms, and
/// ‖Ã₀h‖₁ = 0.057 gives them to 3e-16, in 0.12 ms (Padé without squaring).
struct Balanced {
  Eigen::MatrixXd a0;           // Ã₀, 2n × 2n
  Eigen::MatrixXd u;            // D b_c = (0, −M⁻¹ e_c / σ), 2n × n_c
  Eigen::MatrixXd flexibility;  // E M⁻¹ Eᵀ, n_c × n_c [1/kg]
  double sigma = 1.0;
};

/// One dense LU of M, O(n³). floquet.cpp.
[[nodiscard]] Balanced balanced_system(const MechanicalSystem& system, const std::vector<ContactPoint>& contacts);

/// floquet_multipliers on a balanced system set up beforehand (the input already checked).
[[nodiscard]] FloquetResult balanced_floquet(const Balanced& balanced, const std::vector<ContactPoint>& contacts,
                                             const Eigen::MatrixXd& contact_displacement, double frequency_hz);

/// Multipliers by decreasing modulus, spectral radius and error estimate (FloquetResult's
/// fields other than `monodromy` and `steps`) of a monodromy matrix `phi` in any coordinates
/// similar to the physical state, with `phi_half` that of the same orbit on the P/2 even samples
/// (empty: no estimate, every error inf). floquet.cpp.
void analyse_monodromy(const Eigen::MatrixXd& phi, const Eigen::MatrixXd& phi_half, FloquetResult& out);

/// Validation shared by both paths: friction and rigid stops refused, P ≥ 8, one row per contact,
/// finite samples, f > 0 (std::invalid_argument, the messages of floquet_multipliers).
void check_floquet_input(const std::vector<ContactPoint>& contacts, const Eigen::MatrixXd& contact_displacement,
                         double frequency_hz);
void check_floquet_contacts(const std::vector<ContactPoint>& contacts);

/// The stepping below is explicit in the contact force (e_cᵀ b_d = 0 makes its trapezoidal rule a
/// kick–flight–kick, Störmer–Verlet in the contact springs): it is stable only while h ω_c < 2,
/// ω_c² the largest eigenvalue of K_c G, K_c = diag(max over the samples of each contact's
/// stiffness), G = E M⁻¹ Eᵀ (n_c × n_c, the contacts' inverse mass [1/kg]), bounded here by
/// Gershgorin: max_c k_c Σ_d |G_cd|. Beyond it the computed multipliers grow without bound (1e13
/// on LL11's blade at P = 512, h ω_c = 29). floquet.cpp.
inline constexpr double kResolvedPhase = 0.5;              // the h ω_c the steps are raised to
inline constexpr Eigen::Index kMaxResolvedSteps = 32768;  // beyond, the contact is refused

/// s, the smallest power of two with h ω_c / s ≤ kResolvedPhase at P s steps (so the P/2
/// estimate stays at ≤ 1); 1 when the samples resolve the contacts. Throws
/// std::invalid_argument naming the contact and its stiffness when P s would exceed
/// kMaxResolvedSteps.
[[nodiscard]] Eigen::Index resolution_factor(const std::vector<ContactPoint>& contacts,
                                             const Eigen::MatrixXd& contact_displacement, double frequency_hz,
                                             const Eigen::MatrixXd& flexibility);

/// contact_displacement refined by linear interpolation (the interpolant the crossings already
/// use) to P s samples, s = resolution_factor(...); unchanged when s = 1. Same exception.
[[nodiscard]] Eigen::MatrixXd resolved_samples(const std::vector<ContactPoint>& contacts,
                                               const Eigen::MatrixXd& contact_displacement, double frequency_hz,
                                               const Eigen::MatrixXd& flexibility);

/// The P/2 even samples of contact_displacement (n_c × P/2).
[[nodiscard]] inline Eigen::MatrixXd even_samples(const Eigen::MatrixXd& contact_displacement) {
  Eigen::MatrixXd half(contact_displacement.rows(), contact_displacement.cols() / 2);
  for (Eigen::Index q = 0; q < half.cols(); ++q) half.col(q) = contact_displacement.col(2 * q);
  return half;
}

/// A Jenkins element along the orbit of the monodromy's samples (floquet.hpp, "Jenkins elements"),
/// one per hysteretic contact in contact order. floquet.cpp.
struct JenkinsSamples {
  Eigen::Index contact = 0;           // its index in the contacts
  Eigen::Index normal = -1;           // ContactPoint::normal, or −1 (a constant normal load)
  double tangential_stiffness = 0.0;  // k_t [N/m]
  bool full_stick = false;            // no sample slips: a spring k_t (the slider's neutral direction left out)
  Eigen::VectorXd load_sensitivity;   // ∂f_q/∂n_q = μ σ_q at a slip sample, 0 at a stick one [-]
  std::vector<char> stick;            // per sample, from the periodic loop: the slider holds
  /// The located switches in sample time t ∈ [0, P) (step p is [p, p + 1)), sorted, alternating:
  /// (t, true) where a stick begins, (t, false) where a slip begins. Empty in full stick and in
  /// permanent slip.
  std::vector<std::pair<double, bool>> switches;
  /// Whether the slider holds at sample time t (the last switch at or before t, cyclically).
  [[nodiscard]] bool sticks_at(double t) const {
    if (switches.empty()) return full_stick;
    auto it = std::upper_bound(switches.begin(), switches.end(), t,
                               [](double x, const std::pair<double, bool>& e) { return x < e.first; });
    return it == switches.begin() ? switches.back().second : std::prev(it)->second;
  }
};

/// The elements of the hysteretic contacts on contact_displacement (n_c × P, relative
/// displacements): the periodic loop by evaluate_contact_period, and its switches located between
/// the samples (floquet.hpp). Throws std::invalid_argument for a hysteretic law that is not a
/// contact::JenkinsLaw.
[[nodiscard]] std::vector<JenkinsSamples> jenkins_samples(const std::vector<ContactPoint>& contacts,
                                                         const Eigen::MatrixXd& contact_displacement);

/// The number of hysteretic contacts: the states the monodromy matrix carries beyond 2n.
[[nodiscard]] inline Eigen::Index jenkins_states(const std::vector<ContactPoint>& contacts) {
  return std::count_if(contacts.begin(), contacts.end(), [](const ContactPoint& c) { return c.law->hysteretic(); });
}

/// stepped_monodromy with Jenkins elements (floquet.hpp, "Jenkins elements"): the state (y, φ),
/// φ_j the perturbation of Jenkins element j's force [N], (states + n_J) × (states + n_J), or that
/// times `start` ((states + n_J) × r). Every step is stepped (no runs of powers), split at the
/// penalty laws' interpolated crossings and at each element's located switches. Memoryless
/// contacts kick as in stepped_monodromy; an element in full stick is a spring k_t, its φ row 0.
template <class LinearPart>
Eigen::MatrixXd stepped_monodromy_jenkins(const LinearPart& linear, const std::vector<ContactPoint>& contacts,
                                          const Eigen::MatrixXd& contact_displacement, double frequency_hz,
                                          const Eigen::MatrixXd* start) {
  const auto nc = static_cast<Eigen::Index>(contacts.size());
  const Eigen::Index p_count = contact_displacement.cols();
  const Eigen::Index states = linear.states();
  const std::vector<JenkinsSamples> jenkins = jenkins_samples(contacts, contact_displacement);
  const auto nj = static_cast<Eigen::Index>(jenkins.size());
  const Eigen::MatrixXd& u = linear.u();
  const double h = 1.0 / (frequency_hz * static_cast<double>(p_count));
  std::vector<Eigen::Index> element(static_cast<size_t>(nc), -1);  // contact → its Jenkins element
  for (Eigen::Index j = 0; j < nj; ++j) element[static_cast<size_t>(jenkins[static_cast<size_t>(j)].contact)] = j;
  Eigen::MatrixXd y, phi;  // states × cols, n_J × cols
  if (start != nullptr) {
    y = start->topRows(states);
    phi = start->bottomRows(nj);
  } else {
    y = Eigen::MatrixXd::Identity(states, states + nj);
    phi = Eigen::MatrixXd::Zero(nj, states + nj);
    phi.rightCols(nj).setIdentity();
  }
  // The memoryless stiffnesses at the relative displacements uc: the laws' for penalty contacts,
  // k_t for an element in full stick, 0 for the other elements (their force is φ). An element's
  // row of uc is not read (a drift does not enter).
  auto memoryless = [&](const Eigen::VectorXd& uc) {
    Eigen::VectorXd k(nc);
    for (Eigen::Index c = 0; c < nc; ++c) {
      const Eigen::Index j = element[static_cast<size_t>(c)];
      if (j < 0) {
        k(c) = contacts[static_cast<size_t>(c)].law->stiffness(uc(c));
      } else {
        const JenkinsSamples& e = jenkins[static_cast<size_t>(j)];
        k(c) = e.full_stick ? e.tangential_stiffness : 0.0;
      }
    }
    return k;
  };
  auto displacement_at = [&](Eigen::Index p, double theta) {  // linear between the samples
    return Eigen::VectorXd((1.0 - theta) * contact_displacement.col(p) +
                           theta * contact_displacement.col((p + 1) % p_count));
  };
  // The memoryless stiffnesses at the samples, formed once (the pieces' ends at a sample use them).
  Eigen::MatrixXd at_samples(nc, p_count);
  for (Eigen::Index q = 0; q < p_count; ++q) at_samples.col(q) = memoryless(contact_displacement.col(q));
  // The kick changes velocities only (e_cᵀ b_d = 0, u's top rows zero in both linear parts): the
  // contact displacements `rows` of y before it are those after it, and only the velocity half of
  // the state is multiplied.
  const Eigen::Index half = states / 2;
  const bool velocity_rows = u.topRows(half).isZero(0.0);
  Eigen::MatrixXd force(nc, y.cols());
  auto kick = [&](const Eigen::Ref<const Eigen::VectorXd>& k, double hs, const Eigen::MatrixXd& rows) {
    force.noalias() = (0.5 * hs) * (k.asDiagonal() * rows);
    for (Eigen::Index j = 0; j < nj; ++j) force.row(jenkins[static_cast<size_t>(j)].contact) += (0.5 * hs) * phi.row(j);
    if (velocity_rows) {
      y.bottomRows(states - half).noalias() += u.bottomRows(states - half) * force;
    } else {
      y.noalias() += u * force;
    }
  };
  // φ in slip: the slip force's perturbation μ σ n'(u_n) δu_n, n' the normal law's stiffness there
  // (0 under a constant normal load), σ that of the nearest slip sample of step p.
  auto set_slip_value = [&](Eigen::Index j, Eigen::Index p, double n_slope, const Eigen::MatrixXd& rows) {
    const JenkinsSamples& e = jenkins[static_cast<size_t>(j)];
    if (e.normal < 0) {
      phi.row(j).setZero();
      return;
    }
    const Eigen::Index q1 = (p + 1) % p_count, q = e.stick[static_cast<size_t>(q1)] ? p : q1;
    phi.row(j).noalias() = (e.load_sensitivity(q) * n_slope) * rows.row(e.normal);
  };
  auto normal_slope = [&](Eigen::Index j, const Eigen::VectorXd& at) {
    const JenkinsSamples& e = jenkins[static_cast<size_t>(j)];
    return e.normal < 0 ? 0.0 : contacts[static_cast<size_t>(e.normal)].law->stiffness(at(e.normal));
  };
  const auto whole_step = linear.flight(h);
  Eigen::MatrixXd previous = linear.rows(y);  // the contact displacements at φ's last update (and now)
  std::vector<double> edges;
  for (Eigen::Index p = 0; p < p_count; ++p) {
    const Eigen::Index q1 = (p + 1) % p_count;
    const auto tp = static_cast<double>(p);
    edges.assign({0.0, 1.0});
    for (Eigen::Index c = 0; c < nc; ++c) {  // penalty laws' gap crossings, as stepped_monodromy
      if (element[static_cast<size_t>(c)] >= 0) continue;
      const double g = contacts[static_cast<size_t>(c)].law->gap();
      const double d0 = contact_displacement(c, p) - g, d1 = contact_displacement(c, q1) - g;
      if ((d0 > 0.0) != (d1 > 0.0) && d0 != d1) edges.push_back(d0 / (d0 - d1));
    }
    for (const JenkinsSamples& e : jenkins) {  // the elements' switches inside this step
      for (const auto& [t, sticks] : e.switches) {
        if (t > tp && t < tp + 1.0) edges.push_back(t - tp);
      }
    }
    std::sort(edges.begin(), edges.end());
    for (size_t i = 0; i + 1 < edges.size(); ++i) {
      const double a = edges[i], b = edges[i + 1], inside = 1e-9 * (b - a);
      if (!(b > a)) continue;
      const double hs = (b - a) * h;
      const bool last = i + 2 == edges.size();
      if (i == 0) {
        kick(at_samples.col(p), hs, previous);
      } else {
        kick(memoryless(displacement_at(p, a + inside)), hs, previous);
      }
      if (a == 0.0 && b == 1.0) {
        linear.apply(whole_step, y);  // a step without a switch: its flight formed once
      } else {
        linear.apply(linear.flight(hs), y);
      }
      const Eigen::VectorXd u_end = last ? Eigen::VectorXd() : displacement_at(p, b - inside);
      const Eigen::MatrixXd now = linear.rows(y);
      // φ at the piece's end: the stick recurrence φ + k_t (δw − δw_prev), or the slip value.
      for (Eigen::Index j = 0; j < nj; ++j) {
        const JenkinsSamples& e = jenkins[static_cast<size_t>(j)];
        if (e.full_stick) {
          phi.row(j).setZero();
        } else if (e.sticks_at(tp + 0.5 * (a + b))) {
          phi.row(j) += e.tangential_stiffness * (now.row(e.contact) - previous.row(e.contact));
        } else {
          const double n_slope = e.normal < 0 ? 0.0 : (last ? at_samples(e.normal, q1) : normal_slope(j, u_end));
          set_slip_value(j, p, n_slope, now);
        }
      }
      previous = now;
      kick(last ? Eigen::VectorXd(at_samples.col(q1)) : memoryless(u_end), hs, now);
      // A slip that begins at b (inside the step, or at its end when a located onset falls on the
      // sample): the next piece starts from the slip value.
      const double period = static_cast<double>(p_count);
      const double next = std::fmod(last ? tp + 1.0 + 1e-9 : tp + 0.5 * (b + edges[i + 2]), period);
      for (Eigen::Index j = 0; j < nj; ++j) {
        const JenkinsSamples& e = jenkins[static_cast<size_t>(j)];
        if (!e.full_stick && e.sticks_at(tp + 0.5 * (a + b)) && !e.sticks_at(next)) {
          set_slip_value(j, p, last ? (e.normal < 0 ? 0.0 : at_samples(e.normal, q1))
                                    : normal_slope(j, displacement_at(p, b + inside)),
                         now);
        }
      }
    }
  }
  Eigen::MatrixXd out(states + nj, y.cols());
  out.topRows(states) = y;
  out.bottomRows(nj) = phi;
  return out;
}

/// Φ = Y(T) in the coordinates of `linear`, by the stepping of floquet.hpp on the P =
/// contact_displacement.cols() samples; with `start` (2n × r), Φ · start instead, stepping the r
/// columns through every step (O(P n n_c r), no 2n × 2n powers: Arnoldi's products Φ v).
/// LinearPart provides:
///   Eigen::Index states() const;                              2n
///   Flight flight(double hs) const;                           e^{A₀ hs}, hs [s]
///   void apply(const Flight&, Eigen::MatrixXd& z) const;      z ← e^{A₀ hs} z
///   Eigen::MatrixXd rows(const Eigen::MatrixXd& z) const;     e_cᵀ z (n_c × cols): contact displacements
///   const Eigen::MatrixXd& u() const;                         b_c (2n × n_c): velocity kick per unit force
///   static constexpr bool kExactFreeRuns;                     a contact-free run of L steps is flight(L h)
/// e_cᵀ b_d = 0 (the force changes velocities only) is what makes the trapezoidal rule a kick of
/// (h/2)(k_p + k_{p+1})-weighted forces between exact flights.
template <class LinearPart>
Eigen::MatrixXd stepped_monodromy(const LinearPart& linear, const std::vector<ContactPoint>& contacts,
                                  const Eigen::MatrixXd& contact_displacement, double frequency_hz,
                                  const Eigen::MatrixXd* start = nullptr) {
  if (jenkins_states(contacts) > 0) {
    return stepped_monodromy_jenkins(linear, contacts, contact_displacement, frequency_hz, start);
  }
  using Flight = decltype(linear.flight(1.0));
  const auto nc = static_cast<Eigen::Index>(contacts.size());
  const Eigen::Index p_count = contact_displacement.cols();
  const Eigen::Index states = linear.states();
  const Eigen::MatrixXd& u = linear.u();
  const double h = 1.0 / (frequency_hz * static_cast<double>(p_count));
  const Flight step = linear.flight(h);
  auto stiffness = [&](Eigen::Index p) {  // k_c(t_p), periodic in p
    Eigen::VectorXd k(nc);
    const Eigen::Index q = p % p_count;
    for (Eigen::Index c = 0; c < nc; ++c) {
      k(c) = contacts[static_cast<size_t>(c)].law->stiffness(contact_displacement(c, q));
    }
    return k;
  };
  // e_cᵀ b_d (n_c × n_c) for the Woodbury solve. It is exactly zero when the kick has no
  // displacement part (both linear parts here): (I − D E U)⁻¹ = I, and the solve is skipped
  // (the LU of I solves exactly: the same bits).
  const Eigen::MatrixXd eu = linear.rows(u);
  const bool kick_is_velocity = eu.isZero(0.0);

  Eigen::MatrixXd y = start != nullptr ? *start : Eigen::MatrixXd::Identity(states, states);
  // One trapezoidal step of length hs from stiffnesses ka (start) to kb (end), applied to z:
  //   (I − (hs/2) K_b) Z ← e^{A₀ hs} (I + (hs/2) K_a) Z, the inverse by Woodbury.
  auto trapezoid_on = [&](Eigen::MatrixXd& z, const Flight& exp_step, double hs, const Eigen::VectorXd& ka,
                          const Eigen::VectorXd& kb) {
    if (!ka.isZero(0.0)) z += u * ((0.5 * hs) * ka.asDiagonal() * linear.rows(z));
    linear.apply(exp_step, z);
    if (!kb.isZero(0.0)) {
      if (kick_is_velocity) {
        z += u * ((0.5 * hs) * kb.asDiagonal() * linear.rows(z));
      } else {
        const Eigen::MatrixXd d = (0.5 * hs) * kb.asDiagonal();
        const Eigen::MatrixXd small = Eigen::MatrixXd::Identity(nc, nc) - d * eu;
        z += u * small.partialPivLu().solve(d * linear.rows(z));
      }
    }
  };
  // Runs of whole steps over which no contact crosses its gap and every contact's stiffness is
  // the same at both ends of each step: each step is one matrix T_k, e^{A₀h} without contact
  // stiffness, the trapezoidal step at k otherwise (a linear penalty stop keeps k over a whole
  // contact phase). A run of L steps is T_k^L by binary powers T_k^{2^j}, kept per k (at most
  // kMaxRuns of them): O(log L) products instead of L; without contact stiffness and an exact
  // flight, e^{A₀Lh} itself.
  struct RunPowers {
    Eigen::VectorXd k;
    std::vector<Eigen::MatrixXd> powers;  // T_k^{2^j}
  };
  constexpr size_t kMaxRuns = 8;
  std::vector<RunPowers> runs;
  Eigen::VectorXd run_k = Eigen::VectorXd::Zero(nc);
  Eigen::Index run_length = 0;
  auto advance_run = [&] {
    if (run_length == 0) return;
    if (run_k.isZero(0.0) && (LinearPart::kExactFreeRuns || run_length == 1)) {
      linear.apply(run_length == 1 ? step : linear.flight(h * static_cast<double>(run_length)), y);
      run_length = 0;
      return;
    }
    if (run_length == 1 || start != nullptr) {  // one step, or a few columns: no power to form
      for (; run_length > 0; --run_length) trapezoid_on(y, step, h, run_k, run_k);
      return;
    }
    auto it = std::find_if(runs.begin(), runs.end(), [&](const RunPowers& r) { return r.k == run_k; });
    if (it == runs.end()) {
      if (runs.size() == kMaxRuns) runs.clear();
      Eigen::MatrixXd t = Eigen::MatrixXd::Identity(states, states);
      trapezoid_on(t, step, h, run_k, run_k);  // e^{A₀h} alone without contact stiffness
      runs.push_back({run_k, {std::move(t)}});
      it = runs.end() - 1;
    }
    std::vector<Eigen::MatrixXd>& powers = it->powers;
    for (size_t j = 0; run_length > 0; ++j, run_length >>= 1) {
      if (j == powers.size()) powers.push_back(powers.back() * powers.back());
      if (run_length & 1) y = powers[j] * y;
    }
  };
  // Fractions θ ∈ (0, 1) of step p where a contact displacement, interpolated linearly between
  // the samples, crosses its gap (where the law's stiffness jumps), sorted.
  auto crossings = [&](Eigen::Index p) {
    std::vector<double> theta;
    const Eigen::Index q0 = p % p_count, q1 = (p + 1) % p_count;
    for (Eigen::Index c = 0; c < nc; ++c) {
      const double g = contacts[static_cast<size_t>(c)].law->gap();
      const double d0 = contact_displacement(c, q0) - g, d1 = contact_displacement(c, q1) - g;
      if ((d0 > 0.0) != (d1 > 0.0) && d0 != d1) {
        const double t = d0 / (d0 - d1);
        if (t > 0.0 && t < 1.0) theta.push_back(t);
      }
    }
    std::sort(theta.begin(), theta.end());
    return theta;
  };
  // Stiffnesses at fraction θ of step p, from the linear interpolant of the samples.
  auto stiffness_at = [&](Eigen::Index p, double theta) {
    Eigen::VectorXd k(nc);
    const Eigen::Index q0 = p % p_count, q1 = (p + 1) % p_count;
    for (Eigen::Index c = 0; c < nc; ++c) {
      const double uc = (1.0 - theta) * contact_displacement(c, q0) + theta * contact_displacement(c, q1);
      k(c) = contacts[static_cast<size_t>(c)].law->stiffness(uc);
    }
    return k;
  };
  Eigen::VectorXd k_now = stiffness(0);
  for (Eigen::Index p = 0; p < p_count; ++p) {
    const Eigen::VectorXd k_next = stiffness(p + 1);
    const std::vector<double> theta = crossings(p);
    if (!theta.empty()) {
      // A contact opens or closes inside the step: the jump of its stiffness is placed at the
      // interpolated crossing, each piece integrated with one-sided stiffnesses (evaluated a
      // relative 1e-9 inside the piece). Without this split the switch sits at a sample, which
      // is first order in h, with an error growing with the stop's stiffness (issue #19).
      advance_run();
      std::vector<double> edges = {0.0};
      edges.insert(edges.end(), theta.begin(), theta.end());
      edges.push_back(1.0);
      for (size_t i = 0; i + 1 < edges.size(); ++i) {
        const double a = edges[i], b = edges[i + 1], inside = 1e-9 * (b - a);
        if (!(b > a)) continue;
        const double hs = (b - a) * h;
        trapezoid_on(y, linear.flight(hs), hs, i == 0 ? k_now : stiffness_at(p, a + inside),
                     i + 2 == edges.size() ? k_next : stiffness_at(p, b - inside));
      }
      k_now = k_next;
      continue;
    }
    if (k_now == k_next) {
      if (run_length > 0 && k_now != run_k) advance_run();
      run_k = k_now;
      ++run_length;
      continue;
    }
    advance_run();
    trapezoid_on(y, step, h, k_now, k_next);
    k_now = k_next;
  }
  advance_run();
  return y;
}

}  // namespace wbm::solvers::detail
