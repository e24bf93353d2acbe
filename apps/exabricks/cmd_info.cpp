// exabricks info: what a dataset holds and what its bricks and regions look like.
#include "commands.h"
#include "common.h"
#include "mpi/data_parallel.h"
#include "mpi/processes.h"

#include "exabricks/io/model_info.h"
#include "exabricks/io/particles.h"

#include "exabricks/core/log.h"
#include "exabricks/core/text.h"

#include <cstdio>
#include <iostream>

namespace exa::cli {
namespace {

struct InfoOptions {
  InputOptions in;
  bool json = false;
  bool fieldsOnly = false;
};

/// The particle species beside the cells, from the input's headers (none for the embedded
/// dataset, model files and formats without particles).
std::vector<ParticleSpeciesInfo> particlesOf(const InfoOptions& o) {
  return o.in.input.empty() ? std::vector<ParticleSpeciesInfo>{} : listParticles(o.in.input);
}

nlohmann::json particlesJson(const std::vector<ParticleSpeciesInfo>& species) {
  return nlohmann::json::parse(particleSpeciesJson(species));
}

void printParticles(const std::vector<ParticleSpeciesInfo>& species) {
  for (const ParticleSpeciesInfo& s : species) {
    std::string attributes;
    for (const std::string& a : s.attributes)
      attributes += (attributes.empty() ? "" : ", ") + a;
    std::printf("particles        %s: %llu (%s; %zu bytes each when read)\n", s.name.c_str(),
                (unsigned long long)s.count, s.precision.c_str(), bytesPerParticle(s));
    std::printf("  attributes     %s\n", attributes.empty() ? "none" : attributes.c_str());
  }
}

void printFields(const InfoOptions& o) {
  const std::vector<std::string> names = listFields(o.in.input);
  if (o.json) {
    std::cout << nlohmann::json{{"fields", names}}.dump(2) << "\n";
    return;
  }
  for (const std::string& n : names)
    std::printf("%s\n", n.c_str());
}

/// Under MPI: the data-parallel split, each process's part and what it holds (its box, the cells
/// it holds with its halo, those it owns, bricks, regions, memory).
void runParts(const InfoOptions& o) {
  Timer total;
  const mpi::DataPart part = mpi::loadDataPart(o.in.input, o.in.loadOptions(true));
  const double loadSeconds = total.seconds();
  const ModelSummary s = summarize(part.model);
  const uint64_t owned = part.ownedCells();
  auto gather = [](double v) { return mpi::allGather(v); };
  const std::vector<double> resident = gather(double(s.cells)), own = gather(double(owned)),
                            bricks = gather(double(s.bricks)), regions = gather(double(s.regions)),
                            rss = gather(double(peakResidentBytes())), seconds = gather(loadSeconds);
  std::vector<std::vector<double>> box(6);
  for (int a = 0; a < 3; ++a) {
    box[size_t(a)] = gather(double(part.box.lower[a]));
    box[size_t(a) + 3] = gather(double(part.box.upper[a]));
  }
  if (!mpi::processes().root()) return;
  const int n = mpi::processes().size;
  const box3i cb = part.whole.cellBounds;
  // A face on the outside of the data is unbounded: null in JSON, "-" in text.
  auto face = [](double v) -> nlohmann::json {
    if (std::abs(v) >= double(kUnboundedLattice)) return nullptr;
    return int64_t(v);
  };
  uint64_t totalOwned = 0;
  for (double v : own)
    totalOwned += uint64_t(v);
  if (o.json) {
    nlohmann::json ranks = nlohmann::json::array();
    for (int r = 0; r < n; ++r) {
      const size_t i = size_t(r);
      ranks.push_back({{"rank", r},
                       {"box",
                        {{"lower", {face(box[0][i]), face(box[1][i]), face(box[2][i])}},
                         {"upper", {face(box[3][i]), face(box[4][i]), face(box[5][i])}}}},
                       {"resident_cells", uint64_t(resident[i])},
                       {"owned_cells", uint64_t(own[i])},
                       {"halo_cells", uint64_t(resident[i]) - uint64_t(own[i])},
                       {"bricks", uint64_t(bricks[i])},
                       {"regions", uint64_t(regions[i])},
                       {"peak_rss_bytes", uint64_t(rss[i])},
                       {"load_seconds", seconds[i]}});
    }
    nlohmann::json j;
    j["input"] = o.in.name();
    j["processes"] = n;
    j["distribute"] = "data";
    j["cells"] = totalOwned;
    j["coarsest_level"] = part.coarsestLevel;
    j["lattice_bounds"] = {{"lower", {cb.lower.x, cb.lower.y, cb.lower.z}},
                           {"upper", {cb.upper.x, cb.upper.y, cb.upper.z}}};
    j["ranks"] = ranks;
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("input            %s\n", o.in.name().c_str());
  std::printf("processes        %d (data-parallel parts: k-d split balanced by cells)\n", n);
  std::printf("cells            %llu\n", (unsigned long long)totalOwned);
  std::printf("  %-5s %-44s %12s %12s %12s %10s\n", "rank", "box (lattice, - = unbounded)", "owned", "halo", "bricks",
              "peak MB");
  for (int r = 0; r < n; ++r) {
    const size_t i = size_t(r);
    auto txt = [&](double v) {
      return std::abs(v) >= double(kUnboundedLattice) ? std::string("-") : strCat(int64_t(v));
    };
    const std::string b = strCat("[", txt(box[0][i]), " ", txt(box[1][i]), " ", txt(box[2][i]), "] - [", txt(box[3][i]),
                                 " ", txt(box[4][i]), " ", txt(box[5][i]), "]");
    std::printf("  %-5d %-44s %12llu %12llu %12llu %10.1f\n", r, b.c_str(), (unsigned long long)own[i],
                (unsigned long long)(resident[i] - own[i]), (unsigned long long)bricks[i], rss[i] / 1e6);
  }
}

/// A step larger than the budget: what its parts hold, read one at a time.
void runStreamed(const InfoOptions& o, const LoadOptions& lo, MemoryPlan plan) {
  Timer total;
  StreamedStep step(o.in.input, lo, std::move(plan));
  const StepSurvey& s = step.survey();
  const Model& model = step.skeleton();
  const double seconds = total.seconds();
  const box3i lattice = s.cellBounds;
  const box3d world = model.world.toWorld(lattice);
  const MemoryPlan& p = step.plan();
  if (o.json) {
    nlohmann::json j = nlohmann::json::parse(step.infoJson(o.in.name(), seconds));
    j["particles"] = particlesJson(particlesOf(o));
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("input            %s\n", o.in.name().c_str());
  std::printf("lattice bounds   [%d %d %d] - [%d %d %d] (finest-level units, upper exclusive)\n", lattice.lower.x,
              lattice.lower.y, lattice.lower.z, lattice.upper.x, lattice.upper.y, lattice.upper.z);
  std::printf("world bounds     [%g %g %g] - [%g %g %g]\n", world.lower.x, world.lower.y, world.lower.z, world.upper.x,
              world.upper.y, world.upper.z);
  std::printf("cells            %llu\n", (unsigned long long)s.cells);
  std::printf("  %-8s %-10s %14s\n", "level", "width", "cells");
  for (auto l = s.levels.rbegin(); l != s.levels.rend(); ++l)
    std::printf("  %-8d %-10d %14llu\n", *l, 1 << *l, (unsigned long long)s.levelCells[size_t(*l)]);
  for (size_t f = 0; f < model.fieldNames.size(); ++f)
    std::printf("field %-10s [%g, %g]%s\n", model.fieldNames[f].c_str(), s.dataset.valueRanges[f].lower,
                s.dataset.valueRanges[f].upper,
                model.unitsOf(int(f)).empty() ? "" : (" " + model.unitsOf(int(f))).c_str());
  std::printf("memory budget    %s: %d parts read one at a time, the largest about %s beside %s\n",
              formatBytes(p.budget).c_str(), step.parts(), formatBytes(p.largestPartBytes()).c_str(),
              formatBytes(p.fixedBytes).c_str());
  std::printf("over the parts   %llu bricks, %llu regions (halos included)\n", (unsigned long long)s.bricks,
              (unsigned long long)s.regions);
  std::printf("peak memory      %s (read in %.3f s)\n", formatBytes(peakResidentBytes()).c_str(), seconds);
  printParticles(particlesOf(o));
}

void run(const InfoOptions& o) {
  if (o.fieldsOnly) {
    mpi::requireOneProcess("info --fields");
    return printFields(o);
  }
  if (mpi::processes().size > 1) {
    memoryPlanFor(o.in, o.in.input, LoadOptions(), 0, true); // refuses --memory-budget
    return runParts(o);
  }
  Timer total;
  LoadOptions lo = o.in.loadOptions(true);
  if (std::optional<MemoryPlan> plan = memoryPlanFor(o.in, o.in.input, lo, 0, false))
    return runStreamed(o, lo, std::move(*plan));
  lo.report = std::make_shared<LoadReport>();
  const Model model = loadModel(o.in.input, lo);
  const double loadSeconds = total.seconds();
  const ModelSummary s = summarize(model);
  const box3i lattice = model.cellBounds();
  const vec3d worldLo = model.world.toWorld(vec3d(lattice.lower));
  const vec3d worldHi = model.world.toWorld(vec3d(lattice.upper));
  const double perCell = s.cells ? 1.0 / double(s.cells) : 0.0;

  if (o.json) {
    nlohmann::json j = nlohmann::json::parse(modelInfoJson(model, o.in.name(), loadSeconds));
    j["device"] = nlohmann::json::parse(deviceInfoJson(model));
    if (lo.nonFinite == NonFinite::Holes) {
      // Cells with NaN or infinite values per field, made holes (--nan-as-holes).
      nlohmann::json counts = nlohmann::json::object();
      for (const auto& [field, cells] : lo.report->nonFinite)
        counts[field] = cells;
      j["non_finite_holes"] = {{"fields", counts}, {"cells", lo.report->holes}};
    }
    j["particles"] = particlesJson(particlesOf(o));
    std::cout << j.dump(2) << "\n";
    return;
  }

  std::printf("input            %s\n", o.in.name().c_str());
  {
    const CudaStatus cuda = cudaStatus();
    const DeviceFootprint need = deviceFootprint(model);
    const double mib = double(need.model.total() + need.fieldBytes) / 1048576.0;
    if (cuda.problem.empty())
      std::printf("device           cuda: %s, %.1f GiB (this dataset with one field: %.1f MiB)\n", cuda.name.c_str(),
                  double(cuda.totalBytes) / 1073741824.0, mib);
    else
      std::printf("device           cpu (%s)\n", cuda.problem.c_str());
  }
  const SimulationState& sim = model.simulation;
  if (sim.hasTime() || sim.hasCycle())
    std::printf("simulation       time %s%s, cycle %s%s\n", sim.hasTime() ? strCat(sim.time).c_str() : "unknown",
                sim.timeUnits.empty() ? "" : (" (" + sim.timeUnits + ")").c_str(),
                sim.hasCycle() ? std::to_string(sim.cycle).c_str() : "unknown",
                sim.hasRedshift() ? strCat(", redshift ", sim.redshift).c_str() : "");
  std::printf("lattice bounds   [%d %d %d] - [%d %d %d] (finest-level units, upper exclusive)\n", lattice.lower.x,
              lattice.lower.y, lattice.lower.z, lattice.upper.x, lattice.upper.y, lattice.upper.z);
  std::printf("world bounds     [%g %g %g] - [%g %g %g]\n", worldLo.x, worldLo.y, worldLo.z, worldHi.x, worldHi.y,
              worldHi.z);
  std::printf("cells            %llu\n", (unsigned long long)s.cells);
  std::printf("  %-8s %-10s %14s %12s\n", "level", "width", "cells", "bricks");
  for (const auto& l : s.levels)
    std::printf("  %-8d %-10d %14llu %12llu\n", l.level, 1 << l.level, (unsigned long long)l.cells,
                (unsigned long long)l.bricks);
  std::printf("bricks           %llu (%llu single-cell)\n", (unsigned long long)s.bricks,
              (unsigned long long)s.singleCellBricks);
  std::printf("regions          %llu\n", (unsigned long long)s.regions);
  std::printf("bricks/region    %.3f by count, %.3f by volume, %llu at most\n", s.bricksPerRegionByCount,
              s.bricksPerRegionByVolume, (unsigned long long)s.maxBricksPerRegion);
  for (size_t f = 0; f < model.fieldNames.size(); ++f)
    std::printf("field %-10s [%g, %g]%s\n", model.fieldNames[f].c_str(), s.fieldRanges[f].lower, s.fieldRanges[f].upper,
                model.unitsOf(int(f)).empty() ? "" : (" " + model.unitsOf(int(f))).c_str());
  std::printf("memory           bricks %.2f MB, regions %.2f MB, values %.2f MB\n", s.brickBytes / 1e6,
              s.regionBytes / 1e6, s.valueBytes / 1e6);
  std::printf("bytes per cell   %.3f for bricks + regions (one float field: 4)\n",
              double(s.brickBytes + s.regionBytes) * perCell);
  std::printf("build time       bricks %.3f s, regions %.3f s, value ranges %.3f s (load total %.3f s)\n",
              model.stats.brickSeconds, model.stats.regionSeconds, model.stats.rangeSeconds, loadSeconds);
  if (model.stats.parts > 1) std::printf("built in parts   %d, each read alone\n", model.stats.parts);
  printParticles(particlesOf(o));
}

} // namespace

void addInfo(CLI::App& app) {
  auto opts = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand("info", "Print levels, bricks, regions, ranges, memory and build times");
  opts->in.add(*cmd);
  opts->in.addMemoryBudget(*cmd);
  cmd->add_flag("--json", opts->json, "Print one JSON object on stdout");
  cmd->add_flag("--fields", opts->fieldsOnly, "Only list the fields");
  cmd->callback([opts] { run(*opts); });
}

} // namespace exa::cli
