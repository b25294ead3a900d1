// The media a ray is inside: a small fixed array per path (pbrt-v3's medium interfaces, Cycles'
// volume stack). Entered on a front-face hit of a medium's closed boundary, left on a back-face hit.
#pragma once

namespace lt {

struct VolumeStack {
  static constexpr int kCapacity = 8;
  int media[kCapacity];
  int size = 0;
  // Whether the scene's global media (Volume objects, the World volume) fill the ray's space too: not
  // on a shadow catcher's catcher-only path, in a scene without the other objects and the world's
  // volume (Cycles' integrator_volume_stack_init for SHADOW_CATCHER_PASS paths).
  bool global = true;

  // Front face (ray against the geometric normal): enter; back face: leave one occurrence.
  void cross(int medium, bool entering) {
    if (medium < 0) return;
    if (entering) {
      if (size < kCapacity) media[size++] = medium;  // deeper nesting is ignored
      return;
    }
    for (int i = size - 1; i >= 0; --i)
      if (media[i] == medium) {
        media[i] = media[--size];
        return;
      }
  }
  bool contains(int medium) const {
    for (int i = 0; i < size; ++i)
      if (media[i] == medium) return true;
    return false;
  }
};

}  // namespace lt
