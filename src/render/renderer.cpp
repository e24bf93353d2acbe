// The pass and tile loop, and what changes with a scene: one ray per pixel and pass through the
// units along it (dual_ray: clipping and domain; surfaces: iso-surfaces and meshes;
// volume_marcher: the volume; lighting: ambient occlusion; debug_views), summed into the
// caller's FrameBuffer.
#include "exabricks/render/renderer.h"
#include "exabricks/render/scene_vocabulary.h"

#include "debug_views.h"
#include "device_renderer.h"
#include "dual_ray.h"
#include "lighting.h"
#include "particle_spheres.h"
#include "path_trace.h"
#include "surfaces.h"
#include "volume_marcher.h"

#include "exabricks/amr/model.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"
#include "exabricks/core/random.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

namespace exa {
namespace {

using Counters = FrameBuffer::TileCounters;

/// What every ray of a pass shares.
struct PassSetup {
  CameraRays camera;
  RaySettings ray;
  bool surfaces, clipping;
  MarchSettings march;
  PathSettings path;
};

/// The CPU's side of the ray program (ray_program.h): Embree's mesh hierarchy, the iso region
/// set's traversal and the batched volume march.
struct CpuRays {
  const Surfaces& surfaces;
  const VolumeMarcher& volume;
  const MarchSettings& settings;
  SurfaceColors colors;
  const WorldTransform& world;

  bool hasMeshes() const { return surfaces.hasMeshes(); }
  bool meshHit(const DualRay& r, double s0, double s1, SurfaceHit& hit) const {
    return surfaces.meshHit(r, s0, s1, hit);
  }
  bool meshOccludes(const DualRay& r, double s0, double s1) const { return surfaces.meshOccludes(r, s0, s1); }
  bool hasIso() const { return surfaces.isoTraversal() != nullptr; }
  bool isoHit(const Ray& ray, float& t, uint32_t& region, int& which, RayCounts& c) const {
    uint64_t n = 0;
    const bool found = surfaces.findIso(ray, settings.sample.sampling, settings.sample.rate, t, region, which, n);
    c.isoSamples += uint32_t(n);
    return found;
  }
  const FieldView& isoView() const { return surfaces.isoView(); }
  const vec3f& invScale() const { return surfaces.invScale(); }
  vec3f surfaceColor(const SurfaceHit& hit) const { return surfaceColorOf(colors, world, hit); }
  template <bool OpacityOnly>
  void march(const Ray& ray, float rho, const RayLight& light, vec4f& acc, RayCounts& c) const {
    uint64_t samples = 0, regions = 0;
    volume.march<OpacityOnly>(ray, rho, light, settings, acc, samples, regions);
    c.samples += uint32_t(samples);
    c.regions += uint32_t(regions);
  }
};

/// A ray's counts added to its tile's.
void addCounts(Counters& c, const RayCounts& r) {
  ++c.rays;
  c.samples += r.samples;
  c.regions += r.regions;
  c.surfaceHits += r.surfaceHits;
  c.isoSamples += r.isoSamples;
  c.aoRays += r.aoRays;
}

} // namespace

struct Renderer::Impl {
  const Model& model;
  DatasetInfo dataset;
  Scene scene;
  bool haveScene = false;
  RendererOptions options;
  VolumeMarcher volume;
  Surfaces surfaces;
  bool hasDomain = false; ///< primary rays see only the inside of `domain` (world)
  box3d domain;
  std::unique_ptr<DeviceRenderer> device; ///< set where passes run on a device back end
  /// The path tracer's medium: the volume's layers (their majorants are the volume's).
  std::vector<MediumLayer> mediumLayers;
  std::shared_ptr<const ParticleSet> particles;
  bool particlesChanged = false; ///< setParticles since the last setScene

  Impl(const Model& m, const DatasetInfo& d)
      : model(m), dataset(d.checkedFor(m)), volume(m, dataset), surfaces(m, dataset) {}

  /// Smooth shading's gradient fields where primary rays may sample; true when some were built.
  bool attachGradients() {
    return scene.shading == Shading::Smooth && scene.integration.integrator == Integrator::March &&
           volume.attachGradients(hasDomain ? &domain : nullptr);
  }

  PassSetup passSetup(const Frame& frame) const {
    const Scene& s = scene;
    PassSetup ps;
    ps.camera = cameraRaysOf(frame);
    ps.camera.jitter = frame.jitter && s.debug == DebugView::None;
    ps.camera.pixelJitter = frame.samplesPerPixel > 1 && ps.camera.jitter;
    ps.camera.hasDomain = hasDomain;
    ps.camera.domain = domain;
    ps.ray = raySettingsOf(s, dataset, model.world);
    ps.surfaces = surfaces.any() && s.debug == DebugView::None;
    ps.clipping = !s.clip.planes.empty() || !s.clip.box.empty();
    ps.march = MarchSettings::of(s, options, frame.rate);
    ps.path = pathSettingsOf(s.pathTracing, dataset.worldDiagonal);
    ps.path.up = skyUp(frame.camera.up);
    return ps;
  }

  CpuRays rays(const MarchSettings& march) const {
    return {surfaces, volume, march, surfaces.colors(scene.iso.colors), model.world};
  }

  /// The path tracer's medium for the volume's current layers, with their majorants.
  void updateMedium() {
    mediumLayers.clear();
    for (const LayerTable& layer : volume.layers())
      mediumLayers.push_back({layer.view, layer.t, layer.albedo.empty() ? nullptr : layer.albedo.data()});
    volume.updateMajorants(options.majorantGrid);
  }

  MediumView medium() const {
    return {mediumLayers.data(),          int(mediumLayers.size()),   volume.majorants().data(),
            volume.majorantGrid().view(), volume.extinctionPerLog2(), scene.pathTracing.albedo};
  }

  /// One path-traced sample of pixel (x, y): premultiplied radiance and whether the path met the
  /// medium.
  vec4f tracePathPixel(int x, int y, const Frame& frame, const PassSetup& ps, RayCounts& c) const {
    PixelRandom rng(x, y, frame.frameIndex, frame.seed);
    float rho;
    const ClipView clip = clipViewOf(scene.clip);
    const DualRay dr = cameraRay(ps.camera, model.world, &clip, x, y, rng, rho);
    const bool inMedium = scene.volume && !mediumLayers.empty();
    if (!inMedium && !ps.surfaces) return vec4f();
    const RegionTraversal* traversal = volume.traversal();
    auto traverse = [&](const Ray& ray, auto&& emit) {
      if (inMedium) traversal->traverse(ray, emit);
    };
    const CpuRays b = rays(ps.march);
    auto nearest = [&](const DualRay& r, PathSurface& out) {
      SurfaceHit hit;
      if (!ps.surfaces || !nearestSurface(b, r, scene.clip.meshes, hit, c)) return false;
      out.distance = hit.distance;
      out.normal = vec3d(hit.normal);
      out.color = b.surfaceColor(hit);
      return true;
    };
    uint64_t samples = 0;
    const vec4f out = tracePath(medium(), traverse, nearest, model.world, &clip, dr, ps.path, rng, samples);
    c.samples += uint32_t(samples);
    c.marchSamples = c.samples;
    return out;
  }

  /// One ray-marched sample of pixel (x, y) for pass frame.frameIndex (marchSample), or a debug
  /// view's colour: premultiplied.
  vec4f tracePixel(int x, int y, const Frame& frame, const PassSetup& ps, Counters& tile, RayCounts& c) const {
    PixelRandom rng(x, y, frame.frameIndex, frame.seed);
    float rho;
    const ClipView clip = clipViewOf(scene.clip);
    const bool clipped = ps.clipping && scene.debug == DebugView::None;
    const DualRay dr = cameraRay(ps.camera, model.world, clipped ? &clip : nullptr, x, y, rng, rho);
    if (scene.debug == DebugView::Level || scene.debug == DebugView::Region || scene.debug == DebugView::Brick)
      return debugColor(model, *volume.traversal(), scene.debug, dr.lattice, tile);
    const CpuRays b = rays(ps.march);
    const float front = frontOpacityOf(ps.camera, x, y);
    return ps.surfaces ? marchSample<true>(b, ps.ray, model.world, &clip, dr, rho, rng, c, front)
                       : marchSample<false>(b, ps.ray, model.world, &clip, dr, rho, rng, c, front);
  }

  /// The one pass loop of every back end, over the tiles the control selects: each tile in
  /// parallel (none once cancelled) has its counters reset, `traceTile(tile, counters)` add its
  /// pixels to the buffer, and its pass counted, with progress per tile. The pass's statistics
  /// are its tiles' counters summed, plus `whole` (what a back end counts for the pass as a
  /// whole). False when cancelled.
  template <typename TraceTile>
  static bool runPass(FrameBuffer& buffer, const PassControl& control, const RenderStats& whole,
                      TraceTile&& traceTile) {
    std::vector<int>& tiles = buffer.passTiles_;
    control.selected(buffer.tileCount(), tiles);
    const int passTiles = int(tiles.size());
    std::atomic<bool> cancelled{false};
    std::atomic<uint64_t> done{0};
    Timer timer;
    tbb::parallel_for(0, passTiles, [&](int i) {
      const int tile = tiles[size_t(i)];
      Counters& c = buffer.counters_[size_t(tile)];
      c = Counters();
      if (control.cancel && control.cancel->load(std::memory_order_relaxed)) {
        cancelled.store(true, std::memory_order_relaxed);
        return;
      }
      traceTile(tile, c);
      ++buffer.tilePasses_[size_t(tile)];
      const uint64_t n = done.fetch_add(1, std::memory_order_relaxed) + 1;
      if (control.progress) control.progress(n, uint64_t(passTiles));
    });
    RenderStats st = whole;
    st.seconds += timer.seconds();
    for (int i = 0; i < passTiles; ++i) {
      const Counters& c = buffer.counters_[size_t(tiles[size_t(i)])];
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

  /// A pass on CPU threads: the ray program per pixel (ray-marched or path-traced, or a debug view).
  bool cpuPass(const Frame& frame, FrameBuffer& buffer, const PassControl& control) const {
    const PassSetup ps = passSetup(frame);
    const bool steps = scene.debug == DebugView::Steps;
    const bool pathTraced = scene.integration.integrator == Integrator::PathTrace && scene.debug == DebugView::None;
    buffer.stepsView_ = steps;
    return runPass(buffer, control, RenderStats(), [&](int tile, Counters& c) {
      buffer.forTilePixelsNear(tile, [&](int x, int y, size_t p) {
        RayCounts rc;
        const vec4f acc = pathTraced ? tracePathPixel(x, y, frame, ps, rc) : tracePixel(x, y, frame, ps, c, rc);
        addCounts(c, rc);
        buffer.add(p, acc);
        if (steps) buffer.steps_[p] += float(rc.marchSamples);
      });
    });
  }

  /// A pass on the device back end: launched for the whole pass, its colours then added per tile.
  bool devicePass(const Frame& frame, FrameBuffer& buffer, int begin, int end, int stride,
                  const PassControl& control) const {
    if (control.cancel && control.cancel->load(std::memory_order_relaxed)) return false;
    Timer timer;
    buffer.stepsView_ = false;
    gpu::PassCounts counts;
    const vec4f* colors =
        device->pass(frame, hasDomain ? &domain : nullptr, buffer.tilesX_, begin, end, stride, counts);
    RenderStats whole;
    whole.seconds = timer.seconds();
    whole.rays = counts.rays;
    whole.samples = counts.samples;
    whole.surfaceHits = counts.surfaceHits;
    whole.isoSamples = counts.isoSamples;
    whole.aoRays = counts.aoRays;
    whole.deviceSeconds = counts.kernelSeconds;
    return runPass(buffer, control, whole, [&](int tile, Counters&) {
      buffer.forTilePixels(tile, [&](int, int, size_t p) { buffer.add(p, colors[p]); });
    });
  }
};

Renderer::Renderer(const Model& model) : Renderer(model, DatasetInfo::of(model)) {}

Renderer::Renderer(const Model& model, const DatasetInfo& dataset) : impl_(std::make_unique<Impl>(model, dataset)) {}

Renderer::~Renderer() = default;

const char* deviceName(Device device) {
  switch (device) {
  case Device::Cuda:
    return "cuda";
  case Device::Portable:
    return "portable";
  default:
    return "cpu";
  }
}

CudaStatus cudaStatus() { return gpu::status(); }

Device resolveDevice(const std::string& name) {
  if (name == "cpu") return Device::Cpu;
  if (name == "portable") return Device::Portable;
  if (name == "cuda" || name == "auto") {
    const CudaStatus s = gpu::status();
    if (s.problem.empty()) return Device::Cuda;
    if (name == "auto") {
      // A build with the GPU back end that cannot use it says so once per process, where the
      // user asked to hear what was chosen (-v): nothing asked for a GPU.
      static std::once_flag said;
      if (s.built)
        std::call_once(said, [&] { logInfo(strCat("device auto: rendering on the CPU, since ", s.problem)); });
      return Device::Cpu;
    }
    fail("the cuda device cannot be used: ", s.problem);
  }
  std::string choices;
  for (const std::string& c : deviceChoices())
    choices += (choices.empty() ? "" : ", ") + c;
  fail("device is '", name, "' (choose from: ", choices, ")");
}

Device selectDevice(Renderer& renderer, const std::string& choice) {
  const Device device = resolveDevice(choice);
  if (choice != "auto" || device == Device::Cpu) {
    renderer.setDevice(device);
    return renderer.device();
  }
  try {
    renderer.setDevice(device);
  } catch (const Error& e) {
    logNote(strCat("device auto: rendering on the CPU, since ", e.what()));
    renderer.setDevice(Device::Cpu);
  }
  return renderer.device();
}

void Renderer::setDevice(Device device) {
  Impl& im = *impl_;
  if (device == this->device()) return;
  if (device == Device::Cpu) {
    im.device.reset();
    return;
  }
  if (im.haveScene) DeviceRenderer::checkSupported(im.scene);
  auto d = std::make_unique<DeviceRenderer>(device, im.model, im.dataset);
  if (im.haveScene) {
    SceneUpdate u;
    d->sync(im.scene, im.volume, im.surfaces, u);
  }
  im.device = std::move(d);
}

Device Renderer::device() const { return impl_->device ? impl_->device->device() : Device::Cpu; }

DeviceMemory Renderer::deviceMemory() const { return impl_->device ? impl_->device->memory() : DeviceMemory(); }

const Scene& Renderer::scene() const { return impl_->scene; }
void Renderer::setOptions(const RendererOptions& options) {
  Impl& im = *impl_;
  const bool majorants = options.majorantGrid != im.options.majorantGrid;
  im.options = options;
  if (!majorants || !im.haveScene || im.scene.integration.integrator != Integrator::PathTrace) return;
  im.updateMedium();
  SceneUpdate u{.volume = true};
  if (im.device) im.device->sync(im.scene, im.volume, im.surfaces, u);
}
const RendererOptions& Renderer::options() const { return impl_->options; }
const DatasetInfo& Renderer::dataset() const { return impl_->dataset; }
const Model& Renderer::model() const { return impl_->model; }

TraversalKind Renderer::traversalInUse() const {
  const RegionTraversal* t = impl_->volume.traversal();
  return t ? t->kind() : impl_->scene.integration.traversal;
}

size_t Renderer::visibleRegions() const {
  const RegionTraversal* t = impl_->volume.traversal();
  return t ? t->visibleCount() : 0;
}

namespace {

/// Lattice box of the cells inside `within` whose value some layer draws with at least a tenth of
/// that layer's largest opacity: where the volume shows, tighter than the regions that may show
/// it (a faint haze around a structure fills whole regions).
box3f opaqueCellBounds(const Model& model, const std::vector<LayerTable>& layers, const box3f& within) {
  constexpr float kShare = 0.1f;
  std::vector<float> threshold;
  for (const LayerTable& layer : layers) {
    float peak = 0.f;
    for (const vec4f& entry : layer.table)
      peak = std::max(peak, 1.f - std::exp2(entry.w));
    threshold.push_back(kShare * peak);
  }
  auto boxOf = [&](const tbb::blocked_range<size_t>& r, box3f box) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const Brick& b = model.bricks[i];
      const box3i bb = b.bounds();
      if (bb.upper.x <= within.lower.x || bb.upper.y <= within.lower.y || bb.upper.z <= within.lower.z ||
          bb.lower.x >= within.upper.x || bb.lower.y >= within.upper.y || bb.lower.z >= within.upper.z)
        continue;
      const int w = b.cellWidth();
      uint32_t slot = b.valueOffset;
      for (int z = 0; z < b.size.z; ++z)
        for (int y = 0; y < b.size.y; ++y)
          for (int x = 0; x < b.size.x; ++x, ++slot)
            for (size_t l = 0; l < layers.size(); ++l)
              if (1.f - std::exp2(layers[l].lookup(layers[l].view.values[slot]).w) >= threshold[l]) {
                const vec3f lo(b.lower + vec3i(x, y, z) * w);
                box.extend(box3f(lo, lo + vec3f(float(w))));
                break;
              }
    }
    return box;
  };
  auto join = [](box3f a, const box3f& b) {
    a.extend(b);
    return a;
  };
  box3f cells = tbb::parallel_reduce(tbb::blocked_range<size_t>(0, model.bricks.size(), 64), box3f(), boxOf, join);
  cells.lower = max(cells.lower, within.lower);
  cells.upper = min(cells.upper, within.upper);
  return cells;
}

} // namespace

const GradientFields* Renderer::gradients(int field) const { return impl_->volume.gradients(field); }

void Renderer::adoptGradients(int field, GradientFields gradients) {
  impl_->volume.adoptGradients(field, std::move(gradients));
}

VisibleExtent Renderer::visibleExtent() const {
  const Impl& im = *impl_;
  VisibleExtent e;
  const std::vector<uint8_t>& visible = im.volume.visible();
  if (im.scene.volume)
    for (size_t i = 0; i < visible.size(); ++i)
      if (visible[i]) e.volume.extend(im.model.regions.regions[i].bounds());
  if (!e.volume.empty() && im.scene.debug == DebugView::None)
    e.opaque = opaqueCellBounds(im.model, im.volume.layers(), e.volume);
  const std::vector<uint8_t>& isoVisible = im.surfaces.isoVisible();
  for (size_t i = 0; i < isoVisible.size(); ++i)
    if (isoVisible[i]) e.iso.extend(im.model.regions.regions[i].bounds());
  return e;
}

box3d Renderer::visibleBounds() const {
  const box3f framed = visibleExtent().framed();
  if (framed.empty()) return box3d();
  return impl_->model.world.toWorld(framed);
}

void VisibleExtent::extend(const VisibleExtent& other) {
  volume.extend(other.volume);
  opaque.extend(other.opaque);
  iso.extend(other.iso);
}

VisibleExtent VisibleExtent::within(const box3l& part) const {
  const box3f p(vec3f(part.lower), vec3f(part.upper));
  auto clip = [&](const box3f& b) {
    const box3f c(max(b.lower, p.lower), min(b.upper, p.upper));
    return c.lower.x <= c.upper.x && c.lower.y <= c.upper.y && c.lower.z <= c.upper.z ? c : box3f();
  };
  return VisibleExtent{clip(volume), clip(opaque), clip(iso)};
}

box3f VisibleExtent::framed() const {
  box3f box = volume;
  if (!box.empty() && !opaque.empty()) {
    const vec3f margin = (opaque.upper - opaque.lower) * 0.05f;
    box = box3f(max(opaque.lower - margin, volume.lower), min(opaque.upper + margin, volume.upper));
  }
  box.extend(iso);
  return box;
}

size_t Renderer::isoRegions() const {
  const RegionTraversal* t = impl_->surfaces.isoTraversal();
  return t ? t->visibleCount() : 0;
}

size_t Renderer::meshCount() const { return impl_->surfaces.meshCount(); }

void Renderer::setParticles(std::shared_ptr<const ParticleSet> particles) {
  impl_->particles = std::move(particles);
  impl_->particlesChanged = true;
}

size_t Renderer::particleCount() const { return impl_->surfaces.spheres().size(); }

SceneUpdate Renderer::setScene(const Scene& s) {
  Impl& im = *impl_;
  s.validate();
  if (im.hasDomain && s.integration.integrator == Integrator::PathTrace)
    fail("path tracing does not yet render data split over processes (its scattered light would need the other "
         "parts): render the whole data in one process, or ray-march it");
  if (im.device) DeviceRenderer::checkSupported(s);
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
  // The particles' spheres first: an unknown species or attribute leaves the scene as it is.
  std::optional<ParticleSpheres> spheres;
  if (first || s.particles != cur.particles || im.particlesChanged)
    spheres = im.particles ? particleSpheres(*im.particles, s.particles, float(im.dataset.worldDiagonal / 800.0))
                           : ParticleSpheres();
  SceneUpdate u;
  u.volume = first || s.layers != cur.layers || s.integration != cur.integration || s.debug != cur.debug;
  const bool strides = u.volume || s.shading != cur.shading;
  u.iso = first || s.iso != cur.iso ||
          s.integration.embreeBelowVisibleFraction != cur.integration.embreeBelowVisibleFraction;
  u.meshes = first || s.meshes != cur.meshes;
  u.particles = spheres.has_value();
  im.particlesChanged = false;
  im.scene = s;
  im.haveScene = true;
  if (u.volume) {
    Timer t;
    im.volume.update(s.layers, fields, s.integration, s.integration.spaceSkipping && s.debug == DebugView::None);
    if (s.integration.integrator == Integrator::PathTrace) im.updateMedium();
    u.volumeSeconds = t.seconds();
  }
  if (strides) im.volume.updateStrides(s.integration.uniformStride, s.shading != Shading::None);
  if (Timer t; im.attachGradients()) u.volumeSeconds += t.seconds();
  if (u.iso) {
    Timer t;
    im.surfaces.updateIso(s.iso, isoField, isoColorField, s.integration.embreeBelowVisibleFraction);
    u.isoSeconds = t.seconds();
  }
  if (u.meshes || u.particles) {
    Timer t;
    if (u.meshes) im.surfaces.updateMeshes(s.meshes);
    if (u.particles) im.surfaces.updateParticles(std::move(*spheres));
    u.meshSeconds = t.seconds();
  }
  if (im.device) im.device->sync(s, im.volume, im.surfaces, u);
  return u;
}

void Renderer::setDomain(const box3d& world) {
  Impl& im = *impl_;
  im.hasDomain = !(world == box3d());
  im.domain = world;
  // Gradient fields are built only where the domain may be sampled: a scene's reach widens.
  SceneUpdate u;
  if (im.haveScene && im.attachGradients() && im.device) im.device->sync(im.scene, im.volume, im.surfaces, u);
}

const box3d& Renderer::domain() const { return impl_->domain; }

bool Renderer::pick(const vec3d& origin, const vec3d& direction, SurfaceHit& hit) const {
  const Impl& im = *impl_;
  if (!(length(direction) > 0.0) || !im.haveScene) return false;
  const DualRay r = makeDualRay(im.model.world, origin, direction, &im.scene.clip);
  const MarchSettings march = MarchSettings::of(im.scene, im.options, 1.f);
  RayCounts counts;
  return nearestSurface(im.rays(march), r, im.scene.clip.meshes, hit, counts);
}

bool Renderer::renderPass(const Frame& frame, FrameBuffer& buffer, const PassControl& control) const {
  const Impl& im = *impl_;
  if (!im.haveScene) fail("no scene set");
  frame.validate();
  if (buffer.width() != frame.width || buffer.height() != frame.height)
    fail("frame buffer is ", buffer.width(), "x", buffer.height(), ", the frame ", frame.width, "x", frame.height);
  const int tileCount = buffer.tileCount();
  const int end = control.tileEnd < 0 ? tileCount : std::min(control.tileEnd, tileCount);
  const int stride = std::max(1, control.tileStride);
  const int begin = std::max(0, control.tileBegin);
  return im.device ? im.devicePass(frame, buffer, begin, end, stride, control) : im.cpuPass(frame, buffer, control);
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
  renderSampled(frame, buffer);
  if (stats) *stats = buffer.stats();
  return buffer.resolve();
}

} // namespace exa
