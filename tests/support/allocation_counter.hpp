#pragma once
// Counts every heap allocation of a test binary that links
// stria_test_allocation_counter: global operator new/delete and the C
// allocator (malloc, calloc, realloc, aligned_alloc, posix_memalign) are
// replaced in that binary only. Sanitizer builds bring their own allocator,
// so there counting is off and the tests skip.

namespace stria::test {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__) || defined(__SANITIZE_MEMORY__)
inline constexpr bool kCountingAllocations = false;
#else
inline constexpr bool kCountingAllocations = true;
#endif

// Allocations made by the whole process so far (all threads).
long allocationCount();

}  // namespace stria::test
