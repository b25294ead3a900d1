// What the C ABI's opaque handles hold. Internal: for the ABI's implementation and for native
// tests that build a scene through the ABI and then reach the core behind it.
#pragma once

#include <memory>

#include "core/render.h"
#include "scene/scene.h"

struct lt_scene {
  lt::Scene scene;
};
struct lt_render {
  std::unique_ptr<lt::RenderJob> job;
};
