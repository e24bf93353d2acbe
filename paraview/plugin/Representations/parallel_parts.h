// ParaView's processes as exabricks' collectives, and the part of AMR data a process renders when
// ParaView runs on several (pvbatch or pvserver under mpirun, Catalyst): the blocks the reader or
// the simulation gave each process are redistributed into the convex parts of a k-d partition
// with their halos (exabricks' distributeCells), so that IceT can composite the parts' images in
// visibility order.
#pragma once

#include "exabricks/amr/distribute.h"
#include "exabricks/amr/model.h"
#include "exabricks/render/renderer.h"

#include <memory>
#include <string>

class vtkMultiProcessController;
class vtkOverlappingAMR;

namespace exa::paraview {

/// The collectives of a VTK controller (ParaView's global one: the render server's processes).
class ControllerCollectives : public Collectives {
public:
  explicit ControllerCollectives(vtkMultiProcessController* controller) : controller_(controller) {}
  int rank() const override;
  int size() const override;
  std::vector<std::vector<uint8_t>> allGather(const std::vector<uint8_t>& mine) override;
  std::vector<std::vector<uint8_t>> exchange(const std::vector<std::vector<uint8_t>>& outgoing) override;

private:
  vtkMultiProcessController* controller_;
};

/// What one process renders of AMR data spread over the processes.
struct ProcessPart {
  std::unique_ptr<Model> model;          ///< null where the part holds no cells
  DatasetInfo dataset;                   ///< the whole dataset's (opacity per its finest cell, ranges)
  box3d domain;                          ///< the part in world coordinates (faces outside the data unbounded)
  double bounds[6] = {0, 0, 0, 0, 0, 0}; ///< the part clipped to the data's world bounds
  /// Per process, in rank order: {"rank", "cells" (with the halo), "owned_cells", "bytes"}, as a
  /// JSON array (the same on every process).
  std::string partsJson;
};

/// What one process holds, as the Parts information lists it.
struct PartNumbers {
  uint64_t cells = 0;      ///< with the halo
  uint64_t ownedCells = 0; ///< whose centres lie in the part
  uint64_t bytes = 0;      ///< bricks, values and regions
};
/// The numbers of a built model (null: nothing held).
PartNumbers partNumbers(const Model* model, uint64_t ownedCells);
/// The Parts information: a JSON array of {"rank", "cells", "owned_cells", "bytes"} in rank order.
std::string partsJson(const std::vector<PartNumbers>& parts);

/// A collective over the processes of `comm`: the leaf cells of array `name` of the blocks every
/// process holds, split into one k-d part per process with its halo, and this process's part
/// built. Throws on every process when any fails ("process R: ...").
ProcessPart buildProcessPart(vtkOverlappingAMR* amr, const std::string& name, Collectives& comm);

} // namespace exa::paraview
