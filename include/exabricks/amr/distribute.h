// Cells spread over processes in any way (the blocks a parallel reader or a simulation gave each
// one) gathered into the parts of a k-d partition balanced by cells, each part with its halo:
// every cell whose basis support reaches into the part's shading reach, so that samples and
// smooth gradients inside a part equal the whole dataset's. The partition, the halo and the
// exchange are written once here, over a small interface to the processes' collectives (MPI in
// the command line, VTK's controller in the ParaView plugin, threads in the tests).
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/amr/partition.h"

#include <cstdint>
#include <string>
#include <vector>

namespace exa {

/// The collectives of a group of processes. Every call is a collective: every process makes it.
class Collectives {
public:
  virtual ~Collectives() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  /// Every process's bytes, in rank order, on every process.
  virtual std::vector<std::vector<uint8_t>> allGather(const std::vector<uint8_t>& mine) = 0;
  /// Sends outgoing[p] to process p (one entry per process); returns what each process sent to
  /// this one, in rank order.
  virtual std::vector<std::vector<uint8_t>> exchange(const std::vector<std::vector<uint8_t>>& outgoing) = 0;
};

/// Returns when `error` is empty on every process; otherwise throws exa::Error on every process:
/// "process R: ERROR" of the lowest failing rank (its own error on that process). A collective.
void agreeOrThrow(Collectives& comm, const std::string& error);

/// Runs `work` on every process and agrees on its success (agreeOrThrow).
template <typename Work> void onEveryProcess(Collectives& comm, Work&& work) {
  std::string error;
  try {
    work();
  } catch (const std::exception& e) {
    error = e.what();
  }
  agreeOrThrow(comm, error);
}

/// The censuses of every process merged into one (the same on every process).
Census mergeCensuses(const std::vector<Census>& censuses);

/// Flat forms of a census and a cell set for sending (the cell set's world placement and
/// simulation state are not sent: every process knows them).
std::vector<uint8_t> encodeCensus(const Census& census);
Census decodeCensus(const std::vector<uint8_t>& bytes);
std::vector<uint8_t> encodeCells(const CellSet& set);
/// Appends the cells of `bytes` (fields in the order of `set.fields`) to `set`.
void appendDecodedCells(CellSet& set, const std::vector<uint8_t>& bytes);

/// One process's part of cells spread over the processes.
struct CellPart {
  KdPartition partition; ///< one part per process, part p for rank p
  int coarsestLevel = 0;
  box3l box;                        ///< this process's part, lattice (faces outside the data unbounded)
  box3l dataBounds;                 ///< the lattice bounds of every process's cells together
  int finestLevel = 0;              ///< the finest level over every process's cells
  std::vector<range1f> valueRanges; ///< per field, over every process's cells (empty: no finite value)
  CellSet cells;                    ///< the cells whose supports reach the part's shading reach
  uint64_t ownedCells = 0;          ///< cells whose centres lie in the part
  uint64_t totalCells = 0;          ///< cells over every process
};

/// A collective: splits the cells that the processes hold between them (`mine`: this process's
/// share, any share, possibly none; the same fields, world and simulation on every process) into
/// one k-d part per process, balanced by cells, and gives each process the cells its part and its
/// halo need. Every process throws when any fails. A part may hold no cells (more processes than
/// the data can be split into): its process has nothing to draw.
CellPart distributeCells(CellSet&& mine, Collectives& comm);

} // namespace exa
