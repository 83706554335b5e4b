#include <wbm/solvers/condensation.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>

#include <wbm/contact/signorini.hpp>

namespace wbm::solvers {
namespace {

// The sparse selection matrix P (|dofs| × n) with P u = u[dofs].
Eigen::SparseMatrix<double> selection(const std::vector<int>& dofs, int n) {
  Eigen::SparseMatrix<double> p(static_cast<Eigen::Index>(dofs.size()), n);
  std::vector<Eigen::Triplet<double>> t;
  for (size_t i = 0; i < dofs.size(); ++i) t.emplace_back(static_cast<int>(i), dofs[i], 1.0);
  p.setFromTriplets(t.begin(), t.end());
  return p;
}

}  // namespace

std::vector<int> massless_dofs(const Eigen::SparseMatrix<double>& mass) {
  std::vector<bool> has_mass(static_cast<size_t>(mass.rows()), false);
  for (int k = 0; k < mass.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(mass, k); it; ++it) {
      if (it.value() != 0.0) has_mass[static_cast<size_t>(it.row())] = true;
    }
  }
  std::vector<int> out;
  for (size_t i = 0; i < has_mass.size(); ++i) {
    if (!has_mass[i]) out.push_back(static_cast<int>(i));
  }
  return out;
}

int MasslessCondensation::retained_index(int dof) const {
  const auto it = std::lower_bound(retained.begin(), retained.end(), dof);
  return it != retained.end() && *it == dof ? static_cast<int>(it - retained.begin()) : -1;
}

Eigen::MatrixXd MasslessCondensation::expand_displacement(const Eigen::MatrixXd& um) const {
  const auto n = static_cast<Eigen::Index>(retained.size() + massless.size());
  Eigen::MatrixXd u(n, um.cols());
  for (size_t i = 0; i < retained.size(); ++i) u.row(retained[i]) = um.row(static_cast<Eigen::Index>(i));
  Eigen::MatrixXd us = transfer * um;
  for (size_t c = 0; c < contacts.size(); ++c) {
    if (contact_row[c] < 0) continue;
    for (Eigen::Index p = 0; p < um.cols(); ++p) {
      const double f = contacts[c].law->force(contacts[c].displacement(um.col(p)));
      us.col(p) -= flexibility.col(contact_row[c]) * (contact_sign[c] * f);
    }
  }
  for (size_t i = 0; i < massless.size(); ++i) u.row(massless[i]) = us.row(static_cast<Eigen::Index>(i));
  return u;
}

Eigen::MatrixXd MasslessCondensation::expand_velocity(const Eigen::MatrixXd& um, const Eigen::MatrixXd& vm) const {
  const auto n = static_cast<Eigen::Index>(retained.size() + massless.size());
  Eigen::MatrixXd v(n, vm.cols());
  for (size_t i = 0; i < retained.size(); ++i) v.row(retained[i]) = vm.row(static_cast<Eigen::Index>(i));
  Eigen::MatrixXd vs = transfer * vm;
  for (size_t c = 0; c < contacts.size(); ++c) {
    if (contact_row[c] < 0) continue;
    for (Eigen::Index p = 0; p < vm.cols(); ++p) {
      const double df = contacts[c].law->stiffness(contacts[c].displacement(um.col(p))) * contacts[c].displacement(vm.col(p));
      vs.col(p) -= flexibility.col(contact_row[c]) * (contact_sign[c] * df);
    }
  }
  for (size_t i = 0; i < massless.size(); ++i) v.row(massless[i]) = vs.row(static_cast<Eigen::Index>(i));
  return v;
}

MasslessCondensation condense_massless(const MechanicalSystem& system, const std::vector<ContactPoint>& contacts,
                                       const std::vector<int>& forced_dofs, const std::vector<std::string>& names) {
  system.validate();
  const int n = system.dofs();
  ContactPoint::validate(contacts, n);
  auto name = [&](int d) {
    return d >= 0 && static_cast<size_t>(d) < names.size() ? names[static_cast<size_t>(d)] : "DOF " + std::to_string(d);
  };
  auto fail = [](const std::string& what) { throw std::invalid_argument("condense_massless: " + what); };
  MasslessCondensation out;
  out.massless = massless_dofs(system.mass);
  if (out.massless.empty()) fail("every DOF has mass; nothing to condense");
  std::vector<bool> is_massless(static_cast<size_t>(n), false);
  for (int d : out.massless) is_massless[static_cast<size_t>(d)] = true;
  for (int d = 0; d < n; ++d) {
    if (!is_massless[static_cast<size_t>(d)]) out.retained.push_back(d);
  }
  if (out.retained.empty()) fail("no DOF has mass; a static problem has no vibration to solve");
  for (int k = 0; k < system.damping.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(system.damping, k); it; ++it) {
      if (it.value() != 0.0 && (is_massless[static_cast<size_t>(it.row())] || is_massless[static_cast<size_t>(it.col())])) {
        fail("C has an entry at (" + name(static_cast<int>(it.row())) + ", " + name(static_cast<int>(it.col())) +
             ") on a massless DOF; a dashpot on a massless DOF makes it first-order, not static: remove it, or give "
             "the DOF a mass");
      }
    }
  }
  for (int d : forced_dofs) {
    if (d >= 0 && d < n && is_massless[static_cast<size_t>(d)]) {
      fail("the force acts on the massless DOF " + name(d) + "; force a DOF with mass");
    }
  }
  // Sparse throughout except the |s| × |s| flexibility and the |s| × |m| transfer.
  const Eigen::SparseMatrix<double> pm = selection(out.retained, n), ps = selection(out.massless, n);
  const Eigen::MatrixXd kss = Eigen::MatrixXd(ps * system.stiffness * ps.transpose());
  const Eigen::SparseMatrix<double> ksm = ps * system.stiffness * pm.transpose();
  const Eigen::LLT<Eigen::MatrixXd> llt(kss);
  if (llt.info() != Eigen::Success) {
    std::string list;
    for (int d : out.massless) list += (list.empty() ? "" : ", ") + name(d);
    fail("K restricted to the massless DOFs (" + list + ") is not positive definite: a massless DOF must be held by "
         "springs (give it stiffness, or remove it)");
  }
  out.flexibility = llt.solve(Eigen::MatrixXd::Identity(kss.rows(), kss.cols()));
  out.flexibility = 0.5 * (out.flexibility + out.flexibility.transpose()).eval();
  out.transfer = -(out.flexibility * ksm);
  // K̃ = K_mm + K_ms T = K_mm − K_smᵀ F K_sm; T's zero columns stay structural zeros.
  const Eigen::SparseMatrix<double> t_sparse = out.transfer.sparseView(0.0, 0.0);
  Eigen::SparseMatrix<double> k = pm * system.stiffness * pm.transpose();
  k += Eigen::SparseMatrix<double>(ksm.transpose() * t_sparse);
  const Eigen::SparseMatrix<double> kt = k.transpose();
  out.system.stiffness = 0.5 * (k + kt);
  out.system.mass = pm * system.mass * pm.transpose();
  out.system.damping = pm * system.damping * pm.transpose();

  std::vector<int> contact_rows;
  for (const auto& c : contacts) {
    int row = -1;
    for (const auto& [j, w] : c.terms()) {
      if (is_massless[static_cast<size_t>(j)]) row = static_cast<int>(std::lower_bound(out.massless.begin(), out.massless.end(), j) - out.massless.begin());
    }
    if (row < 0) {  // between DOFs with mass: renumbered
      ContactPoint r = c;
      r.dof = out.retained_index(c.dof);
      if (c.other >= 0) r.other = out.retained_index(c.other);
      for (auto& [j, w] : r.along) j = out.retained_index(j);
      out.contacts.push_back(r);
      out.contact_row.push_back(-1);
      out.contact_sign.push_back(0.0);
      continue;
    }
    if (c.law->hysteretic()) {
      fail("the contact at the massless DOF " + name(c.dof) + " is a " + c.law->describe() + ": a friction law behind "
           "a spring is not condensed (its slider state would need a local solve); give the DOF a mass");
    }
    const auto terms = c.terms();
    if (terms.size() != 1) {
      fail("the contact at " + name(c.dof) + " involves the massless DOF " + name(out.massless[static_cast<size_t>(row)]) +
           " and other DOFs; a massless DOF takes a stop of its own (direction +1 or -1), not a contact between DOFs "
           "or along a combination");
    }
    const double sigma = terms.front().second > 0.0 ? 1.0 : -1.0;
    if (std::abs(std::abs(terms.front().second) - 1.0) > 1e-15) {
      fail("the contact at the massless DOF " + name(c.dof) + " has weight " + std::to_string(terms.front().second) +
           "; give direction +1 or -1");
    }
    for (int r : contact_rows) {
      const double fjk = out.flexibility(row, r), scale = std::sqrt(out.flexibility(row, row) * out.flexibility(r, r));
      if (std::abs(fjk) > 1e-12 * scale) {
        fail("the massless contact DOFs " + name(out.massless[static_cast<size_t>(row)]) + " and " +
             name(out.massless[static_cast<size_t>(r)]) + " are coupled through springs (flexibility " +
             std::to_string(fjk) + " m/N): each contact force would depend on both; give one of them a mass");
      }
    }
    contact_rows.push_back(row);
    const double flex = out.flexibility(row, row);
    ContactPoint r;
    r.obstacle = c.obstacle;  // along the same e_c: the series law sees the same relative displacement
    r.law = c.law->rigid() ? std::shared_ptr<const contact::ContactLaw>(std::make_shared<contact::LinearPenalty>(
                                 contact::LinearPenaltyParameters{1.0 / flex, c.law->gap()}))
                           : std::make_shared<contact::SeriesCompliance>(c.law, flex);
    const Eigen::VectorXd e = sigma * out.transfer.row(row).transpose();
    Eigen::Index largest = 0;
    const double emax = e.cwiseAbs().maxCoeff(&largest);
    if (!(emax > 0.0)) {
      fail("the massless contact DOF " + name(c.dof) + " is not connected to any DOF with mass; its contact "
           "cannot act on the structure");
    }
    for (Eigen::Index i = 0; i < e.size(); ++i) {
      if (e(i) != 0.0) r.along.emplace_back(static_cast<int>(i), e(i));
    }
    r.dof = static_cast<int>(largest);
    out.contacts.push_back(r);
    out.contact_row.push_back(row);
    out.contact_sign.push_back(sigma);
  }
  out.system.validate();
  ContactPoint::validate(out.contacts, static_cast<int>(out.retained.size()));
  return out;
}

}  // namespace wbm::solvers
