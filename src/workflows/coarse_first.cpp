#include "exabricks/workflows/coarse_first.h"

#include "exabricks/core/text.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace exa {

double coarseRoom(uint64_t budget, uint64_t fixedBytes, uint64_t bytesPerCell, double maxCells) {
  const double room = (double(budget) - double(fixedBytes)) / 2 / double(bytesPerCell);
  return maxCells > 0 ? std::min(maxCells, room) : room;
}

namespace {

/// The smallest budget under which the coarse levels coarseRoom chooses and, beside them, the
/// largest part of every level fit, as `refused` (a refusal of the parts alone) sizes the process
/// and that part. Candidates: for each coarse choice, the budget that holds it beside the part
/// and the one that leaves the part its half (always enough).
uint64_t smallestBesideCoarse(const std::string& input, const BudgetTooSmall& refused, double maxCoarseCells) {
  const double fixed = double(refused.fixedBytes), part = double(refused.smallestPartBytes);
  const double perCell = double(refused.bytesPerCell);
  double best = std::numeric_limits<double>::infinity();
  for (const CoarseFirst& choice : coarseFirstChoices(input)) {
    if (choice.level == 0) continue;
    const double coarse = choice.coarseCells * perCell;
    for (double budget : {fixed + std::max(2 * coarse, coarse + part), fixed + 2 * std::max(coarse, part)}) {
      const CoarseFirst chosen = coarseFirstLevel(
          input, coarseRoom(uint64_t(budget), refused.fixedBytes, refused.bytesPerCell, maxCoarseCells));
      if (chosen.level > 0 && fixed + chosen.coarseCells * perCell + part <= budget) best = std::min(best, budget);
    }
  }
  if (!std::isfinite(best)) return refused.smallest;
  return wholeMebibytes(uint64_t(std::ceil(best)));
}

/// The parts' refusal (`refused`) said again of `who` holding `beside` next to them: the same
/// figures (after its "(N cells): "), and `smallest` as the smallest budget that works.
BudgetTooSmall refusedBeside(const BudgetTooSmall& refused, const std::string& input, uint64_t budget,
                             const std::string& who, uint64_t smallest, const std::string& beside) {
  const std::string& said = refused.situation;
  const size_t figures = said.find(" cells): ");
  return BudgetTooSmall(strCat("a memory budget of ", formatBytes(budget), " cannot hold ", input, " for ", who,
                               figures == std::string::npos ? "" : said.substr(figures + 7)),
                        smallest, refused.fixedBytes, refused.smallestPartBytes, refused.bytesPerCell,
                        strCat("with ", beside, " beside the parts"));
}

/// A view of an input without coarse levels to read alone but whose cells can be merged
/// (mergesLeaves): the cubes it holds, at most a quarter of coarseRoom's cells (the merge's own
/// tables take more per cube than a model) and at most `maxCoarseCells`, reserved at twice their
/// estimate (cubes at the cells' edges add some) at the bytes of a build from cell records, and
/// its parts planned in the rest. A budget too small is refused with the smallest under which
/// the parts' smallest largest part fits beside the most cubes.
CoarseBeside besideMergedLeaves(const std::string& input, const LoadOptions& options, uint64_t budget,
                                uint64_t frameBytes, const MemoryPlan& sizes, double maxCoarseCells,
                                const std::string& who) {
  CoarseBeside b;
  b.mergedCells = coarseRoom(budget, sizes.fixedBytes, sizes.bytesPerCell, 0) / 4;
  if (maxCoarseCells > 0) b.mergedCells = std::min(b.mergedCells, maxCoarseCells);
  const double cubes = b.mergedCells >= 1 ? mergedLeavesCubes(input, options, b.mergedCells) : 0;
  const uint64_t perCube = std::max(sizes.bytesPerCell, bytesPerResidentCell(1, false));
  const uint64_t held = uint64_t(std::ceil(2 * cubes)) * perCube;
  try {
    if (!(b.mergedCells >= 1)) planMemory(input, options, 0, frameBytes); // refused: no room for cubes
    b.parts = planMemory(input, options, budget > held ? budget - held : 0, frameBytes);
    return b;
  } catch (const BudgetTooSmall& refused) {
    // Held cubes take a quarter of what the budget leaves beside the process: the part needs the
    // other three.
    const uint64_t smallest = refused.fixedBytes + (refused.smallestPartBytes * 4 + 2) / 3;
    throw refusedBeside(refused, input, budget, who, wholeMebibytes(smallest),
                        strCat("every cell merged into cubes that ", who, " holds for drafts"));
  }
}

} // namespace

std::optional<CoarseBeside> coarseBesideParts(const std::string& input, const LoadOptions& options, uint64_t budget,
                                              uint64_t frameBytes, double maxCoarseCells, const std::string& who) {
  try {
    const MemoryPlan sizes = sizeMemory(input, options, budget, frameBytes);
    if (sizes.fitsWhole()) return std::nullopt;
    const CoarseFirst coarse =
        coarseFirstLevel(input, coarseRoom(budget, sizes.fixedBytes, sizes.bytesPerCell, maxCoarseCells));
    if (coarse.level == 0) {
      if (mergesLeaves(input))
        return besideMergedLeaves(input, options, budget, frameBytes, sizes, maxCoarseCells, who);
      return CoarseBeside{coarse, planMemory(input, options, budget, frameBytes)}; // refused where no parts fit
    }
    // The parts beside the coarse levels; where they fit, the parts of the whole budget do too
    // (each count's parts are the same, with more room), so that plan is made only to say why a
    // budget is refused: its own refusal where the step cannot be held in parts at all.
    const uint64_t coarseBytes = uint64_t(std::ceil(coarse.coarseCells)) * sizes.bytesPerCell;
    try {
      return CoarseBeside{coarse,
                          planMemory(input, options, budget > coarseBytes ? budget - coarseBytes : 0, frameBytes)};
    } catch (const BudgetTooSmall&) {
      planMemory(input, options, budget, frameBytes);
      throw;
    }
  } catch (const BudgetTooSmall& refused) {
    // No coarse levels to hold, or cubes held instead: that refusal.
    if (coarseFirstChoices(input).size() < 2 || mergesLeaves(input)) throw;
    throw refusedBeside(refused, input, budget, who, smallestBesideCoarse(input, refused, maxCoarseCells),
                        strCat("the coarse levels ", who, " holds for drafts"));
  }
}

namespace {
/// The dataset of a model that holds less than the step: value ranges the whole step's where its
/// metadata record them, the finest level the step's.
DatasetInfo partialDataset(const std::string& input, const Model& model, int finestLevel) {
  std::vector<range1f> ranges = DatasetInfo::of(model).valueRanges;
  for (size_t k = 0; k < ranges.size(); ++k)
    if (const std::optional<range1f> r = fieldRangeFromMetadata(input, model.fieldNames[k])) ranges[k] = *r;
  return DatasetInfo::from(finestLevel, model.cellBounds(), model.world.scale, ranges);
}
} // namespace

CoarseLevels loadCoarseLevels(const std::string& input, const LoadOptions& options, const CoarseFirst& coarse) {
  LoadOptions o = options;
  o.finestLevel = coarse.level;
  CoarseLevels c;
  c.model = std::make_shared<const Model>(loadModel(input, o));
  c.dataset = partialDataset(input, *c.model, coarse.finestLevel);
  return c;
}

std::optional<CoarseLevels> loadMergedFirst(const std::string& input, const LoadOptions& options,
                                            const CoarseFirst& coarse, double maxCells) {
  std::optional<MergedCoarsest> merged = loadMergedCoarsest(input, options, maxCells);
  if (!merged) return std::nullopt;
  CoarseLevels c;
  c.model = std::make_shared<const Model>(std::move(merged->model));
  c.dataset = partialDataset(input, *c.model, coarse.finestLevel);
  c.mergedFactor = merged->factor;
  c.mergedLevel = merged->level;
  return c;
}

std::optional<CoarseLevels> loadMergedLeavesFirst(const std::string& input, const LoadOptions& options,
                                                  double maxCells) {
  std::optional<MergedLeaves> merged = loadMergedLeaves(input, options, maxCells);
  if (!merged) return std::nullopt;
  CoarseLevels c;
  c.dataset = DatasetInfo::from(merged->finestLevel, merged->cellBounds, merged->model.world.scale, merged->ranges);
  c.model = std::make_shared<const Model>(std::move(merged->model));
  c.mergedLevel = merged->level;
  c.leavesMerged = true;
  c.cells = merged->cells;
  return c;
}

} // namespace exa
