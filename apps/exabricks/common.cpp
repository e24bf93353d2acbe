#include "common.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/core/text.h"
#include "exabricks/render/transfer_function.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace exa::cli {

void InputOptions::add(CLI::App& cmd, bool fieldOption) {
  cmd.add_option("input", input,
                 "Model file, NAME.cells dataset, .grids fixture, AMReX plotfile, Chombo or FLASH HDF5 file, "
                 "Enzo parameter file, VTK .vthb file or .raw volume (default: embedded dataset)");
  if (fieldOption) cmd.add_option("-f,--field", field, "Field to use (default: the first)");
  cmd.add_option("--max-brick-width", maxBrickWidth, "Most cells per axis in one brick")->check(CLI::Range(1, 1024));
  cmd.add_option("--segment-cost", segmentCost,
                 "Regions: what one more segment costs a ray, in brick reconstructions of one sample; "
                 "neighbouring regions of one level merge where that is cheaper (0: one region per set of bricks)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd.add_option(
         "--part-cells", partCells,
         "Build NAME.cells inputs of more cells in parts of about this many, each read alone (less memory; 0: "
         "in one piece); AMReX, Chombo, Enzo and VTK AMR inputs are built from their boxes without cell records, "
         "in parts only with --nan-as-holes")
      ->capture_default_str();
  cmd.add_option("--raw-dims", rawDims,
                 "Raw volume: voxels per axis as NXxNYxNZ (default: from NAME_NXxNYxNZ_TYPE.raw)");
  cmd.add_option("--raw-type", rawType, "Raw volume: uint8, uint16, float32 or float64");
  cmd.add_option("--raw-threshold", rawThreshold, "Raw volume: largest value spread merged into one cell")
      ->check(CLI::NonNegativeNumber);
  cmd.add_option("--raw-max-level", rawMaxLevel, "Raw volume: coarsest merged cells are 2^L voxels wide")
      ->check(CLI::Range(0, 28));
  cmd.add_flag("--nan-as-holes", nanAsHoles,
               "Cells with a NaN or infinite value in any loaded field become holes (dropped from every field; "
               "NAME.cells inputs) instead of an error");
}

LoadOptions InputOptions::loadOptions(bool onlySelectedField) const {
  LoadOptions o;
  if (onlySelectedField && !field.empty()) o.fields = {field};
  o.build.bricks.maxBrickWidth = maxBrickWidth;
  o.build.regions.segmentCost = segmentCost;
  o.partCells = partCells;
  if (nanAsHoles) o.nonFinite = NonFinite::Holes;
  if (!rawDims.empty()) {
    long long x = 0, y = 0, z = 0;
    char extra = 0;
    if (std::sscanf(rawDims.c_str(), "%lldx%lldx%lld%c", &x, &y, &z, &extra) != 3)
      failUsage("--raw-dims: expected NXxNYxNZ (e.g. 256x256x128), got '", rawDims, "'");
    o.raw.dims = vec3l(x, y, z);
  }
  o.raw.type = rawType;
  o.raw.threshold = rawThreshold;
  o.raw.maxLevel = rawMaxLevel;
  return o;
}

void InputOptions::addMemoryBudget(CLI::App& cmd) {
  cmd.add_option("--memory-budget", memoryBudget,
                 "Most resident memory for the whole process, e.g. 512M or 2G: a step that does not fit is read "
                 "and drawn in parts, one at a time (default: the whole step, or three quarters of the memory "
                 "available when it does not fit)");
}

std::optional<uint64_t> memoryBudgetFor(const InputOptions& in, const std::string& input, const LoadOptions& lo,
                                        uint64_t frameBytes, bool severalProcesses) {
  if (!in.memoryBudget.empty()) {
    uint64_t bytes = 0;
    if (!parseByteSize(in.memoryBudget, bytes))
      failUsage("--memory-budget: '", in.memoryBudget, "' is not a size (e.g. 512M, 2G, 1.5GiB)");
    if (severalProcesses)
      failUsage("--memory-budget holds a step in parts on one process; under MPI, --distribute data splits it "
                "among the processes");
    return bytes;
  }
  if (severalProcesses) return std::nullopt;
  return budgetForLargeStep(input, lo, frameBytes);
}

MemoryPlan planWithin(const std::string& input, const LoadOptions& lo, uint64_t budget, uint64_t frameBytes) {
  try {
    return planMemory(input, lo, budget, frameBytes);
  } catch (const BudgetTooSmall& e) {
    failUsage(e.what());
  }
}

std::optional<MemoryPlan> memoryPlanFor(const InputOptions& in, const std::string& input, const LoadOptions& lo,
                                        uint64_t frameBytes, bool severalProcesses) {
  const std::optional<uint64_t> budget = memoryBudgetFor(in, input, lo, frameBytes, severalProcesses);
  if (!budget) return std::nullopt;
  MemoryPlan plan = planWithin(input, lo, *budget, frameBytes);
  if (!plan.streamed()) return std::nullopt;
  return plan;
}

std::string InputOptions::name() const { return input.empty() ? kDefaultDatasetName : input; }

void parseSize(const std::string& text, int& width, int& height) {
  char x = 0;
  std::istringstream in(text);
  if (!(in >> width >> x >> height) || x != 'x' || !in.eof() || width < 1 || height < 1 || width > 32768 ||
      height > 32768)
    failUsage("--size expects WIDTHxHEIGHT with each in 1..32768, got '", text, "'");
}

nlohmann::json toJson(const range1f& r) {
  if (r.empty()) return {{"min", nullptr}, {"max", nullptr}};
  return {{"min", r.lower}, {"max", r.upper}};
}

nlohmann::json deviceJson(const Renderer& renderer) {
  nlohmann::json j;
  j["kind"] = deviceName(renderer.device());
  if (renderer.device() == Device::Cuda) {
    const CudaStatus s = cudaStatus();
    j["name"] = s.name;
    j["memory_total_bytes"] = s.totalBytes;
  }
  const DeviceMemory memory = renderer.deviceMemory();
  if (!memory.structures.empty()) {
    nlohmann::json structures = nlohmann::json::object();
    for (const auto& [name, bytes] : memory.structures)
      structures[name] = bytes;
    j["memory_bytes"] = memory.total();
    j["memory_by_structure"] = structures;
  }
  return j;
}

/// Each number of an option the renderer holds in single precision: a finite number that fits.
const CLI::Validator& singleNumber() {
  static const CLI::Validator v(
      [](std::string& text) {
        double d = 0.0;
        if (!parseFiniteNumber(text, d)) return "'" + text + "' is not a finite number";
        return beyondSinglePrecision(d);
      },
      "NUMBER");
  return v;
}

/// A built-in colour map's name.
const CLI::Validator& colormapName() {
  static const CLI::Validator v(
      [](std::string& text) {
        const std::vector<std::string>& names = builtinColorMapNames();
        if (std::find(names.begin(), names.end(), text) != names.end()) return std::string();
        std::string known;
        for (const std::string& n : names)
          known += (known.empty() ? "" : ", ") + n;
        return "unknown colour map '" + text + "' (choose from: " + known + ")";
      },
      "COLORMAP");
  return v;
}

} // namespace exa::cli
