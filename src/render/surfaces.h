// What a ray can stop at: implicit iso-surfaces (their own set of regions whose value range
// holds an iso-value, stepped and refined by root finding) and triangle meshes (accel's mesh
// BVH), each clipped like the volume, with the colour a hit gets before lighting.
#pragma once

#include "dual_ray.h"
#include "layer_table.h"
#include "particle_spheres.h"
#include "ray_program.h"

#include "exabricks/accel/mesh_bvh.h"
#include "exabricks/accel/sphere_bvh.h"
#include "exabricks/accel/traversal.h"
#include "exabricks/render/renderer.h"

#include <memory>
#include <vector>

namespace exa {

class Surfaces {
public:
  Surfaces(const Model& model, const DatasetInfo& dataset);

  /// Rebuilds the iso region set for `iso` on `field` (-1 with no iso-values), coloured by
  /// `colorField` (-1: by the iso colours); Embree traverses it below `embreeBelowVisibleFraction`
  /// of the regions, the k-d tree above.
  void updateIso(const IsoSurfaces& iso, int field, int colorField, float embreeBelowVisibleFraction);
  /// Rebuilds the mesh BVH.
  void updateMeshes(const std::vector<SceneMesh>& meshes);
  /// Rebuilds the particles' sphere hierarchy (particleSpheres).
  void updateParticles(ParticleSpheres spheres);

  bool any() const { return isoTraversal_ || hasMeshes(); }
  /// Meshes or particles: what meshHit finds.
  bool hasMeshes() const { return !meshes_.empty() || !spheres_.empty(); }
  /// The particles' spheres and their colours (hierarchy order), which the device back ends use too.
  const SphereBvh& spheres() const { return spheres_; }
  const std::vector<vec3f>& sphereColors() const { return sphereColors_; }
  const RegionTraversal* isoTraversal() const { return isoTraversal_.get(); }
  const std::vector<uint8_t>& isoVisible() const { return isoVisible_; }
  size_t meshCount() const { return meshColors_.size(); }
  const std::vector<float>& isoValues() const { return isoValues_; }
  const FieldView& isoView() const { return isoView_; }
  /// The iso colour field's table, or null where iso-surfaces are not coloured by a field.
  const LayerTable* isoColorTable() const { return isoColored_ ? &isoColor_ : nullptr; }

  /// Nearest iso-surface crossing along a lattice ray within [ray.tmin, ray.tmax]: each region
  /// is stepped at its step for `rate` (and at its entry and exit), and a sign change of
  /// value - isovalue is refined by bisection to 1e-3 of the region's finest cell width, then
  /// by one secant step. Returns the lattice t, the region and the iso-value's index.
  bool findIso(const Ray& ray, Sampling sampling, float rate, float& tHit, uint32_t& regionHit, int& which,
               uint64_t& samples) const;
  /// The nearest mesh or particle within [sMin, sMax] along the ray: its kind, distance, normal
  /// and number.
  bool meshHit(const DualRay& r, double sMin, double sMax, SurfaceHit& hit) const;
  /// Whether a mesh or a particle lies within [sMin, sMax] along the ray.
  bool meshOccludes(const DualRay& r, double sMin, double sMax) const;
  /// World units per lattice unit, inverted (iso-surface normals).
  const vec3f& invScale() const { return invScale_; }
  /// What colours a hit before lighting (surfaceColorOf): the meshes', the iso colour field's
  /// through its map, or the iso-values' (`isoColors`, which must outlive the view).
  SurfaceColors colors(const std::vector<vec3f>& isoColors) const;

private:
  const Model& model_;
  const DatasetInfo& dataset_;
  float referenceWidth_;
  vec3f invScale_;
  std::vector<float> isoValues_;
  FieldView isoView_;
  std::vector<uint8_t> isoVisible_;
  std::unique_ptr<RegionTraversal> isoTraversal_;
  bool isoColored_ = false;
  LayerTable isoColor_; ///< colour map of the iso colour field
  MeshBvh meshes_;
  std::vector<vec3f> meshColors_;
  SphereBvh spheres_;
  std::vector<vec3f> sphereColors_;
};

} // namespace exa
