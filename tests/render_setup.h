// Test helpers: a scene and frame set field by field, and a renderer that tests change step by
// step (every change goes through Renderer::setScene).
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/render/renderer.h"

#include <memory>
#include <string>
#include <vector>

namespace exa::test {

struct RenderSetup {
  Scene scene;
  Frame frame;
};

class SceneRenderer {
public:
  /// Volume layers of `field` (index into the model's fields) until told otherwise.
  SceneRenderer(const Model& model, int field, const RenderSetup& setup)
      : model_(model), renderer(model), scene(setup.scene), frame(setup.frame) {
    fieldName_ = model.fieldNames.at(size_t(field));
    for (VolumeLayer& l : scene.layers)
      l.field = fieldName_;
    last = renderer.setScene(scene);
  }
  SceneUpdate setTransferFunction(const TransferFunction& tf) {
    scene.layers = {VolumeLayer{fieldName_, tf}};
    return last = renderer.setScene(scene);
  }
  /// Layers as (field index, transfer function).
  SceneUpdate setVolumeLayers(const std::vector<std::pair<int, TransferFunction>>& layers) {
    scene.layers.clear();
    for (const auto& [f, tf] : layers)
      scene.layers.push_back({model_.fieldNames.at(size_t(f)), tf});
    return last = renderer.setScene(scene);
  }
  SceneUpdate setIsoSurfaces(const IsoSurfaces& iso) {
    scene.iso = iso;
    return last = renderer.setScene(scene);
  }
  SceneUpdate addMesh(const TriangleMesh& mesh, const vec3f& color) {
    scene.meshes.push_back({std::make_shared<TriangleMesh>(mesh), color, ""});
    try {
      return last = renderer.setScene(scene);
    } catch (...) {
      scene.meshes.pop_back();
      throw;
    }
  }
  Image render(const Camera& camera, RenderStats* stats = nullptr) {
    frame.camera = camera;
    return renderer.render(frame, stats);
  }
  bool pick(const vec3d& origin, const vec3d& direction, SurfaceHit& hit) const {
    return renderer.pick(origin, direction, hit);
  }
  size_t isoRegions() const { return renderer.isoRegions(); }
  size_t visibleRegions() const { return renderer.visibleRegions(); }
  size_t meshCount() const { return renderer.meshCount(); }
  TraversalKind traversalInUse() const { return renderer.traversalInUse(); }
  /// Name of field index f.
  std::string field(int f) const { return model_.fieldNames.at(size_t(f)); }

private:
  const Model& model_;
  std::string fieldName_;

public:
  Renderer renderer;
  Scene scene;
  Frame frame;
  SceneUpdate last;
};

} // namespace exa::test
