#pragma once
/// The heap policy of wbm's executables (`wbm`, the reproductions, the benchmarks and the tests,
/// through the object library wbm::heap_at_start): glibc's malloc keeps the memory it is given
/// back instead of returning it to the kernel at once.
///
/// Why. A continuation allocates and frees Jacobians of a few MB at every corrector iteration
/// (the penalty backbone of the 112-DOF Craig–Bampton blade, H = 8: a 1 904-row sparse J of
/// about 3 MB, copied by the bordering and the verified solves). With glibc's defaults, blocks
/// above a dynamic threshold (128 KiB at start, raised by the frees it sees, up to 32 MiB) are
/// mapped and unmapped one by one, and the top of the heap is trimmed above twice that
/// threshold: the same megabytes go back to the kernel and return as fresh zero-filled pages,
/// iteration after iteration. Measured on that backbone alone (329 levels, stop 64): 50–56 s
/// with the defaults, 33–34 s with this policy, the levels bit for bit the same.
///
/// What. mallopt(M_MMAP_THRESHOLD, 32 MiB), glibc's largest (a larger block is still mapped on
/// its own), and mallopt(M_TRIM_THRESHOLD, 1 GiB). The price: memory freed after a peak stays
/// in the process (its resident size does not fall back) until it exits.
///
/// Returns whether the policy was applied. Not applied, and false: another C library than
/// glibc; MALLOC_MMAP_THRESHOLD_, MALLOC_TRIM_THRESHOLD_ or GLIBC_TUNABLES set in the
/// environment (the user's choice is kept); mallopt refused a value. Never throws. The Python
/// module does not apply it (it would change the interpreter's heap on import); setting
/// MALLOC_MMAP_THRESHOLD_=33554432 and MALLOC_TRIM_THRESHOLD_=1073741824 before starting
/// Python has the same effect.

namespace wbm::solvers {

bool retain_freed_heap() noexcept;

}  // namespace wbm::solvers
