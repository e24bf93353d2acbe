// Subcommands of the exabricks tool; each lives in its own file and registers itself here.
#pragma once

#include <CLI/CLI.hpp>

namespace exa::cli {

void addInfo(CLI::App& app);
void addSample(CLI::App& app);
void addBuild(CLI::App& app);
void addGenerate(CLI::App& app);
void addConvert(CLI::App& app);
void addRender(CLI::App& app);
void addBench(CLI::App& app);
void addView(CLI::App& app);
void addMovie(CLI::App& app);
void addKeys(CLI::App& app);

} // namespace exa::cli
