// The media a ray is inside: a small fixed array per path (pbrt-v3's medium interfaces, Cycles'
// volume stack). Entered on a front-face hit of a medium's closed boundary, left on a back-face hit.
#pragma once

namespace lt {

struct VolumeStack {
  static constexpr int kCapacity = 8;
  int media[kCapacity];
  int groups[kCapacity];  // the light group of the object whose boundary entered each (its emission's)
  int size = 0;
  // Whether the scene's global media (Volume objects, the World volume) fill the ray's space too: not
  // on a shadow catcher's catcher-only path, in a scene without the other objects and the world's
  // volume (Cycles' integrator_volume_stack_init for SHADOW_CATCHER_PASS paths).
  bool global = true;

  // Front face (ray against the geometric normal): enter; back face: leave one occurrence (of the
  // same object's group if there is one).
  void cross(int medium, bool entering, int group = -1) {
    if (medium < 0) return;
    if (entering) {
      if (size < kCapacity) {  // deeper nesting is ignored
        groups[size] = group;
        media[size++] = medium;
      }
      return;
    }
    int found = -1;
    for (int i = size - 1; i >= 0; --i)
      if (media[i] == medium && (found < 0 || (groups[i] == group && groups[found] != group))) found = i;
    if (found < 0) return;
    --size;
    media[found] = media[size];
    groups[found] = groups[size];
  }
  bool contains(int medium) const {
    for (int i = 0; i < size; ++i)
      if (media[i] == medium) return true;
    return false;
  }
};

}  // namespace lt
