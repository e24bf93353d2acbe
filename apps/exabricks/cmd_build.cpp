// exabricks build: build bricks and regions once and store them in a model file.
#include "commands.h"
#include "common.h"

#include "exabricks/core/files.h"
#include "exabricks/core/log.h"
#include "exabricks/io/model_file.h"

#include <cstdio>

namespace exa::cli {
namespace {

struct BuildCmdOptions {
  InputOptions in;
  std::vector<std::string> fields;
  std::string output;
};

void run(const BuildCmdOptions& o) {
  checkOutputFolder(o.output);
  LoadOptions load = o.in.loadOptions(false);
  load.fields = o.fields;
  Timer timer;
  const Model model = loadModel(o.in.input, load);
  writeModel(model, o.output);
  const ModelSummary s = summarize(model);
  logInfo(strCat("wrote ", o.output, " (", s.cells, " cells, ", s.bricks, " bricks, ", s.regions, " regions) in ",
                 timer.seconds(), " s"));
}

} // namespace

void addBuild(CLI::App& app) {
  auto opts = std::make_shared<BuildCmdOptions>();
  CLI::App* cmd = app.add_subcommand("build", "Build bricks and regions into one model file");
  opts->in.add(*cmd, false);
  cmd->add_option("-f,--field", opts->fields, "Fields to keep (default: all; repeatable)");
  cmd->add_option("-o,--output", opts->output, "Model file to write")->required();
  cmd->callback([opts] { run(*opts); });
}

} // namespace exa::cli
