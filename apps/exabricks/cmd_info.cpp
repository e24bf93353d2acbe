// exabricks info: what a dataset holds and what its bricks and regions look like.
#include "commands.h"
#include "common.h"

#include "exabricks/io/model_info.h"

#include "exabricks/core/log.h"

#include <cstdio>
#include <iostream>

namespace exa::cli {
namespace {

struct InfoOptions {
  InputOptions in;
  bool json = false;
  bool fieldsOnly = false;
};

void printFields(const InfoOptions& o) {
  const std::vector<std::string> names = listFields(o.in.input);
  if (o.json) {
    std::cout << nlohmann::json{{"fields", names}}.dump(2) << "\n";
    return;
  }
  for (const std::string& n : names) std::printf("%s\n", n.c_str());
}

void run(const InfoOptions& o) {
  if (o.fieldsOnly) return printFields(o);
  Timer total;
  const Model model = loadModel(o.in.input, o.in.loadOptions(true));
  const double loadSeconds = total.seconds();
  const ModelSummary s = summarize(model);
  const box3i lattice = model.cellBounds();
  const vec3d worldLo = model.world.toWorld(vec3d(lattice.lower));
  const vec3d worldHi = model.world.toWorld(vec3d(lattice.upper));
  const double perCell = s.cells ? 1.0 / double(s.cells) : 0.0;

  if (o.json) {
    std::cout << modelInfoJson(model, o.in.name(), loadSeconds) << "\n";
    return;
  }

  std::printf("input            %s\n", o.in.name().c_str());
  if (model.simulation.hasTime() || model.simulation.hasCycle())
    std::printf("simulation       time %s, cycle %s\n",
                model.simulation.hasTime() ? strCat(model.simulation.time).c_str() : "unknown",
                model.simulation.hasCycle() ? std::to_string(model.simulation.cycle).c_str() : "unknown");
  std::printf("lattice bounds   [%d %d %d] - [%d %d %d] (finest-level units, upper exclusive)\n",
              lattice.lower.x, lattice.lower.y, lattice.lower.z, lattice.upper.x,
              lattice.upper.y, lattice.upper.z);
  std::printf("world bounds     [%g %g %g] - [%g %g %g]\n", worldLo.x, worldLo.y, worldLo.z,
              worldHi.x, worldHi.y, worldHi.z);
  std::printf("cells            %llu\n", (unsigned long long)s.cells);
  std::printf("  %-8s %-10s %14s %12s\n", "level", "width", "cells", "bricks");
  for (const auto& l : s.levels)
    std::printf("  %-8d %-10d %14llu %12llu\n", l.level, 1 << l.level,
                (unsigned long long)l.cells, (unsigned long long)l.bricks);
  std::printf("bricks           %llu (%llu single-cell)\n", (unsigned long long)s.bricks,
              (unsigned long long)s.singleCellBricks);
  std::printf("regions          %llu\n", (unsigned long long)s.regions);
  std::printf("bricks/region    %.3f by count, %.3f by volume, %llu at most\n",
              s.bricksPerRegionByCount, s.bricksPerRegionByVolume,
              (unsigned long long)s.maxBricksPerRegion);
  for (size_t f = 0; f < model.fieldNames.size(); ++f)
    std::printf("field %-10s [%g, %g]\n", model.fieldNames[f].c_str(), s.fieldRanges[f].lower,
                s.fieldRanges[f].upper);
  std::printf("memory           bricks %.2f MB, regions %.2f MB, values %.2f MB\n",
              s.brickBytes / 1e6, s.regionBytes / 1e6, s.valueBytes / 1e6);
  std::printf("bytes per cell   %.3f for bricks + regions (one float field: 4)\n",
              double(s.brickBytes + s.regionBytes) * perCell);
  std::printf("build time       bricks %.3f s, regions %.3f s, value ranges %.3f s (load total %.3f s)\n",
              model.stats.brickSeconds, model.stats.regionSeconds, model.stats.rangeSeconds,
              loadSeconds);
}

} // namespace

void addInfo(CLI::App& app) {
  auto opts = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand("info", "Print levels, bricks, regions, ranges, memory and build times");
  opts->in.add(*cmd);
  cmd->add_flag("--json", opts->json, "Print one JSON object on stdout");
  cmd->add_flag("--fields", opts->fieldsOnly, "Only list the fields");
  cmd->callback([opts] { run(*opts); });
}

} // namespace exa::cli
