// exabricks generate: deterministic synthetic AMR datasets in the native format or as AMReX plotfiles.
#include "commands.h"
#include "common.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/core/log.h"
#include "exabricks/io/amrex_write.h"
#include "exabricks/io/native.h"
#include "exabricks/io/particles.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

namespace exa::cli {
namespace {

struct GenerateOptions {
  SceneOptions scene;
  int steps = 0;          ///< 0: one dataset; N: a time series of N steps
  int regrid = 1;         ///< steps between two changes of the hierarchy
  double dt = 1.0;        ///< time between steps
  int64_t particles = -1; ///< particles of the scene's main species; -1: cells / 25 where it has them
  std::string output;
  std::string format = "native"; ///< native (NAME.cells) or amrex (a plotfile folder)
  int precision = 64;            ///< bits per value in an AMReX plotfile
  bool list = false;
  bool json = false;
};

/// Slabs generated at once when streaming to disk: enough to keep every thread busy.
int slabsPerPiece() { return 4 * int(std::max<size_t>(1, tbb::this_task_arena::max_concurrency())); }

/// The particles to write beside the cells (none for a scene without them).
uint64_t particleCount(const GenerateOptions& o) {
  if (o.particles < -1) failUsage("--particles must be 0 or more");
  if (!sceneHasParticles(o.scene)) {
    if (o.particles > 0) failUsage(strCat("--particles: scene '", o.scene.name, "' has no particles (cosmic has)"));
    return 0;
  }
  if (o.particles > (int64_t(1) << 32)) failUsage("--particles: at most 2^32");
  return o.particles >= 0 ? uint64_t(o.particles) : o.scene.targetCells / 25;
}

/// NAME.particles for the scene's resolved lattice, the domain its cells cover.
std::vector<char> particleBytes(const SceneOptions& resolved, uint64_t count) {
  return nativeParticleBytes(generateSceneParticles(resolved, count), vec3d(0.0), vec3d(sceneLatticeWidth(resolved)));
}

/// Checks a generated piece's cells and values; its fields' names.
std::vector<std::string> checkedFields(const CellSet& piece, const std::string& scene) {
  validateCellRecords(piece.cells, scene);
  std::vector<std::string> names;
  for (const Field& f : piece.fields) {
    validateFieldValues(f, piece.cells.size(), scene);
    names.push_back(f.name);
  }
  return names;
}

/// The scene as an AMReX plotfile, written as it is generated: slabs of whole coarsest boxes.
uint64_t writePlotfile(const GenerateOptions& o, uint64_t particles) {
  if (o.steps) failUsage("--steps writes native datasets (--format native)");
  if (o.precision != 32 && o.precision != 64) failUsage("--precision must be 32 or 64");
  if (particles && o.particles > 0) failUsage("--particles: an AMReX plotfile is written without particles");
  if (particles) logNote("the plotfile holds the gas alone (particles are written with --format native)");
  const SceneOptions resolved = resolveSceneSize(o.scene);
  std::unique_ptr<AmrexPlotfileWriter> writer;
  const int slabs = AmrexPlotfileWriter::kSlabCells * std::max(1, slabsPerPiece() / AmrexPlotfileWriter::kSlabCells);
  const uint64_t cells = generateScenePieces(resolved, slabs, [&](CellSet& piece) {
    const std::vector<std::string> names = checkedFields(piece, o.scene.name);
    if (!writer)
      writer = std::make_unique<AmrexPlotfileWriter>(o.output, names, resolved.levels,
                                                     int64_t(sceneLatticeWidth(resolved)), o.precision == 32);
    writer->append(piece);
  });
  const uint64_t boxes = writer->finish();
  logInfo(strCat("wrote ", boxes, " boxes on ", resolved.levels, " levels to ", o.output));
  return cells;
}

void run(const GenerateOptions& o) {
  if (o.list) {
    for (const SceneInfo& s : sceneList())
      std::printf("%-8s %s\n", s.name.c_str(), s.description.c_str());
    return;
  }
  if (o.output.empty())
    fail("generate: an output NAME.cells (or a plotfile folder with --format amrex) is required (-o)");
  if (o.format != "native" && o.format != "amrex") failUsage("--format must be native or amrex");
  if (o.steps < 0 || o.steps > 100000) failUsage("--steps must be in 0..100000");
  if (o.regrid < 1) failUsage("--regrid must be at least 1");
  if (!(o.dt > 0 && std::isfinite(o.dt))) failUsage("--dt must be a positive number");
  const uint64_t particles = particleCount(o);
  Timer timer;
  std::vector<std::string> outputs;
  uint64_t cellCount = 0;
  if (o.format == "amrex") {
    cellCount = writePlotfile(o, particles);
    outputs.push_back(o.output);
  } else if (o.steps == 0) {
    // Written as it is generated, a few slabs at a time: memory for those alone.
    std::unique_ptr<NativeWriter> writer;
    const SceneOptions resolved = resolveSceneSize(o.scene);
    cellCount = generateScenePieces(resolved, slabsPerPiece(), [&](CellSet& piece) {
      const std::vector<std::string> names = checkedFields(piece, o.scene.name);
      if (!writer) writer = std::make_unique<NativeWriter>(o.output, names);
      writer->append(piece);
    });
    if (particles) writer->addFile(nativeParticlesPath(o.output), particleBytes(resolved, particles));
    writer->finish();
    outputs.push_back(o.output);
  } else {
    // NAME.cells -> NAME_0000.cells, NAME_0001.cells, ...: one dataset per step, on one lattice.
    std::string stem = o.output;
    if (stem.size() > 6 && stem.compare(stem.size() - 6, 6, ".cells") == 0) stem.resize(stem.size() - 6);
    const std::filesystem::path folder = std::filesystem::path(stem).parent_path();
    std::error_code ec;
    if (!folder.empty()) std::filesystem::create_directories(folder, ec);
    if (ec) fail(folder.string(), ": cannot create the folder: ", ec.message());
    const SceneOptions resolved = resolveSceneSize(o.scene);
    Progress progress("generating " + std::to_string(o.steps) + " steps", uint64_t(o.steps));
    for (int step = 0; step < o.steps; ++step) {
      SceneOptions so = resolved;
      so.time = step * o.dt;
      so.gridTime = (step / o.regrid) * o.regrid * o.dt;
      const CellSet cells = generateScene(so);
      validateCells(cells, o.scene.name);
      char suffix[32];
      std::snprintf(suffix, sizeof suffix, "_%04d.cells", step);
      outputs.push_back(stem + suffix);
      writeNative(cells, outputs.back());
      cellCount += cells.size();
      progress.advance(1);
    }
    progress.finish();
  }
  logInfo(strCat("generated ", cellCount, " cells in ", timer.seconds(), " s; wrote ", outputs.size(), " dataset(s)"));
  if (o.json) {
    nlohmann::json j{{"output", o.steps ? nlohmann::json(outputs) : nlohmann::json(o.output)},
                     {"scene", o.scene.name},
                     {"cells", cellCount},
                     {"seed", o.scene.seed},
                     {"levels", o.scene.levels},
                     {"seconds", timer.seconds()}};
    if (o.steps) j["steps"] = o.steps;
    if (particles) j["particles"] = {{"dark_matter", particles}, {"star", particles / 25}};
    std::cout << j.dump(2) << "\n";
  }
}

} // namespace

void addGenerate(CLI::App& app) {
  auto opts = std::make_shared<GenerateOptions>();
  CLI::App* cmd = app.add_subcommand("generate", "Write a synthetic AMR dataset (NAME.cells + fields)");
  cmd->add_option("-s,--scene", opts->scene.name, "Scene name (see --list)")->capture_default_str();
  cmd->add_option("-n,--cells", opts->scene.targetCells, "Approximate number of cells")->capture_default_str();
  cmd->add_option("--seed", opts->scene.seed, "Random seed")->capture_default_str();
  cmd->add_option("--levels", opts->scene.levels, "Number of levels")->check(CLI::Range(1, 12))->capture_default_str();
  cmd->add_option("-o,--output", opts->output, "Output NAME.cells");
  cmd->add_option("--steps", opts->steps, "Write a time series of N steps NAME_0000.cells, ... (blobs move)");
  cmd->add_option("--regrid", opts->regrid, "Steps between changes of the hierarchy in a series")
      ->capture_default_str();
  cmd->add_option("--dt", opts->dt, "Time between steps of a series")->capture_default_str();
  cmd->add_option("--particles", opts->particles,
                  "Dark-matter particles written to NAME.particles with count/25 stars (cosmic; default: cells/25)");
  cmd->add_option("--format", opts->format,
                  "native: NAME.cells and its fields; amrex: an AMReX plotfile folder (every level in boxes, covered "
                  "cells the mean of their children)")
      ->capture_default_str();
  cmd->add_option("--precision", opts->precision, "Bits per value of an AMReX plotfile: 64 or 32")
      ->capture_default_str();
  cmd->add_flag("--list", opts->list, "List the scenes");
  cmd->add_flag("--json", opts->json, "Print a JSON summary on stdout");
  cmd->callback([opts] { run(*opts); });
}

} // namespace exa::cli
