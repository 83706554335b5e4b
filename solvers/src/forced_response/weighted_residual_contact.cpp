// WeightedResidual, contact: the contact displacement samples, the contact forces n(x) under either
// quadrature rule, their Jacobians N(x) (dense, low rank I + H W V, Fourier:Fourier shift kernel) and
// the compliance H = P G⁻¹ Pᵀ (weighted_residual_impl.hpp).
#include "weighted_residual_impl.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>

#include <unsupported/Eigen/KroneckerProduct>

namespace wbm::solvers {

namespace detail {

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

}  // namespace detail

Eigen::Index rank;
Eigen::MatrixXd WeightedResidual::Impl::TrialRows::operator()(const Eigen::MatrixXd& y) const {
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


void WeightedResidual::Impl::set_compliance() {
  h = g->compliance(contact_directions(), contact_terms, false);
  h_deferred = g->circulant_compliance();
  h_once = std::make_unique<std::once_flag>();  // H of this frequency, formed on first read
  const auto size = static_cast<double>(nc) * m;
  const auto nonzeros = h_deferred ? g->circulant_compliance_nonzeros() : (h.array() != 0.0).count();
  h_is_sparse = static_cast<double>(nonzeros) <= 0.25 * size * size;
  h_sparse.reset();
  if (h_is_sparse) h_sparse = std::make_shared<const Eigen::SparseMatrix<double>>(dense_h().sparseView());
}


Eigen::MatrixXd WeightedResidual::Impl::compliance_times(const Eigen::MatrixXd& v) const {
  if (v.cols() == 0) return Eigen::MatrixXd(v.rows(), 0);
  if (h_is_sparse) return *h_sparse * v;
  if (g->fast_compliance_product()) return g->compliance_product(v);
  return dense_h() * v;
}


bool WeightedResidual::Impl::fourier_sparse_compliance() const {
  return trial.is_fourier() && weighting.is_fourier() && h_is_sparse;
}


bool WeightedResidual::Impl::couples_only_within_harmonics(double tol) const {
  const spectral::FourierBasis basis(m);
  for (Eigen::Index col = 0; col < h_sparse->outerSize(); ++col) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(*h_sparse, col); it; ++it) {
      const int row_harmonic = basis.harmonic(static_cast<int>(it.row() / nc));
      const int col_harmonic = basis.harmonic(static_cast<int>(it.col() / nc));
      if (std::abs(it.value()) > tol && row_harmonic != col_harmonic) return false;
    }
  }
  return true;
}


bool WeightedResidual::Impl::commutes_with_shifts() const {
  if (!fourier_sparse_compliance()) return false;
  const Eigen::MatrixXd& h = dense_h();
  const double tol = 1e-12 * h.cwiseAbs().maxCoeff();
  if (!couples_only_within_harmonics(tol)) return false;
  const spectral::FourierBasis basis(m);
  const int paired = basis.has_top_function() ? m / 2 - 1 : (m - 1) / 2;
  for (int hh = 1; hh <= paired; ++hh) {  // cos hτ at 2h − 1, sin hτ at 2h (fourier_basis.hpp)
    const Eigen::Index ci = static_cast<Eigen::Index>(2 * hh - 1) * nc, si = static_cast<Eigen::Index>(2 * hh) * nc;
    for (int c = 0; c < nc; ++c) {
      for (int d = 0; d < nc; ++d) {
        const bool rotation = std::abs(h(ci + c, ci + d) - h(si + c, si + d)) <= tol &&
                              std::abs(h(ci + c, si + d) + h(si + c, ci + d)) <= tol;
        if (!rotation) return false;
      }
    }
  }
  return true;
}


std::optional<WeightedResidual::Impl::ShiftKernel> WeightedResidual::Impl::shift_kernel() const {
  if (!fourier_sparse_compliance() || cell_average_rule) return std::nullopt;
  const Eigen::MatrixXd& h = dense_h();
  const double tol = 1e-12 * h.cwiseAbs().maxCoeff();
  if (!couples_only_within_harmonics(tol)) return std::nullopt;
  const spectral::FourierBasis basis(m);
  const bool top = basis.has_top_function();
  const int harmonics = top ? m / 2 : (m - 1) / 2;
  std::vector<int> cos_index(static_cast<size_t>(harmonics) + 1, -1), sin_index = cos_index;
  for (int k = 0; k < m; ++k) (basis.is_sine(k) ? sin_index : cos_index)[static_cast<size_t>(basis.harmonic(k))] = k;
  const int paired = top ? harmonics - 1 : harmonics;
  ShiftKernel k;
  k.kappa.resize(static_cast<size_t>(nc) * nc);
  k.top = Eigen::MatrixXd::Zero(nc, nc);
  k.g = Eigen::VectorXd::Zero(q);
  // cos(2π h s/Q) and sin at column h, from one table of Q angles (h·s mod Q): the sums below run
  // over whole columns (vectorized; the same products and sums as a loop over s, issue #39).
  Eigen::VectorXd cos_table(q), sin_table(q);
  for (int i = 0; i < q; ++i) {
    cos_table(i) = std::cos(2.0 * std::numbers::pi * i / q);
    sin_table(i) = std::sin(2.0 * std::numbers::pi * i / q);
  }
  Eigen::MatrixXd cos_h(q, paired + 1), sin_h(q, paired + 1);
  for (int hh = 1; hh <= paired; ++hh) {
    for (int sft = 0, index = 0; sft < q; ++sft) {  // index = h·s mod Q
      cos_h(sft, hh) = cos_table(index);
      sin_h(sft, hh) = sin_table(index);
      index += hh;
      if (index >= q) index -= q;
    }
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
        kappa.array() += a * cos_h.col(hh).array() - b * sin_h.col(hh).array();
      }
      if (top && kept(m - 1)) k.top(c, d) = at(m - 1, c, m - 1, d);
      k.kappa[static_cast<size_t>(c) * nc + d] = std::move(kappa);
    }
  }
  return k;
}


Eigen::MatrixXd WeightedResidual::Impl::contact_block(const Eigen::VectorXd& kc, const std::vector<int>& active) const {
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


std::vector<int> WeightedResidual::Impl::jenkins_contacts() const {
  std::vector<int> out;
  for (int c = 0; c < nc; ++c) {
    const auto* law = contacts[static_cast<size_t>(c)].law.get();
    if (dynamic_cast<const contact::JenkinsLaw*>(law) != nullptr) out.push_back(c);
  }
  return out;
}


void WeightedResidual::Impl::check_jenkins_piece(const ActiveSet& piece, const char* what) const {
  const size_t expected = jenkins_contacts().size() * static_cast<size_t>(q);
  if (piece.size() != expected) {
    throw std::invalid_argument(std::string("WeightedResidual::") + what + ": the stick/slip piece has " +
                                std::to_string(piece.size()) + " entries; it needs Q = " + std::to_string(q) +
                                " per Jenkins element (" + std::to_string(expected) + ", jenkins_active_set's layout)");
  }
}


Eigen::MatrixXd WeightedResidual::Impl::contact_force_samples(const Eigen::VectorXd& x,
                                                              std::vector<ContactTangent>* tangents,
                                                              const ActiveSet* piece) const {
  refuse_rigid("contact forces as a function of the displacement");
  if (piece != nullptr) check_jenkins_piece(*piece, "contact forces");
  int jenkins_index = 0;  // the block of `piece` of the next Jenkins element
  const Sampling& smp = *sampling;
  const Eigen::MatrixXd u = contact_samples(x);
  Eigen::MatrixXd slope;  // δ_q = u̇_c(τ_q)/Q, CellAverage only
  if (cell_average_rule) slope = smp.trial_slope->to_time(spectral::as_coefficients(x, nc)) / static_cast<double>(q);
  if (cell_average_rule && smp.obstacle_slope.size() > 0) slope -= smp.obstacle_slope;  // relative to the surface
  Eigen::MatrixXd force(nc, q);
  if (tangents != nullptr) tangents->assign(static_cast<size_t>(nc), {});
  Eigen::VectorXd fc(q), kc(q), kd = Eigen::VectorXd::Zero(q);  // f, ∂f/∂u, ∂f/∂δ per sample
  Eigen::VectorXi anchor = Eigen::VectorXi::Constant(q, -1);     // a hysteretic law's last slip
  Eigen::VectorXd load_sensitivity = Eigen::VectorXd::Zero(q);    // ∂f_q/∂n_r under a varying normal load
  contact::JenkinsDiscLoop disc;  // the loop of a two-tangent element, formed at its first tangent
  for (int c = 0; c < nc; ++c) {
    if (cell_average_rule && contacts[c].law->hysteretic()) {
      throw std::invalid_argument("WeightedResidual: contact_quadrature = CellAverage averages a law f(u) over each "
                                  "sample's cell; the contact at DOF " + std::to_string(contacts[c].dof) + " is a " +
                                  contacts[c].law->describe() + ", whose force depends on the history: use "
                                  "contact_quadrature = Midpoint");
    }
    if (const int second = contacts[c].second_tangent; second >= 0) {
      // Tangent 0 of the loop is the element's lower contact index.
      const int first = std::min(c, second), last = std::max(c, second), own = c == first ? 0 : 1;
      if (c == first) disc = jenkins_disc_contact_loop(contacts, first, u, nullptr, tangents != nullptr);
      force.row(c) = disc.force.row(own);
      if (tangents == nullptr) continue;
      ContactTangent& t = (*tangents)[static_cast<size_t>(c)];
      t.kc = Eigen::VectorXd::Zero(q);
      t.kd = Eigen::VectorXd::Zero(q);
      t.anchor = Eigen::VectorXi::Constant(q, -1);
      for (int j = 0; j < 2; ++j) t.dense.emplace_back(j == 0 ? first : last, disc.jacobian.block(own * q, j * q, q, q));
      if (const int n = contacts[c].normal; n >= 0) {  // ∂f/∂u_n = ∂f/∂n · diag(n'(u_n))
        Eigen::VectorXd fn(q), kn(q);
        contacts[n].law->evaluate(u.row(n).transpose(), fn, kn);
        t.dense.emplace_back(n, disc.load_jacobian.middleRows(own * q, q) * kn.asDiagonal());
      }
      continue;
    }
    if (contacts[c].law->hysteretic()) {
      if (piece != nullptr && dynamic_cast<const contact::JenkinsLaw*>(contacts[c].law.get()) != nullptr) {
        const std::vector<std::uint8_t> pattern = jenkins_pattern(*piece, jenkins_index++);
        evaluate_contact_period(contacts, c, u, fc, kc, anchor, load_sensitivity, &pattern);
      } else {
        evaluate_contact_period(contacts, c, u, fc, kc, anchor, load_sensitivity);
      }
    } else if (cell_average_rule) {
      for (int r = 0; r < q; ++r) detail::cell_average(*contacts[c].law, u(c, r), slope(c, r), fc(r), kc(r), kd(r));
    } else {
      contacts[c].law->evaluate(u.row(c).transpose(), fc, kc);
    }
    force.row(c) = fc.transpose();
    if (tangents == nullptr) continue;
    ContactTangent& t = (*tangents)[static_cast<size_t>(c)];
    for (int r = 0; r < q; ++r) {
      if (kc(r) != 0.0) t.active.push_back(r);
      if (kd(r) != 0.0) t.sloped.push_back(r);
      if (kc(r) != 0.0 && anchor(r) >= 0) t.anchored.push_back(r);
    }
    t.kc = kc;
    t.kd = kd;
    t.anchor = anchor;
    if (const int n = contacts[c].normal; n >= 0) {
      t.normal = n;
      for (int r = 0; r < q; ++r) {
        if (load_sensitivity(r) == 0.0) continue;
        const int at = kc(r) != 0.0 ? anchor(r) : r;
        const double kn = contacts[n].law->stiffness(u(n, at));
        if (kn == 0.0) continue;
        t.coupled.push_back(r);
        t.coupled_at.push_back(at);
        t.coupled_weight.push_back(load_sensitivity(r) * kn);
      }
    }
    anchor.setConstant(-1);
    load_sensitivity.setZero();
  }
  return force;
}


std::vector<WeightedResidual::Impl::ForceBlock> WeightedResidual::Impl::contact_force_blocks(
    const std::vector<ContactTangent>& tangents) const {
  std::vector<ForceBlock> blocks;
  for (int c = 0; c < nc; ++c) {
    const ContactTangent& t = tangents[static_cast<size_t>(c)];
    Eigen::MatrixXd block = t.active.empty() ? Eigen::MatrixXd::Zero(m, m) : contact_block(t.kc, t.active);
    if (!t.sloped.empty()) {
      // CellAverage: + Σ_q p_j(τ_q)/Q ∂f̄/∂δ q̇_k(τ_q)/Q over the samples whose cell meets the
      // law's kink (a few per crossing): their rows are evaluated here.
      const auto [ts, ks] = sloped_samples(t);
      block.noalias() += (ks.asDiagonal() * weighting_values(ts)).transpose() * trial.values(ts, 1);
    }
    if (!t.anchored.empty()) {
      // A hysteretic law: − Σ_q p_j(τ_q) κ_q/Q q_k(τ_a(q)) over the stick samples q hanging on
      // the slip sample a(q) (∂f_q/∂u_a = −κ_q).
      const auto na = static_cast<Eigen::Index>(t.anchored.size());
      std::vector<int> slips(t.anchored.size());
      Eigen::VectorXd kq(na);
      for (Eigen::Index i = 0; i < na; ++i) {
        const int r = t.anchored[static_cast<size_t>(i)];
        slips[static_cast<size_t>(i)] = t.anchor(r);
        kq(i) = t.kc(r) / q;
      }
      block -= anchored_product(t.anchored, kq, slips);
    }
    if (!t.dense.empty()) {
      // A Jenkins element with two tangents: + Σ_q Σ_r p_j(τ_q) (∂f_c,q/∂u_c',r)/Q q_k(τ_r), dense.
      std::vector<int> all(static_cast<size_t>(q));
      std::iota(all.begin(), all.end(), 0);
      const Eigen::MatrixXd p = weighting_rows_at(all), v = trial_rows_at(all);
      for (const auto& [column, d] : t.dense) {
        Eigen::MatrixXd b = p.transpose() * (d / q) * v;
        if (column == c) {
          block += b;
        } else {
          blocks.push_back({c, column, std::move(b)});
        }
      }
    }
    blocks.push_back({c, c, std::move(block)});
    if (!t.coupled.empty()) {
      // A varying normal load: + Σ_q p_j(τ_q) (∂f_q/∂u_n,r)/Q q_k(τ_r) into the columns of the
      // normal contact n (r the sample whose slip force f_q hangs on).
      const auto nq = static_cast<Eigen::Index>(t.coupled.size());
      Eigen::VectorXd kq(nq);
      for (Eigen::Index i = 0; i < nq; ++i) kq(i) = t.coupled_weight[static_cast<size_t>(i)] / q;
      blocks.push_back({c, t.normal, anchored_product(t.coupled, kq, t.coupled_at)});
    }
  }
  return blocks;
}


Eigen::MatrixXd WeightedResidual::Impl::contact_force_jacobian(const std::vector<ContactTangent>& tangents) const {
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(nc * m, nc * m);
  for (const ForceBlock& fb : contact_force_blocks(tangents)) {
    for (int k = 0; k < m; ++k) {
      for (int j = 0; j < m; ++j) jac(j * nc + fb.row, k * nc + fb.column) += fb.block(j, k);
    }
  }
  return jac;
}


void WeightedResidual::Impl::scale_tangents(std::vector<ContactTangent>& tangents, double sigma) {
  for (ContactTangent& t : tangents) {
    t.kc *= sigma;
    t.kd *= sigma;
    for (double& w : t.coupled_weight) w *= sigma;
    for (auto& d : t.dense) d.second *= sigma;
  }
}


Eigen::MatrixXd WeightedResidual::Impl::trial_rows_at(const std::vector<int>& at) const {
  return sampling->trial->rows_at(at, trial, sampling->tau);
}


Eigen::MatrixXd WeightedResidual::Impl::anchored_product(const std::vector<int>& r, const Eigen::VectorXd& kappa,
                                                         const std::vector<int>& a) const {
  std::vector<int> distinct = a;
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  const Eigen::MatrixXd p = weighting_rows_at(r);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(distinct.size()), p.cols());
  for (size_t i = 0; i < r.size(); ++i) {
    const auto at = std::lower_bound(distinct.begin(), distinct.end(), a[i]) - distinct.begin();
    g.row(at) += kappa(static_cast<Eigen::Index>(i)) * p.row(static_cast<Eigen::Index>(i));
  }
  return g.transpose() * trial_rows_at(distinct);
}


Eigen::MatrixXd WeightedResidual::Impl::weighting_rows_at(const std::vector<int>& at) const {
  Eigen::MatrixXd v = sampling->weighting->rows_at(at, weighting, sampling->tau);
  if (keep.size() > 0) v *= keep.asDiagonal();
  return v;
}


Eigen::SparseMatrix<double> WeightedResidual::Impl::sparse_contact_force_jacobian(
    const std::vector<ContactTangent>& tangents) const {
  std::vector<Eigen::Triplet<double>> entries;
  for (const ForceBlock& fb : contact_force_blocks(tangents)) {
    for (int k = 0; k < m; ++k) {
      for (int j = 0; j < m; ++j) entries.emplace_back(j * nc + fb.row, k * nc + fb.column, fb.block(j, k));
    }
  }
  Eigen::SparseMatrix<double> nx(nc * m, nc * m);
  nx.setFromTriplets(entries.begin(), entries.end());
  return nx;
}


Eigen::MatrixXd WeightedResidual::Impl::hn_product(const std::vector<ContactTangent>& tangents) const {
  // With H sparse, H N as a product of two sparse matrices: O(nnz(H) M) instead of O(nnz(H) n_c M).
  if (h_is_sparse) return Eigen::MatrixXd(*h_sparse * sparse_contact_force_jacobian(tangents));
  if (g->fast_compliance_product()) return compliance_times(contact_force_jacobian(tangents));
  // Dense H (a Craig–Bampton model, wavelet pairs without a kept structure): N has one M × M block
  // per contact and one per normal coupling, so H N is Σ over the blocks (c, d) of H's columns of
  // contact c times the block, into the columns of contact d: O(blocks · n_c M · M²) instead of
  // the dense product's O((n_c M)³): n_c²/blocks times fewer multiply-adds, 32 on the 48 contacts
  // and 72 blocks of friction_oval_casing's --quick run (M = 7; at M = 13 its H is sparse).
  const Eigen::Index size = static_cast<Eigen::Index>(nc) * m;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(size, size);
  std::vector<Eigen::MatrixXd> columns(static_cast<size_t>(nc));  // H(:, j n_c + c), j = 0 … M − 1
  for (const ForceBlock& fb : contact_force_blocks(tangents)) {
    Eigen::MatrixXd& hc = columns[static_cast<size_t>(fb.row)];
    if (hc.size() == 0) hc = dense_h()(Eigen::all, Eigen::seqN(fb.row, m, nc));
    out(Eigen::all, Eigen::seqN(fb.column, m, nc)) += hc * fb.block;
  }
  return out;
}


Eigen::MatrixXd WeightedResidual::Impl::identity_plus_hn(const std::vector<ContactTangent>& tangents) const {
  Eigen::MatrixXd j = hn_product(tangents);
  j.diagonal().array() += 1.0;
  return j;
}


std::pair<Eigen::VectorXd, Eigen::VectorXd> WeightedResidual::Impl::sloped_samples(const ContactTangent& t) const {
  Eigen::VectorXd ts(static_cast<Eigen::Index>(t.sloped.size())), ks(ts.size());
  for (size_t i = 0; i < t.sloped.size(); ++i) {
    ts(static_cast<Eigen::Index>(i)) = sampling->tau(t.sloped[i]);
    ks(static_cast<Eigen::Index>(i)) = t.kd(t.sloped[i]) / (static_cast<double>(q) * q);
  }
  return {ts, ks};
}


LowRankJacobian WeightedResidual::Impl::low_rank_contact_jacobian(const Eigen::VectorXd& x,
                                                                  const ActiveSet* piece) const {
  std::vector<ContactTangent> tangents;
  (void)contact_forces(x, &tangents, piece);
  return contact_jacobian_from(tangents);
}


LowRankJacobian WeightedResidual::Impl::contact_jacobian_from(const std::vector<ContactTangent>& tangents) const {
  LowRankJacobian jac;
  jac.scale = scale;
  Eigen::Index rank = 0;
  bool anchored = false;  // a hysteretic law's samples hang on earlier ones: W V is not diagonal in the samples
  for (const auto& t : tangents) {
    rank += static_cast<Eigen::Index>(t.active.size() + t.sloped.size());
    // A varying normal load couples two contacts; a two-tangent element is dense in the samples.
    anchored = anchored || !t.anchored.empty() || t.normal >= 0 || !t.dense.empty();
  }
  const Eigen::Index size = static_cast<Eigen::Index>(nc) * m;
  jac.rows = size;
  // The form whose factorized matrix holds the fewest entries: the r × r capacitance, the dense
  // n_c·M square, or (bounded before it is formed) the sparse G + Pᵀ N P.
  const bool low_rank = !anchored && 4 * rank <= 3 * size;
  const double entries = low_rank ? static_cast<double>(rank) * static_cast<double>(rank)
                                  : static_cast<double>(size) * static_cast<double>(size);
  if (rank > 0 || anchored) {
    if (auto sparse = sparse_contact_jacobian(tangents, entries)) return std::move(*sparse);
  }
  if (!low_rank) {
    jac.capacitance = identity_plus_hn(tangents);
    return jac;
  }
  if (rank == 0) {  // no sample in contact: J = I/s, without products of empty matrices (a null data pointer)
    jac.u = Eigen::MatrixXd::Zero(size, 0);
    jac.capacitance.resize(0, 0);
    jac.times_v = [](const Eigen::MatrixXd& y) { return Eigen::MatrixXd(0, y.cols()); };
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


LowRankJacobian WeightedResidual::Impl::shift_kernel_jacobian(const std::vector<ContactTangent>& tangents, LowRankJacobian jac,
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
    // W Z: per contact, the rows of Z times κ_q placed at their samples, projected; only the
    // columns of Z with an entry on the contact's rows (Z = I_r, the bordered corrector's U: r
    // projections in all instead of r per contact), the others left 0.
    Eigen::MatrixXd wz = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(contacts_n) * dimension, z.cols());
    std::vector<Eigen::Index> columns;
    for (int c = 0; c < contacts_n; ++c) {
      const ContactRows& rc = (*rows)[static_cast<size_t>(c)];
      const auto na = static_cast<Eigen::Index>(rc.active.size());
      if (na == 0) continue;
      columns.clear();
      for (Eigen::Index j = 0; j < z.cols(); ++j) {
        if ((z.col(j).segment(rc.first, na).array() != 0.0).any()) columns.push_back(j);
      }
      Eigen::MatrixXd x(static_cast<Eigen::Index>(columns.size()), na);  // columns × active
      for (Eigen::Index i = 0; i < na; ++i) {
        x.col(i) = (*samples)[static_cast<size_t>(rc.first + i)].stiffness * z(rc.first + i, columns).transpose();
      }
      const Eigen::MatrixXd projected = smp->weighting->project_at(rc.active, x);  // columns × M
      for (int l = 0; l < dimension; ++l) {
        wz(static_cast<Eigen::Index>(l) * contacts_n + c, columns) = projected.col(l).transpose();
      }
    }
    // H W Z: with many columns W Z is sparse (each column on one contact's rows), and so is H.
    if (z.cols() > 1) return Eigen::MatrixXd(*hs * Eigen::SparseMatrix<double>(wz.sparseView()));
    return Eigen::MatrixXd(*hs * wz);
  };
  return jac;
}


Eigen::VectorXd WeightedResidual::Impl::contact_residual(const Eigen::VectorXd& x, double load,
                                                         const ActiveSet* piece) const {
  refuse_rigid("contact_residual");
  require_factorized();
  return (x - load * x_lin + compliance_times(contact_forces(x, nullptr, piece))) / scale;
}


const WeightedResidual::Impl::AssembledOperator& WeightedResidual::Impl::assembled_operator() const {
  std::call_once(assembled_once, [this] {
    if (!operator_products->sparse) return;
    // G = f² A_M ⊗ M + f A_C ⊗ C + A_K ⊗ K: kron(A, X)'s entry (j·n + i, k·n + l) = A(j, k) X(i, l),
    // the stacked layout (layout.hpp).
    const double fr = forcing.frequency_hz;
    const std::array<const Eigen::SparseMatrix<double>*, 3> space{&system.mass, &system.damping, &system.stiffness};
    const std::array<double, 3> factor{fr * fr, fr, 1.0};
    auto g_full = std::make_shared<Eigen::SparseMatrix<double>>(n * m, n * m);
    for (size_t t = 0; t < 3; ++t) {
      const Eigen::SparseMatrix<double> a =
          factor[t] * Eigen::SparseMatrix<double>(operator_products->transposed[t].transpose());
      *g_full += Eigen::SparseMatrix<double>(Eigen::kroneckerProduct(a, *space[t]));
    }
    g_full->makeCompressed();
    assembled.g = std::move(g_full);
    std::vector<Eigen::Triplet<double>> terms;
    for (size_t j = 0; j < contact_terms.size(); ++j) {
      for (const auto& [row, w] : contact_terms[j]) terms.emplace_back(static_cast<int>(j), static_cast<int>(row), w);
    }
    auto p = std::make_shared<Eigen::SparseMatrix<double>>(nc * m, n * m);
    p->setFromTriplets(terms.begin(), terms.end());
    assembled.p = std::move(p);
    if (!h_is_sparse) assembled.h = std::make_shared<const Eigen::MatrixXd>(dense_h());
  });
  return assembled;
}


std::optional<LowRankJacobian> WeightedResidual::Impl::sparse_contact_jacobian(
    const std::vector<ContactTangent>& tangents, double limit) const {
  if (!operator_products->sparse || nc == 0) return std::nullopt;
  // K's entries, bounded before anything is formed.
  const std::array<const Eigen::SparseMatrix<double>*, 3> space{&system.mass, &system.damping, &system.stiffness};
  double bound = 0.0;
  for (size_t t = 0; t < 3; ++t) {
    bound += static_cast<double>(operator_products->transposed[t].nonZeros()) *
             static_cast<double>(space[t]->nonZeros());
  }
  for (const auto& c : contacts) bound += std::pow(static_cast<double>(m) * static_cast<double>(c.terms().size()), 2);
  if (bound > limit) return std::nullopt;
  const AssembledOperator& op = assembled_operator();
  // N with every entry of its blocks stored: K's pattern changes only when a coupled block comes or
  // goes (SparseLu then keeps its symbolic analysis).
  auto nx = std::make_shared<const Eigen::SparseMatrix<double>>(sparse_contact_force_jacobian(tangents));
  LowRankJacobian jac;
  jac.scale = scale;
  jac.rows = static_cast<Eigen::Index>(nc) * m;
  jac.sparse_u = *op.p;  // U = P (n_c·M × n·M)
  jac.sparse_v = Eigen::SparseMatrix<double>(op.p->transpose()) * (*nx);
  jac.sparse_capacitance = *op.g + Eigen::SparseMatrix<double>(jac.sparse_v * (*op.p));
  const std::shared_ptr<const Eigen::SparseMatrix<double>> hs = h_sparse;
  const std::shared_ptr<const Eigen::MatrixXd> hd = op.h;
  jac.times_update = [hs, hd, nx](const Eigen::MatrixXd& y) {  // H N Y
    const Eigen::MatrixXd ny = *nx * y;
    if (hs) return Eigen::MatrixXd(*hs * ny);
    return Eigen::MatrixXd(*hd * ny);
  };
  return jac;
}

}  // namespace wbm::solvers
