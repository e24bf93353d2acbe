#include "exabricks/render/renderer.h"

#include "exabricks/amr/cell_locator.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <tbb/blocked_range2d.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstring>

namespace exa {
namespace {

constexpr int kTableSize = 4096;
constexpr int kTile = 16;

uint64_t mixBits(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  return x ^ (x >> 33);
}

/// Deterministic per-pixel, per-sample random numbers in [0, 1).
struct PixelRandom {
  uint64_t state;
  PixelRandom(int x, int y, int sample, uint64_t seed)
      : state(mixBits(seed * 0x9e3779b97f4a7c15ull ^ mixBits((uint64_t(uint32_t(y)) << 32) | uint32_t(x)) ^
                      (uint64_t(sample) << 48))) {}
  float next() {
    state = mixBits(state + 0x9e3779b97f4a7c15ull);
    return float(state >> 40) * (1.f / 16777216.f);
  }
};

vec3f hashColor(uint32_t id) {
  const uint64_t h = mixBits(uint64_t(id) + 12345);
  return vec3f(0.15f + 0.85f * float(h & 255) / 255.f, 0.15f + 0.85f * float((h >> 8) & 255) / 255.f,
               0.15f + 0.85f * float((h >> 16) & 255) / 255.f);
}

/// Colours for levels 0..7, cycling: distinct hues, finest warm.
vec3f levelColor(int level) {
  static const vec3f colors[8] = {{0.90f, 0.10f, 0.10f}, {0.95f, 0.55f, 0.05f}, {0.90f, 0.85f, 0.10f},
                                  {0.20f, 0.75f, 0.20f}, {0.10f, 0.60f, 0.85f}, {0.25f, 0.25f, 0.90f},
                                  {0.60f, 0.20f, 0.80f}, {0.55f, 0.55f, 0.55f}};
  return colors[level & 7];
}

/// 2^x for x <= 0 to float precision (relative error below 2e-7): a degree-6 Taylor
/// polynomial of 2^f on [-1/2, 1/2] times 2^i built from the exponent bits. Cheaper than a libm
/// call on the hot path of every sample's opacity correction.
inline float exp2Negative(float x) {
  if (x < -126.f) return 0.f;
  const float i = std::nearbyint(x);
  const float f = x - i;
  float p = 0.00015403530393381606f;
  p = p * f + 0.0013333558146428443f;
  p = p * f + 0.009618129107628477f;
  p = p * f + 0.05550410866482158f;
  p = p * f + 0.2402265069591007f;
  p = p * f + 0.6931471805599453f;
  p = p * f + 1.f;
  const uint32_t bits = uint32_t(int32_t(i) + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

/// Schlick's rational approximation of x^e for x in [0, 1]: exact at 0 and 1, one division
/// instead of a power per sample.
inline float specularPower(float x, float e) { return x / (e - (e - 1.f) * x); }

} // namespace

struct Renderer::Impl {
  const Model& model;
  int field;
  FieldView view;
  TransferFunction tf;
  /// Colour and log2 of the transmittance of one finest cell width, over the normalised value.
  std::vector<vec4f> table;
  bool fastLinear = false;                ///< t = (value - normLower) * normScale, else tf.normalize
  float normLower = 0.f, normScale = 0.f;
  std::vector<uint8_t> visible;
  std::unique_ptr<RegionTraversal> traversal;
  std::unique_ptr<CellLocator> locator; ///< only for Reconstruction::CellLocation
  float finestWidth = 1.f;   ///< dataset's finest cell width, lattice units (opacity reference)
  float invFinestWidth = 1.f;
  vec3f invScale{1.f};       ///< world units per lattice unit, inverted (for gradients)

  Impl(const Model& m, int f) : model(m), field(f), view(m.view(f)) {
    int finest = kMaxLevel;
    for (const Brick& b : m.bricks) finest = std::min(finest, b.level);
    finestWidth = float(1 << finest);
    invFinestWidth = 1.f / finestWidth;
    invScale = vec3f(1.0 / m.world.scale.x, 1.0 / m.world.scale.y, 1.0 / m.world.scale.z);
  }

  vec4f lookup(float value) const {
    return tableAt(normalized(value));
  }

  float normalized(float value) const {
    return fastLinear ? std::clamp((value - normLower) * normScale, 0.f, 1.f) : tf.normalize(value);
  }

  /// The tabulated transfer function, linearly interpolated, at normalised value n.
  vec4f tableAt(float n) const {
    const float t = n * float(kTableSize - 1);
    const int i = std::clamp(int(t), 0, kTableSize - 2);
    const float f = std::clamp(t - float(i), 0.f, 1.f);
    const vec4f& a = table[size_t(i)];
    const vec4f& b = table[size_t(i) + 1];
    return {a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.z + (b.z - a.z) * f, a.w + (b.w - a.w) * f};
  }

  /// Whether any value in r can be visible through the tabulated function the marcher uses
  /// (its log transmittance is piecewise linear, so its extremes lie at table entries or ends).
  bool mayBeVisible(const range1f& r) const {
    if (r.empty()) return false;
    const float n0 = normalized(r.lower), n1 = normalized(r.upper);
    if (tableAt(n0).w < 0.f || tableAt(n1).w < 0.f) return true;
    const int first = int(std::ceil(n0 * float(kTableSize - 1)));
    const int last = int(std::floor(n1 * float(kTableSize - 1)));
    for (int i = std::max(first, 0); i <= std::min(last, kTableSize - 1); ++i)
      if (table[size_t(i)].w < 0.f) return true;
    return false;
  }
};

Renderer::Renderer(const Model& model, int field, const RenderOptions& options)
    : impl_(std::make_unique<Impl>(model, field)), options_(options) {
  if (options_.width < 1 || options_.height < 1 || options_.width > 32768 || options_.height > 32768)
    fail("image size ", options_.width, "x", options_.height, " is out of range (1..32768)");
  if (options_.samplesPerPixel < 1) fail("samples per pixel must be at least 1");
  if (!(options_.rate > 0.f) || options_.rate > 1024.f) fail("sampling rate must be in (0, 1024]");
}

Renderer::~Renderer() = default;

TraversalKind Renderer::traversalInUse() const {
  return impl_->traversal ? impl_->traversal->kind() : options_.traversal;
}

size_t Renderer::visibleRegions() const {
  return impl_->traversal ? impl_->traversal->visibleCount() : 0;
}

double Renderer::setTransferFunction(const TransferFunction& tfIn) {
  Timer timer;
  Impl& im = *impl_;
  im.tf = tfIn;
  if (im.tf.valueRange.empty()) {
    range1f r;
    for (const range1f& rr : im.model.regions.valueRanges[size_t(im.field)]) r.extend(rr);
    im.tf.valueRange = r;
  }
  // Tabulate colour and log2 transmittance over the normalised value.
  im.table.resize(kTableSize);
  for (int i = 0; i < kTableSize; ++i) {
    const vec4f c = im.tf.atNormalized(float(i) / float(kTableSize - 1));
    im.table[size_t(i)] = {c.x, c.y, c.z, std::log2(1.f - std::min(c.w, 0.999999f))};
  }
  const range1f r = im.tf.valueRange;
  im.fastLinear = !im.tf.logScale && r.upper > r.lower;
  im.normLower = r.lower;
  im.normScale = im.fastLinear ? 1.f / (r.upper - r.lower) : 0.f;
  // Space skipping: a region whose value range maps to zero opacity cannot contribute.
  const auto& ranges = im.model.regions.valueRanges[size_t(im.field)];
  im.visible.assign(ranges.size(), 1);
  if (options_.spaceSkipping && options_.debug == DebugView::None)
    tbb::parallel_for(size_t(0), ranges.size(), [&](size_t i) {
      im.visible[i] = im.mayBeVisible(ranges[i]);
    });
  TraversalKind kind = options_.traversal;
  if (options_.autoTraversal) {
    size_t count = 0;
    for (uint8_t v : im.visible) count += v;
    kind = double(count) < double(options_.embreeBelowVisibleFraction) * double(im.visible.size())
               ? TraversalKind::Embree
               : TraversalKind::KdTree;
  }
  if (!im.traversal || im.traversal->kind() != kind)
    im.traversal = std::make_unique<RegionTraversal>(im.model, kind);
  im.traversal->setVisible(im.visible);
  if (options_.reconstruction == Reconstruction::CellLocation && !im.locator)
    im.locator = std::make_unique<CellLocator>(im.model);
  return timer.seconds();
}

Image Renderer::render(const Camera& camera, RenderStats* statsOut) const {
  const Impl& im = *impl_;
  if (!im.traversal) fail("no transfer function set");
  if (options_.reconstruction == Reconstruction::CellLocation && !im.locator)
    fail("cell-location reconstruction was chosen after the transfer function was set");
  const RenderOptions& o = options_;
  Image image(o.width, o.height);
  const double aspect = double(o.width) / double(o.height);
  const WorldTransform& world = im.model.world;
  const vec3f lightWorld = normalize(o.lightDirection);

  struct Counters {
    uint64_t rays = 0, samples = 0, regions = 0;
  };
  tbb::combinable<Counters> counters;
  const int tilesX = (o.width + kTile - 1) / kTile, tilesY = (o.height + kTile - 1) / kTile;
  Progress progress("rendering", uint64_t(tilesX) * uint64_t(tilesY));
  if (!o.progress) progress.finish();
  std::vector<float> steps; // per pixel, for the steps view
  if (o.debug == DebugView::Steps) steps.assign(size_t(o.width) * size_t(o.height), 0.f);
  Timer timer;

  tbb::parallel_for(
      tbb::blocked_range2d<int>(0, tilesY, 1, 0, tilesX, 1), [&](const tbb::blocked_range2d<int>& tiles) {
        Counters& c = counters.local();
        for (int ty = tiles.rows().begin(); ty < tiles.rows().end(); ++ty)
          for (int tx = tiles.cols().begin(); tx < tiles.cols().end(); ++tx) {
            for (int y = ty * kTile; y < std::min(o.height, (ty + 1) * kTile); ++y)
              for (int x = tx * kTile; x < std::min(o.width, (tx + 1) * kTile); ++x) {
                vec4f sum;
                uint64_t pixelSteps = 0;
                for (int s = 0; s < o.samplesPerPixel; ++s) {
                  PixelRandom rng(x, y, s, o.seed);
                  const bool jitter = o.jitter && o.debug == DebugView::None;
                  const float jx = o.samplesPerPixel > 1 && jitter ? rng.next() : 0.5f;
                  const float jy = o.samplesPerPixel > 1 && jitter ? rng.next() : 0.5f;
                  const float rho = jitter ? rng.next() : 0.5f;
                  vec3d orgW, dirW;
                  camera.ray((x + jx) / o.width, (y + jy) / o.height, aspect, orgW, dirW);
                  // March in lattice space with a unit-length lattice direction: t is in
                  // finest-level lattice units.
                  const vec3d orgL = world.toLattice(orgW);
                  const vec3d dirL = normalize(dirW / world.scale);
                  Ray ray;
                  ray.org = vec3f(orgL);
                  ray.dir = vec3f(dirL);
                  const vec3f viewW = vec3f(normalize(dirW));
                  const vec3f light = o.headlight ? viewW : lightWorld;
                  const vec3f halfVector = normalize(light + viewW);
                  ++c.rays;
                  vec4f acc; // premultiplied, front to back
                  uint64_t raySamples = 0;

                  if (o.debug == DebugView::Level || o.debug == DebugView::Region || o.debug == DebugView::Brick) {
                    im.traversal->traverse(ray, [&](const Segment& seg) {
                      const Region& region = im.model.regions.regions[seg.region];
                      vec3f color;
                      if (o.debug == DebugView::Region) {
                        color = hashColor(seg.region);
                      } else {
                        // The brick whose cells hold the segment's midpoint; where no cell does (the
                        // margin of the supports), the region's finest brick.
                        const vec3f p = ray.org + ray.dir * (0.5f * (seg.t0 + seg.t1));
                        uint32_t brickId = kNoRegion;
                        for (uint32_t k = 0; k < region.brickCount; ++k) {
                          const uint32_t id = im.model.regions.brickIds[region.brickBegin + k];
                          const box3i b = im.model.bricks[id].bounds();
                          if (brickId == kNoRegion || im.model.bricks[id].level < im.model.bricks[brickId].level)
                            brickId = id;
                          if (p.x >= b.lower.x && p.x < b.upper.x && p.y >= b.lower.y && p.y < b.upper.y &&
                              p.z >= b.lower.z && p.z < b.upper.z) {
                            brickId = id;
                            break;
                          }
                        }
                        color = o.debug == DebugView::Level ? levelColor(im.model.bricks[brickId].level)
                                                            : hashColor(brickId);
                      }
                      acc = {color.x, color.y, color.z, 1.f};
                      ++c.regions;
                      return false;
                    });
                    sum.x += acc.x, sum.y += acc.y, sum.z += acc.z, sum.w += acc.w;
                    continue;
                  }

                  im.traversal->traverse(ray, [&](const Segment& seg) {
                    ++c.regions;
                    const Region& region = im.model.regions.regions[seg.region];
                    const float width = o.sampling == Sampling::Adaptive ? region.finestWidth() : im.finestWidth;
                    const float dt = 0.5f * width / o.rate;
                    // Sample positions (k + rho) dt delimit intervals; each interval is sampled at
                    // its midpoint and weighted by its length.
                    float a = seg.t0;
                    float k = std::floor(seg.t0 / dt - rho) + 1.f;
                    while (a < seg.t1) {
                      float b = std::min((k + rho) * dt, seg.t1);
                      if (!(b > a)) b = std::min(a + dt, seg.t1); // guards float round-off
                      if (!(b > a)) break;
                      k += 1.f;
                      const float len = b - a;
                      const float tm = 0.5f * (a + b);
                      a = b;
                      const vec3f p = ray.org + ray.dir * tm;
                      ++raySamples;
                      float value;
                      vec3f grad;
                      const bool wantGrad = o.shading == Shading::Analytic;
                      const bool found =
                          o.reconstruction == Reconstruction::Regions
                              ? sampleRegion(im.view, seg.region, p, value, wantGrad ? &grad : nullptr)
                              : im.locator->sample(im.field, p, value, wantGrad ? &grad : nullptr);
                      if (!found) continue;
                      const vec4f rgba = im.lookup(value);
                      if (rgba.w >= 0.f) continue; // log2 transmittance 0: fully transparent
                      // Opacity correction: 1 - (1 - alpha)^(len / finest width).
                      const float alpha = 1.f - exp2Negative(rgba.w * len * im.invFinestWidth);
                      vec3f color(rgba.x, rgba.y, rgba.z);
                      if (o.shading != Shading::None) {
                        if (o.shading == Shading::Central || o.shading == Shading::ClampedCentral) {
                          const float h = 0.5f * region.finestWidth();
                          const box3f rb = region.bounds();
                          for (int ax = 0; ax < 3; ++ax) {
                            vec3f pp = p, pm = p;
                            pp[ax] += h;
                            pm[ax] -= h;
                            float vp = value, vm = value;
                            if (o.shading == Shading::ClampedCentral) {
                              pp[ax] = std::min(pp[ax], rb.upper[ax]);
                              pm[ax] = std::max(pm[ax], rb.lower[ax]);
                              sampleRegion(im.view, seg.region, pp, vp);
                              sampleRegion(im.view, seg.region, pm, vm);
                            } else {
                              sampleField(im.view, pp, vp);
                              sampleField(im.view, pm, vm);
                            }
                            const float span = pp[ax] - pm[ax];
                            grad[ax] = span > 0.f ? (vp - vm) / span : 0.f;
                          }
                        }
                        const vec3f gw = grad * im.invScale; // per world unit
                        const float gl = length(gw);
                        float shade = o.ambient + o.diffuse;
                        float spec = 0.f;
                        if (gl > 1e-20f) {
                          const vec3f n = gw * (1.f / gl);
                          const float ndl = std::abs(dot(n, light));
                          shade = o.ambient + o.diffuse * ndl;
                          spec = o.specular * specularPower(std::abs(dot(n, halfVector)), o.shininess);
                        }
                        color = color * shade + vec3f(spec);
                      }
                      const float wgt = (1.f - acc.w) * alpha;
                      acc.x += wgt * color.x;
                      acc.y += wgt * color.y;
                      acc.z += wgt * color.z;
                      acc.w += wgt;
                      if (o.earlyTermination && acc.w >= o.terminationOpacity) return false;
                    }
                    return true;
                  });
                  c.samples += raySamples;
                  pixelSteps += raySamples;
                  sum.x += acc.x, sum.y += acc.y, sum.z += acc.z, sum.w += acc.w;
                }
                const float inv = 1.f / float(o.samplesPerPixel);
                image.at(x, y) = {sum.x * inv, sum.y * inv, sum.z * inv, sum.w * inv};
                if (!steps.empty()) steps[size_t(y) * size_t(o.width) + size_t(x)] = float(pixelSteps) * inv;
              }
            progress.advance(1);
          }
      });
  progress.finish();

  if (!steps.empty()) {
    // Steps per ray as a heat map, scaled to the image's maximum.
    float maxSteps = 1.f;
    for (float s : steps) maxSteps = std::max(maxSteps, s);
    const ColorMap heat = builtinColorMap("inferno");
    for (size_t i = 0; i < steps.size(); ++i) {
      const vec3f col = heat.at(steps[i] / maxSteps);
      image.pixels[i] = {col.x, col.y, col.z, 1.f};
    }
  }

  RenderStats st;
  st.seconds = timer.seconds();
  counters.combine_each([&](const Counters& c) {
    st.rays += c.rays;
    st.samples += c.samples;
    st.regionsVisited += c.regions;
  });
  if (statsOut) *statsOut = st;
  return image;
}

} // namespace exa
