#include "server/allocator_tuning.hpp"

#include <cstdlib>  // defines __GLIBC__ on glibc (tested below)

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace shadowtiles::server {

bool keep_batch_buffers_resident() {
#if defined(__GLIBC__)
  // Setting either also stops glibc's dynamic threshold, which otherwise trims the heap after each
  // request (the freed buffers exceed twice the largest mmap'd chunk seen) and faults it back in.
  return mallopt(M_MMAP_THRESHOLD, 32 << 20) == 1 && mallopt(M_TRIM_THRESHOLD, 64 << 20) == 1;
#else
  return false;
#endif
}

}  // namespace shadowtiles::server
