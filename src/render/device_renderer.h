// The device back ends of the renderer: a pass runs traceSample (device_trace.h) for every pixel,
// on a GPU through CUDA or on CPU threads (the portable back end), over device copies of what the
// CPU renderer's units built (the model's bricks, regions and k-d tree, the fields in use, the
// layers' tables, the visible and iso region sets). Copies are made once, and again only for
// what a new scene changed.
#pragma once

#include "exabricks/accel/triangle_bvh.h"
#include "gpu_api.h"
#include "surfaces.h"
#include "volume_marcher.h"

#include <map>
#include <string>
#include <vector>

namespace exa {

class DeviceRenderer {
public:
  DeviceRenderer(Device device, const Model& model, const DatasetInfo& dataset);
  ~DeviceRenderer();
  DeviceRenderer(const DeviceRenderer&) = delete;
  DeviceRenderer& operator=(const DeviceRenderer&) = delete;

  Device device() const { return device_; }
  /// Throws exa::Error naming the first setting of `scene` the device back ends do not have.
  static void checkSupported(const Scene& scene);
  /// Brings the device's copies up to date with the renderer's units for `scene`; adds the bytes
  /// copied and the time to `update`.
  void sync(const Scene& scene, const VolumeMarcher& volume, const Surfaces& surfaces, SceneUpdate& update);
  /// One pass of the selected tiles: returns the colours (width x height; those of the selected
  /// pixels set), valid until the next pass.
  const vec4f* pass(const Frame& frame, const box3d* domain, int tilesX, int tileBegin, int tileEnd, int tileStride,
                    gpu::PassCounts& counts);
  DeviceMemory memory() const;

private:
  /// The device address of `bytes` at `host` under `key`, copied when new or changed: data that
  /// never changes (model arrays, fields) by address and size, small tables by content.
  const void* put(const std::string& key, const void* host, uint64_t bytes, bool byContent, SceneUpdate& update);
  template <typename T>
  const T* put(const std::string& key, const std::vector<T>& v, bool byContent, SceneUpdate& update) {
    return static_cast<const T*>(put(key, v.data(), v.size() * sizeof(T), byContent, update));
  }
  /// A field's view on the device, its values (or a gradient field of it) at `values` (null: the
  /// view without values).
  FieldView fieldView(int field, const float* values, const std::string& what, SceneUpdate& update);
  /// A smooth-shaded layer's field and gradient fields interleaved (TraceLayer::withGradients),
  /// made again only when the gradient fields' `version` (VolumeMarcher::gradientVersion) changed.
  const vec4f* withGradients(const LayerTable& layer, uint64_t version, SceneUpdate& update);
  /// sync's parts: the volume's layers, region trees and integration settings; the iso-surfaces;
  /// the meshes (their hierarchy built again where they or their colours changed).
  void syncVolume(const Scene& scene, const VolumeMarcher& volume, SceneUpdate& update);
  void syncIso(const Scene& scene, const Surfaces& surfaces, SceneUpdate& update);
  void syncMeshes(const Scene& scene, SceneUpdate& update);
  void syncParticles(const Surfaces& surfaces, SceneUpdate& update);

  struct Buffer {
    void* device = nullptr;
    uint64_t capacity = 0; ///< bytes allocated
    uint64_t bytes = 0;    ///< bytes in use
    const void* host = nullptr;
    std::vector<uint8_t> content; ///< byContent: what was copied
  };
  /// Makes `b` hold `bytes` on the device: allocated anew only when it needs more than it has.
  static void reserve(Buffer& b, uint64_t bytes, const std::string& what);
  Device device_;
  const Model& model_;
  const DatasetInfo& dataset_;
  std::map<std::string, Buffer> buffers_;
  std::vector<uint8_t> volumeSubtrees_, isoSubtrees_;
  std::map<int, std::vector<vec4f>> interleaved_;
  std::map<int, uint64_t> interleavedVersion_; ///< per field: the gradient fields' version interleaved
  TriangleBvh meshBvh_;                        ///< the scene's meshes (the CPU renderer's are Embree's)
  std::vector<vec3f> meshColors_;
  std::vector<std::pair<const TriangleMesh*, vec3f>> meshKey_; ///< withGradients' arrays where passes run on the host
  TraceView base_;                                             ///< what the scene sets; pass() adds the frame
  Buffer frame_, counts_;                                      ///< a pass's colours and counters on the device
  vec4f* pinned_ = nullptr;                                    ///< the GPU's colours on the host (page-locked)
  uint64_t pinnedBytes_ = 0;
  std::vector<vec4f> hostColors_; ///< the portable back end's colours
};

} // namespace exa
