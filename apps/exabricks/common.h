// Options and helpers shared by the subcommands.
#pragma once

#include "exabricks/core/error.h"
#include "exabricks/io/load.h"
#include "exabricks/render/renderer.h"
#include "exabricks/workflows/streamed.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <functional>
#include <optional>
#include <string>

namespace exa::cli {

/// The input options every data-reading command takes.
struct InputOptions {
  std::string input; ///< empty: the embedded default dataset
  std::string field; ///< empty: the first field
  int maxBrickWidth = 32;
  double segmentCost = RegionBuildOptions().segmentCost;
  uint64_t partCells = uint64_t(1) << 27; ///< larger inputs are built in parts of about this many cells
  std::string rawDims;                    ///< raw volumes: NXxNYxNZ (default: from the file name)
  std::string rawType;                    ///< raw volumes: uint8, uint16, float32 or float64
  double rawThreshold = 0.0;              ///< raw volumes: largest value spread of a merged cell
  int rawMaxLevel = 4;                    ///< raw volumes: coarsest merged level
  bool nanAsHoles = false;                ///< NaN and infinite values make their cells holes
  std::string memoryBudget;               ///< --memory-budget as given (empty: none)

  void add(CLI::App& cmd, bool fieldOption = true);
  /// Registers --memory-budget (the commands that hold a step in parts under it).
  void addMemoryBudget(CLI::App& cmd);
  LoadOptions loadOptions(bool onlySelectedField) const;
  std::string name() const;
};

/// How a command holds `input` (loaded with `lo`, beside `frameBytes` of images): none when
/// whole, as without a budget; a plan of parts under --memory-budget, or when the step is too
/// large for the memory available (said on stderr). A budget smaller than the process with its
/// smallest part is a usage error naming the smallest budget that works; several processes
/// (`severalProcesses`) refuse --memory-budget.
std::optional<MemoryPlan> memoryPlanFor(const InputOptions& in, const std::string& input, const LoadOptions& lo,
                                        uint64_t frameBytes, bool severalProcesses);
/// The budget memoryPlanFor plans with: --memory-budget, or (without it, on one process) the one
/// budgetForLargeStep chooses for a step too large for the memory available; none otherwise.
std::optional<uint64_t> memoryBudgetFor(const InputOptions& in, const std::string& input, const LoadOptions& lo,
                                        uint64_t frameBytes, bool severalProcesses);
/// planMemory, a budget too small being a usage error that names `input`'s smallest budget.
MemoryPlan planWithin(const std::string& input, const LoadOptions& lo, uint64_t budget, uint64_t frameBytes);

/// Parses WIDTHxHEIGHT (each 1..32768) as given to --size; throws with the text otherwise.
void parseSize(const std::string& text, int& width, int& height);

/// JSON for a range; null bounds for an empty range.
nlohmann::json toJson(const range1f& r);

/// Where a renderer's passes run: {"kind": "cpu" | "cuda" | "portable"} and, on a GPU, its name
/// and the memory the renderer holds there per structure.
nlohmann::json deviceJson(const Renderer& renderer);

/// Each number of an option the renderer holds in single precision: a finite number that fits.
const CLI::Validator& singleNumber();
/// A built-in colour map's name.
const CLI::Validator& colormapName();

} // namespace exa::cli
