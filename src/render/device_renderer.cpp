#include "device_renderer.h"

#include "lighting.h"

#include "exabricks/amr/gradients.h"
#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <cstdlib>
#include <cstring>

namespace exa {

DeviceRenderer::DeviceRenderer(Device device, const Model& model, const DatasetInfo& dataset)
    : device_(device), model_(model), dataset_(dataset) {
  if (device == Device::Cuda) {
    const CudaStatus s = gpu::status();
    if (!s.problem.empty()) fail("the cuda device cannot be used: ", s.problem);
    // The whole model must fit: its structures and one field (values and gradients).
    const DeviceFootprint f = deviceFootprint(model);
    const uint64_t need = f.model.total() + 4 * f.fieldBytes;
    if (need > s.freeBytes)
      fail("the cuda device cannot take the dataset: it needs ", need >> 20, " MiB on the GPU (", model.bricks.size(),
           " bricks, ", model.regions.regions.size(), " regions, ",
           model.fieldValues.empty() ? 0 : model.fieldValues[0].size(), " values per field with their gradients); ",
           s.name, " has ", s.freeBytes >> 20, " MiB free of ", s.totalBytes >> 20, " MiB");
  }
}

DeviceRenderer::~DeviceRenderer() {
  if (device_ != Device::Cuda) return;
  for (auto& [key, b] : buffers_)
    gpu::release(b.device);
  gpu::release(frame_.device);
  gpu::release(counts_.device);
  gpu::releaseHost(pinned_);
}

void DeviceRenderer::reserve(Buffer& b, uint64_t bytes, const std::string& what) {
  if (!b.device || bytes > b.capacity) {
    gpu::release(b.device);
    b.device = nullptr;
    b.device = gpu::allocate(bytes, what.c_str());
    b.capacity = bytes;
  }
  b.bytes = bytes;
}

void DeviceRenderer::checkSupported(const Scene& s) {
  auto refuse = [](const std::string& what) {
    fail("the GPU back end does not render ", what, " yet; render this scene on the CPU (device cpu)");
  };
  if (s.debug != DebugView::None) refuse("debug views");
  if (s.integration.reconstruction == Reconstruction::CellLocation) refuse("reconstruction by cell location");
  if (s.layers.size() > size_t(kTraceMaxLayers)) refuse("more than " + std::to_string(kTraceMaxLayers) + " layers");
  if (s.iso.values.size() > size_t(kTraceMaxIsoValues))
    refuse("more than " + std::to_string(kTraceMaxIsoValues) + " iso-values");
  if (s.iso.colors.size() > size_t(kTraceMaxIsoColors))
    refuse("more than " + std::to_string(kTraceMaxIsoColors) + " iso colours");
  if (s.clip.planes.size() > size_t(kTraceMaxClipPlanes))
    refuse("more than " + std::to_string(kTraceMaxClipPlanes) + " clip planes");
}

const void* DeviceRenderer::put(const std::string& key, const void* host, uint64_t bytes, bool byContent,
                                SceneUpdate& update) {
  if (device_ != Device::Cuda) return host;
  Buffer& b = buffers_[key];
  const bool same =
      b.device && b.bytes == bytes &&
      (byContent ? b.content.size() == bytes && std::memcmp(b.content.data(), host, bytes) == 0 : b.host == host);
  if (same) return b.device;
  reserve(b, bytes, key);
  gpu::copyToDevice(b.device, host, bytes);
  b.host = host;
  if (byContent) b.content.assign(static_cast<const uint8_t*>(host), static_cast<const uint8_t*>(host) + bytes);
  update.deviceBytes += bytes;
  return b.device;
}

FieldView DeviceRenderer::fieldView(int field, const float* values, const std::string& what, SceneUpdate& update) {
  FieldView v = model_.view(field);
  v.bricks = put("bricks", model_.bricks, false, update);
  v.regions = put("regions", model_.regions.regions, false, update);
  v.brickIds = put("region brick lists", model_.regions.brickIds, false, update);
  v.nodes = model_.regions.nodes.empty() ? nullptr : put("region k-d tree", model_.regions.nodes, false, update);
  const uint64_t count = model_.fieldValues[size_t(field)].size();
  if (!values) {
    v.values = nullptr;
    return v;
  }
  v.values = static_cast<const float*>(
      put(what + " " + model_.fieldNames[size_t(field)], values, count * sizeof(float), false, update));
  return v;
}

const vec4f* DeviceRenderer::withGradients(const LayerTable& l, uint64_t version, SceneUpdate& update) {
  const std::string key = "field and gradients " + model_.fieldNames[size_t(l.field)];
  auto fill = [&](std::vector<vec4f>& out) {
    const auto& values = model_.fieldValues[size_t(l.field)];
    out.resize(values.size());
    // Each cell's gradient decoded as the CPU's reconstruction decodes it.
    tbb::parallel_for(size_t(0), model_.bricks.size(), [&](size_t b) {
      const Brick& brick = model_.bricks[b];
      for (size_t i = brick.valueOffset; i < size_t(brick.valueOffset) + brick.cellCount(); ++i) {
        const vec3f g = unpackGradient(l.gradients.cells[2 * i + 1], l.gradients.scaleBias[b]);
        out[i] = vec4f(values[i], g.x, g.y, g.z);
      }
    });
  };
  uint64_t& made = interleavedVersion_[l.field];
  const bool current = made == version;
  made = version;
  if (device_ != Device::Cuda) {
    std::vector<vec4f>& v = interleaved_[l.field];
    if (v.empty() || !current) fill(v);
    return v.data();
  }
  // The values never change, the gradient fields only as bricks' are built: copied again then.
  if (auto it = buffers_.find(key); it != buffers_.end() && current)
    return static_cast<const vec4f*>(it->second.device);
  std::vector<vec4f> interleaved;
  fill(interleaved);
  buffers_[key].host = nullptr; // copied even where the new array lies where the last one did
  return put(key, interleaved, false, update);
}

namespace {

TfTableView tableView(const LayerTable& l, const vec4f* entries) {
  TfTableView t = l.t;
  t.entries = entries;
  return t;
}

} // namespace

void DeviceRenderer::sync(const Scene& s, const VolumeMarcher& volume, const Surfaces& surfaces, SceneUpdate& update) {
  Timer timer;
  TraceView& v = base_;
  v = TraceView();
  v.world = model_.world;
  v.referenceWidth = dataset_.referenceWidth;
  v.invReferenceWidth = 1.f / dataset_.referenceWidth;
  v.invScale = vec3f(1.0 / model_.world.scale.x, 1.0 / model_.world.scale.y, 1.0 / model_.world.scale.z);
  v.meanScale = float((model_.world.scale.x + model_.world.scale.y + model_.world.scale.z) / 3.0);
  if (!model_.regions.regions.empty()) v.regions = put("regions", model_.regions.regions, false, update);
  syncVolume(s, volume, update);
  syncIso(s, surfaces, update);
  syncMeshes(s, update);
  syncParticles(surfaces, update);
  v.clipping = !s.clip.planes.empty() || !s.clip.box.empty();
  v.planeCount = int(s.clip.planes.size());
  for (size_t i = 0; i < s.clip.planes.size(); ++i)
    v.planes[i] = s.clip.planes[i];
  v.clipBox = s.clip.box;
  v.ray = raySettingsOf(s, dataset_, model_.world);
  update.deviceSeconds += timer.seconds();
}

void DeviceRenderer::syncVolume(const Scene& s, const VolumeMarcher& volume, SceneUpdate& update) {
  TraceView& v = base_;
  const std::vector<LayerTable>& layers = volume.layers();
  v.volume = s.volume && !layers.empty();
  v.pathTrace = s.integration.integrator == Integrator::PathTrace; // lit by its paths: no gradients
  v.layerCount = int(layers.size());
  for (size_t i = 0; i < layers.size(); ++i) {
    const LayerTable& l = layers[i];
    TraceLayer& t = v.layers[i];
    // Smooth shading reads the values with the gradients (TraceLayer::withGradients).
    const bool smooth = s.shading == Shading::Smooth && l.gradients.cells && !v.pathTrace;
    t.view = fieldView(l.field, smooth ? nullptr : l.view.values, "field", update);
    if (smooth) t.withGradients = withGradients(l, volume.gradientVersion(l.field), update);
    for (int a = 0; a < 3; ++a)
      t.grad[a] = t.view;
    t.tf = tableView(l, put("transfer function " + std::to_string(i), l.table, true, update));
    t.byValue = l.fadeByValue();
    t.invSpan = l.invSpan;
  }
  if (!model_.regions.nodes.empty()) {
    volumeSubtrees_ = visibleSubtrees(model_.regions.nodes, volume.visible());
    v.volumeTree.nodes = put("region k-d tree", model_.regions.nodes, false, update);
    v.volumeTree.visible = put("visible regions", volume.visible(), true, update);
    v.volumeTree.subtreeVisible = put("visible subtrees", volumeSubtrees_, true, update);
    v.volumeTree.bounds = model_.regions.bounds;
  }
  v.strides = layers.empty() ? nullptr : put("region strides", volume.strides(), true, update);
  if (v.pathTrace) {
    for (size_t i = 0; i < layers.size(); ++i) {
      const std::vector<float>& albedo = layers[i].albedo;
      v.mediumLayers[i] = {v.layers[i].view, v.layers[i].tf,
                           albedo.empty() ? nullptr : put("albedo " + std::to_string(i), albedo, true, update)};
    }
    v.majorants = put("majorants", volume.majorants(), true, update);
    v.majorantGrid = volume.majorantGrid().view();
    if (v.majorantGrid.majorant) {
      v.majorantGrid.majorant = put("majorant grid", volume.majorantGrid().majorants(), true, update);
      v.majorantGrid.gridded = put("gridded regions", volume.majorantGrid().gridded(), true, update);
    }
    v.extinctionPerLog2 = volume.extinctionPerLog2();
    v.path = pathSettingsOf(s.pathTracing, dataset_.worldDiagonal);
  }
  v.sample = volumeSettingsOf(s, v.sample.rate); // the rate is the frame's (sync)
}

void DeviceRenderer::syncIso(const Scene& s, const Surfaces& surfaces, SceneUpdate& update) {
  TraceView& v = base_;
  const std::vector<float>& isoValues = surfaces.isoValues();
  v.iso = surfaces.isoTraversal() != nullptr && !isoValues.empty() && !model_.regions.nodes.empty();
  if (v.iso) {
    const FieldView& iv = surfaces.isoView();
    int isoField = 0;
    for (size_t f = 0; f < model_.fieldValues.size(); ++f)
      if (model_.fieldValues[f].data() == iv.values) isoField = int(f);
    v.isoView = fieldView(isoField, iv.values, "field", update);
    v.isoCount = int(isoValues.size());
    for (size_t i = 0; i < isoValues.size(); ++i)
      v.isoValues[i] = isoValues[i];
    isoSubtrees_ = visibleSubtrees(model_.regions.nodes, surfaces.isoVisible());
    v.isoTree.nodes = put("region k-d tree", model_.regions.nodes, false, update);
    v.isoTree.visible = put("iso regions", surfaces.isoVisible(), true, update);
    v.isoTree.subtreeVisible = put("iso subtrees", isoSubtrees_, true, update);
    v.isoTree.bounds = model_.regions.bounds;
    if (const LayerTable* c = surfaces.isoColorTable()) {
      v.isoColored = true;
      v.isoColorView = fieldView(c->field, c->view.values, "field", update);
      v.isoColorTf = tableView(*c, put("iso colour map", c->table, true, update));
    }
    v.isoColorCount = int(s.iso.colors.size());
    for (size_t i = 0; i < s.iso.colors.size(); ++i)
      v.isoColors[i] = s.iso.colors[i];
  }
}

void DeviceRenderer::syncMeshes(const Scene& s, SceneUpdate& update) {
  TraceView& v = base_;
  // Meshes: the hierarchy built again where the meshes or their colours changed.
  std::vector<std::pair<const TriangleMesh*, vec3f>> meshKey;
  for (const SceneMesh& m : s.meshes)
    meshKey.emplace_back(m.mesh.get(), m.color);
  if (meshKey != meshKey_) {
    std::vector<const TriangleMesh*> list;
    meshColors_.clear();
    for (const SceneMesh& m : s.meshes)
      list.push_back(m.mesh.get()), meshColors_.push_back(m.color);
    meshBvh_.build(list);
    meshKey_ = meshKey;
    for (const char* key : {"mesh hierarchy", "mesh triangles", "mesh colours"})
      if (auto it = buffers_.find(key); it != buffers_.end()) {
        if (device_ == Device::Cuda) gpu::release(it->second.device);
        buffers_.erase(it);
      }
  }
  v.meshes = !meshBvh_.empty();
  if (v.meshes) {
    v.meshBvh.nodes = put("mesh hierarchy", meshBvh_.nodes(), false, update);
    v.meshBvh.triangles = put("mesh triangles", meshBvh_.triangles(), false, update);
    v.meshColors = put("mesh colours", meshColors_, false, update);
  }
}

void DeviceRenderer::syncParticles(const Surfaces& surfaces, SceneUpdate& update) {
  TraceView& v = base_;
  // The CPU renderer's hierarchy and colours, copied again where they were built again.
  if (update.particles)
    for (const char* key : {"particle hierarchy", "particle spheres", "particle colours"})
      if (auto it = buffers_.find(key); it != buffers_.end()) {
        if (device_ == Device::Cuda) gpu::release(it->second.device);
        buffers_.erase(it);
      }
  const SphereBvh& spheres = surfaces.spheres();
  v.particles = !spheres.empty();
  if (v.particles) {
    v.particleBvh.nodes = put("particle hierarchy", spheres.nodes(), false, update);
    v.particleBvh.spheres = put("particle spheres", spheres.spheres(), false, update);
    v.particleColors = put("particle colours", surfaces.sphereColors(), false, update);
  }
}

const vec4f* DeviceRenderer::pass(const Frame& frame, const box3d* domain, int tilesX, int tileBegin, int tileEnd,
                                  int tileStride, gpu::PassCounts& counts) {
  TraceView v = base_;
  v.frame = cameraRaysOf(frame);
  v.frame.depthLimit = nullptr; // placed below, where the pass runs
  v.frame.hasDomain = domain != nullptr;
  if (domain) v.frame.domain = *domain;
  v.frameIndex = frame.frameIndex;
  v.seed = frame.seed;
  v.sample.rate = frame.rate;
  v.path.up = skyUp(frame.camera.up);
  const size_t pixels = size_t(frame.width) * size_t(frame.height);
  counts = gpu::PassCounts();
  if (device_ == Device::Cuda) {
    const uint64_t bytes = pixels * sizeof(vec4f);
    reserve(frame_, bytes, "the frame");
    reserve(counts_, sizeof(gpu::PassCounts), "the pass's counters");
    if (frame.depthLimit) {
      // Copied every pass: the caller may change the limit in place.
      Buffer& b = buffers_["depth limit"];
      reserve(b, pixels * sizeof(float), "the depth limit");
      gpu::copyToDevice(b.device, frame.depthLimit, b.bytes);
      v.frame.depthLimit = static_cast<const float*>(b.device);
    }
    if (frame.frontOpacity) {
      Buffer& b = buffers_["front opacity"];
      reserve(b, pixels * sizeof(float), "the front opacity");
      gpu::copyToDevice(b.device, frame.frontOpacity, b.bytes);
      v.frame.frontOpacity = static_cast<const float*>(b.device);
    }
    if (bytes > pinnedBytes_) {
      gpu::releaseHost(pinned_);
      pinned_ = nullptr;
      pinned_ = static_cast<vec4f*>(gpu::allocateHost(bytes));
      pinnedBytes_ = bytes;
    }
    gpu::tracePass(v, tilesX, tileBegin, tileEnd, tileStride, frame_.device, counts_.device, pinned_, counts);
    return pinned_;
  }
  std::vector<vec4f>& colors = hostColors_;
  colors.resize(pixels);
  v.frame.depthLimit = frame.depthLimit;
  v.frame.frontOpacity = frame.frontOpacity;
  std::atomic<uint64_t> rays{0}, samples{0}, iso{0}, ao{0}, hits{0};
  tbb::parallel_for(0, frame.height, [&](int y) {
    RayCounts c;
    uint64_t r = 0;
    for (int x = 0; x < frame.width; ++x) {
      if (!tileSelected(x, y, tilesX, tileBegin, tileEnd, tileStride)) continue;
      const bool surfaces = v.iso || v.meshes || v.particles;
      colors[size_t(y) * size_t(frame.width) + size_t(x)] =
          v.pathTrace ? (surfaces ? tracePathSample<true>(v, x, y, c) : tracePathSample<false>(v, x, y, c))
                      : (surfaces ? traceSample<true>(v, x, y, c) : traceSample<false>(v, x, y, c));
      ++r;
    }
    rays += r;
    samples += c.samples;
    iso += c.isoSamples;
    ao += c.aoRays;
    hits += c.surfaceHits;
  });
  counts.rays = rays, counts.samples = samples, counts.isoSamples = iso, counts.aoRays = ao, counts.surfaceHits = hits;
  return colors.data();
}

DeviceMemory DeviceRenderer::memory() const {
  DeviceMemory m;
  for (const auto& [key, b] : buffers_)
    m.structures.emplace_back(key, b.capacity);
  if (frame_.capacity) m.structures.emplace_back("frame", frame_.capacity);
  return m;
}

std::string deviceInfoJson(const Model& model) {
  const CudaStatus s = cudaStatus();
  nlohmann::json j;
  j["cuda_built"] = s.built;
  j["gpus"] = s.devices;
  if (s.devices > 0) {
    j["name"] = s.name;
    j["memory_total_bytes"] = s.totalBytes;
    j["memory_free_bytes"] = s.freeBytes;
  }
  if (!s.problem.empty()) j["problem"] = s.problem;
  j["auto"] = s.problem.empty() ? "cuda" : "cpu";
  const DeviceFootprint f = deviceFootprint(model);
  nlohmann::json need = nlohmann::json::object();
  for (const auto& [name, bytes] : f.model.structures)
    need[name] = bytes;
  need["field values"] = f.fieldBytes;
  need["field with smooth-shading gradients"] = 4 * f.fieldBytes;
  j["memory_needed_bytes"] = need;
  return j.dump();
}

DeviceFootprint deviceFootprint(const Model& model) {
  DeviceFootprint f;
  f.model.structures = {{"bricks", model.bricks.size() * sizeof(Brick)},
                        {"regions", model.regions.regions.size() * sizeof(Region)},
                        {"region brick lists", model.regions.brickIds.size() * sizeof(uint32_t)},
                        {"region k-d tree", model.regions.nodes.size() * sizeof(RegionKdNode)}};
  f.fieldBytes = model.fieldValues.empty() ? 0 : model.fieldValues[0].size() * sizeof(float);
  return f;
}

int cudaDeviceOfProcess(int devices) {
  if (devices <= 1) return 0;
  auto number = [](const char* name) -> long {
    const char* v = std::getenv(name);
    if (!v || !*v) return -1;
    char* end = nullptr;
    const long n = std::strtol(v, &end, 10);
    return end && *end == '\0' && n >= 0 ? n : -1;
  };
  if (const long d = number("EXABRICKS_CUDA_DEVICE"); d >= 0) return int(d % devices);
  for (const char* name : {"OMPI_COMM_WORLD_LOCAL_RANK", "MPI_LOCALRANKID", "PMI_LOCAL_RANK", "SLURM_LOCALID"})
    if (const long k = number(name); k >= 0) return int(k % devices);
  return 0;
}

} // namespace exa
