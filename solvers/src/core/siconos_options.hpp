#pragma once
// Siconos Numerics' SolverOptions, owned: one RAII wrapper for the units that call Siconos
// (core/lcp_step.cpp, reference/friction_contact_step.cpp). Include it only from those units:
// Siconos' C headers define macros that must not reach the unity batches (solvers/CMakeLists.txt,
// wbm_solvers_siconos).
#include <cstdlib>
#include <stdexcept>
#include <string>

// Siconos Numerics' headers are C99: `restrict` is a keyword there, and __restrict in C++.
#define restrict __restrict
#include <siconos/numerics/SolverOptions.h>
#undef restrict

namespace wbm::solvers::detail {

/// The options of one Siconos solver (solver_options_create(id)), freed at destruction.
/// solver_options_delete (Siconos 4.4) frees the members, not the struct that solver_options_create
/// malloc'ed: LeakSanitizer found the 120 bytes of each one left, hence the std::free. Throws
/// std::runtime_error naming `name` if Siconos returns no options.
class SiconosOptions {
 public:
  SiconosOptions(int id, const char* name) : options_(solver_options_create(id)) {
    if (options_ == nullptr) {
      throw std::runtime_error(std::string("Siconos Numerics: solver_options_create(") + name + ") failed");
    }
  }
  ~SiconosOptions() {
    solver_options_delete(options_);
    std::free(options_);
  }
  SiconosOptions(const SiconosOptions&) = delete;
  SiconosOptions& operator=(const SiconosOptions&) = delete;
  [[nodiscard]] SolverOptions* get() const noexcept { return options_; }

 private:
  SolverOptions* options_;
};

}  // namespace wbm::solvers::detail
