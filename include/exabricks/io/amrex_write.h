// Writes AMReX plotfiles (HyperCLaw-V1.1 headers, VisMF version 1 FABs, refinement ratio 2) from
// leaf cells given piece by piece, so that a step of billions of cells is written in the memory of
// one piece. Every level stores its cells in boxes, those covered by finer cells included (their
// value: the mean of their children's, as AMReX's average-down makes it), as plotfiles do.
#pragma once

#include "exabricks/amr/cells.h"

#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace exa {

class AmrexPlotfileWriter {
public:
  /// A plotfile of `levels` levels (exabricks levels 0 .. levels - 1; the coarsest is AMReX's
  /// level 0) over the lattice [0, latticeWidth)^3, the physical domain the unit cube, with the
  /// fields `fieldNames` in float64 or float32. Written into PATH.partial, renamed at finish().
  AmrexPlotfileWriter(std::string path, std::vector<std::string> fieldNames, int levels, int64_t latticeWidth,
                      bool float32);
  ~AmrexPlotfileWriter();
  AmrexPlotfileWriter(const AmrexPlotfileWriter&) = delete;
  AmrexPlotfileWriter& operator=(const AmrexPlotfileWriter&) = delete;

  /// The cells of one piece: every leaf in slabs of coarsest cells along z whose ends are
  /// multiples of kSlabCells coarsest cells (the last may end at the lattice's end). Each level's
  /// cells go into boxes of at most 32 cells per axis that stay within the slab, cut smaller where
  /// only part of a box holds cells.
  void append(const CellSet& piece);
  /// Writes the headers and renames the plotfile into place; returns its boxes.
  uint64_t finish();

  /// The slab of coarsest cells that pieces must consist of whole.
  static constexpr int kSlabCells = 8;

private:
  struct Level;
  void writeBox(int level, const vec3l& lower, const vec3l& cells, const std::vector<float>& values);
  std::string path_, partial_;
  std::vector<std::string> names_;
  int levels_;
  int64_t width_;
  bool float32_;
  std::vector<std::unique_ptr<Level>> perLevel_;
  bool finished_ = false;
};

} // namespace exa
