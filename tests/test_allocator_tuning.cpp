// The serve command's allocator policy takes effect on glibc: a batch-sized buffer comes from the
// heap (kept resident between requests), not from a mapping of its own.
#include <gtest/gtest.h>

#include <cstdlib>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "server/allocator_tuning.hpp"

namespace shadowtiles {
namespace {

#if defined(__SANITIZE_ADDRESS__)  // GCC's -fsanitize=address (clang's fuzz build does not run tests)
// ASan's allocator replaces glibc's, and its mallopt changes nothing: the policy must say it did not
// take effect rather than claim it did.
TEST(AllocatorTuning, UnderAsanThePolicyReportsItHasNoEffect) {
  EXPECT_FALSE(server::keep_batch_buffers_resident());
}
#elif defined(__GLIBC__)
TEST(AllocatorTuning, GlibcKeepsBatchBuffersInTheHeap) {
  ASSERT_TRUE(server::keep_batch_buffers_resident());
  // 8 MiB: above glibc's default mmap threshold (128 KiB, raised dynamically up to 32 MiB only after
  // such blocks were freed), below the tuned one: it must come from the heap, not a new mapping.
  constexpr size_t kBytes = size_t(8) << 20;
  const size_t mapped_before = mallinfo2().hblkhd;
  void* block = std::malloc(kBytes);
  ASSERT_NE(block, nullptr);
  static_cast<volatile char*>(block)[0] = 1;
  EXPECT_LT(mallinfo2().hblkhd, mapped_before + kBytes) << "the block was mapped on its own";
  std::free(block);
}
#endif

}  // namespace
}  // namespace shadowtiles
