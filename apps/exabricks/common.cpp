#include "common.h"

#include "exabricks/amr/scenes.h"

namespace exa::cli {

void InputOptions::add(CLI::App& cmd, bool fieldOption) {
  cmd.add_option("input", input,
                 "Model file, NAME.cells dataset or .grids fixture (default: embedded dataset)");
  if (fieldOption) cmd.add_option("-f,--field", field, "Field to use (default: the first)");
  cmd.add_option("--max-brick-width", maxBrickWidth, "Most cells per axis in one brick")
      ->check(CLI::Range(1, 1024));
}

LoadOptions InputOptions::loadOptions(bool onlySelectedField) const {
  LoadOptions o;
  if (onlySelectedField && !field.empty()) o.fields = {field};
  o.build.bricks.maxBrickWidth = maxBrickWidth;
  return o;
}

std::string InputOptions::name() const { return input.empty() ? kDefaultDatasetName : input; }

nlohmann::json toJson(const range1f& r) {
  if (r.empty()) return {{"min", nullptr}, {"max", nullptr}};
  return {{"min", r.lower}, {"max", r.upper}};
}

} // namespace exa::cli
