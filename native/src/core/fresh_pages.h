// Memory for large image-wide arrays that are written once after they are made (the denoiser's
// inputs, planes and sums): fresh anonymous pages, zero without a pass over them, in 2 MB pages
// where the kernel gives them (a page fault per 2 MB rather than per 4 KB); small ones from
// calloc. Measured: the faults and zero-filling passes of such arrays were a fifth of the
// denoiser's time (bench/README.md).
#pragma once

#include <cstddef>
#include <new>
#include <utility>
#include <vector>

namespace lt {

// Zeroed memory of `bytes` (never null: throws std::bad_alloc), freed by fresh_pages_free with the
// same size.
void* fresh_pages_allocate(size_t bytes);
void fresh_pages_free(void* p, size_t bytes);

// An allocator over them. The container does not value-initialise elements (the memory is zero
// already), so a vector using it reads zeros after it grows from empty, but one that grows again
// after shrinking keeps the old values there: for arrays sized once.
template <class T>
struct FreshPages {
  using value_type = T;
  FreshPages() = default;
  template <class U>
  FreshPages(const FreshPages<U>&) {}
  T* allocate(size_t n) { return static_cast<T*>(fresh_pages_allocate(n * sizeof(T))); }
  void deallocate(T* p, size_t n) { fresh_pages_free(p, n * sizeof(T)); }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  void construct(U*) {}  // value-initialisation: zero already
  template <class U>
  bool operator==(const FreshPages<U>&) const {
    return true;
  }
  template <class U>
  bool operator!=(const FreshPages<U>&) const {
    return false;
  }
};

template <class T>
using FreshVector = std::vector<T, FreshPages<T>>;

}  // namespace lt
