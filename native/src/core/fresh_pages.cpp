#include "core/fresh_pages.h"

#include <cstdlib>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace lt {

namespace {
constexpr size_t kMapped = size_t(1) << 20;  // from this size on, its own mapping
}

void* fresh_pages_allocate(size_t bytes) {
  if (bytes == 0) bytes = 1;
#if defined(__linux__)
  if (bytes >= kMapped) {
    void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    madvise(p, bytes, MADV_HUGEPAGE);  // a hint: refused, the pages stay small
    return p;
  }
#endif
  void* p = std::calloc(bytes, 1);
  if (!p) throw std::bad_alloc();
  return p;
}

void fresh_pages_free(void* p, size_t bytes) {
  if (!p) return;
  if (bytes == 0) bytes = 1;
#if defined(__linux__)
  if (bytes >= kMapped) {
    munmap(p, bytes);
    return;
  }
#endif
  std::free(p);
}

}  // namespace lt
