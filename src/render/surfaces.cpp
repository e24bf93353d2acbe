#include "surfaces.h"

#include "iso_search.h"
#include "particle_spheres.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace exa {

Surfaces::Surfaces(const Model& model, const DatasetInfo& dataset)
    : model_(model), dataset_(dataset), referenceWidth_(dataset.referenceWidth),
      invScale_(1.0 / model.world.scale.x, 1.0 / model.world.scale.y, 1.0 / model.world.scale.z) {}

void Surfaces::updateIso(const IsoSurfaces& iso, int field, int colorField, float embreeBelowVisibleFraction) {
  isoValues_ = iso.values;
  isoColored_ = colorField >= 0;
  if (iso.values.empty()) {
    isoTraversal_.reset();
    isoVisible_.clear();
    return;
  }
  isoView_ = model_.view(field);
  if (isoColored_) isoColor_.build(model_, dataset_, colorField, iso.colorTf);
  const auto& ranges = model_.regions.valueRanges[size_t(field)];
  isoVisible_.assign(ranges.size(), 0);
  tbb::parallel_for(size_t(0), ranges.size(), [&](size_t i) {
    const range1f& r = ranges[i];
    bool any = false;
    for (float v : iso.values)
      any = any || (!r.empty() && r.lower <= v && v <= r.upper);
    isoVisible_[i] = any;
  });
  size_t count = 0;
  for (uint8_t v : isoVisible_)
    count += v;
  // Iso-surfaces are sparse: Embree skips the empty space in its BVH unless most regions hold one.
  const TraversalKind kind = double(count) < double(embreeBelowVisibleFraction) * double(ranges.size())
                                 ? TraversalKind::Embree
                                 : TraversalKind::KdTree;
  if (!isoTraversal_ || isoTraversal_->kind() != kind) isoTraversal_ = std::make_unique<RegionTraversal>(model_, kind);
  isoTraversal_->setVisible(isoVisible_);
}

void Surfaces::updateMeshes(const std::vector<SceneMesh>& meshes) {
  meshColors_.clear();
  std::vector<const TriangleMesh*> list;
  for (const SceneMesh& m : meshes)
    list.push_back(m.mesh.get());
  meshes_.build(list);
  for (const SceneMesh& m : meshes)
    meshColors_.push_back(m.color);
}

void Surfaces::updateParticles(ParticleSpheres made) {
  std::vector<uint32_t> order;
  spheres_.build(made.spheres, order);
  sphereColors_.resize(order.size());
  tbb::parallel_for(size_t(0), order.size(), [&](size_t i) { sphereColors_[i] = made.colors[order[i]]; });
}

bool Surfaces::meshHit(const DualRay& r, double sMin, double sMax, SurfaceHit& hit) const {
  MeshHit m;
  bool found = false;
  if (!meshes_.empty() && meshes_.intersect(r.orgW, r.dirW, sMin, sMax, m)) {
    hit.kind = SurfaceHit::Mesh;
    hit.index = m.mesh;
    hit.distance = m.distance;
    hit.normal = m.normal;
    sMax = m.distance;
    found = true;
  }
  if (particleHit(spheres_.view(), r, sMin, sMax, hit)) found = true;
  return found;
}

bool Surfaces::meshOccludes(const DualRay& r, double sMin, double sMax) const {
  if (!meshes_.empty() && meshes_.occluded(r.orgW, r.dirW, sMin, sMax)) return true;
  return particleOccludes(spheres_.view(), r, sMin, sMax);
}

bool Surfaces::findIso(const Ray& ray, Sampling sampling, float rate, float& tHit, uint32_t& regionHit, int& which,
                       uint64_t& samples) const {
  if (!isoTraversal_) return false;
  auto walk = [&](const Ray& r, auto&& emit) { isoTraversal_->traverse(r, emit); };
  return findIsoCrossing(walk, isoView_, isoValues_.data(), int(isoValues_.size()), ray, sampling, referenceWidth_,
                         rate, tHit, regionHit, which, samples);
}

SurfaceColors Surfaces::colors(const std::vector<vec3f>& isoColors) const {
  SurfaceColors c;
  c.meshColors = meshColors_.data();
  c.particleColors = sphereColors_.data();
  c.isoColors = isoColors.data();
  c.isoColorCount = int(isoColors.size());
  c.isoColored = isoColored_;
  if (isoColored_) {
    c.isoColorView = isoColor_.view;
    c.isoColorTable = isoColor_.t;
  }
  return c;
}

} // namespace exa
