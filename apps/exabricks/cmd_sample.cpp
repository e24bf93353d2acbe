// exabricks sample: reconstructed values and gradients at given world positions.
#include "commands.h"
#include "common.h"

#include "exabricks/core/error.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

namespace exa::cli {
namespace {

struct SampleOptions {
  InputOptions in;
  std::string points; ///< empty or "-": standard input
};

/// Writes to standard output; a failed write (a full disk, a closed pipe) fails the command.
void writeOut(const std::string& text) {
  if (!text.empty() && std::fwrite(text.data(), 1, text.size(), stdout) != text.size())
    fail("writing standard output: ", std::strerror(errno));
}

/// Reads the points: one per line that holds one ('x y z'; blank and comment lines hold none).
std::vector<vec3d> readPoints(const SampleOptions& o) {
  std::ifstream file;
  std::istream* in = &std::cin;
  const std::string source = o.points.empty() || o.points == "-" ? "<stdin>" : o.points;
  if (source != "<stdin>") {
    file.open(o.points);
    if (!file) fail(o.points, ": cannot open: ", std::strerror(errno));
    in = &file;
  }
  std::vector<vec3d> points;
  std::string line;
  size_t lineNo = 0;
  while (std::getline(*in, line)) {
    ++lineNo;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    // Blank and comment lines hold no point and give no output; every other line is one point
    // and gives one line, or the command fails naming it. nan and out-of-range numbers (1e400)
    // are points outside the data.
    std::istringstream ls(line);
    std::vector<std::string> words;
    for (std::string word; ls >> word;)
      words.push_back(word);
    if (words.empty()) continue;
    double w[3];
    bool ok = words.size() == 3;
    for (size_t k = 0; ok && k < 3; ++k) {
      char* end = nullptr;
      w[k] = std::strtod(words[k].c_str(), &end);
      ok = end && *end == '\0';
    }
    if (!ok) fail(source, ": line ", lineNo, ": expected three numbers 'x y z', got '", line, "'");
    points.push_back(vec3d(w[0], w[1], w[2]));
  }
  return points;
}

/// Writes one line per point to standard output, `sampleAt(i, value, gradient)` saying whether
/// point i has a value ("value gx gy gz", else "nan nan nan nan"), in pieces of 64 KiB.
template <typename SampleAt> void writeSamples(size_t count, SampleAt&& sampleAt) {
  std::string out;
  char buffer[160];
  for (size_t i = 0; i < count; ++i) {
    double value;
    vec3d g;
    if (sampleAt(i, value, g)) {
      std::snprintf(buffer, sizeof buffer, "%.9g %.9g %.9g %.9g\n", value, g.x, g.y, g.z);
      out += buffer;
    } else {
      out += "nan nan nan nan\n";
    }
    if (out.size() > (1 << 16)) {
      writeOut(out);
      out.clear();
    }
  }
  writeOut(out);
}

/// A step larger than the budget: the points sorted into the parts that hold them, each part read
/// once (samples inside a part equal the whole step's: it holds every cell whose support reaches it).
void runStreamed(const SampleOptions& o, const LoadOptions& lo, MemoryPlan plan, const std::vector<vec3d>& points) {
  StreamedStep step(o.in.input, lo, std::move(plan));
  const int field = step.skeleton().requireField(o.in.field);
  std::vector<double> values;
  std::vector<vec3d> gradients;
  std::vector<bool> found;
  step.sample(field, points, values, gradients, found);
  writeSamples(points.size(), [&](size_t i, double& value, vec3d& g) {
    value = values[i], g = gradients[i];
    return bool(found[i]);
  });
}

void run(const SampleOptions& o) {
  const LoadOptions lo = o.in.loadOptions(true);
  const std::vector<vec3d> points = readPoints(o);
  if (std::optional<MemoryPlan> plan = memoryPlanFor(o.in, o.in.input, lo, 0, false))
    return runStreamed(o, lo, std::move(*plan), points);
  const Model model = loadModel(o.in.input, lo);
  const int field = model.requireField(o.in.field);
  writeSamples(points.size(),
               [&](size_t i, double& value, vec3d& g) { return model.sampleWorld(field, points[i], value, g); });
}

} // namespace

void addSample(CLI::App& app) {
  auto opts = std::make_shared<SampleOptions>();
  CLI::App* cmd =
      app.add_subcommand("sample", "Reconstruct 'value gx gy gz' at 'x y z' world positions (nan outside the data)");
  opts->in.add(*cmd);
  opts->in.addMemoryBudget(*cmd);
  cmd->add_option("-p,--points", opts->points, "File of 'x y z' lines (default: standard input)");
  cmd->callback([opts] { run(*opts); });
}

} // namespace exa::cli
