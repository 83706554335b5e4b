// The heap policy of wbm's executables (<wbm/solvers/heap.hpp>), against glibc's own account of
// its heap (mallinfo2): with it, a block of a few MB comes from the heap rather than from its own
// mapping, and freeing it does not hand the heap's top back to the kernel. Without it (glibc's
// defaults in a fresh process) the same block is mapped on its own: mallinfo2's hblks goes 0 → 1
// and uordblks does not grow (checked with a scratch C program, glibc 2.36).
#include <cstdlib>
#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include <wbm/solvers/heap.hpp>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#if defined(__SANITIZE_ADDRESS__)
#define WBM_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define WBM_TEST_ASAN 1
#endif
#endif

namespace {

bool user_heap_settings() {
  for (const char* name : {"MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_", "GLIBC_TUNABLES"}) {
    if (std::getenv(name) != nullptr) return true;
  }
  return false;
}

TEST(HeapPolicy, AtStartAFewMegabyteBlockComesFromTheHeapAndItsFreeKeepsTheHeap) {
#if !defined(__GLIBC__) || defined(WBM_TEST_ASAN)
  GTEST_SKIP() << "glibc's malloc only (ASan replaces it)";
#else
  if (user_heap_settings()) GTEST_SKIP() << "the environment sets glibc's heap thresholds";
  // Not called here first: the policy must already be in force from wbm::heap_at_start, before main().
  constexpr std::size_t kBytes = 8u << 20;          // 8 MiB, above the defaults' thresholds
  const struct mallinfo2 before = mallinfo2();
  void* block = std::malloc(kBytes);
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, kBytes);
  const struct mallinfo2 during = mallinfo2();
  // A read through volatile, so that the compiler cannot drop the malloc/memset/free triple.
  EXPECT_EQ(static_cast<volatile unsigned char*>(block)[kBytes - 1], 1);
  EXPECT_EQ(during.hblks, before.hblks) << "the block was mapped on its own";
  EXPECT_GE(during.uordblks, before.uordblks + kBytes) << "the block is not in the heap's allocated bytes";
  std::free(block);
  const struct mallinfo2 after = mallinfo2();
  EXPECT_EQ(after.arena, during.arena) << "the heap's top was returned to the kernel";
  EXPECT_GE(after.fordblks, during.fordblks + kBytes) << "the block is not free in the heap";
  EXPECT_TRUE(wbm::solvers::retain_freed_heap());  // and applying it again succeeds
#endif
}

TEST(HeapPolicy, TheUsersOwnSettingIsKept) {
#if !defined(__GLIBC__)
  GTEST_SKIP() << "glibc only";
#else
  const char* name = "MALLOC_TRIM_THRESHOLD_";
  const char* previous = std::getenv(name);
  const std::string kept = previous != nullptr ? previous : "";
  ASSERT_EQ(setenv(name, "131072", 1), 0);
  EXPECT_FALSE(wbm::solvers::retain_freed_heap());
  if (previous != nullptr) {
    setenv(name, kept.c_str(), 1);
  } else {
    unsetenv(name);
  }
#endif
}

}  // namespace
