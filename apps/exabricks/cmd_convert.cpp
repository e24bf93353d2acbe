// exabricks convert: write any readable input as a native NAME.cells dataset.
#include "commands.h"
#include "common.h"

#include "exabricks/core/files.h"
#include "exabricks/core/log.h"
#include "exabricks/io/native.h"

namespace exa::cli {
namespace {

struct ConvertOptions {
  InputOptions in;
  std::vector<std::string> fields;
  std::string output;
};

void run(const ConvertOptions& o) {
  checkOutputFolder(o.output);
  LoadOptions load = o.in.loadOptions(false);
  load.fields = o.fields;
  const CellSet cells = loadCells(o.in.input, load);
  if (!cells.world.isIdentity())
    logWarning("the native format stores no world transform; origin and scale are dropped");
  writeNative(cells, o.output);
  logInfo(strCat("wrote ", cells.size(), " cells to ", o.output));
}

} // namespace

void addConvert(CLI::App& app) {
  auto opts = std::make_shared<ConvertOptions>();
  CLI::App* cmd = app.add_subcommand("convert", "Write an input as a native NAME.cells dataset");
  opts->in.add(*cmd, false);
  cmd->add_option("-f,--field", opts->fields, "Fields to keep (default: all; repeatable)");
  cmd->add_option("-o,--output", opts->output, "Output NAME.cells")->required();
  cmd->callback([opts] { run(*opts); });
}

} // namespace exa::cli
