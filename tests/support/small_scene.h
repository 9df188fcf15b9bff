// A small built-in scene with its light tree and ray tracer, as a session holds them: what a test
// that calls render() or render_wavefront() by hand renders.
#pragma once

#include <memory>
#include <string>

#include "rll/accel/accel.h"
#include "rll/lighttree/light_tree.h"
#include "support/test_support.h"

namespace rll::test {

struct SmallScene {
  Scene scene;
  LightTree tree;
  std::unique_ptr<Accel> accel;
  // small_builtin_scene(name, width, height), its tree built (which orders its lights) and its
  // accel.
  SmallScene(const std::string& name, int width, int height)
      : scene(small_builtin_scene(name, width, height)) {
    tree = build_light_tree(scene);
    accel = std::make_unique<Accel>(scene.mesh);
  }
};

}  // namespace rll::test
