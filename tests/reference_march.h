// The volume march one sample after another, written from the per-sample headers alone (basis,
// traversal, sample_math): the reference the renderer's batches are tested against, for one layer
// or several, reconstruction from regions or by the cell locator, and every shading mode. Volume
// only: no surfaces, clipping or domain.
#pragma once

#include "exabricks/accel/traversal.h"
#include "exabricks/amr/basis.h"
#include "exabricks/amr/cell_locator.h"
#include "exabricks/amr/gradients.h"
#include "exabricks/amr/model.h"
#include "exabricks/core/image.h"
#include "exabricks/core/random.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/sample_math.h"
#include "exabricks/render/scene.h"
#include "exabricks/render/shade_batch.h"
#include "exabricks/render/transfer_function.h"

#include <array>
#include <memory>
#include <vector>

namespace exa::reference {

/// One volume layer: its field, transfer function table and (smooth shading) gradient fields.
struct Layer {
  int field = 0;
  FieldView view;
  TransferFunction tf;
  std::vector<vec4f> table;
  TfTableView t;
  float invSpan = 0.f;
  bool byValue = false;
  std::array<std::vector<float>, 3> gradData;
  std::array<FieldView, 3> grad{};
};

inline Layer makeLayer(const Model& m, const DatasetInfo& d, const VolumeLayer& vl) {
  Layer l;
  l.field = m.requireField(vl.field);
  l.view = m.view(l.field);
  l.tf = vl.tf;
  if (l.tf.valueRange.empty()) l.tf.valueRange = d.valueRanges[size_t(l.field)];
  if (l.tf.opacityScale == 0.f) l.tf.opacityScale = d.defaultOpacityScale;
  l.table = tabulateTransferFunction(l.tf);
  const range1f r = l.tf.valueRange;
  l.t.entries = l.table.data();
  l.t.range = r;
  l.t.logScale = l.tf.logScale;
  l.t.fastLinear = !l.tf.logScale && r.upper > r.lower;
  l.t.lower = r.lower;
  l.t.scale = l.t.fastLinear ? 1.f / (r.upper - r.lower) : 0.f;
  const float span = r.empty() ? 0.f : r.upper - r.lower;
  l.invSpan = span > 0.f ? 1.f / span : 0.f;
  l.byValue = l.tf.logScale || !(span > 0.f);
  l.gradData = cellGradients(l.view, m.bricks, m.fieldValues[size_t(l.field)].size());
  for (int a = 0; a < 3; ++a) {
    l.grad[size_t(a)] = l.view;
    l.grad[size_t(a)].values = l.gradData[size_t(a)].data();
  }
  return l;
}

/// Central differences half the region's finest width each way (one-sided where a point has no
/// value), each point reconstructed from the region's bricks inside the region, else where it falls.
inline vec3f centralGradient(const FieldView& view, uint32_t regionIndex, const Region& region, const vec3f& p,
                             float value) {
  vec3f grad;
  const float h = 0.5f * region.finestWidth();
  const box3f rb = region.bounds();
  auto inside = [&](const vec3f& q) {
    return q.x >= rb.lower.x && q.x <= rb.upper.x && q.y >= rb.lower.y && q.y <= rb.upper.y && q.z >= rb.lower.z &&
           q.z <= rb.upper.z;
  };
  auto at = [&](const vec3f& q, float& v) {
    return inside(q) ? sampleRegion(view, regionIndex, q, v) : sampleField(view, q, v);
  };
  for (int ax = 0; ax < 3; ++ax) {
    vec3f pp = p, pm = p;
    pp[ax] += h;
    pm[ax] -= h;
    float vp = value, vm = value;
    if (!at(pp, vp)) vp = value, pp[ax] = p[ax];
    if (!at(pm, vm)) vm = value, pm[ax] = p[ax];
    const float span = pp[ax] - pm[ax];
    grad[ax] = span > 0.f ? (vp - vm) / span : 0.f;
  }
  return grad;
}

/// Renders a volume-only scene (space skipping on, no debug view), pass after pass, one sample
/// after another along each ray.
inline Image render(const Model& m, const DatasetInfo& d, const Scene& s, const Frame& f) {
  std::vector<Layer> layers;
  for (const VolumeLayer& vl : s.layers)
    layers.push_back(makeLayer(m, d, vl));
  std::vector<uint8_t> visible(m.regions.regions.size(), 0);
  for (size_t i = 0; i < visible.size(); ++i)
    for (const Layer& l : layers)
      visible[i] = visible[i] || tfMayBeVisible(l.t, m.regions.valueRanges[size_t(l.field)][i]);
  RegionTraversal traversal(m, TraversalKind::KdTree);
  traversal.setVisible(visible);
  std::unique_ptr<CellLocator> locator;
  if (s.integration.reconstruction == Reconstruction::CellLocation) locator = std::make_unique<CellLocator>(m);
  const float invReference = 1.f / d.referenceWidth;
  const vec3f invScale(1.0 / m.world.scale.x, 1.0 / m.world.scale.y, 1.0 / m.world.scale.z);
  const float meanScale = float((m.world.scale.x + m.world.scale.y + m.world.scale.z) / 3.0);
  const Integration& in = s.integration;
  const bool wantGrad = s.shading == Shading::Analytic;

  auto march = [&](const Ray& ray, float rho, const vec3f& light, const vec3f& halfVector) {
    vec4f acc;
    traversal.traverse(ray, [&](const Segment& seg) {
      const Region& region = m.regions.regions[seg.region];
      const float width = in.sampling == Sampling::Adaptive ? region.finestWidth() : d.referenceWidth;
      SegmentMarch sm(std::max(seg.t0, ray.tmin), std::min(seg.t1, ray.tmax), rho, 0.5f * width / f.rate);
      while (sm.a < sm.end) {
        const float b = sm.intervalEnd();
        if (!(b > sm.a)) break;
        sm.k += 1.f;
        const float len = b - sm.a;
        const vec3f p = ray.org + ray.dir * (0.5f * (sm.a + b));
        sm.a = b;
        float logSum = 0.f, alphaSum = 0.f;
        vec3f colorSum(0.f), color(0.f);
        for (const Layer& l : layers) {
          float value;
          vec3f grad(0.f);
          const bool found = locator ? locator->sample(l.field, p, value, wantGrad ? &grad : nullptr)
                                     : sampleRegion(l.view, seg.region, p, value, wantGrad ? &grad : nullptr);
          if (!found) break;
          const vec4f rgba = tfLookup(l.t, value);
          if (rgba.w >= 0.f) continue;
          const float alpha = correctedOpacity(rgba.w, len, invReference);
          logSum += rgba.w;
          vec3f c = rgba.rgb();
          if (s.shading != Shading::None) {
            if (s.shading == Shading::Smooth)
              for (int a = 0; a < 3; ++a)
                if (!sampleRegion(l.grad[size_t(a)], seg.region, p, grad[a])) grad[a] = 0.f;
            if (s.shading == Shading::Central) grad = centralGradient(l.view, seg.region, region, p, value);
            const float cellWidth = region.finestWidth() * meanScale;
            const float fade = fadeScaleAt(l.byValue ? cellWidth : cellWidth * l.invSpan, l.byValue, value);
            c = shadeVolumeSample(c, grad * invScale, light, halfVector, s.light.terms, fade);
          }
          colorSum += c * alpha;
          alphaSum += alpha;
          color = c;
        }
        if (!(logSum < 0.f)) continue;
        const float alpha = correctedOpacity(logSum, len, invReference);
        if (layers.size() > 1) color = alphaSum > 0.f ? colorSum * (1.f / alphaSum) : vec3f(0.f);
        compositeBehind(acc, color, alpha);
        if (in.earlyTermination && acc.w >= in.terminationOpacity) return false;
      }
      return true;
    });
    return acc;
  };

  Image image(f.width, f.height);
  const double aspect = double(f.width) / double(f.height);
  const int passes = f.samplesPerPixel;
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x) {
      vec4f sum;
      for (int pass = 0; pass < passes; ++pass) {
        PixelRandom rng(x, y, pass, f.seed);
        const bool pixelJitter = passes > 1 && f.jitter;
        const float jx = pixelJitter ? rng.next() : 0.5f, jy = pixelJitter ? rng.next() : 0.5f;
        const float rho = f.jitter ? rng.next() : 0.5f;
        vec3d orgW, dirW;
        f.camera.ray((x + jx) / f.width, (y + jy) / f.height, aspect, orgW, dirW);
        dirW = normalize(dirW);
        const vec3d dL = dirW / m.world.scale;
        Ray ray;
        ray.org = vec3f(m.world.toLattice(orgW));
        ray.dir = vec3f(dL / length(dL));
        const vec3f viewW(dirW);
        const vec3f light = s.light.headlight ? viewW : normalize(s.light.direction);
        sum += march(ray, rho, light, normalize(light + viewW));
      }
      const float inv = 1.f / float(passes);
      image.pixels[size_t(y) * size_t(f.width) + size_t(x)] = {sum.x * inv, sum.y * inv, sum.z * inv, sum.w * inv};
    }
  return image;
}

} // namespace exa::reference
