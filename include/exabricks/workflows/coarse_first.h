// A step larger than its memory budget explored interactively: its coarse levels held resident
// for drafts and first passes, every level drawn in parts beside them (the viewer, Python).
#pragma once

#include "exabricks/workflows/streamed.h"

#include <memory>
#include <optional>
#include <string>

namespace exa {

/// The most cells coarse levels may hold under `budget`: half of what the budget leaves beside
/// the process (`fixedBytes`), or fewer where `maxCells` above 0 says so.
double coarseRoom(uint64_t budget, uint64_t fixedBytes, uint64_t bytesPerCell, double maxCells);

/// The coarse levels a view holds resident, and its parts planned beside them (in the budget
/// less the coarse levels' estimated bytes).
struct CoarseBeside {
  CoarseFirst coarse;
  MemoryPlan parts;
  double mergedCells = 0; ///< above 0: no coarse levels to hold, every cell merged into about this many cubes
};

/// How `input` is explored under `budget` with `frameBytes` of images: none when it fits whole;
/// else the coarse levels to hold (coarseFirstLevel of coarseRoom's cells; level 0 where the
/// format cannot read its coarse levels alone, and only the parts are held) beside which its
/// parts fit; for an input without coarse levels whose cells can be merged (mergesLeaves), the
/// cubes of every cell merged instead (`mergedCells`). A budget too small for both throws
/// BudgetTooSmall naming the smallest that holds both, said to be `who`'s ("the viewer"); for an
/// input without coarse levels to hold, the parts' own refusal.
std::optional<CoarseBeside> coarseBesideParts(const std::string& input, const LoadOptions& options, uint64_t budget,
                                              uint64_t frameBytes, double maxCoarseCells, const std::string& who);

/// The coarse levels `coarse` names (level > 0): cells 2^level wide and wider are leaves where the
/// finer levels are not read. The dataset's value ranges are the whole step's where its metadata
/// records them (AMReX: per box), its finest level the step's.
struct CoarseLevels {
  std::shared_ptr<const Model> model;
  DatasetInfo dataset;
  int64_t mergedFactor = 1;  ///< loadMergedFirst: the coarsest level's cells merged per axis
  int mergedLevel = 0;       ///< loadMergedFirst: the coarsest level's; loadMergedLeavesFirst: the cubes'
  bool leavesMerged = false; ///< loadMergedLeavesFirst
  double cells = 0;          ///< loadMergedLeavesFirst: the cells merged
};
CoarseLevels loadCoarseLevels(const std::string& input, const LoadOptions& options, const CoarseFirst& coarse);

/// A picture before the coarse levels, for steps whose coarsest level alone holds more than
/// `maxCells` cells: that level's cells merged into about `maxCells` (loadMergedCoarsest), with
/// the dataset as loadCoarseLevels gives it. None where the step cannot be merged so.
std::optional<CoarseLevels> loadMergedFirst(const std::string& input, const LoadOptions& options,
                                            const CoarseFirst& coarse, double maxCells);

/// A picture of an input without coarse levels to read alone: every cell merged into about
/// `maxCells` cubes (loadMergedLeaves), with the cells' value ranges and bounds. None where the
/// input cannot be merged so.
std::optional<CoarseLevels> loadMergedLeavesFirst(const std::string& input, const LoadOptions& options,
                                                  double maxCells);

} // namespace exa
