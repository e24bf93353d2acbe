// A three-level Chombo HDF5 fixture with closed-form values, shared by the reader tests and the
// fixture writer the command-line tests use.
#pragma once

#include "h5_writer.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>
#include <vector>

namespace chombo_fixture {
namespace fs = std::filesystem;

/// A known function of the world position (cell centres).
inline double truth(double x, double y, double z) { return std::sin(x) + 0.5 * y - 0.1 * z * z; }

struct Box {
  int lo[3], hi[3]; // inclusive, in the level's index space
  bool contains(int i, int j, int k) const {
    return i >= lo[0] && i <= hi[0] && j >= lo[1] && j <= hi[1] && k >= lo[2] && k <= hi[2];
  }
};

/// Three levels: an 8^3 domain in two boxes, level 1 (ratio 2) refines [2,3]^3 of level 0,
/// level 2 (ratio 4) refines [4,5]^3 of level 1. Components: density = truth(centre) and
/// energy = 2 * density + level. Ghost cells hold -999 so that reading them shows.
struct ChomboFixture {
  fs::path file;
  bool float32 = false;
  int ghost = 0;
  int ratio1 = 4;
  int spaceDim = 3;
  int numLevels = 3;
  bool nanValue = false;
  bool shortData = false;
  bool badDx = false;        ///< level 2's dx disagrees with the ratios
  bool latestFormat = false; ///< the newest HDF5 file format (h5w::Writer)
  std::vector<std::vector<Box>> levels{{{{0, 0, 0}, {3, 7, 7}}, {{4, 0, 0}, {7, 7, 7}}},
                                       {{{4, 4, 4}, {7, 7, 7}}},
                                       {{{16, 16, 16}, {23, 23, 23}}, {{24, 16, 16}, {27, 19, 19}}}};
  std::vector<int> ratios() const { return {2, ratio1, 2}; }
  double dx(int l) const {
    double d = 1.0;
    for (int i = 0; i < l; ++i)
      d /= ratios()[size_t(i)];
    return d;
  }

  void write() const {
    fs::create_directories(file.parent_path());
    h5w::Writer w(file.string(), latestFormat);
    w.attrInts("/", "num_levels", {numLevels});
    w.attrInts("/", "num_components", {2});
    w.attrString("/", "component_0", "density");
    w.attrString("/", "component_1", "energy");
    w.group("/Chombo_global");
    w.attrInts("/Chombo_global", "SpaceDim", {spaceDim});
    for (int l = 0; l < 3; ++l) {
      const std::string g = "/level_" + std::to_string(l);
      w.group(g);
      w.attrDoubles(g, "dx", {badDx && l == 2 ? 1.5 * dx(l) : dx(l)});
      w.attrInts(g, "ref_ratio", {ratios()[size_t(l)]});
      w.group(g + "/data_attributes");
      w.attrIntCompound(g + "/data_attributes", "outputGhost", {"intvecti", "intvectj", "intvectk"},
                        {ghost, ghost, ghost});
      std::vector<int> boxes;
      std::vector<long long> offsets{0};
      std::vector<double> data;
      for (const Box& b : levels[size_t(l)]) {
        boxes.insert(boxes.end(), {b.lo[0], b.lo[1], b.lo[2], b.hi[0], b.hi[1], b.hi[2]});
        for (int c = 0; c < 2; ++c)
          for (int k = b.lo[2] - ghost; k <= b.hi[2] + ghost; ++k)
            for (int j = b.lo[1] - ghost; j <= b.hi[1] + ghost; ++j)
              for (int i = b.lo[0] - ghost; i <= b.hi[0] + ghost; ++i) {
                const bool inside = b.contains(i, j, k);
                const double v = truth((i + 0.5) * dx(l), (j + 0.5) * dx(l), (k + 0.5) * dx(l));
                data.push_back(!inside ? -999.0 : c == 0 ? v : 2 * v + l);
              }
        offsets.push_back((long long)data.size());
      }
      if (nanValue && l == 2 && data.size() > 5) data[5] = std::nan("");
      if (shortData && l == 1 && data.size() >= 10) data.resize(data.size() - 10);
      w.intCompound(g + "/boxes", {"lo_i", "lo_j", "lo_k", "hi_i", "hi_j", "hi_k"}, boxes);
      w.int64s(g + "/data:offsets=0", {offsets.size()}, offsets);
      w.doubles(g + "/data:datatype=0", {data.size()}, data, float32);
    }
  }

  /// Expected leaf cells of the first `levelsRead` levels: (x, y, z, level) on the finest
  /// lattice -> level index.
  std::map<std::tuple<int, int, int, int>, int> expectedLeaves(int levelsRead = 3) const {
    std::map<std::tuple<int, int, int, int>, int> out;
    const int widths[3] = {2 * ratio1, ratio1, 1};
    const int exaLevels[3] = {ratio1 == 4 ? 3 : 2, ratio1 == 4 ? 2 : 1, 0};
    for (int l = 0; l < levelsRead; ++l)
      for (const Box& b : levels[size_t(l)])
        for (int k = b.lo[2]; k <= b.hi[2]; ++k)
          for (int j = b.lo[1]; j <= b.hi[1]; ++j)
            for (int i = b.lo[0]; i <= b.hi[0]; ++i) {
              bool covered = false;
              if (l + 1 < levelsRead) {
                const int r = ratios()[size_t(l)];
                for (const Box& f : levels[size_t(l) + 1])
                  covered |= f.contains(i * r, j * r, k * r);
              }
              if (!covered) out[{i * widths[l], j * widths[l], k * widths[l], exaLevels[l]}] = l;
            }
    return out;
  }
};

} // namespace chombo_fixture
