// The global operator new of the file fuzz targets: a request beyond 2 GB (the runs'
// -rss_limit_mb) throws std::bad_alloc, as a machine's allocator does for a request beyond its
// memory, instead of ASan's report-and-abort (its operator new never throws). OpenVDB and OpenEXR
// allocate what a corrupt length field says (docs/testing.md); Lantern must refuse such a file
// with a status and a message, and this lets the fuzzer check that it does. Every variant is
// replaced (malloc / free underneath, which ASan still checks) so that no memory crosses between
// this family and ASan's, which would be reported as an alloc-dealloc mismatch.
#include <cstddef>
#include <cstdlib>
#include <new>

namespace {

constexpr std::size_t kLimit = std::size_t(2) << 30;

void* allocate(std::size_t n, std::size_t align) {
  if (n > kLimit) return nullptr;
  if (n == 0) n = 1;
  if (align <= alignof(std::max_align_t)) return std::malloc(n);
  return std::aligned_alloc(align, (n + align - 1) / align * align);
}

void* allocate_or_throw(std::size_t n, std::size_t align) {
  if (void* p = allocate(n, align)) return p;
  throw std::bad_alloc();
}

std::size_t value(std::align_val_t a) { return static_cast<std::size_t>(a); }

}  // namespace

void* operator new(std::size_t n) { return allocate_or_throw(n, 0); }
void* operator new[](std::size_t n) { return allocate_or_throw(n, 0); }
void* operator new(std::size_t n, std::align_val_t a) { return allocate_or_throw(n, value(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return allocate_or_throw(n, value(a)); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return allocate(n, 0); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return allocate(n, 0); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept { return allocate(n, value(a)); }
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate(n, value(a));
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
