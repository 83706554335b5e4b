#pragma once
// Private to wbm_solvers: the compliance blocks KroneckerFactorization keeps in a structured form
// (kronecker_factorization.cpp forms them, kronecker_compliance.cpp applies them).
#include <vector>

#include <wbm/spectral/circulant.hpp>

#include "fourier_weighting_factor.hpp"
#include "kronecker_factorization.hpp"

namespace wbm::solvers::detail {

// The blocks H_cd (n_c × n_c, pair (c, d) at c·n_c + d) in a structured form, kept by
// compliance() for compliance_product(): circulant, or the core sums Σ_i w_i S_i whose product
// with the shift-structured A_K⁻¹ is H_cd.
struct KroneckerFactorization::ComplianceStructure {
  int contacts = 0;
  std::vector<spectral::Circulant> circulant;
  std::vector<FourierCore> cores;
  const FourierWeighting* fourier_weighting = nullptr;  // owned by Setup
};

}  // namespace wbm::solvers::detail
