#include "surfaces.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace exa {
namespace {

/// Default iso-surface colours (linear RGB), cycled over the iso-values.
vec3f defaultIsoColor(int index) {
  switch (index & 3) {
  case 0:
    return {0.80f, 0.80f, 0.78f};
  case 1:
    return {0.85f, 0.35f, 0.20f};
  case 2:
    return {0.20f, 0.45f, 0.85f};
  default:
    return {0.35f, 0.70f, 0.30f};
  }
}

} // namespace

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

bool Surfaces::traceMesh(const DualRay& r, double sMin, double sMax, SurfaceHit& hit) const {
  MeshHit m;
  if (!meshes_.intersect(r.orgW, r.dirW, sMin, sMax, m)) return false;
  hit.kind = SurfaceHit::Mesh;
  hit.index = m.mesh;
  hit.distance = m.distance;
  hit.position = r.orgW + r.dirW * hit.distance;
  hit.normal = m.normal;
  return true;
}

bool Surfaces::meshOccludes(const DualRay& r, double sMin, double sMax) const {
  return meshes_.occluded(r.orgW, r.dirW, sMin, sMax);
}

bool Surfaces::findIso(const Ray& ray, Sampling sampling, float rate, float& tHit, uint32_t& regionHit, int& which,
                       uint64_t& samples) const {
  if (!isoTraversal_ || isoValues_.empty() || !(ray.tmax > ray.tmin)) return false;
  bool found = false;
  isoTraversal_->traverse(ray, [&](const Segment& seg) {
    const float t0 = std::max(seg.t0, ray.tmin), t1 = std::min(seg.t1, ray.tmax);
    if (!(t1 > t0)) return true;
    const Region& region = model_.regions.regions[seg.region];
    const float dt = sampleStep(region, sampling, referenceWidth_, rate);
    const float tolerance = 1e-3f * region.finestWidth();
    auto value = [&](float t, float& v) {
      ++samples;
      return sampleRegion(isoView_, seg.region, ray.org + ray.dir * t, v);
    };
    const int steps = std::max(1, int(std::ceil((t1 - t0) / dt)));
    float ta = t0, va = 0.f;
    bool aValid = value(ta, va);
    for (int i = 1; i <= steps; ++i) {
      const float tb = i == steps ? t1 : t0 + (t1 - t0) * float(i) / float(steps);
      float vb = 0.f;
      const bool bValid = value(tb, vb);
      if (aValid && bValid) {
        float best = std::numeric_limits<float>::infinity();
        int bestIndex = -1;
        for (size_t j = 0; j < isoValues_.size(); ++j) {
          const float c = isoValues_[j];
          const bool sideA = va >= c, sideB = vb >= c;
          if (sideA == sideB) continue;
          const float t = refineCrossing(value, ta, tb, va, vb, c, sideA, tolerance);
          if (t < best) best = t, bestIndex = int(j);
        }
        if (bestIndex >= 0) {
          tHit = best;
          regionHit = seg.region;
          which = bestIndex;
          found = true;
          return false;
        }
      }
      ta = tb, va = vb, aValid = bValid;
    }
    return true;
  });
  return found;
}

bool Surfaces::nearest(const DualRay& r, bool clipMeshes, Sampling sampling, float rate, SurfaceHit& hit,
                       uint64_t& isoSamples) const {
  bool have = false;
  if (!meshes_.empty()) {
    const double s0 = clipMeshes ? r.sMin : r.domainMin;
    const double s1 = clipMeshes ? r.sMax : r.domainMax;
    have = traceMesh(r, s0, s1, hit);
  }
  if (!isoTraversal_ || clippedAway(r)) return have;
  Ray lr = r.lattice;
  if (have) lr.tmax = std::min(lr.tmax, float(hit.distance * r.kappa));
  float t;
  uint32_t region;
  int which;
  if (!findIso(lr, sampling, rate, t, region, which, isoSamples)) return have;
  const vec3f p = lr.org + lr.dir * t;
  float v;
  vec3f g;
  hit.kind = SurfaceHit::Iso;
  hit.index = which;
  hit.distance = double(t) / r.kappa;
  hit.position = r.orgW + r.dirW * hit.distance;
  vec3f n = -vec3f(r.dirW);
  if (sampleRegion(isoView_, region, p, v, &g)) {
    const vec3f gw = g * invScale_;
    if (length(gw) > 1e-30f) n = normalize(gw);
  }
  if (dot(vec3d(n), r.dirW) > 0.0) n = -n;
  hit.normal = n;
  return true;
}

vec3f Surfaces::color(const SurfaceHit& hit, const std::vector<vec3f>& isoColors) const {
  if (hit.kind == SurfaceHit::Mesh) return meshColors_[size_t(hit.index)];
  if (isoColored_) {
    float v;
    const vec3d pl = model_.world.toLattice(hit.position);
    if (sampleField(isoColor_.view, vec3f(pl), v)) return isoColor_.lookup(v).rgb();
  }
  if (!isoColors.empty()) return isoColors[size_t(hit.index) % isoColors.size()];
  return defaultIsoColor(hit.index);
}

} // namespace exa
