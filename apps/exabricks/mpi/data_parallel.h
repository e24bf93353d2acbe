// Data-parallel rendering over MPI: the processes split the dataset by a k-d partition balanced
// by cells, each reads and builds only its part plus the halo of cells whose basis support reaches
// into it, and the dataset-wide values every process renders with are agreed by reductions.
#pragma once

#include "../scene_options.h"

#include "exabricks/amr/model.h"
#include "exabricks/amr/partition.h"
#include "exabricks/io/load.h"
#include "exabricks/render/renderer.h"

#include <optional>
#include <string>
#include <vector>

namespace exa::mpi {

/// This process's part of a dataset.
struct DataPart {
  KdPartition partition;
  int coarsestLevel = 0;
  box3l box;            ///< this process's part, lattice (faces outside the data unbounded)
  Model model;          ///< the cells whose supports reach into the part
  DatasetInfo dataset;  ///< the whole dataset's, agreed by every process
  cli::WholeData whole; ///< likewise

  /// The part's box in world coordinates (the renderer's domain).
  box3d worldBox() const;
  /// Cells whose centres lie in the part (every cell belongs to one part).
  uint64_t ownedCells() const;
  /// The processes' parts front to back as the camera sees them.
  std::vector<int> order(const Camera& camera) const;
};

/// Loads this process's part: the first process takes the census and splits it into one part per
/// process, every process reads its part with its halo and builds it. A failure in any process
/// stops every process with an error; so does a part that holds no cells (too many processes for
/// the data).
DataPart loadDataPart(const std::string& input, const LoadOptions& options);

/// The union over the processes of what may be visible in each one's part (what a first view frames).
box3d agreedVisibleBounds(const Renderer& renderer, const DataPart& part);

} // namespace exa::mpi
