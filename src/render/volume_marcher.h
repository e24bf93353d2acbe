// The volume along a ray (paper §5): the visible regions' segments front to back, samples at
// mid-intervals of adaptive steps, basis reconstruction, the transfer function with opacity
// correction, shading and front-to-back compositing. The marcher owns what it samples with: the
// layers' tables, the visible region set and its traversal, smooth shading's gradient fields.
#pragma once

#include "layer_table.h"
#include "majorant_grid.h"
#include "ray_program.h"

#include "exabricks/accel/traversal.h"
#include "exabricks/amr/cell_locator.h"
#include "exabricks/amr/gradients.h"
#include "exabricks/render/renderer.h"

#include <array>
#include <map>
#include <memory>
#include <vector>

namespace exa {

/// What a march takes from the scene, the renderer's options and the frame: the same for every
/// ray of a pass.
struct MarchSettings {
  VolumeSettings sample; ///< as the per-ray code samples (ray_program.h)
  ShadingTerms terms;
  Reconstruction reconstruction = Reconstruction::Regions;
  RendererOptions options;

  static MarchSettings of(const Scene& scene, const RendererOptions& options, float rate);
};

class VolumeMarcher {
public:
  VolumeMarcher(const Model& model, const DatasetInfo& dataset);

  /// Rebuilds the layer tables, the visible regions (with `skipping`, those whose value ranges some
  /// layer's transfer function may show; else all) and the traversal (`in` picks its kind).
  void update(const std::vector<VolumeLayer>& layers, const std::vector<int>& fields, const Integration& in,
              bool skipping);
  /// Builds the gradient fields of every layer's field (smooth shading) in the bricks of the
  /// visible regions that meet the world box `domain` (null: everywhere), where they are not built
  /// yet, and points the layers at them; true when a brick's were built. A sample reads only its
  /// region's bricks, and no sample is taken in a hidden region or outside a renderer's domain,
  /// so the other bricks' gradients are not needed until a transfer function or domain shows them.
  bool attachGradients(const box3d* domain);
  /// The gradient fields of model field `field` built so far (null: none yet), and gradient
  /// fields built before by a marcher over the same model, used instead of building them again.
  const GradientFields* gradients(int field) const;
  void adoptGradients(int field, GradientFields gradients);
  /// gradients(field)'s version, 0 when there are none.
  uint64_t gradientVersion(int field) const;

  bool empty() const { return layers_.empty(); }
  const std::vector<LayerTable>& layers() const { return layers_; }
  const RegionTraversal* traversal() const { return traversal_.get(); }
  const std::vector<uint8_t>& visible() const { return visible_; }
  /// Per region, the stride of its step (regionStride; 1 everywhere until updateStrides).
  const std::vector<float>& strides() const { return strides_; }
  /// Rebuilds the strides from the current tables and visible regions: regionStride's where
  /// `enabled` (Integration::uniformStride), for shaded samples where `shaded`; else 1.
  void updateStrides(bool enabled, bool shaded);
  /// The path tracer's majorants: per region, the largest extinction (per lattice unit) its
  /// value ranges reach through every layer's table, summed (0 for hidden regions), and the
  /// majorant grid's (`grid` false: none). Rebuilt by updateMajorants from the current tables.
  void updateMajorants(bool grid = true);
  const std::vector<float>& majorants() const { return majorants_; }
  const MajorantGrid& majorantGrid() const { return majorantGrid_; }
  /// Extinction per lattice unit of a table entry's -log2 transmittance (ln 2 / reference width).
  float extinctionPerLog2() const;

  /// Marches the visible regions along the lattice ray within [tmin, tmax] with sample offset
  /// rho (in steps), compositing front to back into acc (premultiplied). OpacityOnly skips colour
  /// and shading (shadow-like rays). Adds the samples taken and the segments visited. One march
  /// for every case: batches of consecutive samples, reconstructed from their regions' bricks or
  /// by the cell locator, for one layer or several (the device back ends' one-sample-at-a-time
  /// march, device_trace.h, is the reference it is tested against).
  template <bool OpacityOnly>
  void march(const Ray& ray, float rho, const RayLight& light, const MarchSettings& s, vec4f& acc, uint64_t& raySamples,
             uint64_t& regionCount) const;

private:
  const Model& model_;
  const DatasetInfo& dataset_;
  std::vector<LayerTable> layers_;
  /// Smooth shading's gradient fields per model field, built brick by brick as transfer
  /// functions and the domain show the bricks' regions.
  std::map<int, GradientFields> gradientFields_;
  std::vector<uint8_t> visible_;
  std::vector<float> majorants_;
  std::vector<float> strides_; ///< per region, its step's stride (regionStride)
  MajorantGrid majorantGrid_;
  std::unique_ptr<RegionTraversal> traversal_;
  std::unique_ptr<CellLocator> locator_; ///< only for Reconstruction::CellLocation
  float referenceWidth_ = 1.f;           ///< opacity reference (dataset's finest cell width), lattice units
  vec3f invScale_{1.f};                  ///< world units per lattice unit, inverted (for gradients)
  float meanScale_ = 1.f;                ///< world units per lattice unit, averaged over the axes
};

extern template void VolumeMarcher::march<false>(const Ray&, float, const RayLight&, const MarchSettings&, vec4f&,
                                                 uint64_t&, uint64_t&) const;
extern template void VolumeMarcher::march<true>(const Ray&, float, const RayLight&, const MarchSettings&, vec4f&,
                                                uint64_t&, uint64_t&) const;

} // namespace exa
