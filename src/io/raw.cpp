#include "exabricks/io/raw.h"

#include "patches.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>

namespace exa {
namespace fs = std::filesystem;

namespace {

size_t typeSize(const std::string& type) {
  if (type == "uint8") return 1;
  if (type == "uint16") return 2;
  if (type == "float32") return 4;
  if (type == "float64") return 8;
  return 0;
}

/// Per-level summary of the 2^l-wide blocks that lie fully inside the volume.
struct LevelSummary {
  vec3l n{0};
  std::vector<float> lo, hi;
  std::vector<double> mean;
  std::vector<uint8_t> ok;   ///< the block may be one cell (spread within the threshold)
  std::vector<uint8_t> stop; ///< this block or an ancestor became a cell
  size_t index(int64_t x, int64_t y, int64_t z) const { return size_t((z * n.y + y) * n.x + x); }
};

} // namespace

bool isRawVolume(const std::string& path) { return path.size() > 4 && path.compare(path.size() - 4, 4, ".raw") == 0; }

bool parseRawName(const std::string& path, RawOptions& out) {
  static const std::regex pattern(R"(_(\d+)x(\d+)x(\d+)_(uint8|uint16|float32|float64)\.raw$)");
  std::smatch m;
  const std::string name = fs::path(path).filename().string();
  if (!std::regex_search(name, m, pattern)) return false;
  try {
    out.dims = vec3l(std::stoll(m[1]), std::stoll(m[2]), std::stoll(m[3]));
  } catch (const std::exception&) {
    return false;
  }
  out.type = m[4];
  return true;
}

CellSet mergeDenseVolume(const std::vector<float>& voxels, vec3l dims, double threshold, int maxLevel) {
  EXA_CHECK(int64_t(voxels.size()) == dims.x * dims.y * dims.z);
  maxLevel = std::clamp(maxLevel, 0, kMaxLevel);
  std::vector<LevelSummary> levels(1);
  levels[0].n = dims;
  // Level 1 and up from the level below: all eight children must be mergeable themselves.
  for (int l = 1; l <= maxLevel; ++l) {
    const LevelSummary& c = levels.back();
    LevelSummary s;
    s.n = vec3l(c.n.x / 2, c.n.y / 2, c.n.z / 2);
    if (s.n.x == 0 || s.n.y == 0 || s.n.z == 0) break;
    const size_t count = size_t(s.n.x * s.n.y * s.n.z);
    s.lo.resize(count);
    s.hi.resize(count);
    s.mean.resize(count);
    s.ok.resize(count);
    s.stop.resize(count, 0);
    for (int64_t z = 0; z < s.n.z; ++z)
      for (int64_t y = 0; y < s.n.y; ++y)
        for (int64_t x = 0; x < s.n.x; ++x) {
          float lo = INFINITY, hi = -INFINITY;
          double sum = 0;
          bool ok = true;
          for (int k = 0; k < 8; ++k) {
            const int64_t cx = 2 * x + (k & 1), cy = 2 * y + ((k >> 1) & 1), cz = 2 * z + (k >> 2);
            const size_t ci = c.index(cx, cy, cz);
            if (l == 1) {
              const float v = voxels[ci];
              lo = std::min(lo, v);
              hi = std::max(hi, v);
              sum += v;
            } else {
              lo = std::min(lo, c.lo[ci]);
              hi = std::max(hi, c.hi[ci]);
              sum += c.mean[ci];
              ok = ok && c.ok[ci];
            }
          }
          const size_t i = s.index(x, y, z);
          s.lo[i] = lo;
          s.hi[i] = hi;
          s.mean[i] = sum / 8;
          s.ok[i] = ok && double(hi) - double(lo) <= threshold;
        }
    levels.push_back(std::move(s));
  }
  // Top-down: keep the coarsest mergeable block; everything below it is covered.
  CellSet set;
  set.fields.push_back({"scalar", {}});
  const int top = int(levels.size()) - 1;
  for (int l = top; l >= 1; --l) {
    LevelSummary& s = levels[size_t(l)];
    const LevelSummary* parent = l < top ? &levels[size_t(l) + 1] : nullptr;
    for (int64_t z = 0; z < s.n.z; ++z)
      for (int64_t y = 0; y < s.n.y; ++y)
        for (int64_t x = 0; x < s.n.x; ++x) {
          const size_t i = s.index(x, y, z);
          const bool covered = parent && x / 2 < parent->n.x && y / 2 < parent->n.y && z / 2 < parent->n.z &&
                               parent->stop[parent->index(x / 2, y / 2, z / 2)];
          s.stop[i] = covered || s.ok[i];
          if (!covered && s.ok[i]) {
            const int32_t w = int32_t(1) << l;
            set.cells.push_back(Cell{vec3i(int32_t(x) * w, int32_t(y) * w, int32_t(z) * w), l});
            set.fields[0].values.push_back(float(s.mean[i]));
          }
        }
  }
  const LevelSummary* parent = top >= 1 ? &levels[1] : nullptr;
  for (int64_t z = 0; z < dims.z; ++z)
    for (int64_t y = 0; y < dims.y; ++y)
      for (int64_t x = 0; x < dims.x; ++x) {
        if (parent && x / 2 < parent->n.x && y / 2 < parent->n.y && z / 2 < parent->n.z &&
            parent->stop[parent->index(x / 2, y / 2, z / 2)])
          continue;
        set.cells.push_back(Cell{vec3i(int32_t(x), int32_t(y), int32_t(z)), 0});
        set.fields[0].values.push_back(voxels[size_t((z * dims.y + y) * dims.x + x)]);
      }
  return set;
}

CellSet readRaw(const std::string& path, const RawOptions& options) {
  RawOptions o = options;
  RawOptions fromName;
  const bool named = parseRawName(path, fromName);
  if (o.dims == vec3l(0)) {
    if (!named)
      fail(path, ": raw volume without dimensions: name it NAME_NXxNYxNZ_TYPE.raw (e.g. head_256x256x128_uint8.raw)",
           " or give --raw-dims NXxNYxNZ and --raw-type");
    o.dims = fromName.dims;
  }
  if (o.type.empty()) {
    if (!named) fail(path, ": raw volume without a scalar type: give --raw-type (uint8, uint16, float32 or float64)");
    o.type = fromName.type;
  }
  const size_t ts = typeSize(o.type);
  if (ts == 0) fail(path, ": unknown raw type '", o.type, "' (uint8, uint16, float32 or float64)");
  for (int a = 0; a < 3; ++a)
    if (o.dims[a] < 1 || o.dims[a] > kLatticeLimit)
      fail(path, ": raw dimensions ", o.dims.x, "x", o.dims.y, "x", o.dims.z, " out of range (1..2^29 per axis)");
  if (!(o.threshold >= 0) || !std::isfinite(o.threshold)) fail(path, ": merge threshold must be a finite value >= 0");
  if (o.maxLevel < 0 || o.maxLevel > kMaxLevel) fail(path, ": maximum level must be within 0..", kMaxLevel);
  if (double(o.dims.x) * double(o.dims.y) * double(o.dims.z) > double(uint64_t(1) << 34))
    fail(path, ": raw dimensions ", o.dims.x, "x", o.dims.y, "x", o.dims.z, " are too large (at most 2^34 voxels)");
  const uint64_t count = uint64_t(o.dims.x) * uint64_t(o.dims.y) * uint64_t(o.dims.z);
  std::error_code ec;
  const uintmax_t size = fs::file_size(path, ec);
  if (ec) fail(path, ": cannot read: ", ec.message());
  if (count > (uint64_t(1) << 34) || size != count * ts)
    fail(path, ": holds ", size, " bytes, but ", o.dims.x, "x", o.dims.y, "x", o.dims.z, " ", o.type, " voxels need ",
         count * ts, " (wrong dimensions or type?)");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, ": cannot open: ", std::strerror(errno));
  std::vector<float> voxels(static_cast<size_t>(count));
  // Read in slabs so that the raw bytes never double the memory of the volume.
  const uint64_t slab = uint64_t(o.dims.x) * uint64_t(o.dims.y);
  std::vector<unsigned char> buf(size_t(slab * ts));
  Progress progress("reading " + path, uint64_t(o.dims.z));
  for (int64_t z = 0; z < o.dims.z; ++z) {
    if (!in.read(reinterpret_cast<char*>(buf.data()), std::streamsize(buf.size())))
      fail(path, ": truncated at slice z = ", z);
    for (uint64_t i = 0; i < slab; ++i) {
      const unsigned char* p = buf.data() + i * ts;
      double v;
      if (ts == 1) {
        v = p[0];
      } else if (ts == 2) {
        v = double(uint16_t(p[0] | (p[1] << 8)));
      } else if (ts == 4) {
        float f;
        std::memcpy(&f, p, 4);
        v = f;
      } else {
        std::memcpy(&v, p, 8);
      }
      voxels[size_t(uint64_t(z) * slab + i)] = io::toFloat32(v, [&] {
        return strCat(path, ": voxel (", int64_t(i % uint64_t(o.dims.x)), ",", int64_t(i / uint64_t(o.dims.x)), ",", z,
                      ")");
      });
    }
    progress.advance(1);
  }
  progress.finish();
  CellSet set = mergeDenseVolume(voxels, o.dims, o.threshold, o.maxLevel);
  logInfo(strCat("merged ", count, " voxels of ", path, " into ", set.cells.size(), " cells"));
  return set;
}

} // namespace exa
