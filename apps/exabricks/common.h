// Options and helpers shared by the subcommands.
#pragma once

#include "exabricks/core/error.h"
#include "exabricks/io/load.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <string>

namespace exa::cli {

/// The input options every data-reading command takes.
struct InputOptions {
  std::string input; ///< empty: the embedded default dataset
  std::string field; ///< empty: the first field
  int maxBrickWidth = 32;

  void add(CLI::App& cmd, bool fieldOption = true);
  LoadOptions loadOptions(bool onlySelectedField) const;
  std::string name() const;
};

/// JSON for a range; null bounds for an empty range.
nlohmann::json toJson(const range1f& r);

} // namespace exa::cli
