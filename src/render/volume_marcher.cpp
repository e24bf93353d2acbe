#include "volume_marcher.h"

#include "path_trace.h"

#include "exabricks/amr/basis_batch.h"
#include "exabricks/amr/gradients.h"
#include "exabricks/core/error.h"
#include "exabricks/render/shade_batch.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace exa {
namespace {

/// At most this many bricks in the union list of a batch that joins several segments; a segment
/// whose bricks would make it longer starts a new batch.
constexpr uint32_t kMaxJoinedBricks = 16;

/// The union of two ascending lists of brick ids into `out` (kMaxJoinedBricks entries), ascending;
/// false where it would be longer. Without branches on the ids, which neighbouring regions'
/// lists share unpredictably.
bool joinBrickLists(const uint32_t* a, const uint32_t* aEnd, const uint32_t* b, const uint32_t* bEnd, uint32_t* out,
                    uint32_t& count) {
  uint32_t u = 0;
  while (a < aEnd && b < bEnd && u < kMaxJoinedBricks) {
    const uint32_t x = *a, y = *b;
    out[u++] = std::min(x, y);
    a += x <= y;
    b += y <= x;
  }
  while (a < aEnd && u < kMaxJoinedBricks)
    out[u++] = *a++;
  while (b < bEnd && u < kMaxJoinedBricks)
    out[u++] = *b++;
  count = u;
  return a == aEnd && b == bEnd;
}

/// Smooth shading's gradient at the samples of a batch that the transfer function shows (`tf`;
/// the others are not lit, and get 0): the layer's packed gradient fields reconstructed like its
/// values, from the same bricks, in one pass over them, for the shown samples gathered into one
/// batch (per lattice unit; 0 where no cell has weight).
void smoothGradients(const LayerTable& layer, const uint32_t* ids, uint32_t count, SampleShadedBatchFunction sample,
                     const TfBatch& tf, SampleBatch& batch) {
  alignas(64) int32_t shown[kSampleBatch];
  int m = 0;
  for (int i = 0; i < batch.count; ++i)
    if (tf.logT[i] < 0.f) shown[m++] = i;
  if (m == batch.count) {
    float* const out[4] = {nullptr, batch.gx, batch.gy, batch.gz};
    sample(layer.view, layer.gradients, false, ids, count, batch, out, nullptr);
    return;
  }
  SampleBatch gathered;
  gathered.count = m;
  for (int k = 0; k < m; ++k)
    gathered.x[k] = batch.x[shown[k]], gathered.y[k] = batch.y[shown[k]], gathered.z[k] = batch.z[shown[k]];
  float* const out[4] = {nullptr, gathered.gx, gathered.gy, gathered.gz};
  sample(layer.view, layer.gradients, false, ids, count, gathered, out, nullptr);
  for (int i = 0; i < batch.count; ++i)
    batch.gx[i] = batch.gy[i] = batch.gz[i] = 0.f;
  for (int k = 0; k < m; ++k)
    batch.gx[shown[k]] = gathered.gx[k], batch.gy[shown[k]] = gathered.gy[k], batch.gz[shown[k]] = gathered.gz[k];
}

/// The march of one ray in batches: the samples of one segment, or with joinSegments of several
/// consecutive ones, reconstructed over the union of their regions' brick lists (ascending, so
/// every sample sums its own region's bricks in its region's order; basis_batch.h), or cell by
/// cell by the locator (Reconstruction::CellLocation). Each batch is looked up in the layers'
/// transfer functions, shaded and composited in order. Several layers sum their optical depths
/// per sample and weigh their colours by their opacities.
template <bool OpacityOnly> class BatchMarch {
public:
  struct Inputs {
    const std::vector<LayerTable>& layers;
    const Model& model;
    const CellLocator* locator; ///< set for Reconstruction::CellLocation
    float referenceWidth;
    vec3f invScale;
    float meanScale;
    const float* strides; ///< per region (VolumeMarcher::strides)
  };

  BatchMarch(const Inputs& in, const MarchSettings& s, const RayLight& light, vec4f& acc, uint64_t& raySamples)
      : in_(in), layer_(in.layers[0]), s_(s), light_(light), acc_(acc), raySamples_(raySamples) {
    wantGrad_ = !OpacityOnly && s.sample.shading == Shading::Analytic;
    smooth_ = !OpacityOnly && s.sample.shading == Shading::Smooth;
    central_ = s.sample.shading == Shading::Central;
    fn_ = s.options.vectorized ? batchFunctions() : scalarBatchFunctions();
    params_.invReferenceWidth = 1.f / in.referenceWidth;
    params_.shade = wantGrad_ || smooth_;
    params_.gradientScale = in.invScale;
    params_.light = light.light, params_.halfVector = light.halfVector, params_.terms = s.terms;
    params_.fadeByValue = layer_.fadeByValue();
    batch_.count = 0;
  }

  /// Places the samples of a segment in the ray's batches, flushing the full ones; false where
  /// the ray terminated.
  bool add(const Ray& ray, float rho, const Segment& seg) {
    const Region& region = in_.model.regions.regions[seg.region];
    const float dt =
        sampleStep(region, s_.sample.sampling, in_.referenceWidth, s_.sample.rate, in_.strides[seg.region]);
    // Sample positions (k + rho) dt delimit intervals, each sampled at its midpoint.
    SegmentMarch march(std::max(seg.t0, ray.tmin), std::min(seg.t1, ray.tmax), rho, dt);
    const uint32_t* ids = layer_.view.brickIds + region.brickBegin;
    const float fade = layer_.fadeWidth(region, in_.meanScale);
    while (march.a < march.end) {
      int m = batch_.count;
      if (m > 0 && (brickIds_ != ids || brickCount_ != region.brickCount)) {
        // Join this segment's bricks to the batch's, or flush first where the union would be
        // too long.
        uint32_t* out = unionIds_[unionSlot_];
        uint32_t joined = 0;
        if (joinBrickLists(brickIds_, brickIds_ + brickCount_, ids, ids + region.brickCount, out, joined)) {
          brickIds_ = out, brickCount_ = joined;
          unionSlot_ ^= 1;
        } else {
          if (flush()) return false;
          m = 0;
        }
      }
      if (m == 0) brickIds_ = ids, brickCount_ = region.brickCount;
      const int n = fn_.place(ray.org, ray.dir, march, batch_, lengths_);
      std::fill_n(fades_ + m, kSampleBatch, fade); // whole vectors: n or more
      std::fill_n(regionOf_ + m, kSampleBatch, seg.region);
      if (n == 0) break;
      if ((batch_.count == kSampleBatch || !s_.options.joinSegments) && flush()) return false;
    }
    return true;
  }

  /// Reconstructs, shades and composites the batch in order and empties it; true where the ray
  /// terminated.
  bool flush() {
    if (batch_.count == 0) return false;
    return in_.layers.size() == 1 ? flushLayer() : flushLayers();
  }

private:
  /// The batch's values (and gradients) of one layer's field.
  void reconstruct(const LayerTable& layer, SampleBatch& batch, bool gradient) const {
    if (!in_.locator) {
      fn_.sample(layer.view, brickIds_, brickCount_, batch, gradient);
      return;
    }
    for (int i = 0; i < batch.count; ++i) {
      vec3f g(0.f);
      float v = 0.f;
      batch.valid[i] =
          in_.locator->sample(layer.field, vec3f(batch.x[i], batch.y[i], batch.z[i]), v, gradient ? &g : nullptr);
      batch.value[i] = v;
      batch.gx[i] = g.x, batch.gy[i] = g.y, batch.gz[i] = g.z;
    }
  }

  /// One layer (the common case).
  bool flushLayer() {
    const int n = batch_.count;
    const bool withGrad = wantGrad_ && !(s_.options.lazyGradients && lastShown_ == 0);
    // Smooth shading where the ray's last batch showed more samples than a narrow batch holds (4):
    // the values and the packed gradient in one pass over the bricks. A second pass for the shown
    // samples would find every brick's factors and corners again, as wide as the batch's.
    const bool together = smooth_ && !in_.locator && lastShown_ > 4;
    if (together) {
      float* const out[4] = {batch_.value, batch_.gx, batch_.gy, batch_.gz};
      fn_.sampleShaded(layer_.view, layer_.gradients, true, brickIds_, brickCount_, batch_, out, batch_.valid);
    } else {
      reconstruct(layer_, batch_, withGrad);
    }
    // The transfer function at every sample (log2 transmittance 0: transparent).
    TfBatch looked;
    const bool anyShown = fn_.tfLookup(layer_.t, batch_, looked);
    lastShown_ = 0;
    for (int i = 0; i < n; ++i)
      lastShown_ += looked.logT[i] < 0.f;
    if (!anyShown) {
      raySamples_ += uint64_t(n);
      batch_.count = 0;
      return false;
    }
    if (wantGrad_ && !withGrad) reconstruct(layer_, batch_, true);
    if (smooth_ && !together) smoothGradients(layer_, brickIds_, brickCount_, fn_.sampleShaded, looked, batch_);
    // Opacity and colour of every sample at once, then the in-order compositing.
    ShadedBatch shaded;
    params_.fadeWidth = fades_;
    fn_.shade(batch_, looked, lengths_, params_, shaded);
    batch_.count = 0;
    return composite(n, central_ ? &looked : nullptr, shaded);
  }

  /// Several layers: per sample the summed log2 transmittance of the layers that show, and their
  /// colours weighed by their own opacities.
  bool flushLayers() {
    const int n = batch_.count;
    alignas(64) float logSum[kSampleBatch] = {}, alphaSum[kSampleBatch] = {};
    alignas(64) float r[kSampleBatch] = {}, g[kSampleBatch] = {}, b[kSampleBatch] = {};
    alignas(64) float fades[2 * kSampleBatch];
    for (const LayerTable& layer : in_.layers) {
      SampleBatch& lb = layerBatch_;
      lb.count = n;
      std::copy(std::begin(batch_.x), std::end(batch_.x), lb.x);
      std::copy(std::begin(batch_.y), std::end(batch_.y), lb.y);
      std::copy(std::begin(batch_.z), std::end(batch_.z), lb.z);
      reconstruct(layer, lb, wantGrad_);
      TfBatch looked;
      if (!fn_.tfLookup(layer.t, lb, looked)) continue;
      if (smooth_) smoothGradients(layer, brickIds_, brickCount_, fn_.sampleShaded, looked, lb);
      for (int i = 0; i < n; ++i)
        fades[i] = layer.fadeWidth(in_.model.regions.regions[regionOf_[i]], in_.meanScale);
      VolumeShadeParams params = params_;
      params.fadeWidth = fades;
      params.fadeByValue = layer.fadeByValue();
      ShadedBatch shaded;
      fn_.shade(lb, looked, lengths_, params, shaded);
      for (int i = 0; i < n; ++i) {
        if (!(looked.logT[i] < 0.f)) continue; // fully transparent here
        logSum[i] += looked.logT[i];
        if (OpacityOnly) continue;
        vec3f c(shaded.r[i], shaded.g[i], shaded.b[i]);
        if (central_) c = shadeCentral(layer, lb, i, c);
        const vec3f weighted = c * shaded.alpha[i];
        r[i] += weighted.x, g[i] += weighted.y, b[i] += weighted.z;
        alphaSum[i] += shaded.alpha[i];
      }
    }
    ShadedBatch combined;
    for (int i = 0; i < n; ++i) {
      const bool shows = logSum[i] < 0.f;
      combined.alpha[i] = shows ? correctedOpacity(logSum[i], lengths_[i], params_.invReferenceWidth) : 0.f;
      const vec3f c = alphaSum[i] > 0.f ? vec3f(r[i], g[i], b[i]) * (1.f / alphaSum[i]) : vec3f(0.f);
      combined.r[i] = c.x, combined.g[i] = c.y, combined.b[i] = c.z;
    }
    batch_.count = 0;
    return composite(n, nullptr, combined);
  }

  /// Front to back with the transmittance as a running product: one multiplication per sample on
  /// the dependency chain (compositeBehind's sums, reassociated). Samples that show nothing have
  /// alpha 0. `centralOf`: the one layer's lookup, where its colours still need central-difference
  /// shading. True where the ray terminated.
  bool composite(int n, const TfBatch* centralOf, const ShadedBatch& shaded) {
    float transmittance = 1.f - acc_.w, r = 0.f, g = 0.f, b = 0.f;
    int i = 0;
    bool done = false;
    if (!OpacityOnly && !centralOf) {
      // The whole batch without a per-sample test: the opacity only grows along the batch, so
      // where it ends below the termination threshold no sample reached it, and only where it
      // ends above is the batch composited again with the test, sample by sample.
      float t = transmittance;
      for (int j = 0; j < n; ++j) {
        const float alpha = shaded.alpha[j];
        const float w = t * alpha;
        r += w * shaded.r[j];
        g += w * shaded.g[j];
        b += w * shaded.b[j];
        t *= 1.f - alpha;
      }
      if (!(s_.sample.earlyTermination && 1.f - t >= s_.sample.terminationOpacity)) {
        transmittance = t;
        i = n;
      } else {
        r = g = b = 0.f;
      }
    }
    while (i < n) {
      const float alpha = shaded.alpha[i];
      const float w = transmittance * alpha;
      if (!OpacityOnly) {
        vec3f c(shaded.r[i], shaded.g[i], shaded.b[i]);
        if (centralOf && centralOf->logT[i] < 0.f) c = shadeCentral(layer_, batch_, i, c); // left unshaded
        r += w * c.x;
        g += w * c.y;
        b += w * c.z;
      }
      transmittance *= 1.f - alpha;
      ++i;
      if (s_.sample.earlyTermination && 1.f - transmittance >= s_.sample.terminationOpacity) {
        done = true;
        break;
      }
    }
    raySamples_ += uint64_t(i);
    acc_.x += r, acc_.y += g, acc_.z += b;
    acc_.w = 1.f - transmittance;
    return done;
  }

  /// Central-difference shading of sample i of a layer's batch.
  vec3f shadeCentral(const LayerTable& layer, const SampleBatch& batch, int i, const vec3f& c) const {
    const Region& region = in_.model.regions.regions[regionOf_[i]];
    const float value = batch.value[i];
    const vec3f p(batch.x[i], batch.y[i], batch.z[i]);
    const vec3f grad = centralGradient(layer.view, regionOf_[i], region, p, value);
    return shadeVolumeSample(c, grad * in_.invScale, light_.light, light_.halfVector, s_.terms,
                             layer.fade(region, in_.meanScale, value));
  }

  const Inputs& in_;
  const LayerTable& layer_; ///< the first layer (the only one, in the common case)
  const MarchSettings& s_;
  const RayLight& light_;
  vec4f& acc_;
  uint64_t& raySamples_;
  bool wantGrad_ = false, smooth_ = false, central_ = false;
  int lastShown_ = 0; // samples the ray's last batch showed (none: reconstruct values first)
  BatchFunctions fn_{};
  VolumeShadeParams params_; // what the batches' shading needs besides the samples
  SampleBatch batch_;
  SampleBatch layerBatch_; ///< several layers: the one being reconstructed
  // Per sample, with room for whole-vector stores past the batch's end (as its positions).
  alignas(64) float lengths_[2 * kSampleBatch], fades_[2 * kSampleBatch];
  alignas(64) uint32_t regionOf_[2 * kSampleBatch];
  uint32_t unionIds_[2][kMaxJoinedBricks];
  const uint32_t* brickIds_ = nullptr;
  uint32_t brickCount_ = 0;
  int unionSlot_ = 0;
};

} // namespace

MarchSettings MarchSettings::of(const Scene& scene, const RendererOptions& options, float rate) {
  MarchSettings m;
  m.sample = volumeSettingsOf(scene, rate);
  m.terms = scene.light.terms;
  m.reconstruction = scene.integration.reconstruction;
  m.options = options;
  return m;
}

VolumeMarcher::VolumeMarcher(const Model& model, const DatasetInfo& dataset)
    : model_(model), dataset_(dataset), majorantGrid_(model) {
  referenceWidth_ = dataset.referenceWidth;
  invScale_ = vec3f(1.0 / model.world.scale.x, 1.0 / model.world.scale.y, 1.0 / model.world.scale.z);
  meanScale_ = float((model.world.scale.x + model.world.scale.y + model.world.scale.z) / 3.0);
}

void VolumeMarcher::update(const std::vector<VolumeLayer>& layers, const std::vector<int>& fields,
                           const Integration& in, bool skipping) {
  std::vector<LayerTable> tables(layers.size());
  for (size_t i = 0; i < layers.size(); ++i)
    tables[i].build(model_, dataset_, fields[i], layers[i].tf);
  layers_ = std::move(tables);
  // Space skipping: a region whose value ranges map to zero opacity in every layer cannot
  // contribute.
  const size_t regionCount = model_.regions.regions.size();
  visible_.assign(regionCount, layers_.empty() && skipping ? 0 : 1);
  if (skipping && !layers_.empty())
    tbb::parallel_for(size_t(0), regionCount, [&](size_t i) {
      bool any = false;
      for (const LayerTable& layer : layers_)
        any = any || tfMayBeVisible(layer.t, model_.regions.valueRanges[size_t(layer.field)][i]);
      visible_[i] = any;
    });
  strides_.assign(regionCount, 1.f); // the old tables' strides: none until updateStrides
  TraversalKind kind = in.traversal;
  if (in.autoTraversal) {
    size_t count = 0;
    for (uint8_t v : visible_)
      count += v;
    kind = double(count) < double(in.embreeBelowVisibleFraction) * double(visible_.size()) ? TraversalKind::Embree
                                                                                           : TraversalKind::KdTree;
  }
  if (!traversal_ || traversal_->kind() != kind) traversal_ = std::make_unique<RegionTraversal>(model_, kind);
  traversal_->setVisible(visible_);
  if (in.reconstruction == Reconstruction::CellLocation && !locator_) locator_ = std::make_unique<CellLocator>(model_);
}

void VolumeMarcher::updateStrides(bool enabled, bool shaded) {
  const size_t regionCount = model_.regions.regions.size();
  strides_.assign(regionCount, 1.f);
  if (!enabled || layers_.empty()) return;
  const float perLog2 = extinctionPerLog2();
  std::vector<const TfTableView*> views;
  for (const LayerTable& layer : layers_)
    views.push_back(&layer.t);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, regionCount), [&](const tbb::blocked_range<size_t>& chunk) {
    std::vector<range1f> ranges(layers_.size());
    for (size_t i = chunk.begin(); i != chunk.end(); ++i) {
      if (!visible_[i]) continue;
      for (size_t l = 0; l < layers_.size(); ++l)
        ranges[l] = model_.regions.valueRanges[size_t(layers_[l].field)][i];
      const box3f b = model_.regions.regions[i].bounds();
      strides_[i] = regionStride(views, ranges, length(b.upper - b.lower), perLog2, shaded);
    }
  });
}

float VolumeMarcher::extinctionPerLog2() const { return float(std::log(2.0)) / referenceWidth_; }

void VolumeMarcher::updateMajorants(bool grid) {
  const float perLog2 = extinctionPerLog2();
  std::vector<TableMaxExtinction> maxima;
  for (const LayerTable& layer : layers_)
    maxima.emplace_back(layer.t, perLog2);
  majorants_.assign(model_.regions.regions.size(), 0.f);
  tbb::parallel_for(size_t(0), majorants_.size(), [&](size_t i) {
    if (i < visible_.size() && !visible_[i]) return;
    float sum = 0.f;
    for (size_t l = 0; l < layers_.size(); ++l)
      sum += maxima[l](model_.regions.valueRanges[size_t(layers_[l].field)][i]);
    majorants_[i] = sum;
  });
  if (grid)
    majorantGrid_.update(layers_, maxima, majorants_);
  else
    majorantGrid_.update({}, {}, majorants_);
}

namespace {

/// Whether two closed boxes share a point.
bool meets(const box3f& a, const box3f& b) {
  return a.lower.x <= b.upper.x && b.lower.x <= a.upper.x && a.lower.y <= b.upper.y && b.lower.y <= a.upper.y &&
         a.lower.z <= b.upper.z && b.lower.z <= a.upper.z;
}

} // namespace

const GradientFields* VolumeMarcher::gradients(int field) const {
  const auto it = gradientFields_.find(field);
  return it == gradientFields_.end() ? nullptr : &it->second;
}

uint64_t VolumeMarcher::gradientVersion(int field) const {
  const auto it = gradientFields_.find(field);
  return it == gradientFields_.end() ? 0 : it->second.version;
}

void VolumeMarcher::adoptGradients(int field, GradientFields gradients) {
  if (gradients.cells.size() != 2 * model_.fieldValues.at(size_t(field)).size())
    fail("gradient fields of ", gradients.cellCount(), " cells adopted for a field of ",
         model_.fieldValues[size_t(field)].size());
  if (gradients.built.size() != model_.bricks.size() || gradients.scaleBias.size() != model_.bricks.size())
    fail("gradient fields of ", gradients.built.size(), " bricks (", gradients.scaleBias.size(),
         " scales) adopted for a model of ", model_.bricks.size());
  if (gradientFields_.count(field)) return; // one already built (and pointed at) stays
  gradients.missing = size_t(std::count(gradients.built.begin(), gradients.built.end(), uint8_t(0)));
  gradients.version = 1;
  gradientFields_.emplace(field, std::move(gradients));
}

bool VolumeMarcher::attachGradients(const box3d* domain) {
  // The bricks that samples may read: those of the visible regions that meet the domain (in
  // lattice units, widened by a finest cell against round-off). Not looked for where every
  // layer's field has them all.
  std::vector<uint8_t> needed;
  const bool complete = std::all_of(layers_.begin(), layers_.end(), [&](const LayerTable& l) {
    const auto it = gradientFields_.find(l.field);
    return it != gradientFields_.end() && it->second.missing == 0;
  });
  if (!complete) {
    const float inf = std::numeric_limits<float>::infinity();
    box3f within(vec3f(-inf), vec3f(inf));
    if (domain) {
      const vec3d a = model_.world.toLattice(domain->lower), b = model_.world.toLattice(domain->upper);
      within = box3f(vec3f(min(a, b)) - vec3f(1.f), vec3f(max(a, b)) + vec3f(1.f));
    }
    needed.assign(model_.bricks.size(), 0);
    for (size_t r = 0; r < visible_.size(); ++r) {
      const Region& region = model_.regions.regions[r];
      if (!visible_[r] || !meets(region.bounds(), within)) continue;
      for (uint32_t k = 0; k < region.brickCount; ++k)
        needed[model_.regions.brickIds[region.brickBegin + k]] = 1;
    }
  }
  bool built = false;
  for (LayerTable& layer : layers_) {
    auto it = gradientFields_.find(layer.field);
    if (it == gradientFields_.end()) {
      it = gradientFields_.emplace(layer.field, GradientFields()).first;
      const ValueArray& values = model_.fieldValues[size_t(layer.field)];
      it->second.reset(values.data(), values.size(), model_.bricks.size());
    }
    GradientFields& fields = it->second;
    std::vector<uint32_t> which;
    if (fields.missing != 0)
      for (size_t b = 0; b < needed.size(); ++b)
        if (needed[b] && !fields.built[b]) which.push_back(uint32_t(b));
    if (!which.empty()) {
      fillPackedGradients(layer.view, model_.bricks, model_.regions.regions.size(), which, fields);
      for (uint32_t b : which)
        fields.built[b] = 1;
      fields.missing -= which.size();
      ++fields.version;
      built = true;
    }
    layer.gradients = {fields.cells.data(), fields.scaleBias.data()};
  }
  return built;
}

template <bool OpacityOnly>
void VolumeMarcher::march(const Ray& ray, float rho, const RayLight& light, const MarchSettings& s, vec4f& acc,
                          uint64_t& raySamples, uint64_t& regionCount) const {
  if (layers_.empty() || !(ray.tmax > ray.tmin)) return;
  const typename BatchMarch<OpacityOnly>::Inputs inputs{
      layers_,         model_,    s.reconstruction == Reconstruction::CellLocation ? locator_.get() : nullptr,
      referenceWidth_, invScale_, meanScale_,
      strides_.data()};
  BatchMarch<OpacityOnly> batches(inputs, s, light, acc, raySamples);
  bool terminated = false;
  traversal_->traverse(ray, [&](const Segment& seg) {
    ++regionCount;
    if (batches.add(ray, rho, seg)) return true;
    terminated = true;
    return false;
  });
  if (!terminated) batches.flush();
}

template void VolumeMarcher::march<false>(const Ray&, float, const RayLight&, const MarchSettings&, vec4f&, uint64_t&,
                                          uint64_t&) const;
template void VolumeMarcher::march<true>(const Ray&, float, const RayLight&, const MarchSettings&, vec4f&, uint64_t&,
                                         uint64_t&) const;

} // namespace exa
