// exabricks generate: deterministic synthetic AMR datasets in the native format.
#include "commands.h"
#include "common.h"

#include "exabricks/amr/scenes.h"
#include "exabricks/core/log.h"
#include "exabricks/io/native.h"

#include <cstdio>
#include <iostream>

namespace exa::cli {
namespace {

struct GenerateOptions {
  SceneOptions scene;
  std::string output;
  bool list = false;
  bool json = false;
};

void run(const GenerateOptions& o) {
  if (o.list) {
    for (const SceneInfo& s : sceneList()) std::printf("%-8s %s\n", s.name.c_str(), s.description.c_str());
    return;
  }
  if (o.output.empty()) fail("generate: an output NAME.cells is required (-o)");
  Timer timer;
  const CellSet cells = generateScene(o.scene);
  validateCells(cells, o.scene.name);
  const double genSeconds = timer.seconds();
  writeNative(cells, o.output);
  logInfo(strCat("generated ", cells.size(), " cells in ", genSeconds, " s; wrote ", o.output));
  if (o.json) {
    std::vector<std::string> fields;
    for (const Field& f : cells.fields) fields.push_back(f.name);
    std::cout << nlohmann::json{{"output", o.output},      {"scene", o.scene.name},
                                {"cells", cells.size()},   {"fields", fields},
                                {"seed", o.scene.seed},    {"levels", o.scene.levels},
                                {"seconds", timer.seconds()}}
                     .dump(2)
              << "\n";
  }
}

} // namespace

void addGenerate(CLI::App& app) {
  auto opts = std::make_shared<GenerateOptions>();
  CLI::App* cmd = app.add_subcommand("generate", "Write a synthetic AMR dataset (NAME.cells + fields)");
  cmd->add_option("-s,--scene", opts->scene.name, "Scene name (see --list)")->capture_default_str();
  cmd->add_option("-n,--cells", opts->scene.targetCells, "Approximate number of cells")
      ->capture_default_str();
  cmd->add_option("--seed", opts->scene.seed, "Random seed")->capture_default_str();
  cmd->add_option("--levels", opts->scene.levels, "Number of levels")
      ->check(CLI::Range(1, 12))
      ->capture_default_str();
  cmd->add_option("-o,--output", opts->output, "Output NAME.cells");
  cmd->add_flag("--list", opts->list, "List the scenes");
  cmd->add_flag("--json", opts->json, "Print a JSON summary on stdout");
  cmd->callback([opts] { run(*opts); });
}

} // namespace exa::cli
