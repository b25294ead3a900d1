// What the C ABI's opaque handles hold. Internal: for the ABI's implementation and for native
// tests that build a scene through the ABI and then reach the core behind it.
#pragma once

#include <atomic>
#include <memory>
#include <string>

#include "lantern/lantern.h"
#include "render/render.h"
#include "scene/scene.h"
#include "shading/image.h"

struct lt_scene {
  lt::Scene scene;
  // lt_scene_begin_image's buffer, until lt_scene_end_image takes it.
  struct PendingImage {
    lt_image_desc desc{};  // its pixels and colour space strings are the members below
    lt::FloatBuffer pixels;
    std::string ocio_config, ocio_space;
  };
  std::unique_ptr<PendingImage> pending_image;
  std::atomic<int> live_renders{0};  // renders started and not yet destroyed: they read the scene
};
struct lt_render {
  std::unique_ptr<lt::RenderJob> job;
  lt_scene* scene = nullptr;
  ~lt_render() {
    job.reset();  // stops and joins the render's threads before the scene may change
    if (scene) scene->live_renders.fetch_sub(1);
  }
};
