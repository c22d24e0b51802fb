#include "store/map_advice.hpp"

#include <sys/mman.h>
#include <unistd.h>

namespace shadowtiles::store {
namespace {

// The whole pages under `bytes` (rounded outwards: neighbours' bytes on the edge pages are refetched
// on their next touch, which is harmless for a read-only map).
void advise(std::span<const uint8_t> bytes, int advice) {
  if (bytes.empty()) return;
  static const uintptr_t page = uintptr_t(sysconf(_SC_PAGESIZE));
  const uintptr_t begin = reinterpret_cast<uintptr_t>(bytes.data()) & ~(page - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(bytes.data()) + bytes.size() + page - 1) & ~(page - 1);
  (void)madvise(reinterpret_cast<void*>(begin), end - begin, advice);
}

}  // namespace

void advise_will_need(std::span<const uint8_t> bytes) { advise(bytes, MADV_WILLNEED); }
void advise_done_with(std::span<const uint8_t> bytes) { advise(bytes, MADV_DONTNEED); }

}  // namespace shadowtiles::store
