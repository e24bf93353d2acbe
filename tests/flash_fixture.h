// A FLASH HDF5 fixture (PARAMESH blocks, two refinement levels below the roots) with closed-form
// values, shared by the reader tests and the FLASH fuzz target.
#pragma once

#include "h5_writer.h"

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace flash_fixture {
namespace fs = std::filesystem;

inline double truth(double x, double y, double z) { return std::cos(2 * x) + 0.25 * y * y + 0.3 * z; }

struct Block {
  double lo[3], hi[3];
  int level, nodeType;
};

/// Domain [-1,1] x [0,2] x [0,4] as two root blocks of 4 x 4 x 2 cells (anisotropic cells). The
/// upper root block is refined into eight children, one of which is refined again. Variables:
/// dens = truth(centre), pres = 3 dens + refine level; parents hold -5.
struct FlashFixture {
  fs::path file;
  bool float32 = false;
  int nxb = 4, nyb = 4, nzb = 2;
  int dimensionality = 3;
  double shift = 0;     ///< moves one leaf block off the lattice
  bool badSize = false; ///< gives one leaf block 4/3 of the finest cell size
  bool nanValue = false;
  bool dropRow = false;      ///< variable datasets one block short
  bool latestFormat = false; ///< the newest HDF5 file format (h5w::Writer)
  int particles = -1;        ///< >= 0: a "tracer particles" table of this many (blk, posx, posy, posz, tag)
  std::vector<Block> blocks;

  FlashFixture() {
    blocks.push_back({{-1, 0, 0}, {0, 2, 4}, 1, 1});
    blocks.push_back({{0, 0, 0}, {1, 2, 4}, 1, 3});
    for (int c = 0; c < 8; ++c) {
      Block b{{0, 0, 0}, {0, 0, 0}, 2, c == 5 ? 2 : 1};
      for (int a = 0; a < 3; ++a) {
        const double lo = blocks[1].lo[a], half = (blocks[1].hi[a] - lo) / 2;
        b.lo[a] = lo + ((c >> a) & 1) * half;
        b.hi[a] = b.lo[a] + half;
      }
      blocks.push_back(b);
    }
    const Block parent = blocks[7];
    for (int c = 0; c < 8; ++c) {
      Block b{{0, 0, 0}, {0, 0, 0}, 3, 1};
      for (int a = 0; a < 3; ++a) {
        const double half = (parent.hi[a] - parent.lo[a]) / 2;
        b.lo[a] = parent.lo[a] + ((c >> a) & 1) * half;
        b.hi[a] = b.lo[a] + half;
      }
      blocks.push_back(b);
    }
  }

  void write() {
    std::vector<Block> bs = blocks;
    bs[3].lo[0] += shift;
    bs[3].hi[0] += shift;
    if (badSize) bs[4].hi[0] = bs[4].lo[0] + (bs[4].hi[0] - bs[4].lo[0]) * 2 / 3;
    fs::create_directories(file.parent_path());
    h5w::Writer w(file.string(), latestFormat);
    const size_t n = bs.size();
    std::vector<int> level, node;
    std::vector<double> bbox, size, coord;
    for (const Block& b : bs) {
      level.push_back(b.level);
      node.push_back(b.nodeType);
      for (int a = 0; a < 3; ++a) {
        bbox.insert(bbox.end(), {b.lo[a], b.hi[a]});
        size.push_back(b.hi[a] - b.lo[a]);
        coord.push_back((b.lo[a] + b.hi[a]) / 2);
      }
    }
    w.ints("refine level", {n}, level);
    w.ints("node type", {n}, node);
    w.doubles("bounding box", {n, 3, 2}, bbox, float32);
    w.doubles("block size", {n, 3}, size, float32);
    w.doubles("coordinates", {n, 3}, coord, float32);
    w.strings("unknown names", {2, 1}, {"dens", "pres"}, 4);
    w.nameValueTable("integer scalars", {"nxb", "nyb", "nzb", "dimensionality", "globalnumblocks", "nstep"},
                     {double(nxb), double(nyb), double(nzb), double(dimensionality), double(n), 42.0}, true);
    w.nameValueTable("real scalars", {"time"}, {0.5}, false);
    if (particles >= 0) {
      // Particle p: block p % n, position (0.1 + 0.01 p, 0.2 + 0.02 p, 0.3 + 0.005 p), tag 100 + p.
      std::vector<double> table;
      for (int p = 0; p < particles; ++p)
        table.insert(table.end(), {double(p % int(n)), 0.1 + 0.01 * p, 0.2 + 0.02 * p, 0.3 + 0.005 * p, 100.0 + p});
      w.doubles("tracer particles", {hsize_t(particles), 5}, table, float32);
      w.strings("particle names", {5, 1}, {"blk", "posx", "posy", "posz", "tag"}, 24);
    }
    for (int var = 0; var < 2; ++var) {
      std::vector<double> v;
      const size_t rows = dropRow ? n - 1 : n;
      for (size_t bi = 0; bi < rows; ++bi) {
        const Block& b = bs[bi];
        const double d[3] = {(b.hi[0] - b.lo[0]) / nxb, (b.hi[1] - b.lo[1]) / nyb, (b.hi[2] - b.lo[2]) / nzb};
        for (int k = 0; k < nzb; ++k)
          for (int j = 0; j < nyb; ++j)
            for (int i = 0; i < nxb; ++i) {
              const double t =
                  truth(b.lo[0] + (i + 0.5) * d[0], b.lo[1] + (j + 0.5) * d[1], b.lo[2] + (k + 0.5) * d[2]);
              v.push_back(b.nodeType != 1 ? -5.0 : var == 0 ? t : 3 * t + b.level);
            }
      }
      if (nanValue) v[v.size() - 3] = std::nan("");
      w.doubles(var == 0 ? "dens" : "pres", {rows, hsize_t(nzb), hsize_t(nyb), hsize_t(nxb)}, v, float32);
    }
  }
};

} // namespace flash_fixture
