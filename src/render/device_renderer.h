// The device back ends of the renderer: a pass runs traceSample (device_trace.h) for every pixel,
// on a GPU through CUDA or on CPU threads (the portable back end), over device copies of what the
// CPU renderer's units built (the model's bricks, regions and k-d tree, the fields in use, the
// layers' tables, the visible and iso region sets). Copies are made once, and again only for
// what a new scene changed.
#pragma once

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
  /// One pass of the selected tiles: colours of the selected pixels into `colors` (width x height).
  void pass(const Frame& frame, const box3d* domain, int tilesX, int tileBegin, int tileEnd, int tileStride,
            std::vector<vec4f>& colors, gpu::PassCounts& counts);
  DeviceMemory memory() const;

private:
  /// The device address of `bytes` at `host` under `key`, copied when new or changed: data that
  /// never changes (model arrays, fields) by address and size, small tables by content.
  const void* put(const std::string& key, const void* host, uint64_t bytes, bool byContent, SceneUpdate& update);
  template <typename T>
  const T* put(const std::string& key, const std::vector<T>& v, bool byContent, SceneUpdate& update) {
    return static_cast<const T*>(put(key, v.data(), v.size() * sizeof(T), byContent, update));
  }
  /// A field's view on the device, its values (or a gradient field of it) at `values`.
  FieldView fieldView(int field, const float* values, const std::string& what, SceneUpdate& update);

  struct Buffer {
    void* device = nullptr;
    uint64_t bytes = 0;
    const void* host = nullptr;
    std::vector<uint8_t> content; ///< byContent: what was copied
  };
  Device device_;
  const Model& model_;
  const DatasetInfo& dataset_;
  std::map<std::string, Buffer> buffers_;
  std::vector<uint8_t> volumeSubtrees_, isoSubtrees_;
  TraceView base_; ///< what the scene sets; pass() adds the frame
  void* colors_ = nullptr;
  uint64_t colorBytes_ = 0;
  void* counts_ = nullptr;
};

} // namespace exa
