// Linked into wbm's executables (the object library wbm::heap_at_start): applies the heap policy
// of <wbm/solvers/heap.hpp> before main().
#include <wbm/solvers/heap.hpp>

namespace {
[[maybe_unused]] const bool kHeapRetained = wbm::solvers::retain_freed_heap();
}  // namespace
