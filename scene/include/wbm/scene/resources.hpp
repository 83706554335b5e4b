#pragma once
/// What a scene will cost before it runs (issue #40, item 4: documented ranges the machine could
/// not serve ended in "std::bad_alloc" after `wbm check` said valid). Units: bytes.
///
/// Peak memory of the weighted-residual analyses (solve, continuation), fitted to measured peaks
/// of `wbm run` (the JL14 rod, maximum resident set, Release build, 2026-11):
///   memory ≈ 8 n² + c_M M² + 400 n M + 16 (n_c M)² (rigid stops only)   [bytes]
/// with n the DOFs, M the basis dimension, n_c the contacts; 8 n² is the dense n × n modal
/// eigenproblem of the operator G (n = 8000, M = 16: 507 MB measured), c_M M² the dense time
/// operators and sampled bases (c_M = 40 for Fourier: M = 4096, 677 MB and M = 16384, 10.5 GB
/// measured; 100 for wavelets: DB6:Fourier M = 4096, 1.66 GB), 400 n M the stacked unknowns
/// and their factorization (n = 1000, M = 256: 84 MB), 16 (n_c M)² the Delassus operator.
/// Timestep and nnm are bounded by their own key ranges and are not estimated.
///
/// Result files: the CSV files of one run hold P samples of (2 + 2 d) columns (τ, t, and
/// displacement and velocity of d output DOFs) plus the energy, about 24 bytes a cell.

#include <cstdint>
#include <string>

#include <wbm/scene/scene.hpp>

namespace wbm::scene {

struct ResourceEstimate {
  double memory_bytes = 0.0;  // peak memory of the analysis, as in the file comment (0: not estimated)
  double output_bytes = 0.0;  // the CSV files of one run
  std::string memory_key;     // the key whose value dominates memory_bytes, e.g. "basis.dimension"
};

/// The estimate for a parsed scene (no matrices are built). Never throws.
[[nodiscard]] ResourceEstimate estimate_resources(const Scene& scene);

/// This machine's physical memory [bytes] (sysconf), or 0 if unknown.
[[nodiscard]] double physical_memory_bytes();

/// "1.2 GB", "350 MB": bytes in decimal units, 2 significant digits.
[[nodiscard]] std::string format_bytes(double bytes);

}  // namespace wbm::scene
