// exabricks: render and inspect structured AMR data with the ExaBricks method.
#include "commands.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include <cstdio>
#include <exception>
#include <new>

int main(int argc, char** argv) {
  CLI::App app{"exabricks: fast, faithful rendering of structured AMR data (ExaBricks method)"};
  app.require_subcommand(1);
  bool quiet = false, verbose = false;
  app.add_flag("-q,--quiet", quiet, "Print nothing but results and errors");
  app.add_flag("-v,--verbose", verbose, "Log build steps and timings on stderr");
  app.parse_complete_callback([&] {
    exa::setLogLevel(quiet ? exa::LogLevel::Quiet
                           : (verbose ? exa::LogLevel::Info : exa::LogLevel::Warning));
  });
  exa::cli::addInfo(app);
  exa::cli::addSample(app);
  exa::cli::addBuild(app);
  exa::cli::addGenerate(app);
  exa::cli::addConvert(app);
  exa::cli::addRender(app);
  exa::cli::addBench(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const exa::Error& e) {
    std::fprintf(stderr, "exabricks: error: %s\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "exabricks: error: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "exabricks: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
