// Scenes that the device back ends must draw like the CPU renderer, and the bound they are held
// to: every feature of the per-ray path (shading modes, layers, iso-surfaces coloured by a field,
// clipping, the domain, ambient occlusion, early termination, world transforms), on generated
// multi-level data.
#pragma once

#include "exabricks/amr/model.h"
#include "exabricks/amr/scenes.h"
#include "exabricks/core/image.h"
#include "exabricks/core/mesh.h"
#include "exabricks/render/renderer.h"
#include "exabricks/render/transfer_function.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace exa::device_test {

/// How far two images are apart: the mean and the 99.9th percentile of the absolute channel
/// differences (colour and alpha), and the largest.
struct ImageDifference {
  double mean = 0, p999 = 0, max = 0;
  double coverage = 0; ///< mean alpha of the second image (what there was to compare)
};

inline ImageDifference difference(const Image& a, const Image& b) {
  std::vector<float> d;
  d.reserve(a.pixels.size() * 4);
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const vec4f e = a.pixels[i] - b.pixels[i];
    for (float c : {e.x, e.y, e.z, e.w})
      d.push_back(std::abs(c));
  }
  ImageDifference r;
  for (const vec4f& p : b.pixels)
    r.coverage += p.w / double(std::max<size_t>(1, b.pixels.size()));
  for (float x : d)
    r.mean += x;
  r.mean /= double(std::max<size_t>(1, d.size()));
  std::sort(d.begin(), d.end());
  r.p999 = d.empty() ? 0 : d[std::min(d.size() - 1, size_t(0.999 * double(d.size())))];
  r.max = d.empty() ? 0 : d.back();
  return r;
}

/// The bound device images are held to against the CPU's: mean below 0.5/255 and 99.9 % of the
/// channels within 2/255 (the paths differ in float round-off, which can move a sample across a
/// region face or an iso crossing by a step in a few pixels).
inline bool withinBound(const ImageDifference& d) { return d.mean < 0.5 / 255 && d.p999 <= 2.0 / 255; }
/// Path-traced images: the mean within a fraction of the paths' noise at a few samples.
inline bool withinNoise(const ImageDifference& d) { return d.mean < 2.0 / 255; }

inline std::string describe(const ImageDifference& d) {
  return "coverage " + std::to_string(d.coverage) + ", mean " + std::to_string(d.mean * 255) + "/255, 99.9% " +
         std::to_string(d.p999 * 255) + "/255, max " + std::to_string(d.max * 255) + "/255";
}

/// A UV sphere of the given world centre and radius.
inline std::shared_ptr<const TriangleMesh> sphereMesh(const vec3d& centre, double radius, int rings = 12,
                                                      int segments = 24) {
  auto m = std::make_shared<TriangleMesh>();
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double theta = M_PI * i / rings, phi = 2.0 * M_PI * j / segments;
      m->vertices.push_back(vec3f(
          centre + vec3d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)) * radius));
    }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = i * segments + j, b = i * segments + (j + 1) % segments;
      m->triangles.push_back({a, a + segments, b});
      m->triangles.push_back({b, a + segments, b + segments});
    }
  return m;
}

struct Variant {
  std::string name;
  std::function<void(Scene&, Frame&, const DatasetInfo&, const box3d&)> set;
  bool domain = false;     ///< render with a domain box (the data's lower half along x)
  bool depthLimit = false; ///< render with a planar depth limit that cuts through the data
  /// Path traced: the same paths where every float decision agrees; a GPU's arithmetic may turn
  /// a rare one, so the bound is the paths' noise (withinNoise) rather than a marcher's.
  bool pathTraced = false;
};

/// Shading modes, sampling, maps and layers of the volume.
inline std::vector<Variant> volumeVariants() {
  auto tf = [](const char* map) { return defaultTransferFunction(map); };
  return {
      {"smooth shading", [](Scene&, Frame&, const DatasetInfo&, const box3d&) {}},
      {"analytic shading", [](Scene& s, Frame&, const DatasetInfo&, const box3d&) { s.shading = Shading::Analytic; }},
      {"central differences", [](Scene& s, Frame&, const DatasetInfo&, const box3d&) { s.shading = Shading::Central; }},
      {"unshaded, fixed steps, no early termination",
       [](Scene& s, Frame&, const DatasetInfo&, const box3d&) {
         s.shading = Shading::None;
         s.integration.sampling = Sampling::Fixed;
         s.integration.earlyTermination = false;
       }},
      {"logarithmic map, light from a direction",
       [](Scene& s, Frame&, const DatasetInfo&, const box3d&) {
         s.layers[0].tf.logScale = true;
         s.light.headlight = false;
         s.light.direction = {-1.f, -0.5f, -0.2f};
       }},
      {"one colour and a faint opacity over the lowest fifth: longer steps where regions look uniform",
       [](Scene& s, Frame&, const DatasetInfo&, const box3d&) {
         TransferFunction& t = s.layers[0].tf;
         t.colorMap.positions = {0.f, 0.2f, 1.f};
         t.colorMap.colors = {vec3f(0.1f, 0.3f, 0.6f), vec3f(0.1f, 0.3f, 0.6f), vec3f(0.9f, 0.8f, 0.2f)};
         t.opacity = {{0.f, 0.0005f}, {0.2f, 0.0005f}, {1.f, 0.8f}};
       }},
      {"two layers",
       [tf](Scene& s, Frame&, const DatasetInfo&, const box3d&) {
         VolumeLayer radius{"radius", tf("plasma")};
         radius.tf.opacity = {{0.f, 0.f}, {0.6f, 0.f}, {1.f, 0.5f}};
         s.layers.push_back(radius);
       }},
  };
}

/// Iso-surfaces, meshes, clipping, the domain and the depth limit.
inline std::vector<Variant> surfaceVariants() {
  auto tf = [](const char* map) { return defaultTransferFunction(map); };
  return {
      {"iso-surfaces coloured by a field, clip plane and box",
       [tf](Scene& s, Frame&, const DatasetInfo& d, const box3d& bounds) {
         const range1f r = d.valueRanges[0];
         s.iso.values = {r.lower + 0.4f * (r.upper - r.lower), r.lower + 0.7f * (r.upper - r.lower)};
         s.iso.colorField = "radius";
         s.iso.colorTf = tf("viridis");
         const vec3d centre = (bounds.lower + bounds.upper) * 0.5, size = bounds.upper - bounds.lower;
         s.clip.planes.push_back({centre, normalize(vec3d(1.0, 0.3, 0.1))});
         s.clip.box = box3d(bounds.lower - size * 0.1, centre + size * vec3d(0.3, 0.4, 0.2));
         s.layers[0].tf.opacityScale = 0.3f;
       }},
      {"iso-surfaces with their colours and ambient occlusion through the volume",
       [](Scene& s, Frame&, const DatasetInfo& d, const box3d&) {
         const range1f r = d.valueRanges[0];
         s.iso.values = {r.lower + 0.5f * (r.upper - r.lower)};
         s.iso.colors = {{0.9f, 0.5f, 0.2f}};
         s.ao.rays = 4;
         s.ao.volume = true;
       }},
      {"iso-surfaces only, orthographic, ambient occlusion",
       [](Scene& s, Frame& f, const DatasetInfo& d, const box3d&) {
         const range1f r = d.valueRanges[0];
         s.volume = false;
         s.iso.values = {r.lower + 0.3f * (r.upper - r.lower)};
         s.ao.rays = 3;
         f.camera.orthographic = true;
       }},
      {"a domain box", [](Scene&, Frame&, const DatasetInfo&, const box3d&) {}, true},
      {"meshes in the volume, ambient occlusion",
       [](Scene& s, Frame&, const DatasetInfo&, const box3d& bounds) {
         const vec3d centre = (bounds.lower + bounds.upper) * 0.5, size = bounds.upper - bounds.lower;
         s.meshes.push_back({sphereMesh(centre, 0.25 * size.x), {0.8f, 0.3f, 0.2f}, ""});
         s.meshes.push_back({sphereMesh(centre + size * 0.3, 0.1 * size.x), {0.2f, 0.6f, 0.9f}, ""});
         s.ao.rays = 3;
         s.ao.volume = true;
       }},
      {"a clipped mesh with an iso-surface",
       [](Scene& s, Frame&, const DatasetInfo& d, const box3d& bounds) {
         const vec3d centre = (bounds.lower + bounds.upper) * 0.5, size = bounds.upper - bounds.lower;
         s.meshes.push_back({sphereMesh(centre, 0.3 * size.x, 20, 40), {0.7f, 0.7f, 0.2f}, ""});
         s.clip.planes.push_back({centre, normalize(vec3d(-0.2, 1.0, 0.3))});
         s.clip.meshes = true;
         const range1f r = d.valueRanges[0];
         s.iso.values = {r.lower + 0.6f * (r.upper - r.lower)};
         s.ao.rays = 2;
       }},
      {"a depth limit through the data, with an iso-surface",
       [](Scene& s, Frame&, const DatasetInfo& d, const box3d&) {
         const range1f r = d.valueRanges[0];
         s.iso.values = {r.lower + 0.3f * (r.upper - r.lower)};
       },
       false, true},
  };
}

/// The path tracer with layers, iso-surfaces, meshes and clipping.
inline std::vector<Variant> pathTracingVariants() {
  auto tf = [](const char* map) { return defaultTransferFunction(map); };
  return {
      {"path tracing: two layers, sun and environment, anisotropic, clipped",
       [tf](Scene& s, Frame& f, const DatasetInfo&, const box3d& bounds) {
         s.integration.integrator = Integrator::PathTrace;
         s.pathTracing.sunIntensity = 3.f;
         s.pathTracing.anisotropy = 0.4f;
         s.pathTracing.environment = vec3f(0.3f, 0.35f, 0.4f);
         s.layers[0].tf.opacityScale = 0.5f;
         VolumeLayer radius{"radius", tf("plasma")};
         radius.tf.opacity = {{0.f, 0.f}, {0.6f, 0.f}, {1.f, 0.3f}};
         s.layers.push_back(radius);
         const vec3d centre = (bounds.lower + bounds.upper) * 0.5;
         s.clip.planes.push_back({centre, normalize(vec3d(1.0, 0.3, 0.1))});
         f.samplesPerPixel = 4;
       },
       false, false, true},
      {"path tracing: iso-surfaces and a mesh in the medium, emission",
       [](Scene& s, Frame& f, const DatasetInfo& d, const box3d& bounds) {
         s.integration.integrator = Integrator::PathTrace;
         s.pathTracing.sunIntensity = 2.f;
         s.pathTracing.emission = 0.5f;
         s.pathTracing.albedo = 0.6f;
         const range1f r = d.valueRanges[0];
         s.iso.values = {r.lower + 0.6f * (r.upper - r.lower)};
         const vec3d centre = (bounds.lower + bounds.upper) * 0.5, size = bounds.upper - bounds.lower;
         s.meshes.push_back({sphereMesh(centre + size * 0.3, 0.1 * size.x), {0.2f, 0.6f, 0.9f}, ""});
         f.samplesPerPixel = 4;
       },
       false, false, true},
      {"path tracing: a dense medium, through the majorant grid",
       [](Scene& s, Frame& f, const DatasetInfo&, const box3d&) {
         s.integration.integrator = Integrator::PathTrace;
         s.pathTracing.sunIntensity = 2.f;
         s.layers[0].tf.opacityScale = 30.f;
         f.samplesPerPixel = 4;
       },
       false, false, true},
  };
}

/// Every variant: the volume's, the surfaces', one sample without jitter, the path tracer's.
inline std::vector<Variant> variants() {
  std::vector<Variant> all = volumeVariants();
  for (Variant& v : surfaceVariants())
    all.push_back(std::move(v));
  all.push_back({"one sample, no jitter",
                 [](Scene&, Frame& f, const DatasetInfo&, const box3d&) { f.samplesPerPixel = 1, f.jitter = false; }});
  for (Variant& v : pathTracingVariants())
    all.push_back(std::move(v));
  return all;
}

/// Generated multi-level data with two fields, placed in a world frame that is not the lattice's.
inline Model deviceTestModel() {
  Model m = buildModel(generateScene({"blobs", 30000, 7, 4}));
  m.world.origin = vec3d(-3.0, 1.5, 10.0);
  m.world.scale = vec3d(0.02, 0.025, 0.02);
  return m;
}

inline Frame deviceTestFrame(const Model& m, int width = 96, int height = 80) {
  Frame frame;
  frame.width = width;
  frame.height = height;
  frame.samplesPerPixel = 3;
  frame.seed = 11;
  frame.camera = Camera::frame(m.worldBounds(), 35, 25, 40, false);
  return frame;
}

/// The domain box of the variant that has one: the lower half of the data along x.
inline box3d deviceTestDomain(const Model& m) {
  box3d b = m.worldBounds();
  b.upper.x = 0.5 * (b.lower.x + b.upper.x);
  return b;
}

/// Renders `v` on `device` and on the CPU; returns the difference (and the device's stats).
inline ImageDifference compareWithCpu(const Model& m, const DatasetInfo& info, Device device, const Variant& v,
                                      RenderStats* deviceStats = nullptr) {
  Scene scene;
  scene.layers[0].tf.valueRange = info.valueRanges[0];
  Frame frame = deviceTestFrame(m);
  v.set(scene, frame, info, m.worldBounds());
  std::vector<float> depth;
  if (v.depthLimit) {
    // A z-buffer that slants through the data: from 0.8 to 1.2 times the distance to its centre.
    const double centre = length(frame.camera.lookAt - frame.camera.position);
    for (int y = 0; y < frame.height; ++y)
      for (int x = 0; x < frame.width; ++x)
        depth.push_back(float(centre * (0.8 + 0.4 * double(x) / frame.width)));
    frame.depthLimit = depth.data();
    frame.depthLimitPlanar = true;
  }
  Renderer cpu(m, info), dev(m, info);
  if (v.domain) cpu.setDomain(deviceTestDomain(m)), dev.setDomain(deviceTestDomain(m));
  cpu.setScene(scene);
  dev.setScene(scene);
  dev.setDevice(device);
  return difference(dev.render(frame, deviceStats), cpu.render(frame));
}

/// Every variant on `device` against the CPU: within the bound, something drawn, and work the
/// device reports (`work` of its stats) above zero.
inline void expectEveryVariantLikeTheCpu(Device device, uint64_t (*work)(const RenderStats&)) {
  const Model m = deviceTestModel();
  const DatasetInfo info = DatasetInfo::of(m);
  for (const Variant& v : variants()) {
    RenderStats stats;
    const ImageDifference d = compareWithCpu(m, info, device, v, &stats);
    std::printf("%-72s %s\n", v.name.c_str(), describe(d).c_str());
    EXPECT_TRUE(v.pathTraced && device == Device::Cuda ? withinNoise(d) : withinBound(d))
        << v.name << ": " << describe(d);
    EXPECT_GT(d.coverage, 0.01) << v.name << ": nothing drawn";
    EXPECT_GT(work(stats), 0u) << v.name;
  }
}

} // namespace exa::device_test
