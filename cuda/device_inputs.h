// The inputs of the device check as one file: a model's field, regions and k-d tree, a
// transfer-function table and rays, written on the host that built the model and read where a
// GPU is (host code only; plain structs, the same layout on both sides).
#pragma once

#include "device_samples.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace exa {

struct DeviceInputsHeader {
  char magic[8] = {'E', 'X', 'A', 'D', 'E', 'V', '0', '1'};
  uint64_t bricks = 0, values = 0, regions = 0, brickIds = 0, nodes = 0, rays = 0;
  box3f bounds;
  range1f tfRange;
  uint32_t logScale = 0, fastLinear = 0;
  float tfLower = 0, tfScale = 0;
  float dt = 0.5f, invReferenceWidth = 1.f, isoValue = 0.5f, fadeScale = 1.f;
  ShadingTerms shading;
};

struct DeviceInputs {
  DeviceInputsHeader header;
  std::vector<Brick> bricks;
  std::vector<float> values;
  std::vector<Region> regions;
  std::vector<uint32_t> brickIds;
  std::vector<RegionKdNode> nodes;
  std::vector<uint8_t> visible;
  std::vector<vec4f> table;
  std::vector<Ray> rays;

  /// Views of the arrays given (host arrays here, or device copies of them).
  DeviceRayInputs view(const Brick* b, const float* v, const Region* r, const uint32_t* ids, const RegionKdNode* n,
                       const uint8_t* vis, const vec4f* t) const {
    DeviceRayInputs in;
    in.field.bricks = b;
    in.field.values = v;
    in.field.regions = r;
    in.field.brickIds = ids;
    in.field.nodes = n;
    in.field.bounds = header.bounds;
    in.tree.nodes = n;
    in.tree.visible = vis;
    in.tree.bounds = header.bounds;
    in.table.entries = t;
    in.table.range = header.tfRange;
    in.table.logScale = header.logScale != 0;
    in.table.fastLinear = header.fastLinear != 0;
    in.table.lower = header.tfLower;
    in.table.scale = header.tfScale;
    in.shading = header.shading;
    in.dt = header.dt;
    in.invReferenceWidth = header.invReferenceWidth;
    in.isoValue = header.isoValue;
    in.fadeScale = header.fadeScale;
    return in;
  }
  DeviceRayInputs hostView() const {
    return view(bricks.data(), values.data(), regions.data(), brickIds.data(), nodes.data(), visible.data(),
                table.data());
  }

  void write(const std::string& path) {
    header.bricks = bricks.size();
    header.values = values.size();
    header.regions = regions.size();
    header.brickIds = brickIds.size();
    header.nodes = nodes.size();
    header.rays = rays.size();
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(&header), sizeof header);
    auto put = [&](const auto& v) {
      out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof v[0]));
    };
    put(bricks), put(values), put(regions), put(brickIds), put(nodes), put(visible), put(table), put(rays);
    if (!out) throw std::runtime_error(path + ": cannot write");
  }

  static DeviceInputs read(const std::string& path) {
    DeviceInputs d;
    std::ifstream in(path, std::ios::binary);
    in.read(reinterpret_cast<char*>(&d.header), sizeof d.header);
    if (!in || std::memcmp(d.header.magic, "EXADEV01", 8) != 0)
      throw std::runtime_error(path + ": not a device-check input file");
    auto get = [&](auto& v, uint64_t n) {
      v.resize(n);
      in.read(reinterpret_cast<char*>(v.data()), std::streamsize(n * sizeof v[0]));
    };
    get(d.bricks, d.header.bricks), get(d.values, d.header.values), get(d.regions, d.header.regions);
    get(d.brickIds, d.header.brickIds), get(d.nodes, d.header.nodes), get(d.visible, d.header.regions);
    get(d.table, uint64_t(kTfTableSize)), get(d.rays, d.header.rays);
    if (!in) throw std::runtime_error(path + ": truncated");
    return d;
  }
};

} // namespace exa
