// exabricks: render and inspect structured AMR data with the ExaBricks method.
//
// Exit status: 0 success; 1 a failure while working (unreadable or invalid input, a render or
// write that failed, including standard output); 2 a usage error (unknown option, bad option
// value, missing argument); 130 / 143 interrupted by SIGINT / SIGTERM (no temporary file is left).
#include "commands.h"
#include "mpi/processes.h"

#include "exabricks/amr/basis_batch.h"

#include "exabricks/core/error.h"
#include "exabricks/core/files.h"
#include "exabricks/core/log.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <memory>
#include <new>
#include <string>
#include <vector>

#ifndef EXABRICKS_VERSION
#define EXABRICKS_VERSION "unknown"
#endif

namespace {

extern "C" void onInterrupt(int signal) {
  if (exa::deferInterrupt(signal)) return; // taken again when the files being published are in place
  exa::removePendingTemporaries();
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

/// Standard output is part of the result: a write error (a full disk, a closed pipe) fails.
bool flushStandardOutput() {
  std::cout.flush();
  if (std::fflush(stdout) != 0 || std::ferror(stdout) || !std::cout) {
    std::fprintf(stderr, "exabricks: error: writing standard output: %s\n", std::strerror(errno ? errno : EIO));
    return false;
  }
  return true;
}

/// Edits (insertions, deletions, substitutions, swaps of neighbours) between two words.
size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i)
    d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j)
    d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i)
    for (size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

/// The message of a usage error: where no command was recognised, "unknown command 'WORD'" for
/// the first word that is not an option, with the command within two edits of it.
std::string usageMessage(CLI::App& app, int argc, char** argv, const CLI::ParseError& e) {
  // CLI11's "Could not convert: --fps = abc" as the other messages read: "--fps: 'abc' is not a valid
  // number for it".
  const std::string what = e.what(), convert = "Could not convert: ";
  if (dynamic_cast<const CLI::ConversionError*>(&e) && what.rfind(convert, 0) == 0) {
    const size_t eq = what.find(" = ");
    if (eq != std::string::npos)
      return what.substr(convert.size(), eq - convert.size()) + ": '" + what.substr(eq + 3) +
             "' is not a valid number for it";
  }
  for (CLI::App* command : app.get_subcommands({}))
    if (command->parsed()) return e.what();
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') continue;
    std::string best;
    size_t bestDistance = 3;
    for (CLI::App* command : app.get_subcommands({}))
      if (const size_t d = editDistance(word, command->get_name()); d < bestDistance) {
        bestDistance = d;
        best = command->get_name();
      }
    return "unknown command '" + word + "'" + (best.empty() ? "" : " (did you mean '" + best + "'?)");
  }
  return e.what();
}

} // namespace

int main(int argc, char** argv) {
  exa::mpi::Session processes(argc, argv);
  const bool root = exa::mpi::processes().root();
  const std::string who = root ? "exabricks" : "exabricks[" + std::to_string(exa::mpi::processes().rank) + "]";
  std::signal(SIGINT, onInterrupt);
  std::signal(SIGTERM, onInterrupt);
  CLI::App app{"exabricks: fast, faithful rendering of structured AMR data (ExaBricks method)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("exabricks ") + EXABRICKS_VERSION);
  bool quiet = false, verbose = false;
  int threads = 0;
  std::string simd;
  std::unique_ptr<tbb::global_control> threadLimit;
  app.add_flag("-q,--quiet", quiet, "Print nothing but results and errors");
  app.add_flag("-v,--verbose", verbose, "Log build steps and timings on stderr");
  app.add_option("--threads", threads, "Worker threads (default: every core)")->check(CLI::Range(1, 4096));
  app.add_option("--simd", simd, "Instruction set of the sampling batches (default: the best this CPU has)");
  app.parse_complete_callback([&] {
    // Under MPI only the first process logs; every process reports its own errors.
    exa::setLogLevel(quiet || !root ? exa::LogLevel::Quiet : (verbose ? exa::LogLevel::Info : exa::LogLevel::Warning));
    for (const char* command : {"sample", "build", "generate", "convert", "bench", "view"})
      if (app.got_subcommand(command)) exa::mpi::requireOneProcess(command);
    if (!simd.empty() && !exa::useBatchTarget(simd)) {
      std::string known;
      for (const std::string& t : exa::batchTargets())
        known += (known.empty() ? "" : ", ") + t;
      exa::failUsage("--simd ", simd, ": not an instruction set of this CPU (", known, ")");
    }
    if (threads > 0)
      threadLimit =
          std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(threads));
  });
  exa::cli::addInfo(app);
  exa::cli::addSample(app);
  exa::cli::addBuild(app);
  exa::cli::addGenerate(app);
  exa::cli::addConvert(app);
  exa::cli::addRender(app);
  exa::cli::addBench(app);
  exa::cli::addView(app);
  exa::cli::addMovie(app);
  exa::cli::addKeys(app);
  // The global flags may follow the command too (exabricks render -q ...).
  for (CLI::App* command : app.get_subcommands({}))
    command->fallthrough();
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // Usage errors: one line, exit 2, with the command meant where a word is close to one.
    std::fprintf(stderr, "%s: error: %s\n", who.c_str(), usageMessage(app, argc, argv, e).c_str());
    return 2;
  } catch (const exa::UsageError& e) {
    std::fprintf(stderr, "%s: error: %s\n", who.c_str(), e.what());
    return 2;
  } catch (const exa::Error& e) {
    std::fprintf(stderr, "%s: error: %s\n", who.c_str(), e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "%s: error: out of memory\n", who.c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", who.c_str(), e.what());
    return 1;
  }
  return flushStandardOutput() ? 0 : 1;
}
