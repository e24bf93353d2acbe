#include "exabricks/render/renderer.h"

#include "exabricks/amr/basis_batch.h"
#include "exabricks/amr/cell_locator.h"
#include "exabricks/amr/gradients.h"
#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/core/random.h"
#include "exabricks/render/shade_batch.h"

#include "../accel/embree_util.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace exa {
namespace {

/// At most this many bricks in the union list of a batch that joins several segments; a segment
/// whose bricks would make it longer starts a new batch.
constexpr uint32_t kMaxJoinedBricks = 16;

/// Whether p lies in the closed box b.
bool insideBox(const box3f& b, const vec3f& p) {
  return p.x >= b.lower.x && p.x <= b.upper.x && p.y >= b.lower.y && p.y <= b.upper.y && p.z >= b.lower.z &&
         p.z <= b.upper.z;
}

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

} // namespace

vec3f debugLevelColor(int level) {
  switch (level & 7) {
  case 0:
    return {0.90f, 0.10f, 0.10f};
  case 1:
    return {0.95f, 0.55f, 0.05f};
  case 2:
    return {0.90f, 0.85f, 0.10f};
  case 3:
    return {0.20f, 0.75f, 0.20f};
  case 4:
    return {0.10f, 0.60f, 0.85f};
  case 5:
    return {0.25f, 0.25f, 0.90f};
  case 6:
    return {0.60f, 0.20f, 0.80f};
  default:
    return {0.55f, 0.55f, 0.55f};
  }
}

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

/// A transfer function tabulated for the marcher (the storage behind a TfTableView).
struct LayerTable {
  int field = 0;
  FieldView view;
  std::array<FieldView, 3> grad{}; ///< smooth shading: the field's gradient fields (cellGradients)
  TransferFunction tf;
  std::vector<vec4f> table;
  TfTableView t;
  float span = 0.f, invSpan = 0.f; ///< width of the value range (the scale of shading weights)

  void build(const Model& model, const DatasetInfo& dataset, int fieldIndex, const TransferFunction& tfIn) {
    field = fieldIndex;
    view = model.view(fieldIndex);
    tf = tfIn;
    if (tf.valueRange.empty() && size_t(field) < dataset.valueRanges.size())
      tf.valueRange = dataset.valueRanges[size_t(field)];
    if (tf.opacityScale == 0.f) tf.opacityScale = dataset.defaultOpacityScale;
    table = tabulateTransferFunction(tf);
    const range1f r = tf.valueRange;
    t.entries = table.data();
    t.range = r;
    t.logScale = tf.logScale;
    t.fastLinear = !tf.logScale && r.upper > r.lower;
    t.lower = r.lower;
    t.scale = t.fastLinear ? 1.f / (r.upper - r.lower) : 0.f;
    span = r.empty() ? 0.f : r.upper - r.lower;
    invSpan = span > 0.f ? 1.f / span : 0.f;
  }
  vec4f lookup(float value) const { return tfLookup(t, value); }
};

using Counters = FrameBuffer::TileCounters;

/// A ray in both spaces: world origin and unit direction, and the lattice ray whose t is in
/// finest lattice units along a unit lattice direction; t = s * kappa for world distance s.
struct DualRay {
  vec3d orgW, dirW;
  Ray lattice;
  double kappa = 1.0;
  double sMin = 0.0, sMax = std::numeric_limits<double>::infinity(); ///< clipped world interval
  /// The interval inside the renderer's domain (meshes are limited to it even when not clipped).
  double domainMin = 0.0, domainMax = std::numeric_limits<double>::infinity();
};

/// Unit vectors perpendicular to n (and to each other).
void orthonormalBasis(const vec3f& n, vec3f& u, vec3f& v) {
  const vec3f a = std::abs(n.x) > 0.9f ? vec3f(0.f, 1.f, 0.f) : vec3f(1.f, 0.f, 0.f);
  u = normalize(cross(a, n));
  v = cross(n, u);
}

} // namespace

DatasetInfo DatasetInfo::of(const Model& m) {
  int finest = kMaxLevel;
  for (const Brick& b : m.bricks)
    finest = std::min(finest, b.level);
  std::vector<range1f> ranges(m.fieldValues.size());
  for (size_t f = 0; f < m.fieldValues.size() && f < m.regions.valueRanges.size(); ++f)
    for (const range1f& r : m.regions.valueRanges[f])
      ranges[f].extend(r);
  return from(finest, m.cellBounds(), m.world.scale, std::move(ranges));
}

DatasetInfo DatasetInfo::from(int finestLevel, const box3i& cb, const vec3d& worldScale,
                              std::vector<range1f> valueRanges) {
  DatasetInfo d;
  d.referenceWidth = float(1 << std::clamp(finestLevel, 0, kMaxLevel));
  if (!cb.empty()) d.worldDiagonal = length(vec3d(cb.size()) * worldScale);
  d.valueRanges = std::move(valueRanges);
  const float extentCells = cb.empty() ? 1.f : float(reduceMax(cb.size())) / d.referenceWidth;
  d.extentCells = extentCells;
  d.defaultOpacityScale = std::min(1.f, 8.f / std::max(1.f, extentCells));
  return d;
}

RenderStats& RenderStats::operator+=(const RenderStats& o) {
  seconds += o.seconds;
  rays += o.rays;
  samples += o.samples;
  regionsVisited += o.regionsVisited;
  surfaceHits += o.surfaceHits;
  isoSamples += o.isoSamples;
  aoRays += o.aoRays;
  tiles += o.tiles;
  return *this;
}

void FrameBuffer::resize(int width, int height) {
  if (width < 1 || height < 1 || width > 32768 || height > 32768)
    fail("frame buffer size ", width, "x", height, " is out of range (1..32768)");
  width_ = width;
  height_ = height;
  tilesX_ = (width + kRenderTile - 1) / kRenderTile;
  tilesY_ = (height + kRenderTile - 1) / kRenderTile;
  sum_.resize(size_t(width) * size_t(height));
  steps_.resize(size_t(width) * size_t(height));
  tilePasses_.resize(size_t(tilesX_) * size_t(tilesY_));
  counters_.resize(size_t(tilesX_) * size_t(tilesY_));
  clear();
}

void FrameBuffer::clear() {
  std::fill(sum_.begin(), sum_.end(), vec4f());
  std::fill(steps_.begin(), steps_.end(), 0.f);
  std::fill(tilePasses_.begin(), tilePasses_.end(), 0u);
  stats_ = RenderStats();
}

FrameBuffer::Sums FrameBuffer::sums() {
  static_assert(sizeof(vec4f) == 4 * sizeof(float), "vec4f must be four packed floats");
  return {reinterpret_cast<float*>(sum_.data()),
          steps_.data(),
          sum_.size(),
          tilePasses_.data(),
          tilePasses_.size(),
          &stats_,
          &stepsView_};
}

uint32_t FrameBuffer::passes() const {
  if (tilePasses_.empty()) return 0;
  return *std::min_element(tilePasses_.begin(), tilePasses_.end());
}

void FrameBuffer::resolve(Image& out) const {
  if (out.width != width_ || out.height != height_) out = Image(width_, height_);
  auto tilePassesAt = [&](int x, int y) {
    return tilePasses_[size_t(y / kRenderTile) * size_t(tilesX_) + size_t(x / kRenderTile)];
  };
  // The steps view: samples per ray, averaged over the passes, scaled to the image's maximum.
  float maxSteps = 1.f;
  if (stepsView_)
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x)
        if (const uint32_t n = tilePassesAt(x, y))
          maxSteps = std::max(maxSteps, steps_[size_t(y) * size_t(width_) + size_t(x)] * (1.f / float(n)));
  const ColorMap heat = stepsView_ ? builtinColorMap("inferno") : ColorMap();
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      const size_t i = size_t(y) * size_t(width_) + size_t(x);
      const uint32_t n = tilePassesAt(x, y);
      if (n == 0) {
        out.pixels[i] = vec4f();
        continue;
      }
      const float inv = 1.f / float(n);
      if (stepsView_) {
        const vec3f c = heat.at(steps_[i] * inv / maxSteps);
        out.pixels[i] = {c.x, c.y, c.z, 1.f};
      } else {
        const vec4f& s = sum_[i];
        out.pixels[i] = {s.x * inv, s.y * inv, s.z * inv, s.w * inv};
      }
    }
}

Image FrameBuffer::resolve() const {
  Image image;
  resolve(image);
  return image;
}

struct Renderer::Impl {
  const Model& model;
  DatasetInfo dataset;
  Scene scene;
  bool haveScene = false;

  std::vector<LayerTable> layers;
  /// Smooth shading's gradient fields (cellGradients) per model field, built when first needed.
  std::map<int, std::array<std::vector<float>, 3>> gradientFields;
  std::vector<uint8_t> visible;
  std::unique_ptr<RegionTraversal> traversal;
  std::unique_ptr<CellLocator> locator; ///< only for Reconstruction::CellLocation
  float referenceWidth = 1.f;           ///< opacity reference (dataset's finest cell width), lattice units
  float invReferenceWidth = 1.f;
  vec3f invScale{1.f}; ///< world units per lattice unit, inverted (for gradients)
  double minScale = 1.0;
  float meanScale = 1.f;  ///< world units per lattice unit, averaged over the axes
  bool hasDomain = false; ///< primary rays see only the inside of `domain` (world)
  box3d domain;

  // Iso-surfaces: their own set of regions (value range holds an iso-value) and traversal.
  std::vector<float> isoValues;
  FieldView isoView;
  std::vector<uint8_t> isoVisible;
  std::unique_ptr<RegionTraversal> isoTraversal;
  bool isoColored = false;
  LayerTable isoColor; ///< colour map of the iso colour field

  // Triangle meshes in world space.
  RTCDevice device = nullptr;
  RTCScene meshScene = nullptr;
  std::vector<vec3f> meshColors;

  Impl(const Model& m, const DatasetInfo& d) : model(m), dataset(d) {
    if (dataset.valueRanges.size() != m.fieldValues.size())
      fail("dataset information holds ", dataset.valueRanges.size(), " value ranges for ", m.fieldValues.size(),
           " fields");
    if (!(dataset.referenceWidth > 0.f) || !std::isfinite(dataset.referenceWidth))
      fail("dataset reference width must be a positive number");
    referenceWidth = dataset.referenceWidth;
    invReferenceWidth = 1.f / referenceWidth;
    invScale = vec3f(1.0 / m.world.scale.x, 1.0 / m.world.scale.y, 1.0 / m.world.scale.z);
    minScale = reduceMin(m.world.scale);
    meanScale = float((m.world.scale.x + m.world.scale.y + m.world.scale.z) / 3.0);
  }

  ~Impl() { releaseMeshes(); }

  void releaseMeshes() {
    if (meshScene) rtcReleaseScene(meshScene);
    if (device) rtcReleaseDevice(device);
    meshScene = nullptr;
    device = nullptr;
    meshColors.clear();
  }

  /// Rebuilds the layer tables, the visible regions and the volume traversal.
  void updateVolume(const Scene& s, const std::vector<int>& fields) {
    std::vector<LayerTable> tables(s.layers.size());
    for (size_t i = 0; i < s.layers.size(); ++i)
      tables[i].build(model, dataset, fields[i], s.layers[i].tf);
    layers = std::move(tables);
    // Space skipping: a region whose value ranges map to zero opacity in every layer cannot
    // contribute.
    const Integration& in = s.integration;
    const size_t regionCount = model.regions.regions.size();
    const bool skipping = in.spaceSkipping && s.debug == DebugView::None;
    visible.assign(regionCount, layers.empty() && skipping ? 0 : 1);
    if (skipping && !layers.empty())
      tbb::parallel_for(size_t(0), regionCount, [&](size_t i) {
        bool any = false;
        for (const LayerTable& layer : layers)
          any = any || tfMayBeVisible(layer.t, model.regions.valueRanges[size_t(layer.field)][i]);
        visible[i] = any;
      });
    TraversalKind kind = in.traversal;
    if (in.autoTraversal) {
      size_t count = 0;
      for (uint8_t v : visible)
        count += v;
      kind = double(count) < double(in.embreeBelowVisibleFraction) * double(visible.size()) ? TraversalKind::Embree
                                                                                            : TraversalKind::KdTree;
    }
    if (!traversal || traversal->kind() != kind) traversal = std::make_unique<RegionTraversal>(model, kind);
    traversal->setVisible(visible);
    if (in.reconstruction == Reconstruction::CellLocation && !locator) locator = std::make_unique<CellLocator>(model);
  }

  /// Rebuilds the iso region set (regions whose value range holds an iso-value).
  void updateIso(const Scene& s, int field, int colorField) {
    const IsoSurfaces& iso = s.iso;
    isoValues = iso.values;
    isoColored = colorField >= 0;
    if (iso.values.empty()) {
      isoTraversal.reset();
      isoVisible.clear();
      return;
    }
    isoView = model.view(field);
    if (isoColored) isoColor.build(model, dataset, colorField, iso.colorTf);
    const auto& ranges = model.regions.valueRanges[size_t(field)];
    isoVisible.assign(ranges.size(), 0);
    tbb::parallel_for(size_t(0), ranges.size(), [&](size_t i) {
      const range1f& r = ranges[i];
      bool any = false;
      for (float v : iso.values)
        any = any || (!r.empty() && r.lower <= v && v <= r.upper);
      isoVisible[i] = any;
    });
    size_t count = 0;
    for (uint8_t v : isoVisible)
      count += v;
    // Iso-surfaces are sparse: Embree skips the empty space in its BVH unless most regions hold one.
    const TraversalKind kind = double(count) < double(s.integration.embreeBelowVisibleFraction) * double(ranges.size())
                                   ? TraversalKind::Embree
                                   : TraversalKind::KdTree;
    if (!isoTraversal || isoTraversal->kind() != kind) isoTraversal = std::make_unique<RegionTraversal>(model, kind);
    isoTraversal->setVisible(isoVisible);
  }

  /// Rebuilds the mesh BVH.
  void updateMeshes(const Scene& s) {
    releaseMeshes();
    if (s.meshes.empty()) return;
    device = embree::newDevice();
    meshScene = rtcNewScene(device);
    rtcSetSceneFlags(meshScene, RTC_SCENE_FLAG_ROBUST);
    for (size_t m = 0; m < s.meshes.size(); ++m) {
      const TriangleMesh& mesh = *s.meshes[m].mesh;
      RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                   3 * sizeof(float), mesh.vertices.size()));
      auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                     3 * sizeof(uint32_t), mesh.triangles.size()));
      if (!vertices || !indices) {
        rtcReleaseGeometry(geom);
        releaseMeshes();
        fail("mesh ", m, ": out of memory for ", mesh.triangles.size(), " triangles");
      }
      for (size_t i = 0; i < mesh.vertices.size(); ++i)
        for (int k = 0; k < 3; ++k)
          vertices[3 * i + size_t(k)] = mesh.vertices[i][k];
      for (size_t i = 0; i < mesh.triangles.size(); ++i)
        for (int k = 0; k < 3; ++k)
          indices[3 * i + size_t(k)] = uint32_t(mesh.triangles[i][k]);
      rtcCommitGeometry(geom);
      const unsigned id = rtcAttachGeometry(meshScene, geom);
      rtcReleaseGeometry(geom);
      EXA_CHECK(id == m);
      meshColors.push_back(s.meshes[m].color);
    }
    rtcCommitScene(meshScene);
  }

  /// World ray -> lattice ray with the clip interval applied (planes and box, world space).
  /// The lattice interval may be empty; sMin/sMax keep the clipped world interval.
  DualRay makeRay(const vec3d& orgW, const vec3d& dirWIn, bool clip) const {
    const Clipping& c = scene.clip;
    DualRay r;
    r.orgW = orgW;
    r.dirW = normalize(dirWIn);
    const vec3d orgL = model.world.toLattice(orgW);
    const vec3d dL = r.dirW / model.world.scale;
    r.kappa = length(dL);
    r.lattice.org = vec3f(orgL);
    r.lattice.dir = vec3f(dL / r.kappa);
    if (clip) {
      for (const ClipPlane& cp : c.planes) {
        const double g0 = dot(orgW - cp.point, cp.normal), dn = dot(r.dirW, cp.normal);
        if (dn == 0.0) {
          if (g0 > 0.0) r.sMax = -1.0;
        } else if (dn > 0.0) {
          r.sMax = std::min(r.sMax, -g0 / dn);
        } else {
          r.sMin = std::max(r.sMin, -g0 / dn);
        }
      }
      if (!c.box.empty()) {
        for (int a = 0; a < 3; ++a) {
          if (r.dirW[a] == 0.0) {
            if (orgW[a] < c.box.lower[a] || orgW[a] > c.box.upper[a]) r.sMax = -1.0;
            continue;
          }
          const double ta = (c.box.lower[a] - orgW[a]) / r.dirW[a];
          const double tb = (c.box.upper[a] - orgW[a]) / r.dirW[a];
          r.sMin = std::max(r.sMin, std::min(ta, tb));
          r.sMax = std::min(r.sMax, std::max(ta, tb));
        }
      }
    }
    setLatticeInterval(r);
    return r;
  }

  static void setLatticeInterval(DualRay& r) {
    r.lattice.tmin = float(r.sMin * r.kappa);
    r.lattice.tmax = std::isinf(r.sMax) ? std::numeric_limits<float>::infinity() : float(r.sMax * r.kappa);
    if (!(r.lattice.tmax >= r.lattice.tmin)) r.lattice.tmax = r.lattice.tmin = 0.f, r.sMax = -1.0;
  }

  /// Restricts a primary ray to the domain box (volume, iso-surfaces and meshes alike).
  void restrictToDomain(DualRay& r) const {
    if (!hasDomain) return;
    // The domain's interval on its own (meshes that clipping leaves use it), then with the clip.
    for (int a = 0; a < 3; ++a) {
      if (r.dirW[a] == 0.0) {
        if (r.orgW[a] < domain.lower[a] || r.orgW[a] >= domain.upper[a]) r.domainMax = -1.0;
        continue;
      }
      const double ta = (domain.lower[a] - r.orgW[a]) / r.dirW[a];
      const double tb = (domain.upper[a] - r.orgW[a]) / r.dirW[a];
      r.domainMin = std::max(r.domainMin, std::min(ta, tb));
      r.domainMax = std::min(r.domainMax, std::max(ta, tb));
    }
    if (r.sMax >= r.sMin) { // not clipped away already
      r.sMin = std::max(r.sMin, r.domainMin);
      r.sMax = std::min(r.sMax, r.domainMax);
    }
    setLatticeInterval(r);
  }

  bool clippedAway(const DualRay& r) const { return r.sMax < r.sMin; }

  /// Nearest mesh hit within [sMin, sMax] (world distances along the unit direction).
  bool traceMesh(const DualRay& r, double sMin, double sMax, SurfaceHit& hit) const {
    if (!meshScene || !(sMax >= sMin)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh = embree::makeRayHit(vec3f(r.orgW), vec3f(r.dirW), float(std::max(sMin, 0.0)),
                                      std::isinf(sMax) ? std::numeric_limits<float>::infinity() : float(sMax));
    rtcIntersect1(meshScene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit.kind = SurfaceHit::Mesh;
    hit.index = int(rh.hit.geomID);
    hit.distance = rh.ray.tfar;
    hit.position = r.orgW + r.dirW * hit.distance;
    vec3f n = normalize(vec3f(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
    if (dot(vec3d(n), r.dirW) > 0.0) n = -n;
    hit.normal = n;
    return true;
  }

  /// Whether any mesh lies within [sMin, sMax] along the ray.
  bool meshOccludes(const DualRay& r, double sMin, double sMax) const {
    if (!meshScene || !(sMax > sMin)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray = embree::makeRay(vec3f(r.orgW), vec3f(r.dirW), float(std::max(sMin, 0.0)), float(sMax));
    rtcOccluded1(meshScene, &context, &ray);
    return ray.tfar < 0.f;
  }

  /// Lattice step of a region at the given rate.
  float stepOf(const Region& region, float rate) const {
    const float width = scene.integration.sampling == Sampling::Adaptive ? region.finestWidth() : referenceWidth;
    return 0.5f * width / rate;
  }

  /// Nearest iso-surface crossing along a lattice ray within [ray.tmin, ray.tmax]: each region
  /// is stepped at its adaptive rate (and at its entry and exit), and a sign change of
  /// value - isovalue is refined by bisection to 1e-3 of the region's finest cell width, then
  /// by one secant step. Returns the lattice t, the region and the iso-value's index.
  bool findIso(const Ray& ray, float rate, float& tHit, uint32_t& regionHit, int& which, uint64_t& samples) const {
    if (!isoTraversal || isoValues.empty() || !(ray.tmax > ray.tmin)) return false;
    bool found = false;
    isoTraversal->traverse(ray, [&](const Segment& seg) {
      const float t0 = std::max(seg.t0, ray.tmin), t1 = std::min(seg.t1, ray.tmax);
      if (!(t1 > t0)) return true;
      const Region& region = model.regions.regions[seg.region];
      const float dt = stepOf(region, rate);
      const float tolerance = 1e-3f * region.finestWidth();
      auto value = [&](float t, float& v) {
        ++samples;
        return sampleRegion(isoView, seg.region, ray.org + ray.dir * t, v);
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
          for (size_t j = 0; j < isoValues.size(); ++j) {
            const float c = isoValues[j];
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

  /// Nearest surface (mesh or iso-surface) along a primary ray.
  bool nearestSurface(const DualRay& r, float rate, SurfaceHit& hit, uint64_t& isoSamples) const {
    bool have = false;
    const bool clipMeshes = scene.clip.meshes;
    if (meshScene) {
      const double s0 = clipMeshes ? r.sMin : r.domainMin;
      const double s1 = clipMeshes ? r.sMax : r.domainMax;
      have = traceMesh(r, s0, s1, hit);
    }
    if (isoTraversal && !clippedAway(r)) {
      Ray lr = r.lattice;
      if (have) lr.tmax = std::min(lr.tmax, float(hit.distance * r.kappa));
      float t;
      uint32_t region;
      int which;
      if (findIso(lr, rate, t, region, which, isoSamples)) {
        const vec3f p = lr.org + lr.dir * t;
        float v;
        vec3f g;
        hit.kind = SurfaceHit::Iso;
        hit.index = which;
        hit.distance = double(t) / r.kappa;
        hit.position = r.orgW + r.dirW * hit.distance;
        vec3f n = -vec3f(r.dirW);
        if (sampleRegion(isoView, region, p, v, &g)) {
          const vec3f gw = g * invScale;
          if (length(gw) > 1e-30f) n = normalize(gw);
        }
        if (dot(vec3d(n), r.dirW) > 0.0) n = -n;
        hit.normal = n;
        have = true;
      }
    }
    return have;
  }

  /// Colour of a surface hit before lighting.
  vec3f surfaceColor(const SurfaceHit& hit) const {
    if (hit.kind == SurfaceHit::Mesh) return meshColors[size_t(hit.index)];
    if (isoColored) {
      float v;
      const vec3d pl = model.world.toLattice(hit.position);
      if (sampleField(isoColor.view, vec3f(pl), v)) return isoColor.lookup(v).rgb();
    }
    const std::vector<vec3f>& colors = scene.iso.colors;
    if (!colors.empty()) return colors[size_t(hit.index) % colors.size()];
    return defaultIsoColor(hit.index);
  }

  /// Fraction of unoccluded cosine-weighted rays over the hemisphere of the hit's normal.
  float ambientOcclusion(const SurfaceHit& hit, float rate, PixelRandom& rng, Counters& c) const {
    const AmbientOcclusion& ao = scene.ao;
    const double lengthW = ao.length > 0.f ? double(ao.length) : 0.1 * dataset.worldDiagonal;
    const double eps = std::max(1e-5 * dataset.worldDiagonal, 1e-2 * double(referenceWidth) * minScale);
    vec3f u, v;
    orthonormalBasis(hit.normal, u, v);
    float open = 0.f;
    for (int i = 0; i < ao.rays; ++i) {
      const float r1 = rng.next(), r2 = rng.next();
      const float radius = std::sqrt(r1), phi = 6.2831853f * r2;
      const vec3f d =
          u * (radius * std::cos(phi)) + v * (radius * std::sin(phi)) + hit.normal * std::sqrt(std::max(0.f, 1.f - r1));
      ++c.aoRays;
      const DualRay ar = makeRay(hit.position + vec3d(hit.normal) * eps, vec3d(d), true);
      const double meshMin = scene.clip.meshes ? ar.sMin : 0.0;
      const double meshMax = scene.clip.meshes ? std::min(ar.sMax, lengthW) : lengthW;
      if (meshOccludes(ar, meshMin, meshMax)) continue;
      Ray lr = ar.lattice;
      lr.tmax = std::min(lr.tmax, float(lengthW * ar.kappa));
      float t;
      uint32_t region;
      int which;
      if (!clippedAway(ar) && findIso(lr, rate, t, region, which, c.isoSamples)) continue;
      float visibility = 1.f;
      if (ao.volume && scene.volume && !clippedAway(ar) && lr.tmax > lr.tmin) {
        vec4f acc;
        uint64_t samples = 0, regions = 0;
        integrate<true>(lr, 0.5f, rate, vec3f(0.f), vec3f(0.f), acc, samples, regions);
        c.samples += samples;
        visibility = 1.f - acc.w;
      }
      open += visibility;
    }
    return ao.rays > 0 ? open / float(ao.rays) : 1.f;
  }

  /// Marches the visible regions along the lattice ray within [tmin, tmax], compositing front to
  /// back into acc (premultiplied). OpacityOnly skips colour and shading (shadow-like rays).
  template <bool OpacityOnly>
  void integrate(const Ray& ray, float rho, float rate, const vec3f& light, const vec3f& halfVector, vec4f& acc,
                 uint64_t& raySamples, uint64_t& regionCount) const {
    if (layers.empty() || !(ray.tmax > ray.tmin)) return;
    const size_t layerCount = layers.size();
    const Shading shading = scene.shading;
    const ShadingTerms& terms = scene.light.terms;
    const Integration& in = scene.integration;
    const bool wantGrad = !OpacityOnly && shading == Shading::Analytic;
    // Smooth shading in batches: the gradient fields reconstructed after the lookup.
    const bool smooth = !OpacityOnly && shading == Shading::Smooth;
    // Batches: one layer reconstructed from its regions (the common case).
    const bool batched = in.vectorized && layerCount == 1 && in.reconstruction == Reconstruction::Regions;
    bool lastHidden = true; // the last batch showed nothing: reconstruct values first
    // What the batches' shading needs besides the samples; only the fade width varies by region.
    VolumeShadeParams shadeParams;
    BatchFunctions batchFn{};
    if (batched) {
      batchFn = batchFunctions();
      shadeParams.invReferenceWidth = invReferenceWidth;
      shadeParams.shade = wantGrad || smooth;
      shadeParams.gradientScale = invScale;
      shadeParams.light = light, shadeParams.halfVector = halfVector, shadeParams.terms = terms;
      shadeParams.fadeByValue = fadeByValue(layers[0]);
    }
    const bool central = shading == Shading::Central;
    // The batch being filled: the samples of one segment, or with joinSegments of several
    // consecutive ones, reconstructed over the union of their regions' brick lists (ascending, so
    // every sample sums its own region's bricks in its region's order; basis_batch.h).
    SampleBatch batch;
    // Per sample, with room for whole-vector stores past the batch's end (as its positions).
    alignas(64) float lengths[2 * kSampleBatch], fades[2 * kSampleBatch];
    alignas(64) uint32_t regionOf[2 * kSampleBatch];
    uint32_t unionIds[2][kMaxJoinedBricks];
    const uint32_t* brickIds = nullptr;
    uint32_t brickCount = 0;
    int unionSlot = 0;
    batch.count = 0;
    // Reconstructs, shades and composites the batch in order and empties it; true where the ray
    // terminated.
    const auto flush = [&]() {
      const int n = batch.count;
      const LayerTable& layer = layers[0];
      const bool withGrad = wantGrad && !(in.lazyGradients && lastHidden);
      batchFn.sample(layer.view, brickIds, brickCount, batch, withGrad);
      // The transfer function at every sample (log2 transmittance 0: transparent).
      TfBatch looked;
      const bool anyShown = batchFn.tfLookup(layer.t, batch, looked);
      lastHidden = !anyShown;
      if (!anyShown) {
        raySamples += uint64_t(n);
        batch.count = 0;
        return false;
      }
      if (wantGrad && !withGrad) batchFn.sample(layer.view, brickIds, brickCount, batch, true);
      if (smooth) smoothGradients(layer, brickIds, brickCount, batchFn.sample, batch);
      // Opacity and colour of every sample at once, then the in-order compositing.
      ShadedBatch shaded;
      shadeParams.fadeWidth = fades;
      batchFn.shade(batch, looked, lengths, shadeParams, shaded);
      batch.count = 0;
      // Front to back with the transmittance as a running product: one multiplication per
      // sample on the dependency chain (compositeBehind's sums, reassociated). Samples that
      // show nothing have alpha 0.
      float transmittance = 1.f - acc.w, r = 0.f, g = 0.f, b = 0.f;
      int i = 0;
      bool done = false;
      if (!OpacityOnly && !central) {
        // The whole batch without a per-sample test: the opacity only grows along the batch,
        // so where it ends below the termination threshold no sample reached it, and only
        // where it ends above is the batch composited again with the test, sample by sample.
        float t = transmittance;
        for (int j = 0; j < n; ++j) {
          const float alpha = shaded.alpha[j];
          const float w = t * alpha;
          r += w * shaded.r[j];
          g += w * shaded.g[j];
          b += w * shaded.b[j];
          t *= 1.f - alpha;
        }
        if (!(in.earlyTermination && 1.f - t >= in.terminationOpacity)) {
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
          if (central && looked.logT[i] < 0.f) { // the batch left the table's colour unshaded
            const Region& region = model.regions.regions[regionOf[i]];
            const float value = batch.value[i];
            const vec3f p(batch.x[i], batch.y[i], batch.z[i]);
            const vec3f grad = centralGradient(layer, regionOf[i], region, p, value);
            c = shadeVolumeSample(c, grad * invScale, light, halfVector, terms, volumeFade(layer, region, value));
          }
          r += w * c.x;
          g += w * c.y;
          b += w * c.z;
        }
        transmittance *= 1.f - alpha;
        ++i;
        if (in.earlyTermination && 1.f - transmittance >= in.terminationOpacity) {
          done = true;
          break;
        }
      }
      raySamples += uint64_t(i);
      acc.x += r, acc.y += g, acc.z += b;
      acc.w = 1.f - transmittance;
      return done;
    };
    bool terminated = false;
    traversal->traverse(ray, [&](const Segment& seg) {
      ++regionCount;
      const Region& region = model.regions.regions[seg.region];
      const float dt = stepOf(region, rate);
      // Sample positions (k + rho) dt delimit intervals, each sampled at its midpoint.
      SegmentMarch march(std::max(seg.t0, ray.tmin), std::min(seg.t1, ray.tmax), rho, dt);
      if (batched) {
        const uint32_t* ids = layers[0].view.brickIds + region.brickBegin;
        const float fade = fadeWidth(layers[0], region);
        while (march.a < march.end) {
          int m = batch.count;
          if (m > 0 && (brickIds != ids || brickCount != region.brickCount)) {
            // Join this segment's bricks to the batch's, or flush first where the union would be
            // too long.
            uint32_t* out = unionIds[unionSlot];
            uint32_t joined = 0;
            if (joinBrickLists(brickIds, brickIds + brickCount, ids, ids + region.brickCount, out, joined)) {
              brickIds = out, brickCount = joined;
              unionSlot ^= 1;
            } else {
              if (flush()) return terminated = true, false;
              m = 0;
            }
          }
          if (m == 0) brickIds = ids, brickCount = region.brickCount;
          const int n = batchFn.place(ray.org, ray.dir, march, batch, lengths);
          std::fill_n(fades + m, kSampleBatch, fade); // whole vectors: n or more
          std::fill_n(regionOf + m, kSampleBatch, seg.region);
          if (n == 0) break;
          if ((batch.count == kSampleBatch || !in.joinSegments) && flush()) return terminated = true, false;
        }
        return true;
      }
      while (march.a < march.end) {
        const float b = march.intervalEnd();
        if (!(b > march.a)) break;
        march.k += 1.f;
        const float len = b - march.a;
        const float tm = 0.5f * (march.a + b);
        march.a = b;
        const vec3f p = ray.org + ray.dir * tm;
        ++raySamples;
        float logSum = 0.f, alphaSum = 0.f, alpha = 0.f;
        vec3f colorSum(0.f), color(0.f);
        for (size_t li = 0; li < layerCount; ++li) {
          const LayerTable& layer = layers[li];
          float value;
          vec3f grad;
          const bool found = in.reconstruction == Reconstruction::Regions
                                 ? sampleRegion(layer.view, seg.region, p, value, wantGrad ? &grad : nullptr)
                                 : locator->sample(layer.field, p, value, wantGrad ? &grad : nullptr);
          if (!found) break; // no value here for any field: the cells are shared
          const vec4f rgba = layer.lookup(value);
          if (rgba.w >= 0.f) continue; // log2 transmittance 0: fully transparent
          const float layerAlpha = correctedOpacity(rgba.w, len, invReferenceWidth);
          logSum += rgba.w;
          if (OpacityOnly) continue;
          vec3f c = rgba.rgb();
          if (shading != Shading::None) {
            if (shading == Shading::Smooth)
              grad = smoothGradientAt(layer, seg.region, p);
            else if (central)
              grad = centralGradient(layer, seg.region, region, p, value);
            c = shadeVolumeSample(c, grad * invScale, light, halfVector, terms, volumeFade(layer, region, value));
          }
          if (layerCount == 1) {
            alpha = layerAlpha;
            color = c;
          } else {
            colorSum += c * layerAlpha;
            alphaSum += layerAlpha;
          }
        }
        if (!(logSum < 0.f)) continue;
        if (OpacityOnly || layerCount > 1) alpha = correctedOpacity(logSum, len, invReferenceWidth);
        if (!OpacityOnly && layerCount > 1) color = alphaSum > 0.f ? colorSum * (1.f / alphaSum) : vec3f(0.f);
        if (OpacityOnly)
          acc.w += (1.f - acc.w) * alpha;
        else
          compositeBehind(acc, color, alpha);
        if (in.earlyTermination && acc.w >= in.terminationOpacity) return false;
      }
      return true;
    });
    if (batched && !terminated && batch.count > 0) flush();
  }

  /// Cell width (world) over the scale of the field's changes: how much of the gradient shading
  /// a sample gets (shadeVolumeSample). The scale is the transfer function's value range, or for
  /// logarithmic mapping (or an empty range) the value itself.
  bool fadeByValue(const LayerTable& layer) const { return layer.tf.logScale || !(layer.span > 0.f); }
  float fadeWidth(const LayerTable& layer, const Region& region) const {
    const float cellWidth = region.finestWidth() * meanScale;
    return fadeByValue(layer) ? cellWidth : cellWidth * layer.invSpan;
  }
  float volumeFade(const LayerTable& layer, const Region& region, float value) const {
    return fadeScaleAt(fadeWidth(layer, region), fadeByValue(layer), value);
  }

  /// Builds the gradient fields of every volume layer's field that has none yet and points the
  /// layers at them; true when one was built.
  bool attachGradients() {
    bool built = false;
    for (LayerTable& layer : layers) {
      auto it = gradientFields.find(layer.field);
      if (it == gradientFields.end()) {
        it = gradientFields
                 .emplace(layer.field,
                          cellGradients(layer.view, model.bricks, model.fieldValues[size_t(layer.field)].size()))
                 .first;
        built = true;
      }
      for (int a = 0; a < 3; ++a) {
        layer.grad[size_t(a)] = layer.view;
        layer.grad[size_t(a)].values = it->second[size_t(a)].data();
      }
    }
    return built;
  }

  /// Smooth shading's gradient at every sample of a batch: the layer's gradient fields
  /// reconstructed like its values, from the same bricks (per lattice unit; 0 where none).
  static void smoothGradients(const LayerTable& layer, const uint32_t* ids, uint32_t count,
                              SampleBricksBatchFunction sample, SampleBatch& batch) {
    SampleBatch g;
    g.count = batch.count;
    std::copy(std::begin(batch.x), std::end(batch.x), g.x);
    std::copy(std::begin(batch.y), std::end(batch.y), g.y);
    std::copy(std::begin(batch.z), std::end(batch.z), g.z);
    float* const out[3] = {batch.gx, batch.gy, batch.gz};
    for (int a = 0; a < 3; ++a) {
      sample(layer.grad[size_t(a)], ids, count, g, false);
      for (int i = 0; i < batch.count; ++i)
        out[a][i] = g.valid[i] ? g.value[i] : 0.f;
    }
  }

  /// The same at one point of a region.
  static vec3f smoothGradientAt(const LayerTable& layer, uint32_t regionIndex, const vec3f& p) {
    vec3f g(0.f);
    for (int a = 0; a < 3; ++a)
      if (!sampleRegion(layer.grad[size_t(a)], regionIndex, p, g[a])) g[a] = 0.f;
    return g;
  }

  /// Central differences at p over half the region's finest width each way; each point
  /// reconstructed from the region's bricks where it lies inside the region, else where it
  /// falls; one-sided where a point has no value.
  vec3f centralGradient(const LayerTable& layer, uint32_t regionIndex, const Region& region, const vec3f& p,
                        float value) const {
    vec3f grad;
    const float h = 0.5f * region.finestWidth();
    const box3f rb = region.bounds();
    auto at = [&](const vec3f& q, float& v) {
      return insideBox(rb, q) ? sampleRegion(layer.view, regionIndex, q, v) : sampleField(layer.view, q, v);
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

  /// Colour of a debug view for one ray: the first visible region's level, brick or id.
  vec4f debugColor(const Ray& ray, Counters& c) const {
    vec4f acc;
    const DebugView view = scene.debug;
    traversal->traverse(ray, [&](const Segment& seg) {
      const Region& region = model.regions.regions[seg.region];
      vec3f color;
      if (view == DebugView::Region) {
        color = hashColor(seg.region);
      } else {
        // The brick whose cells hold the segment's midpoint; where no cell does (the margin of
        // the supports), the region's finest brick.
        const vec3f p = ray.org + ray.dir * (0.5f * (seg.t0 + seg.t1));
        uint32_t brickId = kNoRegion;
        for (uint32_t k = 0; k < region.brickCount; ++k) {
          const uint32_t id = model.regions.brickIds[region.brickBegin + k];
          const box3i b = model.bricks[id].bounds();
          if (brickId == kNoRegion || model.bricks[id].level < model.bricks[brickId].level) brickId = id;
          if (p.x >= b.lower.x && p.x < b.upper.x && p.y >= b.lower.y && p.y < b.upper.y && p.z >= b.lower.z &&
              p.z < b.upper.z) {
            brickId = id;
            break;
          }
        }
        color = view == DebugView::Level ? debugLevelColor(model.bricks[brickId].level) : hashColor(brickId);
      }
      acc = {color.x, color.y, color.z, 1.f};
      ++c.regions;
      return false;
    });
    return acc;
  }

  /// What every ray of a pass shares.
  struct PassSetup {
    double aspect;
    vec3f lightWorld;
    bool surfaces, clipping, jitter, pixelJitter;
  };

  /// One sample of pixel (x, y) for pass frame.frameIndex: premultiplied colour and volume
  /// samples taken.
  vec4f tracePixel(int x, int y, const Frame& frame, const PassSetup& ps, Counters& c, uint64_t& raySamples) const {
    PixelRandom rng(x, y, frame.frameIndex, frame.seed);
    const float jx = ps.pixelJitter ? rng.next() : 0.5f;
    const float jy = ps.pixelJitter ? rng.next() : 0.5f;
    const float rho = ps.jitter ? rng.next() : 0.5f;
    vec3d orgW, dirW;
    frame.camera.ray((x + jx) / frame.width, (y + jy) / frame.height, ps.aspect, orgW, dirW);
    // March in lattice space with a unit-length lattice direction: t is in finest-level lattice
    // units.
    DualRay dr = makeRay(orgW, dirW, ps.clipping && scene.debug == DebugView::None);
    restrictToDomain(dr);
    const Ray& ray = dr.lattice;
    const vec3f viewW = vec3f(dr.dirW);
    const vec3f light = scene.light.headlight ? viewW : ps.lightWorld;
    const vec3f halfVector = normalize(light + viewW);
    ++c.rays;
    raySamples = 0;
    if (scene.debug == DebugView::Level || scene.debug == DebugView::Region || scene.debug == DebugView::Brick)
      return debugColor(ray, c);

    vec4f acc; // premultiplied, front to back
    SurfaceHit hit;
    const bool haveHit = ps.surfaces && nearestSurface(dr, frame.rate, hit, c.isoSamples);
    Ray volumeRay = ray;
    if (haveHit) volumeRay.tmax = std::min(volumeRay.tmax, float(hit.distance * dr.kappa));
    if (scene.volume && !clippedAway(dr))
      integrate<false>(volumeRay, rho, frame.rate, light, halfVector, acc, raySamples, c.regions);
    if (haveHit && acc.w < 1.f) {
      ++c.surfaceHits;
      const vec3f base = surfaceColor(hit);
      const float ao = scene.ao.rays > 0 ? ambientOcclusion(hit, frame.rate, rng, c) : 1.f;
      compositeOpaqueBehind(acc, shadeSurface(base, hit.normal, light, halfVector, ao, scene.light.terms));
    }
    c.samples += raySamples;
    return acc;
  }
};

Renderer::Renderer(const Model& model) : Renderer(model, DatasetInfo::of(model)) {}

Renderer::Renderer(const Model& model, const DatasetInfo& dataset) : impl_(std::make_unique<Impl>(model, dataset)) {}

Renderer::~Renderer() = default;

const Scene& Renderer::scene() const { return impl_->scene; }
const DatasetInfo& Renderer::dataset() const { return impl_->dataset; }
const Model& Renderer::model() const { return impl_->model; }

TraversalKind Renderer::traversalInUse() const {
  return impl_->traversal ? impl_->traversal->kind() : impl_->scene.integration.traversal;
}

size_t Renderer::visibleRegions() const { return impl_->traversal ? impl_->traversal->visibleCount() : 0; }

box3d Renderer::visibleBounds() const {
  const Impl& im = *impl_;
  box3f lattice;
  if (im.scene.volume)
    for (size_t i = 0; i < im.visible.size(); ++i)
      if (im.visible[i]) lattice.extend(im.model.regions.regions[i].bounds());
  for (size_t i = 0; i < im.isoVisible.size(); ++i)
    if (im.isoVisible[i]) lattice.extend(im.model.regions.regions[i].bounds());
  if (lattice.empty()) return box3d();
  return box3d(im.model.world.toWorld(vec3d(lattice.lower)), im.model.world.toWorld(vec3d(lattice.upper)));
}

size_t Renderer::isoRegions() const { return impl_->isoTraversal ? impl_->isoTraversal->visibleCount() : 0; }

size_t Renderer::meshCount() const { return impl_->meshColors.size(); }

SceneUpdate Renderer::setScene(const Scene& s) {
  Impl& im = *impl_;
  s.validate();
  for (size_t m = 0; m < s.meshes.size(); ++m)
    if (!s.meshes[m].mesh) fail("mesh ", m, " (", s.meshes[m].source, ") has not been read");
  // Resolve every field name first: an unknown one leaves the current scene as it is.
  std::vector<int> fields;
  for (const VolumeLayer& layer : s.layers)
    fields.push_back(im.model.requireField(layer.field));
  int isoField = -1, isoColorField = -1;
  if (!s.iso.values.empty()) {
    isoField = !s.iso.field.empty() ? im.model.requireField(s.iso.field)
                                    : (fields.empty() ? im.model.requireField("") : fields[0]);
    if (!s.iso.colorField.empty()) isoColorField = im.model.requireField(s.iso.colorField);
  }

  const Scene& cur = im.scene;
  const bool first = !im.haveScene;
  SceneUpdate u;
  u.volume = first || s.layers != cur.layers || s.integration != cur.integration || s.debug != cur.debug;
  u.iso = first || s.iso != cur.iso ||
          s.integration.embreeBelowVisibleFraction != cur.integration.embreeBelowVisibleFraction;
  u.meshes = first || s.meshes != cur.meshes;
  // Helpers read the scene while rebuilding: make the new one current first.
  im.scene = s;
  im.haveScene = true;
  if (u.volume) {
    Timer t;
    im.updateVolume(s, fields);
    u.volumeSeconds = t.seconds();
  }
  if (s.shading == Shading::Smooth) {
    Timer t;
    if (im.attachGradients()) u.volumeSeconds += t.seconds();
  }
  if (u.iso) {
    Timer t;
    im.updateIso(s, isoField, isoColorField);
    u.isoSeconds = t.seconds();
  }
  if (u.meshes) {
    Timer t;
    im.updateMeshes(s);
    u.meshSeconds = t.seconds();
  }
  return u;
}

void Renderer::setDomain(const box3d& world) {
  impl_->hasDomain = !(world == box3d());
  impl_->domain = world;
}

const box3d& Renderer::domain() const { return impl_->domain; }

bool Renderer::pick(const vec3d& origin, const vec3d& direction, SurfaceHit& hit) const {
  if (!(length(direction) > 0.0) || !impl_->haveScene) return false;
  const DualRay r = impl_->makeRay(origin, direction, true);
  uint64_t samples = 0;
  return impl_->nearestSurface(r, 1.f, hit, samples);
}

bool Renderer::renderPass(const Frame& frame, FrameBuffer& buffer, const PassControl& control) const {
  const Impl& im = *impl_;
  if (!im.haveScene) fail("no scene set");
  frame.validate();
  if (buffer.width() != frame.width || buffer.height() != frame.height)
    fail("frame buffer is ", buffer.width(), "x", buffer.height(), ", the frame ", frame.width, "x", frame.height);
  const Scene& s = im.scene;
  Impl::PassSetup ps;
  ps.aspect = double(frame.width) / double(frame.height);
  ps.lightWorld = normalize(s.light.direction);
  ps.surfaces = (im.isoTraversal || im.meshScene) && s.debug == DebugView::None;
  ps.clipping = !s.clip.planes.empty() || !s.clip.box.empty();
  ps.jitter = frame.jitter && s.debug == DebugView::None;
  ps.pixelJitter = frame.samplesPerPixel > 1 && ps.jitter;

  const int tileCount = buffer.tileCount();
  const int end = control.tileEnd < 0 ? tileCount : std::min(control.tileEnd, tileCount);
  const int stride = std::max(1, control.tileStride);
  const int begin = std::max(0, control.tileBegin);
  const int passTiles = end > begin ? (end - begin + stride - 1) / stride : 0;
  const bool steps = s.debug == DebugView::Steps;
  buffer.stepsView_ = steps;
  std::atomic<bool> cancelled{false};
  std::atomic<uint64_t> done{0};
  Timer timer;

  tbb::parallel_for(0, passTiles, [&](int i) {
    const int tile = begin + i * stride;
    Counters& c = buffer.counters_[size_t(tile)];
    c = Counters();
    if (control.cancel && control.cancel->load(std::memory_order_relaxed)) {
      cancelled.store(true, std::memory_order_relaxed);
      return;
    }
    const int tx = tile % buffer.tilesX_, ty = tile / buffer.tilesX_;
    for (int y = ty * kRenderTile; y < std::min(frame.height, (ty + 1) * kRenderTile); ++y)
      for (int x = tx * kRenderTile; x < std::min(frame.width, (tx + 1) * kRenderTile); ++x) {
        uint64_t raySamples = 0;
        const vec4f acc = im.tracePixel(x, y, frame, ps, c, raySamples);
        const size_t p = size_t(y) * size_t(frame.width) + size_t(x);
        buffer.sum_[p] += acc;
        if (steps) buffer.steps_[p] += float(raySamples);
      }
    ++buffer.tilePasses_[size_t(tile)];
    const uint64_t n = done.fetch_add(1, std::memory_order_relaxed) + 1;
    if (control.progress) control.progress(n, uint64_t(passTiles));
  });

  RenderStats st;
  st.seconds = timer.seconds();
  for (int i = 0; i < passTiles; ++i) {
    const Counters& c = buffer.counters_[size_t(begin + i * stride)];
    st.rays += c.rays;
    st.samples += c.samples;
    st.regionsVisited += c.regions;
    st.surfaceHits += c.surfaceHits;
    st.isoSamples += c.isoSamples;
    st.aoRays += c.aoRays;
  }
  st.tiles = done.load();
  buffer.stats_ += st;
  return !cancelled.load();
}

bool Renderer::renderPasses(const Frame& frame, FrameBuffer& buffer, int passes, const PassControl& control) const {
  Frame pass = frame;
  while (int(buffer.passes()) < passes) {
    if (control.cancel && control.cancel->load(std::memory_order_relaxed)) return false;
    pass.frameIndex = int(buffer.passes());
    if (!renderPass(pass, buffer, control)) return false;
  }
  return true;
}

Image Renderer::render(const Frame& frame, RenderStats* stats) const {
  frame.validate();
  FrameBuffer buffer(frame.width, frame.height);
  renderPasses(frame, buffer, frame.samplesPerPixel);
  if (stats) *stats = buffer.stats();
  return buffer.resolve();
}

} // namespace exa
